#pragma once
// The spikes stage's own types, at the bottom of its rooms: what addSpikes (SpikeMapper.hpp)
// takes (SpikeInput: the frame's surface, magnets, fluid and particles) and gives
// (SpikeResult: the spiky mesh, its patterns and tips). The phases (SurfaceFields,
// SpikeLattice, SpikeDisplacement, SpikeSolids) include this, never the orchestrator's
// header, so the includes of spikes/ run one way: types, phases, orchestrator, frames.
#include "sim/geometry/Container.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/scene/SimParams.hpp"
#include "spikes/SpikeParams.hpp"
#include "spikes/SpikePhysics.hpp"
#include "sim/core/TriangleMesh.hpp"

#include <memory>
#include <vector>

namespace ferro {

class ParticleFieldEvaluator; // sim/particlefield/ParticleField.hpp
class SurfaceChargeSolver;    // sim/solids/SurfaceChargeSolver.hpp

class SurfaceFlowHistory;

/// What addSpikes needs to know about the fluid and its vessel.
struct SpikeFluid {
    double density = 1000.0;        ///< rho [kg/m^3]
    double surfaceTension = 0.0;    ///< sigma [N/m]
    double viscosity = 0.0;         ///< kinematic nu [m^2/s] (the fastest-growing wavenumber)
    Vec3d gravity{0, 0, -9.81};     ///< [m/s^2]
    MagnetizationParams law;        ///< chi0, Ms
    std::shared_ptr<const Container> container; ///< wetted walls; null = every surface is free
    /// The scene's solids ([[solids]]) as obstacles (null = none): surface closer than
    /// SpikeParams::filmThickness to one is its bare wall or a wetting film, never spiky.
    std::shared_ptr<const Container> solids;
    bool hasCenter = false;         ///< a natural anchor (the container's centre) for uniform fields
    Vec3d center{0, 0, 0};
    double particleSpacing = 0.0;   ///< [m]; 0 = unknown
    double period[2] = {0.0, 0.0};  ///< container.periodic_sides: the box's x and y extent [m] (the
                                    ///< particle field sums the periodic copies); 0 = not periodic
};

/// The frame's particles (optional): positions and |M| [A/m] for the mapping area.
struct SpikeParticles {
    std::vector<Vec3d> positions;
    std::vector<double> magnetization; ///< |M| per particle; empty = use the law at the local field
    double spacing = 0.0;              ///< particle spacing [m]
};

/// The fluid's particles at earlier frames (spikes/SpikeFrames.cpp reads them from a shot's
/// particle files).
class ParticleHistory {
public:
    virtual ~ParticleHistory() = default;
    /// The particles' positions [m] at `time` [s]: those of the frame nearest it, or null
    /// when there is none. Throws SpikeInputError when that frame's file cannot be read.
    virtual std::shared_ptr<const std::vector<Vec3d>> positionsAt(double time) const = 0;
};

struct SpikeInput {
    double time = 0;                    ///< the frame's time [s]
    TriangleMesh surface;               ///< closed fluid surface, outward triangles
    std::vector<Magnet> magnets;        ///< the magnets at the frame's time
    SpikeFluid fluid;
    SpikeParticles particles;
    /// The magnetized particles' field: a tree of their smoothed dipoles, as the simulator's
    /// (null = magnets only; particleFieldAt).
    std::shared_ptr<const ParticleFieldEvaluator> particleField;
    /// The magnetized solids ([[solids]]): their surface charge, solved in the magnets' and
    /// the particles' field (null = no solids; solidFieldAt).
    std::shared_ptr<const SurfaceChargeSolver> solids;
    /// The magnets' recent past for SpikeParams::growthTime, from the scene's tracks:
    /// pastMagnets[k] at k steps back (k = 0: now, by the tracks, the reference the past is
    /// compared with, so header magnets softened differently never make a still field lag),
    /// pastWeights[k] its weight. Empty = no lag.
    std::vector<std::vector<Magnet>> pastMagnets;
    std::vector<double> pastWeights;
    /// The scene's magnet tracks when they are the frame's magnets (null otherwise): the
    /// bifurcation curve's hysteresis looks further back than pastMagnets, in steps of
    /// lookbackStep [s], for the last time the field left the bistable band.
    std::shared_ptr<const std::vector<MagnetTrack>> tracks;
    double lookbackStep = 0;
    /// The fluid's flow over earlier frames, for SpikeParams::responseTime (SurfaceFlow.hpp):
    /// the tips are carried by it. Null = the tips stand where the field lays them out.
    std::shared_ptr<const SurfaceFlowHistory> flow;
    /// The particles at earlier times, for SurfaceFields::fieldHistoryPeak: where the surface
    /// stood when the field was strongest. Null = unknown.
    std::shared_ptr<const ParticleHistory> pastParticles;
};

/// The particles' field at x [A/m]; zero without SpikeInput::particleField.
Vec3d particleFieldAt(const SpikeInput& in, const Vec3d& x);
/// The solids' field at x [A/m], outside them; zero without SpikeInput::solids.
Vec3d solidFieldAt(const SpikeInput& in, const Vec3d& x);

/// One hexagonal pattern (one magnet).
struct SpikePattern {
    int magnet = -1;        ///< index into SpikeInput::magnets (the one dominating the origin)
    /// 0: the magnet's own pattern, from where its axis meets the surface; k > 0: the k-th
    /// pattern seeded where a surface with solids was supercritical but no pattern reached
    /// (a coat's far side, a sculpture's edge away from the magnet's axis).
    int region = 0;
    /// The pattern's identity in the art director's noise and in the tips' matching from frame
    /// to frame: the magnet's index for its own pattern.
    int noiseKey() const { return magnet + 7919 * region; }
    Vec3d origin;           ///< x0 on the surface [m]
    Vec3d normal;           ///< outward surface normal at x0
    Vec3d axis;             ///< first lattice axis (unit, tangent at x0)
    double spacing = 0;     ///< tip spacing l [m]
    double field = 0;       ///< |H(x0)| [A/m]
    double magnetization = 0; ///< |M(x0)| [A/m]
    int rings = 0;          ///< rings traced around x0 (tips traced in rows, a square's or a morphing
                            ///< lattice's: the most tips one traced line reached)
    SpikeParams::Lattice lattice = SpikeParams::Lattice::Hexagon; ///< the planform (SpikeParams::latticeOf)
    double squareness = 0;  ///< 0 = hexagons, 1 = squares, between: the morph (SpikeParams::squarenessOf)
};

struct SpikeTip {
    int pattern = -1;
    int i = 0, j = 0;       ///< lattice coordinates: base = x0 + i l e1 + j l e2 on a flat surface
                            ///< (e2 at 60 degrees from e1 on a hexagon, 90 on a square,
                            ///< 60 + 30 squareness between)
    Vec3d base;             ///< tip position on the undisplaced surface [m]
    Vec3d apex;             ///< base + height * direction [m]
    Vec3d direction;        ///< unit growth direction (the local field, outward)
    double height = 0;      ///< displacement of the tip [m]
};

struct SpikeResult {
    TriangleMesh mesh;      ///< the spiky surface, with normals and the input's comments
    TriangleMesh refined;   ///< the refined surface before displacement (same vertex order as mesh)
    std::vector<SpikePattern> patterns;
    std::vector<SpikeTip> tips;      ///< tips with height > 0, pattern by pattern
    CriticalMagnetization critical;  ///< eq. 16 for this fluid
    double volumeIn = 0, volumeOut = 0; ///< enclosed volumes [m^3]
    double maxHeight = 0;            ///< largest tip height [m]
    bool refinedOk = true;           ///< false: the mesh was not a manifold CGAL could remesh
};

} // namespace ferro

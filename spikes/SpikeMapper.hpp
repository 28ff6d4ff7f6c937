#pragma once
// The paper's spike synthesis (section 4.3, eqs. 12-16, Fig. 7) on one frame's surface mesh.
//
// What addSpikes does, in order:
//  1. Field and magnetization on the surface: H = magnets (at the frame's time) + the
//     magnetized particles' own field when available; |M| from the particles around a surface
//     point (Shepard average of their M), or from the fluid's law at H when there are none.
//     Surface closer than wall_margin to the container is wetted wall and never spiky.
//  2. One pattern per magnet whose field makes the fluid supercritical (|M| > M_c, eq. 16) where
//     the magnet's axis meets the free surface: that point is the pattern origin x0 (for a
//     uniform field: the line along the field through [spikes] origin, else through the
//     container's centre). The lattice axes come from a fixed world direction projected into
//     the tangent plane at x0, so a still magnet gives the same tips in every frame.
//  3. Tips, as in Fig. 7: from x0 trace the six axis directions along the surface with step
//     l (eq. 15, or the physical spacing), each next tip where the field line through the
//     stepped point meets the surface; tips between two axes interpolate the two n-th axis
//     tips and are again dropped along the field line onto the surface.
//     On a surface with solids (SpikeFluid::solids: a coat on a sculpture), the tips are
//     traced in rows along the surface, no two closer than 0.8 l, a line ends where the
//     normal has turned 75 degrees from the origin's, and every part of the
//     supercritical surface no pattern reached seeds a pattern of its own (at its vertex
//     nearest its centroid; SpikePattern::region). Surface within film_thickness of a solid (its bare wall,
//     a wetting film) is never spiky, and the field includes the solids' (SpikeSolids.hpp).
//  4. Refinement: CGAL isotropic remeshing of the supercritical region to l / resolution.
//  5. Displacement: each vertex gets the lattice coordinates of eq. 13 from its nearby tips
//     (each tip's local lattice basis, from its neighbours' positions, maps the vertex to
//     coordinates; a smooth partition of unity over tips blends them, exact on a regular
//     lattice), height C0 F (C0 = beta |H|, eq. 14) times the fades (magnetization from M_c,
//     distance from the wetted wall, coverage of the traced lattice), along the local field
//     direction (tilted at most max_tilt from the normal). Several patterns blend by field
//     dominance |H_i|^2 / sum |H_j|^2, so they meet without cracks.
//  6. Volume: a normal offset over the spiky region, weighted like the heights, restores the
//     input's enclosed volume (the paper's first listed limitation).
#include "sim/geometry/Container.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/scene/SimParams.hpp"
#include "spikes/SpikeParams.hpp"
#include "spikes/SpikePhysics.hpp"
#include "sim/core/TriangleMesh.hpp"

#include <functional>
#include <memory>
#include <vector>

namespace ferro {

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

struct SpikeInput {
    double time = 0;                    ///< the frame's time [s]
    TriangleMesh surface;               ///< closed fluid surface, outward triangles
    std::vector<Magnet> magnets;        ///< the magnets at the frame's time
    SpikeFluid fluid;
    SpikeParticles particles;
    /// Field of the magnetized particles at a point [A/m] (null = magnets only).
    std::function<Vec3d(const Vec3d&)> particleField;
    /// Field of the magnetized solids ([[solids]]) at a point outside them [A/m], solved in
    /// the magnets' and the particles' field (null = no solids).
    std::function<Vec3d(const Vec3d&)> solidField;
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
    /// The particles' positions [m] at an earlier time [s] (the particle file of the frame
    /// nearest it; null when there is none; SpikeInputError when it cannot be read), for
    /// SurfaceFields::fieldHistoryPeak: where the surface stood when the field was strongest.
    /// Null = unknown.
    std::function<std::shared_ptr<const std::vector<Vec3d>>(double)> pastParticles;
};

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

/// The field H [A/m] at x: the magnets plus, when given, the magnetized particles and solids.
Vec3d totalFieldAt(const SpikeInput& input, const Vec3d& x);

/// Synthesizes the spikes on input.surface. Deterministic: the same input gives the same
/// output. Below M_c everywhere (or with spikes disabled) the surface is returned unchanged.
/// When the input surface has vertex velocities, so does the result (mesh.velocities [m/s]):
/// the surface's, except that along the surface the spikes move as their tips do (they stand
/// where the field lays them out, not where the fluid flows), and their displacement grows
/// with their tips' amplitude. How the tips moved comes from `earlier`: the same surface and
/// particles with the magnets and their past `interval` [s] before (earlierSpikeInput), each
/// tip found again there by its lattice coordinates; null = the tips stand still (a field
/// still over the spikes' whole past).
SpikeResult addSpikes(const SpikeInput& input, const SpikeParams& params, const SpikeInput* earlier = nullptr,
                      double interval = 0);

} // namespace ferro

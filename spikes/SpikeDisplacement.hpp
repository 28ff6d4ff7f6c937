#pragma once
// The displacement of the surface into spikes (phase 5 of addSpikes, paper eqs. 13-14): at a
// surface point, the blended lattice coordinates of the nearby tips give the height profile,
// the tips give its amplitude and direction, and several patterns blend by field dominance.
// Internal to ferro_spikes.
#include "spikes/SpikeLattice.hpp"
#include "spikes/SpikeRefinement.hpp"

#include <vector>

namespace ferro {

/// The wetted wall on the refined surface: never displaced, and heights fade in away from it.
struct WettedWall {
    std::vector<char> wetted; ///< per vertex of the refined mesh: 1 = wetted wall
    HashGrid grid;           ///< the wetted vertices [m]
    double fade;              ///< heights ramp in over this distance from the wall [m]
};

/// The wetted vertices of `mesh` (SurfaceFields::wetted) and the fade distance: P.wallFade, or
/// minSpacing [m] (the smallest tip spacing of the patterns) when that is 0.
WettedWall findWettedWall(const TriangleMesh& mesh, const SurfaceFields& fields, const SpikeParams& P,
                          double minSpacing);

/// What the displacement at a surface point depends on (references, all outliving it).
struct SpikeSurface {
    const SurfaceFields& fields;
    const std::vector<Pattern>& patterns; ///< traced (traceLattice), at least one
    const std::vector<Magnet>& magnets;   ///< Pattern::info.magnet indexes these
    const SpikeParams& P;
    const WettedWall& wall;
};

/// The displacement [m] at surface point x [m] with unit outward normal nx, along `direction`
/// (unit). Over the tips of every pattern, each weighted by its ownership (settleSeams: 1 with
/// one pattern) and, with several patterns, faded out where its pattern's share of the field
/// dominance at x is under 0.3 (gone under 0.1): eq. 13 from every tip within its pattern's l
/// (its lattice map applied to x, F blended by the partition of unity (1 - d^2/l^2)^2, exact on
/// a regular lattice; sharpened by P.sharpness), the amplitude C0 (eq. 14) and direction from
/// the tips within 0.75 l (weight (1 - d^2/(0.75 l)^2)^4, so each spike is a rigid, symmetric
/// cone leaning along the field at its tip), the local field's C0 and direction taking over far
/// from every tip. `weight` is the fade factor: the magnetization gate (0 at M_c) times the
/// distance from the wetted wall times the coverage of the traced lattice; the displacement is
/// weight C0 F. 0 with weight 0 and direction nx on the wetted wall or where every fade is 0.
double spikeDisplacement(const SpikeSurface& surface, const Vec3d& x, const Vec3d& nx, double& weight,
                         Vec3d& direction);

/// Phase 5 on every vertex that is not wetted wall: `out` is the refined mesh with each such
/// vertex moved by spikeDisplacement along its direction (the normals of `refined`). Returns the
/// per-vertex fade weight (0 on the wetted wall), which the volume correction uses.
std::vector<double> displaceVertices(const SpikeSurface& surface, const RefinedSurface& refined, TriangleMesh& out);

} // namespace ferro

#pragma once
// The spiky surface's velocity (the last step of addSpikes): the fluid's surface carries the
// spikes, and the spikes' own motion (tips that drift with their lattice, grow, are born or
// sink) is added on top, so motion blur and the Blender cache show spikes that slide with a
// magnet instead of rising and sinking in place. Internal to ferro_spikes: it reads the
// phases' types (Pattern, RefinedSurface) and is called only by SpikeMapper.
#include "spikes/SpikeRefinement.hpp"

#include <vector>

namespace ferro {

/// How a tip moved over the interval before the frame: its drift along the surface [m/s] and
/// the relative rate its amplitude grows at [1/s].
struct TipMotion {
    Vec3d drift = Vec3d::Zero();
    double growth = 0;
};

/// Each tip of `patterns` found again in `before` (the lattice `interval` seconds [s] earlier,
/// on the same surface) by its magnet and lattice coordinates (i, j) drifts and grows by the
/// difference; a tip not there earlier grew from nothing over the interval. Without `before`
/// (a field still over the spikes' whole past) every tip stands still. One entry per tip of
/// each pattern, in order.
std::vector<std::vector<TipMotion>> tipMotions(const std::vector<Pattern>& patterns,
                                               const std::vector<Pattern>* before, double interval);

/// The input surface's vertex velocities [m/s] at `points` (on or next to the input
/// surface): each point takes its nearest input vertex's. Empty when the surface has none.
std::vector<Vec3> surfaceVelocityAt(const TriangleMesh& surface, const std::vector<Vec3>& points);

/// The spiky surface's velocity [m/s] at each vertex of `now` (the refined surface displaced
/// by `patterns` with `weight`, the displacement's weight per vertex: 0 off the spikes, 1 on
/// them). Along the surface (refined normals) the surface's velocity gives way, on a spike, to
/// the spike's own drift; the drift and the growth come from the nearby tips, blended as the
/// displacement blends them ((1 - d^2 / l^2)^3 times ownership, radius l), and the growth
/// scales the displacement. `surfaceVelocity` per refined vertex (surfaceVelocityAt).
std::vector<Vec3> spikyVelocities(const TriangleMesh& now, const RefinedSurface& refined,
                                  const std::vector<Vec3>& surfaceVelocity, const std::vector<double>& weight,
                                  const std::vector<Pattern>& patterns,
                                  const std::vector<std::vector<TipMotion>>& motion);

/// Adds to `velocity` (per vertex of `surface`) the velocity of spikes that have gone:
/// `then` is `surface` displaced as the earlier frame's spikes displaced it, `interval` [s]
/// before; the displacement is undone over the interval (the spikes sink where they stood).
void addSinkingVelocity(std::vector<Vec3>& velocity, const TriangleMesh& surface, const TriangleMesh& then,
                        double interval);

} // namespace ferro

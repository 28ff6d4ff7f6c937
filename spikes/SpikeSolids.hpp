#pragma once
// The scene's magnetizable solids ([[solids]], sim/solids) in one spike frame: where they stand
// (the film test of SurfaceFields::wetted) and the field their magnetization adds to the
// magnets' and the fluid's (SurfaceFields::field). Internal to ferro_spikes (SpikeFrames.cpp).
#include "sim/solids/SolidParams.hpp"
#include "spikes/SpikeTypes.hpp"

#include <string>
#include <vector>

namespace ferro {

/// Poses `solids` at in.time and fills in.fluid.solids (their surfaces as obstacles) and
/// in.solids: the surface charge (SurfaceChargeSolver) solved cold in the field of
/// in.magnets plus in.particleField, as ferro-sim's step solves it (panels of each solid's
/// panel_size, else twice `spacing` [m]), and the field that charge makes at a point outside
/// every solid [A/m]. Nothing when `solids` is empty. Throws SceneError (naming `where`) for a
/// mesh that cannot be read, SpikeInputError (BadInputError) for a charge solve that does not
/// converge or gives a non-finite charge.
void addSolids(const std::vector<SolidParams>& solids, double spacing, const std::string& where, SpikeInput& in);

} // namespace ferro

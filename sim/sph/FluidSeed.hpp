#pragma once
// The fluid at the start of a shot: the scene's [[fluid.block]]s filled with particles on a
// lattice at the spacing (or with an exact count), checked against the container.
#include "sim/core/Types.hpp"
#include "sim/scene/SimParams.hpp"
#include "sim/sph/Container.hpp"

#include <vector>

namespace ferro {

/// Initial fluid particles of a scene (lattice fill of its blocks) and their spacing.
struct FluidSeed {
    double spacing = 0;
    std::vector<Vec3> positions;
    std::vector<Vec3> velocities;
};
/// Fills the scene's blocks; throws SceneError naming the block for fluid outside the
/// container or a block that cannot hold its count.
FluidSeed seedFluid(const SimScene& scene, const Container& container);

} // namespace ferro

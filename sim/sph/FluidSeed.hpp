#pragma once
// The fluid at the start of a shot: the scene's [[fluid.block]]s filled with particles on a
// lattice at the spacing (or with an exact count), checked against the container.
#include "sim/core/Types.hpp"
#include "sim/scene/SimParams.hpp"
#include "sim/geometry/Container.hpp"

#include <string>
#include <vector>

namespace ferro {

/// The memory a run will need, estimated from the scene before anything is allocated.
struct RunSize {
    /// Bytes per fluid particle [B]: state, neighbour candidate slots and lists with DFSPH's
    /// stored gradients, solver and magnetics arrays; set above a measured DFSPH run's peak to
    /// leave room for the magnetics arrays and the wider neighbour slots of a compressed
    /// fluid. Measurements: docs/physics/sph-solver.md, "Memory estimate".
    static constexpr double kBytesPerFluidParticle = 3000;
    /// Bytes per boundary particle: position, volume, split coordinates, sort.
    static constexpr double kBytesPerBoundaryParticle = 64;
    double fluidParticles = 0, boundaryParticles = 0, spacing = 0, bytes = 0;
    std::string key;   ///< the scene key that sets the size ("fluid.spacing" or a block's count)
};
RunSize estimateRunSize(const SimScene& scene);
/// Throws SceneError naming the key when the estimate exceeds the available memory.
void checkRunSize(const SimScene& scene);

/// Initial fluid particles of a scene (lattice fill of its blocks) and their spacing.
struct FluidSeed {
    double spacing = 0;
    std::vector<Vec3> positions;
    std::vector<Vec3> velocities;
};
/// Fills the scene's blocks; throws SceneError naming the block for fluid outside the
/// container or a block that cannot hold its count.
/// `walls`: the scene's solids (solidWalls(scene)), which the blocks are filled around.
FluidSeed seedFluid(const SimScene& scene, const Container& container, const std::vector<SolidWall>& walls = {});

/// The scene's solids as walls at time 0 (ferro-sim keeps solids still), meshed at their panel
/// size, else twice the fluid spacing, else an eighth of their radius (a mesh file keeps its own
/// triangles; the walls sample themselves at the particle spacing whatever their triangles).
std::vector<SolidWall> solidWalls(const SimScene& scene);
/// The scene's solids (`walls`, solidWalls(scene)) where they may stand: each inside the
/// vessel or outside it but not across its wall, no magnet inside one, and some magnet
/// reaching each (at least 1 A/m at it during the shot). Throws a one-line SceneError.
void checkSolids(const SimScene& scene, const std::vector<SolidWall>& walls);

} // namespace ferro

#pragma once
// The fluid's velocity at surface points (mesh vertices, level-set voxels): the particles'
// velocities averaged with the surface's own density kernels (Shepard interpolation,
// sum_j W_j(x) v_j / sum_j W_j(x)), so that a mesh carries the motion the fluid it wraps has:
// what Blender, Houdini and Nuke use for motion blur and retiming. No OpenVDB here.
#include "surface/DensityKernels.hpp"

#include "sim/core/Types.hpp"

#include <vector>

namespace ferro {

/// Velocity [m/s] at each point of `at` [m] from the kernels (buildKernels over the particles)
/// and the particles' velocities `v` (indexed like buildKernels' positions). A point outside
/// every kernel takes the velocity of the kernel whose centre is nearest. Exact for a uniform
/// velocity; linear fields are reproduced to the kernels' asymmetry near the surface.
/// Parallel (TBB), deterministic. Empty `kernels` gives zeros.
std::vector<Vec3> interpolateVelocities(const std::vector<DensityKernel>& kernels, const std::vector<Vec3>& v,
                                        const std::vector<Vec3>& at);

} // namespace ferro

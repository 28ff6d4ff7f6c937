#pragma once
// The OpenVDB side of surface extraction, for the .cpp files that include OpenVDB already
// (SurfaceExtractor.cpp, KernelRasterizer.cpp, LevelSetFile.cpp): the kernels' rasterizer
// and the level set's file. Includes OpenVDB: never include it from a public header.
#include "surface/DensityKernels.hpp"

#include "sim/core/TriangleMesh.hpp"

#include <openvdb/openvdb.h>

#include <functional>
#include <string>
#include <vector>

namespace ferro {

/// openvdb::initialize(), once per process (thread-safe).
void initOpenVdb();

/// Sums the kernels [m] into a sparse FloatGrid (background 0, voxels > 0 active).
///
/// Parallel by leaf, not by kernel: every kernel is binned (counting sort) into the leaves
/// its bounding box touches, then each leaf gathers its kernels into a private 8^3 buffer.
/// No atomics or locks on voxel data, and the sum order is fixed (kernels in index order),
/// so the grid is the same for any thread count.
/// Voxel i has its centre at i * voxelSize [m]. Throws SurfaceError when a kernel lies beyond
/// the grid's index range (particles too far apart for the voxel size, or not finite).
openvdb::FloatGrid::Ptr rasterizeKernels(const std::vector<DensityKernel>& kernels, double voxelSize);

/// The level set of `mesh` as grid "surface" in a .vdb file and, when `velocity` is given, the
/// fluid's velocity on the same voxels as grid "v" (a staggered-free Vec3f grid, world units
/// m/s, the VDB convention other tools read for motion blur and advection). Written
/// atomically; throws MeshFileError (exit kExitIoError) when the file cannot be written.
void writeLevelSet(const std::string& path, const TriangleMesh& mesh, double voxelSize,
                   const std::function<std::vector<Vec3>(const std::vector<Vec3>&)>& velocity);

} // namespace ferro

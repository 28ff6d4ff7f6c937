#pragma once
// From particle positions to a closed, outward-oriented triangle mesh of the fluid surface.
//
// Pipeline: density kernels (DensityKernels.hpp) -> our sparse rasterizer into an OpenVDB
// FloatGrid (only leaves that some kernel reaches exist: never a dense box) -> optional
// Gaussian smoothing -> openvdb::tools::volumeToMesh at the iso level -> triangles with
// area-weighted vertex normals. The OpenVdb method replaces the first two steps by
// openvdb::tools::ParticlesToLevelSet (spheres of one spacing radius).
// OpenVDB stays inside SurfaceExtractor.cpp, KernelRasterizer.cpp and LevelSetFile.cpp
// (their shared header OpenVdbSurface.hpp is private to them).
#include "surface/SurfaceParams.hpp"
#include "sim/core/TriangleMesh.hpp"

#include "sim/core/Types.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace ferro {

/// The voxel sizes extractSurface accepts: from spacing / kMinVoxelsPerSpacing (finer needs
/// a grid of (50 x fluid size / spacing)^3 voxels and more) to kMaxSpacingsPerVoxel spacings
/// (coarser loses the fluid's features, a thin layer altogether).
constexpr double kMinVoxelsPerSpacing = 50;
constexpr double kMaxSpacingsPerVoxel = 4;

/// Input the extractor cannot mesh (non-finite positions, a grid too large to index).
class SurfaceError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The grid a voxel size asks for, estimated from the particles before anything is
/// allocated: the cells of one kernel diameter (2 kernelRadius spacings) that hold a
/// particle stand for the kernels' bounding boxes (which the rasterizer fills), each
/// filled with voxels. A compact fluid's estimate is its volume grown by a kernel radius
/// on every side; an isolated particle's is its kernel's box.
struct GridEstimate {
    /// Peak bytes per estimated voxel [B], a round bound over ferro-surface's measured peak
    /// (anisotropic method). Measurements: docs/physics/surface.md, last paragraph.
    static constexpr double kBytesPerVoxel = 20;
    double cell = 0;     ///< the cells' edge [m]: the kernel's diameter
    size_t cells = 0;    ///< cells holding a particle
    double voxels = 0;   ///< voxels in those cells
    double bytes = 0;    ///< voxels * kBytesPerVoxel
};
GridEstimate estimateGrid(const std::vector<Vec3>& positions, const SurfaceParams& params, double spacing,
                          double voxelSize);

/// Where the time of one extraction went, and what it produced.
struct SurfaceStats {
    double spacing = 0, voxelSize = 0, isoLevel = 0, offset = 0;
    size_t leaves = 0, activeVoxels = 0;
    double estimatedVoxels = 0;       ///< estimateGrid's voxels (the memory check's)
    double kernelSeconds = 0, rasterSeconds = 0, meshSeconds = 0;
    double velocitySeconds = 0;       ///< the vertex velocities' interpolation
    size_t particles = 0;             ///< particles meshed
    bool emptyFromParticles = false;  ///< particles were given but the mesh is empty
};

/// Meshes the fluid described by `positions` [m]. `spacing` > 0 is the particle spacing
/// (0 = params.spacing, else estimated). Empty input gives an empty mesh; a single particle
/// a small closed blob. If `vdbPath` is not empty, the surface is also written there as a
/// narrow-band level set (OpenVDB .vdb, grid "surface", atomically). With `velocities` (one
/// per particle [m/s]) the mesh gets vertex velocities and the .vdb a grid "v" on the band's
/// voxels, both interpolated with the surface's own kernels (VertexVelocity.hpp).
/// Throws SurfaceError for bad positions, for a grid (estimateGrid) larger than the
/// machine's available memory, MeshFileError when the .vdb cannot be written.
TriangleMesh extractSurface(const std::vector<Vec3>& positions, const SurfaceParams& params,
                            double spacing = 0, const std::string& vdbPath = {},
                            SurfaceStats* stats = nullptr, const std::vector<Vec3>* velocities = nullptr);

/// The density field of the kernels sampled into a sparse grid and meshed, without the
/// kernel step (for tests of the rasterizer against densityAt). Returns the sum of all
/// voxel values times the voxel volume (= total kernel volume if nothing was lost).
double rasterizedVolume(const std::vector<struct DensityKernel>& kernels, double voxelSize);

} // namespace ferro

// extractSurface of SurfaceExtractor.hpp: the three methods' grids (the kernels' rasterizer in
// KernelRasterizer.cpp, OpenVDB's sphere rasterizer), the offset, the meshing; the memory
// estimate is in GridEstimate.cpp, the .vdb file in LevelSetFile.cpp.
#include "surface/SurfaceExtractor.hpp"
#include "surface/OpenVdbParticles.hpp"
#include "surface/OpenVdbSurface.hpp"
#include "surface/VertexVelocity.hpp"

#include "sim/core/MachineMemory.hpp"

#include <openvdb/tools/FastSweeping.h>
#include <openvdb/tools/Filter.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/ValueTransformer.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/tick_count.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

namespace ferro {

namespace {

using openvdb::FloatGrid;
using LeafT = openvdb::FloatTree::LeafNodeType;

/// Quads split along the shorter diagonal, all polygons oriented outward (counter-clockwise
/// seen from outside). volumeToMesh's polygons of a level set (inside below the iso value)
/// come out the other way round (the tests check the sign of the volume), hence `flip`.
TriangleMesh toTriangleMesh(std::vector<openvdb::Vec3s>& points, std::vector<openvdb::Vec3I>& tris,
                            std::vector<openvdb::Vec4I>& quads, bool flip) {
    TriangleMesh mesh;
    mesh.vertices.resize(points.size());
    for (size_t i = 0; i < points.size(); ++i) mesh.vertices[i] = Vec3(points[i].x(), points[i].y(), points[i].z());
    mesh.triangles.reserve(tris.size() + 2 * quads.size());
    auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
        if (flip) mesh.triangles.push_back({a, c, b});
        else mesh.triangles.push_back({a, b, c});
    };
    for (const auto& t : tris) add(t[0], t[1], t[2]);
    for (const auto& q : quads) {
        const float d02 = (mesh.vertices[q[0]] - mesh.vertices[q[2]]).squaredNorm();
        const float d13 = (mesh.vertices[q[1]] - mesh.vertices[q[3]]).squaredNorm();
        if (d02 <= d13) {
            add(q[0], q[1], q[2]);
            add(q[0], q[2], q[3]);
        } else {
            add(q[0], q[1], q[3]);
            add(q[1], q[2], q[3]);
        }
    }
    return mesh;
}

double seconds(const tbb::tick_count& since) { return (tbb::tick_count::now() - since).seconds(); }

} // namespace

TriangleMesh extractSurface(const std::vector<Vec3>& positions, const SurfaceParams& params, double spacing,
                            const std::string& vdbPath, SurfaceStats* stats, const std::vector<Vec3>* velocities) {
    if (velocities && velocities->size() != positions.size())
        throw SurfaceError(std::to_string(velocities->size()) + " velocities for " + std::to_string(positions.size()) +
                           " particles");
    if (velocities)
        for (size_t i = 0; i < velocities->size(); ++i)
            if (!(*velocities)[i].allFinite())
                throw SurfaceError("particle " + std::to_string(i) + " has a non-finite velocity");
    initOpenVdb();
    for (size_t i = 0; i < positions.size(); ++i)
        if (!positions[i].allFinite())
            throw SurfaceError("particle " + std::to_string(i) + " has a non-finite position");
    if (!(spacing > 0)) spacing = params.spacing;
    if (!(spacing > 0)) spacing = estimateSpacing(positions);
    if (!(spacing > 0)) spacing = 1e-3; // zero or one particle: any scale will do
    const double voxel = params.voxelSize > 0 ? params.voxelSize : spacing / 2;
    // A voxel far below the spacing makes a grid no machine holds (OpenVDB then fails with
    // "Non-zero scale values required" or runs out of memory); one far above it loses the
    // surface (an empty or blocky mesh). Both are typos, refused with the sizes named.
    if (!std::isfinite(voxel) || !(voxel > 0))
        throw SurfaceError("voxel size " + std::to_string(voxel) + " m: must be a positive number");
    if (voxel < spacing / kMinVoxelsPerSpacing || voxel > kMaxSpacingsPerVoxel * spacing) {
        std::ostringstream o;
        o << "voxel size " << voxel << " m against a particle spacing of " << spacing << " m: must be within "
          << spacing / kMinVoxelsPerSpacing << " .. " << kMaxSpacingsPerVoxel * spacing
          << " m (1/" << kMinVoxelsPerSpacing << " to " << kMaxSpacingsPerVoxel << " spacings; default half a spacing)";
        throw SurfaceError(o.str());
    }
    // Before anything is allocated: a fine voxel over many particles asks for more memory
    // than the machine has (std::bad_alloc or the OOM killer after minutes otherwise).
    GridEstimate grid;
    if (!positions.empty()) {
        grid = estimateGrid(positions, params, spacing, voxel);
        const double available = availableMemoryBytes();
        if (available > 0 && grid.bytes > available) {
            std::ostringstream o;
            o.precision(3);
            o << "voxel size " << voxel << " m (--voxel-size or surface.voxel_size; the spacing is " << spacing
              << " m): the grid needs about " << formatBytes(grid.bytes) << " (" << grid.voxels << " voxels around "
              << positions.size() << " particles), more than the " << formatBytes(available)
              << " this machine has available";
            throw SurfaceError(o.str());
        }
    }
    SurfaceStats local;
    SurfaceStats& st = stats ? *stats : local;
    st = SurfaceStats{};
    st.spacing = spacing;
    st.voxelSize = voxel;
    st.estimatedVoxels = grid.voxels;

    TriangleMesh mesh;
    std::vector<DensityKernel> kernels; // the density's kernels, kept for the velocity
    if (!positions.empty()) {
        std::vector<openvdb::Vec3s> points;
        std::vector<openvdb::Vec3I> tris;
        std::vector<openvdb::Vec4I> quads;
        const SurfaceCalibration cal = calibrateSurface(params, spacing);
        FloatGrid::Ptr grid;        // what volumeToMesh meshes at `iso`
        double iso = 0;
        auto t0 = tbb::tick_count::now();
        if (params.method == SurfaceMethod::OpenVdb) {
            grid = openvdb::createLevelSet<FloatGrid>(voxel, 3.0);
            openvdb::tools::ParticlesToLevelSet<FloatGrid> raster(*grid);
            raster.rasterizeSpheres(ParticleList{positions, spacing});
            raster.finalize(true);
            iso = 0;
            st.rasterSeconds = seconds(t0);
            t0 = tbb::tick_count::now();
            if (std::abs(cal.offset) > 0.05 * voxel) {
                // Inside a union of spheres ParticlesToLevelSet's values are no distances to
                // the union's surface: re-distance the band (fast sweeping) before moving in.
                grid = openvdb::tools::sdfToSdf(*grid, 0.0f, 1);
                iso = cal.offset;
            }
        } else {
            kernels = buildKernels(positions, params, spacing);
            st.kernelSeconds = seconds(t0);
            t0 = tbb::tick_count::now();
            grid = rasterizeKernels(kernels, voxel);
            st.rasterSeconds = seconds(t0);
            t0 = tbb::tick_count::now();
            if (params.smoothing > 0) {
                openvdb::tools::Filter<FloatGrid> filter(*grid);
                filter.gaussian(1, params.smoothing);
            }
            iso = cal.isoLevel;
            if (std::abs(cal.offset) > 0.05 * voxel) {
                // Moving the surface along its normals must not fold it where it is concave:
                // offset a distance field, not the vertices. Fast sweeping turns the density
                // into distances on its active voxels, first grown out past the offset.
                const int grow = int(std::ceil(std::max(0.0, cal.offset) / voxel)) + 1;
                openvdb::tools::dilateActiveValues(grid->tree(), grow, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                                   openvdb::tools::IGNORE_TILES);
                // Only a band around the surface needs distances: voxels deeper inside than
                // the band are switched off, and filled in as inside afterwards.
                const int band = grow + 2;
                openvdb::BoolGrid::Ptr deep = openvdb::BoolGrid::create(false);
                {
                    // The inside voxels, leaf by leaf in parallel.
                    std::vector<const LeafT*> in;
                    grid->tree().getNodes(in);
                    using MaskLeaf = openvdb::BoolTree::LeafNodeType;
                    std::vector<MaskLeaf*> out(in.size(), nullptr);
                    const float level = float(iso);
                    tbb::parallel_for(tbb::blocked_range<size_t>(0, in.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t l = r.begin(); l != r.end(); ++l) {
                            auto* leaf = new MaskLeaf(in[l]->origin(), false);
                            for (auto it = in[l]->cbeginValueOn(); it; ++it)
                                if (*it > level) leaf->setValueOn(it.pos());
                            if (leaf->isEmpty()) delete leaf;
                            else out[l] = leaf;
                        }
                    });
                    for (MaskLeaf* leaf : out)
                        if (leaf) deep->tree().addLeaf(leaf);
                }
                openvdb::tools::erodeActiveValues(deep->tree(), band, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                                  openvdb::tools::IGNORE_TILES);
                grid->tree().topologyDifference(deep->tree());
                grid = openvdb::tools::fogToSdf(*grid, float(iso), 1);
                openvdb::tools::signedFloodFill(grid->tree());
                iso = cal.offset;
            } else {
                // Negated, the density follows the level-set convention (inside below the
                // iso value), as the distance fields do.
                openvdb::tools::foreach(grid->beginValueOn(), [](const FloatGrid::ValueOnIter& it) { it.setValue(-*it); });
                iso = -iso;
            }
            grid->setGridClass(openvdb::GRID_LEVEL_SET);
        }
        st.leaves = grid->tree().leafCount();
        st.activeVoxels = grid->activeVoxelCount();
        st.isoLevel = iso;
        openvdb::tools::volumeToMesh(*grid, points, tris, quads, iso, params.adaptivity);
        mesh = toTriangleMesh(points, tris, quads, /*flip=*/true);
        computeVertexNormals(mesh);
        st.offset = cal.offset;
        st.meshSeconds = seconds(t0);
    }
    st.particles = positions.size();
    st.emptyFromParticles = !positions.empty() && mesh.empty();
    std::function<std::vector<Vec3>(const std::vector<Vec3>&)> velocityAt;
    if (velocities && !positions.empty()) {
        // The OpenVDB method rasterizes spheres, not kernels: its velocity takes round
        // kernels of the same support.
        if (kernels.empty()) {
            SurfaceParams round = params;
            round.method = SurfaceMethod::Isotropic;
            kernels = buildKernels(positions, round, spacing);
        }
        velocityAt = [&](const std::vector<Vec3>& at) { return interpolateVelocities(kernels, *velocities, at); };
        const auto t0 = tbb::tick_count::now();
        mesh.velocities = velocityAt(mesh.vertices);
        st.velocitySeconds = seconds(t0);
    }
    if (!vdbPath.empty()) writeLevelSet(vdbPath, mesh, voxel, velocityAt);
    return mesh;
}

} // namespace ferro

// Sparse anisotropic-kernel rasterizer on OpenVDB and mesh extraction (see SurfaceExtractor.hpp).
#include "surface/SurfaceExtractor.hpp"
#include "surface/VertexVelocity.hpp"
#include "surface/OpenVdbParticles.hpp"

#include "surface/DensityKernels.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/core/MachineMemory.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/FastSweeping.h>
#include <openvdb/tools/Filter.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/ValueTransformer.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/tick_count.h>

#include <algorithm>
#include <functional>
#include <atomic>
#include <cmath>
#include <sstream>
#include <mutex>

namespace ferro {

namespace {

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::FloatTree;
using LeafT = FloatTree::LeafNodeType;
constexpr int kLeafDim = int(LeafT::DIM); // 8
constexpr int kLeafLog = int(LeafT::LOG2DIM);

void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

/// Index-space bounding box of one kernel: voxel i has its centre at i * voxel.
struct VoxelBox {
    int lo[3], hi[3];
};

/// Largest voxel index we accept: keeps every coordinate and leaf offset inside int.
constexpr double kMaxIndex = 1 << 29;

VoxelBox voxelBox(const DensityKernel& k, float invVoxel) {
    VoxelBox b;
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = int(std::ceil((k.centre[a] - k.halfExtent[a]) * invVoxel));
        b.hi[a] = int(std::floor((k.centre[a] + k.halfExtent[a]) * invVoxel));
    }
    return b;
}

/// Adds every kernel of `list` into the 8^3 buffer of the leaf at `origin`.
/// Each kernel is visited only where its ellipsoid meets the leaf: per (x, y) column the
/// z range inside the ellipsoid comes from the quadratic q(z) < 1, so no voxel outside it
/// is touched.
void splatLeaf(const Coord& origin, const uint32_t* list, size_t count, const std::vector<DensityKernel>& kernels,
               const std::vector<VoxelBox>& boxes, float voxel, float* buf) {
    const int ox = origin.x(), oy = origin.y(), oz = origin.z();
    for (size_t n = 0; n < count; ++n) {
        const DensityKernel& k = kernels[list[n]];
        const VoxelBox& b = boxes[list[n]];
        const int x0 = std::max(b.lo[0], ox), x1 = std::min(b.hi[0], ox + kLeafDim - 1);
        const int y0 = std::max(b.lo[1], oy), y1 = std::min(b.hi[1], oy + kLeafDim - 1);
        const int z0 = std::max(b.lo[2], oz), z1 = std::min(b.hi[2], oz + kLeafDim - 1);
        if (x0 > x1 || y0 > y1 || z0 > z1) continue;
        const float cx = k.centre.x(), cy = k.centre.y(), cz = k.centre.z();
        const float A = k.m[5], invA = 1.0f / A, amp = k.amplitude;
        for (int ix = x0; ix <= x1; ++ix) {
            const float dx = float(ix) * voxel - cx;
            for (int iy = y0; iy <= y1; ++iy) {
                const float dy = float(iy) * voxel - cy;
                // q(dz) = A dz^2 + B dz + C
                const float B = 2 * (k.m[2] * dx + k.m[4] * dy);
                const float C = k.m[0] * dx * dx + 2 * k.m[1] * dx * dy + k.m[3] * dy * dy;
                const float disc = B * B - 4 * A * (C - 1);
                if (disc <= 0) continue;
                const float root = std::sqrt(disc);
                const float zlo = cz + (-B - root) * 0.5f * invA, zhi = cz + (-B + root) * 0.5f * invA;
                const int za = std::max(z0, int(std::ceil(zlo / voxel)));
                const int zb = std::min(z1, int(std::floor(zhi / voxel)));
                float* row = buf + ((ix - ox) << (2 * kLeafLog)) + ((iy - oy) << kLeafLog) - oz;
                for (int iz = za; iz <= zb; ++iz) {
                    const float dz = float(iz) * voxel - cz;
                    const float t = 1 - ((A * dz + B) * dz + C);
                    if (t > 0) row[iz] += amp * t * t * t;
                }
            }
        }
    }
}

/// Sums the kernels into a sparse FloatGrid (background 0, voxels > 0 active).
///
/// Parallel by leaf, not by kernel: every kernel is binned (counting sort) into the leaves
/// its bounding box touches, then each leaf gathers its kernels into a private 8^3 buffer.
/// No atomics or locks on voxel data, and the sum order is fixed (kernels in index order),
/// so the grid is the same for any thread count.
FloatGrid::Ptr rasterize(const std::vector<DensityKernel>& kernels, double voxelSize) {
    FloatGrid::Ptr grid = FloatGrid::create(0.0f);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxelSize));
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->setName("density");
    const size_t n = kernels.size();
    if (n == 0) return grid;
    const float voxel = float(voxelSize), invVoxel = float(1.0 / voxelSize);

    std::vector<VoxelBox> boxes(n);
    struct LeafBounds {
        int lo[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, hi[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
    };
    const LeafBounds lb = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 4096), LeafBounds{},
        [&](const tbb::blocked_range<size_t>& r, LeafBounds acc) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const DensityKernel& k = kernels[i];
                for (int a = 0; a < 3; ++a)
                    if (!(std::abs(double(k.centre[a]) * invVoxel) + double(k.halfExtent[a]) * invVoxel < kMaxIndex))
                        throw SurfaceError("particles lie too far apart for the voxel size (or are not finite)");
                boxes[i] = voxelBox(k, invVoxel);
                for (int a = 0; a < 3; ++a) {
                    acc.lo[a] = std::min(acc.lo[a], boxes[i].lo[a] >> kLeafLog);
                    acc.hi[a] = std::max(acc.hi[a], boxes[i].hi[a] >> kLeafLog);
                }
            }
            return acc;
        },
        [](LeafBounds a, const LeafBounds& b) {
            for (int k = 0; k < 3; ++k) {
                a.lo[k] = std::min(a.lo[k], b.lo[k]);
                a.hi[k] = std::max(a.hi[k], b.hi[k]);
            }
            return a;
        });
    size_t dims[3], total = 1;
    for (int a = 0; a < 3; ++a) {
        dims[a] = size_t(std::max(0, lb.hi[a] - lb.lo[a] + 1));
        total *= dims[a];
    }
    if (total == 0) return grid;

    // Bin kernels by leaf. Leaves are indexed densely over the particles' leaf bounding box
    // when that is small (the usual case: fluid fills a good part of its box); otherwise
    // (spray over a huge box) the (leaf, kernel) pairs are sorted instead.
    std::vector<uint64_t> leafKeys;    // key of each occupied leaf
    std::vector<size_t> leafStart;     // its kernels: binned[leafStart[l] .. leafStart[l+1])
    std::vector<uint32_t> binned;
    auto leafKey = [&](int lx, int ly, int lz) {
        return (uint64_t(lz - lb.lo[2]) * dims[1] + uint64_t(ly - lb.lo[1])) * dims[0] + uint64_t(lx - lb.lo[0]);
    };
    auto forEachLeafOf = [&](size_t i, auto&& f) {
        const VoxelBox& b = boxes[i];
        for (int lz = b.lo[2] >> kLeafLog; lz <= b.hi[2] >> kLeafLog; ++lz)
            for (int ly = b.lo[1] >> kLeafLog; ly <= b.hi[1] >> kLeafLog; ++ly)
                for (int lx = b.lo[0] >> kLeafLog; lx <= b.hi[0] >> kLeafLog; ++lx) f(leafKey(lx, ly, lz));
    };
    constexpr size_t kDenseLimit = size_t(1) << 23;
    if (total <= kDenseLimit) {
        std::vector<std::atomic<uint32_t>> counts(total);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, total, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) counts[i].store(0, std::memory_order_relaxed);
        });
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 2048), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                forEachLeafOf(i, [&](uint64_t key) { counts[key].fetch_add(1, std::memory_order_relaxed); });
        });
        std::vector<uint32_t> slot(total);
        size_t sum = 0;
        for (size_t key = 0; key < total; ++key) {
            const uint32_t c = counts[key].load(std::memory_order_relaxed);
            if (c == 0) continue;
            slot[key] = uint32_t(leafKeys.size());
            leafKeys.push_back(key);
            leafStart.push_back(sum);
            sum += c;
        }
        leafStart.push_back(sum);
        binned.resize(sum);
        std::vector<std::atomic<size_t>> cursor(leafKeys.size());
        for (size_t l = 0; l < leafKeys.size(); ++l) cursor[l].store(leafStart[l], std::memory_order_relaxed);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 2048), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                forEachLeafOf(i, [&](uint64_t key) {
                    binned[cursor[slot[key]].fetch_add(1, std::memory_order_relaxed)] = uint32_t(i);
                });
        });
        // Threads filled each bin in arbitrary order: sort for a reproducible sum.
        tbb::parallel_for(tbb::blocked_range<size_t>(0, leafKeys.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t l = r.begin(); l != r.end(); ++l)
                std::sort(binned.begin() + long(leafStart[l]), binned.begin() + long(leafStart[l + 1]));
        });
    } else {
        std::vector<std::pair<uint64_t, uint32_t>> pairs;
        for (size_t i = 0; i < n; ++i) forEachLeafOf(i, [&](uint64_t key) { pairs.emplace_back(key, uint32_t(i)); });
        tbb::parallel_sort(pairs.begin(), pairs.end());
        binned.resize(pairs.size());
        for (size_t p = 0; p < pairs.size(); ++p) {
            if (p == 0 || pairs[p].first != pairs[p - 1].first) {
                leafKeys.push_back(pairs[p].first);
                leafStart.push_back(p);
            }
            binned[p] = pairs[p].second;
        }
        leafStart.push_back(pairs.size());
    }

    std::vector<LeafT*> leaves(leafKeys.size(), nullptr);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leafKeys.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        alignas(64) float buf[LeafT::SIZE];
        for (size_t l = r.begin(); l != r.end(); ++l) {
            const uint64_t key = leafKeys[l];
            const int lx = int(key % dims[0]) + lb.lo[0];
            const int ly = int((key / dims[0]) % dims[1]) + lb.lo[1];
            const int lz = int(key / (dims[0] * dims[1])) + lb.lo[2];
            const Coord origin(lx * kLeafDim, ly * kLeafDim, lz * kLeafDim);
            std::fill(buf, buf + LeafT::SIZE, 0.0f);
            splatLeaf(origin, binned.data() + leafStart[l], leafStart[l + 1] - leafStart[l], kernels, boxes,
                      voxel, buf);
            bool any = false;
            for (float v : buf) any = any || v > 0;
            if (!any) continue;
            auto* leaf = new LeafT(origin, 0.0f, false);
            for (openvdb::Index i = 0; i < LeafT::SIZE; ++i)
                if (buf[i] > 0) leaf->setValueOn(i, buf[i]);
            leaves[l] = leaf;
        }
    });
    FloatTree& tree = grid->tree();
    for (LeafT* leaf : leaves)
        if (leaf) tree.addLeaf(leaf);
    return grid;
}


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

/// The level set of `mesh` as grid "surface" in a .vdb file and, when `velocity` is given, the
/// fluid's velocity on the same voxels as grid "v" (a staggered-free Vec3f grid, world units
/// m/s, the VDB convention other tools read for motion blur and advection).
void writeLevelSet(const std::string& path, const TriangleMesh& mesh, double voxelSize,
                   const std::function<std::vector<Vec3>(const std::vector<Vec3>&)>& velocity) {
    initOpenVdb();
    auto xform = openvdb::math::Transform::createLinearTransform(voxelSize);
    std::vector<openvdb::Vec3s> points(mesh.vertices.size());
    for (size_t i = 0; i < points.size(); ++i)
        points[i] = openvdb::Vec3s(mesh.vertices[i].x(), mesh.vertices[i].y(), mesh.vertices[i].z());
    std::vector<openvdb::Vec3I> tris(mesh.triangles.size());
    for (size_t t = 0; t < tris.size(); ++t)
        tris[t] = openvdb::Vec3I(mesh.triangles[t][0], mesh.triangles[t][1], mesh.triangles[t][2]);
    FloatGrid::Ptr sdf = openvdb::tools::meshToLevelSet<FloatGrid>(*xform, points, tris, 3.0f);
    sdf->setName("surface");
    sdf->setGridClass(openvdb::GRID_LEVEL_SET);
    openvdb::GridPtrVec grids{sdf};
    if (velocity) {
        // The velocity at every active voxel of the band, in the band's own topology.
        std::vector<openvdb::Coord> coords;
        coords.reserve(size_t(sdf->activeVoxelCount()));
        for (auto it = sdf->cbeginValueOn(); it; ++it) coords.push_back(it.getCoord());
        std::vector<Vec3> centres(coords.size());
        for (size_t i = 0; i < coords.size(); ++i) {
            const openvdb::Vec3d w = xform->indexToWorld(coords[i]);
            centres[i] = Vec3(Real(w.x()), Real(w.y()), Real(w.z()));
        }
        const std::vector<Vec3> v = velocity(centres);
        openvdb::Vec3fGrid::Ptr vg = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
        vg->setTransform(xform->copy());
        vg->setName("v");
        vg->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
        auto acc = vg->getAccessor();
        for (size_t i = 0; i < coords.size(); ++i) acc.setValue(coords[i], openvdb::Vec3f(v[i].x(), v[i].y(), v[i].z()));
        grids.push_back(vg);
    }
    try {
        writeFileAtomicallyByPath(path, [&](const std::string& tmp) {
            try {
                openvdb::io::File file(tmp);
                file.write(grids);
                file.close();
            } catch (const std::exception& e) {
                throw MeshFileError(path + ": cannot write the level set: " + e.what(), kExitIoError);
            }
        });
    } catch (const AtomicFileError&) {
        throw MeshFileError(path + ": cannot rename the temporary file", kExitIoError);
    }
}

double seconds(const tbb::tick_count& since) { return (tbb::tick_count::now() - since).seconds(); }

} // namespace

double rasterizedVolume(const std::vector<DensityKernel>& kernels, double voxelSize) {
    initOpenVdb();
    FloatGrid::Ptr grid = rasterize(kernels, voxelSize);
    double sum = 0;
    for (auto it = grid->cbeginValueOn(); it; ++it) sum += double(*it);
    return sum * voxelSize * voxelSize * voxelSize;
}

GridEstimate estimateGrid(const std::vector<Vec3>& positions, const SurfaceParams& params, double spacing,
                          double voxelSize) {
    GridEstimate g;
    g.cell = 2 * std::max(params.kernelRadius, 1.0) * spacing;
    if (positions.empty() || !(g.cell > 0) || !(voxelSize > 0)) return g;
    // Cell keys, sorted and counted: O(n log n), a few MB, no grid. Coordinates beyond
    // 2^20 cells from the origin wrap (the key has 21 bits per axis): such a cloud is
    // refused by the rasterizer's index check anyway, and wrapping only undercounts.
    std::vector<uint64_t> keys(positions.size());
    const double inv = 1.0 / g.cell;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, positions.size(), 1 << 14), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            uint64_t key = 0;
            for (int a = 0; a < 3; ++a) {
                const double c = std::floor(double(positions[i][a]) * inv);
                const int64_t k = std::isfinite(c) ? int64_t(std::clamp(c, -1e15, 1e15)) : 0;
                key = (key << 21) | (uint64_t(k) & ((uint64_t(1) << 21) - 1));
            }
            keys[i] = key;
        }
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    g.cells = size_t(std::unique(keys.begin(), keys.end()) - keys.begin());
    const double perCell = std::pow(g.cell / voxelSize, 3);
    g.voxels = double(g.cells) * perCell;
    g.bytes = g.voxels * GridEstimate::kBytesPerVoxel;
    return g;
}

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
            grid = rasterize(kernels, voxel);
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

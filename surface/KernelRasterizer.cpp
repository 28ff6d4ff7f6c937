// The kernels' rasterizer of OpenVdbSurface.hpp: every kernel binned into the 8^3 leaves
// its box touches, each leaf summed in a private buffer (no atomics on voxel data, a fixed
// sum order: the same grid for any thread count).
#include "surface/OpenVdbSurface.hpp"
#include "surface/SurfaceExtractor.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

namespace ferro {

namespace {

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::FloatTree;
using LeafT = FloatTree::LeafNodeType;
constexpr int kLeafDim = int(LeafT::DIM); // 8
constexpr int kLeafLog = int(LeafT::LOG2DIM);

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

} // namespace

void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::FloatGrid::Ptr rasterizeKernels(const std::vector<DensityKernel>& kernels, double voxelSize) {
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

double rasterizedVolume(const std::vector<DensityKernel>& kernels, double voxelSize) {
    initOpenVdb();
    openvdb::FloatGrid::Ptr grid = rasterizeKernels(kernels, voxelSize);
    double sum = 0;
    for (auto it = grid->cbeginValueOn(); it; ++it) sum += double(*it);
    return sum * voxelSize * voxelSize * voxelSize;
}

} // namespace ferro

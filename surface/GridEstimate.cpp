// estimateGrid of SurfaceExtractor.hpp: the grid a voxel size asks for, before anything is
// allocated.
#include "surface/SurfaceExtractor.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace ferro {

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

} // namespace ferro

#pragma once
// Uniform-grid neighbour search over particles sorted by cell.
//
// Fluid particles are reordered every step by (cell, id): neighbours in memory are
// neighbours in space (cache-friendly loops), each row of three cells is one contiguous
// index range, and the order is a pure function of the positions, so a resumed run
// sums in exactly the same order as an uninterrupted one (bitwise-identical frames).
#include "sim/Types.hpp"

#include <cstdint>
#include <vector>

namespace ferro {

/// Dense grid of cells of size >= `cellSize` over an axis-aligned box.
struct GridGeometry {
    Vec3 origin{0, 0, 0};
    Real cellSize = 1;
    int dims[3] = {1, 1, 1};

    /// Covers [lo, hi] with cells of at least `cellSize`; cells grow if the box would
    /// need more than `maxCells` cells (correct, only slower, for very spread particles).
    void fit(const Vec3& lo, const Vec3& hi, Real cellSize, size_t maxCells = size_t(1) << 24);
    size_t cellCount() const { return size_t(dims[0]) * dims[1] * dims[2]; }
    void cellOf(const Vec3& p, int c[3]) const;
    uint32_t linear(const int c[3]) const { return uint32_t((size_t(c[2]) * dims[1] + c[1]) * dims[0] + c[0]); }
};

/// Points sorted by cell with per-cell start offsets.
class SortedGrid {
public:
    /// Computes the permutation that sorts `x` by (cell, tie) where `tie[i]` breaks ties
    /// deterministically (particle ids); `order[k]` is the old index of the k-th point.
    void sort(const std::vector<Vec3>& x, const std::vector<uint32_t>& tie, Real cellSize,
              std::vector<uint32_t>& order);
    /// Builds cell offsets for points already sorted by cell with geometry `g`.
    void index(const std::vector<Vec3>& sortedX, const GridGeometry& g);

    const GridGeometry& geometry() const { return geom_; }
    /// Index range [begin, end) of the points in cells c0..c0+2 along x (clamped) of row (cy, cz).
    void rowRange(int cx, int cy, int cz, uint32_t& begin, uint32_t& end) const;

private:
    GridGeometry geom_;
    std::vector<uint32_t> cellStart_; // size cellCount + 1
    std::vector<uint64_t> keys_;
};

/// Compressed neighbour lists with the kernel gradient of each pair stored beside the
/// index: the iterative pressure solvers sweep them many times per step.
struct NeighborLists {
    std::vector<uint32_t> offset;   ///< size n + 1
    std::vector<uint32_t> index;    ///< neighbour indices, pair k of particle i at offset[i] + k
    std::vector<Vec3> gradW;        ///< grad_i W(x_i - x_j) of each pair
    std::vector<Real> W;            ///< W(|x_i - x_j|) of each pair
    size_t pairs() const { return index.size(); }
};

} // namespace ferro

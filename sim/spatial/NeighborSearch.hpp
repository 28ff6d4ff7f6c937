#pragma once
// Uniform-grid neighbour search over particles sorted by cell.
//
// Fluid particles are reordered at every search by (cell, id): neighbours in memory are
// neighbours in space (cache-friendly loops), each row of three cells is one contiguous
// index range, and the order is a pure function of the positions, so a resumed run
// sums in exactly the same order as an uninterrupted one (bitwise-identical frames).
#include "sim/core/Types.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ferro {

/// Coordinates of x split into three arrays (the search's and the four-lane loops' layout).
inline void splitCoordinates(const std::vector<Vec3>& x, std::vector<Real>& px, std::vector<Real>& py,
                      std::vector<Real>& pz) {
    px.resize(x.size());
    py.resize(x.size());
    pz.resize(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
        px[i] = x[i].x();
        py[i] = x[i].y();
        pz[i] = x[i].z();
    }
}

/// Dense grid of cells, one search radius wide, over an axis-aligned box (why not half a
/// radius: docs/physics/sph-solver.md, "Neighbour search").
struct GridGeometry {
    static constexpr int kPad = 1;  ///< spare cells on every side (the stencil's reach)
    Vec3 origin{0, 0, 0};
    Real cellSize = 1;
    int dims[3] = {1, 1, 1};

    /// Covers [lo, hi] with cells of at least `cellSize`; cells grow if the box would
    /// need more than `maxCells` cells (correct, only slower, for very spread particles).
    void fit(const Vec3& lo, const Vec3& hi, Real cellSize, size_t maxCells = size_t(1) << 24);
    size_t cellCount() const { return size_t(dims[0]) * dims[1] * dims[2]; }
    void cellOf(const Vec3& p, int c[3]) const;
    uint32_t linear(int cx, int cy, int cz) const { return uint32_t((size_t(cz) * dims[1] + cy) * dims[0] + cx); }
};

/// Points sorted by cell with per-cell start offsets.
class SortedGrid {
public:
    /// Computes the permutation that sorts `x` by (cell, tie) where `tie[i]` breaks ties
    /// deterministically (particle ids); `order[k]` is the old index of the k-th point.
    /// Cells are `radius` wide.
    void sort(const std::vector<Vec3>& x, const std::vector<uint32_t>& tie, Real radius,
              std::vector<uint32_t>& order);
    /// Builds cell offsets for points already sorted by cell with geometry `g`.
    void index(const std::vector<Vec3>& sortedX, const GridGeometry& g);

    const GridGeometry& geometry() const { return geom_; }

    /// Calls f(begin, end) for index ranges that together hold every point within
    /// `radius` (the cell size) of p, and more: the 3 x 3 rows of three cells around p's
    /// cell, each one contiguous range since points are sorted by cell.
    template <class F>
    void forEachCandidateRange(const Vec3& p, F&& f) const {
        int c[3];
        geom_.cellOf(p, c);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy) {
                const uint32_t row = geom_.linear(c[0], c[1] + dy, c[2] + dz);
                f(cellStart_[row - 1], cellStart_[row + 2]);
            }
    }

private:
    GridGeometry geom_;
    std::vector<uint32_t> cellStart_; // size cellCount + 1
    std::vector<uint64_t> keys_;
};

/// Appends to `out` the indices j in [begin, end) with |x_j - p|^2 < h2, skipping `self`.
/// Positions come as separate coordinate arrays so that blocks of 8 candidates are tested
/// with SIMD into a bit mask and only the hits (about one in seven) are appended; the tail
/// appends branch-free (write always, advance on a hit): no unpredictable branch per
/// candidate.
inline uint32_t gatherRange(const Real* px, const Real* py, const Real* pz, uint32_t begin, uint32_t end,
                            const Vec3& p, Real h2, uint32_t self, uint32_t* out, uint32_t count) {
    const Real x = p.x(), y = p.y(), z = p.z();
    uint32_t j = begin;
#if defined(__SSE2__)
    // SSE is part of x86-64: four distance tests per instruction, hits as a bit mask.
    const __m128 vx = _mm_set1_ps(x), vy = _mm_set1_ps(y), vz = _mm_set1_ps(z), vh2 = _mm_set1_ps(h2);
    for (; j + 8 <= end; j += 8) {
        uint32_t mask = 0;
        for (uint32_t l = 0; l < 8; l += 4) {
            const __m128 dx = _mm_sub_ps(_mm_loadu_ps(px + j + l), vx);
            const __m128 dy = _mm_sub_ps(_mm_loadu_ps(py + j + l), vy);
            const __m128 dz = _mm_sub_ps(_mm_loadu_ps(pz + j + l), vz);
            const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
            mask |= uint32_t(_mm_movemask_ps(_mm_cmplt_ps(d2, vh2))) << l;
        }
        if (self - j < 8) mask &= ~(1u << (self - j));
        while (mask) {
            out[count++] = j + uint32_t(__builtin_ctz(mask));
            mask &= mask - 1;
        }
    }
#endif
    for (; j < end; ++j) {
        const Real dx = px[j] - x, dy = py[j] - y, dz = pz[j] - z;
        out[count] = j;
        count += uint32_t((dx * dx + dy * dy + dz * dz < h2) & (j != self));
    }
    return count;
}

/// Neighbours of `p` among the points of `grid` (coordinates px/py/pz), into `out`, which
/// must hold `room` entries. Returns the count, or room + 1 if they did not fit.
inline uint32_t gatherNeighbors(const SortedGrid& grid, const Real* px, const Real* py, const Real* pz,
                                const Vec3& p, Real radius, uint32_t self, uint32_t* out, uint32_t room) {
    uint32_t count = 0;
    const Real h2 = radius * radius;
    grid.forEachCandidateRange(p, [&](uint32_t beg, uint32_t end) {
        if (count > room) return;
        if (count + (end - beg) > room) {
            count = room + 1;
            return;
        }
        count = gatherRange(px, py, pz, beg, end, p, h2, self, out, count);
    });
    return count;
}

/// Neighbour lists in fixed slots. Particle i owns the slots [offset[i], offset[i + 1]),
/// one for every candidate of the last search (within the kernel support plus a skin, so
/// the slots stay valid while particles move less than half the skin); its neighbours of
/// the current step (closer than the support) are the first count[i] of them. The kernel
/// gradient of each pair is stored beside its index only when a solver sweeps the lists
/// many times per step (DFSPH's iterations); otherwise gradW is empty and loops evaluate
/// the kernel themselves, which is cheaper than storing and loading 12 bytes a pair.
struct NeighborLists {
    std::vector<uint32_t> offset;   ///< size n + 1: first slot of each particle
    std::vector<uint32_t> count;    ///< size n: current neighbours of each particle
    std::vector<uint32_t> index;    ///< neighbour indices, neighbour k of particle i at offset[i] + k
    /// s_ij of each pair with grad_i W(x_i - x_j) = s_ij (x_i - x_j), at the positions of the
    /// last updateNeighbors (empty if not stored). One float, not the gradient's three: the
    /// pressure sweeps stream these lists, so half the bytes a pair makes them faster; the
    /// offset x_i - x_j is rebuilt from positions in cache. Measurements:
    /// docs/physics/sph-solver.md, "Neighbour search".
    std::vector<Real> gradFactor;

    uint32_t begin(size_t i) const { return offset[i]; }
    uint32_t end(size_t i) const { return offset[i] + count[i]; }
    bool hasGradients() const { return !index.empty() && gradFactor.size() == index.size(); }
    /// Lists for n particles without neighbours.
    void clear(size_t n) {
        offset.assign(n + 1, 0);
        count.assign(n, 0);
        index.clear();
        gradFactor.clear();
    }
};

} // namespace ferro

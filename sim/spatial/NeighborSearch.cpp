#include "sim/spatial/NeighborSearch.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

void GridGeometry::fit(const Vec3& lo, const Vec3& hi, Real size, size_t maxCells) {
    cellSize = size;
    // kPad spare cells on each side so that the 3-cell stencil never leaves the grid for
    // a point inside [lo, hi].
    for (;;) {
        size_t total = 1;
        for (int a = 0; a < 3; ++a) {
            const double extent = std::max(0.0, double(hi[a]) - double(lo[a]));
            dims[a] = int(std::floor(extent / cellSize)) + 1 + 2 * kPad;
            total *= size_t(dims[a]);
        }
        if (total <= maxCells) break;
        cellSize *= Real(1.26); // doubles the cell volume every three rounds
    }
    origin = lo - Vec3::Constant(kPad * cellSize);
}

void GridGeometry::cellOf(const Vec3& p, int c[3]) const {
    for (int a = 0; a < 3; ++a) {
        // Clamp before converting: a NaN or far-away coordinate must not become UB. Inside
        // the clamp the value is positive, so truncation is floor (and no library call).
        const Real f = (p[a] - origin[a]) / cellSize;
        c[a] = f >= kPad ? (f < Real(dims[a] - kPad) ? int(f) : dims[a] - 1 - kPad) : kPad;
    }
}

namespace {
struct Bounds {
    Vec3 lo = Vec3::Constant(std::numeric_limits<Real>::max());
    Vec3 hi = Vec3::Constant(std::numeric_limits<Real>::lowest());
};

Bounds boundsOf(const std::vector<Vec3>& x) {
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, x.size(), 4096), Bounds{},
        [&](const tbb::blocked_range<size_t>& r, Bounds b) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                // NaN compares false and is ignored here; the solver reports it.
                b.lo = b.lo.cwiseMin(x[i]);
                b.hi = b.hi.cwiseMax(x[i]);
            }
            return b;
        },
        [](Bounds a, const Bounds& b) {
            a.lo = a.lo.cwiseMin(b.lo);
            a.hi = a.hi.cwiseMax(b.hi);
            return a;
        });
}
} // namespace

void SortedGrid::sort(const std::vector<Vec3>& x, const std::vector<uint32_t>& tie, Real radius,
                      std::vector<uint32_t>& order) {
    const size_t n = x.size();
    Bounds b = boundsOf(x);
    if (n == 0) b.lo = b.hi = Vec3::Zero();
    geom_.fit(b.lo, b.hi, radius);
    keys_.resize(n);
    // Key = cell << 32 | tie: a strict total order, so the sort result is unique.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            int c[3];
            geom_.cellOf(x[i], c);
            keys_[i] = (uint64_t(geom_.linear(c[0], c[1], c[2])) << 32) | tie[i];
        }
    });
    // Map tie value -> current index, then sort the keys alone (8 bytes each).
    std::vector<uint32_t> slotOfTie(n);
    for (size_t i = 0; i < n; ++i) slotOfTie[tie[i]] = uint32_t(i);
    tbb::parallel_sort(keys_.begin(), keys_.end());
    order.resize(n);
    for (size_t k = 0; k < n; ++k) order[k] = slotOfTie[uint32_t(keys_[k] & 0xffffffffu)];
}

void SortedGrid::index(const std::vector<Vec3>& sortedX, const GridGeometry& g) {
    geom_ = g;
    const size_t cells = geom_.cellCount();
    cellStart_.assign(cells + 1, 0);
    for (const Vec3& p : sortedX) {
        int c[3];
        geom_.cellOf(p, c);
        ++cellStart_[geom_.linear(c[0], c[1], c[2]) + 1];
    }
    for (size_t c = 0; c < cells; ++c) cellStart_[c + 1] += cellStart_[c];
}


} // namespace ferro

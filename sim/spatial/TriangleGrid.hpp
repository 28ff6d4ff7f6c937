#pragma once
// A uniform grid of triangle indices over a box, for segment, ray and distance queries against
// a triangle mesh (the mesh container's walls).
#include "sim/core/Types.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace ferro {

/// Uniform grid of triangle indices; a triangle is listed in every cell its (slightly
/// padded) bounding box overlaps.
struct TriangleGrid {
    Vec3d origin{0, 0, 0};
    double h = 1;
    long n[3] = {1, 1, 1};
    std::vector<uint32_t> start; ///< cell -> first entry in items; size cells + 1
    std::vector<uint32_t> items;

    size_t cell(long i, long j, long k) const {
        return (size_t(k) * size_t(n[1]) + size_t(j)) * size_t(n[0]) + size_t(i);
    }

    /// Cell index range overlapping [lo, hi]; false if the box misses the grid.
    bool range(const Vec3d& lo, const Vec3d& hi, long i0[3], long i1[3]) const {
        for (int a = 0; a < 3; ++a) {
            // Clamped in double first: far-away points must not overflow the integer cast.
            const double f0 = std::floor((lo[a] - origin[a]) / h);
            const double f1 = std::floor((hi[a] - origin[a]) / h);
            if (!(f1 >= 0) || !(f0 < double(n[a]))) return false;
            i0[a] = long(std::max(f0, 0.0));
            i1[a] = long(std::min(f1, double(n[a] - 1)));
        }
        return true;
    }

    /// Lists `tris` in cells over [lo, hi]: about two cells a triangle (at most 4M cells), each
    /// triangle's box grown by `pad` [m] on every side.
    void build(const std::vector<std::array<Vec3d, 3>>& tris, const Vec3d& lo, const Vec3d& hi,
               double pad);
};

} // namespace ferro

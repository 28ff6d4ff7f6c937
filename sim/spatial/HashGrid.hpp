#pragma once
// Points in a uniform hash grid, for radius and nearest-point queries where the points are
// few or spread (no bounding box to fill densely): the particles around a surface point, the
// tips around a vertex, the wetted wall near a vertex, a tip's nearest surface vertex.
#include "sim/core/Types.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <unordered_map>
#include <vector>

namespace ferro {

/// A copy of `points` [m] hashed into cubic cells of edge `cell` [m] (<= 0 means 1 m). Queries
/// are const and thread-safe; indices are positions in the original vector.
class HashGrid {
public:
    HashGrid(const std::vector<Vec3d>& points, double cell) : points_(points), cell_(cell > 0 ? cell : 1.0)
    {
        for (size_t i = 0; i < points_.size(); ++i) cells_[key(cellOf(points_[i]))].push_back(uint32_t(i));
    }
    /// An empty grid of cells `cell` [m] wide, filled by add().
    explicit HashGrid(double cell) : cell_(cell > 0 ? cell : 1.0) {}
    /// Appends p [m]; its index is the number of points added before it.
    void add(const Vec3d& p)
    {
        cells_[key(cellOf(p))].push_back(uint32_t(points_.size()));
        points_.push_back(p);
    }
    bool empty() const { return points_.empty(); }
    const std::vector<Vec3d>& points() const { return points_; }
    /// True if some point is closer than `radius` (strictly) to x.
    bool anyCloserThan(const Vec3d& x, double radius) const
    {
        bool found = false;
        forEachWithin(x, radius, [&](uint32_t, double d2) { found = found || d2 < radius * radius; });
        return found;
    }
    /// Calls f(index, squared distance) for every point within `radius` of x.
    template <class F> void forEachWithin(const Vec3d& x, double radius, F&& f) const
    {
        const Eigen::Vector3i lo = cellOf(x - Vec3d::Constant(radius)), hi = cellOf(x + Vec3d::Constant(radius));
        const double r2 = radius * radius;
        for (int a = lo.x(); a <= hi.x(); ++a)
            for (int b = lo.y(); b <= hi.y(); ++b)
                for (int c = lo.z(); c <= hi.z(); ++c) {
                    auto it = cells_.find(key(Eigen::Vector3i(a, b, c)));
                    if (it == cells_.end()) continue;
                    for (uint32_t i : it->second) {
                        const double d2 = (points_[i] - x).squaredNorm();
                        if (d2 <= r2) f(i, d2);
                    }
                }
    }
    /// Index of the nearest point to x, searching rings of cells outward (up to 64 cells
    /// away); 0 if the grid is empty or nothing is that close. Ties go to the first point
    /// met: the lower ring, then the cell order, then the input order.
    uint32_t nearest(const Vec3d& x) const
    {
        const Eigen::Vector3i c = cellOf(x);
        uint32_t best = 0;
        double bestD = std::numeric_limits<double>::infinity();
        for (int ring = 0; ring < 64; ++ring) {
            for (int dx = -ring; dx <= ring; ++dx)
                for (int dy = -ring; dy <= ring; ++dy)
                    for (int dz = -ring; dz <= ring; ++dz) {
                        if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
                        const auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
                        if (it == cells_.end()) continue;
                        for (uint32_t i : it->second) {
                            const double d = (points_[i] - x).squaredNorm();
                            if (d < bestD) bestD = d, best = i;
                        }
                    }
            // Every point within ring * cell has been seen once one was found that close.
            if (bestD <= (ring * cell_) * (ring * cell_)) break;
        }
        return best;
    }
    /// Distance to the nearest point, or `cap` if none is closer than cap.
    double nearestDistance(const Vec3d& x, double cap) const
    {
        double best = cap * cap;
        forEachWithin(x, cap, [&](uint32_t, double d2) { best = std::min(best, d2); });
        return std::sqrt(best);
    }

private:
    Eigen::Vector3i cellOf(const Vec3d& x) const { return (x / cell_).array().floor().cast<int>(); }
    static int64_t key(const Eigen::Vector3i& c)
    {
        return (int64_t(c.x() & 0x1FFFFF) << 42) | (int64_t(c.y() & 0x1FFFFF) << 21) | int64_t(c.z() & 0x1FFFFF);
    }
    std::vector<Vec3d> points_;
    double cell_;
    std::unordered_map<int64_t, std::vector<uint32_t>> cells_;
};

} // namespace ferro

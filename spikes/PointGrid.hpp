#pragma once
// Points in a uniform hash grid, for radius queries: the particles around a surface point, the
// tips around a vertex, the wetted wall near a vertex. Internal to ferro_spikes.
#include "sim/core/Types.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace ferro {

/// A copy of `points` [m] hashed into cubic cells of edge `cell` [m] (<= 0 means 1 m). Queries
/// are const and thread-safe; indices are positions in the original vector.
class PointGrid {
public:
    PointGrid(const std::vector<Vec3d>& points, double cell) : points_(points), cell_(cell > 0 ? cell : 1.0)
    {
        for (size_t i = 0; i < points_.size(); ++i) cells_[key(cellOf(points_[i]))].push_back(uint32_t(i));
    }
    bool empty() const { return points_.empty(); }
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

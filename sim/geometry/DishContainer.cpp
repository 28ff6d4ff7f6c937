// The dish container: a cylinder with a floor, axis +z, open at the top; walls sampled as
// staggered rings, constrain() a clamp (the dish is convex).
#include "sim/geometry/ContainerKinds.hpp"
#include "sim/core/Constants.hpp"

#include <vector>

namespace ferro {
namespace container_detail {
namespace {

class DishContainer final : public Container {
public:
    DishContainer(const Vec3d& center, double radius, double height)
        : c_(center), r_(radius), h_(height), floorF_(inwardLo(center.z())) {}

    std::vector<Vec3> sampleWalls(double spacing, double offset) const override {
        checkSpacing(spacing);
        const double R = r_ + offset, floorZ = c_.z() - offset, wallH = h_ + offset;
        std::vector<Vec3> out;
        auto ring = [&](double radius, double z, long count, bool stagger) {
            // Alternate rings are turned by half a step, which packs them hexagonally.
            const double phase = stagger ? kPi / double(count) : 0.0;
            for (long i = 0; i < count; ++i) {
                const double a = phase + 2.0 * kPi * double(i) / double(count);
                out.push_back(toVec3(Vec3d(c_.x() + radius * std::cos(a),
                                           c_.y() + radius * std::sin(a), z)));
            }
        };
        // Floor: centre point and concentric rings; its outermost ring (r = R) is the
        // wall's bottom ring, emitted once below.
        out.push_back(toVec3(Vec3d(c_.x(), c_.y(), floorZ)));
        const long rings = intervals(R, spacing);
        for (long k = 1; k < rings; ++k) {
            const double r = R * double(k) / double(rings);
            ring(r, floorZ, std::max(3L, std::lround(2.0 * kPi * r / spacing)), k % 2 == 1);
        }
        const long around = std::max(3L, std::lround(2.0 * kPi * R / spacing));
        const long levels = intervals(wallH, spacing);
        for (long j = 0; j <= levels; ++j)
            ring(R, floorZ + wallH * double(j) / double(levels), around, (rings + j) % 2 == 1);
        return out;
    }

    bool contains(const Vec3d& p, double margin) const override {
        const double dx = p.x() - c_.x(), dy = p.y() - c_.y();
        return p.z() - c_.z() >= margin && std::sqrt(dx * dx + dy * dy) <= r_ - margin;
    }

    bool constrain(const Vec3& xOld, Vec3& x, Vec3& v) const override {
        if (parkIfNonFinite(xOld, x, v)) return true;
        bool corrected = false;
        if (x.z() < floorF_) {
            x.z() = floorF_;
            v.z() = std::max(v.z(), 0.0f);
            corrected = true;
        }
        const double dx = double(x.x()) - c_.x(), dy = double(x.y()) - c_.y();
        const double r2 = dx * dx + dy * dy;
        if (r2 <= r_ * r_) return corrected;

        // Radial projection onto the wall (extended upward: the wall is a safety net at
        // any height), pulled slightly inward so that the rounded float lands inside too.
        // Far from the origin floats are coarse, hence the growing pull and the fallback.
        const double r = std::sqrt(r2), nx = dx / r, ny = dy / r;
        for (double pull = 1e-6; pull < 1e-2; pull *= 8) {
            const Vec3 moved = toStoredVec3(Vec3d(c_.x() + nx * r_ * (1.0 - pull),
                                                  c_.y() + ny * r_ * (1.0 - pull), x.z()));
            const double ex = double(moved.x()) - c_.x(), ey = double(moved.y()) - c_.y();
            if (ex * ex + ey * ey > r_ * r_) continue;
            x = moved;
            const double vn = double(v.x()) * nx + double(v.y()) * ny;
            if (vn > 0) {
                v.x() = float(double(v.x()) - vn * nx);
                v.y() = float(double(v.y()) - vn * ny);
            }
            return true;
        }
        x = xOld;
        v.setZero();
        return true;
    }

    void bounds(Vec3d& lo, Vec3d& hi) const override {
        // Open top with no ceiling: the fluid may rise arbitrarily high.
        lo = Vec3d(c_.x() - r_, c_.y() - r_, c_.z());
        hi = Vec3d(c_.x() + r_, c_.y() + r_, kHuge);
    }

private:
    Vec3d c_;
    double r_, h_;
    float floorF_;
};

} // namespace

std::unique_ptr<Container> makeDishContainer(const Vec3d& center, double radius, double height) {
    return std::make_unique<DishContainer>(center, radius, height);
}

} // namespace container_detail
} // namespace ferro

// The box container: an axis-aligned box, walls sampled on one lattice, constrain() a clamp.
// With periodic sides only the floor (and a lid) are walls: x and y wrap (PeriodicDomain).
#include "sim/geometry/ContainerKinds.hpp"

#include <vector>

namespace ferro {
namespace container_detail {
namespace {

class BoxContainer final : public Container {
public:
    BoxContainer(const Vec3d& lo, const Vec3d& hi, bool closedTop, bool periodicSides)
        : lo_(lo), hi_(hi), closedTop_(closedTop), periodic_(periodicSides) {
        for (int a = 0; a < 3; ++a) {
            loF_[a] = inwardLo(lo[a]);
            hiF_[a] = inwardHi(hi[a]);
        }
    }

    std::vector<Vec3> sampleWalls(double spacing, double offset) const override {
        checkSpacing(spacing);
        if (periodic_) return sampleFloorAndLid(spacing, offset);
        const Vec3d lo = lo_ - Vec3d::Constant(offset);
        const Vec3d hi = hi_ + Vec3d(offset, offset, closedTop_ ? offset : 0.0);
        const Vec3d ext = hi - lo;
        const long nx = intervals(ext.x(), spacing), ny = intervals(ext.y(), spacing),
                   nz = intervals(ext.z(), spacing);
        std::vector<Vec3> out;
        auto put = [&](long i, long j, long k) {
            out.push_back(toVec3(lo + Vec3d(ext.x() * double(i) / double(nx),
                                             ext.y() * double(j) / double(ny),
                                             ext.z() * double(k) / double(nz))));
        };
        // One lattice over the whole box surface: every lattice point is visited once, so
        // shared edges and corners carry no duplicates.
        for (long k = 0; k <= nz; ++k) {
            if (k == 0 || (k == nz && closedTop_)) {
                for (long j = 0; j <= ny; ++j)
                    for (long i = 0; i <= nx; ++i) put(i, j, k);
                continue;
            }
            for (long i = 0; i <= nx; ++i) {
                put(i, 0, k);
                put(i, ny, k);
            }
            for (long j = 1; j < ny; ++j) {
                put(0, j, k);
                put(nx, j, k);
            }
        }
        return out;
    }

    bool contains(const Vec3d& p, double margin) const override {
        for (int a = 0; a < 3; ++a) {
            // A periodic side is no wall: no margin, and a particle a little past the face
            // (wrapped at the next neighbour search, at most half a Verlet skin out) is still in;
            // half a period out is not (the sanity guard's "outside").
            if (periodic_ && a < 2) {
                const double half = 0.5 * (hi_[a] - lo_[a]);
                if (!(p[a] >= lo_[a] - half && p[a] <= hi_[a] + half)) return false;
                continue;
            }
            if (!(p[a] >= lo_[a] + margin && p[a] <= hi_[a] - margin)) return false;
        }
        return true;
    }

    bool constrain(const Vec3& xOld, Vec3& x, Vec3& v) const override {
        if (parkIfNonFinite(xOld, x, v)) return true;
        bool corrected = false;
        for (int a = periodic_ ? 2 : 0; a < 3; ++a) corrected |= clampAxis(x[a], v[a], loF_[a], hiF_[a]);
        return corrected;
    }

    void bounds(Vec3d& lo, Vec3d& hi) const override {
        lo = lo_;
        hi = hi_;
    }

private:
    // Periodic sides: the floor (and lid) lattice over [lo, hi) in x and y with a whole number
    // of steps per period, so that it tiles across the glued faces without seam or double.
    std::vector<Vec3> sampleFloorAndLid(double spacing, double offset) const {
        const Vec3d ext = hi_ - lo_;
        const long nx = std::max(1L, std::lround(ext.x() / spacing)), ny = std::max(1L, std::lround(ext.y() / spacing));
        std::vector<Vec3> out;
        // The floor always, the lid only on a closed top (chosen by index: with a negative
        // offset, samples on the fluid side, the floor's z lies above lo.z too).
        for (int wall = 0; wall < (closedTop_ ? 2 : 1); ++wall) {
            const double z = wall == 0 ? lo_.z() - offset : hi_.z() + offset;
            for (long j = 0; j < ny; ++j)
                for (long i = 0; i < nx; ++i)
                    out.push_back(toVec3(Vec3d(lo_.x() + ext.x() * double(i) / double(nx),
                                               lo_.y() + ext.y() * double(j) / double(ny), z)));
        }
        return out;
    }

    Vec3d lo_, hi_;
    bool closedTop_, periodic_;
    float loF_[3], hiF_[3];
};

} // namespace

std::unique_ptr<Container> makeBoxContainer(const Vec3d& lo, const Vec3d& hi, bool closedTop, bool periodicSides) {
    return std::make_unique<BoxContainer>(lo, hi, closedTop, periodicSides);
}

} // namespace container_detail
} // namespace ferro

// Bar magnet (kind "bar"): two opposite magnetic pole charges +-q_m = strength [A m],
// `length` apart along the axis (the Gilbert model; the paper's eqs. 3-4), softened.
#include "sim/magnetics/MagnetKinds.hpp"

#include "sim/core/Constants.hpp"
#include "sim/magnetics/MagnetField.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

namespace {

constexpr double kInv4Pi = 1.0 / (4.0 * kPi);

// Field of a unit point charge, r / (r^2 + eps^2)^(3/2) (no 1/4pi); zero at the exact
// singular point when eps = 0.
Vec3d chargeField(const Vec3d& r, double eps2) {
    const double s2 = r.squaredNorm() + eps2;
    if (!(s2 > 0.0)) return Vec3d::Zero();
    const double s = std::sqrt(s2);
    return r / (s2 * s);
}

// Jacobian of chargeField: delta_ij / s^3 - 3 r_i r_j / s^5.
Mat3d chargeGradient(const Vec3d& r, double eps2) {
    const double s2 = r.squaredNorm() + eps2;
    if (!(s2 > 0.0)) return Mat3d::Zero();
    const double s = std::sqrt(s2);
    const double inv3 = 1.0 / (s2 * s);
    return inv3 * Mat3d::Identity() - (3.0 * inv3 / s2) * (r * r.transpose());
}

} // namespace

Vec3d barMagnetField(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    const double eps2 = mag.softening * mag.softening;
    const Vec3d half = 0.5 * mag.length * n;
    return (mag.strength * kInv4Pi) *
           (chargeField(x - (mag.position + half), eps2) - chargeField(x - (mag.position - half), eps2));
}

Mat3d barMagnetGradient(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    const double eps2 = mag.softening * mag.softening;
    const Vec3d half = 0.5 * mag.length * n;
    return (mag.strength * kInv4Pi) *
           (chargeGradient(x - (mag.position + half), eps2) - chargeGradient(x - (mag.position - half), eps2));
}

} // namespace ferro

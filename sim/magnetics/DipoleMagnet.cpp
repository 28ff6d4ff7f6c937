// Point dipole (kind "dipole"): moment m = strength * axis [A m^2] at the magnet's position,
// Plummer-softened over `softening` so that particles touching the pole stay finite.
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

Vec3d dipoleField(const Vec3d& m, const Vec3d& r, double eps2) {
    const double s2 = r.squaredNorm() + eps2;
    if (!(s2 > 0.0)) return Vec3d::Zero();
    const double s = std::sqrt(s2);
    const double inv3 = 1.0 / (s2 * s);
    // Softened dipole = -grad of m.r / (4 pi s^3): still curl-free, finite at r = 0.
    return kInv4Pi * inv3 * (3.0 * m.dot(r) / s2 * r - m);
}

Mat3d dipoleGradient(const Vec3d& m, const Vec3d& r, double eps2) {
    const double s2 = r.squaredNorm() + eps2;
    if (!(s2 > 0.0)) return Mat3d::Zero();
    const double s = std::sqrt(s2);
    const double inv5 = 1.0 / (s2 * s2 * s);
    const double mr = m.dot(r);
    Mat3d J = 3.0 * inv5 * (r * m.transpose() + m * r.transpose() + mr * Mat3d::Identity());
    J -= (15.0 * mr * inv5 / s2) * (r * r.transpose());
    return kInv4Pi * J;
}

} // namespace

Vec3d dipoleMagnetField(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    return dipoleField(mag.strength * n, x - mag.position, mag.softening * mag.softening);
}

Mat3d dipoleMagnetGradient(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    return dipoleGradient(mag.strength * n, x - mag.position, mag.softening * mag.softening);
}

} // namespace ferro

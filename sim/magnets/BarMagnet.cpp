// Bar magnet (kind "bar"): two opposite magnetic pole charges +-q_m = strength [A m],
// `length` apart along the axis (the Gilbert model; the paper's eqs. 3-4), softened.
#include "sim/magnets/MagnetKinds.hpp"

#include "sim/core/Constants.hpp"
#include "sim/magnets/BodyScale.hpp"
#include "sim/magnets/MagnetField.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

namespace {


// The unit pole charge's potential is chi(t) / (4 pi), chi = (t^4 + a^8)^(-1/8) of
// t = r^2 + eps^2: the Plummer-softened 1/r without a body (a = 0), bounded within the
// radius a of the smallest pole face that carries the charge (magnetBodyRadius), exact to
// (1 + (a/r)^8)^(-1/8) outside it (see DipoleMagnet.cpp for the dipole's). Scaled by
// S = (t^4 + a^8)^(1/4), w = t / S: chi' = -1/2 w^3 S^-3/2, chi'' = -1/2 (3 w^2 - 9/2 w^6) S^-5/2.
struct ChargeProfile {
    double d1 = 0, d2 = 0;
    ChargeProfile(double t, double a) {
        const BodyScale b(t, a);
        if (!b.valid) return;
        const double S = b.S, w = b.w, w2 = w * w, rs = b.rs;
        const double s32 = rs * rs * rs;        // S^-3/2
        d1 = -0.5 * w2 * w * s32;
        d2 = -0.5 * (3.0 * w2 - 4.5 * w2 * w2 * w2) * s32 / S;
    }
};

// Field of a unit point charge, -2 chi' r (no 1/4pi): r / (r^2 + eps^2)^(3/2) without a body;
// zero at the exact singular point when eps = a = 0.
Vec3d chargeField(const Vec3d& r, double eps2, double a) {
    const ChargeProfile f(r.squaredNorm() + eps2, a);
    return (-2.0 * f.d1) * r;
}

// Jacobian of chargeField: -(2 chi' I + 4 chi'' r r^T).
Mat3d chargeGradient(const Vec3d& r, double eps2, double a) {
    const ChargeProfile f(r.squaredNorm() + eps2, a);
    return (-2.0 * f.d1) * Mat3d::Identity() - (4.0 * f.d2) * (r * r.transpose());
}

} // namespace

/// A pole face of magnetization kStrongestMagnetization: sqrt(|q| / (pi M)).
double barBodyRadius(double strength) { return std::sqrt(std::abs(strength) / (kPi * kStrongestMagnetization)); }

Vec3d barMagnetField(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    const double eps2 = mag.softening * mag.softening;
    const double a = barBodyRadius(mag.strength);
    const Vec3d half = 0.5 * mag.length * n;
    return (mag.strength * kInv4Pi) *
           (chargeField(x - (mag.position + half), eps2, a) - chargeField(x - (mag.position - half), eps2, a));
}

Mat3d barMagnetGradient(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    const double eps2 = mag.softening * mag.softening;
    const double a = barBodyRadius(mag.strength);
    const Vec3d half = 0.5 * mag.length * n;
    return (mag.strength * kInv4Pi) *
           (chargeGradient(x - (mag.position + half), eps2, a) - chargeGradient(x - (mag.position - half), eps2, a));
}

} // namespace ferro

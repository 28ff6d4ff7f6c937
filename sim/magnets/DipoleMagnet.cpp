// Point dipole (kind "dipole"): moment m = strength * axis [A m^2] at the magnet's position,
// Plummer-softened over `softening` so that particles touching the pole stay finite, and
// bounded within the smallest body that can carry the moment (magnetBodyRadius).
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


/// phi(t) = (t^4 + a^8)^(-3/8) of t = r^2 + eps^2 (Plummer-softened r^2) and its first two
/// derivatives: the dipole's potential is m . r phi / (4 pi). Without a body (a = 0) it is
/// the Plummer-softened dipole, t^(-3/2); with one, phi -> a^-3 inside the body radius a,
/// the interior of a uniformly magnetized sphere (H = -M/3), and 1/r^3 outside it to
/// (1 + (a/r)^8)^(-3/8): 0.15 % off at 2a, 1e-4 at 3a. Still a potential: curl-free, and
/// the Kelvin force of the body model stays conservative. Scaled by S = (t^4 + a^8)^(1/4),
/// w = t / S <= 1, so that nothing overflows: phi = S^-3/2, phi' = -3/2 w^3 S^-5/2,
/// phi'' = -3/2 (3 w^2 - 11/2 w^6) S^-7/2.
struct DipoleProfile {
    double phi = 0, d1 = 0, d2 = 0;
    DipoleProfile(double t, double a) {
        const BodyScale b(t, a);
        if (!b.valid) return;
        const double S = b.S, w = b.w, w2 = w * w, rs = b.rs;
        phi = rs * rs * rs;                    // S^-3/2
        d1 = -1.5 * w2 * w * phi / S;          // -3/2 w^3 S^-5/2
        d2 = -1.5 * (3.0 * w2 - 5.5 * w2 * w2 * w2) * phi / (S * S);
    }
};

double bodyRadius(const Magnet& mag) { return dipoleBodyRadius(mag.strength); }

Vec3d dipoleField(const Vec3d& m, const Vec3d& r, double eps2, double a) {
    // H = -grad (m . r phi / 4 pi) = -(m phi + 2 phi' (m . r) r) / 4 pi.
    const DipoleProfile f(r.squaredNorm() + eps2, a);
    return -kInv4Pi * (f.phi * m + (2.0 * f.d1 * m.dot(r)) * r);
}

Mat3d dipoleGradient(const Vec3d& m, const Vec3d& r, double eps2, double a) {
    // J = -(2 phi' (m r^T + r m^T + (m . r) I) + 4 phi'' (m . r) r r^T) / 4 pi: symmetric.
    const DipoleProfile f(r.squaredNorm() + eps2, a);
    const double mr = m.dot(r);
    Mat3d J = (2.0 * f.d1) * (r * m.transpose() + m * r.transpose() + mr * Mat3d::Identity());
    J += (4.0 * f.d2 * mr) * (r * r.transpose());
    return -kInv4Pi * J;
}

} // namespace

/// A sphere of magnetization kStrongestMagnetization: (3 |m| / (4 pi M))^(1/3).
double dipoleBodyRadius(double strength) {
    return std::cbrt(3.0 * std::abs(strength) / (4.0 * kPi * kStrongestMagnetization));
}

Vec3d dipoleMagnetField(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    return dipoleField(mag.strength * n, x - mag.position, mag.softening * mag.softening, bodyRadius(mag));
}

Mat3d dipoleMagnetGradient(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    return dipoleGradient(mag.strength * n, x - mag.position, mag.softening * mag.softening, bodyRadius(mag));
}

} // namespace ferro

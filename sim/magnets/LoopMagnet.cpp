// Current loop (kind "loop"): current I = strength [A] in a circle of `radius` around the
// axis, its exact off-axis field from complete elliptic integrals; points closer than
// `softening` to the wire are evaluated at that distance.
#include "sim/magnets/MagnetKinds.hpp"

#include "sim/core/Constants.hpp"
#include "sim/magnets/MagnetField.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

namespace {

// K and E from m = k^2 and its complement m1 = 1 - m. Taking m1 separately keeps full
// precision near the wire, where m -> 1 and 1 - m would be all cancellation; the loop
// computes m1 = alpha^2 / beta^2 directly from the geometry.
// AGM: K = pi / (2 AGM(1, sqrt(m1))), E = K (1 - sum_n 2^(n-1) c_n^2) with c_0^2 = m.
void ellipticKE(double m, double m1, double& K, double& E) {
    if (!(m1 > 0.0)) {
        K = std::numeric_limits<double>::infinity();
        E = 1.0;
        return;
    }
    double a = 1.0, b = std::sqrt(m1);
    double pw = 0.5;          // 2^(n-1)
    double sum = pw * m;      // n = 0 term
    for (int n = 0; n < 64; ++n) {
        const double c = 0.5 * (a - b);
        const double an = 0.5 * (a + b);
        b = std::sqrt(a * b);
        a = an;
        pw *= 2.0;
        sum += pw * c * c;
        // Quadratic convergence: once c ~ 1e-9 a the next c is ~1e-18 a, below double
        // precision in both a and the sum.
        if (std::abs(c) <= 1e-9 * a) {
            const double cn = 0.5 * (a - b);
            sum += 2.0 * pw * cn * cn;
            break;
        }
    }
    K = kPi / (2.0 * a);
    E = K * (1.0 - sum);
}

// Circular loop, current I, radius a, at cylindrical (rho >= 0, z) in the loop frame.
// Returns H_z and H_rho / rho (the latter so that rho -> 0 needs no division and the
// caller multiplies by the in-plane offset vector). Formulas: Simpson et al., "Simple
// analytic expressions for the magnetic field of a circular current loop" (NASA 2001),
// divided by mu0. alpha2 = (rho - a)^2 + z^2 > 0 is the squared distance to the wire,
// passed in because the caller already has it without cancellation.
void loopFieldCylExact(double I, double a, double rho, double z, double alpha2,
                       double& Hz, double& HrhoOverRho) {
    Hz = 0.0;
    HrhoOverRho = 0.0;
    const double beta2 = (rho + a) * (rho + a) + z * z;
    const double beta = std::sqrt(beta2);
    const double m = 4.0 * a * rho / beta2;
    const double m1 = alpha2 / beta2;
    if (m < 0.1) {
        // Near the axis the elliptic bracket of H_rho cancels to O(m^2) and loses digits
        // (1e-8 relative at rho ~ 1e-6 R). There the Biot-Savart integral itself is cheap and
        // exact: with P = a^2 + rho^2 + z^2, q = 2 a rho / P < 0.053 and c = cos(phi),
        //   H_z     = I a / (4 pi) * integral (a - rho c) (P - 2 a rho c)^(-3/2) dphi,
        //   H_rho   = I a z / (4 pi) * integral c (P - 2 a rho c)^(-3/2) dphi.
        // The integrands are periodic and analytic, so the trapezoid rule converges like
        // (q/2)^N: N = 16 is below 1e-20. Writing (1 - q c)^(-3/2) = 1 + q c h(q c) removes
        // the constant that integrates to zero against c, so H_rho / rho keeps full precision
        // down to rho = 0.
        constexpr int N = 16;
        const double P = a * a + rho * rho + z * z;
        const double q = 2.0 * a * rho / P;
        double sz = 0.0, sr = 0.0;
        for (int j = 0; j < N; ++j) {
            const double c = std::cos(2.0 * kPi * j / N);
            const double x = q * c;
            // h(x) = ((1 - x)^(-3/2) - 1) / x, via expm1/log1p so small x keeps its digits.
            const double h = x == 0.0 ? 1.5 : std::expm1(-1.5 * std::log1p(-x)) / x;
            sz += (a - rho * c) * (1.0 + x * h);
            sr += c * c * h;
        }
        const double w = I * a / (4.0 * kPi) * (2.0 * kPi / N) / (P * std::sqrt(P));
        Hz = w * sz;
        HrhoOverRho = w * z * (2.0 * a / P) * sr;
        return;
    }
    if (!(m1 > 0.0)) return; // underflowed distance to the wire: treat as on the wire
    double K, E;
    ellipticKE(m, m1, K, E);
    const double r2 = rho * rho + z * z;
    const double c = I / (2.0 * kPi * alpha2 * beta);
    Hz = c * ((a * a - r2) * E + alpha2 * K);
    HrhoOverRho = c * z * ((a * a + r2) * E - alpha2 * K) / (rho * rho);
}

// Loop field with the softening clamp: points closer than eps to the wire are evaluated
// at distance eps from it, along the same direction in the (rho, z) half-plane, which
// keeps the field continuous and bounded by its value at distance eps.
void loopFieldCyl(double I, double a, double eps, double rho, double z,
                  double& Hz, double& HrhoOverRho) {
    Hz = 0.0;
    HrhoOverRho = 0.0;
    // eps is capped at a/2 so the clamped point stays off the axis (rho >= a/2).
    eps = std::min(eps, 0.5 * a);
    double dr = rho - a;
    double alpha2 = dr * dr + z * z;
    if (eps > 0.0 && alpha2 < eps * eps) {
        const double alpha = std::sqrt(alpha2);
        double zc = z;
        if (alpha > 0.0) {
            dr *= eps / alpha;
            zc *= eps / alpha;
        } else {
            dr = eps; // exactly on the wire: any side is as good; take the outside
        }
        const double rhoc = a + dr;
        loopFieldCylExact(I, a, rhoc, zc, dr * dr + zc * zc, Hz, HrhoOverRho);
        // The caller scales H_rho / rho by the original offset (|offset| = rho >= a/2 here),
        // so convert to the clamped point's H_rho.
        HrhoOverRho *= rhoc / rho;
        return;
    }
    if (!(alpha2 > 0.0)) return; // eps = 0 exactly on the wire: documented zero
    loopFieldCylExact(I, a, rho, z, alpha2, Hz, HrhoOverRho);
}

// The clamp radius: the softening, and at least the thinnest wire that carries the current
// (magnetBodyRadius): the field beside a real wire is bounded by its thickness.
double loopSoftening(const Magnet& mag) {
    return std::max({mag.softening, loopBodyRadius(mag.strength), 0.0});
}

Vec3d loopField(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    if (!(mag.radius > 0.0)) return Vec3d::Zero();
    const Vec3d d = x - mag.position;
    const double z = d.dot(n);
    const Vec3d radial = d - z * n;
    double Hz, HrhoOverRho;
    loopFieldCyl(mag.strength, mag.radius, loopSoftening(mag), radial.norm(), z, Hz,
                 HrhoOverRho);
    return Hz * n + HrhoOverRho * radial;
}

} // namespace

double ellipticK(double m) {
    double K, E;
    ellipticKE(m, 1.0 - m, K, E);
    return K;
}

double ellipticE(double m) {
    if (m >= 1.0) return 1.0;
    double K, E;
    ellipticKE(m, 1.0 - m, K, E);
    return E;
}

/// The wire that carries the current at kStrongestCurrentDensity: sqrt(|I| / (pi J)).
double loopBodyRadius(double strength) { return std::sqrt(std::abs(strength) / (kPi * kStrongestCurrentDensity)); }

Vec3d loopMagnetField(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    return loopField(mag, n, x);
}

Mat3d loopMagnetGradient(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    if (!(mag.radius > 0.0)) return Mat3d::Zero();
    // The field varies on the scale of the distance to the wire (or eps inside the clamp),
    // so the step is relative to that: 1e-5 balances O(h^2) truncation against roundoff.
    const Vec3d d = x - mag.position;
    const double z = d.dot(n);
    const double rho = (d - z * n).norm();
    const double wire = std::hypot(rho - mag.radius, z);
    const double eps = std::min(loopSoftening(mag), 0.5 * mag.radius);
    const double scale = std::max(wire, eps);
    if (!(scale > 0.0)) return Mat3d::Zero(); // eps = 0 exactly on the wire
    const double h = 1e-5 * scale;
    Mat3d J;
    for (int j = 0; j < 3; ++j) {
        Vec3d step = Vec3d::Zero();
        step[j] = h;
        J.col(j) = (loopField(mag, n, x + step) - loopField(mag, n, x - step)) / (2.0 * h);
    }
    return J;
}

} // namespace ferro

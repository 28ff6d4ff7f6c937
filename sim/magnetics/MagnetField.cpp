#include "sim/magnetics/MagnetField.hpp"

#include "sim/sph/Kernel.hpp" // kPi

#include <Eigen/Geometry> // cross, unitOrthogonal

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

namespace {

constexpr double kInv4Pi = 1.0 / (4.0 * kPi);

// Unit axis of a magnet; false for a zero (or non-finite) direction, which has no axis.
bool unitAxis(const Vec3d& direction, Vec3d& n) {
    const double len = direction.norm();
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    n = direction / len;
    return true;
}

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

Vec3d loopField(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    if (!(mag.radius > 0.0)) return Vec3d::Zero();
    const Vec3d d = x - mag.position;
    const double z = d.dot(n);
    const Vec3d radial = d - z * n;
    double Hz, HrhoOverRho;
    loopFieldCyl(mag.strength, mag.radius, std::max(mag.softening, 0.0), radial.norm(), z, Hz,
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

Vec3d magnetField(const Magnet& mag, const Vec3d& x) {
    Vec3d n;
    if (!unitAxis(mag.direction, n)) return Vec3d::Zero();
    const double eps2 = mag.softening * mag.softening;
    switch (mag.kind) {
    case Magnet::Kind::Dipole:
        return dipoleField(mag.strength * n, x - mag.position, eps2);
    case Magnet::Kind::Bar: {
        const Vec3d half = 0.5 * mag.length * n;
        return (mag.strength * kInv4Pi) *
               (chargeField(x - (mag.position + half), eps2) -
                chargeField(x - (mag.position - half), eps2));
    }
    case Magnet::Kind::Uniform:
        return mag.strength * n;
    case Magnet::Kind::Loop:
        return loopField(mag, n, x);
    }
    return Vec3d::Zero();
}

Vec3d magnetField(const std::vector<Magnet>& magnets, const Vec3d& x) {
    Vec3d H = Vec3d::Zero();
    for (const Magnet& m : magnets) H += magnetField(m, x);
    return H;
}

Mat3d fieldGradient(const Magnet& mag, const Vec3d& x) {
    Vec3d n;
    if (!unitAxis(mag.direction, n)) return Mat3d::Zero();
    const double eps2 = mag.softening * mag.softening;
    switch (mag.kind) {
    case Magnet::Kind::Dipole:
        return dipoleGradient(mag.strength * n, x - mag.position, eps2);
    case Magnet::Kind::Bar: {
        const Vec3d half = 0.5 * mag.length * n;
        return (mag.strength * kInv4Pi) *
               (chargeGradient(x - (mag.position + half), eps2) -
                chargeGradient(x - (mag.position - half), eps2));
    }
    case Magnet::Kind::Uniform:
        return Mat3d::Zero();
    case Magnet::Kind::Loop: {
        if (!(mag.radius > 0.0)) return Mat3d::Zero();
        // The field varies on the scale of the distance to the wire (or eps inside the clamp),
        // so the step is relative to that: 1e-5 balances O(h^2) truncation against roundoff.
        const Vec3d d = x - mag.position;
        const double z = d.dot(n);
        const double rho = (d - z * n).norm();
        const double wire = std::hypot(rho - mag.radius, z);
        const double eps = std::min(std::max(mag.softening, 0.0), 0.5 * mag.radius);
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
    }
    return Mat3d::Zero();
}

Mat3d fieldGradient(const std::vector<Magnet>& magnets, const Vec3d& x) {
    Mat3d J = Mat3d::Zero();
    for (const Magnet& m : magnets) J += fieldGradient(m, x);
    return J;
}

// ---------------------------------------------------------------------------------------
// Keyframe interpolation

namespace {

// Cubic Hermite basis on u in [0, 1]; tangents are per unit time, hence the dt factor.
template <class T>
T hermite(const T& p0, const T& p1, const T& m0, const T& m1, double dt, double u) {
    const double u2 = u * u, u3 = u2 * u;
    return (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * dt * m0 + (-2 * u3 + 3 * u2) * p1 +
           (u3 - u2) * dt * m1;
}

// Catmull-Rom tangent at key j for uneven spacing: central difference over the two
// neighbours, one-sided at the ends. Coincident key times degrade to a zero tangent.
Vec3d positionTangent(const std::vector<MagnetKeyframe>& k, size_t j) {
    const size_t lo = j == 0 ? 0 : j - 1;
    const size_t hi = std::min(j + 1, k.size() - 1);
    const double dt = k[hi].time - k[lo].time;
    if (!(dt > 0.0)) return Vec3d::Zero();
    return (k[hi].position - k[lo].position) / dt;
}

double secant(const std::vector<MagnetKeyframe>& k, size_t i) {
    const double dt = k[i + 1].time - k[i].time;
    return dt > 0.0 ? (k[i + 1].strength - k[i].strength) / dt : 0.0;
}

// Fritsch-Butland (PCHIP) tangent: weighted harmonic mean of the adjacent secants, zero at
// a local extremum, so the interpolant stays monotone between keys and never overshoots.
double strengthTangent(const std::vector<MagnetKeyframe>& k, size_t j) {
    const size_t n = k.size();
    if (j == 0) return secant(k, 0);
    if (j == n - 1) return secant(k, n - 2);
    const double d0 = secant(k, j - 1), d1 = secant(k, j);
    if (d0 * d1 <= 0.0) return 0.0;
    const double h0 = k[j].time - k[j - 1].time, h1 = k[j + 1].time - k[j].time;
    const double w0 = 2 * h1 + h0, w1 = h1 + 2 * h0;
    return (w0 + w1) / (w0 / d0 + w1 / d1);
}

// Slerp between unit vectors a and b. Antiparallel keys have no unique great circle; any
// perpendicular axis gives a valid (unit, continuous in u) rotation.
Vec3d slerp(const Vec3d& a, const Vec3d& b, double u) {
    const double c = std::clamp(a.dot(b), -1.0, 1.0);
    const double theta = std::acos(c);
    if (theta < 1e-9) return ((1 - u) * a + u * b).normalized();
    Vec3d perp = b - c * a;
    if (perp.norm() < 1e-12) perp = a.unitOrthogonal();
    perp.normalize();
    return std::cos(theta * u) * a + std::sin(theta * u) * perp;
}

Vec3d keyDirection(const MagnetKeyframe& k, const Vec3d& fallback) {
    Vec3d n;
    return unitAxis(k.direction, n) ? n : fallback;
}

} // namespace

Magnet MagnetTrack::at(double t) const {
    Magnet m = base;
    if (keys.empty()) return m;
    Vec3d baseDir;
    if (!unitAxis(base.direction, baseDir)) baseDir = Vec3d::UnitZ();

    auto apply = [&](const MagnetKeyframe& k) {
        m.position = k.position;
        m.direction = keyDirection(k, baseDir);
        m.strength = k.strength;
        return m;
    };
    if (keys.size() == 1 || !(t > keys.front().time)) return apply(keys.front());
    if (t >= keys.back().time) return apply(keys.back());

    // Segment i with keys[i].time <= t < keys[i+1].time.
    const auto it = std::upper_bound(keys.begin(), keys.end(), t,
                                     [](double v, const MagnetKeyframe& k) { return v < k.time; });
    const size_t i = size_t(it - keys.begin()) - 1;
    const MagnetKeyframe& k0 = keys[i];
    const MagnetKeyframe& k1 = keys[i + 1];
    const double dt = k1.time - k0.time;
    if (!(dt > 0.0)) return apply(k1);
    const double u = (t - k0.time) / dt;

    m.position = hermite<Vec3d>(k0.position, k1.position, positionTangent(keys, i),
                                positionTangent(keys, i + 1), dt, u);
    m.strength = hermite<double>(k0.strength, k1.strength, strengthTangent(keys, i),
                                 strengthTangent(keys, i + 1), dt, u);
    m.direction = slerp(keyDirection(k0, baseDir), keyDirection(k1, baseDir), u);
    return m;
}

} // namespace ferro

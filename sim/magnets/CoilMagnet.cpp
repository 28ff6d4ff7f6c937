// Solenoid (kind "coil"): `turns` turns of current I = strength [A] wound evenly over
// `length` on a cylinder of `radius`, axis = direction, centred at position: the ideal
// solenoid (a current sheet of n I = turns I / length A/m), its exact field everywhere from
// Derby and Olbert's closed form with Bulirsch's generalized complete elliptic integral.
// Points closer than the softening (at least the wire that carries the current) to one of
// the two end rings, where the sheet's field diverges logarithmically, are evaluated at that
// distance, as the loop clamps its wire.
//
// Reference: N. Derby and S. Olbert, "Cylindrical magnets and ideal solenoids", Am. J. Phys.
// 78 (2010) 229-235, eqs. (3)-(6) and the appendix's cel(kc, p, c, s) (R. Bulirsch, Numer.
// Math. 13 (1969) 305-315).
#include "sim/magnets/MagnetKinds.hpp"

#include "sim/core/Constants.hpp"
#include "sim/magnets/MagnetField.hpp"

#include <algorithm>
#include <cmath>

namespace ferro {

namespace {

// Bulirsch's generalized complete elliptic integral
//   cel(kc, p, c, s) = int_0^{pi/2} (c cos^2 t + s sin^2 t) / ((cos^2 t + p sin^2 t)
//                       sqrt(cos^2 t + kc^2 sin^2 t)) dt,
// kc != 0 (the caller keeps it away from 0 by the end-ring clamp). Iterates a Landen-type
// transformation to relative accuracy 1e-13 (quadratic convergence: ~5 iterations).
double cel(double kc, double p, double c, double s) {
    if (kc == 0.0) return 0.0; // only on an end ring with no clamp: the documented zero
    constexpr double errtol = 1e-13;
    double k = std::abs(kc), pp = p, cc = c, ss = s, em = 1.0;
    if (p > 0.0) {
        pp = std::sqrt(p);
        ss = s / pp;
    } else {
        double f = kc * kc;
        double q = 1.0 - f;
        const double g = 1.0 - pp;
        f -= pp;
        q *= ss - c * pp;
        pp = std::sqrt(f / g);
        cc = (c - ss) / g;
        ss = -q / (g * g * pp) + cc * pp;
    }
    double f = cc;
    cc += ss / pp;
    double g = k / pp;
    ss = 2.0 * (ss + f * g);
    pp += g;
    g = em;
    em += k;
    double kk = k;
    for (int it = 0; it < 64 && std::abs(g - k) > g * errtol; ++it) {
        k = 2.0 * std::sqrt(kk);
        kk = k * em;
        f = cc;
        cc += ss / pp;
        g = kk / pp;
        ss = 2.0 * (ss + f * g);
        pp += g;
        g = em;
        em += k;
    }
    return 0.5 * kPi * (ss + cc * em) / (em * (em + pp));
}

// The sheet's field at cylindrical (rho >= 0, z) in the coil's frame: current density
// nI [A/m] on radius a from z = -b to b (Derby & Olbert eqs. 3-6, divided by mu0).
void sheetFieldCyl(double nI, double a, double b, double rho, double z, double& Hz, double& Hrho) {
    const double H0 = nI / kPi;
    const double gamma = (a - rho) / (a + rho);
    Hz = 0.0;
    Hrho = 0.0;
    for (int end = 0; end < 2; ++end) {
        const double sign = end == 0 ? 1.0 : -1.0; // z+ = z + b, z- = z - b
        const double zs = z + sign * b;
        const double d = std::sqrt(zs * zs + (rho + a) * (rho + a));
        const double alpha = a / d, beta = zs / d;
        const double kc = std::sqrt(zs * zs + (a - rho) * (a - rho)) / d;
        Hrho += sign * alpha * cel(kc, 1.0, 1.0, -1.0);
        Hz += sign * beta * cel(kc, gamma * gamma, 1.0, gamma);
    }
    Hrho *= H0;
    Hz *= H0 * a / (a + rho);
}

// The clamp radius: the softening, and at least the thinnest wire that carries the current;
// at most half the radius and half the length, so the clamped point stays on its side.
double coilSoftening(const Magnet& mag) {
    const double eps = std::max({mag.softening, coilBodyRadius(mag.strength), 0.0});
    return std::min({eps, 0.5 * mag.radius, 0.5 * mag.length});
}

Vec3d coilField(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    if (!(mag.radius > 0.0) || !(mag.length > 0.0)) return Vec3d::Zero();
    const double a = mag.radius, b = 0.5 * mag.length;
    const Vec3d d = x - mag.position;
    double z = d.dot(n);
    const Vec3d radial = d - z * n;
    double rho = radial.norm();
    // The end ring nearer to the point; within eps of it the point moves out to eps.
    const double eps = coilSoftening(mag);
    const double ringZ = z >= 0 ? b : -b;
    const double dr = rho - a, dz = z - ringZ;
    const double dist = std::hypot(dr, dz);
    if (dist < eps) {
        if (dist > 0) {
            rho = a + dr * eps / dist;
            z = ringZ + dz * eps / dist;
        } else {
            rho = a + eps; // exactly on the ring: take the outside
        }
    } else if (!(dist > 0)) {
        return Vec3d::Zero(); // eps = 0 exactly on an end ring
    }
    double Hz, Hrho;
    sheetFieldCyl(mag.turns * mag.strength / mag.length, a, b, rho, z, Hz, Hrho);
    const double r = radial.norm();
    return Hz * n + (r > 0 ? Vec3d(radial * (Hrho / r)) : Vec3d::Zero());
}

} // namespace

/// The wire that carries the current at kStrongestCurrentDensity, as the loop's.
double coilBodyRadius(double strength) { return std::sqrt(std::abs(strength) / (kPi * kStrongestCurrentDensity)); }

Vec3d coilMagnetField(const Magnet& mag, const Vec3d& n, const Vec3d& x) { return coilField(mag, n, x); }

Mat3d coilMagnetGradient(const Magnet& mag, const Vec3d& n, const Vec3d& x) {
    if (!(mag.radius > 0.0) || !(mag.length > 0.0)) return Mat3d::Zero();
    // The field varies on the scale of the distance to the sheet and its end rings: the
    // step is relative to the distance to the nearer end ring, capped by the distance to
    // the sheet (the field is continuous there only in its tangential part).
    const Vec3d d = x - mag.position;
    const double z = d.dot(n);
    const double rho = (d - z * n).norm();
    const double b = 0.5 * mag.length;
    const double ring = std::hypot(rho - mag.radius, std::abs(z) - b);
    const double sheet = std::abs(z) <= b ? std::abs(rho - mag.radius) : ring;
    const double scale = std::max(std::min(ring, sheet), coilSoftening(mag));
    if (!(scale > 0.0)) return Mat3d::Zero();
    const double h = 1e-5 * scale;
    Mat3d J;
    for (int j = 0; j < 3; ++j) {
        Vec3d step = Vec3d::Zero();
        step[j] = h;
        J.col(j) = (coilField(mag, n, x + step) - coilField(mag, n, x - step)) / (2.0 * h);
    }
    return J;
}

} // namespace ferro

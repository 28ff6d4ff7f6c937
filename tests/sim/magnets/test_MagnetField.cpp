// Analytic magnet fields (sim/magnets/MagnetField): closed forms, Biot-Savart, far-field limits,
// softening and keyframe interpolation.
#include "sim/magnets/MagnetField.hpp"
#include "sim/magnets/MagnetKinds.hpp"
#include "sim/core/Constants.hpp"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include <cmath>

using namespace ferro;

namespace {

double relErr(const Vec3d& a, const Vec3d& b) { return (a - b).norm() / b.norm(); }

bool finite(const Vec3d& v) { return v.allFinite(); }

Mat3d numericGradient(const Magnet& m, const Vec3d& x, double h) {
    Mat3d J;
    for (int j = 0; j < 3; ++j) {
        Vec3d s = Vec3d::Zero();
        s[j] = h;
        J.col(j) = (magnetField(m, x + s) - magnetField(m, x - s)) / (2 * h);
    }
    return J;
}

// Biot-Savart of a circular loop, periodic trapezoid rule (exponentially convergent away
// from the wire): H = I/(4 pi) sum dl x (x - l) / |x - l|^3.
Vec3d biotSavartLoop(const Magnet& m, const Vec3d& x, int segments) {
    const Vec3d n = m.direction.normalized();
    const Vec3d u = n.unitOrthogonal();
    const Vec3d v = n.cross(u);
    const double dphi = 2 * kPi / segments;
    Vec3d H = Vec3d::Zero();
    for (int i = 0; i < segments; ++i) {
        const double phi = i * dphi;
        const Vec3d p = m.position + m.radius * (std::cos(phi) * u + std::sin(phi) * v);
        const Vec3d dl = m.radius * dphi * (-std::sin(phi) * u + std::cos(phi) * v);
        const Vec3d r = x - p;
        H += dl.cross(r) / std::pow(r.norm(), 3);
    }
    return m.strength / (4 * kPi) * H;
}

Magnet dipole(const Vec3d& pos, const Vec3d& dir, double moment) {
    Magnet m;
    m.kind = Magnet::Kind::Dipole;
    m.position = pos;
    m.direction = dir;
    m.strength = moment;
    return m;
}

Magnet loop(const Vec3d& pos, const Vec3d& dir, double current, double radius) {
    Magnet m;
    m.kind = Magnet::Kind::Loop;
    m.position = pos;
    m.direction = dir;
    m.strength = current;
    m.radius = radius;
    return m;
}

} // namespace

TEST_CASE("Dipole field matches the closed form", "[magnet]") {
    const double mom = 2.5;
    const Magnet d = dipole(Vec3d(0.1, -0.2, 0.3), Vec3d(0, 0, 2), mom); // unnormalized axis
    // The closed form holds outside the magnet's body (magnetBodyRadius, 7.9 mm here): the
    // field differs from it by (1 + (a/r)^8)^(-3/8), 1.4e-7 at r = 5 cm, hence 1e-6.
    const double r = 0.05;
    // On the axis: H = 2 m / (4 pi r^3) along the axis, either side.
    for (double sgn : {1.0, -1.0}) {
        const Vec3d H = magnetField(d, d.position + Vec3d(0, 0, sgn * r));
        CHECK(relErr(H, Vec3d(0, 0, 2 * mom / (4 * kPi * r * r * r))) < 1e-6);
    }
    // Equatorial plane: H = -m / (4 pi r^3).
    for (const Vec3d& e : {Vec3d(1, 0, 0), Vec3d(0, -1, 0), Vec3d(1, 1, 0).normalized()}) {
        const Vec3d H = magnetField(d, d.position + r * e);
        CHECK(relErr(H, Vec3d(0, 0, -mom / (4 * kPi * r * r * r))) < 1e-6);
    }
    // General points against the vector formula, tilted dipole.
    const Vec3d mvec = mom * Vec3d(1, 2, -0.5).normalized();
    const Magnet t = dipole(Vec3d(0, 0, 0), Vec3d(1, 2, -0.5), mom);
    // (A point inside the 7.9 mm body gets the bounded interior field, not the closed form.)
    for (const Vec3d& x : {Vec3d(0.3, 0.1, 0.02), Vec3d(-0.03, 0.06, 0.015), Vec3d(10, -20, 5)}) {
        const double rn = x.norm();
        const Vec3d rh = x / rn;
        const Vec3d ref = (3 * mvec.dot(rh) * rh - mvec) / (4 * kPi * rn * rn * rn);
        CHECK(relErr(magnetField(t, x), ref) < 1e-6);
    }
}

TEST_CASE("Dipole gradient: analytic, divergence- and curl-free", "[magnet]") {
    const Magnet d = dipole(Vec3d(0.01, 0.02, -0.03), Vec3d(0.3, -1, 0.7), 1.7);
    for (const Vec3d& x : {Vec3d(0.1, 0.05, 0.02), Vec3d(-0.02, 0.01, 0.03), Vec3d(1, 2, 3)}) {
        const Mat3d J = fieldGradient(d, x);
        const double scale = J.norm();
        // div H = -div M of the magnet's body, which reaches out as (a/r)^8: ~1e-8 here.
        CHECK(std::abs(J.trace()) < 1e-6 * scale);
        CHECK((J - J.transpose()).norm() < 1e-13 * scale);
        const double h = 1e-5 * (x - d.position).norm();
        CHECK((J - numericGradient(d, x, h)).norm() < 1e-8 * scale);
    }
    // Bar magnet gradient as well.
    Magnet bar;
    bar.kind = Magnet::Kind::Bar;
    bar.direction = Vec3d(0, 1, 1);
    bar.strength = 30;
    bar.length = 0.02;
    for (const Vec3d& x : {Vec3d(0.03, 0.01, 0.0), Vec3d(0.0, 0.0, 0.05)}) {
        const Mat3d J = fieldGradient(bar, x);
        const double scale = J.norm();
        CHECK(std::abs(J.trace()) < 1e-6 * scale);
        CHECK((J - J.transpose()).norm() < 1e-12 * scale);
        CHECK((J - numericGradient(bar, x, 1e-7)).norm() < 1e-7 * scale);
    }
}

TEST_CASE("Bar magnet far field tends to a dipole with m = q_m L", "[magnet]") {
    Magnet bar;
    bar.kind = Magnet::Kind::Bar;
    bar.position = Vec3d(0.5, 0.5, 0);
    bar.direction = Vec3d(1, 1, 1);
    bar.strength = 40;   // q_m [A m]
    bar.length = 0.01;   // [m]
    const Magnet dip = dipole(bar.position, bar.direction, bar.strength * bar.length);
    const Vec3d dirs[] = {Vec3d(1, 1, 1).normalized(), Vec3d(1, -1, 0).normalized(),
                          Vec3d(0.3, -0.8, 0.5).normalized()};
    for (const Vec3d& e : dirs) {
        const double e10 = relErr(magnetField(bar, bar.position + 10 * bar.length * e),
                                  magnetField(dip, bar.position + 10 * bar.length * e));
        const double e100 = relErr(magnetField(bar, bar.position + 100 * bar.length * e),
                                   magnetField(dip, bar.position + 100 * bar.length * e));
        CHECK(e10 < 2e-2);
        CHECK(e100 < 2e-4);
        // Quadrupole-free (symmetric charges): error falls as (L/r)^2, i.e. by ~100.
        CHECK(e10 / e100 == Approx(100).epsilon(0.05));
    }
}

TEST_CASE("Complete elliptic integrals", "[magnet]") {
    CHECK(ellipticK(0) == Approx(kPi / 2).epsilon(1e-15));
    CHECK(ellipticE(0) == Approx(kPi / 2).epsilon(1e-15));
    CHECK(std::abs(ellipticK(0.5) - 1.854074677301372) < 1e-14);
    CHECK(std::abs(ellipticE(0.5) - 1.350643881047675) < 1e-14);
    CHECK(ellipticE(1.0) == 1.0);
    // Reference values (mpmath, 30 digits) at k = 0.1, 0.7, 0.99; argument is m = k^2.
    CHECK(std::abs(ellipticK(0.01) - 1.574745561517355953) < 2e-15);
    CHECK(std::abs(ellipticE(0.01) - 1.566861942021668290) < 2e-15);
    CHECK(std::abs(ellipticK(0.49) - 1.845693998374723464) < 2e-15);
    CHECK(std::abs(ellipticE(0.49) - 1.355661135571955497) < 2e-15);
    CHECK(std::abs(ellipticK(0.9801) - 3.356600523361191667) < 4e-15);
    CHECK(std::abs(ellipticE(0.9801) - 1.028475809028804035) < 2e-15);
    // libstdc++'s std::comp_ellint_* (argument k) agree only loosely near k -> 1
    // (E(0.99) is off by 4e-13 there), hence the looser tolerance.
    for (double k : {0.1, 0.3, 0.7, 0.9, 0.99}) {
        CHECK(ellipticK(k * k) == Approx(std::comp_ellint_1(k)).epsilon(1e-11));
        CHECK(ellipticE(k * k) == Approx(std::comp_ellint_2(k)).epsilon(1e-11));
    }
    // Near m -> 1: K ~ ln(4 / k') with k' = sqrt(1 - m) (error O(k'^2 ln k')).
    const double m1 = 1e-20;
    CHECK(ellipticK(1 - m1) > 20);
    CHECK(std::isfinite(ellipticK(1 - 1e-15)));
}

TEST_CASE("Loop field: on axis, Biot-Savart off axis, dipole far field", "[magnet]") {
    const double I = 3.0, R = 0.04;
    SECTION("on-axis closed form") {
        const Magnet l = loop(Vec3d(0.1, 0.2, 0.3), Vec3d(0, 0, 1), I, R);
        for (double z : {0.0, 0.01, -0.03, 0.5}) {
            const Vec3d H = magnetField(l, l.position + Vec3d(0, 0, z));
            const double ref = I * R * R / (2 * std::pow(R * R + z * z, 1.5));
            CHECK(relErr(H, Vec3d(0, 0, ref)) < 1e-14);
        }
        // Just off the axis the elliptic form agrees with the paraxial expansion
        // H_z = on-axis value, H_rho = -(rho/2) dH_z/dz (cancellation-prone region).
        for (double rho : {0.0, 1e-9, 1e-8, 1e-7}) {
            const double z = 0.01, s2 = R * R + z * z;
            const Vec3d H = magnetField(l, l.position + Vec3d(rho, 0, z));
            const Vec3d ref(3 * I * R * R * z * rho / (4 * std::pow(s2, 2.5)), 0,
                            I * R * R / (2 * std::pow(s2, 1.5)));
            CHECK(relErr(H, ref) < 1e-10);
            CHECK(std::abs(H.x() - ref.x()) <= 1e-9 * ref.x());
        }
    }
    SECTION("off axis against Biot-Savart, tilted loop") {
        const Magnet l = loop(Vec3d(0.01, -0.02, 0.03), Vec3d(0.2, -0.4, 1), I, R);
        const Vec3d n = l.direction.normalized();
        const Vec3d u = n.unitOrthogonal();
        const Vec3d v = n.cross(u);
        // (rho, z) in the loop frame, including points near the wire (rho ~ R, small z).
        const double pts[][2] = {{0.5 * R, 0.2 * R}, {1.5 * R, -0.7 * R}, {3 * R, 2 * R},
                                 {0.99 * R, 0.0},     {R, 0.01 * R},      {1.002 * R, 0.001 * R},
                                 {0.2 * R, 0.0},      {0.0001 * R, 0.3 * R},
                                 // m = 4 a rho / beta^2 either side of the 0.1 switch to the
                                 // quadrature branch near the axis / far away
                                 {0.02 * R, 0.1 * R}, {0.027 * R, 0.0},   {0.5 * R, 5 * R},
                                 {0.6 * R, 3.5 * R},  {40 * R, 0.0}};
        for (const auto& p : pts) {
            const Vec3d x = l.position + p[0] * (0.6 * u + 0.8 * v) + p[1] * n;
            const Vec3d H = magnetField(l, x);
            const Vec3d ref = biotSavartLoop(l, x, 20000);
            INFO("rho/R = " << p[0] / R << ", z/R = " << p[1] / R << ", rel. error " << relErr(H, ref));
            CHECK(relErr(H, ref) < 1e-10); // observed <= 6e-14
        }
    }
    SECTION("far field tends to a dipole with m = I pi R^2") {
        const Magnet l = loop(Vec3d(0, 0, 0), Vec3d(1, 0, 1), I, R);
        const Magnet dip = dipole(l.position, l.direction, I * kPi * R * R);
        const Vec3d e = Vec3d(0.3, 0.5, -0.2).normalized();
        const double e10 = relErr(magnetField(l, 10 * R * e), magnetField(dip, 10 * R * e));
        const double e100 = relErr(magnetField(l, 100 * R * e), magnetField(dip, 100 * R * e));
        CHECK(e10 < 2e-2);
        CHECK(e100 < 2e-4);
    }
    SECTION("gradient: finite-difference Jacobian is divergence- and curl-free") {
        const Magnet l = loop(Vec3d(0, 0, 0), Vec3d(0, 1, 1), I, R);
        for (const Vec3d& x : {Vec3d(0.01, 0.02, 0.0), Vec3d(0.05, -0.01, 0.03),
                               Vec3d(0.0, 0.0, 0.0)}) {
            const Mat3d J = fieldGradient(l, x);
            const double scale = J.norm();
            // (All zero at the loop centre, by symmetry: hence <= and a floor.)
            CHECK(std::abs(J.trace()) <= 1e-7 * scale + 1e-12);
            CHECK((J - J.transpose()).norm() <= 1e-7 * scale + 1e-12);
        }
    }
}

TEST_CASE("Uniform field and superposition", "[magnet]") {
    Magnet u;
    u.kind = Magnet::Kind::Uniform;
    u.direction = Vec3d(0, 3, 4);
    u.strength = 1000;
    u.position = Vec3d(5, 5, 5); // ignored
    CHECK(relErr(magnetField(u, Vec3d(0.1, -7, 2)), Vec3d(0, 600, 800)) < 1e-15);
    CHECK(fieldGradient(u, Vec3d(1, 2, 3)).norm() == 0.0);

    const Magnet a = dipole(Vec3d(0, 0, -0.05), Vec3d(0, 0, 1), 2.0);
    const Magnet b = loop(Vec3d(0.02, 0, 0.01), Vec3d(1, 0, 0), 5.0, 0.03);
    const std::vector<Magnet> all{a, b, u};
    for (const Vec3d& x : {Vec3d(0.01, 0.02, 0.03), Vec3d(-0.1, 0.05, 0.0)}) {
        const Vec3d sum = magnetField(a, x) + magnetField(b, x) + magnetField(u, x);
        CHECK(relErr(magnetField(all, x), sum) < 1e-15);
        const Mat3d Jsum = fieldGradient(a, x) + fieldGradient(b, x) + fieldGradient(u, x);
        CHECK((fieldGradient(all, x) - Jsum).norm() <= 1e-15 * Jsum.norm());
    }
    CHECK(magnetField(std::vector<Magnet>{}, Vec3d(1, 2, 3)).norm() == 0.0);
}

TEST_CASE("Softening keeps singular points finite without changing the far field",
          "[magnet]") {
    // Plummer softening changes the field by O((eps/r)^2) at distance r, so "far" here is
    // r > ~1000 eps: a 0.1 mm softening seen from ~1.4 m, or equivalently 1 mm from 14 m.
    const double eps = 1e-4;
    Magnet d = dipole(Vec3d(0, 0, 0), Vec3d(0, 0, 1), 1.0);
    Magnet bar;
    bar.kind = Magnet::Kind::Bar;
    bar.direction = Vec3d(0, 0, 1);
    bar.strength = 10;
    bar.length = 0.02;
    Magnet l = loop(Vec3d(0, 0, 0), Vec3d(0, 0, 1), 2.0, 0.05);

    // eps = 0 exactly at the singular point: finite, never NaN; the magnet's body bounds it
    // (a dipole's centre: -M/3 of a sphere magnetized at kStrongestMagnetization).
    CHECK(magnetField(d, d.position).norm() <= kStrongestMagnetization / 3 * (1 + 1e-12));
    CHECK(magnetField(bar, Vec3d(0, 0, 0.01)).allFinite());
    CHECK(magnetField(l, Vec3d(0.05, 0, 0)).allFinite());
    CHECK(fieldGradient(d, d.position).allFinite());
    CHECK(fieldGradient(l, Vec3d(0.05, 0, 0)).allFinite());

    const Vec3d far(0.7, -0.4, 1.1);
    const Vec3d dFar = magnetField(d, far), barFar = magnetField(bar, far),
                lFar = magnetField(l, far);
    d.softening = bar.softening = l.softening = eps;

    // At the dipole centre, on the pole, on and next to the wire: finite.
    CHECK(finite(magnetField(d, d.position)));
    CHECK(magnetField(d, d.position).norm() > 0);
    CHECK(finite(magnetField(bar, Vec3d(0, 0, 0.01))));
    CHECK(finite(magnetField(bar, Vec3d(0, 0, -0.01))));
    for (const Vec3d& x : {Vec3d(0.05, 0, 0), Vec3d(0.0500001, 0, 1e-7), Vec3d(0, 0.04995, 0)}) {
        CHECK(finite(magnetField(l, x)));
        CHECK(fieldGradient(l, x).allFinite());
    }
    CHECK(fieldGradient(d, d.position).allFinite());
    CHECK(fieldGradient(bar, Vec3d(0, 0, 0.01)).allFinite());
    // Inside the clamp the loop field is the field at distance eps along the same direction
    // from the wire (here a tilted 3D point, so H_rho matters).
    const Vec3d e = Vec3d(1, 2, 0).normalized();
    const Vec3d inside = (0.05 + 0.3 * eps) * e + Vec3d(0, 0, 0.4 * eps);  // distance eps/2
    const Vec3d onShell = (0.05 + 0.6 * eps) * e + Vec3d(0, 0, 0.8 * eps); // distance eps
    CHECK(relErr(magnetField(l, inside), magnetField(l, onShell)) < 1e-13);
    const double atEps = magnetField(l, Vec3d(0.05 + eps, 0, 0)).norm();
    CHECK(magnetField(l, Vec3d(0.05, 0, 0)).norm() == Approx(atEps).epsilon(1e-13));
    CHECK(magnetField(l, Vec3d(0.05, 0, 0)).norm() > 0);

    // Far field unchanged.
    CHECK(relErr(magnetField(d, far), dFar) < 1e-6);
    CHECK(relErr(magnetField(bar, far), barFar) < 1e-6);
    CHECK(relErr(magnetField(l, far), lFar) == 0.0); // the wire clamp is purely local
    // Plummer change is second order in eps / r.
    const double q = eps / far.norm();
    CHECK(relErr(magnetField(d, far), dFar) < 3 * q * q);
}

TEST_CASE("Magnet keyframe tracks", "[magnet]") {
    MagnetTrack track;
    track.base = dipole(Vec3d(9, 9, 9), Vec3d(1, 0, 0), 7.0);
    track.base.softening = 2e-3;

    SECTION("no keys returns base") {
        const Magnet m = track.at(1.0);
        CHECK(m.position == track.base.position);
        CHECK(m.strength == 7.0);
    }

    track.keys = {
        {0.0, Vec3d(0, 0, 0.10), Vec3d(0, 0, 1), 1.0},
        {0.5, Vec3d(0.02, 0, 0.08), Vec3d(1, 0, 1), 2.0},
        {2.0, Vec3d(0.02, 0.03, 0.05), Vec3d(0, 0, -1), 0.5},
        {2.5, Vec3d(0, 0, 0.05), Vec3d(0, 1, 0), 0.5},
    };

    SECTION("reproduces keys, clamps outside, keeps base properties") {
        for (const MagnetKeyframe& k : track.keys) {
            const Magnet m = track.at(k.time);
            CHECK((m.position - k.position).norm() < 1e-15);
            CHECK(m.strength == Approx(k.strength).epsilon(1e-14));
            CHECK((m.direction - k.direction.normalized()).norm() < 1e-12);
            CHECK(m.kind == Magnet::Kind::Dipole);
            CHECK(m.softening == 2e-3);
        }
        CHECK(track.at(-3.0).position == track.keys.front().position);
        CHECK(track.at(-3.0).strength == track.keys.front().strength);
        CHECK(track.at(100.0).position == track.keys.back().position);
        CHECK((track.at(100.0).direction - Vec3d(0, 1, 0)).norm() < 1e-15);
    }

    SECTION("continuous, unit direction, strength without overshoot") {
        const double dt = 1e-6;
        for (double t = -0.1; t <= 2.7; t += dt * 997) {
            const Magnet a = track.at(t);
            const Magnet b = track.at(t + dt);
            CHECK(std::abs(a.direction.norm() - 1) < 1e-12);
            // Small step -> small change (Lipschitz with a generous constant).
            CHECK((b.position - a.position).norm() < 1e-6 * 10);
            CHECK(std::abs(b.strength - a.strength) < 1e-6 * 10);
            CHECK((b.direction - a.direction).norm() < 1e-6 * 10);
            // Monotone Hermite strength stays within the key range.
            CHECK(a.strength >= 0.5 - 1e-12);
            CHECK(a.strength <= 2.0 + 1e-12);
        }
        // Antiparallel keys (t = 2 -> 2.5 is 90 deg, add an explicit 180 deg pair).
        MagnetTrack flip;
        flip.keys = {{0, Vec3d::Zero(), Vec3d(0, 0, 1), 1}, {1, Vec3d::Zero(), Vec3d(0, 0, -1), 1}};
        for (double t = 0; t <= 1; t += 0.125) {
            const Vec3d dir = flip.at(t).direction;
            CHECK(dir.allFinite());
            CHECK(std::abs(dir.norm() - 1) < 1e-12);
        }
        CHECK(flip.at(0.5).direction.z() == Approx(0).margin(1e-12));
    }
}

namespace {

Magnet coil(const Vec3d& pos, const Vec3d& dir, double current, double radius, double length, double turns) {
    Magnet m;
    m.kind = Magnet::Kind::Coil;
    m.position = pos;
    m.direction = dir;
    m.strength = current;
    m.radius = radius;
    m.length = length;
    m.turns = turns;
    return m;
}

// The ideal solenoid as a stack of current loops: Gauss-Legendre in z over `panels` equal
// panels of the winding, 8 nodes each, every node a loop of current turns I / length * dz
// (the loop field is tested against Biot-Savart above).
Vec3d stackedLoops(const Magnet& c, const Vec3d& x, int panels) {
    static const double node[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static const double weight[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    const Vec3d n = c.direction.normalized();
    const double h = c.length / panels;
    Vec3d H = Vec3d::Zero();
    for (int p = 0; p < panels; ++p) {
        const double mid = -0.5 * c.length + (p + 0.5) * h;
        for (int k = 0; k < 8; ++k) {
            const double s = (k < 4 ? -1 : 1) * node[k % 4];
            const Magnet l = loop(c.position + (mid + 0.5 * h * s) * n, n,
                                  c.turns * c.strength / c.length * 0.5 * h * weight[k % 4], c.radius);
            H += magnetField(l, x);
        }
    }
    return H;
}

} // namespace

TEST_CASE("Coil field: the solenoid's on-axis closed form, stacked loops off axis, dipole far field", "[magnet]") {
    const double I = 2.5, R = 0.03, L = 0.05, N = 400;
    SECTION("on-axis closed form H = n I / 2 (cos at the two ends)") {
        const Magnet c = coil(Vec3d(0.01, -0.02, 0.05), Vec3d(0, 0, 1), I, R, L, N);
        for (double z : {0.0, 0.01, 0.02499, 0.025, -0.03, 0.06, -0.2}) {
            const Vec3d H = magnetField(c, c.position + Vec3d(0, 0, z));
            const double zp = z + 0.5 * L, zm = z - 0.5 * L;
            const double ref = N * I / L / 2 * (zp / std::hypot(zp, R) - zm / std::hypot(zm, R));
            INFO("z = " << z << ", H = " << H.transpose() << ", closed form " << ref);
            CHECK(relErr(H, Vec3d(0, 0, ref)) < 1e-10); // the must-show is 1 %
        }
    }
    SECTION("off axis against a stack of loops, tilted coil") {
        const Magnet c = coil(Vec3d(0.02, 0.01, -0.03), Vec3d(-0.3, 0.5, 1), I, R, L, N);
        const Vec3d n = c.direction.normalized();
        const Vec3d u = n.unitOrthogonal();
        // (rho, z) in the coil frame: inside, outside, beside the ends, far.
        const double pts[][2] = {{0.5 * R, 0.0},     {0.9 * R, 0.3 * L}, {1.2 * R, 0.1 * L}, {2 * R, 0.6 * L},
                                 {0.3 * R, 0.8 * L}, {1.1 * R, -0.55 * L}, {0.99 * R, 0.52 * L}, {5 * R, -3 * L}};
        for (const auto& p : pts) {
            const Vec3d x = c.position + p[0] * u + p[1] * n;
            const Vec3d H = magnetField(c, x);
            const Vec3d ref = stackedLoops(c, x, 400);
            INFO("rho/R = " << p[0] / R << ", z/L = " << p[1] / L << ", rel. error " << relErr(H, ref));
            CHECK(relErr(H, ref) < 1e-6);
        }
    }
    SECTION("far field tends to a dipole with m = N I pi R^2") {
        const Magnet c = coil(Vec3d(0, 0, 0), Vec3d(1, 0, 1), I, R, L, N);
        const Magnet dip = dipole(c.position, c.direction, N * I * kPi * R * R);
        const Vec3d e = Vec3d(0.3, 0.5, -0.2).normalized();
        CHECK(relErr(magnetField(c, 20 * R * e), magnetField(dip, 20 * R * e)) < 1e-2);
        CHECK(relErr(magnetField(c, 200 * R * e), magnetField(dip, 200 * R * e)) < 1e-4);
    }
    SECTION("gradient is divergence- and curl-free; an end ring stays finite") {
        const Magnet c = coil(Vec3d(0, 0, 0), Vec3d(0, 1, 1), I, R, L, N);
        for (const Vec3d& x : {Vec3d(0.01, 0.02, 0.0), Vec3d(0.05, -0.01, 0.03), Vec3d(0.0, 0.0, 0.0)}) {
            const Mat3d J = fieldGradient(c, x);
            const double scale = J.norm();
            CHECK(std::abs(J.trace()) <= 1e-6 * scale + 1e-9);
            CHECK((J - J.transpose()).norm() <= 1e-6 * scale + 1e-9);
        }
        const Vec3d n = c.direction.normalized();
        const Vec3d ring = c.position + 0.5 * L * n + R * n.unitOrthogonal();
        CHECK(magnetField(c, ring).allFinite());
        CHECK(fieldGradient(c, ring).allFinite());
    }
}

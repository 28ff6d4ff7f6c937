// Surface tension: a free blob pulls itself into a sphere, and its interior pressure grows
// with the surface tension coefficient as the Laplace pressure 2 sigma / R (checked on a
// droplet of 8 spacings: AkinciTension::kCalibration (sim/sph/forces/AkinciTension.hpp) was fitted on one
// of 11); and, independent of that fit, a droplet's l = 2 shape oscillation against
// Rayleigh's (1879) frequency omega_2^2 = 8 sigma / (rho R^3).
#include "sim/sph/FluidSimulation.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

using namespace ferro;

namespace {

struct Droplet {
    double radiusOfGyrationRatio; ///< r_gyr / R; a solid sphere has sqrt(3/5)
    double interiorPressure;      ///< mean pressure inside R/2 [Pa]
    double radius;                ///< radius of a sphere of the fluid's volume [m]
};

Droplet relaxDroplet(double sigma, double cylinderRadius) {
    SimScene s;
    s.path = "droplet";
    s.fluid.restDensity = 1000;
    s.fluid.viscosity = 1e-5;
    s.fluid.surfaceTension = sigma;
    s.fluid.spacing = 0.001;
    FluidBlock b;  // a squat cylinder: far from round at the start
    b.shape = FluidBlock::Shape::Cylinder;
    b.center = Vec3d(0, 0, -cylinderRadius);
    b.radius = cylinderRadius;
    b.height = 2 * cylinderRadius;
    s.fluid.blocks.push_back(b);
    s.container.type = ContainerParams::Type::None;
    s.solver.gravity = Vec3d::Zero();
    FluidSimulation sim(s);
    sim.advanceTo(0.2);
    Vec3d c = Vec3d::Zero();
    for (const Vec3& p : sim.positions()) c += p.cast<double>();
    c /= double(sim.size());
    const double R = std::cbrt(sim.size() * sim.particleMass() / sim.restDensity() * 3 / (4 * kPi));
    double r2 = 0, p = 0;
    int inner = 0;
    for (size_t i = 0; i < sim.size(); ++i) {
        const double r = (sim.positions()[i].cast<double>() - c).norm();
        r2 += r * r;
        if (r < 0.5 * R) {
            p += sim.pressures()[i];
            ++inner;
        }
    }
    return {std::sqrt(r2 / double(sim.size())) / R, p / inner, R};
}

} // namespace

// KNOWN FAILURE (measured 2026-12, Akinci 2013 tension with AkinciTension::kCalibration):
// the interior pressure's slope d p / d sigma does not follow 2 / R. It is ~175 /m whatever
// the radius: 175 at R = 5.9 spacings (2/R = 382), 166 at 8.0 (268), passes at 11.4 (175),
// 184 at 14.8 (139). The cohesion term compresses the whole droplet by an amount set by the
// spacing, not the curvature, and the constant was fitted where that equals 2 sigma / R.
// Hidden ([.known-failure]): ctest does not run it, since a check that may fail can never
// fail CI; `ferro_sph_tests [known-failure]` shows the numbers. Unhide it when the model is
// fixed.
TEST_CASE("a free blob becomes a sphere with Laplace pressure 2 sigma / R", "[sph][tension][.known-failure]") {
    // A cylinder of radius 7 spacings and height 14: a sphere of R = 8.0 spacings, not the
    // 11 spacings the coefficient was fitted on.
    const Droplet weak = relaxDroplet(0.025, 0.007), strong = relaxDroplet(0.07, 0.007);
    CAPTURE(weak.radiusOfGyrationRatio, strong.radiusOfGyrationRatio, weak.interiorPressure, strong.interiorPressure);
    // The pressure difference isolates the surface tension term from the discretization's
    // baseline (compression of a particle cluster without any tension).
    const double slope = (strong.interiorPressure - weak.interiorPressure) / (0.07 - 0.025);
    CAPTURE(slope, 2 / strong.radius);
    CHECK(slope == Approx(2 / strong.radius).epsilon(0.25));
}

TEST_CASE("a free blob pulls itself into a sphere", "[sph][tension]") {
    for (double sigma : {0.025, 0.07}) {
        const Droplet d = relaxDroplet(sigma, 0.007);
        CAPTURE(sigma, d.radiusOfGyrationRatio);
        // A solid sphere has r_gyr / R = sqrt(3/5) = 0.775; the start, a cylinder as high as
        // it is wide, has (a^2 / 2 + h^2 / 12)^1/2 / (3 a^2 h / 4)^1/3 = 0.797.
        REQUIRE(d.radiusOfGyrationRatio == Approx(std::sqrt(0.6)).epsilon(0.02));
    }
}

namespace {

/// Quadrupole moment of the particles about their centre, (<z^2> - (<x^2> + <y^2>) / 2) / R^2:
/// zero for a sphere, (c^2 - a^2) / (5 R^2) for an ellipsoid of semi-axes a, a, c.
double quadrupole(const std::vector<Vec3>& x, double R) {
    Vec3d c = Vec3d::Zero();
    for (const Vec3& p : x) c += p.cast<double>();
    c /= double(x.size());
    double q = 0;
    for (const Vec3& p : x) {
        const Vec3d d = p.cast<double>() - c;
        q += d.z() * d.z() - 0.5 * (d.x() * d.x() + d.y() * d.y());
    }
    return q / double(x.size()) / (R * R);
}

} // namespace

// KNOWN FAILURE, see the report of issue 12: the droplet's l = 2 oscillation is ~4x slower
// than Rayleigh's and strongly damped even without viscosity. Here (R = 6.8 spacings, 1331
// particles): Rayleigh T = 0.150 s, quadrupole zeros at 0.167 s and 0.475 s, i.e. T/4 x 4.5
// and a period of 0.615 s (x 4.1). In side runs: first zero at 4.3 T/4 at R = 7.5 spacings,
// 4.6 T/4 at 11.7, none within 3 T at 15.6 (over-damped); with nu = 0 alike; 4 sigma halves
// the time, so it scales as sigma^-1/2 but with an effective sigma of ~ sigma / 18.
// Same cause as above: the calibrated cohesion acts as a bulk pressure, and the part of the
// force that depends on the shape (the curvature term) is far weaker than sigma.
// Hidden like the case above ([.known-failure]).
TEST_CASE("a droplet's l = 2 oscillation has Rayleigh's period 2 pi sqrt(rho R^3 / (8 sigma))", "[sph][tension][.known-failure]") {
    const double s = 0.001, sigma = 0.07, rho0 = 1000, eps = 0.1;
    SimScene scene;
    scene.path = "rayleigh";
    scene.fluid.restDensity = rho0;
    scene.fluid.viscosity = 1e-6;        // water: Lamb's damping 5 nu / R^2 = 0.09 /s, negligible
    scene.solver.artificialViscosity = 0;
    scene.fluid.surfaceTension = sigma;
    scene.fluid.spacing = s;
    FluidBlock b;  // only sets the particle count: the state is replaced below
    b.shape = FluidBlock::Shape::Cylinder;
    b.center = Vec3d(0, 0, 0);
    b.radius = 0.0066;
    b.height = 0.0114;
    scene.fluid.blocks.push_back(b);
    scene.container.type = ContainerParams::Type::None;
    scene.solver.gravity = Vec3d::Zero();
    FluidSimulation sim(scene);
    const size_t n = sim.size();
    // The same number of lattice points, in a prolate spheroid of semi-axes R (1 + eps)^-1/2,
    // R (1 + eps): the n points of smallest ellipsoidal radius, at rest.
    std::vector<std::pair<double, Vec3>> lattice;
    for (int i = -20; i <= 20; ++i)
        for (int j = -20; j <= 20; ++j)
            for (int k = -20; k <= 20; ++k) {
                const Vec3d p = s * Vec3d(i, j, k);
                lattice.push_back({(p.x() * p.x() + p.y() * p.y()) * (1 + eps) + p.z() * p.z() / ((1 + eps) * (1 + eps)),
                                   p.cast<Real>()});
            }
    std::stable_sort(lattice.begin(), lattice.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
    std::vector<Vec3> x(n), v(n, Vec3::Zero());
    for (size_t i = 0; i < n; ++i) x[i] = lattice[i].second;
    sim.setState(0, x, v, {});

    const double R = std::cbrt(double(n) * sim.particleVolume() * 3 / (4 * kPi));
    const double period = 2 * kPi * std::sqrt(rho0 * R * R * R / (8 * sigma));
    // The quadrupole starts at its maximum and passes zero at T/4 and 3T/4 (damping moves
    // both zeros by the same amount to first order, so their distance is T/2).
    std::vector<double> zeros;
    double previous = quadrupole(sim.positions(), R);
    const double q0 = previous;
    for (int k = 1; k <= 400 && zeros.size() < 2; ++k) {
        const double t0 = sim.time(), t = k * period / 100;
        sim.advanceTo(t);
        const double q = quadrupole(sim.positions(), R);
        if ((q < 0) != (previous < 0)) zeros.push_back(t0 + (t - t0) * previous / (previous - q));
        previous = q;
    }
    CAPTURE(n, R / s, q0, period, zeros);
    REQUIRE(q0 > 0.04);
    REQUIRE(zeros.size() == 2);
    CHECK(zeros[0] == Approx(period / 4).epsilon(0.2));
    CHECK(2 * (zeros[1] - zeros[0]) == Approx(period).epsilon(0.2));
}

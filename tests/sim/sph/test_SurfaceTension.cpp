// Surface tension: a free blob pulls itself into a sphere, and its interior pressure grows
// with the surface tension coefficient as the Laplace pressure 2 sigma / R.
#include "sim/sph/FluidSimulation.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using namespace ferro;

namespace {

struct Droplet {
    double radiusOfGyrationRatio; ///< r_gyr / R; a solid sphere has sqrt(3/5)
    double interiorPressure;      ///< mean pressure inside R/2 [Pa]
    double radius;                ///< radius of a sphere of the fluid's volume [m]
};

Droplet relaxDroplet(double sigma) {
    SimScene s;
    s.path = "droplet";
    s.fluid.restDensity = 1000;
    s.fluid.viscosity = 1e-5;
    s.fluid.surfaceTension = sigma;
    s.fluid.spacing = 0.001;
    FluidBlock b;  // a squat cylinder: far from round at the start
    b.shape = FluidBlock::Shape::Cylinder;
    b.center = Vec3d(0, 0, -0.01);
    b.radius = 0.01;
    b.height = 0.02;
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

TEST_CASE("a free blob becomes a sphere with Laplace pressure 2 sigma / R", "[sph][tension][slow]") {
    const Droplet weak = relaxDroplet(0.025), strong = relaxDroplet(0.07);
    CAPTURE(weak.radiusOfGyrationRatio, strong.radiusOfGyrationRatio, weak.interiorPressure, strong.interiorPressure);
    REQUIRE(strong.radiusOfGyrationRatio == Approx(std::sqrt(0.6)).epsilon(0.02));
    REQUIRE(weak.radiusOfGyrationRatio == Approx(std::sqrt(0.6)).epsilon(0.02));
    // The pressure difference isolates the surface tension term from the discretization's
    // baseline (compression of a particle cluster without any tension).
    const double slope = (strong.interiorPressure - weak.interiorPressure) / (0.07 - 0.025);
    CAPTURE(slope, 2 / strong.radius);
    REQUIRE(slope == Approx(2 / strong.radius).epsilon(0.25));
}

// Physics checks of the SPH core: hydrostatics, volume conservation, momentum
// conservation, the Martin & Moyce dam break, a settling dish, a mesh vessel.
#include "sim/FluidSimulation.hpp"
#include "sim/SceneFile.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

using namespace ferro;

namespace {

std::string example(const std::string& name) { return std::string(FERRO_SOURCE_DIR) + "/examples/" + name; }

double meanZ(const FluidSimulation& sim) {
    double s = 0;
    for (const Vec3& p : sim.positions()) s += p.z();
    return s / double(sim.size());
}

Vec3d momentum(const FluidSimulation& sim) {
    Vec3d m = Vec3d::Zero();
    for (const Vec3& v : sim.velocities()) m += sim.particleMass() * v.cast<double>();
    return m;
}

/// Hydrostatic checks on the tank of examples/hydrostatic.toml after settling.
void checkResting(FluidSimulation& sim, double depth) {
    const double rho0 = sim.restDensity();
    const double g = 9.81;
    double err = 0;
    for (Real r : sim.densities()) err += std::abs(r / rho0 - 1);
    err /= double(sim.size());
    CAPTURE(err);
    REQUIRE(err < 0.01);

    // Pressure of the bottom layer against rho g (depth - z).
    const double s = sim.spacing();
    double measured = 0, expected = 0;
    int n = 0;
    for (size_t i = 0; i < sim.size(); ++i) {
        const double z = sim.positions()[i].z();
        if (z > 1.2 * s) continue;
        // Stay away from the side walls, where the kernel is truncated.
        const double x = sim.positions()[i].x(), y = sim.positions()[i].y();
        if (x < 2 * s || x > 0.05 - 2 * s || y < 2 * s || y > 0.05 - 2 * s) continue;
        measured += sim.pressures()[i];
        expected += rho0 * g * (depth - z);
        ++n;
    }
    REQUIRE(n > 50);
    CAPTURE(measured / n, expected / n);
    REQUIRE(measured / n == Approx(expected / n).epsilon(0.05));
}

} // namespace

TEST_CASE("resting tank (DFSPH): density, bottom pressure, volume drift over 5 s", "[sph][slow]") {
    SimScene scene = loadSimScene(example("hydrostatic.toml"));
    FluidSimulation sim(scene);
    // Fluid depth: particle volume times count over the floor area.
    const double depth = sim.size() * sim.particleMass() / sim.restDensity() / (0.05 * 0.05);
    REQUIRE(depth == Approx(0.05).epsilon(0.02));
    const double z0 = meanZ(sim);
    double worst = 0;
    for (int second = 1; second <= 5; ++second) {
        sim.advanceTo(second);
        worst = std::max(worst, std::abs(meanZ(sim) / z0 - 1));
        if (second == 1) checkResting(sim, depth);
    }
    CAPTURE(worst);
    REQUIRE(worst < 0.01);
    checkResting(sim, depth);
    double vmax = 0;
    for (const Vec3& v : sim.velocities()) vmax = std::max(vmax, double(v.norm()));
    REQUIRE(vmax < 0.01);
}

TEST_CASE("resting tank (WCSPH): density and bottom pressure", "[sph][slow]") {
    SimScene scene = loadSimScene(example("hydrostatic.toml"), {"sim.solver=wcsph"});
    FluidSimulation sim(scene);
    const double depth = sim.size() * sim.particleMass() / sim.restDensity() / (0.05 * 0.05);
    const double z0 = meanZ(sim);
    sim.advanceTo(1.0);
    checkResting(sim, depth);
    REQUIRE(std::abs(meanZ(sim) / z0 - 1) < 0.01);
}

TEST_CASE("free flight without walls or gravity conserves momentum", "[sph]") {
    for (auto kind : {SolverParams::Kind::WCSPH, SolverParams::Kind::DFSPH}) {
        SimScene scene;
        scene.path = "free-flight";
        scene.fluid.restDensity = 1000;
        scene.fluid.viscosity = 1e-4;
        scene.fluid.surfaceTension = 0.07;   // a cube pulls itself round: strong internal forces
        scene.fluid.spacing = 0.001;
        FluidBlock block;
        block.min = Vec3d(0, 0, 0);
        block.max = Vec3d(0.012, 0.01, 0.008);
        block.velocity = Vec3d(0.3, -0.2, 0.1);
        scene.fluid.blocks.push_back(block);
        scene.container.type = ContainerParams::Type::None;
        scene.solver.kind = kind;
        scene.solver.gravity = Vec3d::Zero();
        FluidSimulation sim(scene);
        const Vec3d p0 = momentum(sim);
        sim.advanceTo(0.05);
        const Vec3d p1 = momentum(sim);
        CAPTURE(int(kind), p0.transpose(), p1.transpose(), sim.stepCount());
        REQUIRE(sim.stepCount() > 20);
        REQUIRE((p1 - p0).norm() / p0.norm() < 1e-6);
        // The blob moved as a whole, at its initial velocity.
        Vec3d centre = Vec3d::Zero();
        for (const Vec3& x : sim.positions()) centre += x.cast<double>();
        centre /= double(sim.size());
        REQUIRE(centre.x() == Approx(0.006 + 0.3 * 0.05).epsilon(1e-3));
    }
}

TEST_CASE("dam break surge front follows Martin & Moyce (1952)", "[sph][slow]") {
    // Martin & Moyce 1952, 2:1 column (n^2 = 2), a = 2.25 in: dimensionless surge front
    // Z = x / a against T = t sqrt(2 g / a), their Table 2, up to T = 2.5.
    //
    // Known discrepancy: every instantaneous-release simulation runs ahead of this data at
    // early times, because the experiment's gate took a finite time to open. Ferro is
    // 13-16 % ahead at T = 0.8-1.5 (at a/20 and at a/30 alike), and within 10 % from
    // T = 1.8 on; the front speed dZ/dT, which the release delay does not affect, is
    // within 5 %. The test holds all three.
    const std::vector<std::pair<double, double>> data = {
        {0.41, 1.11}, {0.84, 1.22}, {1.19, 1.44}, {1.43, 1.67}, {1.63, 1.89},
        {1.83, 2.11}, {1.98, 2.33}, {2.20, 2.56}, {2.32, 2.78}, {2.51, 3.00}};
    for (const char* solver : {"dfsph", "wcsph"}) {
        SimScene scene = loadSimScene(example("dam_break.toml"), {std::string("sim.solver=") + solver});
        FluidSimulation sim(scene);
        const double a = 0.05715, g = 9.81;
        const double tScale = std::sqrt(a / (2 * g));
        std::vector<double> Zsim;
        for (const auto& [T, Z] : data) {
            sim.advanceTo(T * tScale);
            double front = 0;
            for (const Vec3& p : sim.positions()) front = std::max(front, double(p.x()));
            // The fluid ends half a spacing beyond the last particle centre.
            Zsim.push_back((front + 0.5 * sim.spacing()) / a);
            const double err = Zsim.back() / Z - 1;
            CAPTURE(solver, T, Z, Zsim.back(), err);
            CHECK(std::abs(err) < (T >= 1.8 ? 0.10 : 0.18));
        }
        // Front speed over T = 1.43 .. 2.51 (data points 3 and 9).
        const double speedData = (data[9].second - data[3].second) / (data[9].first - data[3].first);
        const double speedSim = (Zsim[9] - Zsim[3]) / (data[9].first - data[3].first);
        CAPTURE(solver, speedData, speedSim);
        CHECK(speedSim == Approx(speedData).epsilon(0.05));
    }
}

TEST_CASE("dish of examples/dish.toml settles flat and stays flat", "[sph][slow]") {
    SimScene scene = loadSimScene(example("dish.toml"), {"shot.duration=1.0"});
    FluidSimulation sim(scene);
    REQUIRE(sim.size() == 40960);
    const double s = sim.spacing();
    sim.advanceTo(1.0);
    // Top surface: the highest particle in each column cell of 3 spacings.
    std::map<std::pair<int, int>, double> top;
    for (const Vec3& p : sim.positions()) {
        const double r = std::hypot(p.x(), p.y());
        if (r > 0.05 - 4 * s) continue;  // the meniscus at the wall is physical
        auto key = std::make_pair(int(std::floor(p.x() / (3 * s))), int(std::floor(p.y() / (3 * s))));
        auto it = top.find(key);
        if (it == top.end() || p.z() > it->second) top[key] = p.z();
    }
    double mean = 0, var = 0;
    for (auto& [k, z] : top) mean += z;
    mean /= double(top.size());
    for (auto& [k, z] : top) var += (z - mean) * (z - mean);
    const double rms = std::sqrt(var / double(top.size()));
    double vmax = 0;
    for (const Vec3& v : sim.velocities()) vmax = std::max(vmax, double(v.norm()));
    CAPTURE(mean, rms, s, vmax);
    REQUIRE(rms < 0.25 * s);
    REQUIRE(mean + 0.5 * s == Approx(0.01).epsilon(0.1));
    REQUIRE(vmax < 0.02);
}

TEST_CASE("fluid poured into a thin-walled vessel mesh stays inside", "[sph][container][slow]") {
    SimScene scene = loadSimScene(example("vessel_pour.toml"));
    FluidSimulation sim(scene);
    const size_t n = sim.size();
    REQUIRE(n > 1000);
    sim.advanceTo(2.0);
    // The cup of examples/meshes/vessel.obj: cavity r < 30 mm above the 0.5 mm floor.
    size_t outside = 0;
    double zmax = 0;
    for (const Vec3& p : sim.positions()) {
        const double r = std::hypot(p.x(), p.y());
        if (!(r < 0.03 && p.z() > 0.0005)) ++outside;
        zmax = std::max(zmax, double(p.z()));
    }
    CAPTURE(zmax);
    REQUIRE(outside == 0);
    REQUIRE(zmax < 0.04);  // it all ended up in the cup, below the rim
}

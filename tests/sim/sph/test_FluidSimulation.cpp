// Physics checks of the SPH core: hydrostatics, volume conservation, momentum
// conservation, the Martin & Moyce dam break, a settling dish, a mesh vessel.
#include "sim/sph/FluidSimulation.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimSceneFile.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>

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

/// Hydrostatic checks on the tank of examples/hydrostatic.toml after settling: density
/// error, pressure against rho g (depth - z), residual motion. Averaged over 20 snapshots
/// in 0.1 s, which removes what sloshing remains. The bottom pressure is the value at the
/// floor of a straight-line fit p(z) through the interior: the one layer touching a wall
/// carries extra pressure in the Akinci boundary model (see kWallMirror in the solver).
void checkResting(FluidSimulation& sim, double depth) {
    const double rho0 = sim.restDensity();
    const double g = 9.81;
    const double s = sim.spacing();
    double err = 0, speed = 0;
    double sz = 0, sp = 0, szz = 0, szp = 0;
    long n = 0;
    const int snapshots = 20;
    for (int k = 0; k < snapshots; ++k) {
        sim.advanceTo(sim.time() + 0.005);
        double e = 0;
        for (size_t i = 0; i < sim.size(); ++i) {
            e += std::abs(sim.densities()[i] / rho0 - 1);
            speed += sim.velocities()[i].norm();
            const Vec3& x = sim.positions()[i];
            const double z = x.z();
            if (z < 1.5 * s || z > depth - 3 * s) continue;  // interior layers only
            if (x.x() < 2 * s || x.x() > 0.05 - 2 * s || x.y() < 2 * s || x.y() > 0.05 - 2 * s) continue;
            const double p = sim.pressures()[i];
            sz += z;
            sp += p;
            szz += z * z;
            szp += z * p;
            ++n;
        }
        err += e / double(sim.size());
    }
    err /= snapshots;
    speed /= double(snapshots) * double(sim.size());
    const double slope = (n * szp - sz * sp) / (n * szz - sz * sz);
    const double bottom = (sp - slope * sz) / n;
    CAPTURE(err, bottom, rho0 * g * depth, slope, -rho0 * g, speed);
    REQUIRE(n > 1000 * snapshots);
    // Mean |rho / rho0 - 1| over all particles, the free-surface layer included.
    REQUIRE(err < 0.01);
    REQUIRE(bottom == Approx(rho0 * g * depth).epsilon(0.05));
    // The symmetric SPH pressure gradient is not exactly first-order consistent on a
    // particle lattice: the balancing pressure gradient comes out a few percent steep.
    REQUIRE(slope == Approx(-rho0 * g).epsilon(0.10));
    REQUIRE(speed < 0.005);  // mean particle speed below 5 mm/s: settled
}

} // namespace

TEST_CASE("resting tank (DFSPH): density, bottom pressure, volume drift over 2 s", "[sph][slow]") {
    SimScene scene = loadSimScene(example("hydrostatic.toml"), {"shot.duration=3"});
    FluidSimulation sim(scene);
    // Fluid depth: particle volume times count over the floor area.
    const double depth = sim.size() * sim.particleMass() / sim.restDensity() / (0.05 * 0.05);
    REQUIRE(depth == Approx(0.05).epsilon(0.02));
    // The initial lattice compacts by about 2 % of its height in the first few tenths of a
    // second (the free-surface layer, short of neighbours, sinks until it reaches rest
    // density); the drift is measured from the settled tank on.
    sim.advanceTo(0.5);
    const double z0 = meanZ(sim);
    double worst = 0;
    for (int k = 1; k <= 4; ++k) {
        sim.advanceTo(0.5 + 0.5 * k);
        worst = std::max(worst, std::abs(meanZ(sim) / z0 - 1));
        if (k == 2) checkResting(sim, depth);
    }
    // Measured 2026-12-05: 0.033 % over 2 s (81 CPU s). It ran 3 s until then; the last second
    // was cut to buy back suite time.
    CAPTURE(worst);
    REQUIRE(worst < 0.01);
    checkResting(sim, depth);
}

TEST_CASE("resting tank (WCSPH): density and bottom pressure", "[sph][slow]") {
    SimScene scene = loadSimScene(example("hydrostatic.toml"), {"sim.solver=wcsph"});
    FluidSimulation sim(scene);
    const double depth = sim.size() * sim.particleMass() / sim.restDensity() / (0.05 * 0.05);
    sim.advanceTo(0.5);
    const double z0 = meanZ(sim);
    sim.advanceTo(1.5);
    checkResting(sim, depth);
    REQUIRE(std::abs(meanZ(sim) / z0 - 1) < 0.01);
}

TEST_CASE("free flight without walls or gravity conserves momentum", "[sph]") {
    for (const std::string kind : {"wcsph", "dfsph"}) {
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
        scene.solver.pressureSolver = kind;
        scene.solver.gravity = Vec3d::Zero();
        FluidSimulation sim(scene);
        const Vec3d p0 = momentum(sim);
        sim.advanceTo(0.05);
        const Vec3d p1 = momentum(sim);
        CAPTURE(kind, p0.transpose(), p1.transpose(), sim.stepCount());
        REQUIRE(sim.stepCount() > 20);
        REQUIRE((p1 - p0).norm() / p0.norm() < 1e-6);
        // The blob moved as a whole, at its initial velocity.
        Vec3d centre = Vec3d::Zero();
        for (const Vec3& x : sim.positions()) centre += x.cast<double>();
        centre /= double(sim.size());
        REQUIRE(centre.x() == Approx(0.006 + 0.3 * 0.05).epsilon(1e-3));
    }
}

TEST_CASE("WCSPH neighbours kept with a Verlet skin equal a brute-force search", "[sph]") {
    // A cube with surface tension, no walls or gravity, its lattice jittered and every
    // particle started in a random direction: pairs close in from every angle between
    // searches. Every density must equal the sum over all particles, found by testing every
    // pair: a pair the skin search missed shows up as a density short by one kernel weight.
    SimScene scene;
    scene.path = "skin";
    scene.fluid.restDensity = 1000;
    scene.fluid.viscosity = 1e-6;
    scene.fluid.surfaceTension = 0.07;
    scene.fluid.spacing = 0.001;
    FluidBlock block;
    block.min = Vec3d(0, 0, 0);
    block.max = Vec3d(0.012, 0.012, 0.012);
    scene.fluid.blocks.push_back(block);
    scene.container.type = ContainerParams::Type::None;
    scene.solver.pressureSolver = "wcsph";
    scene.solver.gravity = Vec3d::Zero();
    FluidSimulation sim(scene);
    std::vector<Vec3> x = sim.positionsById(), v(x.size());
    std::mt19937 rng(7);
    std::uniform_real_distribution<Real> unit(-1, 1);
    for (size_t i = 0; i < x.size(); ++i) {
        x[i] += Real(0.3 * 0.001) * Vec3(unit(rng), unit(rng), unit(rng));
        v[i] = Real(0.3) * Vec3(unit(rng), unit(rng), unit(rng));
    }
    sim.setState(0.0, x, v, {});
    const size_t searches0 = sim.lastStep().searches;
    const CubicSplineKernel kernel(Real(sim.supportRadius()));
    const double V = sim.particleMass() / sim.restDensity();
    double worst = 0;
    size_t checks = 0;
    for (int step = 0; step < 40; ++step) {
        sim.step(1.0);
        const std::vector<Vec3>& p = sim.positions();
        for (size_t i = 0; i < p.size(); ++i) {
            double sum = 0;
            for (size_t j = 0; j < p.size(); ++j) sum += kernel.W((p[i] - p[j]).norm());
            const double rho = sim.restDensity() * V * sum;
            worst = std::max(worst, std::abs(double(sim.densities()[i]) / rho - 1));
            ++checks;
        }
    }
    const size_t searches = sim.lastStep().searches - searches0;
    CAPTURE(worst, checks, searches, sim.stepCount());
    REQUIRE(searches >= 2);               // the particles did move through the skin ...
    REQUIRE(searches < sim.stepCount());  // ... and lists did outlive steps
    // A pair missed at q = 0.98 would leave 2e-6 (W(0.98 h) / sum W); float rounding of
    // the sums is ~3e-7.
    REQUIRE(worst < 1.5e-6);
}

TEST_CASE("the skin search keeps a pair that is two grid cells apart", "[sph]") {
    // The worst case for a skin search: A sits at the far edge of its grid cell and B,
    // 1.08 h away along x, two cells further; they close in on each other, A and B each
    // by 0.055 h, so no new search is due (2 x 0.055 h < skin 0.2 h) but the pair enters
    // the support. C, far off, only fixes where the grid starts.
    SimScene scene;
    scene.path = "skin-edge";
    scene.fluid.restDensity = 1000;
    scene.fluid.viscosity = 0;
    scene.fluid.spacing = 0.001;
    FluidBlock block;
    block.min = Vec3d(0, 0, 0);
    block.max = Vec3d(0.003, 0.001, 0.001);   // three particles
    scene.fluid.blocks.push_back(block);
    scene.container.type = ContainerParams::Type::None;
    scene.solver.pressureSolver = "wcsph";
    scene.solver.gravity = Vec3d::Zero();
    scene.solver.artificialViscosity = 0;
    FluidSimulation sim(scene);
    REQUIRE(sim.size() == 3);
    const Real h = Real(sim.supportRadius()), u = Real(0.05);
    sim.setState(0.0, {Vec3(0, 0, 0), Vec3(Real(1.08) * h, 0, 0), Vec3(Real(-0.995) * h, 5 * h, 0)},
                 {Vec3(u, 0, 0), Vec3(-u, 0, 0), Vec3(0, 0, 0)}, {});
    const size_t searches0 = sim.lastStep().searches;
    while (sim.time() < 0.0022) sim.step(0.0022 - sim.time());
    REQUIRE(sim.lastStep().searches == searches0);
    const std::vector<Vec3> x = sim.positionsById();
    const double r = (x[0] - x[1]).norm();
    REQUIRE(r < 0.99 * h);
    const CubicSplineKernel kernel(h);
    const double V = sim.particleMass() / sim.restDensity();
    const double expected = sim.restDensity() * V * (kernel.W0() + kernel.W(Real(r)));
    CAPTURE(r / h, expected);
    REQUIRE(sim.densitiesById()[0] == Approx(expected).epsilon(1e-6));
    REQUIRE(sim.densitiesById()[1] == Approx(expected).epsilon(1e-6));
}

TEST_CASE("dam break surge front follows Martin & Moyce (1952)", "[sph][slow]") {
    // Martin & Moyce 1952, 2:1 column (n^2 = 2), a = 2.25 in: dimensionless surge front
    // Z = x / a against T = t sqrt(2 g / a), their Table 2, up to T = 2.5.
    //
    // Instantaneous-release solvers (VOF, MPS, SPH alike) are known to run ahead of this
    // data from the second point on while their front speed agrees; the usual explanation
    // is that the release took a finite time, which offsets the experiment's clock.
    // Ferro's raw lead is 0.16-0.30 in Z over T = 0.84-2.5 (at a/20 and a/30 alike): a
    // constant lead, not a growing one, i.e. an offset in time. So the test fits one release delay T0 (the
    // experiment's T = T0 is the simulation's T = 0), requires it to be a delay of at most
    // 0.3 (16 ms), and then every data point within 10 %. A wrong front speed or a wrong
    // collapse shape cannot be hidden by one shift; the front speed is checked on its own.
    const std::vector<std::pair<double, double>> data = {
        {0.41, 1.11}, {0.84, 1.22}, {1.19, 1.44}, {1.43, 1.67}, {1.63, 1.89},
        {1.83, 2.11}, {1.98, 2.33}, {2.20, 2.56}, {2.32, 2.78}, {2.51, 3.00}};
    const double a = 0.05715, g = 9.81;
    const double tScale = std::sqrt(a / (2 * g));
    constexpr double kSample = 0.02;   // dimensionless sampling interval of the simulated front
    for (const char* solver : {"dfsph", "wcsph"}) {
        SimScene scene = loadSimScene(example("dam_break.toml"), {std::string("sim.solver=") + solver});
        FluidSimulation sim(scene);
        // Front Z(T) of the simulation every kSample up to the last data point.
        std::vector<double> front;
        for (int k = 0; k * kSample <= data.back().first + 1e-9; ++k) {
            if (k > 0) sim.advanceTo(k * kSample * tScale);
            double x = 0;
            for (const Vec3& p : sim.positions()) x = std::max(x, double(p.x()));
            // The fluid ends half a spacing beyond the last particle centre.
            front.push_back((x + 0.5 * sim.spacing()) / a);
        }
        auto Zsim = [&](double T) {
            if (T <= 0) return front.front();
            const double u = T / kSample;
            const size_t k = std::min(size_t(u), front.size() - 2);
            return front[k] + (u - double(k)) * (front[k + 1] - front[k]);
        };
        auto worstError = [&](double T0) {
            double worst = 0;
            for (const auto& [T, Z] : data) worst = std::max(worst, std::abs(Zsim(T - T0) / Z - 1));
            return worst;
        };
        double bestT0 = 0, best = worstError(0);
        for (double T0 = 0.005; T0 <= 0.5; T0 += 0.005)
            if (worstError(T0) < best) best = worstError(T0), bestT0 = T0;
        CAPTURE(solver, worstError(0), bestT0, best);
        for (const auto& [T, Z] : data) {
            CAPTURE(T, Z, Zsim(T), Zsim(T - bestT0));
            CHECK(std::abs(Zsim(T - bestT0) / Z - 1) < 0.10);
        }
        CHECK(bestT0 <= 0.3);
        // Front speed over T = 1.43 .. 2.51 (data points 3 and 9), which no delay shifts.
        const double speedData = (data[9].second - data[3].second) / (data[9].first - data[3].first);
        const double speedSim = (Zsim(data[9].first) - Zsim(data[3].first)) / (data[9].first - data[3].first);
        CAPTURE(speedData, speedSim);
        CHECK(speedSim == Approx(speedData).epsilon(0.10));
    }
}

TEST_CASE("dish of examples/dish.toml settles flat and stays flat", "[sph][slow]") {
    SimScene scene = loadSimScene(example("dish.toml"));
    FluidSimulation sim(scene);
    REQUIRE(sim.size() == 40960);
    const double s = sim.spacing();
    const double volume = sim.size() * sim.particleMass() / sim.restDensity();
    const double level = volume / (kPi * 0.05 * 0.05);
    // Surface height per column of 8 x 8 spacings, from the fluid volume in the column
    // (particle count times particle volume over the column area): it sees waves and
    // heaps, not the jitter of single surface particles. Columns within 8 spacings of the
    // wall (the meniscus) are left out.
    const double cell = 8 * s;
    int columns = 0;
    auto surfaceRms = [&](double& mean) {
        std::map<std::pair<int, int>, int> count;
        for (const Vec3& p : sim.positions())
            ++count[std::make_pair(int(std::floor(p.x() / cell)), int(std::floor(p.y() / cell)))];
        double sum = 0, sum2 = 0;
        int n = 0;
        for (const auto& [key, c] : count) {
            const double cx = (key.first + 0.5) * cell, cy = (key.second + 0.5) * cell;
            if (std::hypot(cx, cy) + 0.75 * cell > 0.05 - 8 * s) continue;
            const double height = c * volume / double(sim.size()) / (cell * cell);
            sum += height;
            sum2 += height * height;
            ++n;
        }
        mean = sum / n;
        columns = n;
        return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
    };
    // Settled by 0.75 s and still so a quarter second later (measured 2026-12-05: surface RMS
    // 0.083 and 0.086 spacing, mean speed 1.09 and 0.61 mm/s, level within 0.44 %; 132 CPU s).
    // It was checked at 1 and 2 s, then at 0.75 and 1.5 s (0.11 spacing, 0.46 mm/s at 1.5 s);
    // 1 s since 2026-12-05 to buy back suite time: the 40,960 particles' last half second
    // cost a minute of CPU.
    for (double t : {0.75, 1.0}) {
        sim.advanceTo(t);
        double mean = 0;
        const double rms = surfaceRms(mean);
        double speed = 0;
        for (const Vec3& v : sim.velocities()) speed += v.norm();
        speed /= double(sim.size());
        CAPTURE(t, level, mean, rms, s, speed);
        REQUIRE(rms < 0.25 * s);                       // flat to a quarter spacing
        REQUIRE(mean == Approx(level).epsilon(0.02));  // no volume lost or gained
        REQUIRE(speed < 0.01);                         // mean speed under 1 cm/s
    }
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

TEST_CASE("an unknown sim.solver names the key's line and the registered solvers", "[sph]") {
    const SceneDocument doc = SceneDocument::parse(
        "[fluid]\nspacing = 0.01\n[[fluid.block]]\nmin = [0, 0, 0]\nmax = [0.02, 0.02, 0.02]\n"
        "[sim]\nsolver = \"pcisph\"\n",
        "t.toml");
    const SimScene scene = parseSimScene(doc);
    try {
        FluidSimulation sim(scene);
        FAIL("an unknown solver was accepted");
    } catch (const SceneError& e) {
        CHECK(std::string(e.what()) == "t.toml:7: sim.solver: must be one of \"wcsph\", \"dfsph\" (got \"pcisph\")");
    }
    for (const std::string& name : pressureSolverNames())
        CHECK(std::string(findPressureSolver(name).name) == name);
}

TEST_CASE("a pressure solver's own [sim] keys: its registry row reads them, and refuses bad and unknown ones "
          "with their line", "[sph]") {
    auto error = [](const std::string& simKeys, const std::vector<std::string>& overrides = {}) {
        const SceneDocument doc = SceneDocument::parse(
            "[fluid]\nspacing = 0.01\n[[fluid.block]]\nmin = [0, 0, 0]\nmax = [0.02, 0.02, 0.02]\n[sim]\n" + simKeys,
            "t.toml", overrides);
        const SimScene scene = parseSimScene(doc);
        try {
            parsePressureSolverKeys(scene.solver, scene.path);
        } catch (const SceneError& e) {
            return std::string(e.what());
        }
        return std::string("(no error)");
    };
    // The first unknown key in file order, not the first alphabetically.
    CHECK(error("zeta = 1\nalpha = 2\n") == "t.toml:7: sim.zeta: unknown key");
    CHECK(error("", {"sim.bogus=1"}) == "--set sim.bogus:1: sim.bogus: unknown key");
    CHECK(error("max_iterations = 10.5\n") == "t.toml:7: sim.max_iterations: expected an integer (got float)");
    CHECK_THAT(error("max_iterations = 0\n"), Catch::Contains("t.toml:7: sim.max_iterations: must be in [1,"));
    CHECK_THAT(error("sound_speed = -1\n"), Catch::Contains("t.toml:7: sim.sound_speed: must be >= 0"));
    // One solver's keys stay valid while another is chosen (a --set sim.solver on a tuned scene).
    CHECK(error("max_density_error = 1e-4\nsound_speed = 20\n", {"sim.solver=\"wcsph\""}) == "(no error)");
    // What the chosen solver reads reaches it.
    const SceneDocument doc = SceneDocument::parse(
        "[fluid]\nspacing = 0.01\n[[fluid.block]]\nmin = [0, 0, 0]\nmax = [0.02, 0.02, 0.02]\n[sim]\nsolver = \"wcsph\"\n"
        "sound_speed = 20\nmax_density_error = 1e-4\n",
        "t.toml");
    const FluidSimulation wcsph(parseSimScene(doc));
    REQUIRE(wcsph.pressureSolverSettings() == std::vector<std::pair<std::string, double>>{{"c", 20.0}});
    const FluidSimulation dfsph(parseSimScene(SceneDocument::parse(
        "[fluid]\nspacing = 0.01\n[[fluid.block]]\nmin = [0, 0, 0]\nmax = [0.02, 0.02, 0.02]\n[sim]\n"
        "max_density_error = 1e-4\nmax_iterations = 30\n",
        "t.toml")));
    REQUIRE(dfsph.pressureSolverSettings() ==
            std::vector<std::pair<std::string, double>>{{"density_tol", 1e-4}, {"divergence_tol", 0.001}, {"max_iterations", 30}});
}

TEST_CASE("periodic sides: a layer slides across the glued faces without seam, at rest density, "
          "keeping its momentum", "[sph][periodic]") {
    // A 4 mm layer fills a 12 x 10 mm box whose x and y faces are glued, over a free-slip
    // floor, moving at (0.3, -0.2) m/s: in 0.1 s it crosses the box 2.5 times in x and twice
    // in y. An infinite layer in uniform motion is a steady state: the floor and the pair
    // forces exert no net horizontal force, so the momentum stays (to the floor lattice's
    // ripple), every particle stays at rest density, and the particles that just crossed a
    // face are packed as the rest (a seam would show as a density step there).
    for (const std::string kind : {"dfsph", "wcsph"}) {
        SimScene scene;
        scene.path = "periodic-layer";
        scene.fluid.restDensity = 1000;
        scene.fluid.viscosity = 1e-4;
        scene.fluid.surfaceTension = 0.03;
        scene.fluid.spacing = 0.001;
        FluidBlock block;
        block.min = Vec3d(0, 0, 0);
        block.max = Vec3d(0.012, 0.010, 0.004);
        block.velocity = Vec3d(0.3, -0.2, 0);
        scene.fluid.blocks.push_back(block);
        scene.container.type = ContainerParams::Type::Box;
        scene.container.min = Vec3d(0, 0, 0);
        scene.container.max = Vec3d(0.012, 0.010, 0.015);
        scene.container.periodicSides = true;
        scene.solver.pressureSolver = kind;
        FluidSimulation sim(scene);
        REQUIRE(sim.size() == 12 * 10 * 4);
        const Vec3d p0 = momentum(sim);
        sim.advanceTo(0.1);
        const Vec3d p1 = momentum(sim);
        const double s = sim.spacing(), rho0 = sim.restDensity();
        double err = 0, face = 0, inner = 0, top = 0;
        int nFace = 0, nInner = 0;
        for (size_t i = 0; i < sim.size(); ++i) {
            const Vec3& x = sim.positions()[i];
            const double r = sim.densities()[i] / rho0;
            top = std::max(top, double(x.z()));
            // Inside the box (wrapped at each search; up to half the skin past a face between).
            REQUIRE(x.x() > -0.5 * s);
            REQUIRE(x.x() < 0.012 + 0.5 * s);
            REQUIRE(x.y() > -0.5 * s);
            REQUIRE(x.y() < 0.010 + 0.5 * s);
            if (x.z() > 2.5 * s) continue; // the two lower layers: no free surface
            err = std::max(err, std::abs(r - 1));
            const bool nearFace = x.x() < s || x.x() > 0.012 - s || x.y() < s || x.y() > 0.010 - s;
            (nearFace ? face : inner) += r;
            ++(nearFace ? nFace : nInner);
        }
        face /= nFace;
        inner /= nInner;
        CAPTURE(kind, p0.transpose(), p1.transpose(), err, face, inner, top, nFace, nInner, sim.stepCount());
        REQUIRE(nFace > 100);
        REQUIRE(nInner > 40);
        REQUIRE(std::abs(p1.x() / p0.x() - 1) < 0.01);
        REQUIRE(std::abs(p1.y() / p0.y() - 1) < 0.01);
        // Below the free surface every particle is within 1 % of rest density (a pair that
        // missed its image across a face was 10 % over, and the face rows 0.8 % on average).
        REQUIRE(err < 0.01);
        REQUIRE(std::abs(face - inner) < 0.002);
        // Flat: no particle rose a spacing above the layer's 4 mm (a side wall's meniscus
        // or a seam's splash would).
        REQUIRE(top < 0.004);
    }
}

TEST_CASE("periodic sides refuse a box too narrow for the search, a block past the glued faces and a field that does not repeat", "[sph][periodic]") {
    SimScene scene;
    scene.path = "periodic-bad";
    scene.fluid.restDensity = 1000;
    scene.fluid.spacing = 0.001;
    FluidBlock block;
    block.min = Vec3d(0, 0, 0);
    block.max = Vec3d(0.012, 0.012, 0.003);
    scene.fluid.blocks.push_back(block);
    scene.container.type = ContainerParams::Type::Box;
    scene.container.min = Vec3d(0, 0, 0);
    scene.container.max = Vec3d(0.012, 0.012, 0.01);
    scene.container.periodicSides = true;
    // The reference scene runs: 12 spacings are enough.
    REQUIRE_NOTHROW(FluidSimulation(scene));
    // The floor is the only wall: 12 x 12 lattice points, none on the glued faces twice.
    REQUIRE(FluidSimulation(scene).boundaryPositions().size() == 144);
    SimScene narrow = scene;
    narrow.container.max.x() = 0.006;
    narrow.fluid.blocks[0].max.x() = 0.006;
    REQUIRE_THROWS_WITH(FluidSimulation(narrow), Catch::Contains("container.periodic_sides: the box must be wider"));
    SimScene past = scene;
    past.fluid.blocks[0].max.y() = 0.015;
    REQUIRE_THROWS_WITH(FluidSimulation(past), Catch::Contains("fluid outside the box in y"));
    // A uniform field repeats with the box; a dipole's does not.
    SimScene field = scene;
    MagnetTrack uniform;
    uniform.base.kind = MagnetKind::Uniform;
    uniform.base.strength = 1000;
    field.magnets.push_back(uniform);
    REQUIRE_NOTHROW(FluidSimulation(field));
    MagnetTrack dipole;
    dipole.base.kind = MagnetKind::Dipole;
    dipole.base.position = Vec3d(0.006, 0.006, -0.01);
    dipole.base.strength = 0.1;
    field.magnets.push_back(dipole);
    REQUIRE_THROWS_WITH(FluidSimulation(field),
                        "periodic-bad: container.periodic_sides: magnets[1] is a dipole; periodic sides take uniform "
                        "fields only (a source's field does not repeat with the box)");
}

// sim.pressure_iteration = "auto" (issue 52): in a column 50 particles deep (the hydrostatic
// tank narrowed to 10 x 10 mm, 2 mm spacing, 1,250 particles) relaxed Jacobi's sweeps, which
// grow with the square of the depth, stop at the cap of 100 in most steps; auto hands those
// steps over to conjugate gradients and meets the tolerance. Reference: the solve's own
// tolerance (sim.max_density_error) and Jacobi's caps on the same column. Measured 2026-12-07,
// from 0.3 to 0.6 s: Jacobi at its cap in 202 of 301 steps (up to 0.073 % left against
// 0.02 %), 75 sweeps a step; auto in none, 39 a step, CG in 100 of the steps. ~10 s.
TEST_CASE("a deep column: the auto density iteration meets the tolerance where Jacobi stops at its cap", "[sph][slow]") {
    struct Run {
        size_t steps = 0, atCap = 0, cgSteps = 0, iterations = 0;
        double worst = 0, tolerance = 0;
    };
    auto run = [](const std::string& iteration) {
        FluidSimulation sim(loadSimScene(example("hydrostatic.toml"),
                                         {"fluid.block.0.max=[0.01, 0.01, 0.1]", "container.max=[0.01, 0.01, 0.15]",
                                          "fluid.spacing=0.002", "sim.pressure_iteration=\"" + iteration + "\""}));
        REQUIRE(sim.size() == 1250);
        Run r;
        for (const auto& [name, value] : sim.pressureSolverSettings())
            if (name == "density_tol") r.tolerance = value;   // sim.max_density_error, the solver's default
        for (int frame = 1; frame <= 6; ++frame) {
            sim.advanceTo(0.1 * frame);
            if (frame <= 3) continue;   // the column settles from its seed lattice first
            const SolverCapCount& c = sim.frameSolverCaps();
            r.steps += c.steps;
            r.atCap += c.densityAtCap;
            r.cgSteps += c.densityByCg;
            r.iterations += c.pressureIterations;
            r.worst = std::max(r.worst, c.densityError);
        }
        for (const Vec3& x : sim.positions()) REQUIRE(x.allFinite());
        return r;
    };
    const Run jacobi = run("jacobi"), autoRun = run("auto");
    const double tolerance = autoRun.tolerance;
    REQUIRE(tolerance > 0);
    CAPTURE(jacobi.steps, jacobi.atCap, jacobi.iterations, jacobi.worst, autoRun.steps, autoRun.atCap, autoRun.cgSteps,
            autoRun.iterations, autoRun.worst);
    REQUIRE(jacobi.cgSteps == 0);
    REQUIRE(jacobi.atCap > jacobi.steps / 2);           // the contrast: Jacobi is at its cap here
    REQUIRE(autoRun.cgSteps > autoRun.steps / 10);      // auto handed steps over
    REQUIRE(autoRun.atCap <= autoRun.steps / 50);       // and met the tolerance in nearly all
    REQUIRE(autoRun.worst < 1.25 * tolerance);          // what a capped step left stays near it
    REQUIRE(autoRun.iterations < jacobi.iterations);    // with fewer iterations in all
}

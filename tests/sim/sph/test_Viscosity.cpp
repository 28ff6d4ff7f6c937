// Viscosity: the implicit solve (Weiler et al. 2018) against the analytic decay of a
// shear mode between free-slip walls, the explicit update's stable step, and a resting tank at viscosities
// from water's to 1 m^2/s with both pressure solvers.
#include "sim/sph/FluidSimulation.hpp"
#include "sim/sph/ImplicitViscosity.hpp"
#include "sim/sph/forces/StandardViscosity.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimSceneFile.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

using namespace ferro;

namespace {

std::string example(const std::string& name) { return std::string(FERRO_SOURCE_DIR) + "/examples/" + name; }

constexpr double kPiD = 3.14159265358979323846;

/// A closed box [0, 4L] x [0, W] x [0, L] filled with fluid, no gravity, free-slip walls
/// (wall_friction 0), no artificial viscosity.
SimScene shearBox(double spacing, int cells, int width, double nu, const std::string& solver,
                  FluidParams::ViscosityMethod method) {
    const double L = cells * spacing, W = width * spacing;
    SimScene scene;
    scene.path = "shear-mode";
    scene.fluid.restDensity = 1000;
    scene.fluid.viscosity = nu;
    scene.fluid.viscosityMethod = method;
    scene.fluid.spacing = spacing;
    FluidBlock block;
    block.min = Vec3d(0, 0, 0);
    block.max = Vec3d(4 * L, W, L);
    scene.fluid.blocks.push_back(block);
    scene.container.type = ContainerParams::Type::Box;
    scene.container.min = Vec3d(0, 0, 0);
    scene.container.max = Vec3d(4 * L, W, L);
    scene.container.closedTop = true;
    scene.container.wallFriction = 0;
    scene.solver.pressureSolver = solver;
    scene.solver.gravity = Vec3d::Zero();
    scene.solver.artificialViscosity = 0;
    scene.solver.viscosityTolerance = 1e-5;
    if (solver == "wcsph") scene.solver.solverKeys = solverKeysFromText("sound_speed = 10");   // incompressible on the viscous time scale
    scene.solver.minDt = 1e-9;
    return scene;
}

struct DecayMeasurement {
    double rate = 0;        ///< fitted decay rate of the mode's amplitude [1/s]
    double analytic = 0;    ///< nu k^2 [1/s]
    double discrete = 0;    ///< the SPH operator's rate on the mode, -u.a(u) / u.u [1/s]
    double expected = 0;    ///< the discrete rate after the time discretization [1/s]
    double dt = 0;          ///< the step [s]
    size_t steps = 0;
    double wallSeconds = 0;
    int viscosityIterations = 0;  ///< of the last step
};

/// The shear mode v_x = A cos(k z), k = pi / L, between the floor and the lid (free slip:
/// dv_x/dz = 0 there) decays as exp(-nu k^2 t): a divergence-free Stokes eigenmode. Walls
/// at the ends x = 0, 4L stop the flow there; the recirculation they force decays as
/// exp(-pi |x - end| / L), so the amplitude is measured in the middle, x in [1.5 L, 2.5 L]
/// (end effect below 1 %). On the particle lattice the mode is also an eigenvector of the
/// SPH operator (a_y = a_z = 0 and a_x proportional to cos k z by the lattice's symmetry),
/// with the discrete rate `discrete`; `expected` adds the time stepping: backward Euler
/// decays by 1 / (1 + dt lambda) per step, a rate ln(1 + dt lambda) / dt.
DecayMeasurement measureShearDecay(double nu, const std::string& solver, FluidParams::ViscosityMethod method,
                                   double stepFraction) {
    const double s = 0.002;
    const int cells = 16, width = 6;
    const double L = cells * s;
    SimScene scene = shearBox(s, cells, width, nu, solver, method);
    const double k = kPiD / L;
    DecayMeasurement m;
    m.analytic = nu * k * k;
    const double tau = 1 / m.analytic;
    scene.solver.maxDt = std::min(scene.solver.maxDt, stepFraction * tau);
    scene.shot.fps = 1 / tau;
    FluidSimulation sim(scene);
    const double A0 = 0.01;   // m/s: particles move 0.03 spacings per e-folding time at nu = 1e-3
    std::vector<Vec3> v = sim.positionsById();
    for (Vec3& x : v) x = Vec3(Real(A0 * std::cos(k * x.z())), 0, 0);
    sim.setState(0, sim.positionsById(), v, {});
    auto middle = [&](const Vec3& x) { return x.x() >= 1.5 * L && x.x() <= 2.5 * L; };
    {
        ImplicitViscosity op;
        op.setUp(sim.viscosityOperator(), 0);
        std::vector<Vec3> a;
        op.acceleration(sim.velocities(), a);
        double ua = 0, uu = 0;
        for (size_t i = 0; i < sim.size(); ++i) {
            if (!middle(sim.positions()[i])) continue;
            ua -= double(a[i].dot(sim.velocities()[i]));
            uu += double(sim.velocities()[i].squaredNorm());
        }
        m.discrete = ua / uu;
    }
    auto amplitude = [&] {
        double vu = 0, uu = 0;
        for (size_t i = 0; i < sim.size(); ++i) {
            const Vec3& x = sim.positions()[i];
            if (!middle(x)) continue;
            const double u = std::cos(k * x.z());
            vu += sim.velocities()[i].x() * u;
            uu += u * u;
        }
        return vu / uu;
    };
    const auto start = std::chrono::steady_clock::now();
    double st = 0, sy = 0, stt = 0, sty = 0;
    const int samples = 10;
    for (int q = 1; q <= samples; ++q) {
        sim.advanceTo(q * tau / samples);
        m.dt = std::max(m.dt, sim.lastStep().dt);
        const double t = sim.time(), y = std::log(amplitude() / A0);
        st += t;
        sy += y;
        stt += t * t;
        sty += t * y;
    }
    m.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    m.rate = -(samples * sty - st * sy) / (samples * stt - st * st);
    m.expected = sim.implicitViscosity() ? std::log1p(m.dt * m.discrete) / m.dt : m.discrete;
    m.steps = sim.stepCount();
    m.viscosityIterations = sim.lastStep().viscosityIterations;
    return m;
}

} // namespace

TEST_CASE("a shear mode between free-slip walls decays at the SPH operator's rate, 0.67 nu k^2 on the lattice",
          "[sph][viscosity][slow]") {
    using Method = FluidParams::ViscosityMethod;
    struct Case {
        double nu;
        const char* solver;
        Method method;
        double stepFraction;   // largest step as a fraction of the e-folding time 1 / (nu k^2)
    };
    const Case cases[] = {
        {1e-3, "dfsph", Method::Implicit, 0.02}, {1e-2, "dfsph", Method::Implicit, 0.02},
        {1e-1, "dfsph", Method::Implicit, 0.02}, {1e-1, "dfsph", Method::Implicit, 0.2},
        {1e-2, "wcsph", Method::Implicit, 0.02}, {1e-2, "dfsph", Method::Explicit, 0.02},
    };
    for (const Case& c : cases) {
        const DecayMeasurement m = measureShearDecay(c.nu, c.solver, c.method, c.stepFraction);
        const char* method = c.method == Method::Implicit ? "implicit" : "explicit";
        char line[260];
        std::snprintf(line, sizeof line,
                      "nu %.0e %s %s dt %.2g s: rate %.4g 1/s = %.3f nu k^2 (operator %.3f, expected %.3f), "
                      "%zu steps, %d visc it, %.2f s",
                      c.nu, c.solver, method, m.dt, m.rate, m.rate / m.analytic, m.discrete / m.analytic,
                      m.expected / m.analytic, m.steps, m.viscosityIterations, m.wallSeconds);
        WARN(line);
        CAPTURE(c.nu, c.solver, method, m.rate, m.analytic, m.discrete, m.expected, m.steps);
        REQUIRE(std::isfinite(m.rate));
        // The SPH viscosity (Weiler 2018 eq. 8, Monaghan's 2 (d + 2) form) reproduces
        // nu k^2 only where the kernel's second moments are those of the continuum. On a
        // cubic lattice at support h = 2 spacings the moment sum V |F| x^2 z^2 / r^2 that
        // this mode feels is 0.698 of its integral (0.674 at this k, measured here); the
        // lattice stays near that for the short time measured. The bound contains 0.698.
        REQUIRE(m.discrete / m.analytic == Approx(0.674).margin(0.03));
        // The measured decay follows the operator (and backward Euler's ln(1 + x) / x): the
        // bound contains 1 (measured 1.00-1.07, both solvers, implicit and explicit;
        // docs/physics/sph-solver.md, "Tested accuracy").
        REQUIRE(m.rate / m.expected == Approx(1.05).margin(0.08));
    }
}

TEST_CASE("the implicit solve satisfies (I + dt L) v = v* and tends to the explicit update for a small step",
          "[sph][viscosity]") {
    SimScene scene = loadSimScene(example("hydrostatic.toml"), {"fluid.viscosity=0.01", "sim.artificial_viscosity=0",
                                                                  "container.wall_friction=0.5"});
    FluidSimulation sim(scene);
    sim.advanceTo(0.01);   // a disordered state with neighbours and densities current
    const ViscosityOperatorInput op = sim.viscosityOperator();
    std::vector<Vec3> vStar = sim.velocities();
    for (size_t i = 0; i < vStar.size(); ++i)   // a rough field, rich in short waves
        vStar[i] += Vec3(Real(0.01 * std::sin(1e3 * op.positions->at(i).z())), Real(0.01 * ((i * 7919) % 13) / 13.0), 0);
    for (const double dt : {1e-6, 1e-3}) {
        ImplicitViscositySettings settings;
        settings.tolerance = 1e-6;
        settings.maxIterations = 500;
        ImplicitViscosity solver(settings);
        solver.setUp(op, dt);
        std::vector<Vec3> v = vStar;
        const ImplicitViscosityResult r = solver.solve(v);
        CAPTURE(dt, r.iterations, r.relativeResidual);
        REQUIRE(r.converged);
        // Residual recomputed from the operator: v - dt a(v) = v*.
        std::vector<Vec3> a;
        solver.acceleration(v, a);
        double res = 0, ref = 0;
        for (size_t i = 0; i < v.size(); ++i) {
            res += (v[i] - Real(dt) * a[i] - vStar[i]).cast<double>().squaredNorm();
            ref += vStar[i].cast<double>().squaredNorm();
        }
        CHECK(std::sqrt(res / ref) < 1e-5);
        if (dt == 1e-6) {
            // Backward and forward Euler agree to O(dt^2) for a step far below the limit.
            solver.acceleration(vStar, a);
            double diff = 0, change = 0;
            for (size_t i = 0; i < v.size(); ++i) {
                diff += (v[i] - (vStar[i] + Real(dt) * a[i])).cast<double>().squaredNorm();
                change += (Real(dt) * a[i]).cast<double>().squaredNorm();
            }
            CHECK(std::sqrt(diff / change) < 0.05);
        }
    }
}

TEST_CASE("the explicit viscous step limit lies below 2 / lambda_max of the viscous operator", "[sph][viscosity]") {
    // Power iteration on the operator of the resting tank (free surface, walls with
    // friction 1) gives its fastest rate; forward Euler is stable for dt < 2 / lambda_max.
    for (const char* friction : {"0", "1"}) {
        SimScene scene = loadSimScene(example("hydrostatic.toml"),
                                      {"fluid.viscosity=0.01", "sim.artificial_viscosity=0",
                                       std::string("container.wall_friction=") + friction});
        FluidSimulation sim(scene);
        sim.advanceTo(0.02);
        ImplicitViscosity op;
        op.setUp(sim.viscosityOperator(), 0);
        const double lambda = op.largestRate(200);
        const double h = sim.supportRadius(), nu = sim.viscosity();
        const double stableCoefficient = 2 / (lambda * h * h / nu);   // dt < C h^2 / nu
        char line[160];
        std::snprintf(line, sizeof line,
                      "wall friction %s: lambda_max = %.2f nu / h^2, stable explicit step < %.4f h^2 / nu", friction,
                      lambda * h * h / nu, stableCoefficient);
        WARN(line);
        CHECK(0.125 > stableCoefficient);   // the former limit was not stable
        REQUIRE(StandardViscosity::kExplicitStep < 0.8 * stableCoefficient);
    }
}

namespace {

struct TankRun {
    double maxSpeed = 0;      ///< largest particle speed over the frames [m/s]
    double heightChange = 0;  ///< largest |mean z / initial mean z - 1| over the frames
    bool finite = true, inside = true, implicit = false;
    size_t steps = 0;
    double wallSeconds = 0;
    int viscosityIterations = 0;   ///< most in one step
};

TankRun runTank(double nu, const std::string& solver, const std::string& method, int frames) {
    char nuText[32];
    std::snprintf(nuText, sizeof nuText, "%g", nu);
    SimScene scene = loadSimScene(example("hydrostatic.toml"), {std::string("fluid.viscosity=") + nuText,
                                                                  "sim.solver=" + solver,
                                                                  "fluid.viscosity_method=" + method});
    FluidSimulation sim(scene);
    TankRun run;
    run.implicit = sim.implicitViscosity();
    auto meanZ = [&] {
        double s = 0;
        for (const Vec3& x : sim.positions()) s += x.z();
        return s / double(sim.size());
    };
    const double z0 = meanZ();
    const Vec3d lo = scene.container.min, hi = scene.container.max;
    const auto start = std::chrono::steady_clock::now();
    for (int f = 1; f <= frames; ++f) {
        try {
            const double t1 = f / scene.shot.fps;
            while (sim.time() < t1) {
                sim.step(t1 - sim.time());
                run.viscosityIterations = std::max(run.viscosityIterations, sim.lastStep().viscosityIterations);
                if (t1 - sim.time() < 1e-12) break;
            }
        } catch (const SimulationError&) {
            run.finite = false;
            break;
        }
        for (size_t i = 0; i < sim.size(); ++i) {
            const Vec3& x = sim.positions()[i];
            const Vec3& v = sim.velocities()[i];
            if (!x.allFinite() || !v.allFinite()) run.finite = false;
            for (int a = 0; a < 3; ++a)
                if (!(x[a] >= lo[a] - 1e-6 && x[a] <= hi[a] + 1e-6)) run.inside = false;
            run.maxSpeed = std::max(run.maxSpeed, double(v.norm()));
        }
        run.heightChange = std::max(run.heightChange, std::abs(meanZ() / z0 - 1));
    }
    run.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    run.steps = sim.stepCount();
    return run;
}

/// The tank of examples/hydrostatic.toml (8,000 particles, started on a lattice) for two
/// frames (as in issue 15: 9.9 m/s at nu = 1e-2 before, 80 m/s at 1e-1) at water's viscosity
/// and at each of `cases` (nu, viscosity_method). Water's run is the yardstick: from the
/// lattice the free-surface layer sinks until it reaches rest density (the mean height
/// drops 1-2 %, single particles reach 0.2 m/s); viscosity may only calm that.
void checkTank(const std::string& solver, const std::vector<std::pair<double, std::string>>& cases) {
    const int frames = 2;
    const TankRun water = runTank(1e-6, solver, "auto", frames);
    auto report = [&](double nu, const TankRun& run) {
        char line[240];
        std::snprintf(line, sizeof line,
                      "%s nu %.0e (%s): max speed %.1f mm/s, mean height change %.2f %%, %zu steps, max %d visc it, "
                      "%.1f s wall",
                      solver.c_str(), nu, run.implicit ? "implicit" : "explicit", 1e3 * run.maxSpeed,
                      100 * run.heightChange, run.steps, run.viscosityIterations, run.wallSeconds);
        WARN(line);
    };
    report(1e-6, water);
    REQUIRE(water.finite);
    REQUIRE(water.inside);
    for (const auto& [nu, method] : cases) {
        const TankRun run = runTank(nu, solver, method, frames);
        report(nu, run);
        CAPTURE(solver, nu, method, run.maxSpeed, water.maxSpeed, run.heightChange, water.heightChange, run.steps);
        REQUIRE(run.finite);
        REQUIRE(run.inside);   // so the count-based volume is exact
        REQUIRE(run.maxSpeed <= 1.1 * water.maxSpeed + 0.001);
        REQUIRE(run.heightChange <= water.heightChange + 0.001);
        REQUIRE(run.heightChange < 0.02);
    }
}

} // namespace

TEST_CASE("a resting tank stays at rest at nu = 1e-3 and 1e-2 m^2/s (DFSPH)", "[sph][viscosity][slow]") {
    checkTank("dfsph", {{1e-3, "auto"}, {1e-3, "explicit"}, {1e-2, "auto"}});
}

TEST_CASE("a resting tank stays at rest at nu = 0.1 and 1 m^2/s (DFSPH)", "[sph][viscosity][slow]") {
    checkTank("dfsph", {{1e-1, "auto"}, {1.0, "auto"}});
}

TEST_CASE("a resting tank stays at rest at nu = 1e-3 and 1e-2 m^2/s (WCSPH)", "[sph][viscosity][slow]") {
    checkTank("wcsph", {{1e-3, "auto"}, {1e-2, "auto"}, {1e-2, "explicit"}});
}

TEST_CASE("a resting tank stays at rest at nu = 0.1 and 1 m^2/s (WCSPH)", "[sph][viscosity][slow]") {
    checkTank("wcsph", {{1e-1, "auto"}, {1.0, "auto"}});
}

TEST_CASE("fluid.viscosity_method: auto keeps water explicit and takes implicit for thick fluids, bad values are refused",
          "[sph][viscosity]") {
    {
        FluidSimulation sim(loadSimScene(example("hydrostatic.toml"), {}));
        CHECK_FALSE(sim.implicitViscosity());
    }
    {
        FluidSimulation sim(loadSimScene(example("dish.toml"), {}));
        CHECK_FALSE(sim.implicitViscosity());
    }
    {
        FluidSimulation sim(loadSimScene(example("hydrostatic.toml"), {"fluid.viscosity=0.1"}));
        CHECK(sim.implicitViscosity());
    }
    {
        FluidSimulation sim(loadSimScene(example("hydrostatic.toml"), {"fluid.viscosity=0.1", "fluid.viscosity_method=explicit"}));
        CHECK_FALSE(sim.implicitViscosity());
    }
    {
        FluidSimulation sim(loadSimScene(example("hydrostatic.toml"), {"fluid.viscosity_method=implicit"}));
        CHECK(sim.implicitViscosity());
    }
    try {
        loadSimScene(example("hydrostatic.toml"), {"fluid.viscosity_method=fast"});
        FAIL("a bad viscosity_method was accepted");
    } catch (const SceneError& e) {
        const std::string what = e.what();
        CAPTURE(what);
        CHECK(what.find("fluid.viscosity_method") != std::string::npos);
        CHECK(what.find('\n') == std::string::npos);
    }
    try {
        loadSimScene(example("hydrostatic.toml"), {"sim.viscosity_tolerance=0"});
        FAIL("a zero viscosity_tolerance was accepted");
    } catch (const SceneError& e) {
        CHECK(std::string(e.what()).find("sim.viscosity_tolerance") != std::string::npos);
    }
}

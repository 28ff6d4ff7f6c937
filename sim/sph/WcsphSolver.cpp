// Weakly compressible SPH (Becker & Teschner 2007, the kind of solver the paper uses):
// pressure from the Tait equation of state, summed in the same four-pair sweep as
// viscosity, surface tension, gravity and the Kelvin force. Small steps (the speed of
// sound), cheap ones: the neighbour lists keep a Verlet skin and no gradients.
#include "sim/sph/PressureSolver.hpp"

#include "sim/core/ParticleLoops.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/sph/FluidSimulation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ferro {

namespace {

/// Verlet skin of the neighbour search, as a fraction of the kernel support: a WCSPH
/// step moves particles a few hundredths of a spacing, so a search lasts many steps.
constexpr double kNeighborSkin = 0.2;

/// WCSPH's own [sim] keys (parseWcsphKeys).
struct WcsphSettings final : PressureSolverSettings {
    /// sim.sound_speed [m/s]; 0 = ten times the scene's expected flow speed.
    double soundSpeed = 0.0;
};

class WcsphSolver final : public PressureSolver {
public:
    WcsphSolver(FluidSimulation& sim, const WcsphSettings& settings) : sim_(sim), settings_(settings) {}

    double neighborSkin() const override { return kNeighborSkin; }

    double maxTimeStep(double maxSpeed) const override {
        return sim_.scene().solver.cfl * sim_.spacing() / (soundSpeed() + maxSpeed);
    }

    std::string settingsSummary() const override {
        char text[64];
        std::snprintf(text, sizeof text, "sound speed %.3g m/s", soundSpeed());
        return text;
    }

    std::vector<std::pair<std::string, double>> settingValues() const override { return {{"c", soundSpeed()}}; }

    std::string advice() const override {
        // The default sound speed is 10x the flow speed vg of gravity's fall (or the scene's
        // other speeds). Under a strong magnet the pressure at rest also holds the magnetic
        // energy, p / rho0 = (vg^2 + vm^2) / 2 where the pull is strongest, and the Tait law
        // below compresses fluid there by (1 + 7 p / (rho0 c^2))^(1/7) - 1 (an estimate: the
        // heap pool at 0.77 mm measured 1.05 % on average). 10 hypot(vg, vm) brings that back
        // to the 0.5 % the default gives under gravity alone. Measured trade:
        // docs/physics/sph-solver.md, "WCSPH under a strong magnet".
        if (settings_.soundSpeed > 0) return {};
        const double c = soundSpeed(), vg = c / 10, vm = sim_.magneticFallSpeed();
        if (!(vm > vg)) return {};
        const double v = std::hypot(vg, vm);
        char text[400];
        std::snprintf(text, sizeof text,
                      "the magnets pull harder than the default sound speed allows for (a fall at %.2g m/s against %.2g): "
                      "fluid at rest under them may sit up to ~%.1f %% compressed and keep moving; sim.sound_speed = %.3g "
                      "holds it near 0.5 %% for about %.1fx the steps (this settled a 0.77 mm pool, not a 1.9 mm one), "
                      "or use sim.solver = \"dfsph\"",
                      vm, vg, 100 * (std::pow(1 + 7 * (vg * vg + vm * vm) / (2 * c * c), 1.0 / 7) - 1), 10 * v, v / vg);
        return text;
    }

    void advanceVelocities(double dt) override {
        const size_t n = sim_.size();
        const double rho0 = sim_.restDensity();
        const double c = soundSpeed();
        const std::vector<Real>& rho = sim_.densities();
        std::vector<Real>& p = pressure_;
        p.resize(n);
        // Tait equation of state, negative pressures clamped (no tensile instability at the
        // free surface).
        const double B = rho0 * c * c / 7;
        // p / rho^2 per particle: one division per particle instead of one per pair.
        pOverRho2_.resize(n);
        forEachParticle(n, [&](size_t i) {
            const double ratio = double(rho[i]) / rho0;
            const double r2 = ratio * ratio, r4 = r2 * r2;
            p[i] = Real(std::max(0.0, B * (r4 * r2 * ratio - 1)));
            pOverRho2_[i] = p[i] / (rho[i] * rho[i]);
        });
        // One sweep: pressure, viscosity, tension, gravity, Kelvin force.
        sim_.computeAccelerations(pOverRho2_.data());
        std::vector<Vec3>& v = sim_.solverVelocities();
        const std::vector<Vec3>& a = sim_.accelerations();
        forEachParticle(n, [&](size_t i) { v[i] += Real(dt) * a[i]; });
        // Implicit viscosity (when chosen) on the velocities after all other forces.
        sim_.applyImplicitViscosity(dt);
        sim_.stopMotionIntoMagnetBodies(dt);
        StepStats& stats = sim_.solverStats();
        stats.pressureIterations = 0;
        stats.divergenceIterations = 0;
        stats.densityError =
            deterministicSum(n, [&](size_t i) { return std::max(0.0, double(rho[i]) / rho0 - 1); }) /
            double(std::max<size_t>(n, 1));
    }

private:
    /// Ten times the fastest expected flow speed (FluidSimulation::expectedSpeed, at least
    /// 0.1 m/s) keeps the density error near 1 % (Monaghan), unless sim.sound_speed is set.
    double soundSpeed() const {
        return settings_.soundSpeed > 0 ? settings_.soundSpeed : 10 * std::max(sim_.expectedSpeed(), 0.1);
    }

    FluidSimulation& sim_;
    const WcsphSettings settings_;
    std::vector<Real> pOverRho2_;
};

} // namespace

std::unique_ptr<PressureSolverSettings> parseWcsphKeys(const TableReader& r) {
    auto s = std::make_unique<WcsphSettings>();
    s->soundSpeed = r.nonNegative("sound_speed", s->soundSpeed);
    return s;
}

std::unique_ptr<PressureSolver> makeWcsphSolver(FluidSimulation& sim, const PressureSolverSettings& settings) {
    return std::make_unique<WcsphSolver>(sim, static_cast<const WcsphSettings&>(settings));
}

} // namespace ferro

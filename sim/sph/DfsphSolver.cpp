// Divergence-free SPH (Bender & Koschier 2017): a divergence solve keeps the velocity
// field divergence-free, a constant-density solve corrects the predicted density, both
// by relaxed Jacobi iterations on the pressure Poisson system, warm-started. The density
// solve may hand over to conjugate gradients when Jacobi's progress says it would stop at
// its cap (sim.pressure_iteration = "auto"), or run them first ("cg"). Steps are
// about ten times longer than WCSPH's.
#include "sim/sph/PressureSolver.hpp"

#include "sim/core/ParticleLoops.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/sph/FluidSimulation.hpp"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <cmath>

namespace ferro {

namespace {

/// Fewer neighbours than this (fluid and wall) marks a particle near the free surface,
/// where the divergence solve leaves it alone (SPlisHSPlasH's threshold for 3-D).
constexpr uint32_t kDenseNeighborhood = 20;

/// The density solve starts from this fraction of the last step's pressure (solveDensity).
constexpr double kDensityWarmStart = 0.8;

/// sim.pressure_iteration = "auto": Jacobi hands the density solve over to conjugate
/// gradients once its own rate of progress (over the last kRateWindow sweeps, judged from
/// sweep kFirstJudgement on) says it would not reach the tolerance within the iteration cap.
/// CG needs about as many iterations as the layer is deep in particles, Jacobi about the
/// square of that; but on shallow layers Jacobi's sweeps are cheaper (CG holds a tighter
/// tolerance, kCgTolerance, and costs more a sweep). So only the steps Jacobi would leave at
/// its cap go to CG. Measurements: docs/physics/sph-solver.md, "Choosing the density
/// iteration".
constexpr int kFirstJudgement = 6;
constexpr int kRateWindow = 3;

/// Conjugate gradients stop at this fraction of sim.max_density_error. A stop on the residual
/// cannot see a smooth error of the pressure (a near-uniform excess or deficit over the
/// layer changes the density by the system's smallest eigenvalue, about 1/depth^2 of a local
/// error). Jacobi's sweeps hardly change that mode within a step, so their warm start carries
/// it steadily; CG changes it freely within the tolerance, differently each step, and the
/// fluid answers the flicker with motion (a resting tank's pressure total swung 300-5,900
/// with a four-step period at 1.0; within 0.7 % a step at 0.1). Measurements:
/// docs/physics/sph-solver.md, "Why CG leaves a pool less at rest".
constexpr double kCgTolerance = 0.1;

/// DFSPH's own [sim] keys (parseDfsphKeys).
struct DfsphSettings final : PressureSolverSettings {
    /// sim.max_density_error: mean relative density error the density solve stops at (0.02 %):
    /// a looser one left a pool over a still magnet jittering. Measurements:
    /// docs/physics/sph-solver.md, "Density tolerance".
    double maxDensityError = 0.0002;
    /// sim.max_divergence_error: mean relative density change per step the divergence solve
    /// leaves (0.1 %).
    double maxDivergenceError = 0.001;
    /// sim.max_iterations: the iteration cap of each solve.
    int maxIterations = 100;
    /// sim.pressure_iteration: how the density solve iterates. Jacobi (default):
    /// SPlisHSPlasH's relaxed Jacobi, warm-started from 0.8 of the last pressure where the step
    /// compresses. Auto: each step starts with Jacobi and hands over to conjugate gradients when
    /// Jacobi's own rate of progress says it would not reach the tolerance within
    /// max_iterations (deep layers: Jacobi's sweeps grow with the square of the depth in
    /// particles, CG's with the depth); not yet the default (it waits for a whole suite run
    /// with it). CG: bound-constrained conjugate gradients (MPRGP) from the start on the same
    /// (symmetric) system to a tenth of the tolerance, then Jacobi sweeps to it. Measurements:
    /// docs/physics/sph-solver.md, "Choosing the density iteration".
    enum class Iteration { Jacobi, Auto, ConjugateGradient };
    Iteration iteration = Iteration::Jacobi;
};

class DfsphSolver final : public PressureSolver {
public:
    DfsphSolver(FluidSimulation& sim, const DfsphSettings& settings) : sim_(sim), settings_(settings) {}

    bool storesGradients() const override { return true; }

    double maxTimeStep(double maxSpeed) const override {
        const SolverParams& sp = sim_.scene().solver;
        return maxSpeed > 0 ? sp.cfl * sim_.spacing() / maxSpeed : sp.maxDt;
    }

    void advanceVelocities(double dt) override {
        computeFactors();
        solveDivergence(dt);
        sim_.computeAccelerations(nullptr); // everything but pressure
        std::vector<Vec3>& v = sim_.solverVelocities();
        const std::vector<Vec3>& a = sim_.accelerations();
        forEachParticle(sim_.size(), [&](size_t i) { v[i] += Real(dt) * a[i]; });
        // Implicit viscosity (when chosen) is a non-pressure force too: solved here, before
        // the density solve, as in SPlisHSPlasH's DFSPH.
        sim_.applyImplicitViscosity(dt);
        sim_.stopMotionIntoMagnetBodies(dt);
        solveDensity(dt);
    }

    void permuteState(const std::vector<uint32_t>& order) override {
        if (kappaV_.size() == order.size()) ferro::permute(kappaV_, order);
    }

    std::vector<std::pair<std::string, double>> settingValues() const override {
        return {{"density_tol", settings_.maxDensityError},
                {"divergence_tol", settings_.maxDivergenceError},
                {"max_iterations", double(settings_.maxIterations)}};
    }

    std::string capWarning(const SolverCapCount& caps) const override {
        const bool density = caps.densityAtCap >= caps.divergenceAtCap;
        char text[400];
        std::snprintf(text, sizeof text,
                      "the %s solve stopped at its iteration cap (sim.max_iterations = %d) in %zu of %zu steps, leaving a "
                      "mean compression of up to %.3g %% against sim.%s = %.3g %%: raise sim.max_iterations or lower sim.max_dt",
                      density ? "density" : "divergence", settings_.maxIterations,
                      density ? caps.densityAtCap : caps.divergenceAtCap, caps.steps,
                      100 * (density ? caps.densityError : caps.divergenceError),
                      density ? "max_density_error" : "max_divergence_error",
                      100 * (density ? settings_.maxDensityError : settings_.maxDivergenceError));
        return text;
    }

    void resetWarmStart() override {
        kappaV_.assign(sim_.size(), Real(0));
    }

private:
    void computeFactors();
    void solveDivergence(double dt);
    void solveDensity(double dt);
    /// Relaxed Jacobi sweeps until the mean residual is under eta (after at least
    /// minIterations) or maxIterations. With `handOver`, it also stops, setting *handOver, once
    /// its rate of progress predicts that maxIterations would not do.
    int relaxedJacobi(std::vector<Real>& kappa, const std::vector<Real>& source, double hPow, double eta,
                      int minIterations, bool densitySolve, int maxIterations, bool* handOver = nullptr);
    /// The density solve by bound-constrained conjugate gradients (MPRGP) until the mean of
    /// hPow |projected gradient| is under eta, or maxIterations products.
    int conjugateGradient(std::vector<Real>& kappa, const std::vector<Real>& source, double hPow, double eta,
                          int maxIterations);
    /// out = M u (the density solve's matrix, M = D G: minus the density change per unit hPow
    /// that the pressure accelerations of u cause), every particle.
    void applySystem(const std::vector<Real>& u, std::vector<Real>& out);
    uint32_t neighborCount(size_t i) const {
        return sim_.fluidNeighbors().count[i] + sim_.boundaryNeighbors().count[i];
    }

    FluidSimulation& sim_;
    const DfsphSettings settings_;
    std::vector<Real> alpha_, kappa_, kappaV_, source_, residual_;
    std::vector<Real> change_;  // the density change of a field, per particle (FluidSimulation::divergence)
    std::vector<Real> cgResidual_, cgPreconditioned_, cgDirection_, cgProduct_; // conjugateGradient's vectors
};

void DfsphSolver::computeFactors() {
    // alpha_i = 1 / (|sum_j V grad W_ij + sum_b V_b grad W_ib|^2 + sum_j |V grad W_ij|^2),
    // the inverse diagonal of the pressure system (Bender & Koschier 2017).
    const Real V = Real(sim_.particleVolume());
    const NeighborLists& fluidNbr = sim_.fluidNeighbors();
    const NeighborLists& boundaryNbr = sim_.boundaryNeighbors();
    const std::vector<Real>& bVolume = sim_.boundaryVolumes();
    const std::vector<Vec3>& x = sim_.positions();
    const std::vector<Vec3>& bx = sim_.boundaryPositions();
    const PeriodicDomain periodic = sim_.periodic(); // a copy: the loop stores floats
    const double h = sim_.supportRadius();
    alpha_.resize(sim_.size());
    // One loop, instantiated with and without the periodic image map (a closed box then runs
    // the loop it had: the map's test per pair cost this sweep a quarter more instructions).
    auto sweep = [&](auto offset) {
    forEachParticle(sim_.size(), [&](size_t i) {
        // With mirrored wall pressure the diagonal of the system is
        // (g_f + g_b) . (g_f + kWallMirror g_b) + sum_j |V grad W_ij|^2.
        Vec3 fluid = Vec3::Zero(), wall = Vec3::Zero();
        Real sum2 = 0;
        for (uint32_t k = fluidNbr.begin(i); k < fluidNbr.end(i); ++k) {
            const Vec3 g = (V * fluidNbr.gradFactor[k]) * offset(x[i] - x[fluidNbr.index[k]]);
            fluid += g;
            sum2 += g.squaredNorm();
        }
        for (uint32_t k = boundaryNbr.begin(i); k < boundaryNbr.end(i); ++k) {
            const uint32_t b = boundaryNbr.index[k];
            wall += (bVolume[b] * boundaryNbr.gradFactor[k]) * offset(x[i] - bx[b]);
        }
        const Real denom = (fluid + wall).dot(fluid + FluidSimulation::kWallMirror * wall) + sum2;
        alpha_[i] = denom > Real(1e-6) * Real(1 / (h * h)) ? 1 / denom : 0;
    });
    };
    if (periodic.active()) sweep([&](const Vec3& d) { return periodic.offset(d); });
    else sweep([](const Vec3& d) { return d; });
}

int DfsphSolver::relaxedJacobi(std::vector<Real>& kappa, const std::vector<Real>& source, double hPow,
                               double eta, int minIterations, bool densitySolve, int maxIterations, bool* handOver) {
    // Relaxed Jacobi on the pressure Poisson system of DFSPH (SPlisHSPlasH's form):
    // kappa_i <- max(kappa_i - 0.5 (s_i - (A kappa)_i) alpha_i / hPow, 0), where
    // (A kappa)_i = hPow * sum_j V (a_i - a_j) . grad W_ij is the density change the
    // pressure accelerations cause. Stops when the mean residual is below eta.
    const size_t n = sim_.size();
    const Real hp = Real(hPow), invHp = Real(1 / hPow);
    std::vector<Real>& residual = residual_;
    residual.resize(n);
    change_.resize(n);
    int it = 0;
    double err = 0;
    double history[kRateWindow + 1] = {}; // the last errors, history[it % (kRateWindow + 1)]
    if (handOver) *handOver = false;
    for (; it < maxIterations; ++it) {
        sim_.pressureAccelerations(kappa);
        forEachParticleBlock(n, [&](size_t begin, size_t end) {
            // The density change the pressure causes, a block at a time (one sweep call).
            sim_.pressureDivergence(begin, end, change_.data());
            for (size_t i = begin; i < end; ++i) {
                const Real Ap = hp * change_[i];
                const Real r = source[i] - Ap;
                kappa[i] = std::max(kappa[i] - Real(0.5) * r * alpha_[i] * invHp, Real(0));
                // Sparse particles (near the free surface) do not count toward divergence error.
                const bool counts = densitySolve || neighborCount(i) >= kDenseNeighborhood;
                residual[i] = counts ? std::max(-r, Real(0)) : 0;
            }
        });
        err = deterministicSum(n, [&](size_t i) { return double(residual[i]); }) / double(std::max<size_t>(n, 1));
        if (it + 1 >= minIterations && err <= eta) {
            ++it;
            break;
        }
        history[it % (kRateWindow + 1)] = err;
        if (handOver && it + 1 >= kFirstJudgement) {
            // Geometric progress at the last window's rate: sweeps still needed.
            const double before = history[(it + 1) % (kRateWindow + 1)]; // kRateWindow sweeps ago
            const double rate = before > 0 ? std::pow(err / before, 1.0 / kRateWindow) : 1.0;
            const double needed = rate < 1 ? std::log(eta / err) / std::log(rate) : 1e9;
            if (it + 1 + needed > maxIterations) {
                *handOver = true;
                ++it;
                break;
            }
        }
    }
    // Never silent at the cap: the step says so (FluidSimulation counts it per frame).
    const bool atCap = it >= maxIterations && err > eta;
    StepStats& stats = sim_.solverStats();
    if (densitySolve) {
        stats.densityError = err;
        stats.densityAtCap = atCap;
    } else {
        stats.divergenceError = err * hPow; // relative compression per step
        stats.divergenceAtCap = atCap;
    }
    return it;
}

void DfsphSolver::applySystem(const std::vector<Real>& u, std::vector<Real>& out) {
    sim_.pressureAccelerations(u);
    sim_.pressureDivergence(out);
    forEachParticle(sim_.size(), [&](size_t i) { out[i] = -out[i]; });
}

int DfsphSolver::conjugateGradient(std::vector<Real>& kappa, const std::vector<Real>& source, double hPow, double eta,
                                   int maxIterations) {
    // The density solve as what it is, a bound-constrained quadratic program: minimize
    // q(k) = k.M k / 2 - b.k subject to k >= 0 (b = -source / hPow), whose optimality conditions
    // are the complementarity problem the Jacobi sweeps solve: g = M k - b >= 0 where k = 0 (no
    // compression left without pressure), g = 0 where k > 0. MPRGP (Dostal & Schoberl 2005,
    // "Minimizing quadratic functions subject to bound constraints with the rate of convergence
    // and finite termination", Comput. Optim. Appl. 30): conjugate gradients on the face of
    // the particles that carry pressure, preconditioned by alpha (1 / M_ii) as the unbounded CG;
    // a step that would take a pressure below zero stops at the bound and leaves the face by a
    // projected relaxed Jacobi step (the "expansion"); when the face's gradient is small
    // against the pull of particles outside it that the step compresses ("proportioning"),
    // a step along that pull lets them in. Each iteration is one product M p (two on an
    // expansion). Dot products in fixed order (deterministicSum): resumed runs stay exact.
    const size_t n = sim_.size();
    const Real hp = Real(hPow);
    constexpr double kGamma = 1.0;         // proportioning threshold (Dostal's Gamma)
    constexpr Real kExpansion = Real(0.5); // the expansion's relaxed Jacobi weight (SPlisHSPlasH's)
    std::vector<Real>& g = cgResidual_;    // M k - b
    std::vector<Real>& z = cgPreconditioned_;
    std::vector<Real>& p = cgDirection_;
    std::vector<Real>& Ap = cgProduct_;
    g.resize(n);
    z.resize(n);
    p.resize(n);
    Ap.resize(n);
    auto gradient = [&]() {   // g = M k - b: one product
        applySystem(kappa, Ap);
        forEachParticle(n, [&](size_t i) { g[i] = Ap[i] + source[i] / hp; });
    };
    // Free gradient phi (on the face k > 0) and chopped gradient beta (at the bound, pulling in).
    auto phi = [&](size_t i) { return kappa[i] > 0 ? g[i] : Real(0); };
    auto beta = [&](size_t i) { return kappa[i] > 0 ? Real(0) : std::min(g[i], Real(0)); };
    // The stopping measure: the mean of hPow |projected gradient|, the compression left
    // without pressure (the Jacobi sweeps' measure) plus the expansion left under pressure,
    // which CG may overshoot into and the sweeps, rising from below, hardly leave.
    auto error = [&]() {
        return deterministicSum(n, [&](size_t i) { return std::abs(double(hp * (phi(i) + beta(i)))); }) /
               double(std::max<size_t>(n, 1));
    };
    auto dot = [&](const std::vector<Real>& x, const std::vector<Real>& y) {
        return deterministicSum(n, [&](size_t i) { return double(x[i]) * double(y[i]); });
    };
    forEachParticle(n, [&](size_t i) { kappa[i] = std::max(kappa[i], Real(0)); });
    int it = 1;
    gradient();
    auto restart = [&]() {
        forEachParticle(n, [&](size_t i) {
            z[i] = alpha_[i] * phi(i);
            p[i] = z[i];
        });
    };
    restart();
    double err = error();
    while (it < maxIterations && err > eta) {
        const double betaNorm2 = deterministicSum(n, [&](size_t i) { return double(beta(i)) * double(beta(i)) * alpha_[i]; });
        const double phiZ = deterministicSum(n, [&](size_t i) { return double(phi(i)) * double(z[i]); });
        if (betaNorm2 <= kGamma * kGamma * phiZ) {
            applySystem(p, Ap);
            ++it;
            const double pAp = dot(p, Ap);
            if (!(pAp > 0)) break;
            const double stepCg = dot(g, p) / pAp;
            // The longest step that keeps k >= 0 (k - step p).
            const double stepMax =
                smallestOf(n, 1e300, [&](size_t i) { return p[i] > 0 ? double(kappa[i]) / double(p[i]) : 1e300; });
            if (stepCg <= stepMax) {
                const Real a = Real(stepCg);
                forEachParticle(n, [&](size_t i) {
                    kappa[i] = std::max(kappa[i] - a * p[i], Real(0));
                    g[i] -= a * Ap[i];
                    z[i] = alpha_[i] * phi(i);
                });
                const Real gamma = Real(dot(z, Ap) / pAp);
                forEachParticle(n, [&](size_t i) { p[i] = z[i] - gamma * p[i]; });
            } else {
                // Expansion: to the bound, then a projected relaxed Jacobi step off the face.
                const Real a = Real(stepMax);
                forEachParticle(n, [&](size_t i) {
                    kappa[i] = std::max(kappa[i] - a * p[i], Real(0));
                    g[i] -= a * Ap[i];
                });
                forEachParticle(n, [&](size_t i) { kappa[i] = std::max(kappa[i] - kExpansion * alpha_[i] * g[i], Real(0)); });
                gradient();
                ++it;
                restart();
            }
        } else {
            // Proportioning: along the chopped gradient, letting compressed particles carry pressure.
            forEachParticle(n, [&](size_t i) { z[i] = alpha_[i] * beta(i); });
            applySystem(z, Ap);
            ++it;
            const double dAd = dot(z, Ap);
            if (!(dAd > 0)) break;
            const Real a = Real(dot(g, z) / dAd);
            forEachParticle(n, [&](size_t i) {
                kappa[i] = std::max(kappa[i] - a * z[i], Real(0));
                g[i] -= a * Ap[i];
            });
            restart();
        }
        err = error();
    }
    return it;
}

void DfsphSolver::solveDivergence(double dt) {
    const size_t n = sim_.size();
    std::vector<Vec3>& v = sim_.solverVelocities();
    const std::vector<Vec3>& a = sim_.accelerations();
    if (kappaV_.size() != n) kappaV_.assign(n, Real(0));
    source_.resize(n);
    sim_.divergence(v, change_);
    forEachParticle(n, [&](size_t i) {
        Real div = change_[i];
        // Only compression is corrected, and not at the sparse free surface.
        if (neighborCount(i) < kDenseNeighborhood || div < 0) div = 0;
        source_[i] = -div;
        // Warm start from the previous step's solution (stored times dt).
        kappaV_[i] = div > 0 ? Real(0.5) * std::min(kappaV_[i], Real(0.5)) / Real(dt) : 0;
    });
    const double eta = settings_.maxDivergenceError / dt;
    sim_.solverStats().divergenceIterations = relaxedJacobi(kappaV_, source_, dt, eta, 1, false, settings_.maxIterations);
    sim_.pressureAccelerations(kappaV_);
    forEachParticle(n, [&](size_t i) {
        v[i] += Real(dt) * a[i];
        kappaV_[i] *= Real(dt);
    });
}

void DfsphSolver::solveDensity(double dt) {
    const size_t n = sim_.size();
    const Real rho0 = Real(sim_.restDensity());
    const Real h2 = Real(dt * dt);
    std::vector<Vec3>& v = sim_.solverVelocities();
    std::vector<Real>& p = pressure_;
    p.resize(n, Real(0));
    const std::vector<Real>& rho = sim_.densities();
    const std::vector<Vec3>& a = sim_.accelerations();
    kappa_.resize(n);
    source_.resize(n);
    sim_.divergence(v, change_);
    forEachParticle(n, [&](size_t i) {
        // Predicted density and the unclamped source 1 - rho* / rho0. With kappa >= 0 the
        // Jacobi sweep then solves the complementarity problem (no pressure where the fluid
        // stays at or below rest density, rest density where it has pressure). Clamping the
        // source at 0 for rho* < rho0 (SPlisHSPlasH's max(rho*, 1)) asks instead that the
        // pressure leave an expanded particle's density unchanged, (A kappa)_i = 0: its
        // kappa grows whenever its neighbours' pressure pushes inward, so pressure builds
        // in expanding fluid and pushes it further apart. The pressure's work per step is
        // m sum kappa_i (rho_i / rho0 - rho_i after / rho0); under a strong non-uniform body
        // force (the Kelvin force of a magnet below the dish, 20-30 g) the pressurized
        // particles sat 30 % below rest density and that work pumped the fluid at 30-40 mm/s
        // for good (issue 13). Expansion still gets no pressure.
        const Real predicted = rho[i] / rho0 + Real(dt) * change_[i];
        source_[i] = 1 - predicted;
        // Warm start from 0.8 of the previous step's pressure where the step compresses
        // (SPlisHSPlasH: 0.5): the solve, stopped at its tolerance, must end below the right
        // pressure (what it leaves is compression the next step corrects; too much pressure
        // pumps the fluid), and from 0.8 only a fifth is left to rebuild. From the pressure
        // every frame file stores, so resumed runs stay identical. Measurements:
        // docs/physics/sph-solver.md, "The density solve's warm start".
        kappa_[i] = predicted > 1 ? Real(kDensityWarmStart) * std::min(p[i] * rho0 / (rho[i] * rho[i]), Real(0.00025) / h2) : 0;
    });
    const DfsphSettings& sp = settings_;
    using Iteration = DfsphSettings::Iteration;
    // Auto: Jacobi first, then CG from where Jacobi stopped if its progress is too slow.
    // Jacobi sweeps finish after CG (to the tolerance, usually none: CG stops at a tenth of it).
    int jacobi = 0;
    bool useCg = sp.iteration == Iteration::ConjugateGradient;
    if (sp.iteration == Iteration::Auto)
        jacobi = relaxedJacobi(kappa_, source_, dt * dt, sp.maxDensityError, 2, true, sp.maxIterations - 1, &useCg);
    const int cg = useCg ? conjugateGradient(kappa_, source_, dt * dt, kCgTolerance * sp.maxDensityError,
                                             sp.maxIterations - 1 - jacobi)
                         : 0;
    const int finish = (jacobi > 0 && !useCg) ? 0
                       : relaxedJacobi(kappa_, source_, dt * dt, sp.maxDensityError, useCg ? 1 : 2, true,
                                       sp.maxIterations - jacobi - cg);
    sim_.solverStats().pressureIterations = jacobi + cg + finish;
    sim_.solverStats().densityByCg = useCg;
    sim_.pressureAccelerations(kappa_);
    forEachParticle(n, [&](size_t i) {
        v[i] += Real(dt) * a[i];
        // kappa = p / rho^2 normalized by rho0, so p = kappa rho^2 / rho0.
        p[i] = kappa_[i] * rho[i] * rho[i] / rho0;
    });
}

} // namespace

std::unique_ptr<PressureSolverSettings> parseDfsphKeys(const TableReader& r) {
    auto s = std::make_unique<DfsphSettings>();
    s->maxDensityError = r.positive("max_density_error", s->maxDensityError);
    s->maxDivergenceError = r.positive("max_divergence_error", s->maxDivergenceError);
    s->maxIterations = r.integerInRange("max_iterations", s->maxIterations, 1, INT_MAX);
    const std::string it = r.choice("pressure_iteration", {"jacobi", "auto", "cg"}, "jacobi");
    s->iteration = it == "cg"     ? DfsphSettings::Iteration::ConjugateGradient
                   : it == "auto" ? DfsphSettings::Iteration::Auto
                                  : DfsphSettings::Iteration::Jacobi;
    return s;
}

std::unique_ptr<PressureSolver> makeDfsphSolver(FluidSimulation& sim, const PressureSolverSettings& settings) {
    return std::make_unique<DfsphSolver>(sim, static_cast<const DfsphSettings&>(settings));
}

} // namespace ferro

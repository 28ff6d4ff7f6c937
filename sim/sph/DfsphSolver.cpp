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
/// square of that; but CG stops with the smooth part of the pressure less settled (a
/// resting tank's bottom pressure 30 % low where CG took over at a budget of 40 sweeps), and
/// its set of pressured particles costs it more than Jacobi on shallow layers. So only the
/// steps Jacobi would leave at its cap go to CG. Measurements: docs/physics/sph-solver.md,
/// "Choosing the density iteration".
constexpr int kFirstJudgement = 6;
constexpr int kRateWindow = 3;

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
    /// particles, CG's with the depth); not the default, because the steps CG solves leave a
    /// pool over a magnet less at rest. CG: conjugate gradients from the start on the same
    /// (symmetric) system, then Jacobi sweeps to the tolerance. Measurements:
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
    int conjugateGradient(std::vector<Real>& kappa, const std::vector<Real>& source, double hPow, double eta,
                          int maxIterations);
    uint32_t neighborCount(size_t i) const {
        return sim_.fluidNeighbors().count[i] + sim_.boundaryNeighbors().count[i];
    }

    FluidSimulation& sim_;
    const DfsphSettings settings_;
    std::vector<Real> alpha_, kappa_, kappaV_, source_, residual_;
    std::vector<Real> change_;  // the density change of a field, per particle (FluidSimulation::divergence)
    std::vector<Real> cgResidual_, cgPreconditioned_, cgDirection_, cgProduct_; // conjugateGradient's vectors
    std::vector<uint8_t> cgInSet_;  // conjugateGradient: 1 where a particle may carry pressure (the set S)
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

int DfsphSolver::conjugateGradient(std::vector<Real>& kappa, const std::vector<Real>& source, double hPow, double eta,
                                   int maxIterations) {
    // The density solve's system is M kappa = b with M = D G, b = -source / hPow: G kappa the
    // pressure accelerations (pressureAccelerations: a = -G kappa), D the density change of a
    // velocity field (divergence). D is G's adjoint, sum_i k_i (D u)_i = sum_i u_i . (G k)_i,
    // walls included (they push with kappa_i alone), so M is symmetric positive
    // semi-definite: preconditioned conjugate gradients apply, with alpha (1 / M_ii) as
    // preconditioner. Jacobi's sweeps grow with the square of the fluid's depth in
    // spacings, CG's with the depth. The inequality kappa >= 0 is not CG's: the set S of
    // particles that may carry pressure is every particle of the dense interior and the
    // sparse (free-surface) ones the step compresses; a second round drops from S the
    // particles the first left under tension and solves again from there (taking back in
    // the particles left out that the step then compresses made a dam break's solve churn:
    // 100 sweeps, 0.096 % left); negative values are then clamped, and the caller's
    // Jacobi sweeps finish the complementarity problem. Dot products in fixed order
    // (deterministicSum): resumed runs stay exact.
    const size_t n = sim_.size();
    const Real hp = Real(hPow);
    std::vector<Real>& R = cgResidual_;        // b - M kappa, every particle
    std::vector<Real>& Z = cgPreconditioned_;  // alpha R on S
    std::vector<Real>& P = cgDirection_;
    std::vector<Real>& Q = cgProduct_;         // M P
    std::vector<uint8_t>& inS = cgInSet_;
    R.resize(n);
    Z.resize(n);
    P.resize(n);
    Q.resize(n);
    inS.resize(n);
    forEachParticle(n, [&](size_t i) {
        inS[i] = source[i] < 0 || neighborCount(i) >= kDenseNeighborhood;
        if (!inS[i]) kappa[i] = 0;
    });
    // The compression the step would leave on S: hPow R_i where positive, summed over CG's own
    // unknowns and divided by every particle (the Jacobi sweeps' mean, restricted to S). A
    // particle outside S (sparse, not compressed by the step itself) may still be compressed by
    // its neighbours' pressure, which no kappa in S undoes:
    // counting those kept CG at its cap on shallow layers (40,960 particles 8 deep, every step
    // of 5 frames, 0.33 % falling to 0.11 % left). The caller's Jacobi sweeps, over every
    // particle, finish them.
    auto error = [&]() {
        return deterministicSum(n, [&](size_t i) { return inS[i] ? std::max(double(hp * R[i]), 0.0) : 0.0; }) /
               double(std::max<size_t>(n, 1));
    };
    auto dotOnS = [&](const std::vector<Real>& x, const std::vector<Real>& y) {
        return deterministicSum(n, [&](size_t i) { return inS[i] ? double(x[i]) * double(y[i]) : 0.0; });
    };
    int it = 0;
    constexpr int kRounds = 2;
    for (int round = 0; round < kRounds && it < maxIterations; ++round) {
        if (round > 0) {
            // Particles the first round left under tension leave S.
            const double leaving = deterministicSum(n, [&](size_t i) { return inS[i] && kappa[i] < 0 ? 1.0 : 0.0; });
            if (leaving == 0) break;
            forEachParticle(n, [&](size_t i) {
                if (inS[i] && kappa[i] < 0) {
                    inS[i] = 0;
                    kappa[i] = 0;
                }
            });
        }
        // The residual costs a sweep like an iteration's, and is counted as one.
        ++it;
        sim_.pressureAccelerations(kappa);
        sim_.pressureDivergence(change_);
        forEachParticle(n, [&](size_t i) {
            R[i] = -source[i] / hp + change_[i];
            Z[i] = inS[i] ? alpha_[i] * R[i] : 0;
            P[i] = Z[i];
        });
        double rz = dotOnS(R, Z);
        double err = error();
        // The first round gets a quarter of the sweeps: where it leaves tension (a poured
        // lattice's floor layer starts 8 % below rest density) it is not converging to
        // anything the second round keeps.
        const int roundEnd = round == 0 ? std::max(1, maxIterations / 4) : maxIterations;
        while (it < roundEnd && err > eta && rz > 0) {
            sim_.pressureAccelerations(P);
            sim_.pressureDivergence(Q);
            forEachParticle(n, [&](size_t i) { Q[i] = -Q[i]; });
            const double pq = dotOnS(P, Q);
            if (!(pq > 0)) break;
            const Real step = Real(rz / pq);
            forEachParticle(n, [&](size_t i) {
                if (inS[i]) kappa[i] += step * P[i];
                R[i] -= step * Q[i];
                Z[i] = inS[i] ? alpha_[i] * R[i] : 0;
            });
            ++it;
            err = error();
            const double rzNext = dotOnS(R, Z);
            const Real beta = Real(rzNext / rz);
            rz = rzNext;
            forEachParticle(n, [&](size_t i) { P[i] = inS[i] ? Z[i] + beta * P[i] : 0; });
        }
    }
    forEachParticle(n, [&](size_t i) { kappa[i] = std::max(kappa[i], Real(0)); });
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
    // Whatever CG leaves (its set of pressured particles is fixed, kappa >= 0 is clamped
    // after) Jacobi sweeps finish, as after "cg".
    int jacobi = 0;
    bool useCg = sp.iteration == Iteration::ConjugateGradient;
    if (sp.iteration == Iteration::Auto)
        jacobi = relaxedJacobi(kappa_, source_, dt * dt, sp.maxDensityError, 2, true, sp.maxIterations - 1, &useCg);
    const int cg = useCg ? conjugateGradient(kappa_, source_, dt * dt, sp.maxDensityError, sp.maxIterations - 1 - jacobi) : 0;
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

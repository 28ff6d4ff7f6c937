#include "sim/magnetics/MagnetizationSolver.hpp"
#include "sim/core/Gmres.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace ferro {

// ---------------------------------------------------------------------------------------
// Solver

namespace {

using Clock = std::chrono::steady_clock;
using VecX = Eigen::VectorXd;

// The Jacobian of M(H) at H: s I + (t - s) h h^T (s secant, t slope, h = H / |H|).
struct LocalSusceptibility {
    double s, t;
    Eigen::Vector3d h;
};

LocalSusceptibility localSusceptibility(const Eigen::Vector3d& H, double chi0, double Ms) {
    const double a = H.norm();
    LocalSusceptibility L{langevinSecant(a, chi0, Ms), langevinSlope(a, chi0, Ms), Eigen::Vector3d::Zero()};
    if (a > 0 && std::isfinite(a)) L.h = H / a;
    return L;
}

// Deterministic sample of particle indices for error estimates.
std::vector<size_t> sampleIndices(size_t n, size_t count) {
    std::vector<size_t> s;
    if (n == 0) return s;
    if (n <= count) {
        for (size_t i = 0; i < n; ++i) s.push_back(i);
        return s;
    }
    uint64_t state = 0x9e3779b97f4a7c15ULL;
    for (size_t i = 0; i < count; ++i) {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        s.push_back(size_t((state >> 33) % n));
    }
    return s;
}

constexpr size_t kErrorSamples = 64;
// GMRES restart length: 30 Krylov vectors (3N doubles each: 30 MB at 40,960 particles).
// Up to chi0 ~ 5 a solve needs ~4-15 evaluations and never restarts. Far beyond (chi0 ~ 20,
// linear) the near field of close particle pairs makes the system indefinite and GMRES
// slows down (residual ~4 % after 50 evaluations on a jittered layer); saturation (Ms > 0)
// keeps the effective susceptibility low and converges again.
constexpr int kRestart = 30;

void magnetizationOf(const VecX& H, double chi0, double Ms, VecX& M) {
    const Eigen::Index n = H.size() / 3;
    M.resize(H.size());
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, 4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
        for (Eigen::Index k = r.begin(); k < r.end(); ++k) {
            const Eigen::Vector3d h = H.segment<3>(3 * k);
            M.segment<3>(3 * k) = langevinSecant(h.norm(), chi0, Ms) * h;
        }
    });
}

} // namespace

static_assert(MagnetizationParams{}.smoothing == DipoleTree::kDefaultSmoothing,
              "the solver's and the evaluator's default particle model must agree");

MagnetizationSolver::MagnetizationSolver(const MagnetizationParams& params) : params_(params) {}

void MagnetizationSolver::solveSelfConsistent(DipoleTree& tree, bool useTree, const VecX& Hext, VecX& H,
                                              Stats& stats) const {
    const double chi0 = params_.susceptibility, Ms = params_.saturation;
    const bool linear = !(Ms > 0);
    const double extNorm = std::max(Hext.norm(), 1e-300);
    const double target = 0.1 * std::max(params_.tolerance, 1e-12) * extNorm;
    const int maxApply = std::max(1, params_.maxIterations);
    const Eigen::Index n = H.size() / 3;

    VecX M, AM, R, D(9 * n), dH, Hprev, step;
    double prevRes = std::numeric_limits<double>::infinity();
    int backtracks = 0;
    while (true) {
        magnetizationOf(H, chi0, Ms, M);
        tree.setMagnetization(M);
        tree.fieldAtParticles(AM, useTree);
        ++stats.iterations;
        R = H - Hext - AM;
        double res = R.norm();
        // Newton safeguard: a step that raised the residual is halved (at most 4 times).
        if (res > prevRes && backtracks < 4 && stats.newtonSteps > 0 && stats.iterations < maxApply) {
            step *= 0.5;
            H = Hprev + step;
            ++backtracks;
            continue;
        }
        backtracks = 0;
        stats.residual = res / extNorm;
        if (res <= target || stats.iterations >= maxApply) break;
        // Local susceptibility tensors at H.
        std::vector<LocalSusceptibility> chi(n);
        tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, 4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
            for (Eigen::Index k = r.begin(); k < r.end(); ++k)
                chi[k] = localSusceptibility(H.segment<3>(3 * k), chi0, Ms);
        });
        VecX w(3 * n);
        auto op = [&](const VecX& v) {
            tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, 4096), [&](const tbb::blocked_range<Eigen::Index>& r) {
                for (Eigen::Index k = r.begin(); k < r.end(); ++k) {
                    const Eigen::Vector3d vk = v.segment<3>(3 * k);
                    const LocalSusceptibility& c = chi[k];
                    w.segment<3>(3 * k) = c.s * vk + (c.t - c.s) * c.h.dot(vk) * c.h;
                }
            });
            tree.setMagnetization(w);
            VecX Aw;
            tree.fieldAtParticles(Aw, useTree);
            return VecX(v - Aw);
        };
        // Linear: solve to the target at once. Langevin: inexact Newton (a tenth of the
        // current residual, but not below the target).
        const double tol = linear ? target : std::max(0.1 * res, 0.5 * target);
        double gres = 0;
        const VecX rhs = -R;
        stats.iterations += gmres(op, rhs, dH, tol, maxApply - stats.iterations, kRestart, gres);
        ++stats.newtonSteps;
        Hprev = H;
        step = dH;
        H += dH;
        prevRes = res;
        if (linear) { // M is linear in H: the GMRES residual is the new residual exactly
            stats.residual = gres / extNorm;
            break;
        }
        if (stats.iterations >= maxApply) {
            // No evaluation left to check the step; keep it (GMRES never increases |R| of
            // the linearization) and report the linearized residual.
            stats.residual = gres / extNorm;
            break;
        }
    }
    stats.converged = stats.residual * extNorm <= target * (1 + 1e-9);
}

MagnetizationSolver::Stats MagnetizationSolver::solve(const std::vector<Vec3>& x, const std::vector<Real>& volume,
                                                      const std::vector<Magnet>& magnets, std::vector<Vec3>& H,
                                                      std::vector<Vec3>& M, std::vector<Eigen::Matrix3f>* J,
                                                      const std::vector<Vec3>* extraField) {
    const bool extra = extraField && extraField->size() == x.size();
    const auto t0 = Clock::now();
    Stats stats;
    const size_t n = x.size();
    stats.particles = n;
    const bool warm = H.size() == n;
    H.resize(n);
    M.assign(n, Vec3::Zero());
    if (J) J->assign(n, Eigen::Matrix3f::Zero());
    if (magnets.empty() || n == 0 || !params_.enabled()) {
        stats.skipped = true;
        lastSolver_ = Solver::External;
        if (magnets.empty() || n == 0) {
            std::fill(H.begin(), H.end(), Vec3::Zero());
        } else { // non-magnetic fluid: the field is the magnets' alone
            tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t i = r.begin(); i < r.end(); ++i) {
                    Vec3d h = magnetField(magnets, x[i].cast<double>());
                    if (extra) h += (*extraField)[i].cast<double>();
                    H[i] = h.allFinite() ? Vec3(h.cast<Real>()) : Vec3(Vec3::Zero());
                }
            });
        }
        stats.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        return stats;
    }
    const double chi0 = params_.susceptibility, Ms = params_.saturation;
    Solver solver = params_.solver;
    double theta = params_.openingAngle > 0 ? params_.openingAngle : 0.5;

    DipoleTree tree; // Auto builds the interaction lists only once it has picked Tree
    tree.setSmoothing(params_.smoothing);
    tree.setSurfaceOnset(params_.localCorrection);
    tree.setPeriodic(period_[0], period_[1]);
    tree.build(x, volume, solver == Solver::Tree ? theta : 0.0);
    const std::vector<uint32_t>& order = tree.order();
    // With periodic sides the tree's places include the copies (nt = 9 n): each carries its
    // particle's field and magnetization (the magnets' field is taken at the particle, so
    // that a copy's stays its particle's).
    const size_t nt = tree.size();
    std::vector<size_t> targets;
    for (size_t k = 0; k < nt; ++k)
        if (tree.isTarget(k)) targets.push_back(k);
    auto sampleTargets = [&]() {
        std::vector<size_t> s = sampleIndices(n, kErrorSamples);
        for (size_t& k : s) k = targets[k];
        return s;
    };

    VecX Hext(3 * nt), Hs(3 * nt);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt, 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
            const size_t i = order[k] % n;
            Vec3d h = magnetField(magnets, x[i].cast<double>());
            if (extra) h += (*extraField)[i].cast<double>();
            if (!h.allFinite()) h.setZero();
            Hext.segment<3>(3 * k) = h;
            Vec3d start = h;
            if (warm) {
                const Vec3d w = H[i].cast<double>();
                if (w.allFinite()) start = w;
            }
            Hs.segment<3>(3 * k) = start;
        }
    });
    const double extNorm = Hext.norm();

    // External magnetization and, for External and Auto, the sampled size of the particle
    // field it neglects.
    auto externalError = [&]() {
        VecX Mext;
        magnetizationOf(Hext, chi0, Ms, Mext);
        tree.setMagnetization(Mext);
        const std::vector<size_t> samples = sampleTargets();
        std::vector<double> ind(samples.size()), ext(samples.size());
        tbb::parallel_for(size_t(0), samples.size(), [&](size_t s) {
            ind[s] = tree.fieldAtParticleDirect(samples[s]).squaredNorm();
            ext[s] = Hext.segment<3>(3 * samples[s]).squaredNorm();
        });
        double a = 0, b = 0;
        for (size_t s = 0; s < samples.size(); ++s) {
            a += ind[s];
            b += ext[s];
        }
        return b > 0 ? std::sqrt(a / b) : 0.0;
    };

    if (solver == Solver::External || solver == Solver::Auto) {
        const double err = externalError();
        if (solver == Solver::External || err <= params_.tolerance) {
            stats.solver = Solver::External;
            stats.fieldError = err;
            Hs = Hext;
        } else {
            solver = n > directLimit() ? Solver::Tree : Solver::Direct;
            if (solver == Solver::Tree) tree.build(x, volume, theta);
        }
    }
    if (solver == Solver::Direct || solver == Solver::Tree) {
        const bool useTree = solver == Solver::Tree;
        stats.solver = solver;
        for (int attempt = 0;; ++attempt) {
            if (params_.localCorrection && !tree.hasLocalCorrection()) tree.computeLocalCorrection(useTree);
            solveSelfConsistent(tree, useTree, Hext, Hs, stats);
            stats.fieldError = stats.residual;
            if (!useTree) break;
            stats.openingAngle = tree.openingAngle();
            // Sampled tree error with the final magnetization.
            VecX Mfinal;
            magnetizationOf(Hs, chi0, Ms, Mfinal);
            tree.setMagnetization(Mfinal);
            const std::vector<size_t> samples = sampleTargets();
            std::vector<double> diff(samples.size()), ref(samples.size());
            tbb::parallel_for(size_t(0), samples.size(), [&](size_t s) {
                const Eigen::Vector3d exact = tree.fieldAtParticleDirect(samples[s]);
                diff[s] = (tree.fieldAtParticleTree(samples[s]) - exact).squaredNorm();
                ref[s] = (Hext.segment<3>(3 * samples[s]) + exact).squaredNorm();
            });
            double a = 0, b = 0;
            for (size_t s = 0; s < samples.size(); ++s) {
                a += diff[s];
                b += ref[s];
            }
            stats.fieldError = (b > 0 ? std::sqrt(a / b) : 0.0) + stats.residual;
            // Auto promised an error under the tolerance: tighten theta (warm-started) if not.
            if (params_.solver != Solver::Auto || stats.fieldError <= params_.tolerance || attempt >= 2 ||
                tree.openingAngle() <= 0.15)
                break;
            theta = tree.openingAngle() * 0.7;
            tree.build(x, volume, theta);
        }
    }
    (void)extNorm;
    lastSolver_ = stats.solver;

    // Back to the caller's order, float.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t q = r.begin(); q < r.end(); ++q) {
            const size_t k = targets[q], i = order[k];
            Eigen::Vector3d h = Hs.segment<3>(3 * k);
            if (!h.allFinite()) h.setZero();
            H[i] = h.cast<Real>();
            M[i] = (langevinSecant(h.norm(), chi0, Ms) * h).cast<Real>();
        }
    });
    if (J) { // Jacobians at the solution, on the same tree
        std::vector<Mat3f> Js;
        if (stats.solver != Solver::External) {
            VecX Mfinal;
            magnetizationOf(Hs, chi0, Ms, Mfinal);
            tree.setMagnetization(Mfinal);
            tree.gradientAtParticles(Js, stats.solver == Solver::Tree);
        }
        addMagnetGradients(x, magnets, order, Js, *J);
    }
    stats.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    return stats;
}

void MagnetizationSolver::addMagnetGradients(const std::vector<Vec3>& x, const std::vector<Magnet>& magnets,
                                             const std::vector<uint32_t>& order, const std::vector<Mat3f>& Js,
                                             std::vector<Eigen::Matrix3f>& J) {
    const size_t n = x.size();
    J.assign(n, Eigen::Matrix3f::Zero());
    // A periodic tree's order holds its copies too (input index n and up): skipped.
    const size_t places = order.empty() ? n : order.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, places, 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
            const size_t i = order.empty() ? k : order[k];
            if (i >= n) continue;
            Mat3d g = ferro::fieldGradient(magnets, Vec3d(x[i].cast<double>()));
            if (!g.allFinite()) g.setZero();
            Eigen::Matrix3f total = g.cast<float>();
            if (k < Js.size()) total += Js[k];
            if (!total.allFinite()) total.setZero();
            J[i] = total;
        }
    });
}

void MagnetizationSolver::fieldGradient(const std::vector<Vec3>& x, const std::vector<Real>& volume,
                                        const std::vector<Magnet>& magnets, const std::vector<Vec3>& M,
                                        std::vector<Eigen::Matrix3f>& J) const {
    const size_t n = x.size();
    J.assign(n, Eigen::Matrix3f::Zero());
    if (magnets.empty() || n == 0 || !params_.enabled()) return;
    Solver kind = params_.solver;
    if (kind == Solver::Auto) kind = lastSolver_ ? *lastSolver_ : (n > directLimit() ? Solver::Tree : Solver::Direct);
    if (kind == Solver::External) { // the particles' own field is neglected, its gradient too
        addMagnetGradients(x, magnets, {}, {}, J);
        return;
    }
    const bool useTree = kind == Solver::Tree;
    DipoleTree tree;
    tree.setSmoothing(params_.smoothing);
    tree.setSurfaceOnset(params_.localCorrection);
    tree.setPeriodic(period_[0], period_[1]);
    tree.build(x, volume, useTree ? (params_.openingAngle > 0 ? params_.openingAngle : 0.5) : 0.0);
    tree.setMagnetizationUnsorted(M);
    std::vector<Mat3f> Js;
    tree.gradientAtParticles(Js, useTree);
    addMagnetGradients(x, magnets, tree.order(), Js, J);
}

} // namespace ferro

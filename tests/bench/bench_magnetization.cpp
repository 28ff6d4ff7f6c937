// bench-magnetization: cost and accuracy of the magnetization solvers (sim/magnetics/MagnetizationSolver)
// on a ferrofluid layer in a dish over a dipole magnet, for 10,240 / 40,960 / 163,840 particles.
//
//   build/bin/bench-magnetization [--threads 2] [--theta 0.5] [--sizes 10240,40960,163840]
//                                 [--direct-max 40960] [--tolerance 0.01] [--smoothing 2.5]
//                                 [--local-correction false] [--repeats 3]
//   build/bin/bench-magnetization --particles FILE [--thetas 0.3,0.5,0.8] [--threads 2] ...
//
// --particles FILE: instead of the synthetic layer, the particles of a ferro-sim particle file
// (a settled pool, scripts/bench/magnetics.sh), with its magnets and the fluid's law from the
// header (volume = particle_mass / rest_density). Prints CSV: one row per solver (external,
// tree at each opening angle of --thetas, auto) with CPU ms per cold solve, iterations, and the
// per-particle field error against the direct solve on the same particles: RMS
// (sqrt(sum |H - H_direct|^2 / sum |H_direct|^2)) and worst particle (|H - H_direct| / |H_direct|).
//
// --smoothing: the particle model, MagnetizationParams::smoothing: Wendland C2 smoothed
// dipoles of support smoothing x spacing (default), 0 = the older uniformly-magnetized-sphere
// model; run both to compare their cost.
//
// The layer: 8 layers of particles at 1.24 mm spacing (about 1 cm deep, the paper's dish),
// radius growing with N, lattice jittered by 10% of the spacing; oil-based ferrofluid
// chi0 = 1.5, Ms = 30 kA/m; a 2 A m^2 dipole 2 cm under the floor (|H| ~ 37 kA/m at the floor
// centre: the fluid saturates over the magnet). Every solve is cold (no warm start).
//
// For each solver: wall ms per solve (the fastest of --repeats cold solves, default 3: the
// same solve was measured up to 30 % apart within one run on a shared machine), field
// evaluations (particle-field products) per solve, ms per evaluation, and the relative RMS
// error of H and M against the direct solution. Above --direct-max particles the direct
// solve is not run: its cost is estimated as (all-pairs evaluation time measured on 2,048
// random target particles) x N / 2,048 x (the tree solve's evaluation count), and the tree's error is measured on those 2,048
// targets as |H_tree - (H_ext + exact particle field of the tree's M)| (the tree's
// approximation error at its own solution, plus its residual), not against a direct solve.
#include "sim/magnetics/MagnetizationSolver.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/Constants.hpp"
#include "tests/TestUtil.hpp"
#include "sim/core/CommandLine.hpp"

#include <CLI/CLI.hpp>

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

using namespace ferro;

namespace {

using Solver = MagnetizationParams::Solver;

void dishLayer(size_t count, std::vector<Vec3>& x, std::vector<Real>& V) {
    const double s = 1.24e-3;
    const int layers = 8;
    const double R = s * std::sqrt(double(count) / (layers * kPi)) * 1.05 + 2 * s;
    const int n = int(std::ceil(R / s));
    struct P {
        double r2;
        Vec3d p;
    };
    std::vector<P> all;
    uint32_t state = 2024;
    auto jitter = [&]() {
        state = state * 1664525u + 1013904223u;
        return 0.1 * s * (double(state >> 8) / double(1u << 24) - 0.5);
    };
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int k = 0; k < layers; ++k) {
                const Vec3d p(i * s, j * s, (k + 0.5) * s);
                all.push_back({p.head<2>().squaredNorm() + 1e-12 * k, p + Vec3d(jitter(), jitter(), jitter())});
            }
    std::stable_sort(all.begin(), all.end(), [](const P& a, const P& b) { return a.r2 < b.r2; });
    x.clear();
    V.clear();
    for (size_t i = 0; i < count && i < all.size(); ++i) {
        x.push_back(all[i].p.cast<Real>());
        V.push_back(Real(s * s * s));
    }
}

const char* name(Solver s) {
    switch (s) {
    case Solver::External: return "external";
    case Solver::Direct: return "direct";
    case Solver::Tree: return "tree";
    default: return "auto";
    }
}

/// --particles mode (see the file comment): field error per solver on a real particle set.
int particleFileBench(const std::string& path, const std::vector<double>& thetas, double tolerance,
                      double smoothing, bool localCorrection) {
    const ParticleTable t = readParticleFile(path);
    const std::vector<Vec3> x = t.vec3("x", "y", "z");
    const double mass = t.commentNumber("particle_mass", 0), rho0 = t.commentNumber("rest_density", 0);
    const double volume = mass > 0 && rho0 > 0 ? mass / rho0 : std::pow(t.commentNumber("spacing", 0), 3);
    const std::vector<Magnet> magnets = readMagnetComments(t);
    if (x.empty() || !(volume > 0) || magnets.empty()) {
        std::fprintf(stderr, "bench-magnetization: %s: needs particles, a spacing and magnets\n", path.c_str());
        return 2;
    }
    const std::vector<Real> V(x.size(), Real(volume));
    MagnetizationParams p;
    p.susceptibility = t.commentNumber("susceptibility", 1.5);
    p.saturation = t.commentNumber("saturation", 0);
    p.tolerance = tolerance;
    p.maxIterations = 100;
    p.smoothing = smoothing;
    p.localCorrection = localCorrection;
    p.solver = Solver::Direct;
    // Cost as CPU time of the process (run it with --threads 1): the machine may be shared,
    // and CPU seconds do not count the neighbours' share as wall seconds do.
    auto cpuMs = [](std::clock_t since) { return 1e3 * double(std::clock() - since) / CLOCKS_PER_SEC; };
    std::vector<Vec3> Hd, Md;
    std::clock_t c0 = std::clock();
    const auto sd = MagnetizationSolver(p).solve(x, V, magnets, Hd, Md);
    const double directMs = cpuMs(c0);
    std::printf("solver,opening_angle,particles,cpu_ms_per_solve,iterations,field_rms_err,field_max_err,reference\n");
    std::printf("direct,,%zu,%.2f,%d,0,0,direct\n", x.size(), directMs, sd.iterations);
    std::fflush(stdout);
    struct Run {
        Solver kind;
        double theta;
    };
    std::vector<Run> runs{{Solver::External, 0}};
    for (double th : thetas) runs.push_back({Solver::Tree, th});
    runs.push_back({Solver::Auto, MagnetizationParams{}.openingAngle});
    for (const Run& run : runs) {
        p.solver = run.kind;
        p.openingAngle = run.theta > 0 ? run.theta : MagnetizationParams{}.openingAngle;
        std::vector<Vec3> H, M;
        c0 = std::clock();
        const auto st = MagnetizationSolver(p).solve(x, V, magnets, H, M);
        const double ms = cpuMs(c0);
        double worst = 0;
        for (size_t i = 0; i < x.size(); ++i)
            worst = std::max(worst, double((H[i] - Hd[i]).norm() / std::max(Real(1e-30), Hd[i].norm())));
        char theta[32] = "";
        if (run.kind == Solver::Tree || run.kind == Solver::Auto) std::snprintf(theta, sizeof theta, "%g", p.openingAngle);
        std::printf("%s,%s,%zu,%.2f,%d,%.4g,%.4g,direct\n", run.kind == Solver::Auto ? (std::string("auto:") + name(st.solver)).c_str() : name(run.kind),
                    theta, x.size(), ms, st.iterations, ferro::test::relativeRms(H, Hd), worst);
        std::fflush(stdout);
    }
    return 0;
}

/// The fastest of `repeats` runs of timed() (each returns its own time): the machine may be
/// shared, and the same solve measured 30 % apart within one run; the minimum is the cost
/// without the interference.
template <class F>
double fastestOf(int repeats, F timed) {
    double best = timed();
    for (int k = 1; k < repeats; ++k) best = std::min(best, timed());
    return best;
}

/// The synthetic layer's table (the default run).
int layerBench(int threads, double theta, double tolerance, double smoothing, bool localCorrection,
               size_t directMax, int repeats, const std::vector<size_t>& sizes) {
    std::string sizeList;
    for (size_t n : sizes) sizeList += (sizeList.empty() ? "" : ",") + std::to_string(n);
    std::printf("bench-magnetization: fluid layer (8 x 1.24 mm) over a 2 A m^2 dipole, chi0 1.5, Ms 30 kA/m, "
                "%d threads, theta %g, tolerance %g, cold solves, particles: %s%s\n",
                threads, theta, tolerance, smoothing > 0 ? "smoothed dipoles" : "uniformly magnetized spheres",
                smoothing > 0 ? (localCorrection ? " with the local correction" : " without the local correction") : "");
    std::printf("reproduce: build/bin/bench-magnetization --threads %d --theta %g --tolerance %g --sizes %s "
                "--direct-max %zu --smoothing %g --local-correction %s --repeats %d\n\n",
                threads, theta, tolerance, sizeList.c_str(), directMax, smoothing, localCorrection ? "true" : "false",
                repeats);
    std::printf("%8s %-9s %-9s %11s %6s %10s %9s %9s %9s %9s\n", "N", "solver", "picked", "ms/solve", "evals",
                "ms/eval", "err H", "err M", "est.err", "speedup");

    Magnet magnet;
    magnet.kind = Magnet::Kind::Dipole;
    magnet.position = Vec3d(0, 0, -0.02);
    magnet.direction = Vec3d(0, 0, 1);
    magnet.strength = 2.0;
    magnet.softening = 1e-3;
    const std::vector<Magnet> magnets{magnet};

    for (size_t N : sizes) {
        std::vector<Vec3> x;
        std::vector<Real> V;
        dishLayer(N, x, V);
        MagnetizationParams p;
        p.susceptibility = 1.5;
        p.saturation = 3e4;
        p.tolerance = tolerance;
        p.openingAngle = theta;
        p.maxIterations = 100;
        p.smoothing = smoothing;
        p.localCorrection = localCorrection;

        std::vector<Vec3> Hd, Md;
        double directMs = 0;
        bool haveDirect = false;
        if (N <= directMax) {
            p.solver = Solver::Direct;
            MagnetizationSolver::Stats st;
            directMs = fastestOf(repeats, [&] {
                Hd.clear();
                Md.clear();
                st = MagnetizationSolver(p).solve(x, V, magnets, Hd, Md);
                return 1e3 * st.seconds;
            });
            haveDirect = true;
            std::printf("%8zu %-9s %-9s %11.1f %6d %10.2f %9s %9s %9.1e %9s\n", N, "direct", name(st.solver), directMs,
                        st.iterations, directMs / std::max(1, st.iterations), "ref", "ref", st.fieldError, "1");
            std::fflush(stdout);
        }
        for (Solver kind : {Solver::Tree, Solver::External, Solver::Auto}) {
            p.solver = kind;
            std::vector<Vec3> H, M;
            MagnetizationSolver::Stats st;
            std::unique_ptr<MagnetizationSolver> s; // the last repeat's, for the warm solve below
            const double ms = fastestOf(repeats, [&] {
                H.clear();   // cold: a solve warm-starts from the H and M it is given
                M.clear();
                s = std::make_unique<MagnetizationSolver>(p);
                st = s->solve(x, V, magnets, H, M);
                return 1e3 * st.seconds;
            });
            char errH[32] = "-", errM[32] = "-", speed[32] = "-";
            if (haveDirect) {
                std::snprintf(errH, sizeof errH, "%.2e", ferro::test::relativeRms(H, Hd));
                std::snprintf(errM, sizeof errM, "%.2e", ferro::test::relativeRms(M, Md));
                std::snprintf(speed, sizeof speed, "%.1f", directMs / ms);
            } else if (kind == Solver::Tree && !localCorrection) {
                // Direct estimated on a subset of targets (see the file comment). Not with the
                // local correction: its three extra evaluations per solve and its D_i M_i term
                // are in neither the all-pairs cost nor the all-pairs field, so the estimate
                // would count the correction as the tree's error.
                DipoleTree exact;
                exact.setSmoothing(smoothing);
                exact.build(x, V, 0.0);
                exact.setMagnetizationUnsorted(M);
                std::vector<uint32_t> targets;
                uint64_t state = 7;
                for (int q = 0; q < 2048; ++q) {
                    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
                    targets.push_back(uint32_t((state >> 33) % N));
                }
                Eigen::VectorXd Hs;
                const double sub = fastestOf(repeats, [&] {
                    const auto t0 = std::chrono::steady_clock::now();
                    exact.fieldAtParticlesDirect(targets, Hs);
                    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                });
                const double evalMs = 1e3 * sub * double(N) / double(targets.size());
                const double estDirectMs = evalMs * st.iterations;
                double d = 0, r = 0;
                for (size_t q = 0; q < targets.size(); ++q) {
                    const size_t i = exact.order()[targets[q]];
                    const Vec3d ref = magnetField(magnets, x[i].cast<double>()) + Hs.segment<3>(3 * q);
                    d += (H[i].cast<double>() - ref).squaredNorm();
                    r += ref.squaredNorm();
                }
                std::snprintf(errH, sizeof errH, "%.2e*", std::sqrt(d / r));
                std::snprintf(speed, sizeof speed, "%.1f*", estDirectMs / ms);
                std::printf("%8zu %-9s %-9s %10.0f* %6d %9.1f* %9s %9s %9s %9s\n", N, "direct", "estimated",
                            estDirectMs, st.iterations, evalMs, "ref", "ref", "-", "1");
            }
            std::printf("%8zu %-9s %-9s %11.1f %6d %10.2f %9s %9s %9.1e %9s\n", N, name(kind), name(st.solver), ms,
                        st.iterations, ms / std::max(1, st.iterations), errH, errM, st.fieldError, speed);
            std::fflush(stdout);
            if (kind != Solver::Tree) continue;
            // A simulation step later: the magnet 0.2 mm higher, warm start from this solution.
            std::vector<Magnet> moved = magnets;
            moved[0].position.z() += 2e-4;
            std::vector<Vec3> Hw = H, Mw = M;
            const auto sw = s->solve(x, V, moved, Hw, Mw);
            std::printf("%8zu %-9s %-9s %11.1f %6d %10.2f %9s %9s %9.1e %9s\n", N, "tree-warm", "tree",
                        1e3 * sw.seconds, sw.iterations, 1e3 * sw.seconds / std::max(1, sw.iterations), "-", "-",
                        sw.fieldError, "-");
            // Kelvin-force Jacobians: tree against exact all pairs.
            std::vector<Eigen::Matrix3f> Jt, Jd;
            const auto g0 = std::chrono::steady_clock::now();
            s->fieldGradient(x, V, magnets, M, Jt);
            const double gTree = std::chrono::duration<double>(std::chrono::steady_clock::now() - g0).count();
            if (N <= directMax) {
                MagnetizationParams pd = p;
                pd.solver = Solver::Direct;
                const auto g1 = std::chrono::steady_clock::now();
                MagnetizationSolver(pd).fieldGradient(x, V, magnets, M, Jd);
                const double gDirect = std::chrono::duration<double>(std::chrono::steady_clock::now() - g1).count();
                double d = 0, r = 0;
                for (size_t i = 0; i < N; ++i) {
                    d += (Jt[i] - Jd[i]).cast<double>().squaredNorm();
                    r += Jd[i].cast<double>().squaredNorm();
                }
                char e[32];
                std::snprintf(e, sizeof e, "%.2e", std::sqrt(d / r));
                std::printf("%8zu %-9s %-9s %11.1f %6s %10s %9s %9s %9s %9.1f\n", N, "gradient", "tree", 1e3 * gTree,
                            "1", "-", e, "-", "-", gDirect / gTree);
                std::printf("%8zu %-9s %-9s %11.1f %6s %10s %9s %9s %9s %9s\n", N, "gradient", "direct",
                            1e3 * gDirect, "1", "-", "ref", "-", "-", "1");
            } else {
                std::printf("%8zu %-9s %-9s %11.1f %6s %10s %9s %9s %9s %9s\n", N, "gradient", "tree", 1e3 * gTree,
                            "1", "-", "-", "-", "-", "-");
            }
            std::fflush(stdout);
        }
    }
    if (localCorrection && std::any_of(sizes.begin(), sizes.end(), [&](size_t n) { return n > directMax; }))
        std::printf("\nWith --local-correction true the direct solve is not estimated above --direct-max: raise it\n"
                    "to compare (the estimate leaves the correction out of both the cost and the field).\n");
    std::printf("\n* estimated: direct cost = all-pairs time on 2,048 targets x N/2,048 x the tree's evaluations;\n"
                "  tree error on those targets against H_ext + exact particle field of the tree's own M.\n"
                "err H, err M: relative RMS difference from the direct solution over all particles.\n"
                "speedup: direct ms/solve over this solver's ms/solve.\n"
                "ms/solve: the fastest of --repeats cold solves (tree-warm and gradient: one).\n"
                "tree-warm: the tree solve again with the magnet 0.2 mm higher, warm-started (a later step).\n"
                "gradient: fieldGradient (total-field Jacobians for the Kelvin force), tree vs all pairs;\n"
                "  err H column = relative RMS difference of the Jacobians, speedup column = direct / tree time.\n");
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    int threads = 2;
    double theta = 0.5, tolerance = 0.01, smoothing = MagnetizationParams{}.smoothing;
    size_t directMax = 40960;
    std::vector<size_t> sizes{10240, 40960, 163840};
    std::string particleFile;
    std::vector<double> thetas{0.3, 0.5, 0.8, 1.0};
    bool localCorrection = MagnetizationParams{}.localCorrection;
    int repeats = 3;
    CLI::App app{"bench-magnetization: cost and accuracy of the magnetization solvers on a ferrofluid layer over "
                 "a dipole (or on the particles of a ferro-sim file)"};
    addThreadsOption(app, threads, "worker threads (0 = all cores)");
    app.add_option("--theta", theta, "the tree's opening angle")->check(CLI::Range(0.05, 1.0));
    app.add_option("--tolerance", tolerance, "accepted relative field error (auto's choice)")->check(CLI::PositiveNumber);
    app.add_option("--smoothing", smoothing, "particle model: smoothed-dipole support in spacings (0 = spheres)")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--local-correction", localCorrection,
                   "the smoothed model's local correction, true or false (default: the simulation's default)");
    app.add_option("--repeats", repeats,
                   "layer bench: cold solves per timed row (direct, tree, external, auto, the estimate's "
                   "all-pairs pass), the fastest reported; --particles times one solve each")
        ->check(CLI::Range(1, 100));
    app.add_option("--direct-max", directMax, "largest size solved directly (above: estimated)");
    app.add_option("--sizes", sizes, "particle counts of the synthetic layer, comma-separated")->delimiter(',');
    app.add_option("--particles", particleFile, "bench on the particles of this ferro-sim file instead")
        ->check(CLI::ExistingFile);
    app.add_option("--thetas", thetas, "opening angles for --particles, comma-separated")->delimiter(',')->check(CLI::Range(0.05, 1.0));
    return runCommandLine("bench-magnetization", app, argc, argv, {}, [&] {
        for (size_t n : sizes)
            if (n < 64) throw ArgumentError("--sizes: at least 64 particles per size (got " + std::to_string(n) + ")");
        const auto limit = limitThreads(threads);
        if (!particleFile.empty()) return particleFileBench(particleFile, thetas, tolerance, smoothing, localCorrection);
        return layerBench(tbb::this_task_arena::max_concurrency(), theta, tolerance, smoothing, localCorrection, directMax, repeats, sizes);
    });
}

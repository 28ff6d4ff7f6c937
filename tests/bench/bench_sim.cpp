// bench-sim: cost of the SPH core on a 40,960-particle dam break (the paper's particle
// count), for each solver, with and without surface tension.
//
//   build/bin/bench-sim [--threads 2] [--seconds 0.1] [--warmup 0.05] [--solver all|wcsph|dfsph]
//                       [--tension all|off|akinci] [--sample 0.005] [--widen K]
//
// --widen K makes the block and the box K times as wide and as long (the same 40 layers
// deep): K x K x 40,960 particles (2: 163,840; 5: 1,024,000), for the cost as the work grows.
// Each row then also gives the cost per particle and step, the process's peak memory per
// particle, and the pressure sweep alone (one pressure-acceleration pass and one divergence
// pass, the body of a DFSPH iteration) timed on the state after the run: its time, the bytes
// it streams (neighbour indices and kernel gradients twice, the per-particle arrays) and
// the rate that makes, beside the machine's memory bandwidth (a STREAM-like triad over
// 3 x 256 MB, measured in the same run).
//
// Prints milliseconds per step, the mean solver iterations, wall seconds per simulated
// second (what a shot costs), how many steps one neighbour search lasts (WCSPH keeps
// a Verlet skin; DFSPH searches every step), and two density errors: the mean of what the
// solver reports per step (DFSPH: its final mean residual; WCSPH: the mean compression),
// and the mean compression max(0, rho / rho0 - 1) over the particles, read from the
// densities after the first step past every `--sample` seconds (how scripts/bench-peer.sh
// measures SPlisHSPlasH from its exported densities, so both codes are held to one measure).
// Only the steps are timed, not the sampling.
#include "sim/sph/FluidSimulation.hpp"
#include "sim/scene/SimSceneFile.hpp"

#include "sim/core/ParticleLoops.hpp"

#include <sys/resource.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

using namespace ferro;

namespace {

SimScene damBreak40k(const std::string& kind, double surfaceTension, const std::string& iteration = "jacobi",
                     double densityError = 0, int widen = 1) {
    SimScene s;
    s.path = "bench dam break";
    s.fluid.restDensity = 1000;
    s.fluid.viscosity = 1e-6;
    s.fluid.surfaceTension = surfaceTension;
    s.fluid.spacing = 0.0025;
    FluidBlock b;
    b.min = Vec3d(0, 0, 0);
    b.max = Vec3d(0.08 * widen, 0.08 * widen, 0.1);  // 32 x 32 x 40 = 40,960 particles (times widen^2)
    s.fluid.blocks.push_back(b);
    s.container.type = ContainerParams::Type::Box;
    s.container.min = Vec3d(0, 0, 0);
    s.container.max = Vec3d(0.32 * widen, 0.08 * widen, 0.2);
    s.solver.pressureSolver = kind;
    std::string keys = "pressure_iteration = \"" + iteration + "\"";
    if (densityError > 0) keys += "\nmax_density_error = " + formatNumber(densityError);
    s.solver.solverKeys = solverKeysFromText(keys, "bench dam break");
    return s;
}

/// Mean compression max(0, rho / rho0 - 1) over the fluid particles, from the densities of
/// the last neighbour update (the same lag as SPlisHSPlasH's exported densities: both are
/// the densities the last step started from).
double meanCompression(const FluidSimulation& sim) {
    double sum = 0;
    for (Real rho : sim.densities()) sum += std::max(0.0, double(rho) / sim.restDensity() - 1);
    return sum / double(std::max<size_t>(sim.size(), 1));
}

/// Peak resident memory of this process so far [bytes].
double peakMemory() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return 1024.0 * double(u.ru_maxrss);
}

/// Memory bandwidth [bytes/s]: a STREAM triad a = b + s c over three 256 MB arrays on the
/// bench's threads, best of 5 (24 bytes a element: two reads, one write).
double triadBandwidth() {
    const size_t n = size_t(32) << 20;
    std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
    double best = 0;
    for (int r = 0; r < 5; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        forEachParticle(n, [&](size_t i) { a[i] = b[i] + 3.0 * c[i]; });
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        best = std::max(best, 24.0 * double(n) / t);
    }
    if (a[n / 2] != 7.0) std::abort();  // keeps the loop
    return best;
}

struct SweepCost {
    double seconds = 0;  ///< one sweep
    double bytes = 0;    ///< streamed per sweep
};

/// The body of a DFSPH pressure iteration on the simulation's current neighbour lists: the
/// pressure accelerations of a pressure field, then their divergence per particle (the two
/// passes over the pair lists of DfsphSolver's relaxed Jacobi sweep), best of 10.
SweepCost timePressureSweep(FluidSimulation& sim) {
    const size_t n = sim.size();
    std::vector<Real> kappa(n), out(n);
    for (size_t i = 0; i < n; ++i) kappa[i] = Real(1e-3) * Real(i % 7);
    SweepCost cost;
    cost.seconds = 1e30;
    for (int r = 0; r < 10; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        sim.pressureAccelerations(kappa);
        forEachParticleBlock(n, [&](size_t begin, size_t end) {
            sim.pressureDivergence(begin, end, out.data());
            for (size_t i = begin; i < end; ++i) out[i] = kappa[i] - Real(0.5) * out[i];
        });
        cost.seconds = std::min(cost.seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    // Streamed: per pair (fluid and wall) its index and gradient factor in both passes; per
    // particle the lists' offset and count (both passes), kappa (read twice), the
    // accelerations (written plain and padded, the padded read) and the result (written). Gathers of neighbours'
    // kappa and acceleration are taken to hit the cache (particles are sorted in space).
    const double pairs = double(sim.fluidNeighbors().index.size() + sim.boundaryNeighbors().index.size());
    cost.bytes = 2 * pairs * (sizeof(uint32_t) + sizeof(Real)) +
                 double(n) * (2 * 2 * 2 * sizeof(uint32_t) + 2 * sizeof(Real) + sizeof(Vec3) + 2 * 4 * sizeof(Real) + sizeof(Real));
    return cost;
}

} // namespace

bool isPressureSolver(const std::string& name) {
    const std::vector<std::string> names = pressureSolverNames();
    return std::find(names.begin(), names.end(), name) != names.end();
}

int main(int argc, char** argv) {
    int threads = 2;
    double seconds = 0.1, warmup = 0.05;
    double sample = 0.005;
    std::string solver = "all", tension = "all", iteration = "jacobi";
    double densityError = 0;
    int widen = 1;
    const char* usage = "usage: bench-sim [--threads N] [--seconds S] [--warmup S] [--solver all|wcsph|dfsph] "
                        "[--tension all|off|akinci] [--sample S] [--pressure-iteration auto|jacobi|cg] [--density-error E] "
                        "[--widen K]\n";
    if (argc % 2 == 0) {
        std::fputs(usage, stderr);
        return 2;
    }
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--threads")) threads = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--seconds")) seconds = std::atof(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--warmup")) warmup = std::atof(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--solver")) solver = argv[i + 1];
        else if (!std::strcmp(argv[i], "--tension")) tension = argv[i + 1];
        else if (!std::strcmp(argv[i], "--sample")) sample = std::atof(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--pressure-iteration")) iteration = argv[i + 1];
        else if (!std::strcmp(argv[i], "--density-error")) densityError = std::atof(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--widen")) widen = std::atoi(argv[i + 1]);
        else {
            std::fputs(usage, stderr);
            return 2;
        }
    }
    if (threads < 1 || !(seconds > 0) || !(warmup >= 0) || !(sample > 0) ||
        (solver != "all" && !isPressureSolver(solver)) ||
        (tension != "all" && tension != "off" && tension != "akinci") || (iteration != "auto" && iteration != "jacobi" && iteration != "cg") ||
        !(densityError >= 0) || widen < 1 || widen > 8) {
        std::fprintf(stderr, "bench-sim: error: --threads >= 1, --seconds > 0, --warmup >= 0, --sample > 0, --solver all or a "
                             "registered solver (wcsph, dfsph), --tension all, off or akinci, --pressure-iteration auto, jacobi or cg, "
                             "--density-error >= 0, --widen 1 to 8\n");
        return 2;
    }
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    std::printf("bench-sim: %d-particle dam break, %d threads, %.3f simulated s after %g s warm-up, pressure sweeps %s\n",
                40960 * widen * widen, threads, seconds, warmup, pressureSweeps().instructionSet);
    std::printf("reproduce: build/bin/bench-sim --threads %d --seconds %g --warmup %g --solver %s --tension %s --sample %g "
                "--pressure-iteration %s --density-error %g --widen %d\n",
                threads, seconds, warmup, solver.c_str(), tension.c_str(), sample, iteration.c_str(), densityError, widen);
    {
        // The scene's derived settings, one parseable line (scripts/bench-peer.sh gives the
        // same ones to SPlisHSPlasH): viscosity is fluid plus artificial, c is WCSPH's sound speed.
        const FluidSimulation probe(damBreak40k("dfsph", 0.0, iteration, densityError, widen));
        const FluidSimulation wcsph(damBreak40k("wcsph", 0.0, iteration, densityError, widen));
        auto setting = [](const FluidSimulation& sim, const std::string& name) {
            for (const auto& [key, value] : sim.pressureSolverSettings())
                if (key == name) return value;
            throw std::logic_error("bench-sim: the solver has no setting " + name);
        };
        const SolverParams& sp = probe.scene().solver;
        std::printf("scene: particles=%zu spacing=%g support=%g rho0=%g nu=%.6g c=%.6g cfl=%g max_dt=%g "
                    "density_tol=%g divergence_tol=%g max_iterations=%d gravity=%g\n\n",
                    probe.size(), probe.spacing(), probe.supportRadius(), probe.restDensity(), probe.viscosity(),
                    setting(wcsph, "c"), sp.cfl, sp.maxDt, setting(probe, "density_tol"), setting(probe, "divergence_tol"),
                    int(setting(probe, "max_iterations")), sp.gravity.norm());
    }
    // The last two columns (added after the others, so that column positions stay) are
    // density errors in percent: the solver's own per-step figure and the sampled compression.
    std::printf("%-7s %-8s %8s %10s %10s %12s %10s %12s %9s %9s\n", "solver", "tension", "steps", "ms/step", "dt [ms]",
                "wall s/sim s", "iter p/d", "steps/search", "err %", "rho err %");
    for (const std::string& kind : pressureSolverNames()) {
        if (solver != "all" && kind != solver) continue;
        for (double sigma : {0.0, 0.072}) {
            if ((tension == "off" && sigma > 0) || (tension == "akinci" && sigma == 0)) continue;
            FluidSimulation sim(damBreak40k(kind, sigma, iteration, densityError, widen));
            sim.advanceTo(warmup);
            const size_t steps0 = sim.stepCount(), searches0 = sim.lastStep().searches;
            long iterP = 0, iterD = 0;
            double solverError = 0, sampledError = 0, wall = 0;
            int samples = 0;
            double nextSample = warmup + sample;
            while (sim.time() < warmup + seconds - 1e-12) {
                const auto t0 = std::chrono::steady_clock::now();
                sim.step(warmup + seconds - sim.time());
                wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                iterP += sim.lastStep().pressureIterations;
                iterD += sim.lastStep().divergenceIterations;
                solverError += sim.lastStep().densityError;
                if (sim.time() >= nextSample - 1e-12) {
                    sampledError += meanCompression(sim);
                    ++samples;
                    while (nextSample <= sim.time() + 1e-12) nextSample += sample;
                }
            }
            const size_t steps = sim.stepCount() - steps0;
            const size_t searches = sim.lastStep().searches - searches0;
            std::printf("%-7s %-8s %8zu %10.2f %10.3f %12.1f %5.1f/%.1f %12.1f %9.4f %9.4f\n",
                        sim.pressureSolverLabel(), sigma > 0 ? "Akinci" : "off", steps,
                        1e3 * wall / double(steps), 1e3 * seconds / double(steps), wall / seconds,
                        double(iterP) / double(steps), double(iterD) / double(steps),
                        double(steps) / double(std::max<size_t>(searches, 1)),
                        100 * solverError / double(steps), 100 * sampledError / double(std::max(samples, 1)));
            // The sweep needs the stored kernel gradients: DFSPH's lists have them, WCSPH's not.
            const SweepCost sweep = sim.fluidNeighbors().hasGradients() ? timePressureSweep(sim) : SweepCost{};
            const double n = double(sim.size());
            std::printf("cost: solver=%s tension=%s particles=%zu ns_per_particle_step=%.1f peak_bytes_per_particle=%.0f "
                        "sweep_ms=%.3f sweep_ns_per_particle=%.2f sweep_bytes_per_particle=%.0f sweep_gbytes_per_s=%.2f\n",
                        sim.pressureSolverLabel(), sigma > 0 ? "Akinci" : "off", sim.size(),
                        1e9 * wall / double(steps) / n, peakMemory() / n, 1e3 * sweep.seconds, 1e9 * sweep.seconds / n,
                        sweep.bytes / n, sweep.seconds > 0 ? sweep.bytes / sweep.seconds / 1e9 : 0.0);
        }
    }
    std::printf("memory bandwidth (triad, %d threads): %.2f GB/s\n", threads, triadBandwidth() / 1e9);
    return 0;
}

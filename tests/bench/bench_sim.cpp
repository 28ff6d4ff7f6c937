// bench-sim: cost of the SPH core on a 40,960-particle dam break (the paper's particle
// count), for each solver, with and without surface tension.
//
//   build/bin/bench-sim [--threads 2] [--seconds 0.1] [--warmup 0.05] [--solver all|wcsph|dfsph]
//
// Prints milliseconds per step, the mean solver iterations, wall seconds per simulated
// second (what a shot costs), and how many steps one neighbour search lasts (WCSPH keeps
// a Verlet skin; DFSPH searches every step).
#include "sim/sph/FluidSimulation.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

using namespace ferro;

namespace {

SimScene damBreak40k(const std::string& kind, double surfaceTension) {
    SimScene s;
    s.path = "bench dam break";
    s.fluid.restDensity = 1000;
    s.fluid.viscosity = 1e-6;
    s.fluid.surfaceTension = surfaceTension;
    s.fluid.spacing = 0.0025;
    FluidBlock b;
    b.min = Vec3d(0, 0, 0);
    b.max = Vec3d(0.08, 0.08, 0.1);  // 32 x 32 x 40 = 40,960 particles
    s.fluid.blocks.push_back(b);
    s.container.type = ContainerParams::Type::Box;
    s.container.min = Vec3d(0, 0, 0);
    s.container.max = Vec3d(0.32, 0.08, 0.2);
    s.solver.pressureSolver = kind;
    return s;
}

} // namespace

bool isPressureSolver(const std::string& name) {
    const std::vector<std::string> names = pressureSolverNames();
    return std::find(names.begin(), names.end(), name) != names.end();
}

int main(int argc, char** argv) {
    int threads = 2;
    double seconds = 0.1, warmup = 0.05;
    std::string solver = "all";
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--threads")) threads = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--seconds")) seconds = std::atof(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--warmup")) warmup = std::atof(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--solver")) solver = argv[i + 1];
        else {
            std::fprintf(stderr, "usage: bench-sim [--threads N] [--seconds S] [--warmup S] [--solver all|wcsph|dfsph]\n");
            return 2;
        }
    }
    if (threads < 1 || !(seconds > 0) || !(warmup >= 0) || (solver != "all" && !isPressureSolver(solver))) {
        std::fprintf(stderr, "bench-sim: error: --threads >= 1, --seconds > 0, --warmup >= 0, --solver all or a registered solver (wcsph, dfsph)\n");
        return 2;
    }
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    std::printf("bench-sim: 40,960-particle dam break, %d threads, %.3f simulated s after %g s warm-up\n",
                threads, seconds, warmup);
    std::printf("reproduce: build/bin/bench-sim --threads %d --seconds %g --warmup %g --solver %s\n\n", threads,
                seconds, warmup, solver.c_str());
    std::printf("%-7s %-8s %8s %10s %10s %12s %10s %12s\n", "solver", "tension", "steps", "ms/step", "dt [ms]",
                "wall s/sim s", "iter p/d", "steps/search");
    for (const std::string& kind : pressureSolverNames()) {
        if (solver != "all" && kind != solver) continue;
        for (double sigma : {0.0, 0.072}) {
            FluidSimulation sim(damBreak40k(kind, sigma));
            sim.advanceTo(warmup);
            const size_t steps0 = sim.stepCount(), searches0 = sim.lastStep().searches;
            long iterP = 0, iterD = 0;
            const auto t0 = std::chrono::steady_clock::now();
            while (sim.time() < warmup + seconds - 1e-12) {
                sim.step(warmup + seconds - sim.time());
                iterP += sim.lastStep().pressureIterations;
                iterD += sim.lastStep().divergenceIterations;
            }
            const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            const size_t steps = sim.stepCount() - steps0;
            const size_t searches = sim.lastStep().searches - searches0;
            std::printf("%-7s %-8s %8zu %10.2f %10.3f %12.1f %5.1f/%.1f %12.1f\n",
                        sim.pressureSolverLabel(), sigma > 0 ? "Akinci" : "off", steps,
                        1e3 * wall / double(steps), 1e3 * seconds / double(steps), wall / seconds,
                        double(iterP) / double(steps), double(iterD) / double(steps),
                        double(steps) / double(std::max<size_t>(searches, 1)));
        }
    }
    return 0;
}

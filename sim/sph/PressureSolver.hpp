#pragma once
// The pressure solver of an SPH step, behind one small interface.
//
// FluidSimulation owns the particles, the neighbour lists and the non-pressure forces; a
// PressureSolver turns them into the step's velocity change and pressures. The solvers
// are registered by name in sim/sph/PressureSolvers.cpp (the scene key `sim.solver`).
// Adding one is one file and one line:
//   1. sim/sph/MySolver.cpp: a class derived from PressureSolver and a factory
//      `std::unique_ptr<PressureSolver> makeMySolver(FluidSimulation&)`;
//   2. sim/sph/PressureSolvers.cpp: the factory's declaration and its row in the table.
// A solver reads and writes the fluid through FluidSimulation's solver interface (the
// section "For pressure solvers" of FluidSimulation.hpp).
#include "sim/core/Types.hpp"

#include <memory>
#include <string>
#include <vector>

namespace ferro {

class FluidSimulation;

class PressureSolver {
public:
    virtual ~PressureSolver() = default;

    /// Verlet skin of the neighbour search as a fraction of the kernel support: the search
    /// keeps every pair within (1 + skin) h and repeats only when the skin may be used up.
    /// 0 searches every step.
    virtual double neighborSkin() const { return 0.0; }
    /// true: the neighbour lists keep each pair's kernel gradient (for solvers that sweep
    /// the lists many times a step).
    virtual bool storesGradients() const { return false; }
    /// The solver's own bound on the time step [s] given the fastest particle's speed
    /// [m/s] (CFL); the simulation takes the smallest of all bounds.
    virtual double maxTimeStep(double maxSpeed) const = 0;
    /// One step of length dt [s]: adds the non-pressure and pressure accelerations to the
    /// velocities (the caller then moves the particles) and sets each particle's pressure.
    /// Fills the solver fields of the simulation's StepStats.
    virtual void advanceVelocities(double dt) = 0;
    /// Per-particle solver state follows the particles' re-sort (new index k = old order[k]).
    virtual void permute(const std::vector<uint32_t>& order) {}
    /// Forgets any warm start: called at every frame start and on setState, so that a
    /// run resumed from a frame file continues exactly like an uninterrupted one.
    virtual void resetWarmStart() {}
    /// The settings a run chose for this solver, for the start line (e.g. WCSPH's speed of
    /// sound); empty when there is nothing to say.
    virtual std::string settingsSummary() const { return {}; }
    /// One line of advice about the scene for this solver, printed after the start line
    /// (e.g. WCSPH under a strong magnet); empty when there is none.
    virtual std::string advice() const { return {}; }
};

/// One registered solver: its scene name (`sim.solver`), its label in progress lines and
/// benchmarks, and its factory.
struct PressureSolverEntry {
    const char* name;
    const char* label;
    std::unique_ptr<PressureSolver> (*make)(FluidSimulation& sim);
};

/// Every registered solver, in the order the scene file lists them.
const std::vector<PressureSolverEntry>& pressureSolvers();
/// The names of pressureSolvers(), for messages, benchmarks and tests.
std::vector<std::string> pressureSolverNames();
/// The entry called `name`; throws std::invalid_argument listing the names if none is.
const PressureSolverEntry& findPressureSolver(const std::string& name);

} // namespace ferro

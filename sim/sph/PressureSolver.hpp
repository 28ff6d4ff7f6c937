#pragma once
// The pressure solver of an SPH step, behind one small interface.
//
// FluidSimulation owns the particles, the neighbour lists and the non-pressure forces; a
// PressureSolver turns them into the step's velocity change and pressures. A solver owns its
// whole footprint: its [sim] keys (parsed by its registry row, from the keys the scene
// parser leaves to it: SolverParams::solverKeys), its settings, its state between steps and
// what its steps count. The solvers are registered by name in sim/sph/PressureSolvers.cpp
// (the scene key `sim.solver`). Adding one is one file and one line:
//   1. sim/sph/MySolver.cpp: a class derived from PressureSolver, its settings derived from
//      PressureSolverSettings, and two functions: `parseMySolverKeys(const TableReader& sim)`
//      reading its own [sim] keys, and `makeMySolver(FluidSimulation&, const
//      PressureSolverSettings&)`;
//   2. sim/sph/PressureSolvers.cpp: their declarations and the solver's row in the table.
// A solver reads and writes the fluid through FluidSimulation's solver interface (the
// section "For pressure solvers" of FluidSimulation.hpp).
#include "sim/core/Types.hpp"

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace ferro {

class FluidSimulation;
class TableReader;
struct SolverCapCount;
struct SolverParams;

/// A solver's own settings, read from its [sim] keys by its registry row (each solver
/// derives its own and casts back in its factory).
struct PressureSolverSettings {
    virtual ~PressureSolverSettings() = default;
};

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
    /// The pressure of each particle [Pa], sorted order: what the last step solved (zeros
    /// before the first). Every solver sets it; the frame files carry it.
    const std::vector<Real>& pressures() const { return pressure_; }
    /// Sets the pressures (a resumed run's, from a frame file's `pressure` column; zeros for
    /// a new one), in the particles' current order: a solver that warm-starts from them
    /// (DFSPH) then continues exactly as an uninterrupted run.
    void setPressures(std::vector<Real> p) { pressure_ = std::move(p); }
    /// The pressures and the solver's own per-particle state follow the particles' re-sort
    /// (new index k = old order[k]).
    void permute(const std::vector<uint32_t>& order);
    /// The solver's own per-particle state follows the re-sort (permute calls it).
    virtual void permuteState(const std::vector<uint32_t>& order) {}
    /// Forgets any warm start: called at every frame start and on setState, so that a
    /// run resumed from a frame file continues exactly like an uninterrupted one.
    virtual void resetWarmStart() {}
    /// The settings a run chose for this solver, for the start line (e.g. WCSPH's speed of
    /// sound); empty when there is nothing to say.
    virtual std::string settingsSummary() const { return {}; }
    /// The settings the run chose, by name ("c", "density_tol", ...): benchmarks print them
    /// and hand them to a peer solver (tests/bench/bench_sim.cpp, scripts/bench-peer.sh).
    virtual std::vector<std::pair<std::string, double>> settingValues() const { return {}; }
    /// One line of advice about the scene for this solver, printed after the start line
    /// (e.g. WCSPH under a strong magnet); empty when there is none.
    virtual std::string advice() const { return {}; }
    /// What a frame whose solves kept stopping at the iteration cap (`caps`, the frame's
    /// count) left, and which keys would help, in one line; empty for a solver with no cap.
    virtual std::string capWarning(const SolverCapCount& caps) const { return {}; }

protected:
    std::vector<Real> pressure_;   ///< pressures(): the solver writes them each step
};

/// One registered solver: its scene name (`sim.solver`), its label in progress lines and
/// benchmarks, the parser of its own [sim] keys and its factory.
struct PressureSolverEntry {
    const char* name;
    const char* label;
    /// Reads the solver's own keys from [sim] (a getter's default where a key is absent);
    /// throws SceneError on a bad value. The caller finish()es the reader.
    std::unique_ptr<PressureSolverSettings> (*parseKeys)(const TableReader& sim);
    /// The solver for `sim`, with the settings its parseKeys returned.
    std::unique_ptr<PressureSolver> (*make)(FluidSimulation& sim, const PressureSolverSettings& settings);
};

/// Every registered solver, in the order the scene file lists them.
const std::vector<PressureSolverEntry>& pressureSolvers();
/// The names of pressureSolvers(), for messages, benchmarks and tests.
std::vector<std::string> pressureSolverNames();
/// The entry called `name`; throws std::invalid_argument listing the names if none is.
const PressureSolverEntry& findPressureSolver(const std::string& name);
/// The entry of `p.pressureSolver`; throws SceneError naming sim.solver's line and the
/// registered names if there is none.
const PressureSolverEntry& chosenPressureSolver(const SolverParams& p, const std::string& scenePath);
/// The chosen solver's settings from its own keys in `p.solverKeys` (its defaults without
/// any). Every registered solver's keys are read and checked, so that a scene keeps its
/// keys for one solver while --set picks another; throws SceneError on a bad value or on a
/// [sim] key that neither the scene parser nor any solver reads.
std::unique_ptr<PressureSolverSettings> parsePressureSolverKeys(const SolverParams& p, const std::string& scenePath);

} // namespace ferro

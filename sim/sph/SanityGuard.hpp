#pragma once
// The physical sanity guard of ferro-sim, beside the NaN guard of integratePositions: a
// run that is still finite but no longer physical stops with a one-line SimulationError
// (exit 3, every frame written so far kept) instead of writing frames of an explosion.
//
// It stops when
// - a particle is faster than the scene can make it: the speed bound is the speed the
//   scene's energy sources could give one particle if all of it went into that one,
//       v_scene^2 = 2 g H + max |v0|^2 + (2 u_magnet)^2 + 2 mu0 F(H_max) / rho0 + v_cap^2,
//   g H the fall over the container's (or the fluid's) height, v0 the initial speeds, u
//   the magnets' fastest motion (a wall moving at u throws fluid at up to 2 u), F the
//   Langevin energy density of the largest field any particle has felt so far (the Kelvin
//   body force is mu0 grad F(H) / rho0, so mu0 F(H) / rho0 is the most a particle can gain
//   falling into the field), v_cap^2 = sigma / (rho0 spacing) the capillary speed; times
//   kSpeedSafety (below) or `sim.max_speed` when set;
// - particles are outside the container (constrain() never lets them out: a bug);
// - the time step stays near sim.min_dt for many steps in a row (the run would crawl for
//   hours before failing);
// - the magnetization solve hits its iteration cap without converging many times in a row.
// The last two count steps and solves in a row (StallGuard below), so they are tested as a
// unit with a made-up step history as well as through scenes.
#include "sim/core/Types.hpp"

#include <cstddef>
#include <string>

namespace ferro {

/// Thresholds of the guard. Named constants rather than scene keys: none of them should
/// need tuning; `sim.max_speed` overrides the derived speed bound for scenes that drive
/// the fluid by means the bound does not know.
struct SanityLimits {
    /// The derived speed bound is multiplied by this. The bound counts every energy source
    /// as if it all went into one particle, yet speeds can legitimately exceed the energy
    /// speed of the sources: a dam break's front runs at 2 sqrt(g H) (Ritter), 1.4x the free
    /// fall speed; a converging splash or a jet focuses the energy of many particles into a
    /// few. 5x the speed (25x the energy) leaves room for that. Measurements:
    /// docs/physics/sph-solver.md, "The sanity guard's speed bound".
    static constexpr double kSpeedSafety = 5;
    /// Floor of the speed bound [m/s]: a scene at rest (no gravity, no magnets) still has
    /// pressure noise; 0.1 m/s is far above that and far below an explosion.
    static constexpr double kMinSpeed = 0.1;
    /// A time step below kNearMinDt * sim.min_dt counts as stuck...
    static constexpr double kNearMinDt = 4;
    /// ... and this many stuck steps in a row stop the run: 1000 steps are a few seconds
    /// of wall time at a few hundred particles, and a step that small never recovers in
    /// practice (it is set by a force or speed that a physical scene does not have).
    static constexpr size_t kMaxStuckSteps = 1000;
    /// Magnetization solves in a row that end at their iteration cap without converging.
    /// A single one is reported on the progress line ("NOT CONVERGED") and the run goes
    /// on with the best iterate; this many in a row mean the field is wrong on every step.
    static constexpr size_t kMaxUnconvergedSolves = 50;
    /// A particle is outside when it is farther than this many spacings outside the
    /// container (constrain() lands exactly on the wall, up to float rounding).
    static constexpr double kOutsideTolerance = 0.01;
    /// Particles named in the "outside" message.
    static constexpr size_t kNamedParticles = 3;

    double speedOverride = 0;  ///< sim.max_speed [m/s]; 0 = derived
};

/// The speed bound's parts, so that progress lines and tests can show them.
struct SpeedBound {
    double gravity2 = 0;    ///< 2 g H [m^2/s^2]
    double initial2 = 0;    ///< max |v0|^2
    double magnets2 = 0;    ///< (2 u_magnet)^2
    double magnetic2 = 0;   ///< 2 mu0 F(H_max) / rho0
    double capillary2 = 0;  ///< sigma / (rho0 spacing)
    double override = 0;    ///< sim.max_speed, 0 = derived
    /// The bound [m/s]: the override, or kSpeedSafety * the root of the sum (at least kMinSpeed).
    double value() const;
    /// The same without the safety factor [m/s] (what the scene's energy could give).
    double energySpeed() const;
};

/// The guard's counters of a run that crawls or whose field is wrong on every step.
class StallGuard {
public:
    explicit StallGuard(double minDt) : minDt_(minDt) {}
    /// One step's stable time step [s]: what the scene allowed, before the step was
    /// shortened to land on a frame's end (a frame's short last step neither counts nor
    /// resets the count). Returns true when the run must stop: kMaxStuckSteps steps in a
    /// row below kNearMinDt * min_dt.
    bool recordStep(double stableDt) {
        stuck_ = stableDt < SanityLimits::kNearMinDt * minDt_ ? stuck_ + 1 : 0;
        return stuck_ >= SanityLimits::kMaxStuckSteps;
    }
    /// Steps in a row so far near min_dt.
    size_t stuckSteps() const { return stuck_; }
    /// True when the magnetization solves in a row that ended at their iteration cap
    /// unconverged are too many: the run must stop.
    static bool solverStalled(size_t unconvergedInRow) {
        return unconvergedInRow >= SanityLimits::kMaxUnconvergedSolves;
    }

private:
    double minDt_;
    size_t stuck_ = 0;
};

} // namespace ferro

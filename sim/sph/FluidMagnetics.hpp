#pragma once
// The magnetic part of a ferro-sim step: the magnets at the current time, the fluid's
// magnetization (paper eq. 5 with Langevin saturation) and the Kelvin body force
// mu0 (M . grad) H (paper eqs. 9-11).
//
// What it models, and what it leaves out on purpose:
// - The field at a particle is H = H_magnets(x) + H_induced, the induced part being the
//   field of every other magnetized particle. H_magnets is analytic and re-evaluated every
//   step (O(N) per magnet); H_induced needs the O(N^2) / O(N log N) self-consistent solve of
//   MagnetizationSolver, and changes far more slowly than the SPH step, so it is cached and
//   re-solved only when it has drifted enough to matter: each solve measures how far the
//   cached field had drifted, as the error it put into the Kelvin acceleration relative to
//   the accelerations driving the fluid (gravity, the Kelvin force itself), and sets the
//   next interval so that error stays under magnetization.tolerance (or every
//   magnetization.resolve_every steps). A fast change of the magnets re-solves at once.
//   Between solves M follows the Langevin law locally from the current total field.
// - grad H is the analytic Jacobian of the magnets' field. The particles' own field enters
//   the force through M (demagnetization lowers it), but its gradient does not by default:
//   at a free surface that gradient is the magnetic normal traction mu0 M_n^2 / 2, which
//   SPH with gauge pressure (no atmosphere, no tension) cannot balance, so surface
//   particles lift off, the levitation artifact of particle Kelvin forces; the surface
//   instability it drives is what ferro-spikes synthesizes. magnetization.induced_force
//   adds it as the SPH difference gradient sum_j V (H_ind_j - H_ind_i) (x) grad W_ij.
// - The force per unit mass is mu0 (J M) / rho0: the rest volume m / rho0 of a particle,
//   not its SPH density, whose deficit at the free surface would inflate the force there.
// - A scene without magnets constructs nothing and costs nothing; magnets with a
//   non-magnetic fluid (susceptibility 0) only report the applied field.
#include "sim/magnetics/MagnetField.hpp"
#include "sim/sph/NeighborSearch.hpp"
#include "sim/scene/SimParams.hpp"

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

namespace ferro {

class MagnetizationSolver;

/// Counters for the progress line.
struct MagneticsStats {
    size_t steps = 0;        ///< steps with an active field since the last reset
    size_t solves = 0;       ///< full self-consistent solves among them
    std::string solver;      ///< the solver the last solve used ("external", "direct", "tree")
    int iterations = 0;      ///< iterations of the last solve
    double estimatedError = 0; ///< the last solve's estimated relative field error
    bool converged = true;     ///< every solve since the reset reached its tolerance
    double residual = 0;       ///< largest relative residual of the solves since the reset
    double cacheError = 0;   ///< measured error the cached field had reached, as RMS Kelvin
                             ///< acceleration error relative to gravity / the Kelvin force
};

class FluidMagnetics {
public:
    /// `particleVolume` [m^3] is the rest volume m / rho0 of one fluid particle.
    FluidMagnetics(const SimScene& scene, double particleVolume, double spacing);
    ~FluidMagnetics();

    /// True when the scene has magnets; otherwise nothing here is ever called per step.
    bool active() const { return !tracks_.empty(); }
    /// True when the fluid magnetizes (susceptibility > 0) and feels a force.
    bool magnetic() const { return law_.enabled(); }

    /// The magnets at time t [s], as the scene gives them.
    std::vector<Magnet> magnetsAt(double t) const;
    /// The same with every softening raised to at least one particle spacing: the field
    /// the particles feel (see the .cpp for why).
    std::vector<Magnet> softenedMagnetsAt(double t) const;

    /// Brings H, M and the Kelvin acceleration up to date for particles at `x` (current
    /// sorted order, with their fluid neighbour lists) at time t: applied field
    /// re-evaluated, the induced field re-solved when stale (always when `forceSolve`),
    /// M from the Langevin law, then mu0 (J M) / rho0 per particle.
    void update(double t, const std::vector<Vec3>& x, const NeighborLists& fluidNeighbors, bool forceSolve);
    /// Adds the Kelvin acceleration [m/s^2] of the last update to `a` (current order).
    void addKelvinAcceleration(std::vector<Vec3>& a) const;
    /// Largest Kelvin acceleration of the last update [m/s^2] (for the time step).
    double maxAcceleration() const { return maxAcceleration_; }
    /// Kelvin accelerations of the last update, current order.
    const std::vector<Vec3>& kelvinAcceleration() const { return kelvin_; }

    /// Reorders the cached per-particle state with the simulation's particles.
    void permute(const std::vector<uint32_t>& order);
    /// Total field H [A/m] and magnetization M [A/m] in the current order (empty if inactive).
    const std::vector<Vec3>& field() const { return H_; }
    const std::vector<Vec3>& magnetization() const { return M_; }
    /// Warm start for a resumed run: H and M in the current order.
    void setState(const std::vector<Vec3>& H, const std::vector<Vec3>& M);

    /// Steps one solve of the induced field may currently serve (the measured re-solve
    /// interval); carried in the particle files so that a resumed run re-solves on the
    /// same steps as an uninterrupted one.
    size_t resolveInterval() const { return interval_; }
    void setResolveInterval(size_t steps) { interval_ = std::clamp<size_t>(steps, 1, kMaxInterval); }

    const MagneticsStats& stats() const { return stats_; }
    void resetCounters() {
        stats_.steps = 0;
        stats_.solves = 0;
        stats_.converged = true;
        stats_.residual = 0;
    }
    const MagnetizationParams& law() const { return law_; }

private:
    bool solveIsStale() const;
    void solve(const std::vector<Vec3>& x, bool forced);
    void applyLaw();
    void computeKelvin(const std::vector<Vec3>& x, const NeighborLists& nbr);

    std::vector<MagnetTrack> tracks_;
    MagnetizationParams law_;
    double volume_ = 0, spacing_ = 0, rho0_ = 0, gravity_ = 0;
    std::unique_ptr<MagnetizationSolver> solver_;
    std::vector<Magnet> magnets_;            // at the time of the last update
    std::vector<Vec3> Hext_, Hind_, H_, M_;  // per particle, current order
    std::vector<Vec3> kelvin_;               // Kelvin acceleration per particle [m/s^2]
    double maxAcceleration_ = 0;
    std::vector<Vec3> HextSolved_;           // applied field at the last solve, current order
    static constexpr size_t kMaxInterval = 200;
    size_t interval_ = 1;                    // steps a solve may serve (measured, see solve())
    double inducedShare_ = 0;                // rms |H_ind| / rms |H| at the last solve
    double kelvinShare_ = 1;                 // rms Kelvin acceleration / (its max with gravity)
    double extSolved2_ = 0;                  // sum |H_ext|^2 at the last solve
    double extNow2_ = 0;                     // sum |H_ext|^2 this step (between solves)
    double inducedScale_ = 1;                // rms |H_ext| now / at the last solve
    double lastFieldError_ = 0;              // the last solve's estimated relative field error
    size_t stepsSinceSolve_ = 0;
    bool solved_ = false;
    MagneticsStats stats_;
};

} // namespace ferro

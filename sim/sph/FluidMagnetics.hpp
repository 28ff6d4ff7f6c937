#pragma once
// The magnetic part of a ferro-sim step: the magnets at the current time, the fluid's
// magnetization (paper eq. 5 with Langevin saturation) and the magnetic force (paper eqs.
// 9-11).
// - H = H_magnets (analytic, every step) + H_induced (MagnetizationSolver's self-consistent
//   solve, cached: far dearer than a step and slower to change). Each solve measures the
//   error the cache had reached in the Kelvin acceleration, relative to gravity and the
//   Kelvin force, and sets the next interval to keep it under magnetization.tolerance (or
//   every magnetization.resolve_every steps); a fast change of the magnets re-solves at once.
//   Between solves M follows the Langevin law from the current total field.
// - magnetization.force = "body" (default): mu0 (J_magnets M) / rho0 per unit mass, rho0 the
//   rest density (the SPH density's surface deficit would inflate it). With `external` M is
//   the Langevin law of H_magnets, exactly mu0 grad F(|H_magnets|) / rho0; with a
//   self-consistent solver M is the DemagnetizationCurve M_f(|H_magnets|) fitted at each
//   solve to the free surface's F(H) + M_n^2 / 2 (surfaceSamples, leaning on the last fit:
//   kCurveMemory), so the force stays a gradient (a pool can rest) and a resting surface
//   obeys the ferrohydrostatic Bernoulli law rho g z_s = mu0 (F(H) + M_n^2 / 2) + C.
// - magnetization.force = "surface" (experimental): the total field's Kelvin force taken
//   into the pressure, a push p_s = C - mu0 (F(H) + M_n^2 / 2) along the colour gradient of
//   surface particles, C the largest mu0 (F + M_n^2 / 2) of the sure ones (w >= 1/2): the
//   fluid is pushed, never pulled. Its discrete push is not a potential force, so it stays off by default.
// - A scene without magnets constructs nothing; with a non-magnetic fluid (susceptibility 0)
//   the field is only reported.
// Derivations and measurements: docs/physics/magnetization.md, "The force in the step".
#include "sim/magnetics/DemagnetizationCurve.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/spatial/NeighborSearch.hpp"
#include "sim/sph/FreeSurface.hpp"
#include "sim/scene/SimParams.hpp"

#include <algorithm>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ferro {

class MagnetizationSolver;
class SolidCoupling;

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
    size_t solidPanels = 0;  ///< panels of the magnetized solids (0: none)
    int solidIterations = 0; ///< GMRES applications of the solids' last charge solve
    double solidSeconds = 0; ///< time spent on the solids since the reset [s]
    bool solidConverged = true; ///< every charge solve since the reset reached its tolerance
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

    /// The free surface as FluidSimulation sees it (a neighbour sweep, computed only when
    /// asked for): per particle the colour gradient grad c_i [1/m] (fluid and walls, so a
    /// wetted wall is no surface) and the exposure in [0, 1] (1 when no fluid neighbour
    /// stands in the outward cone: Marrone et al. 2010's scan region). Current order.
    struct SurfaceView {
        const std::vector<Vec3>* colorGradient = nullptr;
        const std::vector<Real>* exposure = nullptr;
    };
    using SurfaceProbe = std::function<SurfaceView()>;

    /// Brings H, M and the magnetic acceleration up to date for particles at `x` (current
    /// sorted order) at time t: applied field re-evaluated, the induced field re-solved
    /// when stale (always when `forceSolve`), M from the Langevin law, then the force of
    /// the model (see above). `surface` is called at most once a step, and only when used:
    /// after a self-consistent solve with magnetization.curve_fit = "free_surface" (the
    /// curve's samples, surfaceSamples()) and every step for force = "surface"; an empty
    /// probe, or one returning empty vectors, means no surface is known.
    void update(double t, const std::vector<Vec3>& x, const SurfaceProbe& surface, bool forceSolve);
    /// Surface weight w in [0, 1] of a particle from its colour gradient |grad c| [1/m].
    double surfaceWeight(double gradient) const;
    /// Adds the magnetic acceleration [m/s^2] of the last update to `a` (current order).
    void addKelvinAcceleration(std::vector<Vec3>& a) const;
    /// Largest Kelvin acceleration of the last update [m/s^2] (for the time step).
    double maxAcceleration() const { return maxAcceleration_; }
    /// Largest |H| [A/m] any particle has felt so far (applied or total field): the
    /// magnetic energy the sanity guard allows for.
    double maxFieldSeen() const { return maxFieldSeen_; }
    /// Self-consistent solves in a row that ended at their iteration cap unconverged.
    size_t unconvergedInRow() const { return unconvergedInRow_; }
    /// Kelvin accelerations of the last update, current order.
    const std::vector<Vec3>& kelvinAcceleration() const { return kelvin_; }
    /// The magnetization the body force uses (fitted at the last self-consistent solve).
    const DemagnetizationCurve& demagnetizationCurve() const { return curve_; }

    /// Reorders the cached per-particle state with the simulation's particles.
    void permute(const std::vector<uint32_t>& order);
    /// Total field H [A/m] and magnetization M [A/m] in the current order (empty if inactive).
    const std::vector<Vec3>& field() const { return H_; }
    const std::vector<Vec3>& magnetization() const { return M_; }
    /// Warm start for a resumed run: H and M in the current order. Forgets the curve's
    /// memory (the next fit starts afresh) unless setCurveMemory() follows.
    void setState(const std::vector<Vec3>& H, const std::vector<Vec3>& M);

    /// Steps one solve of the induced field may currently serve (the measured re-solve
    /// interval); carried in the particle files so that a resumed run re-solves on the
    /// same steps as an uninterrupted one.
    size_t resolveInterval() const { return interval_; }
    void setResolveInterval(size_t steps) { interval_ = std::clamp<size_t>(steps, 1, kMaxInterval); }
    /// The free-surface curve (magnetization.curve_fit = "free_surface") and the time [s] of
    /// its last fit: each fit leans on the last one (the curve's memory, see solve()), so a
    /// resumed run carries both in the particle files to continue exactly.
    struct CurveMemory {
        DemagnetizationCurve::SurfaceFit fit;
        double time = 0;
    };
    std::optional<CurveMemory> curveMemory() const;
    /// Restores a curve read from a particle file; ignored when it is not a valid curve.
    void setCurveMemory(const CurveMemory& c);

    const MagneticsStats& stats() const { return stats_; }
    void resetCounters() {
        stats_.steps = 0;
        stats_.solves = 0;
        stats_.converged = true;
        stats_.residual = 0;
        stats_.solidSeconds = 0;
        stats_.solidConverged = true;
    }
    const MagnetizationParams& law() const { return law_; }
    /// The scene's magnetized solids (null without [[solids]]): their charge and field.
    const SolidCoupling* solids() const { return solids_.get(); }

private:
    bool solveIsStale() const;
    void solve(const std::vector<Vec3>& x, const std::function<SurfaceView()>& surface, bool forced);
    /// The Bernoulli law's magnetic side at particle i's surface point, half a spacing out
    /// from `x` along the unit `outward` normal: the applied field's strength there [A/m],
    /// F(H) and M_n^2 / 2 [A^2/m^2] with H = applied + the particle's induced field, M its
    /// Langevin law. Shared by the surface model and the free-surface curve fit.
    struct SurfacePoint {
        double applied = 0, energy = 0, traction = 0;
    };
    SurfacePoint surfacePoint(size_t i, const Vec3& x, const Vec3d& outward) const;
    /// The DemagnetizationCurve's samples: the free surface's magnetic pressure (see solve()).
    std::vector<DemagnetizationCurve::SurfaceSample> surfaceSamples(const std::vector<Vec3>& x, const SurfaceView& view) const;
    void applyLaw();
    void computeKelvin(const std::vector<Vec3>& x, const std::function<SurfaceView()>& surface);
    /// The applied field's Jacobian at particle i: the magnets' at x plus the solids' cached one.
    Mat3d appliedGradient(size_t i, const Vec3& x) const;
    /// Solves the solids' charge and their field at x (SolidCoupling), M the fluid's (empty:
    /// none); `cold` at a frame's first solve (see SolidCoupling::update).
    void updateSolids(const std::vector<Vec3>& x, const std::vector<Vec3>& M, bool cold);
    void computeBodyForce(const std::vector<Vec3>& x);
    void computeSurfacePressure(const std::vector<Vec3>& x, const std::vector<Vec3>& colorGradient,
                                const std::vector<Real>& exposure);

    std::vector<MagnetTrack> tracks_;
    MagnetizationParams law_;
    double volume_ = 0, spacing_ = 0, rho0_ = 0, gravity_ = 0;
    std::unique_ptr<MagnetizationSolver> solver_;
    std::unique_ptr<SolidCoupling> solids_;  // [[solids]] (null without)
    std::vector<Vec3> Hsol_;                 // the solids' field at each particle, evaluated every step
    std::vector<Eigen::Matrix3f> Jsol_;      // and its Jacobian
    std::vector<Magnet> magnets_;            // at the time of the last update
    std::vector<Vec3> Hext_, Hind_, H_, M_;  // per particle, current order
    std::vector<Vec3> kelvin_;               // Kelvin acceleration per particle [m/s^2]
    double maxAcceleration_ = 0;
    double maxFieldSeen_ = 0;
    size_t unconvergedInRow_ = 0;
    bool traction_ = true;                   // the last solve had the particles' own field
    DemagnetizationCurve curve_;             // M along H_magnets against |H_magnets|, fitted at each solve
    FlatSurface flat_;                       // surface model: the flat lattice surface's weight and kappa
    std::vector<Vec3> HextSolved_;           // applied field at the last solve, current order
    static constexpr size_t kMaxInterval = 200;
    // The free-surface curve's memory [s]: the time over which its fits average the surface,
    // whose particles shuffle between solves (without it a resting pool sloshed). The price:
    // after a change of the field the curve lags by about this time. Measurements:
    // docs/physics/magnetization.md, "The free-surface curve fit".
    static constexpr double kCurveMemory = 0.1;
    size_t interval_ = 1;                    // steps a solve may serve (measured, see solve())
    double inducedShare_ = 0;                // rms |H_ind| / rms |H| at the last solve
    double kelvinShare_ = 1;                 // rms Kelvin acceleration / (its max with gravity)
    double extSolved2_ = 0;                  // sum |H_ext|^2 at the last solve
    double extNow2_ = 0;                     // sum |H_ext|^2 this step (between solves)
    double inducedScale_ = 1;                // rms |H_ext| now / at the last solve
    double lastFieldError_ = 0;              // the last solve's estimated relative field error
    size_t stepsSinceSolve_ = 0;
    double time_ = 0;                        // of the last update [s]
    double curveFitTime_ = 0;                // of the curve's last free-surface fit [s]
    bool solved_ = false;
    MagneticsStats stats_;
};

} // namespace ferro

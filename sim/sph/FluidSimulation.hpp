#pragma once
// The SPH fluid solver of ferro-sim: weakly compressible SPH (Becker & Teschner 2007,
// the paper's kind of solver) and divergence-free SPH (Bender & Koschier 2017) for
// larger steps, with Akinci 2012 boundary particles, viscosity, Akinci 2013 surface
// tension, gravity and a CFL-adaptive time step.
//
// Particles live in (cell, id) order, re-sorted at every neighbour search (every DFSPH
// step; WCSPH keeps a Verlet skin and searches when it is used up) and at every frame
// start; ids are stable and all exported data is in id order. A frame is a pure function
// of the state at its start (no parallel floating-point reductions whose order varies),
// so runs are repeatable and resume bit-for-bit from a frame file.
#include "sim/geometry/Container.hpp"
#include "sim/sph/FluidSeed.hpp"
#include "sim/sph/FluidMagnetics.hpp"
#include "sim/sph/forces/PairForces.hpp"
#include "sim/sph/ImplicitViscosity.hpp"
#include "sim/sph/Kernel.hpp"
#include "sim/sph/MagnetObstacles.hpp"
#include "sim/spatial/NeighborSearch.hpp"
#include "sim/spatial/PeriodicDomain.hpp"
#include "sim/sph/PressureSolver.hpp"
#include "sim/sph/SanityGuard.hpp"
#include "sim/sph/sweeps/PressureSweeps.hpp"
#include "sim/scene/SimParams.hpp"

#include <algorithm>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

namespace ferro {

/// The run cannot continue (non-finite state, collapsed time step). what() is one line.
class SimulationError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// What bounded a step's length (FluidSimulation::chooseTimeStep): sim.max_dt, the pressure
/// solver's CFL bound, the capillary bound, the body-force criterion, the explicit viscous
/// bound; the step shortened to land on a frame's end is counted by the bound it would have had.
enum class TimeStepBound { MaxDt, Cfl, Capillary, BodyForce, Viscous, Count };
/// Short names for the progress line, in TimeStepBound order.
inline const char* timeStepBoundName(TimeStepBound b) {
    static const char* const names[] = {"max_dt", "cfl", "capillary", "force", "viscous"};
    return names[int(b)];
}

/// Counters of the most recent step, for progress lines and benchmarks.
struct StepStats {
    double dt = 0;
    TimeStepBound dtBound = TimeStepBound::MaxDt; ///< what bounded the step (chooseTimeStep)
    int pressureIterations = 0;
    int divergenceIterations = 0;
    double densityError = 0;     ///< mean relative compression after the step's solve
    size_t neighborPairs = 0;    ///< fluid-fluid pairs closer than the kernel support
    size_t candidatePairs = 0;   ///< fluid-fluid pairs of the last search (support plus skin)
    size_t searches = 0;         ///< neighbour searches so far
    int viscosityIterations = 0; ///< implicit viscosity: CG iterations of the step (0 when explicit)
    double viscosityResidual = 0;///< implicit viscosity: relative residual the solve ended at
    double divergenceError = 0;  ///< DFSPH: mean relative compression per step the divergence solve left
    bool densityAtCap = false;   ///< the density solve stopped at sim.max_iterations above its tolerance
    bool densityByCg = false;    ///< DFSPH: the density solve ran conjugate gradients (sim.pressure_iteration)
    bool divergenceAtCap = false;///< the divergence solve stopped at sim.max_iterations above its tolerance
};

/// How often the pressure solver stopped at its iteration cap (sim.max_iterations) with
/// its error still above the tolerance, over a span of steps (a frame, a run): never
/// silent, the progress line, the frame file's header and the closing line show it. Also
/// the span's iterations, the density solves that ran CG and what bounded each step, for
/// the progress line.
struct SolverCapCount {
    size_t steps = 0;             ///< steps counted
    size_t densityAtCap = 0;      ///< steps whose density solve ended at the cap
    size_t divergenceAtCap = 0;   ///< steps whose divergence solve ended at the cap
    double densityError = 0;      ///< largest mean relative compression a capped density solve left
    double divergenceError = 0;   ///< largest mean relative compression per step a capped divergence solve left
    size_t densityByCg = 0;       ///< steps whose density solve ran conjugate gradients
    size_t dtBounds[int(TimeStepBound::Count)] = {}; ///< steps each bound bounded
    size_t pressureIterations = 0;   ///< density solve iterations, summed over the steps
    size_t divergenceIterations = 0; ///< divergence solve iterations, summed over the steps
    void add(const StepStats& s);
    size_t atCap() const { return std::max(densityAtCap, divergenceAtCap); }
};

class FluidSimulation {
public:
    explicit FluidSimulation(const SimScene& scene);
    ~FluidSimulation();

    size_t size() const { return x_.size(); }
    double time() const { return time_; }
    double spacing() const { return spacing_; }
    double supportRadius() const { return h_; }
    double particleMass() const { return mass_; }
    double restDensity() const { return rho0_; }
    const SimScene& scene() const { return scene_; }
    const Container& container() const { return *container_; }
    const StepStats& lastStep() const { return stats_; }
    /// Steps that ended at the solver's iteration cap since the current frame started
    /// (advanceTo resets it) and since the simulation was made.
    const SolverCapCount& frameSolverCaps() const { return frameCaps_; }
    const SolverCapCount& runSolverCaps() const { return runCaps_; }
    size_t stepCount() const { return steps_; }
    /// The scene's flow speed scale U [m/s]: the fastest of a fall through the fluid's height
    /// above the container floor, the initial speeds and the capillary speed. It sets the
    /// artificial viscosity alpha h U and WCSPH's default speed of sound.
    double expectedSpeed() const { return expectedSpeed_; }
    double particleVolume() const { return volume_; }   ///< V = m / rho0 [m^3]
    /// The kinematic viscosity the fluid pairs use: fluid.viscosity plus the artificial
    /// viscosity alpha h U [m^2/s].
    double viscosity() const { return viscosity_; }
    /// true: viscosity is solved implicitly (fluid.viscosity_method, "auto" resolved).
    bool implicitViscosity() const { return implicitViscosity_ != nullptr; }
    /// The viscosity model's explicit step limit [s] (1e30 without viscosity; standard:
    /// StandardViscosity::kExplicitStep h^2 / nu); it bounds the step only when viscosity is
    /// explicit.
    double explicitViscousTimeStep() const;
    /// The pressure solver's label ("DFSPH", "WCSPH"), for progress lines and benchmarks.
    const char* pressureSolverLabel() const { return solverEntry_->label; }
    /// The label and, in parentheses, the settings the solver chose (PressureSolver::settingsSummary).
    std::string pressureSolverSummary() const;
    /// The pressure solver's advice about this scene (PressureSolver::advice), or empty.
    std::string pressureSolverAdvice() const;
    /// The settings the pressure solver chose, by name (PressureSolver::settingValues).
    std::vector<std::pair<std::string, double>> pressureSolverSettings() const { return solver_->settingValues(); }
    /// The pressure solver's line on a frame that kept stopping at its cap (PressureSolver::capWarning).
    std::string pressureSolverCapWarning(const SolverCapCount& caps) const { return solver_->capWarning(caps); }
    /// The speed [m/s] of a fall through the magnets' largest energy difference over the
    /// places the fluid can reach during the shot (its fill and the walls' fluid side, a
    /// sample a frame, at most 256): sqrt(2 mu0 max dF / rho0) with F(H) = int M dH, the
    /// Langevin energy of the magnets' softened field; 0 without magnets or magnetization.
    /// The body force's potential for `external` magnetization; an upper bound with a
    /// self-consistent solve (the particles' own field lowers M). Fluid that leaves the
    /// fill's region without a container is not counted. Behind WCSPH's sound-speed advice
    /// (docs/physics/sph-solver.md).
    double magneticFallSpeed() const;
    /// The sanity guard's speed bound as of the last step (sim/sph/SanityGuard.hpp).
    const SpeedBound& speedBound() const { return speedBound_; }
    /// Largest particle speed so far over the scene's energy speed (the guard stops at
    /// SanityLimits::kSpeedSafety), for the closing line and tests.
    double maxSpeedRatio() const { return maxSpeedRatio_; }
    /// The sanity checks of a frame's end (speed, particles inside the container); throws
    /// SimulationError. advanceTo calls it; the speed is also checked at every step.
    void checkSanity();

    /// Advances to exactly `tEnd` with as many steps as the CFL condition needs; the last
    /// step is shortened to land on tEnd. Throws SimulationError on a non-finite state.
    void advanceTo(double tEnd);
    /// One step of at most `dtLimit` seconds; returns the step taken.
    double step(double dtLimit);

    /// Per-particle data in id order (the order of the initial fill and of every file).
    std::vector<Vec3> positionsById() const;
    std::vector<Vec3> velocitiesById() const;
    std::vector<Real> densitiesById() const;   ///< kg/m^3, as of the last neighbour update
    std::vector<Real> pressuresById() const;   ///< Pa, from the last pressure solve
    /// Total field H and magnetization M [A/m] as of the last step (zero without magnets).
    std::vector<Vec3> fieldById() const;
    std::vector<Vec3> magnetizationById() const;
    /// Replaces the state (resume): time, positions, velocities and pressures (handed to the
    /// pressure solver, PressureSolver::setPressures; empty = zeros) in id order, and
    /// optionally H and M (the magnetization solve's warm start; may be empty).
    void setState(double time, const std::vector<Vec3>& xById, const std::vector<Vec3>& vById,
                  const std::vector<Real>& pById, const std::vector<Vec3>& HById = {},
                  const std::vector<Vec3>& MById = {});
    /// The magnetic part of the step; nullptr when the scene has no magnets.
    const FluidMagnetics* magnetics() const { return magnetics_.get(); }
    void resetMagneticsCounters() { if (magnetics_) magnetics_->resetCounters(); }
    /// The magnetization re-solve interval (see FluidMagnetics), 0 without magnetics.
    size_t magnetizationInterval() const { return magnetics_ ? magnetics_->resolveInterval() : 0; }
    void setMagnetizationInterval(size_t steps) { if (magnetics_ && steps > 0) magnetics_->setResolveInterval(steps); }
    /// The force's free-surface curve and the time of its last fit (see FluidMagnetics), none
    /// without one; carried in the particle files for an exact resume.
    std::optional<FluidMagnetics::CurveMemory> magnetizationCurve() const {
        return magnetics_ ? magnetics_->curveMemory() : std::nullopt;
    }
    void setMagnetizationCurve(const FluidMagnetics::CurveMemory& c) { if (magnetics_) magnetics_->setCurveMemory(c); }
    /// The magnets at the current time as the particles feel them (softened over at least
    /// one spacing; empty without magnets).
    std::vector<Magnet> magnetsNow() const;

    // Sorted-order access for diagnostics and tests.
    const std::vector<Vec3>& positions() const { return x_; }
    /// The periodic sides (inactive unless container.periodic_sides): pair offsets x_i - x_j
    /// and x_i - x_b must go through periodic().offset().
    const PeriodicDomain& periodic() const { return periodic_; }
    const std::vector<Vec3>& velocities() const { return v_; }
    const std::vector<Real>& densities() const { return rho_; }
    const std::vector<Real>& pressures() const { return solver_->pressures(); }  ///< the pressure solver's [Pa]
    const std::vector<Vec3>& boundaryPositions() const { return bx_; }

    // --- For pressure solvers (sim/sph/PressureSolver.hpp): the state they advance and the
    // SPH operators they share, in sorted order.

    /// Wall pressure (Akinci 2012): a wall particle pushes a fluid particle with the fluid
    /// particle's own pressure, p_i / rho_i^2 (not the symmetric pair sum): a mirrored 2 p_i
    /// fed energy into a resting tank's corners. Measurements: docs/physics/sph-solver.md,
    /// "Walls".
    static constexpr Real kWallMirror = 1;

    std::vector<Vec3>& solverVelocities() { return v_; }
    const std::vector<Vec3>& accelerations() const { return a_; }
    const NeighborLists& fluidNeighbors() const { return fluidNbr_; }
    const NeighborLists& boundaryNeighbors() const { return boundaryNbr_; }
    const std::vector<Real>& boundaryVolumes() const { return bVolume_; }
    StepStats& solverStats() { return stats_; }
    /// accelerations() = gravity + viscosity + surface tension + Kelvin force, plus the
    /// pressure force when `pOverRho2` (p / rho^2 per particle) is given: one sweep of the
    /// lists, four pairs at a time.
    void computeAccelerations(const Real* pOverRho2);
    /// accelerations() = the pressure accelerations of kappa = p / (rho^2) normalized by
    /// rho0 (Bender & Koschier 2017), walls included; needs stored gradients.
    void pressureAccelerations(const std::vector<Real>& kappa);
    /// out[i] = sum_j V (u_i - u_j) . grad W_ij + sum_b V_b u_i . grad W_ib for i in [begin,
    /// end): D(rho/rho0)/Dt [1/s] for u = velocities, the density change pressure
    /// accelerations cause for u = a. Needs stored gradients. The sweep of
    /// sim/sph/sweeps/PressureSweeps.hpp, for one block of particles.
    void divergence(const std::vector<Vec3>& u, size_t begin, size_t end, Real* out) const;
    /// The same for every particle, out resized to the particle count.
    void divergence(const std::vector<Vec3>& u, std::vector<Real>& out) const;
    /// divergence() of the accelerations the last pressureAccelerations() computed, from
    /// their padded copy (the pressure iterations' sweep: four aligned loads a pair).
    void pressureDivergence(size_t begin, size_t end, Real* out) const;
    void pressureDivergence(std::vector<Real>& out) const;
    /// The arrays the pressure sweeps read (sim/sph/sweeps): positions, the stored pair
    /// lists and the walls, valid until the next step.
    PressureSweepInput sweepInput() const;
    /// With implicit viscosity, solves (I + dt L) v_new = v for the current velocities
    /// (Weiler 2018; sim/sph/ImplicitViscosity.hpp) and records the iterations in the
    /// stats; does nothing when viscosity is explicit (the force sweep has added it).
    /// Solvers call it after adding the non-pressure accelerations.
    void applyImplicitViscosity(double dt);
    /// Removes the velocity into a magnet's body of each particle that this step's move
    /// would take into it (MagnetObstacles.hpp), so that the pressure solve after it
    /// predicts the positions the body constraint will allow. Solvers call it after the
    /// non-pressure accelerations (and implicit viscosity), before the pressure solve.
    void stopMotionIntoMagnetBodies(double dt);
    /// The viscous operator of the current state (for the implicit solve and for tests).
    ViscosityOperatorInput viscosityOperator() const;

private:
    // Construction, in order: the solver (it decides the neighbour search), the walls'
    // boundary particles, the speed scales (the flow speed scale, artificial viscosity),
    // the pair-force models (viscosity, surface tension) and how viscosity is applied.
    void createPressureSolver();
    void sampleBoundary();
    void chooseSpeedScales();
    void setUpPairForces();
    /// The walls' friction viscosity [m^2/s], for the explicit sweep and the implicit solve
    /// alike: container.wall_friction scales the physical viscosity only (not the artificial).
    double wallViscosity() const { return scene_.fluid.viscosity * scene_.container.wallFriction; }
    /// fluid.viscosity_method: "auto" takes the implicit solve when the explicit viscous
    /// limit would be shorter than the step the scene takes otherwise.
    void chooseViscosityMethod();
    /// Brings the neighbour lists and densities up to date with the positions: a new
    /// search (particle sort, candidates within support plus skin) when `forceSearch` or
    /// when the skin may be used up, then this step's neighbours among the candidates.
    void refreshNeighbors(bool forceSearch);
    void searchCandidates();
    void updateNeighbors();
    /// The colour gradient the magnetic surface force needs (when it does), then the
    /// magnetic update of the step.
    void updateMagnetics(bool forceSolve);
    /// colorGradient_ and exposure_ of the current positions (FluidMagnetics::SurfaceView).
    void computeSurfaceView();
    /// The step: the smallest of the solver's, the force, capillary and viscous limits and
    /// sim.max_dt (`stable`, when given), then shortened to land on dtLimit.
    double chooseTimeStep(double dtLimit, double speed, double* stable = nullptr, TimeStepBound* bound = nullptr) const;
    double maxSpeed(size_t* which = nullptr) const;
    /// The speed bound's parts that do not change during the run (gravity over the
    /// container's height, initial speeds, the magnets' motion, capillary speed).
    void setUpSanityGuard();
    /// Stops the run when particle `which` at `speed` is beyond the speed bound.
    void checkSpeed(double speed, size_t which);
    void integratePositions(double dt);

    SimScene scene_;
    std::unique_ptr<Container> container_;
    PeriodicDomain periodic_;                    // container.periodic_sides (inactive otherwise)
    /// Calls f(q) for p and for each periodic image of p within `reach` of the other side
    /// (the queries a neighbour search makes across the glued faces).
    template <class F>
    void forEachImageQuery(const Vec3& p, Real reach, F&& f) const {
        f(p);
        if (!periodic_.active()) return;
        Real sx[2], sy[2];
        int nx = 0, ny = 0;
        sx[nx++] = 0;
        sy[ny++] = 0;
        if (periodic_.period[0] > 0) {
            if (p.x() - periodic_.lo[0] < reach) sx[nx++] = periodic_.period[0];
            else if (periodic_.lo[0] + periodic_.period[0] - p.x() < reach) sx[nx++] = -periodic_.period[0];
        }
        if (periodic_.period[1] > 0) {
            if (p.y() - periodic_.lo[1] < reach) sy[ny++] = periodic_.period[1];
            else if (periodic_.lo[1] + periodic_.period[1] - p.y() < reach) sy[ny++] = -periodic_.period[1];
        }
        for (int b = 0; b < ny; ++b)
            for (int a = 0; a < nx; ++a)
                if (a || b) f(Vec3(p.x() + sx[a], p.y() + sy[b], p.z()));
    }
    std::unique_ptr<FluidMagnetics> magnetics_;  // only when the scene has magnets
    const PressureSolverEntry* solverEntry_ = nullptr;
    std::unique_ptr<PressureSolver> solver_;
    bool frameStart_ = true;                     // the next step starts a frame: re-solve M
    CubicSplineKernel kernel_;
    double spacing_ = 0, h_ = 0, mass_ = 0, volume_ = 0, rho0_ = 0;
    double viscosity_ = 0;   // physical plus artificial kinematic viscosity [m^2/s]
    double expectedSpeed_ = 0; // the flow speed scale U of chooseSpeedScales [m/s]
    std::unique_ptr<ImplicitViscosity> implicitViscosity_; // only with implicit viscosity
    std::unique_ptr<PairForces> pairForces_;     // the force sweep's viscosity and tension models
    double time_ = 0;
    size_t steps_ = 0;
    StepStats stats_;
    SolverCapCount frameCaps_, runCaps_;
    SanityLimits limits_;
    SpeedBound speedBound_;
    double maxSpeedRatio_ = 0;
    StallGuard stall_{0};       // steps in a row with dt near sim.min_dt
    double magnetSpeed_ = 0;    // the magnets' fastest motion between keys [m/s] (their bodies push at most this fast)

    // Fluid particles, sorted by (cell, id).
    std::vector<Vec3> x_, v_, a_, xOld_;
    std::vector<Real> rho_;
    std::vector<Vec3> colorGradient_;         // grad c (fluid and walls), for the magnetics, on demand
    std::vector<Real> exposure_;              // exposure of the surface (1 = open), with colorGradient_
    std::vector<uint32_t> id_;
    std::vector<uint16_t> boundaryCount_;
    SortedGrid grid_;
    NeighborLists fluidNbr_, boundaryNbr_;
    std::vector<uint32_t> fluidCandidates_, boundaryCandidates_; // slots of the last search
    std::vector<Vec3> xSearch_;               // positions at the last search
    size_t searchStep_ = size_t(-1);          // step count at the last search
    double skin_ = 0;                         // Verlet skin [m]; 0 = search every step
    bool storeGradients_ = true;              // keep grad W per pair (the solver asks for it)
    std::vector<Real> px_, py_, pz_;          // coordinates again, split (kept current) for the
                                              // search and the four-pair loops
    struct alignas(16) Float4 {
        float v[4];
    };
    std::vector<Float4> p4_;                  // positions again, padded (kept current), for
                                              // the pressure sweeps (sim/sph/sweeps)
    std::vector<Float4> a4_;                  // the last pressure accelerations, padded
    void setPadded(size_t i) { p4_[i] = Float4{{x_[i].x(), x_[i].y(), x_[i].z(), 0.0f}}; }
    std::vector<uint32_t> scratch_, bScratch_; // fixed-capacity candidate lists of a search
    std::vector<uint32_t> order_;
    size_t capacity_ = 64, bCapacity_ = 32;

    // Boundary particles (static) with Akinci volumes.
    std::vector<Vec3> bx_;
    std::vector<Real> bVolume_;
    std::vector<Real> bpx_, bpy_, bpz_;
    SortedGrid bGrid_;
};

} // namespace ferro

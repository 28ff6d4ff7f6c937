// FluidSimulation (see FluidSimulation.hpp): construction (solver, walls, speed scales, pair
// forces, viscosity method), the time step, stepping and the state in id order.
#include "sim/sph/FluidSimulation.hpp"

#include "sim/core/Constants.hpp"
#include "sim/core/ParticleLoops.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnetics/MagnetizationSolver.hpp"
#include "sim/magnets/LangevinLaw.hpp"
#include "sim/magnets/MagnetKinds.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ferro {

FluidSimulation::FluidSimulation(const SimScene& scene)
    : scene_(scene) {
    const std::vector<SolidWall> walls = solidWalls(scene_);
    checkSolids(scene_, walls);
    container_ = makeContainerWithSolids(scene_.container, walls, scene_.path);
    FluidSeed seed = seedFluid(scene_, *container_, walls);
    spacing_ = seed.spacing;
    h_ = 2 * spacing_;
    kernel_ = CubicSplineKernel(Real(h_));
    rho0_ = scene_.fluid.restDensity;

    // Particle volume: the inverse kernel sum of a full cubic lattice, so that a particle
    // inside the initial block sits exactly at rest density (no start-up jolt).
    double lattice = 0;
    for (int k = -2; k <= 2; ++k)
        for (int j = -2; j <= 2; ++j)
            for (int i = -2; i <= 2; ++i)
                lattice += kernel_.W(Real(spacing_ * std::sqrt(double(i * i + j * j + k * k))));
    volume_ = 1.0 / lattice;
    mass_ = rho0_ * volume_;

    x_ = std::move(seed.positions);
    v_ = std::move(seed.velocities);
    const size_t n = x_.size();
    id_.resize(n);
    for (size_t i = 0; i < n; ++i) id_[i] = uint32_t(i);
    a_.assign(n, Vec3::Zero());
    rho_.assign(n, Real(rho0_));

    createPressureSolver();
    solver_->setPressures(std::vector<Real>(n, Real(0)));
    if (scene_.container.type == ContainerParams::Type::Box && scene_.container.periodicSides) {
        periodic_ = PeriodicDomain::horizontal(scene_.container.min.cast<Real>(), scene_.container.max.cast<Real>());
        // One image of a neighbour at most (PeriodicDomain's contract), with room to spare.
        const double least = 2 * (h_ + skin_) + 4 * spacing_;
        for (int a = 0; a < 2; ++a)
            if (!(periodic_.period[a] > least))
                throw SceneError(scene_.path + ": container.periodic_sides: the box must be wider than " +
                                 std::to_string(least) + " m (2 supports + skin + 4 spacings) in x and y");
        // Only a field that repeats with the box is periodic: one with a position (a dipole,
        // bar, loop or coil) would jump at the glued faces (and its body would be cut by them).
        for (size_t m = 0; m < scene_.magnets.size(); ++m)
            if (magnetKindInfo(scene_.magnets[m].base.kind).positioned)
                throw SceneError(scene_.path + ": container.periodic_sides: magnets[" + std::to_string(m) + "] is a " +
                                 magnetKindInfo(scene_.magnets[m].base.kind).name +
                                 "; periodic sides take uniform fields only (a source's field does not repeat with the box)");
        // The seed must lie in one period: a block past a glued face would overlap itself.
        for (const Vec3& p : x_)
            for (int a = 0; a < 2; ++a)
                if (!(p[a] >= periodic_.lo[a] && p[a] < periodic_.lo[a] + periodic_.period[a]))
                    throw SceneError(scene_.path + ": container.periodic_sides: fluid outside the box in " +
                                     (a ? "y" : "x") + " (particle at " + std::to_string(p[a]) +
                                     " m): a block must lie within min and max, or it overlaps its periodic copy");
    }
    sampleBoundary();
    chooseSpeedScales();
    setUpPairForces();
    chooseViscosityMethod();

    if (!scene_.magnets.empty()) magnetics_ = std::make_unique<FluidMagnetics>(scene_, volume_, spacing_);
    setUpSanityGuard();

    refreshNeighbors(true);
    // The field of the initial state, so that frame 0 carries H and M too.
    if (magnetics_) updateMagnetics(true);
}

void FluidSimulation::createPressureSolver() {
    // The pressure solver says how it sweeps the neighbour lists: DFSPH sweeps them a
    // dozen times a step and keeps each pair's kernel gradient (so does the induced Kelvin
    // force); WCSPH sweeps them once and takes small steps, so it evaluates the kernel in
    // its sweep and searches only when a Verlet skin is used up.
    solverEntry_ = &chosenPressureSolver(scene_.solver, scene_.path);
    solver_ = solverEntry_->make(*this, *parsePressureSolverKeys(scene_.solver, scene_.path));
    storeGradients_ = solver_->storesGradients();
    skin_ = solver_->neighborSkin() * h_;
}

void FluidSimulation::sampleBoundary() {
    // Boundary particles and their Akinci volumes V_b = 1 / sum_k W_bk.
    bx_ = container_->sampleWalls(spacing_, 0.5 * spacing_);
    {
        std::vector<uint32_t> tie(bx_.size()), order;
        for (size_t i = 0; i < tie.size(); ++i) tie[i] = uint32_t(i);
        // Cells as wide as the search radius: the 3 x 3 x 3 stencil then holds every
        // candidate (the Akinci volumes below test r < h themselves).
        bGrid_.sort(bx_, tie, Real(h_ + skin_), order);
        std::vector<Vec3> sorted(bx_.size());
        for (size_t k = 0; k < order.size(); ++k) sorted[k] = bx_[order[k]];
        bx_.swap(sorted);
        bGrid_.index(bx_, bGrid_.geometry());
        splitCoordinates(bx_, bpx_, bpy_, bpz_);
    }
    // Akinci's volume 1 / sum_k W_bk adapts to how densely a wall is sampled. Scaled by
    // V * P0 (P0: the kernel sum of a square lattice plane at this spacing), a flat wall
    // sampled at the fluid spacing gets exactly the fluid particle volume V: the wall layer
    // then stands in for the mirror image of the first fluid layer, and fluid half a
    // spacing from the wall is at rest density.
    double plane = 0;
    for (int j = -2; j <= 2; ++j)
        for (int i = -2; i <= 2; ++i) plane += kernel_.W(Real(spacing_ * std::sqrt(double(i * i + j * j))));
    const Real wallScale = Real(volume_ * plane);
    bVolume_.assign(bx_.size(), 0);
    const Real h2 = Real(h_ * h_);
    forEachParticle(bx_.size(), [&](size_t b) {
        Real sum = 0;
        forEachImageQuery(bx_[b], Real(h_), [&](const Vec3& q) {
            bGrid_.forEachCandidateRange(q, [&](uint32_t beg, uint32_t end) {
                for (uint32_t k = beg; k < end; ++k) {
                    const Real r2 = (q - bx_[k]).squaredNorm();
                    if (r2 < h2) sum += kernel_.W(std::sqrt(r2));
                }
            });
        });
        bVolume_[b] = wallScale / sum;
    });
}

void FluidSimulation::chooseSpeedScales() {
    // The flow speed scale U: the free-fall speed over the fluid's height above the
    // container floor, or the initial speed, or the capillary speed (WCSPH's default sound
    // speed is ten times it).
    const Vec3d g = scene_.solver.gravity;
    const double gNorm = g.norm();
    double vExpected = std::sqrt(std::max(0.0, scene_.fluid.surfaceTension) / (rho0_ * spacing_));
    if (gNorm > 0) {
        const Vec3d down = g / gNorm;
        Vec3d lo, hi;
        container_->bounds(lo, hi);
        double top = -1e300, bottom = 1e300;
        for (const Vec3& p : x_) {
            top = std::max(top, -p.cast<double>().dot(down));
            bottom = std::min(bottom, -p.cast<double>().dot(down));
        }
        if (scene_.container.type != ContainerParams::Type::None) {
            // The lowest corner of the container along gravity.
            for (int c = 0; c < 8; ++c) {
                const Vec3d corner((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
                bottom = std::min(bottom, std::max(-corner.dot(down), bottom - 10 * (top - bottom)));
            }
        }
        vExpected = std::max(vExpected, std::sqrt(2 * gNorm * std::max(top - bottom, spacing_)));
    }
    for (const Vec3& v : v_) vExpected = std::max(vExpected, double(v.norm()));
    viscosity_ = scene_.fluid.viscosity + scene_.solver.artificialViscosity * h_ * std::max(vExpected, 0.01);
    expectedSpeed_ = vExpected;
}

std::string FluidSimulation::pressureSolverSummary() const {
    const std::string settings = solver_->settingsSummary();
    return settings.empty() ? std::string(pressureSolverLabel()) : std::string(pressureSolverLabel()) + " (" + settings + ")";
}

std::string FluidSimulation::pressureSolverAdvice() const { return solver_->advice(); }

double FluidSimulation::magneticFallSpeed() const {
    if (!magnetics_ || !magnetics_->magnetic()) return 0;
    const MagnetizationParams& law = magnetics_->law();
    // Where the fluid can be: its fill, and the walls' fluid side (samples half a spacing
    // in from each wall, where the first fluid layer's centres sit; the boundary particles
    // lie as far inside the solid, closer to a magnet under the floor than any fluid gets).
    // Each is thinned to at most kPoints: the largest field is at a wall or in the fill, and
    // a few thousand samples find it. The field is the one FluidMagnetics applies
    // (softenedMagnetsAt: softened over at least a spacing, bounded inside the bodies).
    constexpr size_t kPoints = 8192;
    std::vector<Vec3d> points;
    const auto addThinned = [&points](const std::vector<Vec3>& from) {
        const size_t stride = std::max<size_t>(1, (from.size() + kPoints - 1) / kPoints);
        for (size_t i = 0; i < from.size(); i += stride) points.push_back(from[i].cast<double>());
    };
    addThinned(x_);
    if (scene_.container.type != ContainerParams::Type::None) {
        std::vector<Vec3> fluidSide;
        for (const Vec3& p : container_->sampleWalls(spacing_, -0.5 * spacing_))
            if (container_->contains(p.cast<double>(), 0)) fluidSide.push_back(p);
        addThinned(fluidSide);
    }
    if (points.empty()) return 0;
    // Over the shot, a sample a frame (at most kTimes): the largest energy difference across
    // those points at one time, which is what the fluid's pressure may have to hold.
    constexpr int kTimes = 256;
    const int times = std::clamp(scene_.shot.frameCount(), 1, kTimes);
    double head = 0;
    for (int k = 0; k <= times; ++k) {
        const std::vector<Magnet> magnets = magnetics_->softenedMagnetsAt(scene_.shot.duration * k / times);
        using Range = std::pair<double, double>;
        const Range range = tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, points.size()), Range{1e300, 0.0},
            [&](const tbb::blocked_range<size_t>& r, Range acc) {
                for (size_t i = r.begin(); i != r.end(); ++i) {
                    const double F = langevinEnergy(magnetField(magnets, points[i]).norm(), law.susceptibility, law.saturation);
                    acc = {std::min(acc.first, F), std::max(acc.second, F)};
                }
                return acc;
            },
            [](Range a, Range b) { return Range{std::min(a.first, b.first), std::max(a.second, b.second)}; });
        head = std::max(head, range.second - range.first);
    }
    return std::sqrt(2 * kMu0 * head / rho0_);
}

double FluidSimulation::explicitViscousTimeStep() const { return pairForces_->viscousStepLimit(); }

void FluidSimulation::chooseViscosityMethod() {
    // Decided once, from the scene alone (the initial fill's speed scale), so that a resumed
    // run takes the same path. Auto: the step the scene takes without viscosity, at the
    // expected flow speed, against the explicit viscous limit.
    using Method = FluidParams::ViscosityMethod;
    bool implicit = scene_.fluid.viscosityMethod == Method::Implicit;
    if (scene_.fluid.viscosityMethod == Method::Auto) {
        const double otherStep =
            std::min({scene_.solver.maxDt, solver_->maxTimeStep(expectedSpeed_), pairForces_->tensionStepLimit()});
        // The implicit solve inverts the standard operator only: other models stay explicit.
        implicit = explicitViscousTimeStep() < otherStep && pairForces_->viscosityHasImplicitSolve();
    }
    if (implicit && !pairForces_->viscosityHasImplicitSolve())
        throw SceneError(scene_.path + ": fluid.viscosity_method: \"implicit\" solves the \"standard\" viscosity model only (fluid.viscosity_model is \"" +
                         scene_.fluid.viscosityModel + "\")");
    if (implicit && viscosity_ > 0) {
        ImplicitViscositySettings settings;
        settings.tolerance = scene_.solver.viscosityTolerance;
        settings.maxIterations = scene_.solver.viscosityMaxIterations;
        implicitViscosity_ = std::make_unique<ImplicitViscosity>(settings);
        pairForces_->setViscosityInSweep(false);
    }
}

ViscosityOperatorInput FluidSimulation::viscosityOperator() const {
    ViscosityOperatorInput in;
    in.positions = &x_;
    in.densities = &rho_;
    in.fluidNeighbors = &fluidNbr_;
    in.boundaryNeighbors = &boundaryNbr_;
    in.boundaryPositions = &bx_;
    in.boundaryVolumes = &bVolume_;
    in.kernel = kernel_;
    in.periodic = periodic_;
    in.supportRadius = h_;
    in.particleMass = mass_;
    in.restDensity = rho0_;
    in.viscosity = viscosity_;
    in.wallViscosity = wallViscosity();
    return in;
}

void FluidSimulation::applyImplicitViscosity(double dt) {
    if (!implicitViscosity_) return;
    implicitViscosity_->setUp(viscosityOperator(), dt);
    const ImplicitViscosityResult result = implicitViscosity_->solve(v_);
    stats_.viscosityIterations = result.iterations;
    stats_.viscosityResidual = result.relativeResidual;
}

void FluidSimulation::stopMotionIntoMagnetBodies(double dt) {
    if (scene_.magnets.empty()) return;
    const std::vector<MagnetObstacle> bodies =
        magnetObstacles(scene_.magnets, time_ + dt, dt, 0.5 * spacing_, magnetSpeed_);
    if (bodies.empty()) return;
    forEachParticle(x_.size(), [&](size_t i) {
        for (const MagnetObstacle& body : bodies) stopMotionInto(body, x_[i], v_[i], dt);
    });
}

void FluidSimulation::setUpPairForces() {
    PairForceSetup setup;
    setup.scene = &scene_;
    setup.spacing = spacing_;
    setup.support = h_;
    setup.restDensity = rho0_;
    setup.volume = volume_;
    setup.viscosity = viscosity_;
    setup.wallViscosity = wallViscosity();
    pairForces_ = makePairForces(setup);
}

FluidSimulation::~FluidSimulation() = default;


double FluidSimulation::maxSpeed(size_t* which) const {
    const size_t n = x_.size();
    const Real vmax = largestOf(n, Real(0), [&](size_t i) { return v_[i].squaredNorm(); });
    if (which) {
        *which = 0;
        for (size_t i = 0; i < n; ++i)
            if (v_[i].squaredNorm() == vmax) {
                *which = i;
                break;
            }
    }
    return std::sqrt(double(vmax));
}

double FluidSimulation::chooseTimeStep(double dtLimit, double speed, double* stable, TimeStepBound* bound) const {
    // Force criterion (Monaghan 1992): dt <= 0.25 sqrt(h / |a|), h the smoothing length,
    // half the cubic spline's support (the spacing here): the body force moves a particle
    // at most a dt^2 = spacing / 16 in a step before pressure answers; a strong Kelvin force
    // near a magnet pole binds it, gravity alone never does. Measurements (1/8 spacing kept
    // a pool from resting): docs/physics/sph-solver.md, "The time step's force criterion".
    // Gravity and the Kelvin force are known at the step's start, so the step stays a pure
    // function of the state (exact resume).
    const double amax = scene_.solver.gravity.norm() + (magnetics_ ? magnetics_->maxAcceleration() : 0.0);
    const SolverParams& sp = scene_.solver;
    double dt = sp.maxDt;
    TimeStepBound by = TimeStepBound::MaxDt;
    auto bind = [&](double limit, TimeStepBound which) {
        if (limit < dt) {
            dt = limit;
            by = which;
        }
    };
    bind(solver_->maxTimeStep(speed), TimeStepBound::Cfl);
    bind(pairForces_->tensionStepLimit(), TimeStepBound::Capillary);
    if (amax > 0) bind(0.25 * std::sqrt(0.5 * h_ / amax), TimeStepBound::BodyForce);
    if (!implicitViscosity_) bind(explicitViscousTimeStep(), TimeStepBound::Viscous);
    if (bound) *bound = by;
    if (dt < sp.minDt) {
        std::ostringstream msg;
        msg.precision(3);
        msg << "time step " << dt << " s fell below sim.min_dt = " << sp.minDt << " s at t = " << time_
            << " s (max speed " << speed << " m/s): the simulation is unstable";
        throw SimulationError(msg.str());
    }
    if (stable) *stable = dt;
    // Land exactly on the limit (a frame time) without leaving a sliver of a step.
    if (dt >= dtLimit) return dtLimit;
    if (2 * dt > dtLimit) return 0.5 * dtLimit;
    return dt;
}


void FluidSimulation::integratePositions(double dt) {
    const size_t n = x_.size();
    xOld_ = x_;
    std::atomic<size_t> bad{size_t(-1)};
    const Real rdt = Real(dt);
    // The magnets' bodies at the step's end (MagnetObstacles.hpp): solids the fluid keeps
    // half a spacing off; none without magnets.
    const std::vector<MagnetObstacle> bodies =
        scene_.magnets.empty() ? std::vector<MagnetObstacle>{}
                               : magnetObstacles(scene_.magnets, time_ + dt, dt, 0.5 * spacing_, magnetSpeed_);
    forEachParticle(n, [&](size_t i) {
        x_[i] += rdt * v_[i];
        // Checked before the container sees it: constrain() would park a NaN particle at
        // its old position and hide the blow-up.
        if (!x_[i].allFinite() || !v_[i].allFinite()) {
            size_t expected = size_t(-1);
            bad.compare_exchange_strong(expected, i);
        }
        // Bodies first: the container's constraint is the last word (a body reaching
        // through a wall must not push fluid out of the vessel).
        for (const MagnetObstacle& body : bodies) keepOutside(body, x_[i], v_[i]);
        container_->constrain(xOld_[i], x_[i], v_[i]);
        // The split copy the vectorized neighbour loops gather from.
        px_[i] = x_[i].x();
        py_[i] = x_[i].y();
        pz_[i] = x_[i].z();
        setPadded(i);
    });
    if (bad != size_t(-1)) {
        std::ostringstream msg;
        msg << "non-finite position or velocity of particle " << id_[bad] << " at t = " << time_ + dt
            << " s (step " << steps_ + 1 << ", dt " << dt << " s): the simulation blew up";
        throw SimulationError(msg.str());
    }
}

double FluidSimulation::step(double dtLimit) {
    if (magnetics_) {
        // The field at the step's start; the induced part is re-solved at every frame
        // start (so a resumed run continues exactly) and whenever it has gone stale.
        updateMagnetics(frameStart_);
        frameStart_ = false;
        if (StallGuard::solverStalled(magnetics_->unconvergedInRow())) {
            std::ostringstream msg;
            msg.precision(3);
            msg << "the magnetization solve ended at its iteration cap (magnetization.max_iterations = "
                << scene_.magnetization.maxIterations << ") without converging " << magnetics_->unconvergedInRow()
                << " times in a row at t = " << time_ << " s (residual " << magnetics_->stats().residual
                << "): the field is wrong on every step; lower magnetization.susceptibility or raise max_iterations";
            throw SimulationError(msg.str());
        }
    }
    size_t fastest = 0;
    const double speed = maxSpeed(&fastest);
    checkSpeed(speed, fastest);
    double stableDt = 0;
    const double dt = chooseTimeStep(dtLimit, speed, &stableDt, &stats_.dtBound);
    // A step near sim.min_dt that lasts: the run would crawl for hours before (if ever)
    // failing. The stable step counts, not the one shortened to land on a frame's end
    // (that one used to reset the count, so a stuck run whose frames took fewer than
    // kMaxStuckSteps steps each never stopped).
    if (stall_.recordStep(stableDt)) {
        std::ostringstream msg;
        msg.precision(3);
        msg << "time step stayed below " << SanityLimits::kNearMinDt << " x sim.min_dt = "
            << SanityLimits::kNearMinDt * scene_.solver.minDt << " s for " << stall_.stuckSteps()
            << " steps in a row at t = " << time_ << " s (dt " << stableDt << " s, max speed " << speed
            << " m/s, max magnetic acceleration " << (magnetics_ ? magnetics_->maxAcceleration() : 0.0)
            << " m/s^2): the simulation cannot make progress";
        throw SimulationError(msg.str());
    }
    stats_.densityAtCap = stats_.divergenceAtCap = false;
    solver_->advanceVelocities(dt);
    integratePositions(dt);
    time_ += dt;
    ++steps_;
    stats_.dt = dt;
    frameCaps_.add(stats_);
    runCaps_.add(stats_);
    refreshNeighbors(false);
    return dt;
}

void FluidSimulation::advanceTo(double tEnd) {
    // The solver's warm start restarts at every frame, so that a run resumed from a frame
    // file (positions, velocities, pressures) continues exactly like an uninterrupted one.
    // DFSPH's divergence solve converges in a few iterations from zero.
    solver_->resetWarmStart();
    if (implicitViscosity_) implicitViscosity_->resetWarmStart();
    // A frame starts from a fresh search too: the particle order and the neighbour slots
    // are then a function of the frame's state alone, as in a run resumed from its file.
    if (searchStep_ != steps_) refreshNeighbors(true);
    frameStart_ = true;
    frameCaps_ = SolverCapCount{};
    while (time_ < tEnd) {
        step(tEnd - time_);
        if (tEnd - time_ < 1e-12 * std::max(1.0, tEnd)) time_ = tEnd;
    }
    checkSanity();
}


namespace {
template <class T>
std::vector<T> byId(const std::vector<T>& data, const std::vector<uint32_t>& id) {
    std::vector<T> out(data.size());
    for (size_t i = 0; i < data.size(); ++i) out[id[i]] = data[i];
    return out;
}
} // namespace

std::vector<Vec3> FluidSimulation::positionsById() const { return byId(x_, id_); }
std::vector<Vec3> FluidSimulation::velocitiesById() const { return byId(v_, id_); }
std::vector<Real> FluidSimulation::densitiesById() const { return byId(rho_, id_); }
std::vector<Real> FluidSimulation::pressuresById() const { return byId(solver_->pressures(), id_); }
std::vector<Vec3> FluidSimulation::fieldById() const {
    if (!magnetics_ || magnetics_->field().size() != x_.size()) return std::vector<Vec3>(x_.size(), Vec3::Zero());
    return byId(magnetics_->field(), id_);
}
std::vector<Vec3> FluidSimulation::magnetizationById() const {
    if (!magnetics_ || magnetics_->magnetization().size() != x_.size())
        return std::vector<Vec3>(x_.size(), Vec3::Zero());
    return byId(magnetics_->magnetization(), id_);
}
std::vector<Magnet> FluidSimulation::magnetsNow() const {
    return magnetics_ ? magnetics_->softenedMagnetsAt(time_) : std::vector<Magnet>{};
}

void FluidSimulation::setState(double time, const std::vector<Vec3>& xById, const std::vector<Vec3>& vById,
                               const std::vector<Real>& pById, const std::vector<Vec3>& HById,
                               const std::vector<Vec3>& MById) {
    if (xById.size() != x_.size() || vById.size() != x_.size() || (!pById.empty() && pById.size() != x_.size()))
        throw SimulationError("state has " + std::to_string(xById.size()) + " particles, the scene makes " +
                              std::to_string(x_.size()));
    for (size_t i = 0; i < x_.size(); ++i) id_[i] = uint32_t(i);
    x_ = xById;
    v_ = vById;
    solver_->setPressures(pById.empty() ? std::vector<Real>(x_.size(), Real(0)) : pById);
    time_ = time;
    solver_->resetWarmStart();
    if (implicitViscosity_) implicitViscosity_->resetWarmStart();
    if (magnetics_ && HById.size() == x_.size() && MById.size() == x_.size())
        magnetics_->setState(HById, MById);   // id order = current order until the sort below
    refreshNeighbors(true);
}

} // namespace ferro

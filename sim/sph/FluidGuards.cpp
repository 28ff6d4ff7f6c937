// FluidSimulation's guards: the sanity limits a run is checked against (speed bound, stall,
// non-finite state) and the per-frame count of solves that ended at their cap.
#include "sim/sph/FluidSimulation.hpp"

#include "sim/core/Constants.hpp"
#include "sim/core/ParticleLoops.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnetics/MagnetizationSolver.hpp"

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

void FluidSimulation::setUpSanityGuard() {
    // The parts of the speed bound (SanityGuard.hpp) fixed for the whole run.
    limits_.speedOverride = scene_.solver.maxSpeed;
    stall_ = StallGuard(scene_.solver.minDt);
    speedBound_.override = scene_.solver.maxSpeed;
    const Vec3d g = scene_.solver.gravity;
    const double gNorm = g.norm();
    if (gNorm > 0 && !x_.empty()) {
        // The drop from the highest point the fluid or the container's walls reach to the
        // container's lowest point, along gravity (an unbounded container: the fluid's own
        // height, ten times over, as chooseSpeedScales assumes).
        const Vec3d down = g / gNorm;
        double top = -1e300, bottom = 1e300;
        for (const Vec3& p : x_) {
            top = std::max(top, -p.cast<double>().dot(down));
            bottom = std::min(bottom, -p.cast<double>().dot(down));
        }
        const double fluidHeight = top - bottom;
        Vec3d lo, hi;
        container_->bounds(lo, hi);
        if (scene_.container.type == ContainerParams::Type::Dish)
            hi.z() = scene_.container.center.z() + scene_.container.height;
        double cTop = -1e300, cBottom = 1e300;
        for (int c = 0; c < 8; ++c) {
            const Vec3d corner((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
            cTop = std::max(cTop, -corner.dot(down));
            cBottom = std::min(cBottom, -corner.dot(down));
        }
        const double span = 10 * std::max(fluidHeight, spacing_);
        top = std::max(top, std::min(cTop, top + span));
        bottom = std::min(bottom, std::max(cBottom, bottom - span));
        speedBound_.gravity2 = 2 * gNorm * std::max(top - bottom, spacing_);
    }
    for (const Vec3& v : v_) speedBound_.initial2 = std::max(speedBound_.initial2, double(v.squaredNorm()));
    // The magnets' fastest motion, sampled along each key segment (Catmull-Rom may
    // overshoot the chord). Keys at one time (a jump) move nothing: the field's change
    // they cause is in the magnetic energy term.
    double u = 0;
    for (const MagnetTrack& track : scene_.magnets)
        for (size_t k = 0; k + 1 < track.keys.size(); ++k) {
            const double t0 = track.keys[k].time, t1 = track.keys[k + 1].time;
            if (!(t1 > t0)) continue;
            constexpr int kSamples = 32;
            Vec3d prev = track.at(t0).position;
            for (int j = 1; j <= kSamples; ++j) {
                const Vec3d next = track.at(t0 + (t1 - t0) * j / kSamples).position;
                u = std::max(u, (next - prev).norm() / ((t1 - t0) / kSamples));
                prev = next;
            }
        }
    speedBound_.magnets2 = 4 * u * u;
    magnetSpeed_ = u;
    speedBound_.capillary2 = std::max(0.0, scene_.fluid.surfaceTension) / (rho0_ * spacing_);
}

void FluidSimulation::checkSpeed(double speed, size_t which) {
    if (magnetics_ && magnetics_->magnetic()) {
        const MagnetizationParams& law = magnetics_->law();
        speedBound_.magnetic2 =
            2 * kMu0 * langevinEnergy(magnetics_->maxFieldSeen(), law.susceptibility, law.saturation) / rho0_;
    }
    const double energy = speedBound_.energySpeed();
    if (energy > 0) maxSpeedRatio_ = std::max(maxSpeedRatio_, speed / energy);
    const double bound = speedBound_.value();
    if (!(speed > bound) || x_.empty()) return;
    std::ostringstream msg;
    msg.precision(3);
    msg << "particle " << id_[which] << " moves at " << speed << " m/s at t = " << time_ << " s (step " << steps_
        << "), faster than this scene can make it: bound " << bound << " m/s";
    if (speedBound_.override > 0) msg << " (sim.max_speed)";
    else
        msg << " = " << SanityLimits::kSpeedSafety << " x " << energy
            << " m/s, the speed of all its energy in one particle (gravity, initial speeds, magnets' motion, field up to "
            << (magnetics_ ? magnetics_->maxFieldSeen() : 0.0) << " A/m, surface tension; sim.max_speed overrides)";
    msg << ": the simulation is unstable";
    throw SimulationError(msg.str());
}

void FluidSimulation::checkSanity() {
    size_t fastest = 0;
    checkSpeed(maxSpeed(&fastest), fastest);
    // Particles outside the container: constrain() never lets them out, so this is a bug.
    const double margin = -SanityLimits::kOutsideTolerance * spacing_;
    std::vector<uint8_t> outside(x_.size(), 0);
    forEachParticle(x_.size(), [&](size_t i) { outside[i] = !container_->contains(x_[i].cast<double>(), margin); });
    std::vector<uint32_t> ids;
    for (size_t i = 0; i < x_.size(); ++i)
        if (outside[i]) ids.push_back(id_[i]);
    if (ids.empty()) return;
    std::sort(ids.begin(), ids.end());
    std::ostringstream msg;
    msg.precision(3);
    msg << ids.size() << " particle" << (ids.size() == 1 ? " is" : "s are") << " outside the container at t = "
        << time_ << " s (id";
    for (size_t k = 0; k < std::min(ids.size(), SanityLimits::kNamedParticles); ++k)
        msg << (k ? ", " : " ") << ids[k];
    if (ids.size() > SanityLimits::kNamedParticles) msg << ", ...";
    msg << "): the wall constraint failed, a bug; please report it with the scene";
    throw SimulationError(msg.str());
}

void SolverCapCount::add(const StepStats& s) {
    ++steps;
    densityByCg += s.densityByCg;
    ++dtBounds[int(s.dtBound)];
    pressureIterations += size_t(std::max(s.pressureIterations, 0));
    divergenceIterations += size_t(std::max(s.divergenceIterations, 0));
    if (s.densityAtCap) {
        ++densityAtCap;
        densityError = std::max(densityError, s.densityError);
    }
    if (s.divergenceAtCap) {
        ++divergenceAtCap;
        divergenceError = std::max(divergenceError, s.divergenceError);
    }
}

} // namespace ferro

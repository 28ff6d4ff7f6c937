// FluidSimulation's SPH operators: the force sweep (sim/sph/forces), the pressure
// accelerations the pressure solvers share, the free-surface view and the magnetics update.
#include "sim/sph/FluidSimulation.hpp"
#include "sim/sph/FreeSurface.hpp"
#include "sim/sph/forces/ForceSweep.hpp"

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

namespace ferro {

void FluidSimulation::updateMagnetics(bool forceSolve) {
    // The free surface, computed only when the magnetics ask for it (after a self-consistent
    // solve with curve_fit = "free_surface", and every step for the surface model):
    // FluidMagnetics::SurfaceView.
    const FluidMagnetics::SurfaceProbe surface = [this]() {
        computeSurfaceView();
        return FluidMagnetics::SurfaceView{&colorGradient_, &exposure_};
    };
    magnetics_->update(time_, x_, surface, forceSolve);
}

void FluidSimulation::computeSurfaceView() {
    const FreeSurfaceInput in{x_, fluidNbr_, boundaryNbr_, bx_, bVolume_, kernel_, periodic_, Real(volume_), Real(spacing_)};
    computeColorGradient(in, colorGradient_);
    computeExposure(in, colorGradient_, exposure_);
}

void FluidSimulation::computeAccelerations(const Real* pOverRho2) {
    const PairForceView view{x_, v_, rho_, px_.data(), py_.data(), pz_.data(), fluidNbr_, boundaryNbr_, bx_, bVolume_, kernel_, periodic_};
    const SweepConstants k{scene_.solver.gravity.cast<Real>(), Real(mass_), Real(rho0_), kWallMirror};
    pairForces_->accelerations(view, k, pOverRho2, a_);
    if (magnetics_) magnetics_->addKelvinAcceleration(a_);
}

PressureSweepInput FluidSimulation::sweepInput() const {
    static_assert(sizeof(Vec3) == 3 * sizeof(float) && sizeof(Real) == sizeof(float),
                  "the pressure sweeps read Vec3 arrays as three floats a particle");
    PressureSweepInput in;
    in.p4 = reinterpret_cast<const float*>(p4_.data());
    in.offset = fluidNbr_.offset.data();
    in.count = fluidNbr_.count.data();
    in.index = fluidNbr_.index.data();
    in.gradFactor = fluidNbr_.gradFactor.data();
    in.wallOffset = boundaryNbr_.offset.data();
    in.wallCount = boundaryNbr_.count.data();
    in.wallIndex = boundaryNbr_.index.data();
    in.wallGradFactor = boundaryNbr_.gradFactor.data();
    in.wallX = reinterpret_cast<const float*>(bx_.data());
    in.wallVolume = bVolume_.data();
    in.volume = Real(volume_);
    in.wallMirror = kWallMirror;
    for (int a = 0; a < 2; ++a) {
        in.period[a] = periodic_.period[a];
        in.inverse[a] = periodic_.inverse[a];
    }
    return in;
}

void FluidSimulation::pressureAccelerations(const std::vector<Real>& kappa) {
    // a_i = -sum_j V (kappa_i + kappa_j) grad W_ij - sum_b V_b kWallMirror kappa_i grad W_ib, where
    // kappa = p / rho^2 in units normalized by rho0 (Bender & Koschier 2017).
    const PressureSweepInput in = sweepInput();
    const PressureSweeps& sweeps = pressureSweeps();
    float* a = reinterpret_cast<float*>(a_.data());
    a4_.resize(x_.size());
    float* a4 = reinterpret_cast<float*>(a4_.data());
    forEachParticleBlock(x_.size(), [&](size_t begin, size_t end) { sweeps.accelerations(in, kappa.data(), a, a4, begin, end); });
}

void FluidSimulation::divergence(const std::vector<Vec3>& u, size_t begin, size_t end, Real* out) const {
    pressureSweeps().divergence(sweepInput(), reinterpret_cast<const float*>(u.data()), 3, out, begin, end);
}

void FluidSimulation::divergence(const std::vector<Vec3>& u, std::vector<Real>& out) const {
    out.resize(x_.size());
    forEachParticleBlock(x_.size(), [&](size_t begin, size_t end) { divergence(u, begin, end, out.data()); });
}

void FluidSimulation::pressureDivergence(size_t begin, size_t end, Real* out) const {
    pressureSweeps().divergence(sweepInput(), reinterpret_cast<const float*>(a4_.data()), 4, out, begin, end);
}

void FluidSimulation::pressureDivergence(std::vector<Real>& out) const {
    out.resize(x_.size());
    forEachParticleBlock(x_.size(), [&](size_t begin, size_t end) { pressureDivergence(begin, end, out.data()); });
}

} // namespace ferro

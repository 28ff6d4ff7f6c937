// FluidSimulation's SPH operators: the force sweep (sim/sph/forces), the pressure
// accelerations the pressure solvers share, the free-surface view and the magnetics update.
#include "sim/sph/FluidSimulation.hpp"
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
    {
        // The colour gradient grad c_i = V sum_j grad W_ij + sum_b V_b grad W_ib: fluid and
        // walls, so a wetted wall is no surface (FluidMagnetics.hpp).
        // Tried and dropped: the fluid's gradient alone with its part away from a wall
        // removed (the same 18 mm/s at the rim of a pool over a magnet, and faster outliers).
        const size_t n = x_.size();
        const Real V = Real(volume_);
        colorGradient_.resize(n);
        const PeriodicDomain periodic = periodic_;
        forEachParticle(n, [&](size_t i) {
            Vec3 fluid = Vec3::Zero(), wall = Vec3::Zero();
            for (uint32_t k = fluidNbr_.begin(i); k < fluidNbr_.end(i); ++k) {
                const Vec3 xij = periodic.offset(x_[i] - x_[fluidNbr_.index[k]]);
                fluid += kernel_.gradW(xij, xij.norm());
            }
            fluid *= V;
            for (uint32_t k = boundaryNbr_.begin(i); k < boundaryNbr_.end(i); ++k) {
                const uint32_t b = boundaryNbr_.index[k];
                const Vec3 xib = periodic.offset(x_[i] - bx_[b]);
                wall += bVolume_[b] * kernel_.gradW(xib, xib.norm());
            }
            colorGradient_[i] = fluid + wall;
        });
    }
    {
        // Exposure: 1 when no fluid particle stands in the cone of half-angle ~40 degrees
        // along the outward direction -grad c within 1.5 spacings, falling smoothly to 0
        // as one enters it (the scan-region test of Marrone et al. 2010). In a moving,
        // disordered fluid |grad c| alone reaches 40 % of a flat surface's value deep inside.
        const size_t n = x_.size();
        exposure_.resize(n);
        const Real s = Real(spacing_);
        const PeriodicDomain periodic = periodic_;
        forEachParticle(n, [&](size_t i) {
            const Vec3 g = colorGradient_[i];
            const Real gn = g.norm();
            if (!(gn > 0)) {
                exposure_[i] = 0;
                return;
            }
            const Vec3 out = -g / gn;
            Real covered = 0;
            for (uint32_t k = fluidNbr_.begin(i); k < fluidNbr_.end(i); ++k) {
                const Vec3 d = periodic.offset(x_[fluidNbr_.index[k]] - x_[i]);
                const Real r = d.norm();
                if (!(r > 0) || r > 2 * s) continue;
                const Real cosine = d.dot(out) / r;
                const Real inCone = std::clamp((cosine - Real(0.65)) / Real(0.2), Real(0), Real(1));
                const Real near = std::clamp((2 * s - r) / (Real(0.5) * s), Real(0), Real(1));
                covered = std::max(covered, inCone * near);
            }
            exposure_[i] = 1 - covered;
        });
    }
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

// Implicit viscosity (Weiler et al. 2018): matrix-free preconditioned conjugate gradients
// on (I + dt L) v_new = v*. See ImplicitViscosity.hpp for the operator.
#include "sim/sph/ImplicitViscosity.hpp"

#include "sim/core/ParticleLoops.hpp"

#include <algorithm>
#include <cmath>

namespace ferro {

namespace {

using Mat3 = Eigen::Matrix<Real, 3, 3>;

double dot(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    return deterministicSum(a.size(), [&](size_t i) { return double(a[i].dot(b[i])); });
}

} // namespace

void ImplicitViscosity::setUp(const ViscosityOperatorInput& input, double dt) {
    in_ = input;
    dt_ = dt;
    const std::vector<Vec3>& x = *in_.positions;
    const std::vector<Real>& rho = *in_.densities;
    const NeighborLists& fluid = *in_.fluidNeighbors;
    const NeighborLists& wall = *in_.boundaryNeighbors;
    const size_t n = x.size();
    const double h = in_.supportRadius;
    // The explicit sweep's constants (FluidSimulation::computeAccelerations): 10 = 2 (d + 2)
    // for d = 3 (Weiler 2018 eq. 8), eps^2 = 0.01 h^2 keeps the pair term finite at r -> 0.
    const Real eps2 = Real(0.01 * h * h);
    const Real fluidScale = Real(10 * in_.viscosity * 2 * in_.particleMass);
    const Real wallScale = Real(10 * in_.wallViscosity * in_.restDensity);
    const CubicSplineKernel& kernel = in_.kernel;
    pairCoefficient_.resize(fluid.index.size());
    wallCoefficient_.resize(wall.index.size());
    inverseDiagonal_.resize(n);
    const Real rdt = Real(dt);
    const PeriodicDomain periodic = in_.periodic; // a copy: the loop stores floats
    forEachParticle(n, [&](size_t i) {
        // Diagonal block of I + dt L: I - dt (sum_j c_ij x_ij x_ij^T + sum_b c_ib x_ib x_ib^T),
        // positive definite since every c < 0.
        Mat3 block = Mat3::Zero();
        for (uint32_t k = fluid.begin(i); k < fluid.end(i); ++k) {
            const uint32_t j = fluid.index[k];
            const Vec3 xij = periodic.offset(x[i] - x[j]);
            const Real r2 = xij.squaredNorm();
            const Real c = fluidScale / ((rho[i] + rho[j]) * (r2 + eps2)) * kernel.gradWFactor(std::sqrt(r2));
            pairCoefficient_[k] = c;
            block += c * (xij * xij.transpose());
        }
        if (in_.wallViscosity > 0) {
            const std::vector<Vec3>& bx = *in_.boundaryPositions;
            const std::vector<Real>& bV = *in_.boundaryVolumes;
            for (uint32_t k = wall.begin(i); k < wall.end(i); ++k) {
                const uint32_t b = wall.index[k];
                const Vec3 xib = periodic.offset(x[i] - bx[b]);
                const Real r2 = xib.squaredNorm();
                const Real c = wallScale * bV[b] / rho[i] / (r2 + eps2) * kernel.gradWFactor(std::sqrt(r2));
                wallCoefficient_[k] = c;
                block += c * (xib * xib.transpose());
            }
        }
        inverseDiagonal_[i] = (Mat3::Identity() - rdt * block).inverse();
    });
}

void ImplicitViscosity::acceleration(const std::vector<Vec3>& v, std::vector<Vec3>& a) const {
    // a_i = sum_j c_ij ((v_i - v_j) . x_ij) x_ij + sum_b c_ib (v_i . x_ib) x_ib = -(L v)_i.
    const std::vector<Vec3>& x = *in_.positions;
    const NeighborLists& fluid = *in_.fluidNeighbors;
    const NeighborLists& wall = *in_.boundaryNeighbors;
    const bool walls = in_.wallViscosity > 0;
    a.resize(v.size());
    const PeriodicDomain periodic = in_.periodic; // a copy: the loop stores floats
    forEachParticle(v.size(), [&](size_t i) {
        const Vec3 xi = x[i], vi = v[i];
        Vec3 acc = Vec3::Zero();
        for (uint32_t k = fluid.begin(i); k < fluid.end(i); ++k) {
            const uint32_t j = fluid.index[k];
            const Vec3 xij = periodic.offset(xi - x[j]);
            acc += (pairCoefficient_[k] * (vi - v[j]).dot(xij)) * xij;
        }
        if (walls) {
            const std::vector<Vec3>& bx = *in_.boundaryPositions;
            for (uint32_t k = wall.begin(i); k < wall.end(i); ++k) {
                const Vec3 xib = periodic.offset(xi - bx[wall.index[k]]);
                acc += (wallCoefficient_[k] * vi.dot(xib)) * xib;
            }
        }
        a[i] = acc;
    });
}

void ImplicitViscosity::applySystem(const std::vector<Vec3>& v, std::vector<Vec3>& out) const {
    acceleration(v, out);
    const Real rdt = Real(dt_);
    forEachParticle(v.size(), [&](size_t i) { out[i] = v[i] - rdt * out[i]; });
}

ImplicitViscosityResult ImplicitViscosity::solve(std::vector<Vec3>& v) {
    // Preconditioned CG (Weiler 2018 sec. 4.3; Eigen's ConjugateGradient, written out so
    // that every dot product is summed in a fixed order).
    const size_t n = v.size();
    ImplicitViscosityResult result;
    const std::vector<Vec3> rhs = v;
    const double rhsNorm2 = dot(rhs, rhs);
    if (!(rhsNorm2 > 0)) return result;   // v* = 0: v_new = 0
    // Warm start: v* plus the last solve's velocity change.
    if (warmStart_.size() == n) forEachParticle(n, [&](size_t i) { v[i] += warmStart_[i]; });
    std::vector<Vec3>& r = residual_;
    std::vector<Vec3>& p = direction_;
    std::vector<Vec3>& z = preconditioned_;
    std::vector<Vec3>& Ap = product_;
    applySystem(v, Ap);
    r.resize(n);
    forEachParticle(n, [&](size_t i) { r[i] = rhs[i] - Ap[i]; });
    const double threshold2 = settings_.tolerance * settings_.tolerance * rhsNorm2;
    double r2 = dot(r, r);
    z.resize(n);
    p.resize(n);
    forEachParticle(n, [&](size_t i) { z[i] = inverseDiagonal_[i] * r[i]; p[i] = z[i]; });
    double rz = dot(r, z);
    int it = 0;
    while (r2 > threshold2 && it < settings_.maxIterations) {
        applySystem(p, Ap);
        const double pAp = dot(p, Ap);
        if (!(pAp > 0)) break;   // cannot happen for an SPD system; guards a breakdown
        const Real alpha = Real(rz / pAp);
        forEachParticle(n, [&](size_t i) {
            v[i] += alpha * p[i];
            r[i] -= alpha * Ap[i];
            z[i] = inverseDiagonal_[i] * r[i];
        });
        ++it;
        r2 = dot(r, r);
        const double rzNew = dot(r, z);
        const Real beta = Real(rzNew / rz);
        rz = rzNew;
        forEachParticle(n, [&](size_t i) { p[i] = z[i] + beta * p[i]; });
    }
    // A uniform velocity is in the fluid part of L's null space (pairs see differences
    // only), so the exact solution keeps the momentum of v* (less the walls' friction); the
    // CG iterate misses it by sum r, since the block-Jacobi steps do not conserve it. Adding
    // the mean residual to every particle restores it (the free-flight blob of
    // test_FluidSimulation, DFSPH, 0.05 s: momentum drift 3.2e-6 without, 1.4e-7 with).
    Vec3 meanResidual;
    for (int c = 0; c < 3; ++c)
        meanResidual[c] = Real(deterministicSum(n, [&](size_t i) { return double(r[i][c]); }) / double(n));
    forEachParticle(n, [&](size_t i) { v[i] += meanResidual; });
    warmStart_.resize(n);
    forEachParticle(n, [&](size_t i) { warmStart_[i] = v[i] - rhs[i]; });
    result.iterations = it;
    result.relativeResidual = std::sqrt(r2 / rhsNorm2);
    result.converged = r2 <= threshold2;
    return result;
}

double ImplicitViscosity::largestRate(int iterations) const {
    // Power iteration on L from a checkerboard-like start (rich in the short waves whose
    // rate is the largest); Rayleigh quotient v.Lv / v.v at the end.
    const size_t n = in_.positions->size();
    if (n == 0) return 0;
    std::vector<Vec3> v(n), Lv;
    for (size_t i = 0; i < n; ++i) {
        const uint32_t s = uint32_t(i) * 2654435761u;
        v[i] = Vec3(Real((s >> 8) & 1) - Real(0.5), Real((s >> 9) & 1) - Real(0.5), Real((s >> 10) & 1) - Real(0.5));
    }
    double rate = 0;
    for (int k = 0; k < iterations; ++k) {
        acceleration(v, Lv);   // -L v
        const double vv = dot(v, v);
        rate = -dot(v, Lv) / vv;
        const double norm = std::sqrt(dot(Lv, Lv));
        if (!(norm > 0)) return 0;
        forEachParticle(n, [&](size_t i) { v[i] = Lv[i] * Real(-1 / norm); });
    }
    return rate;
}

void ImplicitViscosity::permute(const std::vector<uint32_t>& order) {
    ferro::permute(warmStart_, order);
}

} // namespace ferro

#pragma once
// Internal to sim/sph/forces: the fused force sweep, one pass over every particle's
// neighbours that sums gravity, the pressure force (WCSPH's, when given) and the pair-force
// models, four pairs at a time with SSE2. Compiled once for each combination of models
// (PairForces.cpp), so a model that is off costs nothing. The kernel is evaluated here, which
// is cheaper than loading the gradients DFSPH stores for its iterations.
#include "sim/core/ParticleLoops.hpp"
#include "sim/sph/forces/PairForceModel.hpp"

#include <cmath>
#include <vector>

namespace ferro {

/// What the sweep adds besides the models: gravity, the pressure term, the walls' push.
struct SweepConstants {
    Vec3 gravity;
    Real mass;        ///< m [kg]
    Real restDensity; ///< rho0 [kg/m^3]
    Real wallMirror;  ///< walls push with this times the particle's own pressure (Akinci 2012)
};

/// a[i] = g + pressure + the models' pair forces. pOverRho2: WCSPH's p / rho^2 per particle
/// (kPressure), else unused.
template <class Viscosity, class Tension, bool kPressure>
void forceSweep(const PairForceView& s, const SweepConstants& k, const Viscosity& visc, const Tension& ten,
                const Real* pOverRho2, std::vector<Vec3>& a) {
    const size_t n = s.x.size();
    const Real m = k.mass, rho0 = k.restDensity;
#if defined(__SSE2__)
    const CubicSplineKernel4 kernel4(s.kernel);
#endif
    const bool walls = visc.wantsWalls() || ten.wantsWalls();
    // A copy: the loop's float stores could alias the view's, so a reference would be reloaded
    // (and its test repeated) every pair.
    const PeriodicDomain periodic = s.periodic;
    forEachParticle(n, [&](size_t i) {
        Vec3 acc = ten.own(visc.own(k.gravity, i), i);
        const Vec3 xi = s.x[i];
        const Real rhoi = s.rho[i];
        const Real pi = kPressure ? pOverRho2[i] : 0;
        // Pressure and the radial shares of the models act along grad W_ij with one scalar
        // per pair: the WCSPH pressure -m (p_i / rho_i^2 + p_j / rho_j^2) is symmetric in i
        // and j, so the pair forces cancel (up to rounding: i may take a pair in the
        // four-lane loop and j in the scalar tail) and momentum is conserved.
        uint32_t kk = s.fluid.begin(i);
        const uint32_t end = s.fluid.end(i);
#if defined(__SSE2__)
        {
            const __m128 rhoi4 = _mm_set1_ps(rhoi), pm4 = _mm_set1_ps(pi), m4 = _mm_set1_ps(m);
            auto viscLanes = visc.lanes(i, s);
            auto tenLanes = ten.lanes(i, s);
            __m128 ax = _mm_setzero_ps(), ay = _mm_setzero_ps(), az = _mm_setzero_ps();
            for (; kk + 4 <= end; kk += 4) {
                PairLanes4 p;
                p.j = &s.fluid.index[kk];
                const PairOffsets4 d(xi, s.px, s.py, s.pz, p.j, periodic);
                p.dx = d.dx;
                p.dy = d.dy;
                p.dz = d.dz;
                p.r2 = d.r2;
                p.r = _mm_sqrt_ps(d.r2);
                p.rhoSum = _mm_add_ps(rhoi4, gather4(s.rho.data(), p.j));
                p.gradFactor = kernel4.gradFactor(p.r);
                __m128 c = _mm_setzero_ps();
                if constexpr (kPressure) c = _mm_sub_ps(c, _mm_mul_ps(m4, _mm_add_ps(pm4, gather4(pOverRho2, p.j))));
                c = visc.radial4(c, viscLanes, p);
                c = ten.radial4(c, tenLanes, p);
                __m128 cs = _mm_mul_ps(c, p.gradFactor);
                cs = visc.offset4(cs, viscLanes, p);
                cs = ten.offset4(cs, tenLanes, p);
                ax = _mm_add_ps(ax, _mm_mul_ps(cs, p.dx));
                ay = _mm_add_ps(ay, _mm_mul_ps(cs, p.dy));
                az = _mm_add_ps(az, _mm_mul_ps(cs, p.dz));
            }
            acc = visc.finish4(acc, i, viscLanes);
            acc = ten.finish4(acc, i, tenLanes);
            acc += Vec3(horizontalSum(ax), horizontalSum(ay), horizontalSum(az));
        }
#endif
        for (; kk < end; ++kk) {
            Pair1 p;
            p.i = i;
            p.j = s.fluid.index[kk];
            p.xij = periodic.offset(xi - s.x[p.j]);
            p.r2 = p.xij.squaredNorm();
            p.r = std::sqrt(p.r2);
            p.rhoSum = rhoi + s.rho[p.j];
            p.gradFactor = s.kernel.gradWFactor(p.r);
            Real c = 0;
            if constexpr (kPressure) c -= m * (pi + pOverRho2[p.j]);
            c = visc.radial1(c, p);
            c = ten.radial1(c, p);
            acc += (c * p.gradFactor) * p.xij;
            acc = visc.direct1(acc, p);
            acc = ten.direct1(acc, p);
        }
        if (walls || (kPressure && pi != 0)) {
            for (uint32_t kb = s.boundary.begin(i); kb < s.boundary.end(i); ++kb) {
                WallPair1 w;
                w.i = i;
                w.b = s.boundary.index[kb];
                w.xib = periodic.offset(xi - s.bx[w.b]);
                w.r2 = w.xib.squaredNorm();
                w.gradW = s.kernel.gradW(w.xib, std::sqrt(w.r2));
                // Walls push with the fluid particle's own pressure (Akinci 2012).
                if constexpr (kPressure) acc -= (k.wallMirror * rho0 * s.bVolume[w.b] * pi) * w.gradW;
                acc = visc.wall1(acc, w);
                acc = ten.wall1(acc, w);
            }
        }
        a[i] = acc;
    });
}

} // namespace ferro

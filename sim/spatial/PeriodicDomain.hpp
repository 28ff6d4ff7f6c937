#pragma once
// Periodic side walls: a box whose x and y faces are glued to the opposite ones (a torus in
// the horizontal plane), so that a layer of fluid has no rim. Positions live in
// [lo, lo + period) on a periodic axis (wrapped at each neighbour search; between searches
// a particle may stray up to half the Verlet skin past a face), and every pair offset
// x_i - x_j is taken to its nearest image (the minimum-image convention).
//
// Contract: period > 2 (support + skin) on a periodic axis, so that a particle meets at most
// one image of another (FluidSimulation checks it). An axis with period 0 is not periodic:
// its offsets are returned unchanged, bit for bit (d - 0 * round(d * 0) = d), so a loop may
// apply the map to every pair; offset() and the four-lane gathers skip it when no axis is.
#include "sim/core/Types.hpp"

#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ferro {

struct PeriodicDomain {
    Real lo[2] = {0, 0};      ///< lower face of the periodic x and y axes [m]
    Real period[2] = {0, 0};  ///< period of x and y [m]; 0 = not periodic
    Real inverse[2] = {0, 0}; ///< 1 / period, or 0

    /// x and y periodic over [lo, hi) (a zero or negative extent leaves that axis closed).
    static PeriodicDomain horizontal(const Vec3& lo, const Vec3& hi) {
        PeriodicDomain d;
        for (int a = 0; a < 2; ++a) {
            const Real L = hi[a] - lo[a];
            if (!(L > 0)) continue;
            d.lo[a] = lo[a];
            d.period[a] = L;
            d.inverse[a] = Real(1) / L;
        }
        return d;
    }
    bool active() const { return period[0] > 0 || period[1] > 0; }

    /// The nearest image of the offset d = x_i - x_j.
    Vec3 offset(Vec3 d) const {
        if (!active()) return d;
        for (int a = 0; a < 2; ++a) d[a] -= period[a] * roundToInteger(d[a] * inverse[a]);
        return d;
    }
    /// x rounded to the nearest integer, ties to even (as offset4's lanes): one instruction
    /// where std::nearbyint would be a library call per pair on the baseline x86-64 target.
    static Real roundToInteger(Real x) {
#if defined(__SSE2__)
        return Real(_mm_cvtss_si32(_mm_set_ss(x))); // |x| is a few periods at most: no overflow
#else
        return std::nearbyint(x);
#endif
    }
    /// Puts x into [lo, lo + period) on the periodic axes. A coordinate already inside is left
    /// alone, bit for bit, so wrapping is idempotent (a resumed run wraps the positions it
    /// read again and must get the same ones).
    void wrap(Vec3& x) const {
        for (int a = 0; a < 2; ++a) {
            if (!(period[a] > 0)) continue;
            const Real top = lo[a] + period[a];
            if (x[a] >= lo[a] && x[a] < top) continue;
            x[a] -= period[a] * std::floor((x[a] - lo[a]) * inverse[a]);
            // (x - lo) / period rounds to a whole number just inside either face: fold back.
            if (x[a] < lo[a]) x[a] += period[a];
            if (x[a] >= top) x[a] = lo[a]; // (a NaN stays NaN: the sanity guard reports it)
        }
    }
#if defined(__SSE2__)
    /// offset() for four x (axis 0) or y (axis 1) offsets (round to nearest: the default MXCSR mode).
    __m128 offset4(__m128 d, int axis) const {
        const __m128 k = _mm_cvtepi32_ps(_mm_cvtps_epi32(_mm_mul_ps(d, _mm_set1_ps(inverse[axis]))));
        return _mm_sub_ps(d, _mm_mul_ps(k, _mm_set1_ps(period[axis])));
    }
#endif
};

} // namespace ferro

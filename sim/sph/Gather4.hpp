#pragma once
// Four-lane (SSE2) gathers for the neighbour loops that take four pairs at a time: the
// force sweep and the neighbour compaction (DFSPH's pressure sweeps have their own copy in
// sim/sph/sweeps, which may share no inline code). Lanes are filled
// from scalar loads (SSE2 has no gather instruction); the arithmetic after them is what
// the four lanes buy.
#include "sim/core/Types.hpp"
#include "sim/spatial/PeriodicDomain.hpp"

#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ferro {

#if defined(__SSE2__)
/// a[j[0..3]] in four lanes.
inline __m128 gather4(const Real* a, const uint32_t* j) { return _mm_set_ps(a[j[3]], a[j[2]], a[j[1]], a[j[0]]); }

/// Component c of v[j[0..3]] in four lanes.
inline __m128 gather4(const Vec3* v, const uint32_t* j, int c) {
    return _mm_set_ps(v[j[3]][c], v[j[2]][c], v[j[1]][c], v[j[0]][c]);
}

/// Offsets x_i - x_j to four points j (coordinates split into px, py, pz), each to the
/// nearest periodic image (PeriodicDomain; unchanged without periodic sides).
struct Offsets4 {
    __m128 dx, dy, dz;
    Offsets4(const Vec3& xi, const Real* px, const Real* py, const Real* pz, const uint32_t* j,
             const PeriodicDomain& periodic)
        : dx(_mm_sub_ps(_mm_set1_ps(xi.x()), gather4(px, j))),
          dy(_mm_sub_ps(_mm_set1_ps(xi.y()), gather4(py, j))),
          dz(_mm_sub_ps(_mm_set1_ps(xi.z()), gather4(pz, j))) {
        if (periodic.active()) { // (predictable: the same every pair of a run)
            dx = periodic.offset4(dx, 0);
            dy = periodic.offset4(dy, 1);
        }
    }
};

/// The offsets and their squared lengths.
struct PairOffsets4 : Offsets4 {
    __m128 r2;
    PairOffsets4(const Vec3& xi, const Real* px, const Real* py, const Real* pz, const uint32_t* j,
                 const PeriodicDomain& periodic)
        : Offsets4(xi, px, py, pz, j, periodic),
          r2(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz))) {}
};
#endif

} // namespace ferro

#pragma once
// Internal to sim/particlefield: the particle-particle kernels of the dipole field (a source's
// field and Jacobian at a target, smoothed within its core: DipoleTree.hpp derives them), in
// four float lanes for the sums and in double for the exact references, and small helpers
// the tree's files share. Everything here is inline in dipole_detail.
#include "sim/particlefield/DipoleTree.hpp"

#include "sim/core/Constants.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#define FERRO_DIPOLE_SSE 1
typedef float v4sf __attribute__((vector_size(16)));
#endif

namespace ferro {
namespace dipole_detail {

// Smallest squared distance (scaled units, i.e. in mean particle radii^2) a kernel divides
// by. Only reached by zero-volume particles (moment 0) and exact coincidences, which the
// inside test catches first for real particles; keeps r^-7 finite in float (1e28).
constexpr float kMinR2 = 1e-8f;
// Accepted cells with this few particles are summed exactly instead: same cost, no error.
constexpr uint32_t kMinCellCount = 2;
// Source chunk of the all-pairs sum: 4096 particles x 10 floats stay in L2.
constexpr size_t kDirectChunk = 4096;
constexpr size_t kDirectTargetBlock = 32;

struct Sources {
    const float *x, *y, *z, *mx, *my, *mz, *a2, *ainv; // a2, ainv: core radius^2 and 1 / core radius
};

// How a particle's field differs from a point dipole within its core radius a (see
// DipoleTree.hpp): Point = never (far cells, whose targets lie outside every core),
// Sphere = the uniformly magnetized sphere of radius a, Wendland = the Wendland C2
// kernel-smoothed dipole of support a.
enum class Core { Point, Sphere, Wendland };
inline Core coreOf(double smoothing) { return smoothing > 0 ? Core::Wendland : Core::Sphere; }

// Wendland C2 smoothed dipole, q = r / a < 1 (derivation in DipoleTree.hpp). With the
// enclosed kernel mass Q(q) = 14 q^3 - 84 q^5 + 140 q^6 - 90 q^7 + 21 q^8 and the kernel
// 4 pi a^3 W = 42 (1 - q)^4 (1 + 4 q), the field of moment m at offset r is
//   4 pi H = c1 r (r . m) - c2 m,  c2 = Q / r^3 = wendlandC2(q) / a^3,
//   c1 = 3 Q / r^5 - 4 pi W / r^2 = wendlandC1(q) / a^5,
// and its Jacobian 4 pi dH_d/dx_e = c1 (delta_de (r . m) + r_d m_e + m_d r_e) - c3 r_d r_e (r . m)
// with c3 = -(dc1/dr) / r = (420 / q - 720 + 315 q) / a^7. All three equal the point
// dipole's 1/r^3, 3/r^5, 15/r^7 at q = 1.
template <class T>
inline T wendlandC2(const T& q) { return 14.0f + q * q * (-84.0f + q * (140.0f + q * (-90.0f + 21.0f * q))); }
template <class T>
inline T wendlandC1(const T& q) { return 168.0f + q * (-420.0f + q * (360.0f - 105.0f * q)); }
// c3 a^7 without the 420 / q term (added by the callers as 420 / (r a^6), finite for r > 0).
template <class T>
inline T wendlandC3Smooth(const T& q) { return -720.0f + 315.0f * q; }

#ifdef FERRO_DIPOLE_SSE
// Sources i .. i+3 of s seen from the target t (each coordinate in all four lanes), scaled
// float units: offsets d = t - x, r^2 = |d|^2, inv = 1/r with r^2 clamped below at kMinR2,
// inv2 = inv^2, the moments m and d . m. What both particle kernels start from.
struct SourcePairs4 {
    __m128 dx, dy, dz, r2, inv, inv2, mx, my, mz, dot;
    SourcePairs4(const __m128 t[3], const Sources& s, size_t i) {
        dx = _mm_sub_ps(t[0], _mm_loadu_ps(s.x + i));
        dy = _mm_sub_ps(t[1], _mm_loadu_ps(s.y + i));
        dz = _mm_sub_ps(t[2], _mm_loadu_ps(s.z + i));
        r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
        inv = _mm_div_ps(_mm_set1_ps(1.0f), _mm_sqrt_ps(_mm_max_ps(r2, _mm_set1_ps(kMinR2))));
        inv2 = _mm_mul_ps(inv, inv);
        mx = _mm_loadu_ps(s.mx + i);
        my = _mm_loadu_ps(s.my + i);
        mz = _mm_loadu_ps(s.mz + i);
        dot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, mx), _mm_mul_ps(dy, my)), _mm_mul_ps(dz, mz));
    }
};
#endif

// Field sum (without the 1/4pi) at target t from sources [b, e). C = how a source's field
// differs from its point dipole at targets within its core radius (see Core).
template <Core C>
inline void fieldKernel(const float t[3], const Sources& s, size_t b, size_t e, float h[3]) {
    size_t i = b;
    float hx = 0, hy = 0, hz = 0;
#ifdef FERRO_DIPOLE_SSE
    if (e - b >= 4) {
        const __m128 tv[3] = {_mm_set1_ps(t[0]), _mm_set1_ps(t[1]), _mm_set1_ps(t[2])};
        const __m128 three = _mm_set1_ps(3.0f);
        __m128 ax = _mm_setzero_ps(), ay = _mm_setzero_ps(), az = _mm_setzero_ps();
        for (; i + 4 <= e; i += 4) {
            const SourcePairs4 p(tv, s, i);
            __m128 c2 = _mm_mul_ps(p.inv2, p.inv);                 // 1/r^3
            __m128 c1 = _mm_mul_ps(_mm_mul_ps(three, c2), p.inv2); // 3/r^5
            if (C == Core::Sphere) {
                const __m128 in = _mm_cmplt_ps(p.r2, _mm_loadu_ps(s.a2 + i));
                const __m128 ai = _mm_loadu_ps(s.ainv + i);
                c1 = _mm_andnot_ps(in, c1);
                c2 = _mm_or_ps(_mm_and_ps(in, _mm_mul_ps(_mm_mul_ps(ai, ai), ai)), _mm_andnot_ps(in, c2));
            } else if (C == Core::Wendland) {
                const __m128 in = _mm_cmplt_ps(p.r2, _mm_loadu_ps(s.a2 + i));
                if (_mm_movemask_ps(in)) {
                    const v4sf ai = (v4sf)_mm_loadu_ps(s.ainv + i);
                    const v4sf q = (v4sf)_mm_mul_ps(_mm_mul_ps(p.r2, p.inv), (__m128)ai);
                    const v4sf ai3 = ai * ai * ai, ai5 = ai3 * ai * ai;
                    const __m128 w2 = (__m128)(wendlandC2(q) * ai3), w1 = (__m128)(wendlandC1(q) * ai5);
                    c1 = _mm_or_ps(_mm_and_ps(in, w1), _mm_andnot_ps(in, c1));
                    c2 = _mm_or_ps(_mm_and_ps(in, w2), _mm_andnot_ps(in, c2));
                }
            }
            const __m128 k = _mm_mul_ps(c1, p.dot);
            ax = _mm_add_ps(ax, _mm_sub_ps(_mm_mul_ps(k, p.dx), _mm_mul_ps(c2, p.mx)));
            ay = _mm_add_ps(ay, _mm_sub_ps(_mm_mul_ps(k, p.dy), _mm_mul_ps(c2, p.my)));
            az = _mm_add_ps(az, _mm_sub_ps(_mm_mul_ps(k, p.dz), _mm_mul_ps(c2, p.mz)));
        }
        alignas(16) float lx[4], ly[4], lz[4];
        _mm_store_ps(lx, ax);
        _mm_store_ps(ly, ay);
        _mm_store_ps(lz, az);
        hx = (lx[0] + lx[1]) + (lx[2] + lx[3]);
        hy = (ly[0] + ly[1]) + (ly[2] + ly[3]);
        hz = (lz[0] + lz[1]) + (lz[2] + lz[3]);
    }
#endif
    for (; i < e; ++i) {
        const float dx = t[0] - s.x[i], dy = t[1] - s.y[i], dz = t[2] - s.z[i];
        const float r2 = dx * dx + dy * dy + dz * dz;
        const float inv = 1.0f / std::sqrt(std::max(r2, kMinR2));
        float c2 = inv * inv * inv, c1 = 3.0f * c2 * inv * inv;
        if (C != Core::Point && r2 < s.a2[i]) {
            const float ai = s.ainv[i], ai3 = ai * ai * ai;
            if (C == Core::Sphere) {
                c1 = 0;
                c2 = ai3;
            } else {
                const float q = r2 * inv * ai;
                c1 = wendlandC1(q) * ai3 * ai * ai;
                c2 = wendlandC2(q) * ai3;
            }
        }
        const float dot = dx * s.mx[i] + dy * s.my[i] + dz * s.mz[i];
        hx += c1 * dot * dx - c2 * s.mx[i];
        hy += c1 * dot * dy - c2 * s.my[i];
        hz += c1 * dot * dz - c2 * s.mz[i];
    }
    h[0] += hx;
    h[1] += hy;
    h[2] += hz;
}

// Gradient sum (without 1/4pi) at t from sources [b, e): g = xx, yy, zz, xy, xz, yz.
// Sphere: sources whose sphere contains t contribute nothing (uniform field inside);
// Wendland: the smoothed dipole's Jacobian within the support.
template <Core C>
inline void gradientKernel(const float t[3], const Sources& s, size_t b, size_t e, float g[6]) {
    float acc[6] = {0, 0, 0, 0, 0, 0};
    size_t i = b;
#ifdef FERRO_DIPOLE_SSE
    if (e - b >= 4) {
        const __m128 tv[3] = {_mm_set1_ps(t[0]), _mm_set1_ps(t[1]), _mm_set1_ps(t[2])};
        const __m128 three = _mm_set1_ps(3.0f), five = _mm_set1_ps(5.0f), two = _mm_set1_ps(2.0f);
        __m128 a[6] = {_mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps(),
                       _mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps()};
        for (; i + 4 <= e; i += 4) {
            const SourcePairs4 p(tv, s, i);
            const __m128 dx = p.dx, dy = p.dy, dz = p.dz, mx = p.mx, my = p.my, mz = p.mz, dot = p.dot;
            __m128 c5 = _mm_mul_ps(three, _mm_mul_ps(_mm_mul_ps(p.inv2, p.inv2), p.inv)); // 3/r^5
            __m128 c7 = _mm_mul_ps(five, _mm_mul_ps(c5, p.inv2));                           // 15/r^7
            if (C == Core::Sphere) {
                const __m128 out = _mm_cmpge_ps(p.r2, _mm_loadu_ps(s.a2 + i));
                c5 = _mm_and_ps(out, c5);
                c7 = _mm_and_ps(out, c7);
            } else if (C == Core::Wendland) {
                const __m128 in = _mm_cmplt_ps(p.r2, _mm_loadu_ps(s.a2 + i));
                if (_mm_movemask_ps(in)) {
                    const v4sf ai = (v4sf)_mm_loadu_ps(s.ainv + i);
                    const v4sf q = (v4sf)_mm_mul_ps(_mm_mul_ps(p.r2, p.inv), (__m128)ai);
                    const v4sf ai2 = ai * ai, ai3 = ai2 * ai, ai6 = ai3 * ai3;
                    const __m128 w5 = (__m128)(wendlandC1(q) * ai3 * ai2);
                    const __m128 w7 = (__m128)(420.0f * (v4sf)p.inv * ai6 + wendlandC3Smooth(q) * ai6 * ai);
                    c5 = _mm_or_ps(_mm_and_ps(in, w5), _mm_andnot_ps(in, c5));
                    c7 = _mm_or_ps(_mm_and_ps(in, w7), _mm_andnot_ps(in, c7));
                }
            }
            const __m128 tt = _mm_mul_ps(c5, dot), u = _mm_mul_ps(c7, dot);
            const __m128 c52 = _mm_mul_ps(two, c5);
            a[0] = _mm_add_ps(a[0], _mm_sub_ps(_mm_add_ps(tt, _mm_mul_ps(c52, _mm_mul_ps(dx, mx))), _mm_mul_ps(u, _mm_mul_ps(dx, dx))));
            a[1] = _mm_add_ps(a[1], _mm_sub_ps(_mm_add_ps(tt, _mm_mul_ps(c52, _mm_mul_ps(dy, my))), _mm_mul_ps(u, _mm_mul_ps(dy, dy))));
            a[2] = _mm_add_ps(a[2], _mm_sub_ps(_mm_add_ps(tt, _mm_mul_ps(c52, _mm_mul_ps(dz, mz))), _mm_mul_ps(u, _mm_mul_ps(dz, dz))));
            a[3] = _mm_add_ps(a[3], _mm_sub_ps(_mm_mul_ps(c5, _mm_add_ps(_mm_mul_ps(dx, my), _mm_mul_ps(mx, dy))), _mm_mul_ps(u, _mm_mul_ps(dx, dy))));
            a[4] = _mm_add_ps(a[4], _mm_sub_ps(_mm_mul_ps(c5, _mm_add_ps(_mm_mul_ps(dx, mz), _mm_mul_ps(mx, dz))), _mm_mul_ps(u, _mm_mul_ps(dx, dz))));
            a[5] = _mm_add_ps(a[5], _mm_sub_ps(_mm_mul_ps(c5, _mm_add_ps(_mm_mul_ps(dy, mz), _mm_mul_ps(my, dz))), _mm_mul_ps(u, _mm_mul_ps(dy, dz))));
        }
        for (int k = 0; k < 6; ++k) {
            alignas(16) float l[4];
            _mm_store_ps(l, a[k]);
            acc[k] = (l[0] + l[1]) + (l[2] + l[3]);
        }
    }
#endif
    for (; i < e; ++i) {
        const float dx = t[0] - s.x[i], dy = t[1] - s.y[i], dz = t[2] - s.z[i];
        const float r2 = dx * dx + dy * dy + dz * dz;
        if (C == Core::Sphere && r2 < s.a2[i]) continue;
        const float inv = 1.0f / std::sqrt(std::max(r2, kMinR2));
        const float inv2 = inv * inv;
        float c5 = 3.0f * inv2 * inv2 * inv; // 3/r^5
        float c7 = 5.0f * c5 * inv2;         // 15/r^7
        if (C == Core::Wendland && r2 < s.a2[i]) {
            const float ai = s.ainv[i], q = r2 * inv * ai, ai3 = ai * ai * ai, ai6 = ai3 * ai3;
            c5 = wendlandC1(q) * ai3 * ai * ai;
            c7 = 420.0f * inv * ai6 + wendlandC3Smooth(q) * ai6 * ai;
        }
        const float mx = s.mx[i], my = s.my[i], mz = s.mz[i];
        const float dot = dx * mx + dy * my + dz * mz;
        const float tt = c5 * dot, u = c7 * dot;
        acc[0] += tt + 2 * c5 * dx * mx - u * dx * dx;
        acc[1] += tt + 2 * c5 * dy * my - u * dy * dy;
        acc[2] += tt + 2 * c5 * dz * mz - u * dz * dz;
        acc[3] += c5 * (dx * my + mx * dy) - u * dx * dy;
        acc[4] += c5 * (dx * mz + mx * dz) - u * dx * dz;
        acc[5] += c5 * (dy * mz + my * dz) - u * dy * dz;
    }
    for (int k = 0; k < 6; ++k) g[k] += acc[k];
}

// Double-precision field (without 1/4pi) at scaled point p of one particle with core radius
// a (a2 = a^2, ainv = 1/a; 0 for a particle without volume) of kind `core`.
inline void addDipoleD(const double p[3], double sx, double sy, double sz, double mx, double my, double mz,
                       double a2, double ainv, Core core, double h[3]) {
    const double dx = p[0] - sx, dy = p[1] - sy, dz = p[2] - sz;
    const double r2 = dx * dx + dy * dy + dz * dz;
    double c1, c2;
    if (r2 < a2) {
        const double ai3 = ainv * ainv * ainv;
        if (core == Core::Wendland) {
            const double q = std::sqrt(r2) * ainv;
            c1 = wendlandC1(q) * ai3 * ainv * ainv;
            c2 = wendlandC2(q) * ai3;
        } else {
            c1 = 0;
            c2 = ai3;
        }
    } else {
        if (!(r2 > 0)) return; // zero-volume source exactly at p: no moment
        const double inv = 1.0 / std::sqrt(r2);
        c2 = inv * inv * inv;
        c1 = 3.0 * c2 * inv * inv;
    }
    const double k = c1 * (dx * mx + dy * my + dz * mz);
    h[0] += k * dx - c2 * mx;
    h[1] += k * dy - c2 * my;
    h[2] += k * dz - c2 * mz;
}

inline void addDipoleGradientD(const double p[3], double sx, double sy, double sz, double mx, double my,
                               double mz, double a2, double ainv, Core core, Mat3d& G) {
    const double dx = p[0] - sx, dy = p[1] - sy, dz = p[2] - sz;
    const double r2 = dx * dx + dy * dy + dz * dz;
    if (!(r2 > 0) || (r2 < a2 && core == Core::Sphere)) return;
    const Eigen::Vector3d r(dx, dy, dz), m(mx, my, mz);
    const double inv2 = 1.0 / r2, inv = std::sqrt(inv2);
    double c5 = 3.0 * inv2 * inv2 * inv, c7 = 5.0 * c5 * inv2; // 3/r^5, 15/r^7
    if (r2 < a2) {
        const double q = r2 * inv * ainv, ai3 = ainv * ainv * ainv, ai6 = ai3 * ai3;
        c5 = wendlandC1(q) * ai3 * ainv * ainv;
        c7 = 420.0 * inv * ai6 + wendlandC3Smooth(q) * ai6 * ainv;
    }
    const double dot = r.dot(m);
    G += c5 * (dot * Mat3d::Identity() + r * m.transpose() + m * r.transpose()) - (c7 * dot) * (r * r.transpose());
}

/// Exact double sum (without 1/4pi) of the field of all particles `s` [0, n) at the scaled
/// point p, in sorted order.
inline Eigen::Vector3d directFieldD(const double p[3], const Sources& s, size_t n, Core core) {
    double h[3] = {0, 0, 0};
    for (size_t j = 0; j < n; ++j)
        addDipoleD(p, s.x[j], s.y[j], s.z[j], s.mx[j], s.my[j], s.mz[j], s.a2[j], s.ainv[j], core, h);
    return Eigen::Vector3d(h[0], h[1], h[2]);
}


/// Symmetric 3x3 matrix of g = xx yy zz xy xz yz.
template <class T>
inline Eigen::Matrix<T, 3, 3> symmetricMatrix(const T g[6]) {
    Eigen::Matrix<T, 3, 3> J;
    J << g[0], g[3], g[4], g[3], g[1], g[5], g[4], g[5], g[2];
    return J;
}

inline Mat3f symmetric(const float g[6], float s) { return s * symmetricMatrix(g); }

// Morton code: 21 bits per axis interleaved.
inline uint64_t spread21(uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

inline double boxDistance(const float c[3], const float lo[3], const float hi[3]) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
        const double v = c[k] < lo[k] ? lo[k] - c[k] : c[k] > hi[k] ? c[k] - hi[k] : 0.0;
        d2 += v * v;
    }
    return std::sqrt(d2);
}

} // namespace dipole_detail
} // namespace ferro

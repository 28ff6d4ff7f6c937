#include "sim/particlefield/DipoleTree.hpp"

#include "sim/core/Constants.hpp"

#include <Eigen/Cholesky>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#define FERRO_DIPOLE_SSE 1
typedef float v4sf __attribute__((vector_size(16)));
#endif

namespace ferro {

namespace {

constexpr double kInv4Pi = 1.0 / (4.0 * kPi);
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

// ---- Far cells: dipole, quadrupole and octupole moments of a cell's dipoles ----------
//
// A cell's potential is expanded about its centre c: with s_j = x_j - c the offsets of its
// particles, m = sum m_j, Q_ab = sum m_a s_b, O_abc = sum m_a s_b s_c. Only the symmetric
// trace-free parts of Q and O act on a harmonic 1/r, so cells store those (5 + 7 numbers,
// kept as 6 + 10). With r = target - c and T_n the n-th derivative tensors of 1/r:
//   4 pi H_d = m_a T2_da - Q_ab T3_dab + O_abc T4_dabc / 2
//            = (3 rm/r^5 + 15 rQr/r^7 + 52.5 S/r^9) r_d - m_d/r^3 - 6 (Qr)_d/r^5 - 22.5 u_d/r^7
// where rm = r.m, Qr = Q r, rQr = r.Qr, u_d = O_dbc r_b r_c, S = r.u. The truncation error
// is O((rho/d)^3) relative, against O(rho/d) for a bare dipole at the same centre.
constexpr int kCellFloats = 19; // m[3], Q[6] (xx yy zz xy xz yz), O[10] (xxx xxy xxz xyy xyz xzz yyy yyz yzz zzz)

/// Raw moments of a cell's dipoles about the cell centre c, in the scaled units of the tree
/// (lengths in mean particle radii, moments V M in scaled volume x A/m), double precision:
///   m_a = sum_j m_j,a,   Q_ab = sum_j m_j,a s_j,b,   O_a(bc) = sum_j m_j,a s_j,b s_j,c
/// with s_j = x_j - c. O is symmetric in (b, c): six numbers per a, pairs xx yy zz xy xz yz.
/// Built bottom-up by DipoleTree::sumCellMoments: a leaf adds its particles (addDipole), a
/// parent adds its children's moments moved to its own centre (addShifted); storeTraceFree
/// then writes what the far-cell evaluations (cellField, cellGradient) read. All three are
/// linear in the moments, so the tree operator stays linear in M.
struct RawMoments {
    double m[3] = {0, 0, 0};
    double Q[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}; // Q[3 a + b]
    double O[18] = {};                          // O[6 a + pair(b, c)]

    /// Pair index k -> (b, c) of O's symmetric pair: xx yy zz xy xz yz.
    static constexpr int kPairB[6] = {0, 1, 2, 0, 0, 1}, kPairC[6] = {0, 1, 2, 1, 2, 2};

    /// Adds one dipole `dipole` at offset s = x_j - c from the centre.
    void addDipole(const double dipole[3], const double s[3]) {
        for (int a = 0; a < 3; ++a) m[a] += dipole[a];
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) Q[3 * a + b] += dipole[a] * s[b];
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < 6; ++k) O[6 * a + k] += dipole[a] * s[kPairB[k]] * s[kPairC[k]];
    }

    /// Adds `child`, the raw moments of a sub-cell about its own centre c', moved to this
    /// centre: s = c' - c (the binomial shift of the first and second moments).
    void addShifted(const RawMoments& child, const double s[3]) {
        const double* cm = child.m;
        for (int a = 0; a < 3; ++a) m[a] += cm[a];
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) Q[3 * a + b] += child.Q[3 * a + b] + cm[a] * s[b];
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < 6; ++k) {
                const int b = kPairB[k], c = kPairC[k];
                double v = cm[a] * s[b] * s[c];
                v += child.O[6 * a + k] + child.Q[3 * a + b] * s[c] + child.Q[3 * a + c] * s[b];
                O[6 * a + k] += v;
            }
    }

    /// Writes the kCellFloats numbers a far cell is evaluated with: m (3), the symmetric
    /// trace-free part of Q (6: xx yy zz xy xz yz) and of the fully symmetrized O (10: xxx
    /// xxy xxz xyy xyz xzz yyy yyz yzz zzz). Only these act on the harmonic 1/r.
    void storeTraceFree(float out[]) const {
        for (int a = 0; a < 3; ++a) out[a] = float(m[a]);
        const double tr = (Q[0] + Q[4] + Q[8]) / 3.0;
        out[3] = float(Q[0] - tr);
        out[4] = float(Q[4] - tr);
        out[5] = float(Q[8] - tr);
        out[6] = float(0.5 * (Q[1] + Q[3]));
        out[7] = float(0.5 * (Q[2] + Q[6]));
        out[8] = float(0.5 * (Q[5] + Q[7]));
        // O_a(bc) -> fully symmetric, then trace-free: T_abc - (d_ab q_c + d_ac q_b + d_bc q_a)/5
        auto pairIdx = [](int b, int c) {
            if (b > c) std::swap(b, c);
            return b == c ? b : (b == 0 ? (c == 1 ? 3 : 4) : 5);
        };
        auto raw3 = [&](int a, int b, int c) { return O[6 * a + pairIdx(b, c)]; };
        auto sym3 = [&](int a, int b, int c) { return (raw3(a, b, c) + raw3(b, c, a) + raw3(c, a, b)) / 3.0; };
        double q[3];
        for (int a = 0; a < 3; ++a) q[a] = sym3(a, 0, 0) + sym3(a, 1, 1) + sym3(a, 2, 2);
        static const int I3[10][3] = {{0, 0, 0}, {0, 0, 1}, {0, 0, 2}, {0, 1, 1}, {0, 1, 2},
                                      {0, 2, 2}, {1, 1, 1}, {1, 1, 2}, {1, 2, 2}, {2, 2, 2}};
        for (int k = 0; k < 10; ++k) {
            const int a = I3[k][0], b = I3[k][1], c = I3[k][2];
            const double t = sym3(a, b, c) - ((a == b) * q[c] + (a == c) * q[b] + (b == c) * q[a]) / 5.0;
            out[9 + k] = float(t);
        }
    }
};

template <class T>
struct CellTerms {
    T rm, rQr, S, i3, i5, i7, i9;
    T qr[3], u[3], v[6]; // v = O r (symmetric 3x3), u = v r
};

template <class T>
inline void cellTerms(const T& x, const T& y, const T& z, const T& inv, const T* m, const T* q, const T* o,
                      CellTerms<T>& c) {
    const T i2 = inv * inv;
    c.i3 = inv * i2;
    c.i5 = c.i3 * i2;
    c.i7 = c.i5 * i2;
    c.i9 = c.i7 * i2;
    c.rm = x * m[0] + y * m[1] + z * m[2];
    c.qr[0] = q[0] * x + q[3] * y + q[4] * z;
    c.qr[1] = q[3] * x + q[1] * y + q[5] * z;
    c.qr[2] = q[4] * x + q[5] * y + q[2] * z;
    c.rQr = x * c.qr[0] + y * c.qr[1] + z * c.qr[2];
    // v_de = O_dec r_c
    c.v[0] = o[0] * x + o[1] * y + o[2] * z; // xx
    c.v[1] = o[3] * x + o[6] * y + o[7] * z; // yy
    c.v[2] = o[5] * x + o[8] * y + o[9] * z; // zz
    c.v[3] = o[1] * x + o[3] * y + o[4] * z; // xy
    c.v[4] = o[2] * x + o[4] * y + o[5] * z; // xz
    c.v[5] = o[4] * x + o[7] * y + o[8] * z; // yz
    c.u[0] = c.v[0] * x + c.v[3] * y + c.v[4] * z;
    c.u[1] = c.v[3] * x + c.v[1] * y + c.v[5] * z;
    c.u[2] = c.v[4] * x + c.v[5] * y + c.v[2] * z;
    c.S = x * c.u[0] + y * c.u[1] + z * c.u[2];
}

// 4 pi H of one cell at offset r = (x, y, z), 1/|r| = inv.
template <class T>
inline void cellField(const T& x, const T& y, const T& z, const T& inv, const T* m, const T* q, const T* o, T h[3]) {
    CellTerms<T> c;
    cellTerms(x, y, z, inv, m, q, o, c);
    const T A = c.rm * c.i5 * 3.0f + c.rQr * c.i7 * 15.0f + c.S * c.i9 * 52.5f;
    const T r[3] = {x, y, z};
    for (int d = 0; d < 3; ++d) h[d] += A * r[d] - c.i3 * m[d] - c.i5 * c.qr[d] * 6.0f - c.i7 * c.u[d] * 22.5f;
}

// 4 pi dH_d/dx_e of one cell, g = xx yy zz xy xz yz:
//   dipole  3 (delta rm + m_d r_e + m_e r_d)/r^5 - 15 rm r_d r_e / r^7
//   Q      -105 rQr r_d r_e/r^9 + 15 (delta rQr + 2 r_e Qr_d + 2 r_d Qr_e)/r^7 - 6 Q_de/r^5
//   O      -472.5 S r_d r_e/r^11 + 52.5 (delta S + 3 (r_e u_d + r_d u_e))/r^9 - 45 v_de/r^7
template <class T>
inline void cellGradient(const T& x, const T& y, const T& z, const T& inv, const T* m, const T* q, const T* o,
                         T g[6]) {
    CellTerms<T> c;
    cellTerms(x, y, z, inv, m, q, o, c);
    const T i11 = c.i9 * inv * inv;
    const T rr = c.rm * c.i7 * -15.0f - c.rQr * c.i9 * 105.0f - c.S * i11 * 472.5f; // times r_d r_e
    const T dd = c.rm * c.i5 * 3.0f + c.rQr * c.i7 * 15.0f + c.S * c.i9 * 52.5f;    // times delta_de
    // terms symmetric in (d, e): w_d r_e + w_e r_d with w = 3 m/r^5 + 30 Qr/r^7 + 157.5 u/r^9
    T w[3];
    for (int d = 0; d < 3; ++d) w[d] = m[d] * c.i5 * 3.0f + c.qr[d] * c.i7 * 30.0f + c.u[d] * c.i9 * 157.5f;
    const T r[3] = {x, y, z};
    static const int D[6] = {0, 1, 2, 0, 0, 1}, E[6] = {0, 1, 2, 1, 2, 2};
    for (int k = 0; k < 6; ++k) {
        const int d = D[k], e = E[k];
        T t = rr * r[d] * r[e] + w[d] * r[e] + w[e] * r[d] - q[k] * c.i5 * 6.0f - c.v[k] * c.i7 * 45.0f;
        if (d == e) t += dd;
        g[k] += t;
    }
}

// The two quantities the tree evaluates, so that one loop (farSum, cellSumD,
// DipoleTree::treeSum) serves both: FieldTerm, H [A/m] (scaled moment / scaled length^3,
// kOut = 3: x y z), and GradientTerm, dH_d/dx_e [A/m per scaled length] (kOut = 6: xx yy
// zz xy xz yz).
//   add(x, y, z, inv, mom, out): adds 4 pi times one far cell's contribution at offset
//     r = (x, y, z) = target - centre, inv = 1/|r|, from the kCellFloats moments `mom`
//     (RawMoments::storeTraceFree layout);
//   addParticles(core, t, s, b, e, out): adds 4 pi times the exact sum of particles [b, e)
//     of s at t, with their cores of kind `core` (Sphere or Wendland).
template <bool Gradient>
struct TreeTerm {
    static constexpr int kOut = Gradient ? 6 : 3;
    template <class T>
    static void add(const T& x, const T& y, const T& z, const T& inv, const T* mom, T* out) {
        if constexpr (Gradient) cellGradient(x, y, z, inv, mom, mom + 3, mom + 9, out);
        else cellField(x, y, z, inv, mom, mom + 3, mom + 9, out);
    }
    static void addParticles(Core core, const float t[3], const Sources& s, size_t b, size_t e, float* out) {
        if constexpr (Gradient) {
            if (core == Core::Wendland) gradientKernel<Core::Wendland>(t, s, b, e, out);
            else gradientKernel<Core::Sphere>(t, s, b, e, out);
        } else {
            if (core == Core::Wendland) fieldKernel<Core::Wendland>(t, s, b, e, out);
            else fieldKernel<Core::Sphere>(t, s, b, e, out);
        }
    }
};
using FieldTerm = TreeTerm<false>;
using GradientTerm = TreeTerm<true>;

// Far-cell sums over a gathered buffer: 22 SoA arrays of `count` floats (centre x y z,
// then the kCellFloats moments), 4 cells at a time.
constexpr int kFarArrays = 3 + kCellFloats;

#ifdef FERRO_DIPOLE_SSE
inline v4sf load4(const float* p) { return (v4sf)_mm_loadu_ps(p); }
inline v4sf invSqrt4(v4sf r2) {
    return (v4sf)_mm_div_ps(_mm_set1_ps(1.0f), _mm_sqrt_ps(_mm_max_ps((__m128)r2, _mm_set1_ps(kMinR2))));
}
inline float hsum(v4sf v) { return (v[0] + v[1]) + (v[2] + v[3]); }
#endif

/// Adds to out[Term::kOut] the sum (without 1/4pi) of Term over the `count` far cells in
/// `buf` (gatherFar's layout) at target t, all in the tree's scaled float units. Four cells
/// at a time with SSE, the rest one by one; the order of the sum is fixed.
template <class Term>
inline void farSum(const float t[3], const float* buf, size_t count, float out[]) {
    size_t i = 0;
#ifdef FERRO_DIPOLE_SSE
    v4sf acc[Term::kOut] = {};
    for (; i + 4 <= count; i += 4) {
        const v4sf x = t[0] - load4(buf + i), y = t[1] - load4(buf + count + i), z = t[2] - load4(buf + 2 * count + i);
        v4sf mom[kCellFloats];
        for (int k = 0; k < kCellFloats; ++k) mom[k] = load4(buf + (3 + k) * count + i);
        Term::add(x, y, z, invSqrt4(x * x + y * y + z * z), mom, acc);
    }
    for (int d = 0; d < Term::kOut; ++d) out[d] += hsum(acc[d]);
#endif
    for (; i < count; ++i) {
        const float x = t[0] - buf[i], y = t[1] - buf[count + i], z = t[2] - buf[2 * count + i];
        float mom[kCellFloats];
        for (int k = 0; k < kCellFloats; ++k) mom[k] = buf[(3 + k) * count + i];
        Term::add(x, y, z, 1.0f / std::sqrt(std::max(x * x + y * y + z * z, kMinR2)), mom, out);
    }
}

/// Symmetric 3x3 matrix of g = xx yy zz xy xz yz.
template <class T>
Eigen::Matrix<T, 3, 3> symmetricMatrix(const T g[6]) {
    Eigen::Matrix<T, 3, 3> J;
    J << g[0], g[3], g[4], g[3], g[1], g[5], g[4], g[5], g[2];
    return J;
}

Mat3f symmetric(const float g[6], float s) { return s * symmetricMatrix(g); }

// Morton code: 21 bits per axis interleaved.
uint64_t spread21(uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

double boxDistance(const float c[3], const float lo[3], const float hi[3]) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
        const double v = c[k] < lo[k] ? lo[k] - c[k] : c[k] > hi[k] ? c[k] - hi[k] : 0.0;
        d2 += v * v;
    }
    return std::sqrt(d2);
}

} // namespace

void DipoleTree::build(const std::vector<Vec3>& x, const std::vector<Real>& volume, double openingAngle,
                       int leafSize) {
    const size_t n = x.size();
    theta_ = openingAngle > 0 ? std::clamp(openingAngle, 0.05, 1.0) : 0.0;
    leafSize = std::max(leafSize, 1);
    auto vol = [&](size_t i) {
        const double v = i < volume.size() ? double(volume[i]) : 0.0;
        return std::isfinite(v) && v > 0 ? v : 0.0;
    };
    auto pos = [&](size_t i) {
        const Vec3d p = x[i].cast<double>();
        return p.allFinite() ? p : Vec3d::Zero();
    };
    // Length unit: mean particle radius; origin: centre of the bounding box.
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    double sumA = 0;
    size_t countA = 0;
    for (size_t i = 0; i < n; ++i) {
        const Vec3d p = pos(i);
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
        if (vol(i) > 0) {
            sumA += std::cbrt(3.0 * vol(i) / (4.0 * kPi));
            ++countA;
        }
    }
    if (n == 0) lo = hi = Vec3d::Zero();
    scale_ = countA > 0 && sumA > 0 ? sumA / double(countA) : 1.0;
    origin_ = 0.5 * (lo + hi);
    // A cubic root cell: octants are then cubes, the shape Barnes-Hut cells should have (a
    // per-axis scale would make flat pancakes of a fluid layer, with large radii).
    const Vec3d extent = Vec3d::Constant(std::max((hi - lo).maxCoeff(), 1e-30));

    std::vector<std::pair<uint64_t, uint32_t>> keys(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3d u = (pos(i) - lo).cwiseQuotient(extent) * double((1 << 21) - 1);
            const uint64_t code = spread21(uint64_t(std::clamp(u.x(), 0.0, 2097151.0))) |
                                  spread21(uint64_t(std::clamp(u.y(), 0.0, 2097151.0))) << 1 |
                                  spread21(uint64_t(std::clamp(u.z(), 0.0, 2097151.0))) << 2;
            keys[i] = {code, uint32_t(i)};
        }
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    order_.resize(n);
    std::vector<uint64_t> codes(n);
    for (size_t k = 0; k < n; ++k) {
        order_[k] = keys[k].second;
        codes[k] = keys[k].first;
    }
    for (auto* v : {&px_, &py_, &pz_, &a2_, &ainv_, &vol_, &mx_, &my_, &mz_}) v->assign(n, 0.0f);
    const double inv = 1.0 / scale_;
    for (size_t k = 0; k < n; ++k) {
        const size_t i = order_[k];
        const Vec3d p = (pos(i) - origin_) * inv;
        px_[k] = float(p.x());
        py_[k] = float(p.y());
        pz_[k] = float(p.z());
        const double v = vol(i) * inv * inv * inv;
        vol_[k] = float(v);
        // Core radius: the sphere of volume v, or the smoothing kernel's support.
        const double a = smoothing_ > 0 ? smoothing_ * std::cbrt(v) : std::cbrt(3.0 * v / (4.0 * kPi));
        a2_[k] = float(a * a);
        ainv_[k] = a > 0 ? float(1.0 / a) : 0.0f;
    }

    nodes_.clear();
    leaves_.clear();
    leafBegin_.clear();
    leafSize_ = uint32_t(leafSize);
    if (n > 0) {
        nodes_.emplace_back();
        fillNode(0, 0, uint32_t(n), 0, codes);
        for (uint32_t i = 0; i < nodes_.size(); ++i)
            if (nodes_[i].childCount == 0) leaves_.push_back(i);
        std::sort(leaves_.begin(), leaves_.end(),
                  [&](uint32_t a, uint32_t b) { return nodes_[a].begin < nodes_[b].begin; });
        for (uint32_t l : leaves_) leafBegin_.push_back(nodes_[l].begin);
    }
    cell_.assign(nodes_.size() * kCellFloats, 0.0f);
    farStart_.assign(1, 0);
    nearStart_.assign(1, 0);
    farCells_.clear();
    nearRanges_.clear();
    surfaceWeight_.clear();
    surfaceNormal_.clear();
    localCorrection_.clear();
    if (coreOf(smoothing_) == Core::Wendland) computeSurfaceTerms();
    if (theta_ > 0 && n > 0) buildInteractionLists();
}

void DipoleTree::fillNode(uint32_t index, uint32_t begin, uint32_t end, int level,
                          const std::vector<uint64_t>& codes) {
    nodes_[index].begin = begin;
    nodes_[index].end = end;
    finishNode(nodes_[index]);
    if (end - begin <= leafSize_) return;
    // Descend until the range splits into more than one octant (skips empty levels).
    std::vector<uint32_t> cuts;
    for (; level < 21; ++level) {
        const int shift = 3 * (20 - level);
        cuts.assign(1, begin);
        for (uint32_t digit = 1; digit < 8; ++digit) {
            const auto it = std::partition_point(codes.begin() + begin, codes.begin() + end, [&](uint64_t c) {
                return ((c >> shift) & 7u) < digit;
            });
            cuts.push_back(uint32_t(it - codes.begin()));
        }
        cuts.push_back(end);
        int nonEmpty = 0;
        for (int d = 0; d < 8; ++d) nonEmpty += cuts[d + 1] > cuts[d];
        if (nonEmpty > 1) break;
    }
    if (level >= 21) return; // identical codes: one leaf however many particles
    const uint32_t first = uint32_t(nodes_.size());
    uint32_t count = 0;
    for (int d = 0; d < 8; ++d)
        if (cuts[d + 1] > cuts[d]) ++count;
    nodes_.resize(nodes_.size() + count);
    nodes_[index].firstChild = first;
    nodes_[index].childCount = count;
    uint32_t c = first;
    const std::vector<uint32_t> myCuts = cuts; // fillNode below reuses no state, but be explicit
    for (int d = 0; d < 8; ++d)
        if (myCuts[d + 1] > myCuts[d]) fillNode(c++, myCuts[d], myCuts[d + 1], level + 1, codes);
}

void DipoleTree::finishNode(Node& node) const {
    double vs = 0, c[3] = {0, 0, 0};
    float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                   std::numeric_limits<float>::max()};
    float hi[3] = {-lo[0], -lo[1], -lo[2]};
    float maxA2 = 0;
    for (uint32_t k = node.begin; k < node.end; ++k) {
        const double w = vol_[k];
        vs += w;
        c[0] += w * px_[k];
        c[1] += w * py_[k];
        c[2] += w * pz_[k];
        const float p[3] = {px_[k], py_[k], pz_[k]};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
        maxA2 = std::max(maxA2, a2_[k]);
    }
    if (vs > 0) {
        for (double& v : c) v /= vs;
    } else { // no volume: plain mean (the cell has no moment anyway)
        c[0] = c[1] = c[2] = 0;
        for (uint32_t k = node.begin; k < node.end; ++k) {
            c[0] += px_[k];
            c[1] += py_[k];
            c[2] += pz_[k];
        }
        for (double& v : c) v /= double(std::max<uint32_t>(1, node.end - node.begin));
    }
    double r2 = 0;
    for (uint32_t k = node.begin; k < node.end; ++k) {
        const double dx = px_[k] - c[0], dy = py_[k] - c[1], dz = pz_[k] - c[2];
        r2 = std::max(r2, dx * dx + dy * dy + dz * dz);
    }
    for (int a = 0; a < 3; ++a) {
        node.c[a] = float(c[a]);
        node.lo[a] = lo[a];
        node.hi[a] = hi[a];
    }
    // Round the radius up so float centres never make a cell look smaller than it is.
    node.radius = float(std::sqrt(r2) * (1 + 1e-6) + 1e-6);
    node.maxA = std::sqrt(maxA2);
}

bool DipoleTree::accept(const Node& cell, double d) const {
    // Barnes-Hut: cell size (largest side of its particles' box) over distance below theta;
    // and every particle sphere of the cell nearer to its centre than the target is, so the
    // expansion converges and the target lies outside all of the cell's spheres.
    const double size = std::max({cell.hi[0] - cell.lo[0], cell.hi[1] - cell.lo[1], cell.hi[2] - cell.lo[2]});
    return size < theta_ * d && cell.radius + cell.maxA < d;
}

void DipoleTree::buildInteractionLists() {
    const size_t L = leaves_.size();
    std::vector<std::vector<uint32_t>> far(L), near(L);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, L, 8), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint32_t> stack;
        for (size_t l = r.begin(); l < r.end(); ++l) {
            const Node& target = nodes_[leaves_[l]];
            auto& f = far[l];
            auto& nr = near[l];
            stack.assign(1, 0);
            while (!stack.empty()) {
                const uint32_t ni = stack.back();
                stack.pop_back();
                const Node& cell = nodes_[ni];
                const bool ok = accept(cell, boxDistance(cell.c, target.lo, target.hi));
                if (ok && cell.end - cell.begin > kMinCellCount) {
                    f.push_back(ni);
                } else if (ok || cell.childCount == 0) {
                    if (!nr.empty() && nr.back() == cell.begin) nr.back() = cell.end;
                    else {
                        nr.push_back(cell.begin);
                        nr.push_back(cell.end);
                    }
                } else {
                    for (uint32_t c = cell.childCount; c-- > 0;) stack.push_back(cell.firstChild + c);
                }
            }
        }
    });
    farStart_.resize(L + 1);
    nearStart_.resize(L + 1);
    farStart_[0] = nearStart_[0] = 0;
    for (size_t l = 0; l < L; ++l) {
        farStart_[l + 1] = farStart_[l] + uint32_t(far[l].size());
        nearStart_[l + 1] = nearStart_[l] + uint32_t(near[l].size());
    }
    farCells_.resize(farStart_[L]);
    nearRanges_.resize(nearStart_[L]);
    for (size_t l = 0; l < L; ++l) {
        std::copy(far[l].begin(), far[l].end(), farCells_.begin() + farStart_[l]);
        std::copy(near[l].begin(), near[l].end(), nearRanges_.begin() + nearStart_[l]);
    }
}

void DipoleTree::interactionCounts(double& farPerTarget, double& nearPerTarget) const {
    double f = 0, nn = 0;
    for (size_t l = 0; l + 1 < farStart_.size(); ++l) {
        const double targets = nodes_[leaves_[l]].end - nodes_[leaves_[l]].begin;
        f += targets * (farStart_[l + 1] - farStart_[l]);
        double s = 0;
        for (uint32_t q = nearStart_[l]; q < nearStart_[l + 1]; q += 2) s += nearRanges_[q + 1] - nearRanges_[q];
        nn += targets * s;
    }
    const double n = std::max<double>(1, double(size()));
    farPerTarget = f / n;
    nearPerTarget = nn / n;
}

void DipoleTree::setMagnetization(const Eigen::VectorXd& M) {
    const size_t n = size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8192), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
            mx_[k] = float(vol_[k] * M[3 * k]);
            my_[k] = float(vol_[k] * M[3 * k + 1]);
            mz_[k] = float(vol_[k] * M[3 * k + 2]);
        }
    });
    sumCellMoments();
}

void DipoleTree::setMagnetizationUnsorted(const std::vector<Vec3>& M) {
    const size_t n = size();
    for (size_t k = 0; k < n; ++k) {
        const size_t i = order_[k];
        const Vec3 m = i < M.size() && M[i].allFinite() ? M[i] : Vec3::Zero();
        mx_[k] = vol_[k] * m.x();
        my_[k] = vol_[k] * m.y();
        mz_[k] = vol_[k] * m.z();
    }
    sumCellMoments();
}

void DipoleTree::sumCellMoments() {
    // Raw moments about each cell's centre, bottom-up: leaves from their particles, parents
    // by shifting their children's moments (children have larger indices than their parent:
    // one backward sweep). Then the symmetric trace-free parts go to cell_.
    const size_t nn = nodes_.size();
    std::vector<RawMoments> raw(nn);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t l = r.begin(); l < r.end(); ++l) {
            const Node& node = nodes_[leaves_[l]];
            RawMoments& R = raw[leaves_[l]];
            for (uint32_t k = node.begin; k < node.end; ++k) {
                const double m[3] = {mx_[k], my_[k], mz_[k]};
                const double s[3] = {px_[k] - double(node.c[0]), py_[k] - double(node.c[1]),
                                     pz_[k] - double(node.c[2])};
                R.addDipole(m, s);
            }
        }
    });
    for (size_t i = nn; i-- > 0;) {
        const Node& node = nodes_[i];
        for (uint32_t ch = node.firstChild; ch < node.firstChild + node.childCount; ++ch) {
            const double s[3] = {double(nodes_[ch].c[0]) - node.c[0], double(nodes_[ch].c[1]) - node.c[1],
                                 double(nodes_[ch].c[2]) - node.c[2]};
            raw[i].addShifted(raw[ch], s);
        }
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nn, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) raw[i].storeTraceFree(&cell_[i * kCellFloats]);
    });
}

void DipoleTree::gatherFar(size_t leaf, std::vector<float>& buf, size_t& count) const {
    const uint32_t b = farStart_[leaf], e = farStart_[leaf + 1];
    count = e - b;
    buf.resize(kFarArrays * std::max<size_t>(count, 1));
    for (uint32_t q = b; q < e; ++q) {
        const uint32_t c = farCells_[q];
        const size_t j = q - b;
        for (int a = 0; a < 3; ++a) buf[a * count + j] = nodes_[c].c[a];
        const float* mom = &cell_[size_t(c) * kCellFloats];
        for (int k = 0; k < kCellFloats; ++k) buf[(3 + k) * count + j] = mom[k];
    }
}

template <class Term>
void DipoleTree::treeSum(size_t leaf, size_t k, const std::vector<float>& buf, size_t farCount, float* out) const {
    const float t[3] = {px_[k], py_[k], pz_[k]};
    farSum<Term>(t, buf.data(), farCount, out);
    const Sources near{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                       ainv_.data()};
    for (uint32_t q = nearStart_[leaf]; q < nearStart_[leaf + 1]; q += 2)
        Term::addParticles(coreOf(smoothing_), t, near, nearRanges_[q], nearRanges_[q + 1], out);
}

template <class Visit>
void DipoleTree::forEachTreeTarget(Visit&& visit) const {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<float> buf;
        for (size_t l = r.begin(); l < r.end(); ++l) {
            size_t farCount = 0;
            gatherFar(l, buf, farCount);
            const Node& node = nodes_[leaves_[l]];
            for (uint32_t k = node.begin; k < node.end; ++k) visit(l, k, buf, farCount);
        }
    });
}

void DipoleTree::treeFieldAt(size_t leaf, size_t k, const std::vector<float>& buf, size_t farCount,
                             double h[3]) const {
    float acc[3] = {0, 0, 0};
    treeSum<FieldTerm>(leaf, k, buf, farCount, acc);
    for (int a = 0; a < 3; ++a) h[a] = kInv4Pi * double(acc[a]);
    addSurfaceTerm(k, h);
}

void DipoleTree::addSurfaceTerm(size_t k, double h[3]) const {
    if (!(vol_[k] > 0)) return;
    if (!localCorrection_.empty()) {
        // h -= D_k M_k (D_k row-major, see computeLocalCorrection); M = moment / volume.
        const float* D = &localCorrection_[9 * k];
        const double m[3] = {mx_[k] / double(vol_[k]), my_[k] / double(vol_[k]), mz_[k] / double(vol_[k])};
        for (int a = 0; a < 3; ++a) h[a] -= D[3 * a] * m[0] + D[3 * a + 1] * m[1] + D[3 * a + 2] * m[2];
    }
    if (surfaceWeight_.empty() || !(surfaceWeight_[k] > 0)) return;
    const float* nk = &surfaceNormal_[3 * k];
    // M = moment / volume (both in scaled units: A/m).
    const double mn = (double(mx_[k]) * nk[0] + double(my_[k]) * nk[1] + double(mz_[k]) * nk[2]) / vol_[k];
    for (int a = 0; a < 3; ++a) h[a] -= double(surfaceWeight_[k]) * mn * nk[a];
}

void DipoleTree::leavesWithin(const Node& target, double reach, std::vector<uint32_t>& stack,
                              std::vector<uint32_t>& ranges) const {
    auto boxGap = [](const Node& a, const Node& b) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k) {
            const double g = std::max({0.0, double(a.lo[k]) - b.hi[k], double(b.lo[k]) - a.hi[k]});
            d2 += g * g;
        }
        return std::sqrt(d2);
    };
    ranges.clear();
    stack.assign(1, 0);
    while (!stack.empty()) {
        const Node& node = nodes_[stack.back()];
        stack.pop_back();
        if (boxGap(node, target) >= reach) continue;
        if (node.childCount > 0) {
            for (uint32_t c = 0; c < node.childCount; ++c) stack.push_back(node.firstChild + c);
        } else {
            ranges.push_back(node.begin);
            ranges.push_back(node.end);
        }
    }
}

void DipoleTree::computeSurfaceTerms() {
    // n_k = sum_j V_j W_j(x_k - x_j), the filled fraction of particle k's kernel (1 inside
    // the fluid), and its gradient. Targets are grouped by leaf: one range search of the
    // octree per leaf (cells whose box is within the largest support of the leaf's box),
    // then every target of the leaf runs over those candidates. Outward normal = -grad n.
    const size_t n = size();
    surfaceWeight_.assign(n, 0.0f);
    surfaceNormal_.assign(3 * n, 0.0f);
    if (n == 0 || nodes_.empty()) return;
    const float reach = nodes_[0].maxA; // largest support
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint32_t> stack, ranges;
        for (size_t l = r.begin(); l < r.end(); ++l) {
            const Node& target = nodes_[leaves_[l]];
            leavesWithin(target, reach, stack, ranges);
            for (uint32_t k = target.begin; k < target.end; ++k) {
                const float px = px_[k], py = py_[k], pz = pz_[k];
                double dens = 0, grad[3] = {0, 0, 0};
                for (size_t q = 0; q < ranges.size(); q += 2)
                    for (uint32_t j = ranges[q]; j < ranges[q + 1]; ++j) {
                        const float dx = px - px_[j], dy = py - py_[j], dz = pz - pz_[j];
                        const float r2 = dx * dx + dy * dy + dz * dz;
                        if (!(r2 < a2_[j])) continue;
                        const float ai = ainv_[j], rr = std::sqrt(r2), qq = rr * ai, u = 1 - qq;
                        const float c = float(21.0 / (2.0 * kPi)) * ai * ai * ai * vol_[j];
                        dens += c * u * u * u * u * (1 + 4 * qq);
                        if (rr > 0) {
                            const float dW = -20.0f * c * ai * qq * u * u * u / rr; // (dW/dr) / r
                            grad[0] += dW * dx;
                            grad[1] += dW * dy;
                            grad[2] += dW * dz;
                        }
                    }
                const double g = std::sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]);
                // Onset: the deficit 1 - n ramps in between 0.05 and 0.15. Inside a disordered
                // fluid n scatters by a few percent (5 % RMS on a 0.2-jittered lattice), and
                // every interior particle with n < 1 got a term along a random "normal" that
                // only ever lowers H: on the jittered ball of the tests that was a bias of
                // ~1 % of the interior field at chi0 = 10 and part of the scatter. A real
                // surface has deficits of 0.1-0.5 (0.5 in the top layer of a flat surface).
                const double deficit = 1 - dens;
                const double t = surfaceOnset_ ? std::clamp((deficit - 0.05) / 0.10, 0.0, 1.0) : (deficit > 0 ? 1.0 : 0.0);
                if (t > 0 && g > 0) {
                    surfaceWeight_[k] = float(t * t * (3 - 2 * t) * deficit);
                    for (int a = 0; a < 3; ++a) surfaceNormal_[3 * k + a] = float(-grad[a] / g);
                }
            }
        }
    });
}

void DipoleTree::computeLocalCorrection(bool useTree) {
    // K_k = the field at particle k of a uniform unit magnetization along each axis (one
    // column per axis): the full operator, surface term included, tree or exact as the
    // solve will evaluate it. K_k = N(x_k) + noise_k: N is the body's demagnetization
    // tensor, smooth on the body's scale; the noise is the particle-scale part (the
    // neighbours' positions). D_k = K_k - <K>_k, <K>_k the kernel-weighted mean of the
    // neighbours' K (k itself excluded, support kCorrectionReach times the particle's),
    // keeps N and removes the noise; it is applied only in the interior (fill ramp).
    const size_t n = size();
    localCorrection_.clear();
    if (n == 0 || coreOf(smoothing_) != Core::Wendland || nodes_.empty()) return;
    if (useTree && !(theta_ > 0)) useTree = false;
    const std::vector<float> mx = mx_, my = my_, mz = mz_; // restored below
    std::vector<double> K(9 * n);
    Eigen::VectorXd unit(3 * n), H;
    for (int c = 0; c < 3; ++c) {
        unit.setZero();
        for (size_t k = 0; k < n; ++k) unit[3 * k + c] = 1.0;
        setMagnetization(unit);
        fieldAtParticles(H, useTree);
        for (size_t k = 0; k < n; ++k)
            for (int a = 0; a < 3; ++a) K[9 * k + 3 * a + c] = H[3 * k + a];
    }
    mx_ = mx;
    my_ = my;
    mz_ = mz;
    sumCellMoments();

    std::vector<float> D(9 * n, 0.0f);
    const double reach = kCorrectionReach * nodes_[0].maxA;
    auto wendland = [](double r2, double A2) { // 2 pi A^3 / 21 * W(r; A): the shape only
        const double q = std::sqrt(r2 / A2), u = 1 - q;
        return u * u * u * u * (1 + 4 * q);
    };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint32_t> stack, ranges;
        for (size_t l = r.begin(); l < r.end(); ++l) {
            const Node& target = nodes_[leaves_[l]];
            leavesWithin(target, reach, stack, ranges);
            for (uint32_t k = target.begin; k < target.end; ++k) {
                // Smooth part of K at x_k: a weighted linear least-squares fit over the
                // neighbours (moving least squares), its value at x_k. A plain weighted mean
                // is biased wherever the neighbourhood is one-sided (within two supports of a
                // surface or a floor) and N(x) varies: it would put the body's own field
                // variation into D.
                Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
                Eigen::Matrix<double, 4, 9> B = Eigen::Matrix<double, 4, 9>::Zero();
                double fill = 0;
                for (size_t q = 0; q < ranges.size(); q += 2)
                    for (uint32_t j = ranges[q]; j < ranges[q + 1]; ++j) {
                        const double dx = px_[j] - px_[k], dy = py_[j] - py_[k], dz = pz_[j] - pz_[k];
                        const double r2 = dx * dx + dy * dy + dz * dz;
                        const double a2 = a2_[j], A2 = kCorrectionReach * kCorrectionReach * a2;
                        if (!(r2 < A2)) continue;
                        // fill n_k with the particle kernel (as computeSurfaceTerms)
                        if (r2 < a2) fill += 21.0 / (2.0 * kPi) * ainv_[j] * ainv_[j] * ainv_[j] * vol_[j] * wendland(r2, a2);
                        if (j == k) continue;
                        const double w = vol_[j] * wendland(r2, A2);
                        const double sA = std::sqrt(A2);
                        const Eigen::Vector4d p(1.0, dx / sA, dy / sA, dz / sA);
                        A.noalias() += w * p * p.transpose();
                        for (int e = 0; e < 9; ++e) B.col(e) += (w * K[9 * size_t(j) + e]) * p;
                    }
                // Interior ramp on the fill: 0 below 0.7, 1 above 0.8 (a flat surface's top
                // layer has 0.5, the next ~0.85-0.9; the noise to remove is a few percent).
                const double t = std::clamp((fill - 0.7) / 0.1, 0.0, 1.0);
                const double wgt = t * t * (3 - 2 * t);
                if (wgt > 0 && A(0, 0) > 0) {
                    const Eigen::LDLT<Eigen::Matrix4d> ldlt(A);
                    const Eigen::Matrix<double, 4, 9> C = ldlt.solve(B);
                    if (ldlt.info() == Eigen::Success && C.allFinite())
                        for (int e = 0; e < 9; ++e) D[9 * k + e] = float(wgt * (K[9 * size_t(k) + e] - C(0, e)));
                }
            }
        }
    });
    localCorrection_ = std::move(D);
}

void DipoleTree::fieldAtParticles(Eigen::VectorXd& H, bool useTree) const {
    const size_t n = size();
    H.setZero(3 * Eigen::Index(n));
    if (n == 0) return;
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    if (useTree && theta_ > 0) {
        forEachTreeTarget([&](size_t l, size_t k, const std::vector<float>& buf, size_t farCount) {
            treeFieldAt(l, k, buf, farCount, &H[3 * k]);
        });
        return;
    }
    const size_t blocks = (n + kDirectTargetBlock - 1) / kDirectTargetBlock;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t blk = r.begin(); blk < r.end(); ++blk) {
            const size_t tb = blk * kDirectTargetBlock, te = std::min(n, tb + kDirectTargetBlock);
            for (size_t sb = 0; sb < n; sb += kDirectChunk) {
                const size_t se = std::min(n, sb + kDirectChunk);
                for (size_t k = tb; k < te; ++k) {
                    const float t[3] = {px_[k], py_[k], pz_[k]};
                    float acc[3] = {0, 0, 0};
                    FieldTerm::addParticles(coreOf(smoothing_), t, src, sb, se, acc);
                    for (int a = 0; a < 3; ++a) H[3 * k + a] += kInv4Pi * double(acc[a]);
                }
            }
            for (size_t k = tb; k < te; ++k) addSurfaceTerm(k, &H[3 * k]);
        }
    });
}

void DipoleTree::fieldAtParticlesDirect(const std::vector<uint32_t>& targets, Eigen::VectorXd& H) const {
    const size_t n = size();
    H.setZero(3 * Eigen::Index(targets.size()));
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, targets.size(), 8), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t q = r.begin(); q < r.end(); ++q) {
            const size_t k = targets[q];
            const float t[3] = {px_[k], py_[k], pz_[k]};
            for (size_t sb = 0; sb < n; sb += kDirectChunk) {
                float acc[3] = {0, 0, 0};
                FieldTerm::addParticles(coreOf(smoothing_), t, src, sb, std::min(n, sb + kDirectChunk), acc);
                for (int a = 0; a < 3; ++a) H[3 * q + a] += kInv4Pi * double(acc[a]);
            }
            addSurfaceTerm(k, &H[3 * q]);
        }
    });
}

void DipoleTree::gradientAtParticles(std::vector<Mat3f>& J, bool useTree) const {
    const size_t n = size();
    J.assign(n, Mat3f::Zero());
    if (n == 0) return;
    const float s = float(kInv4Pi / scale_);
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    if (useTree && theta_ > 0) {
        forEachTreeTarget([&](size_t l, size_t k, const std::vector<float>& buf, size_t farCount) {
            float g[6] = {0, 0, 0, 0, 0, 0};
            treeSum<GradientTerm>(l, k, buf, farCount, g);
            J[k] = symmetric(g, s);
        });
        return;
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
            const float t[3] = {px_[k], py_[k], pz_[k]};
            double gd[6] = {0, 0, 0, 0, 0, 0};
            for (size_t sb = 0; sb < n; sb += kDirectChunk) {
                float g[6] = {0, 0, 0, 0, 0, 0};
                GradientTerm::addParticles(coreOf(smoothing_), t, src, sb, std::min(n, sb + kDirectChunk), g);
                for (int a = 0; a < 6; ++a) gd[a] += g[a];
            }
            const float g[6] = {float(gd[0]), float(gd[1]), float(gd[2]), float(gd[3]), float(gd[4]), float(gd[5])};
            J[k] = symmetric(g, s);
        }
    });
}

size_t DipoleTree::leafOf(size_t k) const {
    const auto it = std::upper_bound(leafBegin_.begin(), leafBegin_.end(), uint32_t(k));
    return size_t(it - leafBegin_.begin()) - 1;
}

Eigen::Vector3d DipoleTree::fieldAtParticleTree(size_t k) const {
    if (!(theta_ > 0)) return fieldAtParticleDirect(k);
    const size_t l = leafOf(k);
    std::vector<float> buf;
    size_t fc = 0;
    gatherFar(l, buf, fc);
    double h[3];
    treeFieldAt(l, k, buf, fc, h);
    return Eigen::Vector3d(h[0], h[1], h[2]);
}

namespace {

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

/// Adds to out[Term::kOut] Term (without 1/4pi) of one far cell with centre c and moments
/// `mom` (cell_ layout) at the scaled point p, in double precision.
template <class Term>
void cellSumD(const double p[3], const float c[3], const float* mom, double out[]) {
    double m[kCellFloats];
    for (int k = 0; k < kCellFloats; ++k) m[k] = mom[k];
    const double x = p[0] - c[0], y = p[1] - c[1], z = p[2] - c[2];
    Term::add(x, y, z, 1.0 / std::sqrt(x * x + y * y + z * z), m, out);
}

/// Exact double sum (without 1/4pi) of the field of all particles `s` [0, n) at the scaled
/// point p, in sorted order.
Eigen::Vector3d directFieldD(const double p[3], const Sources& s, size_t n, Core core) {
    double h[3] = {0, 0, 0};
    for (size_t j = 0; j < n; ++j)
        addDipoleD(p, s.x[j], s.y[j], s.z[j], s.mx[j], s.my[j], s.mz[j], s.a2[j], s.ainv[j], core, h);
    return Eigen::Vector3d(h[0], h[1], h[2]);
}

} // namespace

Eigen::Vector3d DipoleTree::fieldAtParticleDirect(size_t k) const {
    const double p[3] = {px_[k], py_[k], pz_[k]};
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    Eigen::Vector3d h = kInv4Pi * directFieldD(p, src, size(), coreOf(smoothing_));
    addSurfaceTerm(k, h.data());
    return h;
}

Eigen::Vector3d DipoleTree::fieldAtDirect(const Eigen::Vector3d& point) const {
    const Eigen::Vector3d q = (point - origin_) / scale_;
    const double p[3] = {q.x(), q.y(), q.z()};
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    return kInv4Pi * directFieldD(p, src, size(), coreOf(smoothing_));
}

template <class Leaf, class Cell>
void DipoleTree::traverse(const Eigen::Vector3d& q, Leaf&& leaf, Cell&& cell) const {
    if (nodes_.empty()) return;
    uint32_t stack[64 * 8];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes_[stack[--top]];
        const uint32_t self = uint32_t(&node - nodes_.data());
        const double d = (q - Eigen::Vector3d(node.c[0], node.c[1], node.c[2])).norm();
        const bool ok = theta_ > 0 && accept(node, d);
        if (ok && node.end - node.begin > kMinCellCount) cell(self);
        else if (ok || node.childCount == 0) leaf(node.begin, node.end);
        else
            for (uint32_t c = node.childCount; c-- > 0;) stack[top++] = node.firstChild + c;
    }
}

Eigen::Vector3d DipoleTree::fieldAt(const Eigen::Vector3d& point) const {
    const Eigen::Vector3d q = (point - origin_) / scale_;
    const double p[3] = {q.x(), q.y(), q.z()};
    double h[3] = {0, 0, 0};
    traverse(
        q,
        [&](uint32_t b, uint32_t e) {
            for (uint32_t j = b; j < e; ++j)
                addDipoleD(p, px_[j], py_[j], pz_[j], mx_[j], my_[j], mz_[j], a2_[j], ainv_[j], coreOf(smoothing_), h);
        },
        [&](uint32_t c) {
            cellSumD<FieldTerm>(p, nodes_[c].c, &cell_[size_t(c) * kCellFloats], h);
        });
    return kInv4Pi * Eigen::Vector3d(h[0], h[1], h[2]);
}

Mat3d DipoleTree::gradientAt(const Eigen::Vector3d& point) const {
    const Eigen::Vector3d q = (point - origin_) / scale_;
    const double p[3] = {q.x(), q.y(), q.z()};
    Mat3d G = Mat3d::Zero();
    traverse(
        q,
        [&](uint32_t b, uint32_t e) {
            for (uint32_t j = b; j < e; ++j)
                addDipoleGradientD(p, px_[j], py_[j], pz_[j], mx_[j], my_[j], mz_[j], a2_[j], ainv_[j], coreOf(smoothing_), G);
        },
        [&](uint32_t c) {
            double g[6] = {0, 0, 0, 0, 0, 0};
            cellSumD<GradientTerm>(p, nodes_[c].c, &cell_[size_t(c) * kCellFloats], g);
            G += symmetricMatrix(g);
        });
    return (kInv4Pi / scale_) * G;
}

Eigen::Vector3d DipoleTree::centroid() const {
    double v = 0;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < size(); ++k) {
        v += vol_[k];
        c += double(vol_[k]) * Eigen::Vector3d(px_[k], py_[k], pz_[k]);
    }
    return v > 0 ? Eigen::Vector3d(origin_ + scale_ * c / v) : origin_;
}

Eigen::Vector3d DipoleTree::totalMoment() const {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < size(); ++k) m += Eigen::Vector3d(mx_[k], my_[k], mz_[k]);
    return scale_ * scale_ * scale_ * m;
}

} // namespace ferro

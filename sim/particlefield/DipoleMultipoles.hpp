#pragma once
// Internal to sim/particlefield: the far cells of the dipole tree: a cell's dipole,
// quadrupole and octupole moments, their field and Jacobian at a target, and the four-lane
// sum over a gathered list of far cells. Inline, in dipole_detail.
#include "sim/particlefield/DipoleKernels.hpp"

namespace ferro {
namespace dipole_detail {

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

/// Adds to out[Term::kOut] Term (without 1/4pi) of one far cell with centre c and moments
/// `mom` (cell_ layout) at the scaled point p, in double precision.
template <class Term>
void cellSumD(const double p[3], const float c[3], const float* mom, double out[]) {
    double m[kCellFloats];
    for (int k = 0; k < kCellFloats; ++k) m[k] = mom[k];
    const double x = p[0] - c[0], y = p[1] - c[1], z = p[2] - c[2];
    Term::add(x, y, z, 1.0 / std::sqrt(x * x + y * y + z * z), m, out);
}

} // namespace dipole_detail
} // namespace ferro

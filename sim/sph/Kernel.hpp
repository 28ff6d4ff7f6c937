#pragma once
// SPH kernels. All kernels take the support radius h (W = 0 for r >= h), following
// SPlisHSPlasH's convention; the smoothing length of the classic papers is h / 2.
#include "sim/core/Types.hpp"
#include "sim/core/Constants.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ferro {


/// Monaghan's cubic spline, normalized in 3D: integral of W over R^3 is 1.
class CubicSplineKernel {
public:
    explicit CubicSplineKernel(Real supportRadius = 1)
        : h_(supportRadius),
          invH_(1 / supportRadius),
          k_(Real(8.0 / (kPi * double(supportRadius) * supportRadius * supportRadius))),
          l_(Real(48.0 / (kPi * double(supportRadius) * supportRadius * supportRadius))) {}

    Real radius() const { return h_; }

    /// W(r), zero beyond the support. Both spline pieces are computed and one selected,
    /// which compiles to a blend rather than a branch that mispredicts for a third of the
    /// pairs (the loops evaluate it for every pair of every step); grouped as in
    /// CubicSplineKernel4, so the scalar and four-lane paths round alike.
    Real W(Real r) const {
        const Real q = r * invH_;
        const Real f = std::max(1 - q, Real(0));
        const Real inner = Real(6) * (q * q) * (q - 1) + 1;
        const Real outer = 2 * (f * (f * f));
        return k_ * (q <= Real(0.5) ? inner : outer);
    }
    Real W0() const { return k_; }

    /// The scalar s with grad_i W(|x_i - x_j|) = s (x_i - x_j), for r = |x_i - x_j| (zero
    /// beyond the support and at r = 0); blended and grouped like W.
    Real gradWFactor(Real r) const {
        const Real q = r * invH_;
        const Real f = std::max(1 - q, Real(0));
        const Real inner = l_ * (q * (Real(3) * q - 2));
        const Real outer = l_ * (0 - f * f);
        const Real dWdq = q <= Real(0.5) ? inner : outer;
        return r > Real(1e-9) * h_ ? dWdq * invH_ / r : Real(0);
    }

    /// Gradient with respect to x_i of W(|x_i - x_j|), given rij = x_i - x_j and r = |rij|.
    /// Exactly antisymmetric in rij, which makes pairwise forces conserve momentum.
    Vec3 gradW(const Vec3& rij, Real r) const { return rij * gradWFactor(r); }

    /// W and its gradient together for rij = x_i - x_j with r2 = |rij|^2 (one square root).
    void evaluate(const Vec3& rij, Real r2, Real& w, Vec3& grad) const {
        const Real r = std::sqrt(r2);
        w = W(r);
        grad = gradW(rij, r);
    }

    Real invRadius() const { return invH_; }
    Real valueScale() const { return k_; }      ///< 8 / (pi h^3)
    Real gradientScale() const { return l_; }   ///< 48 / (pi h^3)

private:
    Real h_, invH_, k_, l_;
};


/// Akinci et al. 2013 cohesion spline C(r) with support h: attractive at mid range,
/// slightly repulsive for r < h/2 so particles do not clump.
class CohesionKernel {
public:
    explicit CohesionKernel(Real supportRadius = 1)
        : h_(supportRadius),
          c_(Real(32.0 / (kPi * std::pow(double(supportRadius), 9)))),
          h6over64_(Real(std::pow(double(supportRadius), 6) / 64.0)) {}

    /// C(r) of Akinci 2013, units 1/m^3.
    Real C(Real r) const {
        if (r <= 0 || r >= h_) return 0;
        const Real hr = h_ - r;
        const Real v = (hr * (hr * hr)) * (r * (r * r));   // grouped as in CohesionKernel4
        if (2 * r > h_) return c_ * v;
        return c_ * (2 * v - h6over64_);
    }

    Real radius() const { return h_; }
    Real scale() const { return c_; }                ///< 32 / (pi h^9)
    Real innerOffset() const { return h6over64_; }   ///< h^6 / 64

private:
    Real h_, c_, h6over64_;
};

#if defined(__SSE2__)
static_assert(std::is_same<Real, float>::value, "the SSE kernels take four floats");

/// The cubic spline for four distances at once (SSE2, part of every x86-64 CPU): the same
/// formulas as CubicSplineKernel::W and gradWFactor, lane by lane, for the loops
/// that sweep every pair of every step.
class CubicSplineKernel4 {
public:
    explicit CubicSplineKernel4(const CubicSplineKernel& k)
        : invH_(_mm_set1_ps(k.invRadius())), k_(_mm_set1_ps(k.valueScale())), l_(_mm_set1_ps(k.gradientScale())),
          rMin_(_mm_set1_ps(Real(1e-9) * k.radius())) {}

    /// W(r) for four distances r >= 0 (zero beyond the support).
    __m128 W(__m128 r) const {
        const __m128 q = _mm_mul_ps(r, invH_);
        const __m128 f = _mm_max_ps(_mm_sub_ps(one(), q), _mm_setzero_ps());
        // inner 6 q^2 (q - 1) + 1, outer 2 f^3
        const __m128 inner = _mm_add_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(6), _mm_mul_ps(q, q)), _mm_sub_ps(q, one())), one());
        const __m128 outer = _mm_mul_ps(_mm_set1_ps(2), _mm_mul_ps(f, _mm_mul_ps(f, f)));
        return _mm_mul_ps(k_, select(_mm_cmple_ps(q, _mm_set1_ps(0.5f)), inner, outer));
    }
    /// s(r) with grad W = s * rij for four distances (zero beyond the support and at r = 0).
    __m128 gradFactor(__m128 r) const {
        const __m128 q = _mm_mul_ps(r, invH_);
        const __m128 f = _mm_max_ps(_mm_sub_ps(one(), q), _mm_setzero_ps());
        const __m128 inner = _mm_mul_ps(q, _mm_sub_ps(_mm_mul_ps(_mm_set1_ps(3), q), _mm_set1_ps(2)));
        const __m128 outer = _mm_sub_ps(_mm_setzero_ps(), _mm_mul_ps(f, f));
        const __m128 dWdq = _mm_mul_ps(l_, select(_mm_cmple_ps(q, _mm_set1_ps(0.5f)), inner, outer));
        // r = 0 divides by zero; the mask turns that lane's inf or NaN into 0.
        return _mm_and_ps(_mm_cmpgt_ps(r, rMin_), _mm_div_ps(_mm_mul_ps(dWdq, invH_), r));
    }
    static __m128 select(__m128 mask, __m128 a, __m128 b) { return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b)); }

private:
    static __m128 one() { return _mm_set1_ps(1.0f); }
    __m128 invH_, k_, l_, rMin_;
};

/// Akinci's cohesion spline C(r) for four distances at once (same formula as
/// CohesionKernel::C; zero at r = 0 and beyond the support).
class CohesionKernel4 {
public:
    explicit CohesionKernel4(const CohesionKernel& k)
        : h_(_mm_set1_ps(k.radius())), c_(_mm_set1_ps(k.scale())), offset_(_mm_set1_ps(k.innerOffset())) {}
    __m128 C(__m128 r) const {
        const __m128 hr = _mm_sub_ps(h_, r);
        const __m128 v = _mm_mul_ps(_mm_mul_ps(hr, _mm_mul_ps(hr, hr)), _mm_mul_ps(r, _mm_mul_ps(r, r)));
        const __m128 inner = _mm_sub_ps(_mm_add_ps(v, v), offset_);
        const __m128 outerLane = _mm_cmpgt_ps(_mm_add_ps(r, r), h_);
        const __m128 value = _mm_mul_ps(c_, CubicSplineKernel4::select(outerLane, v, inner));
        const __m128 inside = _mm_and_ps(_mm_cmpgt_ps(r, _mm_setzero_ps()), _mm_cmplt_ps(r, h_));
        return _mm_and_ps(inside, value);
    }

private:
    __m128 h_, c_, offset_;
};

/// Sum of the four lanes, in a fixed order.
inline float horizontalSum(__m128 v) {
    alignas(16) float lane[4];
    _mm_store_ps(lane, v);
    return (lane[0] + lane[1]) + (lane[2] + lane[3]);
}
#endif

} // namespace ferro

#pragma once
// SPH kernels. All kernels take the support radius h (W = 0 for r >= h), following
// SPlisHSPlasH's convention; the smoothing length of the classic papers is h / 2.
#include "sim/Types.hpp"

#include <cmath>

namespace ferro {

constexpr double kPi = 3.14159265358979323846;

/// Monaghan's cubic spline, normalized in 3D: integral of W over R^3 is 1.
class CubicSplineKernel {
public:
    explicit CubicSplineKernel(Real supportRadius = 1)
        : h_(supportRadius),
          invH_(1 / supportRadius),
          k_(Real(8.0 / (kPi * double(supportRadius) * supportRadius * supportRadius))),
          l_(Real(48.0 / (kPi * double(supportRadius) * supportRadius * supportRadius))) {}

    Real radius() const { return h_; }

    Real W(Real r) const {
        const Real q = r * invH_;
        if (q <= Real(0.5)) return k_ * (Real(6) * q * q * (q - 1) + 1);
        if (q < 1) {
            const Real f = 1 - q;
            return k_ * 2 * f * f * f;
        }
        return 0;
    }
    Real W0() const { return k_; }

    /// Gradient with respect to x_i of W(|x_i - x_j|), given rij = x_i - x_j and r = |rij|.
    /// Exactly antisymmetric in rij, which makes pairwise forces conserve momentum.
    Vec3 gradW(const Vec3& rij, Real r) const {
        const Real q = r * invH_;
        if (r <= Real(1e-9) * h_ || q >= 1) return Vec3::Zero();
        Real dWdq;
        if (q <= Real(0.5)) dWdq = l_ * q * (Real(3) * q - 2);
        else {
            const Real f = 1 - q;
            dWdq = -l_ * f * f;
        }
        return rij * (dWdq * invH_ / r);
    }

    /// W and its gradient together for rij = x_i - x_j with r2 = |rij|^2 < h^2: one square
    /// root and no unpredictable branch (the two spline pieces are blended), since the
    /// neighbour search evaluates this for every pair of every step.
    void evaluate(const Vec3& rij, Real r2, Real& w, Vec3& grad) const {
        const Real r = std::sqrt(r2);
        const Real q = r * invH_;
        const Real f = 1 - q;
        const bool inner = q <= Real(0.5);
        w = k_ * (inner ? Real(6) * q * q * (q - 1) + 1 : 2 * f * f * f);
        const Real dWdq = inner ? l_ * q * (Real(3) * q - 2) : -l_ * f * f;
        grad = r > Real(1e-9) * h_ ? Vec3(rij * (dWdq * invH_ / r)) : Vec3(Vec3::Zero());
    }

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
        const Real v = hr * hr * hr * r * r * r;
        if (2 * r > h_) return c_ * v;
        return c_ * (2 * v - h6over64_);
    }

private:
    Real h_, c_, h6over64_;
};

} // namespace ferro

#pragma once
// Viscosity "standard" (Monaghan 1992 as SPlisHSPlasH's Viscosity_Standard): along grad W_ij,
//   a_i += 10 nu sum_j V_ij (v_ij . x_ij) / (r^2 + 0.01 h^2) grad W_ij,
// with the pair volume V_ij = 2 m / (rho_i + rho_j) at the mean density: symmetric in i and j,
// so momentum is conserved. Walls add Akinci's friction with nu * container.wall_friction.
// The same operator is the implicit solve's (sim/sph/ImplicitViscosity): with
// fluid.viscosity_method implicit or auto-implicit the sweep leaves it out.
#include "sim/sph/forces/PairForceModel.hpp"

namespace ferro {

class StandardViscosity : public PairForceModel {
public:
    static constexpr const char* kName = "standard";
    /// The implicit solve (sim/sph/ImplicitViscosity) discretizes this model's operator, so
    /// fluid.viscosity_method implicit or auto may take it out of the sweep. A viscosity model
    /// must say whether it has one: one that does not stays explicit whatever the method.
    static constexpr bool kHasImplicitSolve = true;
    /// The explicit update's stable step is kExplicitStep h^2 / nu [s] (h the support [m], nu
    /// the kinematic viscosity [m^2/s]): a margin under the operator's measured stability
    /// bound. Measurements: docs/physics/sph-solver.md, "Viscosity".
    static constexpr double kExplicitStep = 0.02;

    explicit StandardViscosity(const PairForceSetup& s)
        : nu_(Real(s.viscosity)), nuWall_(Real(s.wallViscosity)),
          eps2_(Real(0.01 * s.support * s.support)), V_(Real(s.volume)), rho0_(Real(s.restDensity)),
          stepLimit_(s.viscosity > 0 ? kExplicitStep * s.support * s.support / s.viscosity : 1e30) {}

    bool active() const { return nu_ > 0; }
    double timeStepLimit() const { return stepLimit_; }

#if defined(__SSE2__)
    struct Lanes {
        __m128 vx, vy, vz, scale, eps2;
    };
    Lanes lanes(size_t i, const PairForceView& s) const {
        const Vec3 vi = s.v[i];
        return {_mm_set1_ps(vi.x()), _mm_set1_ps(vi.y()), _mm_set1_ps(vi.z()), _mm_set1_ps(scale()), _mm_set1_ps(eps2_)};
    }
    __m128 radial4(__m128 c, Lanes& l, const PairLanes4& p) const {
        const __m128 dvx = _mm_sub_ps(l.vx, gather4(v_->data(), p.j, 0));
        const __m128 dvy = _mm_sub_ps(l.vy, gather4(v_->data(), p.j, 1));
        const __m128 dvz = _mm_sub_ps(l.vz, gather4(v_->data(), p.j, 2));
        const __m128 dvdx = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dvx, p.dx), _mm_mul_ps(dvy, p.dy)), _mm_mul_ps(dvz, p.dz));
        const __m128 den = _mm_mul_ps(p.rhoSum, _mm_add_ps(p.r2, l.eps2));
        return _mm_add_ps(c, _mm_div_ps(_mm_mul_ps(l.scale, dvdx), den));
    }
#endif
    void prepare(const PairForceView& s) {
        v_ = &s.v;
        rho_ = &s.rho;
        bVolume_ = &s.bVolume;
    }
    Real radial1(Real c, const Pair1& p) const {
        return c + scale() * ((*v_)[p.i] - (*v_)[p.j]).dot(p.xij) / (p.rhoSum * (p.r2 + eps2_));
    }
    bool wantsWalls() const { return nuWall_ > 0; }
    /// Wall friction (Akinci 2012): the wall particle at rest, its volume V_b.
    Vec3 wall1(const Vec3& acc, const WallPair1& w) const {
        return acc + (10 * nuWall_ * (*bVolume_)[w.b] * rho0_ / (*rho_)[w.i] * (*v_)[w.i].dot(w.xib) / (w.r2 + eps2_)) * w.gradW;
    }

private:
    /// 10 nu 2 V rho0: 10 nu V_ij with V_ij = 2 m / (rho_i + rho_j), m = V rho0.
    Real scale() const { return 10 * nu_ * 2 * V_ * rho0_; }

    Real nu_, nuWall_, eps2_, V_, rho0_;
    double stepLimit_;
    const std::vector<Vec3>* v_ = nullptr;
    const std::vector<Real>* rho_ = nullptr;
    const std::vector<Real>* bVolume_ = nullptr;
};

} // namespace ferro

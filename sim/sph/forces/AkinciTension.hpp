#pragma once
// Surface tension "akinci2013" (Akinci, Akinci and Teschner 2013): cohesion pulls neighbours
// to about one spacing, curvature flattens the surface,
//   a_i += gamma sum_j K_ij (-(n_i - n_j) - w V C(r) / r x_ij),   K_ij = 2 rho0 / (rho_i + rho_j),
// with the surface normals n_i = h V sum_j (rho0 / rho_j) grad W_ij (prepare()), Akinci's
// cohesion spline C and w = kCohesionWeight. K_ij boosts the force where a particle lacks
// neighbours. gamma [m/s^2] = kCalibration sigma / (rho0 s^2).
#include "sim/core/Constants.hpp"
#include "sim/core/ParticleLoops.hpp"
#include "sim/sph/forces/PairForceModel.hpp"

#include <cmath>

namespace ferro {

class AkinciTension : public PairForceModel {
public:
    static constexpr const char* kName = "akinci2013";
    /// Akinci's model has no physical coefficient: fitted on a free droplet of radius 11
    /// spacings to the Laplace pressure 2 sigma / R, and right only there. Measurements:
    /// docs/physics/sph-solver.md, "Surface tension".
    static constexpr double kCalibration = 0.0029;
    /// Weight of the cohesion term against the curvature term. Akinci's cohesion is
    /// gamma m_j C(r), not dimensionally consistent with the curvature term; with V_j C(r)
    /// (dimensionless) in its place, 1000 restores the balance Akinci and SPlisHSPlasH
    /// tuned for water in SI units.
    static constexpr Real kCohesionWeight = 1000;

    explicit AkinciTension(const PairForceSetup& s)
        : gamma_(Real(kCalibration * s.scene->fluid.surfaceTension / (s.restDensity * s.spacing * s.spacing))),
          rho0_(Real(s.restDensity)), V_(Real(s.volume)), h_(Real(s.support)), cohesion_(Real(s.support)),
          stepLimit_(capillaryStepLimit(s)) {}

    bool active() const { return gamma_ > 0; }
    double timeStepLimit() const { return stepLimit_; }

    /// The surface normals of this sweep's positions.
    void prepare(const PairForceView& s) {
        const size_t n = s.x.size();
        normal_.resize(n);
#if defined(__SSE2__)
        const CubicSplineKernel4 kernel4(s.kernel);
#endif
        const PeriodicDomain periodic = s.periodic; // a copy: see ForceSweep
        forEachParticle(n, [&](size_t i) {
            Vec3 sum = Vec3::Zero();
            uint32_t k = s.fluid.begin(i);
            const uint32_t end = s.fluid.end(i);
#if defined(__SSE2__)
            {
                const __m128 rho04 = _mm_set1_ps(rho0_);
                __m128 sx = _mm_setzero_ps(), sy = _mm_setzero_ps(), sz = _mm_setzero_ps();
                for (; k + 4 <= end; k += 4) {
                    const uint32_t* j = &s.fluid.index[k];
                    const PairOffsets4 d(s.x[i], s.px, s.py, s.pz, j, periodic);
                    const __m128 f =
                        _mm_mul_ps(_mm_div_ps(rho04, gather4(s.rho.data(), j)), kernel4.gradFactor(_mm_sqrt_ps(d.r2)));
                    sx = _mm_add_ps(sx, _mm_mul_ps(f, d.dx));
                    sy = _mm_add_ps(sy, _mm_mul_ps(f, d.dy));
                    sz = _mm_add_ps(sz, _mm_mul_ps(f, d.dz));
                }
                sum = Vec3(horizontalSum(sx), horizontalSum(sy), horizontalSum(sz));
            }
#endif
            for (; k < end; ++k) {
                const uint32_t j = s.fluid.index[k];
                const Vec3 xij = periodic.offset(s.x[i] - s.x[j]);
                sum += (rho0_ / s.rho[j]) * s.kernel.gradW(xij, xij.norm());
            }
            normal_[i] = h_ * V_ * sum;
        });
    }

#if defined(__SSE2__)
    struct Lanes {
        __m128 tx, ty, tz, gKsum;
    };
    Lanes lanes(size_t, const PairForceView&) const {
        return {_mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps()};
    }
    /// The cohesion part joins cs; the curvature part sums gamma K_ij n_j and gamma K_ij.
    __m128 offset4(__m128 cs, Lanes& l, const PairLanes4& p) const {
        const __m128 gK = _mm_div_ps(_mm_set1_ps(gamma_ * 2 * rho0_), p.rhoSum);
        const __m128 coh = _mm_and_ps(_mm_cmpgt_ps(p.r, _mm_set1_ps(Real(1e-9) * h_)),
                                      _mm_div_ps(_mm_mul_ps(_mm_set1_ps(kCohesionWeight * V_), cohesion4_.C(p.r)), p.r));
        l.tx = _mm_add_ps(l.tx, _mm_mul_ps(gK, gather4(normal_.data(), p.j, 0)));
        l.ty = _mm_add_ps(l.ty, _mm_mul_ps(gK, gather4(normal_.data(), p.j, 1)));
        l.tz = _mm_add_ps(l.tz, _mm_mul_ps(gK, gather4(normal_.data(), p.j, 2)));
        l.gKsum = _mm_add_ps(l.gKsum, gK);
        return _mm_sub_ps(cs, _mm_mul_ps(gK, coh));
    }
    /// sum gK (n_j - n_i) = sum gK n_j - n_i sum gK
    Vec3 finish4(const Vec3& acc, size_t i, const Lanes& l) const {
        return acc + (Vec3(horizontalSum(l.tx), horizontalSum(l.ty), horizontalSum(l.tz)) - horizontalSum(l.gKsum) * normal_[i]);
    }
#endif
    Vec3 direct1(const Vec3& acc, const Pair1& p) const {
        const Real Kij = 2 * rho0_ / p.rhoSum;
        Vec3 f = -(normal_[p.i] - normal_[p.j]);
        if (p.r > Real(1e-9) * h_) f -= (kCohesionWeight * V_ * cohesion_.C(p.r) / p.r) * p.xij;
        return acc + gamma_ * Kij * f;
    }

private:
    Real gamma_, rho0_, V_, h_;
    CohesionKernel cohesion_;
#if defined(__SSE2__)
    CohesionKernel4 cohesion4_{cohesion_};
#endif
    double stepLimit_;
    std::vector<Vec3> normal_;
};

} // namespace ferro

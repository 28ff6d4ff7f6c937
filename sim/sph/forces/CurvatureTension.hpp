#pragma once
// Surface tension "csf": the continuum surface force of Brackbill, Kothe and Zemach (1992) on
// a free surface. The Laplace pressure sigma kappa acts as a traction on the surface particles,
//   a_i = w_i sigma kappa_i grad c_i / (rho0 kappa_layer),
// the same way the magnetic surface traction is applied (sim/sph/FreeSurface.hpp: colour
// gradient grad c (fluid and walls), surface weight w from |grad c| and the exposure, the flat
// lattice's kappa_layer), so a surface in a field feels both pressures on the same footing.
// kappa_i = div_s n, the surface divergence of the outward normal n = -grad c / |grad c| (2 / R
// on a sphere of radius R, positive where the surface is convex), from a weighted least-squares
// fit of the neighbours' normals in the particle's tangent plane:
//   n_j - n_i ~ c + G (t_j),   t_j = (x_j - x_i) projected on the tangent plane (2 x 2 G),
// weights w_j W(r_ij), kappa_i = trace G, then averaged over the surface neighbours (weights
// w_j W_ij) against the fit's particle-scale noise. The fit is exact for a normal field that
// varies linearly along the surface, whatever the particle disorder, so unlike a kernel
// divergence it needs no calibration: sigma is the physical coefficient (N/m). The traction
// is sigma (kappa + kAmbientCurvature / s), never negative (below). Not momentum conserving
// pair by pair (CSF never is); the pressure solver holds the fluid against it as against the
// magnetic traction. Measured against Lamb's capillary waves, Rayleigh's droplet oscillation
// and the Laplace pressure: tests/sim/sph/test_SurfaceTension.cpp, docs/physics/sph-solver.md.
#include "sim/core/Constants.hpp"
#include "sim/core/ParticleLoops.hpp"
#include "sim/sph/FreeSurface.hpp"
#include "sim/sph/forces/PairForceModel.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace ferro {

class CurvatureTension : public PairForceModel {
public:
    static constexpr const char* kName = "csf";
    /// The fitted curvature is clamped to kMaxCurvature / s: two spacings across a bend is
    /// as sharp as the particles resolve (a column of 2 x 2 particles).
    static constexpr double kMaxCurvature = 2;
    /// An ambient push sigma kAmbientCurvature / s on the whole surface, and the traction
    /// clamped at zero: the pressure solvers hold the fluid against a push but nothing holds
    /// a surface particle that is pulled out (their pressure is clamped at zero). A uniform
    /// pressure on a closed surface moves nothing in an incompressible fluid (it raises the
    /// interior pressure by sigma kAmbientCurvature / s), but its share flickers as particles
    /// enter and leave the surface, and that shakes the surface: at 0.5 / s a 0.5 mm layer
    /// with no field roughened to 1.2 spacings RMS in 0.4 s (0.16 at 0.25 / s and 0.1 / s).
    /// Without it (a pull allowed) a droplet relaxing from a cylinder shed 24 particles.
    /// Measurements: docs/physics/sph-solver.md, "Surface tension".
    static constexpr double kAmbientCurvature = 0.1;

    explicit CurvatureTension(const PairForceSetup& s)
        : sigma_(s.scene->fluid.surfaceTension), rho0_(s.restDensity), V_(Real(s.volume)), s_(Real(s.spacing)),
          flat_(s.spacing, s.volume), stepLimit_(capillaryStepLimit(s)) {}

    bool active() const { return sigma_ > 0; }
    double timeStepLimit() const { return stepLimit_; }

    /// Colour gradient, exposure, normals and curvature of this sweep's positions, and from
    /// them each particle's acceleration.
    void prepare(const PairForceView& v) {
        const size_t n = v.x.size();
        const FreeSurfaceInput in{v.x, v.fluid, v.boundary, v.bx, v.bVolume, v.kernel, v.periodic, V_, s_};
        computeColorGradient(in, gradC_);
        computeExposure(in, gradC_, exposure_);
        weight_.resize(n);
        normal_.resize(n);
        forEachParticle(n, [&](size_t i) {
            const Real g = gradC_[i].norm();
            weight_[i] = g > 0 ? Real(flat_.weight(double(g))) * exposure_[i] : Real(0);
            normal_[i] = weight_[i] > 0 ? Vec3(-gradC_[i] / g) : Vec3::Zero();
        });
        accel_.resize(n);
        const double scale = sigma_ / (rho0_ * flat_.layerFactor());
        const PeriodicDomain periodic = v.periodic;
        rawCurvature_.resize(n);
        forEachParticle(n, [&](size_t i) { rawCurvature_[i] = weight_[i] > 0 ? curvature(v, periodic, i) : Real(0); });
        // Smoothed over the surface neighbours (weights w_j W_ij): the fit's particle-scale
        // noise would otherwise push single particles out of the surface, which no pressure
        // (clamped at zero) holds back.
        forEachParticle(n, [&](size_t i) {
            accel_[i] = Vec3::Zero();
            if (!(weight_[i] > 0)) return;
            double sum = double(weight_[i]) * double(v.kernel.W0()) * double(rawCurvature_[i]);
            double wsum = double(weight_[i]) * double(v.kernel.W0());
            for (uint32_t k = v.fluid.begin(i); k < v.fluid.end(i); ++k) {
                const uint32_t j = v.fluid.index[k];
                if (!(weight_[j] > 0)) continue;
                const Vec3 d = periodic.offset(v.x[j] - v.x[i]);
                const double w = double(weight_[j]) * double(v.kernel.W(d.norm()));
                sum += w * double(rawCurvature_[j]);
                wsum += w;
            }
            const double traction = std::max(0.0, sum / wsum + kAmbientCurvature / double(s_));
            accel_[i] = (scale * double(weight_[i]) * traction * gradC_[i].cast<double>()).cast<Real>();
        });
    }

    Vec3 own(const Vec3& acc, size_t i) const { return acc + accel_[i]; }

private:
    /// div_s n at surface particle i (see the header), clamped to kMaxCurvature / s.
    Real curvature(const PairForceView& v, const PeriodicDomain& periodic, size_t i) const {
        const Eigen::Vector3d ni = normal_[i].cast<double>();
        // A tangent basis.
        const Eigen::Vector3d helper = std::abs(ni.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
        const Eigen::Vector3d e1 = ni.cross(helper).normalized(), e2 = ni.cross(e1);
        Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
        Eigen::Vector3d b1 = Eigen::Vector3d::Zero(), b2 = Eigen::Vector3d::Zero();
        const double wi = double(weight_[i]) * double(v.kernel.W0());
        A(0, 0) = wi; // the particle itself: t = 0, n - n_i = 0
        int used = 0;
        for (uint32_t k = v.fluid.begin(i); k < v.fluid.end(i); ++k) {
            const uint32_t j = v.fluid.index[k];
            if (!(weight_[j] > 0)) continue;
            const Vec3 d = periodic.offset(v.x[j] - v.x[i]);
            const double w = double(weight_[j]) * double(v.kernel.W(d.norm()));
            if (!(w > 0)) continue;
            const Eigen::Vector3d t = d.cast<double>(), dn = (normal_[j] - normal_[i]).cast<double>();
            const Eigen::Vector3d row(1, t.dot(e1), t.dot(e2));
            A += w * row * row.transpose();
            b1 += (w * dn.dot(e1)) * row;
            b2 += (w * dn.dot(e2)) * row;
            ++used;
        }
        if (used < 5) return 0;
        const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
        // A neighbourhood strung along a line fits no surface.
        const double scale = A(0, 0);
        if (ldlt.info() != Eigen::Success || !(std::abs(A.determinant()) > 1e-6 * scale * A(1, 1) * A(2, 2))) return 0;
        const Eigen::Vector3d g1 = ldlt.solve(b1), g2 = ldlt.solve(b2);
        const double kappa = g1(1) + g2(2);
        const double limit = kMaxCurvature / double(s_);
        return Real(std::clamp(std::isfinite(kappa) ? kappa : 0.0, -limit, limit));
    }

    double sigma_, rho0_;
    Real V_, s_;
    FlatSurface flat_;
    double stepLimit_;
    std::vector<Vec3> gradC_, normal_, accel_;
    std::vector<Real> exposure_, weight_, rawCurvature_;
};

} // namespace ferro

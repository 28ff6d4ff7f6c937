#include "sim/magnetics/SolidCoupling.hpp"

#include "sim/core/ParticleLoops.hpp"
#include "sim/particlefield/ParticleField.hpp"

#include <algorithm>
#include <chrono>

namespace ferro {

SolidCoupling::SolidCoupling(const std::vector<SolidParams>& solids, double spacing, const std::string& where)
    : solids_(solids), spacing_(spacing) {
    for (const SolidParams& s : solids_) {
        const double edge = s.panelSize > 0 ? s.panelSize : 2.0 * spacing;
        shapes_.push_back(solidShape(s, edge, where));
        moving_ = moving_ || s.moves();
    }
}

SolidCoupling::Stats SolidCoupling::update(double t, const std::vector<Magnet>& magnets, const std::vector<Vec3>& x,
                                           const std::vector<Real>& volume, const std::vector<Vec3>& M,
                                           const MagnetizationParams& law, bool cold, std::vector<Vec3>& H,
                                           std::vector<Eigen::Matrix3f>& J) {
    const auto t0 = std::chrono::steady_clock::now();
    Stats st;
    if (!active()) return st;
    if (posedTime_ < 0 || (moving_ && t != posedTime_)) {
        std::vector<SolidSurface> surfaces;
        for (size_t k = 0; k < solids_.size(); ++k) surfaces.push_back(solidSurfaceAt(solids_[k], shapes_[k], t));
        solver_.setSurfaces(surfaces);
        posedTime_ = t;
    }
    if (cold) solver_.coldStart();
    // The fluid's field at the panels, from its magnetization of the last solve (the tree
    // the solver uses, evaluated at points).
    ParticleFieldEvaluator fluid;
    const bool fluidField = !M.empty() && M.size() == x.size() && law.enabled();
    if (fluidField) fluid.build(x, volume, M, law.openingAngle > 0 ? law.openingAngle : 0.5, law.smoothing, false);
    const SurfaceChargeSolver::Stats s = solver_.solve([&](const Vec3d& p) {
        Vec3d h = magnetField(magnets, p);
        if (fluidField) h += fluid.inducedField(p);
        return h;
    });
    st.panels = solver_.panelCount();
    st.iterations = s.iterations;
    st.converged = s.converged;
    const size_t n = x.size();
    // Which particles to evaluate in full (see the header): all after a cold start, a new
    // set of panels or a charge that moved by more than kRecharge; else those that moved.
    const std::vector<double>& sigma = solver_.charge();
    bool all = cold || sigmaEvaluated_.size() != sigma.size() || xEval_.size() != n;
    // The charge's change along its evaluated pattern scales the evaluated fields (the field
    // is linear in the charge: a ramping current changes the scale, not the pattern); what
    // is left beyond kRecharge re-evaluates every particle.
    double scale = 1;
    if (!all) {
        double along = 0, s2 = 0;
        for (size_t j = 0; j < sigma.size(); ++j) {
            along += sigma[j] * sigmaEvaluated_[j];
            s2 += sigmaEvaluated_[j] * sigmaEvaluated_[j];
        }
        scale = s2 > 0 ? along / s2 : 1.0;
        double d2 = 0, n2 = 0;
        for (size_t j = 0; j < sigma.size(); ++j) {
            const double d = sigma[j] - scale * sigmaEvaluated_[j];
            d2 += d * d;
            n2 += sigma[j] * sigma[j];
        }
        all = !(s2 > 0) || d2 > kRecharge * kRecharge * n2;
    }
    if (!all && scale != 1) {
        const Real f = Real(scale);
        forEachParticle(n, [&](size_t i) {
            hEval_[i] *= f;
            jEval_[i] *= f;
        });
        for (double& v : sigmaEvaluated_) v *= scale;
    }
    if (all) {
        sigmaEvaluated_ = sigma;
        xEval_.assign(n, Vec3::Zero());
        hEval_.assign(n, Vec3::Zero());
        jEval_.assign(n, Eigen::Matrix3f::Zero());
    }
    const Real reach2 = Real(kReevaluate * spacing_ * kReevaluate * spacing_);
    std::vector<char> evaluated(n, 0);
    forEachParticle(n, [&](size_t i) {
        if (!all && (x[i] - xEval_[i]).squaredNorm() <= reach2) return;
        Vec3d h;
        Mat3d g;
        solver_.fieldAndGradient(x[i].cast<double>(), h, g);
        xEval_[i] = x[i];
        hEval_[i] = h.allFinite() ? Vec3(h.cast<Real>()) : Vec3(Vec3::Zero());
        jEval_[i] = g.allFinite() ? Eigen::Matrix3f(g.cast<float>()) : Eigen::Matrix3f(Eigen::Matrix3f::Zero());
        evaluated[i] = 1;
    });
    lastEvaluated_ = size_t(std::count(evaluated.begin(), evaluated.end(), 1));
    // The charge since the full evaluation changed the field by under kRecharge: the field
    // carried to each particle's position by its Jacobian.
    H.resize(n);
    J.resize(n);
    forEachParticle(n, [&](size_t i) {
        H[i] = hEval_[i] + jEval_[i] * (x[i] - xEval_[i]);
        J[i] = jEval_[i];
    });
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return st;
}

void SolidCoupling::permute(const std::vector<uint32_t>& order) {
    if (xEval_.size() != order.size()) return;
    ferro::permute(xEval_, order);
    ferro::permute(hEval_, order);
    ferro::permute(jEval_, order);
}

} // namespace ferro

#include "sim/magnetics/SolidCoupling.hpp"

#include "sim/core/ParticleLoops.hpp"
#include "sim/particlefield/ParticleField.hpp"

#include <chrono>

namespace ferro {

SolidCoupling::SolidCoupling(const std::vector<SolidParams>& solids, double spacing, const std::string& where)
    : solids_(solids), standoff_(0.5 * spacing) {
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
    fieldAt(x, H, J);
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return st;
}

void SolidCoupling::fieldAt(const std::vector<Vec3>& x, std::vector<Vec3>& H, std::vector<Eigen::Matrix3f>& J) const {
    if (!active() || posedTime_ < 0) return;
    const size_t n = x.size();
    H.resize(n);
    J.resize(n);
    forEachParticle(n, [&](size_t i) {
        Vec3d h;
        Mat3d g;
        solver_.fieldAndGradient(x[i].cast<double>(), h, g, standoff_);
        H[i] = h.allFinite() ? Vec3(h.cast<Real>()) : Vec3(Vec3::Zero());
        J[i] = g.allFinite() ? Eigen::Matrix3f(g.cast<float>()) : Eigen::Matrix3f(Eigen::Matrix3f::Zero());
    });
}

} // namespace ferro

#include "sim/particlefield/ParticleField.hpp"

namespace ferro {

void ParticleFieldEvaluator::build(const std::vector<Vec3>& x, const std::vector<Real>& volume,
                                   const std::vector<Vec3>& M, double openingAngle, double smoothing,
                                   bool localCorrection) {
    tree_.setSmoothing(smoothing);
    tree_.setSurfaceOnset(localCorrection);
    tree_.build(x, volume, openingAngle);
    sorted_.assign(x.size(), 0);
    for (size_t k = 0; k < tree_.order().size(); ++k) // (a periodic tree's copies come after x)
        if (tree_.order()[k] < x.size()) sorted_[tree_.order()[k]] = uint32_t(k);
    tree_.setMagnetizationUnsorted(M);
    correct_ = localCorrection;
    corrected_ = std::make_unique<std::once_flag>();
}

Vec3d ParticleFieldEvaluator::inducedFieldAtParticle(size_t i) const {
    // The correction costs three field evaluations: only when a particle-centre field is
    // asked for (point evaluations do not use it).
    if (correct_ && corrected_) std::call_once(*corrected_, [this] { tree_.computeLocalCorrection(tree_.openingAngle() > 0); });
    return tree_.fieldAtParticleDirect(sorted_[i]);
}

Vec3d totalField(const std::vector<Magnet>& magnets, const ParticleFieldEvaluator& particles, const Vec3d& p) {
    return magnetField(magnets, p) + particles.inducedField(p);
}

Mat3d totalFieldGradient(const std::vector<Magnet>& magnets, const ParticleFieldEvaluator& particles,
                         const Vec3d& p) {
    return fieldGradient(magnets, p) + particles.inducedGradient(p);
}

} // namespace ferro

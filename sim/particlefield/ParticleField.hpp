#pragma once
// The magnetic field of a saved particle state, anywhere: what ferro-spikes needs at surface
// points, and the solver's H at a particle. Built on DipoleTree with the solver's particle
// model, so a stage reading particle files sees the field the simulation saw.
#include "sim/particlefield/DipoleTree.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/magnets/MagnetizationParams.hpp"
#include "sim/core/Types.hpp"

#include <memory>
#include <mutex>
#include <vector>

namespace ferro {

/// Total or induced field anywhere from a saved particle state (positions, volumes, M as
/// written to the particle files) plus the magnets: what ferro-spikes needs at surface
/// points. The particle field uses the same particle model (smoothed dipoles or spheres) and
/// tree as the solver: inducedField() is the field of the smoothed magnetization at any
/// point; at particle i the solver's H is inducedFieldAtParticle(i) + magnetField(), which
/// adds the surface sampling term of DipoleTree.hpp (zero inside the fluid).
class ParticleFieldEvaluator {
public:
    /// Builds the tree. openingAngle 0 = exact sums (O(N) per point), default 0.5.
    /// smoothing: the particle model, as MagnetizationParams::smoothing (pass the solver's).
    /// localCorrection: as MagnetizationParams::localCorrection (pass the solver's), used by
    /// inducedFieldAtParticle() only.
    /// Periodic sides for the next build() (DipoleTree::setPeriodic): the particles repeat with
    /// periods Lx, Ly [m] in x and y; 0 = not periodic.
    void setPeriodic(double Lx, double Ly) { tree_.setPeriodic(Lx, Ly); }
    void build(const std::vector<Vec3>& x, const std::vector<Real>& volume, const std::vector<Vec3>& M,
               double openingAngle = 0.5, double smoothing = DipoleTree::kDefaultSmoothing,
               bool localCorrection = MagnetizationParams{}.localCorrection);
    /// Field of the magnetized particles at p [m] -> [A/m].
    Vec3d inducedField(const Vec3d& p) const { return tree_.fieldAt(p); }
    /// Jacobian dH_a/dx_b [A/m^2] of the particle field at p.
    Mat3d inducedGradient(const Vec3d& p) const { return tree_.gradientAt(p); }
    /// Exact all-particle sum at p (reference, O(N)).
    Vec3d inducedFieldExact(const Vec3d& p) const { return tree_.fieldAtDirect(p); }
    /// The particle field the solver uses at particle i (index into build()'s x): exact sum,
    /// O(N), including the surface sampling term and the local correction (computed at the
    /// first call: three field evaluations).
    Vec3d inducedFieldAtParticle(size_t i) const;
    size_t size() const { return tree_.size(); }
    /// Total moment sum V M [A m^2] and volume centroid [m]: the far field is that dipole.
    Vec3d totalMoment() const { return tree_.totalMoment(); }
    Vec3d centroid() const { return tree_.centroid(); }

private:
    mutable DipoleTree tree_;      // mutable: the local correction is computed on first use
    std::vector<uint32_t> sorted_; // sorted_[i] = tree place of input particle i
    bool correct_ = true;
    mutable std::unique_ptr<std::once_flag> corrected_;
};

/// H [A/m] at p: magnets plus magnetized particles.
Vec3d totalField(const std::vector<Magnet>& magnets, const ParticleFieldEvaluator& particles, const Vec3d& p);
/// dH_a/dx_b [A/m^2] at p: magnets plus magnetized particles.
Mat3d totalFieldGradient(const std::vector<Magnet>& magnets, const ParticleFieldEvaluator& particles,
                         const Vec3d& p);

} // namespace ferro

#pragma once
// The pair-force models a simulation runs (one viscosity, one surface tension), chosen by
// name from the table in PairForces.cpp, and the fused force sweep that applies them.
#include "sim/sph/forces/PairForceModel.hpp"

#include <memory>
#include <string>
#include <vector>

namespace ferro {

struct SweepConstants;

class PairForces {
public:
    virtual ~PairForces() = default;
    /// a[i] = gravity + WCSPH's pressure (pOverRho2 = p / rho^2, or nullptr) + the models.
    /// Prepares the models first (e.g. surface normals).
    virtual void accelerations(const PairForceView& view, const SweepConstants& k, const Real* pOverRho2,
                               std::vector<Vec3>& a) = 0;
    /// The explicit viscosity's stable step h^2-scaled [s] (1e30 without viscosity): binding
    /// only while the sweep carries viscosity.
    virtual double viscousStepLimit() const = 0;
    /// The surface tension's stable step [s] (1e30 without tension).
    virtual double tensionStepLimit() const = 0;
    /// False: an implicit solve applies viscosity and the sweep leaves it out.
    virtual void setViscosityInSweep(bool inSweep) = 0;
    /// True if the viscosity model is the operator the implicit solve inverts.
    virtual bool viscosityHasImplicitSolve() const = 0;
};

/// The models named fluid.viscosity_model and fluid.surface_tension_model. Throws SceneError
/// naming the key and the known models for an unknown name.
std::unique_ptr<PairForces> makePairForces(const PairForceSetup& setup);

/// The registered names, in table order.
std::vector<std::string> viscosityModelNames();
std::vector<std::string> surfaceTensionModelNames();

} // namespace ferro

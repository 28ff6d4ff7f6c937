// The table of pair-force models: one row a model. A new model is one header (see
// PairForceModel.hpp) and its row here.
#include "sim/sph/forces/PairForces.hpp"

#include "sim/core/SceneDocument.hpp"
#include "sim/sph/forces/ForceSweep.hpp"

#include "sim/sph/forces/AkinciTension.hpp"
#include "sim/sph/forces/CurvatureTension.hpp"
#include "sim/sph/forces/StandardViscosity.hpp"

namespace ferro {

template <class... Models> struct ModelList {};

using ViscosityModels = ModelList<StandardViscosity>;
using SurfaceTensionModels = ModelList<AkinciTension, CurvatureTension>;

namespace {

template <class... M> std::vector<std::string> namesOf(ModelList<M...>) { return {M::kName...}; }

/// The models of one simulation; the sweep is compiled for every on/off combination.
template <class Viscosity, class Tension>
class PairForcesOf final : public PairForces {
public:
    explicit PairForcesOf(const PairForceSetup& s) : viscosity_(s), tension_(s) {}

    void accelerations(const PairForceView& view, const SweepConstants& k, const Real* pOverRho2,
                       std::vector<Vec3>& a) override {
        const bool viscosity = viscosityInSweep_ && viscosity_.active();
        const bool tension = tension_.active();
        if (viscosity) viscosity_.prepare(view);
        if (tension) tension_.prepare(view);
        if (viscosity && tension) run(view, k, viscosity_, tension_, pOverRho2, a);
        else if (viscosity) run(view, k, viscosity_, NoPairForce(), pOverRho2, a);
        else if (tension) run(view, k, NoPairForce(), tension_, pOverRho2, a);
        else run(view, k, NoPairForce(), NoPairForce(), pOverRho2, a);
    }
    double viscousStepLimit() const override { return viscosity_.timeStepLimit(); }
    double tensionStepLimit() const override { return tension_.timeStepLimit(); }
    void setViscosityInSweep(bool inSweep) override { viscosityInSweep_ = inSweep; }
    bool viscosityHasImplicitSolve() const override { return Viscosity::kHasImplicitSolve; }

private:
    template <class V, class T>
    static void run(const PairForceView& view, const SweepConstants& k, const V& v, const T& t, const Real* pOverRho2,
                    std::vector<Vec3>& a) {
        if (pOverRho2) forceSweep<V, T, true>(view, k, v, t, pOverRho2, a);
        else forceSweep<V, T, false>(view, k, v, t, nullptr, a);
    }

    Viscosity viscosity_;
    Tension tension_;
    bool viscosityInSweep_ = true;
};

std::string quotedList(const std::vector<std::string>& names) {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "\"" : ", \"") + n + "\"";
    return list;
}

[[noreturn]] void unknownModel(const PairForceSetup& s, const char* key, const std::string& name, const std::string& where,
                               const std::vector<std::string>& names) {
    throw SceneError((where.empty() ? s.scene->path : where) + ": fluid." + key + ": must be one of " +
                     quotedList(names) + " (got \"" + name + "\")");
}

template <class Viscosity, class... T>
std::unique_ptr<PairForces> withTension(const PairForceSetup& s, ModelList<T...>) {
    std::unique_ptr<PairForces> made;
    const std::string& name = s.scene->fluid.surfaceTensionModel;
    ((name == T::kName ? (void)(made = std::make_unique<PairForcesOf<Viscosity, T>>(s)) : (void)0), ...);
    if (!made) unknownModel(s, "surface_tension_model", name, s.scene->fluid.surfaceTensionModelWhere,
                            surfaceTensionModelNames());
    return made;
}

template <class... V>
std::unique_ptr<PairForces> withViscosity(const PairForceSetup& s, ModelList<V...>) {
    std::unique_ptr<PairForces> made;
    const std::string& name = s.scene->fluid.viscosityModel;
    ((name == V::kName ? (void)(made = withTension<V>(s, SurfaceTensionModels{})) : (void)0), ...);
    if (!made) unknownModel(s, "viscosity_model", name, s.scene->fluid.viscosityModelWhere, viscosityModelNames());
    return made;
}

} // namespace

std::vector<std::string> viscosityModelNames() { return namesOf(ViscosityModels{}); }
std::vector<std::string> surfaceTensionModelNames() { return namesOf(SurfaceTensionModels{}); }

std::unique_ptr<PairForces> makePairForces(const PairForceSetup& setup) {
    return withViscosity(setup, ViscosityModels{});
}

} // namespace ferro

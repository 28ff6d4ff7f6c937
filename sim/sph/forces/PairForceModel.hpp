#pragma once
// The contract of a pair-force model: a force between neighbouring fluid particles (and
// between a particle and the walls) that joins the fused force sweep (ForceSweep.hpp), four
// pairs at a time with SSE2 and one at a time for the rest. Viscosity and surface tension are
// pair-force models; PairForces.cpp lists them by name (the scene's fluid.viscosity_model and
// fluid.surface_tension_model).
//
// A model is a class derived from PairForceModel (whose members do nothing) that overrides what
// it uses; the sweep calls them in this order for every particle i:
//   acc = own(acc, i)                     a force of the particle's own (e.g. a surface traction)
//   Lanes lanes(i, view) const            its per-particle constants and four-lane sums
//   for four neighbours j at a time:
//     c  = radial4(c, lanes, pair)        its share of the pair scalar c (times grad W's factor)
//     cs = offset4(cs, lanes, pair)       its share of cs = c * factor (times x_ij alone)
//   acc = finish4(acc, i, lanes)          what it summed in its own lanes
//   for each remaining neighbour j: radial1 and direct1 (the same for one pair)
//   for each wall neighbour b (when wantsWalls()): wall1
// The one-pair and the four-pair forms must be the same formula: a pair lands in either.
// prepare(view) runs once before each sweep (e.g. surface normals); active() false leaves the
// model out of the sweep; timeStepLimit() is the step its explicit update stays stable at.
#include "sim/core/Constants.hpp"
#include "sim/core/Types.hpp"
#include "sim/scene/SimParams.hpp"
#include "sim/spatial/NeighborSearch.hpp"
#include "sim/sph/Gather4.hpp"
#include "sim/sph/Kernel.hpp"

#include <cmath>
#include <cstdint>
#include <vector>

namespace ferro {

/// What a model is set up from, once per simulation.
struct PairForceSetup {
    const SimScene* scene = nullptr;
    double spacing = 0;      ///< particle spacing [m]
    double support = 0;      ///< kernel support h [m]
    double restDensity = 0;  ///< rho0 [kg/m^3]
    double volume = 0;       ///< particle volume V = m / rho0 [m^3]
    double viscosity = 0;    ///< kinematic viscosity the sweep applies, physical plus artificial [m^2/s]
    double wallViscosity = 0;///< the walls' friction viscosity [m^2/s] (FluidSimulation::wallViscosity)
};

/// The particles as one sweep sees them (sorted order).
struct PairForceView {
    const std::vector<Vec3>& x;
    const std::vector<Vec3>& v;
    const std::vector<Real>& rho;
    const Real* px;  ///< x split into coordinates, for the four-lane gathers
    const Real* py;
    const Real* pz;
    const NeighborLists& fluid;
    const NeighborLists& boundary;
    const std::vector<Vec3>& bx;
    const std::vector<Real>& bVolume;
    const CubicSplineKernel& kernel;
    const PeriodicDomain& periodic; ///< pair offsets go to the nearest image (x_ij, x_ib)
};

#if defined(__SSE2__)
/// Four pairs (i, j[0..3]): offsets x_i - x_j, squared and plain distances, rho_i + rho_j,
/// and the kernel's gradient factor (grad W_ij = gradFactor x_ij).
struct PairLanes4 {
    const uint32_t* j;
    __m128 dx, dy, dz, r2, r, rhoSum, gradFactor;
};
#endif

/// One pair (i, j).
struct Pair1 {
    size_t i;
    uint32_t j;
    Vec3 xij;   ///< x_i - x_j
    Real r2, r; ///< |x_ij|^2, |x_ij|
    Real rhoSum;///< rho_i + rho_j
    Real gradFactor; ///< grad W_ij = gradFactor x_ij
};

/// A particle and a wall particle b.
struct WallPair1 {
    size_t i;
    uint32_t b;
    Vec3 xib;   ///< x_i - x_b
    Real r2;    ///< |x_ib|^2
    Vec3 gradW; ///< grad W(x_ib)
};

/// The capillary wave time step limit (Brackbill et al. 1992), sqrt(rho0 s^3 / (2 pi sigma))
/// [s], for a surface tension model; no limit without tension.
inline double capillaryStepLimit(const PairForceSetup& s) {
    const double sigma = s.scene->fluid.surfaceTension;
    return sigma > 0 ? std::sqrt(s.restDensity * s.spacing * s.spacing * s.spacing / (2 * kPi * sigma)) : 1e30;
}

/// The do-nothing members every model starts from.
class PairForceModel {
public:
    struct Lanes {};
    bool active() const { return false; }
    double timeStepLimit() const { return 1e30; }
    void prepare(const PairForceView&) {}
    Vec3 own(const Vec3& acc, size_t) const { return acc; }
    Lanes lanes(size_t, const PairForceView&) const { return {}; }
#if defined(__SSE2__)
    template <class L> __m128 radial4(__m128 c, L&, const PairLanes4&) const { return c; }
    template <class L> __m128 offset4(__m128 cs, L&, const PairLanes4&) const { return cs; }
    template <class L> Vec3 finish4(const Vec3& acc, size_t, const L&) const { return acc; }
#endif
    Real radial1(Real c, const Pair1&) const { return c; }
    Vec3 direct1(const Vec3& acc, const Pair1&) const { return acc; }
    bool wantsWalls() const { return false; }
    Vec3 wall1(const Vec3& acc, const WallPair1&) const { return acc; }
};

/// The model of "none": no force.
class NoPairForce : public PairForceModel {
public:
    static constexpr const char* kName = "none";
    explicit NoPairForce(const PairForceSetup& = {}) {}
};

} // namespace ferro

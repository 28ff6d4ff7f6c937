#pragma once
// Implicit viscosity after Weiler, Koschier, Brand & Bender 2018, "A Physically Consistent
// Implicit Viscosity Solver for SPH Fluids" (and SPlisHSPlasH's Viscosity_Weiler2018).
//
// The explicit viscous acceleration of FluidSimulation's force sweep is linear in the
// velocities, a = -L v, with (Weiler 2018 eq. 8, in the symmetric pair form used here)
//
//   (L v)_i = -sum_j c_ij ((v_i - v_j) . x_ij) x_ij - sum_b c_ib (v_i . x_ib) x_ib,
//   c_ij    = 10 nu (2 m / (rho_i + rho_j)) F(r_ij) / (r_ij^2 + 0.01 h^2)      (fluid pairs)
//   c_ib    = 10 nu_wall V_b (rho0 / rho_i) F(r_ib) / (r_ib^2 + 0.01 h^2)      (wall particles)
//
// where grad W_ij = F(r) x_ij (F < 0) and the walls are at rest. A backward Euler step of
// the viscous part is the linear system (Weiler 2018 eq. 12)
//
//   (I + dt L) v_new = v*,
//
// v* the velocities after every other force of the step. c_ij = c_ji (the mean density in
// the pair volume) and all particles have one mass, so L is symmetric positive
// semidefinite (each pair block c x x^T with c < 0, the wall blocks on the diagonal) and
// I + dt L is SPD for any dt: the solve is stable at any viscosity and step, where the
// explicit update v + dt a is stable only for dt < 2 / lambda_max(L).
//
// It is solved matrix-free by conjugate gradients with the block-Jacobi (3 x 3 per
// particle) preconditioner, as SPlisHSPlasH does, warm-started from the previous step's
// velocity change v_new - v* (Weiler 2018 sec. 4.3). Dot products are summed in a fixed
// order (deterministicSum), so a step is a pure function of its input.
//
// Walls: the wall term is Weiler's/SPlisHSPlasH's Akinci-boundary friction with
// nu_wall = container.wall_friction * nu (0 = free slip: the walls add nothing, as with
// SPlisHSPlasH's viscosityBoundary = 0). The wall reaction is not applied (walls are static).
#include "sim/spatial/PeriodicDomain.hpp"
#include "sim/core/Types.hpp"
#include "sim/sph/Kernel.hpp"
#include "sim/spatial/NeighborSearch.hpp"

#include <Eigen/Dense>

#include <vector>

namespace ferro {

/// What the viscous operator L reads, in FluidSimulation's sorted particle order.
struct ViscosityOperatorInput {
    const std::vector<Vec3>* positions = nullptr;       ///< fluid particles x [m]
    const std::vector<Real>* densities = nullptr;       ///< rho per particle [kg/m^3]
    const NeighborLists* fluidNeighbors = nullptr;      ///< fluid pairs within the support
    const NeighborLists* boundaryNeighbors = nullptr;   ///< wall particles within the support
    const std::vector<Vec3>* boundaryPositions = nullptr; ///< wall particles x_b [m]
    const std::vector<Real>* boundaryVolumes = nullptr; ///< Akinci volumes V_b [m^3]
    CubicSplineKernel kernel;                           ///< the simulation's kernel (support h)
    PeriodicDomain periodic;                            ///< pair offsets to the nearest image
    double supportRadius = 0;      ///< h [m]
    double particleMass = 0;       ///< m [kg]
    double restDensity = 0;        ///< rho0 [kg/m^3]
    double viscosity = 0;          ///< nu of the fluid pairs, physical plus artificial [m^2/s]
    double wallViscosity = 0;      ///< nu_wall = wall_friction * nu [m^2/s]; 0 = free slip
};

/// Settings of the conjugate gradient solve.
struct ImplicitViscositySettings {
    /// Stop when |v* - (I + dt L) v_new| <= tolerance |v*| (Eigen's / SPlisHSPlasH's
    /// relative residual; SPlisHSPlasH's default is 0.01).
    double tolerance = 1e-3;
    int maxIterations = 100;       ///< iteration cap of one solve
};

/// Outcome of one solve.
struct ImplicitViscosityResult {
    int iterations = 0;
    double relativeResidual = 0;   ///< |r| / |v*| at the end
    bool converged = true;
};

class ImplicitViscosity {
public:
    explicit ImplicitViscosity(const ImplicitViscositySettings& settings = {}) : settings_(settings) {}

    /// Prepares the pair coefficients c_ij, c_ib and the inverse 3 x 3 diagonal blocks of
    /// I + dt L for the current positions and densities. dt may be 0 (operator only).
    void setUp(const ViscosityOperatorInput& input, double dt);
    /// Solves (I + dt L) v_new = v* in place (v holds v* on entry, v_new on return).
    ImplicitViscosityResult solve(std::vector<Vec3>& v);
    /// a = -L v, the explicit viscous acceleration of v [m/s^2] (after setUp).
    void acceleration(const std::vector<Vec3>& v, std::vector<Vec3>& a) const;
    /// The largest eigenvalue of L [1/s] by power iteration (after setUp): the explicit
    /// update is stable for dt < 2 / lambda_max. For diagnostics and tests.
    double largestRate(int iterations = 60) const;

    /// The warm start (v_new - v* of the last solve) follows the particles' re-sort.
    void permute(const std::vector<uint32_t>& order);
    /// Forgets the warm start (every frame start, so resumed runs continue exactly).
    void resetWarmStart() { warmStart_.clear(); }

private:
    /// out = (I + dt L) v.
    void applySystem(const std::vector<Vec3>& v, std::vector<Vec3>& out) const;

    ImplicitViscositySettings settings_;
    ViscosityOperatorInput in_;
    double dt_ = 0;
    std::vector<Real> pairCoefficient_;     // c_ij, parallel to fluidNeighbors->index
    std::vector<Real> wallCoefficient_;     // c_ib, parallel to boundaryNeighbors->index
    std::vector<Eigen::Matrix<Real, 3, 3>> inverseDiagonal_;    // (I + dt L)_ii^-1, the block-Jacobi preconditioner
    std::vector<Vec3> warmStart_;           // v_new - v* of the last solve
    std::vector<Vec3> residual_, direction_, preconditioned_, product_;
};

} // namespace ferro

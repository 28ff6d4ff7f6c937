#pragma once
// Self-consistent magnetization of the ferrofluid particles (paper eq. 5 with Langevin
// saturation) and the total magnetic field they feel.
//
// Model. Each particle i carries the moment V_i M_i spread over a Wendland C2 kernel of
// support MagnetizationParams::smoothing * V_i^(1/3) (smoothed dipoles; smoothing = 0: a
// uniformly magnetized sphere of volume V_i, the older model). sim/particlefield/DipoleTree.hpp
// has the closed-form field, why it gives the macroscopic field on disordered particle sets
// and the surface term S_i. The field at particle i is
//     H_i = H_ext(x_i) + sum_j G(x_i - x_j) V_j M_j - S_i M_i - D_i M_i   (j = i included: -W(0) V_i M_i / 3)
// with D_i the local correction of DipoleTree.hpp (the particle-scale noise of the operator
// for a uniform M, interior particles only; MagnetizationParams::localCorrection)
// and the fluid follows the Langevin law along the local field,
//     M_i = M(|H_i|) H_i / |H_i|,   M(H) = Ms (coth xi - 1/xi),  xi = 3 chi0 H / Ms,
// linear M = chi0 H when Ms = 0. The solver finds H (and M) satisfying both.
//
// Numerics. Newton's method on R(H) = H - H_ext - A M(H) (A = the particle field operator),
// each Newton step a restarted GMRES on (I - A dM/dH) dH = -R. With smoothed dipoles -A is
// positive semidefinite for any particle positions (the kernel's Fourier transform is
// positive, the surface term is a local semidefinite block; exactly so for equal volumes) and dM/dH is symmetric positive
// (semi)definite, so the operator's spectrum is in [1, 1 + chi |A|]: Krylov converges in a
// handful of field evaluations where plain Jacobi iteration diverges for chi > ~2. For
// Ms = 0 one Newton step is exact. The solve stops when |R| / |H_ext| <= 0.1 * tolerance
// (2-norms over all particles; Stats::converged) or after maxIterations field evaluations
// (Stats::converged false: H is the last iterate, Stats::residual says how far it got). A
// warm start (H from the previous solve) cuts the work to what the particles' and magnets'
// motion changed.
//
// Solvers (MagnetizationParams::solver):
//   External  M = M(H_ext) alone, O(N); error ~ the neglected particle field (~chi/(1+chi)).
//   Direct    exact all-pairs products, O(N^2) per field evaluation: the reference.
//   Tree      Barnes-Hut products (sim/particlefield/DipoleTree.hpp), opening angle theta = cell size /
//             distance (default 0.5).
//   Auto      External if its sampled error is under `tolerance`, else Direct up to
//             directLimit() particles, else Tree (theta tightened, warm-started, up to twice
//             if the sampled tree error exceeds the tolerance). Stats::solver says which.
// The local correction adds three field evaluations a solve. The sphere model
// (smoothing = 0) is indefinite on disordered sets and may stop at its iteration cap
// unconverged at large chi0. Measurements (evaluations a solve, the tree's error and speed
// against Direct): docs/physics/magnetics.md, the opening list, and
// docs/physics/particle-field.md, "The sphere model (smoothing = 0)".
//
// Units: SI throughout (A/m, m, m^3); positions and results float, internals double.
#include "sim/particlefield/DipoleTree.hpp"
#include "sim/particlefield/ParticleField.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/magnets/MagnetizationParams.hpp"
#include "sim/core/Types.hpp"

#include "sim/magnets/LangevinLaw.hpp"

#include <Eigen/Core>

#include <memory>
#include <mutex>
#include <optional>
#include <vector>

namespace ferro {

/// Computes particle magnetization and field for one set of positions; see file comment.
class MagnetizationSolver {
public:
    using Solver = MagnetizationParams::Solver;

    struct Stats {
        Solver solver = Solver::External; ///< the solver that ran (Auto reports its pick)
        int iterations = 0;       ///< particle-field evaluations (GMRES matrix-vector products + residuals)
        int newtonSteps = 0;      ///< outer (Newton) steps
        double residual = 0;      ///< final |H - H_ext - A M| / |H_ext| (2-norms; 0 for External)
        /// The self-consistent solve reached its target residual (0.1 * tolerance) within
        /// maxIterations; false means H is the best iterate found, off by about `residual`.
        /// Always true for External and skipped solves (nothing to iterate).
        bool converged = true;
        /// Estimated relative RMS error of H against the converged all-pairs solution:
        /// External: RMS of the neglected particle field / RMS H_ext (sampled);
        /// Tree: sampled tree-vs-exact field difference / RMS H, plus the residual;
        /// Direct: the residual.
        double fieldError = 0;
        double openingAngle = 0;  ///< theta used (Tree)
        double seconds = 0;       ///< wall time of solve()
        size_t particles = 0;
        bool skipped = false;     ///< nothing to do: chi0 = 0, no magnets or no particles
    };

    explicit MagnetizationSolver(const MagnetizationParams& params);

    /// Magnetization M [A/m] and total field H [A/m] of particles at x [m] with volumes
    /// [m^3] (mass / density) in the field of `magnets`. H and M are resized to x.size();
    /// when H already has that size it is the starting guess (warm start; non-finite
    /// entries are replaced by the external field). Returns immediately with H = M = 0
    /// when magnets or x are empty; with chi0 <= 0 (not magnetic) M = 0 and H is the
    /// magnets' field (O(N), no particle field). Never returns non-finite values for
    /// finite inputs (coincident particles, particles on a pole). If J is given it receives
    /// the total-field Jacobians at the solution (see fieldGradient()), computed on the same
    /// tree (one build instead of two).
    /// `extraField`, if given (x.size() entries, input order), is applied field beyond the
    /// magnets' (the magnetized solids', sim/magnetics/SolidCoupling), added to theirs at each
    /// particle; J then holds only the magnets' and the particles' parts.
    Stats solve(const std::vector<Vec3>& x, const std::vector<Real>& volume, const std::vector<Magnet>& magnets,
                std::vector<Vec3>& H, std::vector<Vec3>& M, std::vector<Eigen::Matrix3f>* J = nullptr,
                const std::vector<Vec3>* extraField = nullptr);

    /// J[i](a, b) = dH_a / dx_b [A/m^2] of the TOTAL field at particle i: the magnets'
    /// analytic Jacobian plus that of the particles' field with magnetization M (as solved),
    /// from the same smoothed kernels (bounded; the surface term and the local correction are not differentiated: local terms). The particle part follows the solver: Tree -> tree (opening angle of the
    /// params), Direct -> exact all pairs, External -> none (its model neglects the particle
    /// field), Auto -> what the last solve() picked (before any solve: Tree above
    /// directLimit() particles, else Direct). The Kelvin force on particle i is
    /// mu0 V_i J_i M_i. J is resized to x.size(); zero when nothing is magnetic.
    void fieldGradient(const std::vector<Vec3>& x, const std::vector<Real>& volume,
                       const std::vector<Magnet>& magnets, const std::vector<Vec3>& M,
                       std::vector<Eigen::Matrix3f>& J) const;

    const MagnetizationParams& params() const { return params_; }
    /// Periodic side walls: the particles repeat with periods Lx, Ly [m] in x and y (0 = not
    /// periodic); the particle field then sums the periodic copies (DipoleTree::setPeriodic).
    /// The magnets' field is the scene's, taken at each particle (a uniform field is periodic).
    void setPeriodic(double Lx, double Ly) {
        period_[0] = Lx;
        period_[1] = Ly;
    }
    /// Auto uses Direct up to this many particles (where all pairs are cheaper than a tree).
    static constexpr size_t directLimit() { return 3000; }

private:
    // Newton-GMRES on a built tree, sorted order. Returns iterations etc. in stats.
    void solveSelfConsistent(DipoleTree& tree, bool useTree, const Eigen::VectorXd& Hext, Eigen::VectorXd& H,
                             Stats& stats) const;
    static void addMagnetGradients(const std::vector<Vec3>& x, const std::vector<Magnet>& magnets,
                                   const std::vector<uint32_t>& order, const std::vector<Mat3f>& Js,
                                   std::vector<Eigen::Matrix3f>& J);
    MagnetizationParams params_;
    std::optional<Solver> lastSolver_; // what the last solve() ran (Auto's pick)
    double period_[2] = {0, 0};        // setPeriodic
};

} // namespace ferro

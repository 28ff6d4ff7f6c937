#pragma once
// The scene's magnetizable solids ([[solids]]) in ferro-sim's step: their surface charge
// (sim/solids/SurfaceChargeSolver), solved in the magnets' field plus the fluid's, and the
// field and gradient that charge makes at the fluid's particles.
//
// Coupling. The solids are magnetized by the magnets, each other (the solve couples every
// panel) and the fluid; the fluid by the magnets, itself and the solids. The two solves
// alternate (block Gauss-Seidel), staggered in time: at each self-consistent solve of the
// fluid (sim/sph/FluidMagnetics), the solids are solved first in the magnets' field plus the
// field of the fluid's magnetization from the previous solve, then the fluid in the magnets'
// field plus the solids'. The interval between solves is set by the field's drift
// (FluidMagnetics), which includes the solids' share, so the lag is one solve's drift; how
// far the staggered pair is from the simultaneous solution has not been measured yet.
//
// Cost: one charge solve (GMRES, warm-started within a frame; a dense P x P matrix-vector
// product an application up to 6,144 panels), and the field and Jacobian at every particle,
// O(P) a particle, at every step (fieldAt): the field the force reads must be the gradient
// field at where the particle is now. A per-particle cache extrapolated by its Jacobian is
// not: its jumps at each re-evaluation pump the pool (docs/physics/magnetics.md,
// "Magnetizable solids", coupling with the fluid).
#include "sim/magnets/MagnetField.hpp"
#include "sim/magnets/MagnetizationParams.hpp"
#include "sim/solids/SolidParams.hpp"
#include "sim/solids/SurfaceChargeSolver.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace ferro {

class SolidCoupling {
public:
    struct Stats {
        size_t panels = 0;
        int iterations = 0;     ///< GMRES operator applications of the last solve
        bool converged = true;
        double seconds = 0;     ///< wall time of the last update (solve and evaluation)
    };

    /// The solids of a scene, meshed with panels of `panelSize` (their own key, else twice
    /// the fluid's spacing). Throws SceneError (naming `where`) for an unreadable mesh.
    SolidCoupling(const std::vector<SolidParams>& solids, double spacing, const std::string& where);

    bool active() const { return !solids_.empty(); }
    /// Each solid's surface in its own frame (ferro-sim's walls are these meshes).
    const std::vector<ShapeMesh>& shapes() const { return shapes_; }

    /// Solves the charge at time t in the field of `magnets` plus that of the fluid's
    /// particles at x with volumes and magnetization M (M empty: no fluid field yet), then
    /// evaluates the solids' field H [A/m] and Jacobian J [A/m^2] at every x.
    /// `cold`: the charge solve starts from zero (a frame's first solve, so that a resumed run,
    /// which has no last charge, takes the same steps), else from the last charge.
    Stats update(double t, const std::vector<Magnet>& magnets, const std::vector<Vec3>& x,
                 const std::vector<Real>& volume, const std::vector<Vec3>& M, const MagnetizationParams& law,
                 bool cold, std::vector<Vec3>& H, std::vector<Eigen::Matrix3f>& J);

    /// Between solves, every step: the solids' field H [A/m] and Jacobian J [A/m^2] at the
    /// particles' positions x now, from the last update's charge. Nothing (H and J left as
    /// they are) before the first update. A particle within half a spacing of a solid (or in
    /// it) sees the field half a spacing off the wall (SurfaceChargeSolver::fieldAndGradient's
    /// standoff).
    void fieldAt(const std::vector<Vec3>& x, std::vector<Vec3>& H, std::vector<Eigen::Matrix3f>& J) const;

    const SurfaceChargeSolver& solver() const { return solver_; }

private:
    std::vector<SolidParams> solids_;
    std::vector<ShapeMesh> shapes_;
    SurfaceChargeSolver solver_{couplingParams()};
    // The charge solve to 1e-4 (the solver's own default, 1e-6, is for its analytic tests):
    // a hundred times under the fluid's magnetization tolerance, and a third of the GMRES
    // steps at a coil's held current.
    static SurfaceChargeSolver::Params couplingParams() {
        SurfaceChargeSolver::Params p;
        p.tolerance = 1e-4;
        return p;
    }
    double posedTime_ = -1;   // the time the panels were last placed (moving solids re-place)
    bool moving_ = false;
    double standoff_ = 0;     // [m] half a spacing
};

} // namespace ferro

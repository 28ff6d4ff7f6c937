#pragma once
// The magnetization of soft-iron solids: a boundary-integral solve for the magnetic surface
// charge on their surfaces, and the field that charge makes anywhere.
//
// Model. A solid of relative permeability mu_r = 1 + chi in an applied field H0 (the magnets,
// the fluid) is magnetized, M = chi H inside; with no free current and uniform chi it has no
// volume charge, only the surface charge sigma = M . n [A/m]. Its field is
//     H_s(x) = 1/(4 pi) integral_S sigma(y) (x - y) / |x - y|^3 dA_y,
// and B . n is continuous across the surface, mu_r H_n^- = H_n^+, with
// H_n^+- = H0 . n + K'[sigma] +- sigma / 2 (K' the principal value of H_s . n on S). So
//     sigma / 2 - lambda K'[sigma] = lambda H0 . n,     lambda = (mu_r - 1) / (mu_r + 1),
// a Fredholm equation of the second kind whose spectrum lies in [(1 - lambda)/2, 1]: well
// conditioned for any mu_r except for one mode per closed body, the charge a perfect
// conductor of flux would hold at zero interior field, whose eigenvalue (1 - lambda)/2
// vanishes as mu_r -> infinity. A body's total charge is zero (div B = 0), and that mode is
// exactly its total charge, so each body adds (1/|S_b|) integral_{S_b} sigma dA to its rows:
// the solution is unchanged and the conductor mode is lifted to ~1, so GMRES converges in
// about as many steps at mu_r = 1e5 as at 10. What net charge the discretization still
// leaves is removed as a uniform density, so no monopole outlasts the dipole far away.
// Measurements: docs/physics/magnetics.md, "Magnetizable solids".
//
// The field inside a solid is the small difference of H0 and H_s when mu_r is large (H_in =
// 3 H0 / (mu_r + 2) in a sphere), so it is not evaluated from sigma. Inside, H = -grad psi
// with psi harmonic and d psi / dn = -H_n^- = -sigma / chi known; a second single layer tau
// on S with -tau/2 + K'[tau] = sigma / chi (the same operator, the same deflation) gives
// H_in = 1/(4 pi) integral tau (x - y)/|x - y|^3 dA at relative accuracy, and the panel's
// magnetization chi |H_in|, which an optional saturation bounds (Froehlich-Kennelly,
// M = chi H / (1 + chi H / Ms): each panel's chi is lowered to that secant value and the
// charge solved again until the secants settle).
//
// Discretization: a flat panel per triangle, sigma and tau constant on it, collocation at
// the centroid. In the solve a panel's field is its closed form (PanelIntegral.hpp) within
// kExactReach panel radii, averaged over the target panel's 3-point rule; a 3-point rule
// (degree 2) within kRuleReach; a point charge at the centroid beyond; and each panel adds
// the curved surface's own term its flat shape lacks (curvatureTerms in the .cpp). The
// normal operator is kept as a dense float matrix up to kDenseLimit panels. The field at a
// point (fieldAndGradient, the particles' path) uses the tighter kPoint* reaches, its far
// panels through PanelTree (or one float pass over all below Params::treeMinPanels).
// Convergence with the panel count: tests/sim/solids.
//
// Units: SI (m, A/m); double precision, except the dense operator and the point pass's float
// sum over every panel (the fluid's field tolerance is 1e-2).
#include "sim/solids/PanelIntegral.hpp"
#include "sim/solids/PanelTree.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace ferro {

/// One solid's closed surface at one moment, world coordinates.
struct SolidSurface {
    std::vector<Vec3d> vertices;                     ///< [m]
    std::vector<std::array<uint32_t, 3>> triangles;  ///< counter-clockwise seen from outside
    double permeability = 1000;                      ///< relative permeability mu_r > 1
    double saturation = 0;                           ///< Ms [A/m]; 0 = linear (no saturation)
};

class SurfaceChargeSolver {
public:
    /// Panels closer than this many source radii (centroid to farthest vertex) use the
    /// closed form, closer than kRuleReach the 3-point rule, farther a point charge.
    static constexpr double kExactReach = 4.0;
    static constexpr double kRuleReach = 12.0;
    /// The same reaches for the field at a point (fieldAndGradient), where the point charge's
    /// error falls as (radius / distance)^2 of one panel's share and each point sums every
    /// panel once: tighter, for speed.
    static constexpr double kPointExactReach = 2.0;
    static constexpr double kPointRuleReach = 6.0;
    /// Up to this many panels the normal operator is kept as a dense float matrix (151 MB).
    static constexpr size_t kDenseLimit = 6144;

    struct Params {
        /// GMRES stops at |residual| <= tolerance |rhs| (2-norms): far below the fluid's
        /// magnetization tolerance (1e-2), and the sphere's errors (tests) are the panels'.
        double tolerance = 1e-6;
        int maxIterations = 400;   ///< operator applications per linear solve
        int saturationSteps = 30;  ///< most secant updates with a saturation
        /// fieldAndGradient's tree (PanelTree): a cell of radius R at distance d is one
        /// expansion when R < openingAngle d and its error bound is under treeTolerance times
        /// the RMS surface charge (the field's scale at the surface): within 1e-4 of the sum
        /// over every panel (tests/sim/solids). openingAngle 0: every panel summed.
        double openingAngle = 0.5;
        double treeTolerance = 1e-4;
        /// Fewer panels than this: the direct sum (the tree does not pay).
        size_t treeMinPanels = 1024;
    };

    struct Stats {
        int iterations = 0;        ///< operator applications over all linear solves
        int secantSteps = 0;       ///< saturation updates (0 without saturation)
        double residual = 0;       ///< the last charge solve's relative residual
        bool converged = true;     ///< every linear solve reached its tolerance
    };

    SurfaceChargeSolver() = default;
    explicit SurfaceChargeSolver(const Params& p) : params_(p) {}

    /// The solids at one moment. Builds the panels and their near-field lists; the charges
    /// are cleared. Degenerate (zero-area) triangles are kept as panels without area.
    void setSurfaces(const std::vector<SolidSurface>& surfaces);

    /// Solves the charge in the applied field `applied` (H0 [A/m] at a point [m]: the
    /// magnets, the fluid), evaluated at every panel centroid. GMRES starts from the last
    /// charge (warm start) unless coldStart() was called since: results then agree with a
    /// cold solve to the tolerance, not to the last bit (a resumed run starts cold, so the
    /// caller makes every frame's first solve cold).
    Stats solve(const std::function<Vec3d(const Vec3d&)>& applied);
    /// Forgets the last charge (the interior layer, the saturation's secants) as the next solve's start.
    void coldStart() {
        sigma_.clear();
        tau_.clear(); // the interior layer warm-starts too
        lastField_.clear();
        chi_.clear();
        secantField_.clear();
    }
    /// Relative change (2-norm) of the applied normal field at the panels since the
    /// saturation's secants were fitted that fits them again.
    static constexpr double kSecantRefresh = 0.02;

    /// The solids' own field H_s [A/m] at x [m] outside every solid (inside it is H_s too,
    /// but that is the cancelling part; use interiorField there).
    Vec3d field(const Vec3d& x) const;
    /// The field and its Jacobian at x with the tighter kPoint* reaches, the far panels by
    /// the tree: the particles' path, as accurate as field() (tests/sim/solids; the numbers:
    /// docs/physics/magnetics.md, "Magnetizable solids"). Zero before a solve. A function of
    /// x alone, the same bits on any thread.
    ///
    /// `standoff` [m] > 0: a point nearer the solids' surface than that (or inside) takes the
    /// field at the nearest surface point moved `standoff` out (along the direction from it,
    /// or the panel's normal from inside), and
    /// the Jacobian of that map (the tangential part of J there): what a fluid particle, a
    /// parcel a spacing across, sees at a wall. Without it a particle touching the wall sits
    /// on the flat panels' edges, where the piecewise-constant charge's field has a
    /// logarithmic spike (docs/physics/magnetics.md, "Magnetizable solids", at the wall).
    void fieldAndGradient(const Vec3d& x, Vec3d& H, Mat3d& J, double standoff = 0) const;
    /// The total field H [A/m] at x inside a solid (applied plus own), from the interior layer.
    Vec3d interiorField(const Vec3d& x) const;

    size_t panelCount() const { return centroid_.size(); }
    const std::vector<Vec3d>& centroids() const { return centroid_; }
    const std::vector<Vec3d>& normals() const { return normal_; }
    const std::vector<double>& areas() const { return area_; }
    /// Surface charge sigma = M . n [A/m] per panel (after solve()).
    const std::vector<double>& charge() const { return sigma_; }
    /// |M| [A/m] per panel: chi |H_in| at its collocation point (after solve()).
    const std::vector<double>& magnetizationMagnitude() const;
    /// The secant susceptibility each panel ended with (chi without saturation).
    const std::vector<double>& susceptibility() const { return chi_; }

private:
    // Per panel, the curved surface's own contribution at its centroid that the flat panel
    // lacks (along its normal, without 1/(4 pi)); see the .cpp.
    std::vector<double> curvatureTerms(const std::vector<SolidSurface>& surfaces) const;
    // Principal-value field at every collocation point of the density `d` (one value a panel),
    // without 1/(4 pi).
    void collocationField(const std::vector<double>& d, std::vector<Vec3d>& out) const;
    // fieldAndGradient at x without a standoff, without 1/(4 pi); the panels within
    // kPointRuleReach radii of x in `near`, and every panel whose surface comes within
    // `keepNear` [m] of x that is within those radii (the tree expands no cell that near).
    void pointSum(const Vec3d& x, Vec3d& h, Mat3d& g, std::vector<uint32_t>& near, double keepNear = 0) const;
    // The near panels' exact field added to a far sum.
    void addNearPanels(const Vec3d& x, const std::vector<uint32_t>& near, Vec3d& h, Mat3d& g) const;
    // The field of density d at an arbitrary point, without 1/(4 pi).
    Vec3d densityField(const std::vector<double>& d, const Vec3d& x) const;
    // Each body's total charge of the density d (area-weighted sum over its panels).
    std::vector<double> bodyCharges(const std::vector<double>& d) const;
    // The normal component of collocationField (the dense matrix when there is one).
    void normalField(const std::vector<double>& d, std::vector<double>& out) const;
    // The interior layer tau and the panels' |M| for the current sigma (once per solve).
    int solveInterior() const;
    // Solves  diag * u - lambda (K' u) + deflation = rhs  (diag = +1/2 exterior, -1/2 interior),
    // starting from u when it has a value per panel (warm start).
    int solveLayer(double diag, const std::vector<double>& lambda, const std::vector<double>& rhs,
                   std::vector<double>& u, double& residual) const;

    Params params_;
    std::vector<std::array<Vec3d, 3>> corner_;
    std::vector<Vec3d> centroid_, normal_;
    std::vector<double> area_, radius_;
    std::vector<std::array<Vec3d, 3>> rule_;  // the 3-point rule's points per panel
    std::vector<uint32_t> body_;             // solid index of each panel
    std::vector<double> bodyArea_;           // total area per solid
    std::vector<double> chi0_, saturation_;  // per panel: the solid's chi and Ms
    // Collocation near field (CSR): for panel i, sources nearIndex_[nearStart_[i] ..] with
    // their exact (or 3-point) field per unit density at i.
    std::vector<uint32_t> nearStart_, nearIndex_;
    std::vector<Vec3d> nearField_;
    std::vector<double> sigma_, chi_;
    std::vector<double> secantField_;             // H0 . n at the secants' last fit
    std::vector<double> lastField_;               // H0 . n of the last solve (the warm start's scale)
    mutable std::vector<double> tau_, magnitude_; // the interior layer, solved on demand
    mutable bool interiorSolved_ = false;
    Eigen::MatrixXf dense_;                       // the normal operator (P <= kDenseLimit)
    Vec3d origin_{0, 0, 0};                       // fieldAndGradient's float arrays: centroids
    std::vector<float> pcx_, pcy_, pcz_, pq_, preach2_; // about origin_, charge, near reach^2
    PanelTree tree_;                              // the far field at points (Params::openingAngle > 0)
    double treeTolerance_ = 0;                    // its absolute error bound, in the sums' units
};

} // namespace ferro

#pragma once
// The magnetization the Kelvin body force uses, a function of the applied field's strength
// alone, h = |H_magnets|, fitted at each self-consistent solve:
//     M_f(h) = r(h) M_law(h),   G(h) = integral_0^h M_f dh',
// M_law the Langevin law of the applied field, r(h) a ratio, G the force's potential: the
// body force per volume is mu0 M_f(h) grad h = grad(mu0 G(h)).
//
// Why a function of h and not each particle's own M: the body force mu0 (J_magnets M_i) with
// the self-consistent M_i of every particle is not a gradient. M_i depends on where the other
// particles are (the layer's thickness, the heap's shape), not on h alone, so
// curl f = mu0 grad M x grad h is not zero and the force drives a steady convection roll:
// over a still dipole a pool never rests (docs/physics/magnetization.md, "The body force").
// With M a function of h only the force is a potential force, which the pressure balances
// at rest.
//
// Which function: in an incompressible fluid a potential force only shifts the pressure
// inside; what shapes the free surface is G along it. At rest the surface obeys
// rho g z_s = mu0 G(h) + C, and the ferrohydrostatic Bernoulli law (Rosensweig,
// Ferrohydrodynamics, ch. 5) asks rho g z_s = mu0 (F(H) + M_n^2 / 2) + C with H and M the
// total field and magnetization just inside the surface, M_n the normal component: the
// magnetic pressure plus the normal traction. So G is fitted to the surface pressure
// P = F(H) + M_n^2 / 2 of surface samples. Two fits (the simulation uses FreeSurface; Nodes,
// without samples, is its fallback when a solve has too few surface samples):
//  - Fit::Nodes (the class's default): r piecewise linear in log h on K nodes evenly spaced
//    between the smallest and largest h of the solve, constant beyond them. Least squares of
//    each particle's M along the applied field against r(h) M_law(h) and, given samples,
//    G(h_s) - C = P_s at a tenth of the weight for the particles.
//  - Fit::FreeSurface: samples on the free surface (FluidMagnetics::surfaceSamples), and
//    r(h) = c0 + c1 l + c2 l^2, l = log(h_c / h_ref), h_c = h clamped to the samples' range
//    (their 2nd to 98th percentile), least squares of G(h_s) - C = P_s over the samples alone,
//    C free (at least kMinSurfaceSamples; fewer fall back to the nodes without samples). With
//    a memory m in [0, 1) the targets are m (G_last(h_s) - C_last) + (1 - m) P_s: the curve
//    moves towards each solve's surface instead of jumping to it (the simulation sets m from
//    the time since the last fit, FluidMagnetics::kCurveMemory: without it the samples'
//    particles shuffle and the pool sloshes). A low-order curve on purpose: one free enough
//    to follow each ring of the surface lets the traction feed the shape ring by ring; and
//    the fit is continuous in the samples (a node range that jumps with the samples' extent
//    pumps the pool). r is not clamped at zero: where the surface pressure falls as h rises
//    (a surface the field runs along), so does G. Measurements (the pools' deviation from
//    the law, and the sloshing and pumping above): docs/physics/magnetization.md, "The
//    free-surface curve fit", and docs/physics/magnetics.md.
// Deterministic (sequential sums in the given order).
#include <optional>
#include <vector>

namespace ferro {

class DemagnetizationCurve {
public:
    static constexpr int kDefaultNodes = 16;
    /// Fit::FreeSurface with fewer usable samples than this falls back to the nodes.
    static constexpr int kMinSurfaceSamples = 16;

    /// Susceptibility chi0 [-] and saturation Ms [A/m] of the Langevin law (Ms = 0: linear).
    DemagnetizationCurve(double chi0 = 0, double Ms = 0, int nodes = kDefaultNodes);

    /// A free-surface sample: the applied field strength h [A/m] at the surface, the
    /// magnetic surface pressure P = F(|H|) + M_n^2 / 2 [A^2/m^2] of the ferrohydrostatic
    /// Bernoulli law there (H and M just inside the surface, M_n the normal component;
    /// times mu0 it is in Pa) and a weight >= 0 (how surely it is a surface point).
    struct SurfaceSample {
        double h = 0, pressure = 0, weight = 0;
    };
    /// Which fit (see the header comment).
    enum class Fit { Nodes, FreeSurface };

    /// Fits the curve. `h` [A/m] and `mAlong` [A/m] (same length): each particle's applied
    /// field strength and magnetization along the applied field; entries with h <= 0 or
    /// non-finite values are ignored, and with nothing usable r = 1. Fit::Nodes: r from the
    /// particles, and G(h_s) - C = P_s at the `surface` samples at a tenth of their weight.
    /// Fit::FreeSurface: with kMinSurfaceSamples usable samples or more, G from the samples
    /// alone (the particles only give residual()); with fewer, Fit::Nodes without samples.
    /// `memory` in [0, 1) (Fit::FreeSurface only): when the last fit was a surface fit too,
    /// each sample's target is memory x (the last curve's G(h_s) - C) + (1 - memory) x P_s,
    /// so the curve moves towards the surface's pressure by 1 - memory per fit instead of
    /// jumping to each solve's samples (see the header comment).
    void fit(const std::vector<double>& h, const std::vector<double>& mAlong,
             const std::vector<SurfaceSample>& surface = {}, Fit how = Fit::Nodes, double memory = 0);
    /// G(h) = integral_0^h M_f(h') dh' [A^2/m^2]: mu0 G / rho0 is the body force's potential.
    double potential(double h) const;

    /// What a free-surface fit is: r(h) = c0 + c1 l + c2 l^2, l = log(h_c / sqrt(hLo hHi)),
    /// h_c = h clamped to [hLo, hHi] [A/m], and the constant C [A^2/m^2] of G(h_s) - C = P_s.
    /// Carried in the particle files so that a resumed run continues the same curve.
    struct SurfaceFit {
        double hLo = 0, hHi = 0, c[3] = {1, 0, 0}, C = 0;
    };
    /// The last fit when it was a free-surface fit.
    std::optional<SurfaceFit> surfaceFit() const;
    /// Makes `f` the current curve, as if a free-surface fit had just found it. Returns false
    /// (and changes nothing) unless 0 < hLo <= hHi and every number is finite.
    bool restoreSurfaceFit(const SurfaceFit& f);

    /// True once fit() has been called.
    bool fitted() const { return fitted_; }
    /// True when the last fit was the free-surface polynomial.
    bool fittedToSurface() const { return surface_; }
    /// The ratio r(h) [-] (1 before any fit).
    double ratio(double h) const;
    /// M_f(h) = r(h) M_law(h) [A/m].
    double magnetization(double h) const;
    /// Relative RMS of what the curve leaves out at the fit's particles,
    /// sqrt(sum (m_i - M_f(h_i))^2 / sum m_i^2) (0 before any fit).
    double residual() const { return residual_; }

private:
    // The volume fit's nodes.
    double nodePosition(double h) const;
    /// Phi_b(h) = integral_0^h hat_b(h') M_law(h') dh' for every node b (G = sum r_b Phi_b).
    std::vector<double> basisIntegrals(double h) const;
    void tabulate();
    void fitNodes(const std::vector<double>& h, const std::vector<double>& mAlong,
                  const std::vector<SurfaceSample>& surface);
    // The surface fit.
    bool fitSurface(const std::vector<SurfaceSample>& surface, double memory);
    /// The table of Phi_k over [hLo_, hHi_] (hRef_ their geometric mean).
    void tabulateSurface();
    /// Phi_k(h) = integral_0^h l(h')^k M_law(h') dh', k = 0..2, from the table over [hLo, hHi].
    void surfaceBasis(double h, double phi[3]) const;

    std::vector<double> table_;   // volume: cumulative basis integrals on a fine log-h grid
    int fine_ = 32;               // grid steps per node interval
    double chi0_, Ms_;
    int nodes_;
    double logLow_ = 0, logSpan_ = 1;
    std::vector<double> r_;
    bool surface_ = false;
    double coef_[3] = {1, 0, 0};  // surface: r = c0 + c1 l + c2 l^2
    double constant_ = 0;         // surface: C
    double hLo_ = 1, hHi_ = 1, hRef_ = 1;
    static constexpr int kSurfaceSteps = 4096;   // fine enough that dG/dh is M_f within 0.1 %
    std::vector<double> surfaceTable_;   // surface: Phi_k at kSurfaceSteps + 1 points over [hLo, hHi]
    double residual_ = 0;
    bool fitted_ = false;
};

} // namespace ferro

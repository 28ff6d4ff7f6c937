#pragma once
// The fluid's magnetization along the applied field as a function of the applied field's
// strength alone, fitted to a self-consistent solve:
//     M_f(h) = r(h) M_law(h),   h = |H_magnets|,
// M_law the Langevin law of the applied field and r(h) the demagnetization ratio: how much
// the fluid's own field (mostly the demagnetizing field of a layer magnetized across it)
// lowers M where the applied field has strength h.
//
// Why the Kelvin body force uses it instead of each particle's own M: the body force
// mu0 (J_magnets M_i) with the self-consistent M_i of every particle is not a gradient. M_i
// depends on where the other particles are (the layer's thickness, the heap's shape), not on
// the applied field's strength alone, so curl f = mu0 grad M x grad h is not zero and the
// force drives a steady convection roll: over a still dipole a pool never rests (up at the
// centre, out along the top, measured 5 mm/s RMS on 2,000 particles against 0.6 mm/s with
// the `external` solver, whatever the re-solve interval or a spatial smoothing of the induced
// field). With M a function of h only, f = mu0 M_f(h) grad h = grad(mu0 G(h)), G' = M_f: a
// potential force, which the pressure balances at rest. The fit keeps what the self-consistent
// solve adds (the layer's demagnetization: for a layer magnetized across it M_law(H_in)
// grad|H_magnets| integrates to the ferrohydrostatic Bernoulli law with its normal-traction
// term mu0 M_n^2 / 2; tests/sim/sph/test_FluidMagnetics.cpp checks a resting pool against
// it) and drops only the part of M_i that varies between particles at equal h.
//
// The fit: r piecewise linear in log h on K nodes evenly spaced between the smallest and
// largest h of the solve, constant beyond them. Least squares of two kinds of rows: each
// particle's M along the applied field against r(h) M_law(h), and, given surface samples,
// the potential G(h_s) = integral_0^h_s r M_law dh against the ferrohydrostatic surface
// pressure F(H) + M_n^2 / 2 of the solve's surface samples, up to a free constant. In
// an incompressible fluid a potential body force only shifts the pressure, so what shapes the
// free surface is G along it; matching G to the surface pressure makes a resting surface the
// ferrohydrostatic one, if the samples are the free surface (the volume rows still decide
// the field strengths the surface does not reach). What the simulation passes at rest is the
// floor and the walls instead, and resting pools miss the law by 13 % of the centre rise at
// chi0 0.5 and 39-44 % at 1.5 (sim/sph/FluidMagnetics.cpp, tests/sim/sph/
// test_FluidMagnetics.cpp). Nodes without data are linear between fitted ones.
// Deterministic (sequential sums in the given order).
#include <vector>

namespace ferro {

class DemagnetizationCurve {
public:
    static constexpr int kDefaultNodes = 16;

    /// Susceptibility chi0 [-] and saturation Ms [A/m] of the Langevin law (Ms = 0: linear).
    DemagnetizationCurve(double chi0 = 0, double Ms = 0, int nodes = kDefaultNodes);

    /// A free-surface sample: the applied field strength h [A/m] there, the magnetic surface
    /// pressure P = F(|H|) + M_n^2 / 2 [A^2/m^2] of the ferrohydrostatic Bernoulli law (H and
    /// M just inside the surface, M_n the normal component; times mu0 it is in Pa) and a
    /// weight >= 0 (how surely the particle is a surface particle).
    struct SurfaceSample {
        double h = 0, pressure = 0, weight = 0;
    };

    /// Fits r from the particles' applied field strengths `h` [A/m] and the components of
    /// their magnetization along the applied field `mAlong` [A/m] (same length). Particles
    /// with h <= 0 or non-finite values are ignored; with none left, r = 1 everywhere.
    /// With `surface` samples the fit also asks the force's potential G(h) = integral_0^h
    /// M_f dh' to equal the surface pressure P up to a constant at every sample, so that a
    /// surface at rest in the force's potential is the ferrohydrostatic surface
    /// rho g z_s = mu0 P + C; where the surface has no samples (the field strengths it does
    /// not reach) the volume data decides.
    void fit(const std::vector<double>& h, const std::vector<double>& mAlong,
             const std::vector<SurfaceSample>& surface = {});
    /// G(h) = integral_0^h M_f(h') dh' [A^2/m^2]: mu0 G / rho0 is the body force's potential.
    double potential(double h) const;

    /// True once fit() has been called.
    bool fitted() const { return fitted_; }
    /// The demagnetization ratio r(h) [-] (1 before any fit).
    double ratio(double h) const;
    /// M_f(h) = r(h) M_law(h) [A/m].
    double magnetization(double h) const;
    /// Relative RMS of what the curve leaves out at the fit's particles,
    /// sqrt(sum (m_i - M_f(h_i))^2 / sum m_i^2) (0 before any fit).
    double residual() const { return residual_; }

private:
    double nodePosition(double h) const;
    /// Phi_b(h) = integral_0^h hat_b(h') M_law(h') dh' for every node b (G = sum r_b Phi_b).
    std::vector<double> basisIntegrals(double h) const;
    void tabulate();
    std::vector<double> table_;   // cumulative basis integrals on a fine log-h grid, row-major
    int fine_ = 32;               // grid steps per node interval
    double chi0_, Ms_;
    int nodes_;
    double logLow_ = 0, logSpan_ = 1;
    std::vector<double> r_;
    double residual_ = 0;
    bool fitted_ = false;
};

} // namespace ferro

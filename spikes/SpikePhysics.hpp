#pragma once
// The physics behind the spikes: the fluid's magnetization law, the Cowley-Rosensweig
// critical magnetization (paper eq. 16) and wavelength, and the hexagonal height field of
// eq. 13. Pure functions, SI units.
#include "sim/magnets/MagnetField.hpp"
#include "sim/core/Constants.hpp"
#include "sim/scene/SimParams.hpp"

namespace ferro {


// The fluid's law M(H) is the simulator's: langevinMagnetization / langevinSlope in
// sim/magnets/LangevinLaw.hpp (paper eq. 5 with Langevin saturation).

/// The threshold of the normal-field (Rosensweig) instability of a flat layer.
struct CriticalMagnetization {
    double magnetization = 0;  ///< M_c [A/m]; +inf when the fluid can never reach it
    double r0 = 1;             ///< sqrt(mu_c mu_t) / mu0 at M_c (chord and tangent permeability)
    double internalField = 0;  ///< H inside the fluid at M_c [A/m]
    double appliedField = 0;   ///< field applied normal to a flat layer that gives M_c inside
                               ///< (normal B continuous: H0 = H_in + M_c) [A/m]
};

/// Paper eq. 16 (Cowley & Rosensweig 1967):
///     M_c^2 = (2 / mu0) (1 + 1 / r0) sqrt(g delta_rho sigma),  r0 = sqrt(mu_c mu_t) / mu0,
/// with the chord permeability mu_c = mu0 (1 + M/H) and the tangent permeability
/// mu_t = mu0 (1 + dM/dH) of `law` taken at M_c itself (a fixed point, solved by iteration;
/// for a linear law r0 = 1 + chi0). delta_rho = fluid - ambient density [kg/m^3], g [m/s^2],
/// sigma [N/m]. Returns magnetization = +inf if the law saturates below M_c or chi0 = 0.
CriticalMagnetization criticalMagnetization(double deltaRho, double gravity, double surfaceTension,
                                            const MagnetizationParams& law);

/// Critical wavelength lambda_c = 2 pi sqrt(sigma / (delta_rho g)) [m] (capillary length times 2 pi).
double criticalWavelength(double deltaRho, double gravity, double surfaceTension);

/// A deep layer's surface modes in a normal field, for linear stability theory.
struct SurfaceModes {
    double density = 1000;       ///< rho, the inertia [kg/m^3]
    double deltaRho = 1000;      ///< fluid - ambient density [kg/m^3]
    double gravity = 9.81;       ///< [m/s^2]
    double surfaceTension = 0.025; ///< sigma [N/m]
    double viscosity = 0;        ///< kinematic nu [m^2/s], >= 0
    double supercriticality = 1; ///< (M / M_c)^2: the magnetic term mu0 M^2 / (1 + 1/r0) with r0
                                 ///< taken at M_c, so it is 2 sqrt(g delta_rho sigma) (M / M_c)^2
};

/// The growth rate s [1/s] of the mode of wavenumber k [1/m] on an infinitely deep layer
/// (Lange, Reimann & Richter 2000, "Wave number of maximal growth in viscous magnetic fluids
/// of arbitrary depth", in the deep limit): the root s >= 0 of
///     (s + 2 nu k^2)^2 + w0^2 = 4 nu^2 k^3 sqrt(k^2 + s / nu),
///     rho w0^2 = delta_rho g k + sigma k^3 - mu0 M^2 k^2 / (1 + 1/r0),
/// s = sqrt(-w0^2) without viscosity. 0 where the mode is stable (w0^2 >= 0).
double growthRate(const SurfaceModes& modes, double k);

/// The wavenumber of fastest growth [1/m]: the pattern a flat layer forms after the field jumps
/// above critical. Reimann, Richter, Rehberg & Lange (Phys. Rev. E 61, 5528, 2000) measured
/// that wavenumber after jumps of the field and found it grows linearly with the induction, as
/// this theory gives. k_c = sqrt(delta_rho g / sigma) at or below M_c. Inviscid it is
/// k_c (2 m + sqrt(4 m^2 - 3)) / 3 with m = (M / M_c)^2; a very viscous deep layer keeps k_c
/// (its growth rate, (mu0 M^2 k / (1 + 1/r0) - delta_rho g - sigma k^2) / (2 rho nu), peaks
/// there). Returns 0 without gravity or tension.
double fastestGrowingWavenumber(const SurfaceModes& modes);

/// Distance between neighbouring peaks of eq. 13 for wavenumber k: 4 pi / (sqrt(3) k).
inline double tipSpacingForWavenumber(double k) { return 4.0 * kPi / (1.7320508075688772 * k); }
/// Inverse of tipSpacingForWavenumber.
inline double wavenumberForTipSpacing(double l) { return 4.0 * kPi / (1.7320508075688772 * l); }

/// Eq. 13 divided by C0, in lattice coordinates: with e1 along eq. 13's x axis and e2 at
/// 60 degrees from it, both of length l = 4 pi / (sqrt3 k), the point a e1 + b e2 has
///     F = cos(k/2 (sqrt3 x + y)) + cos(k/2 (sqrt3 x - y)) + cos(k y)
///       = cos(2 pi (a + b)) + cos(2 pi a) + cos(2 pi b)
/// F = 3 at the tips (integer a, b), -1.5 at the centres of the lattice triangles; mean 0.
double hexProfile(double a, double b);

/// The square planform in the same units, tips at integer lattice coordinates (a, b) of
/// orthogonal steps l: with g = (cos 2 pi a + cos 2 pi b) / 2 (eq. 12 with two wave vectors
/// at 90 degrees, k = 2 pi / l),
///     F = 2.25 g + g^2 - 0.25,
/// the lowest-order profile with eq. 13's range and mean: F = 3 at the tips, -1.5 at the
/// cell centres, mean 0 (mean g^2 = 1/4), monotone in g. So the heights (C0, tips 3 C0 above
/// the mean level), the sharpening and the volume work unchanged on either planform.
double squareProfile(double a, double b);

/// The angle [rad] between the lattice axes e1 and e2 of a planform of that squareness in
/// [0, 1]: 60 degrees on a hexagon (0), 90 on a square (1), linear between.
inline double latticeAngle(double squareness) { return kPi / 3.0 * (1.0 + 0.5 * squareness); }

/// The planform morphing from hexagons (s = 0) to squares (s = 1), in the lattice coordinates
/// (a, b) of axes e1, e2 at latticeAngle(s): (1 - s) hexProfile + s squareProfile. Both are
/// eq. 12 on the same tips (F = 3 at integer a, b) with mean 0 over the cell, so the blend
/// keeps the tips, their height and the volume; F >= -1.5.
inline double morphProfile(double a, double b, double s)
{
    return s <= 0 ? hexProfile(a, b) : s >= 1 ? squareProfile(a, b) : (1 - s) * hexProfile(a, b) + s * squareProfile(a, b);
}

/// The hexagons' amplitude equation near onset (weakly nonlinear theory of the normal-field
/// instability; Gailitis 1977, Friedrichs & Engel 2001), in the supercriticality
/// eps = M / M_c - 1 and the amplitude a relative to full height:
///     tau da/dt = eps a + gamma a^2 - g a^3.
/// Hexagons bifurcate subcritically (gamma > 0, the quadratic term that three wave vectors
/// at 120 degrees allow): a flat layer is stable below eps = 0, spikes of finite height stand
/// from eps_s = -gamma^2 / (4 g) on. So the height jumps at onset, and spikes that stand
/// persist as the field falls below onset down to the lower threshold M_s = (1 + eps_s) M_c,
/// where they collapse (the hysteresis Gollwitzer et al. 2007 measured). The two
/// coefficients come from two numbers one reads off a measured sweep: the lower threshold
/// M_s / M_c and the supercriticality eps_full at which the spikes reach full height a = 1.
struct SpikeBifurcation {
    double gamma = 0;     ///< quadratic coefficient, >= 0
    double g = 1;         ///< cubic coefficient, > 0
    double lower = 0;     ///< eps_s = -gamma^2 / (4 g) <= 0: the lower threshold's supercriticality

    /// From M_s / M_c = lowerThreshold in (0, 1] and eps_full > 0: eps_s = lowerThreshold - 1,
    /// and the upper branch through (eps_full, 1):
    ///     gamma = 2 h + sqrt(4 h^2 + 4 h eps_full),  g = gamma + eps_full   (h = -eps_s).
    /// lowerThreshold = 1 gives the supercritical pitchfork a = sqrt(eps / eps_full).
    static SpikeBifurcation fromThresholds(double lowerThreshold, double epsFull);
    /// The stable stationary amplitude on the spikes' branch,
    ///     a*(eps) = (gamma + sqrt(gamma^2 + 4 g eps)) / (2 g)   for eps >= eps_s, else 0:
    /// gamma / g at onset (the jump), gamma / (2 g) at the lower threshold, 1 at eps_full.
    double upperBranch(double eps) const;
};

/// The profile of height F (in [-1.5, 3]) narrowed by exponent p >= 1:
/// 4.5 ((F + 1.5) / 4.5)^p - 1.5. p = 1 is F itself; tips stay at 3, troughs at -1.5.
double sharpenedProfile(double F, double p);

} // namespace ferro

#pragma once
// The fluid's magnetization law (paper eq. 5 with Langevin saturation, Rosensweig,
// Ferrohydrodynamics ch. 2 and 5): M(H) = Ms L(3 chi0 H / Ms), its slope, secant and energy.
// One definition for every stage: the simulator's magnetization solve, the spikes' critical
// magnetization and tip heights. Depends on nothing but <cmath>.

namespace ferro {

/// Langevin function L(xi) = coth(xi) - 1/xi (odd; L(0) = 0, L -> 1 as xi -> inf).
/// Uses the Taylor series for |xi| < 0.2, where the difference of the two ~1/xi terms
/// would cancel digits; ~1e-15 relative everywhere. Never exceeds 1 in magnitude.
double langevin(double xi);
/// dL/dxi = 1/xi^2 - 1/sinh^2(xi) (even; 1/3 at 0), series for |xi| < 0.2.
double langevinDerivative(double xi);

/// Magnetization [A/m] of a fluid of initial susceptibility chi0 and saturation Ms [A/m]
/// in a field of magnitude H [A/m]: M = Ms L(3 chi0 H / Ms); Ms <= 0 means linear chi0 H.
/// Odd in H; |M| < Ms; dM/dH = chi0 at H = 0.
double langevinMagnetization(double H, double chi0, double Ms);
/// Differential susceptibility dM/dH (dimensionless) at H: 3 chi0 L'(xi), chi0 if Ms <= 0.
double langevinSlope(double H, double chi0, double Ms);
/// Secant susceptibility M(H) / H, chi0 at H = 0 (the limit), chi0 if Ms <= 0.
double langevinSecant(double H, double chi0, double Ms);
/// F(H) = integral_0^|H| M(H') dH' [A^2/m^2]: mu0 F is the fluid's magnetic pressure, the
/// potential of the Kelvin force density mu0 M grad|H| (Rosensweig, Ferrohydrodynamics,
/// ch. 5). Langevin: Ms^2 / (3 chi0) ln(sinh xi / xi), xi = 3 chi0 H / Ms; chi0 H^2 / 2 if
/// Ms <= 0. Even, >= 0, finite for finite H (no sinh overflow).
double langevinEnergy(double H, double chi0, double Ms);

} // namespace ferro

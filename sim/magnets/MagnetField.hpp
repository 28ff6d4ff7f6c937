#pragma once
// Analytic magnetic field H [A/m] of the external magnets that drive the ferrofluid.
//
// Everything here is double precision, unlike the float particle state (see Types.hpp):
// fields are evaluated at comparatively few points, span many orders of magnitude
// between the pole and the far field, and the loop field needs elliptic integrals whose
// argument approaches 1 near the wire, where float would lose all digits.
//
// Conventions: H is the field of the magnet alone in vacuum, in SI units (A/m); the
// flux density is B = mu0 H. No mu0 appears anywhere in this file.
#include "sim/core/Types.hpp"
#include "sim/magnets/MagnetKinds.hpp"
#include "sim/core/Constants.hpp"

#include <vector>

namespace ferro {

/// One field source. A plain struct: which members matter depends on `kind`.
struct Magnet {
    using Kind = MagnetKind;  ///< see sim/magnets/MagnetKinds.hpp: one row per kind
    Kind kind = Kind::Dipole;
    Vec3d position{0, 0, 0};  ///< centre of the magnet [m] (ignored by Uniform)
    Vec3d direction{0, 0, 1}; ///< magnetic axis (south -> north for Dipole and Bar; right-hand
                              ///< normal of the current for Loop); normalized on use, a zero
                              ///< vector means "no axis" and gives zero field
    /// Dipole: moment m [A m^2]; Bar: pole strength q_m [A m] (moment m = q_m * length);
    /// Uniform: field magnitude H0 [A/m]; Loop: current I [A]; Coil: current I a turn [A].
    double strength = 0.0;
    double length = 0.0;      ///< Bar: distance between the two pole charges [m]; Coil: winding length [m]
    double radius = 0.0;      ///< Loop, Coil: radius [m]
    double turns = 1.0;       ///< Coil: number of turns over `length` (strength is the current a turn)
    /// Regularization length eps [m] for fields evaluated at particles that may touch a pole
    /// or the wire. Dipole and Bar use r^2 -> r^2 + eps^2 (Plummer softening, still curl-free);
    /// Loop evaluates points closer than eps to the wire at distance eps from it (eps is capped
    /// at radius/2 so the clamped point stays on the same side of the axis).
    /// With eps = 0 the exact singular point (dipole centre, pole, wire) returns zero field
    /// rather than inf/NaN; points merely near it get the exact, large field.
    double softening = 0.0;
};

/// H [A/m] of one magnet at point x [m].
Vec3d magnetField(const Magnet& magnet, const Vec3d& x);
/// H [A/m] of several magnets at x [m]: plain superposition (fields are linear in the sources).
Vec3d magnetField(const std::vector<Magnet>& magnets, const Vec3d& x);

/// Jacobian J(i,j) = dH_i/dx_j [A/m^2] of one magnet's field at x [m], consistent with the
/// (softened) field magnetField returns. Analytic for Dipole, Bar and Uniform; for Loop a
/// central difference with a step 1e-5 times the distance to the wire (relative accuracy
/// ~1e-9), since differentiating the elliptic-integral form analytically buys nothing here.
/// Outside sources (and with eps = 0) the Jacobian is symmetric and traceless (curl H = 0,
/// div H = 0). The Kelvin force density on the fluid is mu0 (M . grad) H = mu0 J M.
Mat3d fieldGradient(const Magnet& magnet, const Vec3d& x);
/// Sum of the Jacobians of several magnets [A/m^2].
Mat3d fieldGradient(const std::vector<Magnet>& magnets, const Vec3d& x);

/// Complete elliptic integral of the first kind K(m), parameter m = k^2 in [0, 1)
/// (arithmetic-geometric mean, ~1e-15 relative). Returns +inf for m >= 1.
double ellipticK(double m);
/// Complete elliptic integral of the second kind E(m), parameter m = k^2 in [0, 1].
double ellipticE(double m);

/// Magnet state at one animation key. Overrides position, direction and strength of the
/// track's base magnet (kind, length, radius and softening always come from the base).
struct MagnetKeyframe {
    double time = 0.0;         ///< [s]
    Vec3d position{0, 0, 0};   ///< [m]
    Vec3d direction{0, 0, 1};  ///< axis, normalized on use
    double strength = 0.0;     ///< same units as Magnet::strength
};

/// A magnet moved by keyframes (keys sorted by non-decreasing time).
/// Interpolation: position by Catmull-Rom (finite-difference tangents, valid for uneven key
/// spacing, one-sided at the ends); strength by monotone cubic Hermite (Fritsch-Butland
/// tangents) so it never overshoots the key values, e.g. never flips the magnet's sign
/// between two keys of equal sign; direction by slerp, always a unit vector. Before the first
/// and after the last key the track holds that key; a track without keys returns base.
struct MagnetTrack {
    Magnet base;
    std::vector<MagnetKeyframe> keys;

    /// The magnet at time t [s].
    Magnet at(double t) const;
};

} // namespace ferro

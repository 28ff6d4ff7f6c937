#pragma once
// Mathematical and physical constants, once for the whole project.

namespace ferro {

constexpr double kPi = 3.14159265358979323846;
/// 1 / (4 pi): the Green's function factor of the magnetic fields (SI, no mu0).
inline constexpr double kInv4Pi = 1.0 / (4.0 * kPi);
constexpr double kMu0 = 4e-7 * kPi; ///< vacuum permeability [T m/A]

} // namespace ferro

#pragma once
// Mathematical and physical constants, once for the whole project.

namespace ferro {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMu0 = 4e-7 * kPi; ///< vacuum permeability [T m/A]

} // namespace ferro

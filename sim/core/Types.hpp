#pragma once
// Basic numeric types of the simulator.
//
// Precision: particle state (positions, velocities, densities) is single precision.
// At the scales of a ferrofluid dish (0.1 m domain, 1 mm spacing) float resolves
// positions to ~1e-8 m, far below anything SPH can represent, and halves the memory
// traffic of the neighbour loops that dominate a step. Time, scene parameters and
// global sums (mass, momentum, volume diagnostics) are double: they accumulate over
// many steps or many particles, where float would lose digits.
#include <Eigen/Core>
#include <cstdint>

namespace ferro {

using Real = float;
using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Vec3d = Eigen::Vector3d;

} // namespace ferro

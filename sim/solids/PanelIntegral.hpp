#pragma once
// The field of a flat triangle carrying a uniform magnetic surface charge: the kernel of the
// solids' boundary-integral solve (SurfaceChargeSolver.hpp).
//
// A charge density sigma [A/m] spread over triangle T makes the field
//     H(x) = sigma / (4 pi) * I(x),   I(x) = integral_T (x - y) / |x - y|^3 dA_y   [1/m^0]
// (dimensionless: an area over a squared length). I splits into the part along T's unit
// normal n, the signed solid angle T subtends at x, and the in-plane part, the divergence
// theorem's edge sum (the gradient of 1/|x - y| integrated over T is 1/|x - y| integrated
// round its rim):
//     I(x) = Omega(x) n + sum_edges u_e ln((R_2 + s_2) / (R_1 + s_1)),
// u_e the in-plane outward normal of the edge, s_1 < s_2 the positions of its ends along it
// measured from the foot of x, R_1, R_2 their distances from x. Omega by van Oosterom and
// Strackee (IEEE Trans. Biomed. Eng. 30 (1983) 125); the logarithm in the form without
// cancellation on either side of the edge's foot.
#include "sim/core/Types.hpp"

#include <Eigen/Core>

namespace ferro {

using Mat3d = Eigen::Matrix3d;

/// I(x) above for the triangle (a, b, c), counter-clockwise about its outward normal. Exact
/// (to rounding) at any x off T's edges; on an edge's line within the edge the in-plane
/// part diverges logarithmically and is evaluated 1e-9 edge lengths off it. `onPanel`: x
/// lies on T (its collocation point): the normal part is the principal value 0 (the jump
/// +-n/2 sigma is the caller's), the in-plane part is kept.
Vec3d uniformTriangleField(const Vec3d& x, const Vec3d& a, const Vec3d& b, const Vec3d& c, bool onPanel = false);

/// The Jacobian dI_i/dx_j of uniformTriangleField at x (off T's rim), in closed form: the
/// edge logarithms' gradients and the solid angle's (the rim's segment Biot-Savart law).
/// Matches central differences of the field to their own accuracy (tests/sim/solids).
Mat3d uniformTriangleGradient(const Vec3d& x, const Vec3d& a, const Vec3d& b, const Vec3d& c);

/// The point of the triangle (a, b, c) nearest to x (Ericson, Real-Time Collision Detection,
/// 5.1.5: by the Voronoi regions of its corners, edges and face).
Vec3d closestPointOnTriangle(const Vec3d& x, const Vec3d& a, const Vec3d& b, const Vec3d& c);

} // namespace ferro

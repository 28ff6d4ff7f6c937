#pragma once
// Magnets are solids: the fluid cannot enter them. Each positioned magnet's body is the
// smallest real body that carries it (magnetBodyRadius, sim/magnets/MagnetKinds.hpp),
// the same body within which its field is bounded and flat:
//   dipole  a sphere of NdFeB around its position;
//   bar     a capsule of the pole-face radius around the segment between its two poles
//           (the real body is the cylinder between the pole faces; the caps beyond the
//           faces are where the model's field is flattened over the pole, so no fluid
//           belongs there either);
//   loop    a torus of the wire's radius around the loop;
//   coil    a cylindrical shell around its winding (the sheet of `radius` over `length`), at
//           any current: the winding is there with the current off too.
// Like Container::constrain, a hard position constraint after each step's move: a
// particle closer than half a spacing to a body is put back on the body's surface plus
// half a spacing (where the centre of the first layer of fluid touching a wall is), and
// its velocity component into the body relative to the magnet's motion is removed.
// There are no boundary particles on a body: the constraint alone holds the fluid off.
// So that the pressure solve knows of it, the solvers first remove the velocity into a
// body of each particle the step would carry into it (stopMotionInto): otherwise the solve
// predicts positions the constraint undoes, and the bodies pump energy into the fluid
// (docs/physics/sph-solver.md, "Magnet bodies"; tests/sim/app/test_extremes.cpp).
// The fluid's blocks are seeded around the bodies (FluidSeed.cpp): a magnet placed in the
// fluid displaces it, and a block's count is the fluid's, the magnet's volume left out.
#include "sim/core/Types.hpp"
#include "sim/magnets/MagnetField.hpp"

#include <vector>

namespace ferro {

struct MagnetObstacle {
    Vec3d a{0, 0, 0}, b{0, 0, 0}; ///< the body's core segment (a == b: a sphere)
    double ringRadius = 0;        ///< > 0: the core is a circle of this radius around a, normal `axis`
    double halfLength = 0;        ///< with ringRadius: the core is the cylinder of that radius
                                  ///< from a - halfLength axis to a + halfLength axis (a coil)
    Vec3d axis{0, 0, 1};
    double radius = 0;            ///< distance from the core the fluid's centres keep [m]
    Vec3d velocity{0, 0, 0};      ///< the magnet's translation [m/s]
    Vec3 lo, hi;                  ///< float bounding box of the kept-out region (quick reject)
};

/// The bodies of `tracks` at time t1 (the end of a step of dt seconds), each grown by
/// `clearance` (half a spacing). Uniform fields and magnets of zero strength have none.
/// The magnet's velocity is its track's motion just before t1, at most `maxSpeed` (the
/// fastest motion between keys: keys at one time are a jump, not a motion).
std::vector<MagnetObstacle> magnetObstacles(const std::vector<MagnetTrack>& tracks, double t1, double dt,
                                            double clearance, double maxSpeed);

/// True when p is closer to the body than its `radius` (where no fluid centre may be).
bool isInside(const MagnetObstacle& body, const Vec3d& p);

/// Puts `x` back outside `body` (onto its surface) and removes the velocity component
/// into it relative to the body's velocity. Returns true when the particle was moved.
bool keepOutside(const MagnetObstacle& body, Vec3& x, Vec3& v);

/// The velocity half of the constraint, for the pressure solve: when x + dt v would enter
/// the body, removes v's component into it (relative to the body's velocity), the normal
/// taken at x. Returns true when v changed.
bool stopMotionInto(const MagnetObstacle& body, const Vec3& x, Vec3& v, double dt);

} // namespace ferro

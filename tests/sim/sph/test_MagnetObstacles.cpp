// Magnet bodies as solids (sim/sph/MagnetObstacles): the position constraint after a step
// and the velocity constraint before the pressure solve, on a sphere and a moving sphere.
#include "sim/sph/MagnetObstacles.hpp"

#include <catch2/catch.hpp>

using namespace ferro;

namespace {

/// A sphere of radius 1 cm around the origin (a dipole's body plus clearance).
MagnetObstacle sphere(const Vec3d& velocity = Vec3d::Zero()) {
    MagnetObstacle o;
    o.radius = 0.01;
    o.velocity = velocity;
    o.lo = Vec3::Constant(-0.01f);
    o.hi = Vec3::Constant(0.01f);
    return o;
}

} // namespace

TEST_CASE("a particle inside a magnet's body is put on its surface, its velocity into it removed", "[magnets][obstacles]") {
    const MagnetObstacle body = sphere();
    Vec3 x(0.006f, 0, 0), v(-2, 1, 0);
    REQUIRE(keepOutside(body, x, v));
    CHECK(double(x.norm()) >= 0.01);
    CHECK(x.norm() == Approx(0.01).epsilon(1e-5));
    CHECK(v.x() == 0.0f);  // the normal is +x: -2 m/s into the body removed
    CHECK(v.y() == 1.0f);  // tangential motion kept
    Vec3 outside(0.02f, 0, 0), vo(-2, 0, 0);
    CHECK_FALSE(keepOutside(body, outside, vo));
    CHECK(vo.x() == -2.0f);
}

TEST_CASE("the velocity into a body is removed before the pressure solve only where the step would enter it", "[magnets][obstacles]") {
    const MagnetObstacle body = sphere();
    const double dt = 1e-4;
    // On the surface (1 mm outside the core radius would be 0.011): moving in at 5 m/s
    // would take it 0.5 mm deep: the normal part goes, the tangential stays.
    Vec3 v(-5, 3, 0);
    CHECK(stopMotionInto(body, Vec3(0.0101f, 0, 0), v, dt));
    CHECK(v.x() == Approx(0).margin(1e-6));
    CHECK(v.y() == 3.0f);
    // The same speed 1 mm off: the step (0.5 mm) does not reach the body: unchanged.
    v = Vec3(-5, 3, 0);
    CHECK_FALSE(stopMotionInto(body, Vec3(0.011f, 0, 0), v, dt));
    CHECK(v.x() == -5.0f);
    // Moving away or along the surface: unchanged.
    v = Vec3(5, 0, 0);
    CHECK_FALSE(stopMotionInto(body, Vec3(0.0101f, 0, 0), v, dt));
    CHECK(v.x() == 5.0f);
    // A body moving at +1 m/s along x (towards the particle): the particle keeps up with it
    // (its normal speed becomes the body's), relative motion into it removed.
    const MagnetObstacle moving = sphere(Vec3d(1, 0, 0));
    v = Vec3(-5, 0, 0);
    CHECK(stopMotionInto(moving, Vec3(0.0101f, 0, 0), v, dt));
    CHECK(v.x() == Approx(1.0));
}

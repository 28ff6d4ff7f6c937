// Containers: wall sampling, contains() and constrain() for box, dish and mesh, and the
// hard guarantee of the mesh container: no motion crosses its (0.5 mm thin) wall.
#include "sim/geometry/Container.hpp"
#include "sim/core/Constants.hpp"
#include "sim/core/SceneDocument.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <assimp/Importer.hpp>
#include <assimp/scene.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

using namespace ferro;
using ferro::test::TempDir;
namespace fs = std::filesystem;

namespace {

const std::string kVessel = std::string(FERRO_SOURCE_DIR) + "/examples/meshes/vessel.obj";

// Cup geometry as written by scripts/make_vessel.py (float, as the mesh is read).
constexpr double kRIn = 0.03, kROut = 0.0305, kFloor = 0.0005, kRim = 0.04;

/// Rounds to float through a volatile: GCC 12's SLP vectorizer can otherwise drop a
/// double -> float -> double round trip, and the seam tests need the exact stored floats.
Vec3 toFloat(const Vec3d& p) {
    volatile float f[3] = {float(p.x()), float(p.y()), float(p.z())};
    const float x = f[0], y = f[1], z = f[2];
    return Vec3(x, y, z);
}

double minPairDistance(const std::vector<Vec3>& pts) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < pts.size(); ++i)
        for (size_t j = i + 1; j < pts.size(); ++j)
            best = std::min(best, double((pts[i] - pts[j]).squaredNorm()));
    return std::sqrt(best);
}

ContainerParams boxParams(bool closedTop) {
    ContainerParams p;
    p.type = ContainerParams::Type::Box;
    p.min = Vec3d(-0.05, 0.0, 0.01);
    p.max = Vec3d(0.05, 0.08, 0.06);
    p.closedTop = closedTop;
    return p;
}

ContainerParams dishParams() {
    ContainerParams p;
    p.type = ContainerParams::Type::Dish;
    p.center = Vec3d(0.01, -0.02, 0.005);
    p.radius = 0.05;
    p.height = 0.02;
    return p;
}

ContainerParams meshParams(const std::string& file, bool fluidInside = false) {
    ContainerParams p;
    p.type = ContainerParams::Type::Mesh;
    p.meshFile = file;
    p.fluidInside = fluidInside;
    return p;
}

/// Unit cube [0,1]^3 as quads, optionally without its top face.
std::string cubeObj(bool withTop) {
    std::string s = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                    "f 1 4 3 2\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    if (withTop) s += "f 5 6 7 8\n";
    return s;
}

/// Fluid side of the cup, decided from the analytic geometry alone: the cavity (inside
/// the inner wall's circumscribed circle, above the floor) or anywhere above the rim,
/// within the default safety box (mesh bounds extended upward by the mesh height).
bool analyticCupFluid(const Vec3& x, const Vec3d& offset = Vec3d::Zero()) {
    const Vec3d p = x.cast<double>() - offset;
    const double side = double(float(kROut)), rim = double(float(kRim));
    const bool inBox = std::abs(p.x()) <= side && std::abs(p.y()) <= side && p.z() >= 0 && p.z() <= 2 * rim;
    return inBox && ((std::hypot(p.x(), p.y()) < kRIn && p.z() > kFloor) || p.z() >= rim);
}

/// Certainly inside the cup's material: between the inner wall's circumscribed circle and
/// the outer wall's inscribed circle below the rim, or in the floor slab.
bool analyticCupMaterial(const Vec3& x, const Vec3d& offset = Vec3d::Zero()) {
    const Vec3d p = x.cast<double>() - offset;
    const double r = std::hypot(p.x(), p.y()), outer = kROut * std::cos(kPi / 64);
    return r < outer && p.z() > 0 && ((r > kRIn && p.z() < kRim) || p.z() < kFloor);
}

} // namespace

TEST_CASE("box walls: lattice on the walls, counts scale with area", "[container]") {
    for (const bool closedTop : {false, true}) {
        const ContainerParams p = boxParams(closedTop);
        const auto box = makeContainer(p, "scene.toml:3");
        const double s = 0.002;
        const std::vector<Vec3> w = box->sampleWalls(s);
        const double area = 0.1 * 0.08 * (closedTop ? 2 : 1) + 2 * (0.1 + 0.08) * 0.05;
        INFO("closedTop " << closedTop << ": " << w.size() << " samples");
        CHECK(double(w.size()) / (area / (s * s)) == Approx(1.0).epsilon(0.1));
        for (const Vec3& q : w) {
            const Vec3d x = q.cast<double>();
            const double eps = 1e-6;
            REQUIRE(box->contains(x, -eps));
            const bool onSide = std::abs(x.x() - p.min.x()) < eps || std::abs(x.x() - p.max.x()) < eps ||
                                std::abs(x.y() - p.min.y()) < eps || std::abs(x.y() - p.max.y()) < eps;
            const bool onFloor = std::abs(x.z() - p.min.z()) < eps;
            const bool onLid = closedTop && std::abs(x.z() - p.max.z()) < eps;
            REQUIRE((onSide || onFloor || onLid));
        }
        // No duplicates on shared edges and corners.
        CHECK(minPairDistance(w) > 0.9 * s);
        // Smaller spacing, about four times the samples.
        CHECK(double(box->sampleWalls(s / 2).size()) / double(w.size()) == Approx(4.0).epsilon(0.1));
    }
}

TEST_CASE("box contains and constrain", "[container]") {
    const ContainerParams p = boxParams(false);
    const auto box = makeContainer(p, "scene.toml:3");
    CHECK(box->contains(Vec3d(0, 0.04, 0.03), 0.005));
    CHECK_FALSE(box->contains(Vec3d(0, 0.04, 0.03), 0.03));
    CHECK_FALSE(box->contains(Vec3d(0, 0.04, 0.005), 0));
    CHECK_FALSE(box->contains(Vec3d(0.06, 0.04, 0.03), 0));
    CHECK_FALSE(box->contains(Vec3d(0, 0.04, 0.07), 0)); // the top is a hard limit too

    // Below the floor, moving down and sideways: lands on the floor, keeps sliding.
    Vec3 xOld(0.0f, 0.04f, 0.011f), x(0.001f, 0.04f, 0.009f), v(0.5f, 0.0f, -1.0f);
    CHECK(box->constrain(xOld, x, v));
    CHECK(x.z() >= 0.01);
    CHECK(x.z() == Approx(0.01));
    CHECK(box->contains(x.cast<double>(), 0));
    CHECK(v == Vec3(0.5f, 0.0f, 0.0f));
    // Out through a side and the top at once.
    xOld = Vec3(0.049f, 0.04f, 0.059f);
    x = Vec3(0.052f, 0.04f, 0.061f);
    v = Vec3(1.0f, 0.2f, 1.0f);
    CHECK(box->constrain(xOld, x, v));
    CHECK(box->contains(x.cast<double>(), 0));
    CHECK(v == Vec3(0.0f, 0.2f, 0.0f));
    // Inside: untouched.
    xOld = x = Vec3(0.0f, 0.04f, 0.03f);
    v = Vec3(1, 1, 1);
    CHECK_FALSE(box->constrain(xOld, x, v));
    CHECK(x == Vec3(0.0f, 0.04f, 0.03f));

    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.07, 0.12);
    for (int i = 0; i < 20000; ++i) {
        const Vec3 start(0.0f, 0.04f, 0.03f);
        Vec3 end = Vec3d(u(rng), u(rng), u(rng)).cast<float>(), vel(1, 1, 1);
        box->constrain(start, end, vel);
        REQUIRE(box->contains(end.cast<double>(), 0));
    }
}

TEST_CASE("dish walls: floor and wall samples, counts scale with area", "[container]") {
    const ContainerParams p = dishParams();
    const auto dish = makeContainer(p, "scene.toml:3");
    const double s = 0.002;
    const std::vector<Vec3> w = dish->sampleWalls(s);
    const double area = kPi * p.radius * p.radius + 2 * kPi * p.radius * p.height;
    INFO(w.size() << " samples for area/s^2 = " << area / (s * s));
    CHECK(double(w.size()) / (area / (s * s)) == Approx(1.0).epsilon(0.15));
    for (const Vec3& q : w) {
        const Vec3d x = q.cast<double>() - p.center;
        const double r = std::hypot(x.x(), x.y());
        const bool onFloor = std::abs(x.z()) < 1e-6 && r <= p.radius + 1e-6;
        const bool onWall = std::abs(r - p.radius) < 1e-6 && x.z() > -1e-6 && x.z() < p.height + 1e-6;
        REQUIRE((onFloor || onWall));
    }
    CHECK(minPairDistance(w) > 0.4 * s);
    CHECK(double(dish->sampleWalls(s / 2).size()) / double(w.size()) == Approx(4.0).epsilon(0.15));
}

TEST_CASE("wall samples moved into the solid by an offset", "[container]") {
    const double s = 0.002, off = 0.001, eps = 1e-6;
    for (const bool closedTop : {false, true}) {
        const ContainerParams p = boxParams(closedTop);
        const auto box = makeContainer(p, "scene.toml:3");
        const Vec3d lo = p.min - Vec3d::Constant(off), hi = p.max + Vec3d(off, off, closedTop ? off : 0);
        for (const Vec3& q : box->sampleWalls(s, off)) {
            const Vec3d x = q.cast<double>();
            REQUIRE(((x - lo).minCoeff() > -eps && (hi - x).minCoeff() > -eps));
            REQUIRE(((x - lo).cwiseAbs().minCoeff() < eps || (hi - x).head<2>().cwiseAbs().minCoeff() < eps ||
                     (closedTop && std::abs(hi.z() - x.z()) < eps)));
            REQUIRE_FALSE(box->contains(x, 0)); // outside the fluid region
        }
    }
    // Periodic sides: only the floor (and a lid) are walls, on either side of the offset's
    // sign (a negative offset puts the samples on the fluid side, as the magnetic step bound
    // takes them).
    for (const bool closedTop : {false, true}) {
        ContainerParams p = boxParams(closedTop);
        p.periodicSides = true;
        const auto box = makeContainer(p, "scene.toml:3");
        for (const double o : {off, -off}) {
            size_t floor = 0, lid = 0;
            for (const Vec3& q : box->sampleWalls(s, o)) {
                const Vec3d x = q.cast<double>();
                REQUIRE(x.x() >= p.min.x() - eps);
                REQUIRE(x.x() < p.max.x() - 0.5 * s); // the face x = max is the face x = min
                floor += std::abs(x.z() - (p.min.z() - o)) < eps;
                lid += std::abs(x.z() - (p.max.z() + o)) < eps;
            }
            const size_t layer = size_t(std::lround(0.1 / s) * std::lround(0.08 / s));
            CHECK(floor == layer);
            CHECK(lid == (closedTop ? layer : 0));
        }
    }
    const ContainerParams p = dishParams();
    const auto dish = makeContainer(p, "scene.toml:3");
    for (const Vec3& q : dish->sampleWalls(s, off)) {
        const Vec3d x = q.cast<double>() - p.center;
        const double r = std::hypot(x.x(), x.y());
        const bool onFloor = std::abs(x.z() + off) < eps && r <= p.radius + off + eps;
        const bool onWall = std::abs(r - p.radius - off) < eps && x.z() > -off - eps && x.z() < p.height + eps;
        REQUIRE((onFloor || onWall));
    }
    // Mesh walls may be thinner than the offset: samples stay on the surface.
    const auto cup = makeContainer(meshParams(kVessel), "scene.toml:7");
    CHECK(cup->sampleWalls(s, off) == cup->sampleWalls(s));
}

TEST_CASE("dish contains and constrain", "[container]") {
    const ContainerParams p = dishParams();
    const auto dish = makeContainer(p, "scene.toml:3");
    const Vec3d c = p.center;
    CHECK(dish->contains(c + Vec3d(0.01, 0.01, 0.01), 0.005));
    CHECK_FALSE(dish->contains(c + Vec3d(0.048, 0, 0.01), 0.005));
    CHECK(dish->contains(c + Vec3d(0.048, 0, 0.01), 0.001));
    CHECK_FALSE(dish->contains(c + Vec3d(0.051, 0, 0.01), 0));
    CHECK_FALSE(dish->contains(c + Vec3d(0, 0, -0.001), 0));
    CHECK(dish->contains(c + Vec3d(0, 0, 0.5), 0)); // open top

    // Out through the wall with an outward and a tangential velocity.
    Vec3 xOld = (c + Vec3d(0.0495, 0, 0.01)).cast<float>();
    Vec3 x = (c + Vec3d(0.0510, 0.001, 0.01)).cast<float>();
    Vec3 v(2.0f, 0.5f, -0.1f);
    CHECK(dish->constrain(xOld, x, v));
    CHECK(dish->contains(x.cast<double>(), 0));
    CHECK(std::hypot(double(x.x()) - c.x(), double(x.y()) - c.y()) == Approx(p.radius).epsilon(1e-5));
    const Vec3d radial = Vec3d(double(x.x()) - c.x(), double(x.y()) - c.y(), 0).normalized();
    CHECK(v.cast<double>().dot(radial) == Approx(0).margin(1e-6));
    CHECK(v.z() == -0.1f);
    CHECK(v.cast<double>().norm() > 0.4); // tangential part kept

    // Through the floor.
    xOld = (c + Vec3d(0.0, 0, 0.0005)).cast<float>();
    x = (c + Vec3d(0.0, 0, -0.001)).cast<float>();
    v = Vec3(0.1f, 0.0f, -1.0f);
    CHECK(dish->constrain(xOld, x, v));
    CHECK(x.z() >= c.z());
    CHECK(v == Vec3(0.1f, 0.0f, 0.0f));
    // Above the wall height the wall still holds (safety net).
    xOld = (c + Vec3d(0.049, 0, 0.2)).cast<float>();
    x = (c + Vec3d(0.06, 0, 0.2)).cast<float>();
    CHECK(dish->constrain(xOld, x, v));
    CHECK(dish->contains(x.cast<double>(), 0));

    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(-0.08, 0.08);
    for (int i = 0; i < 20000; ++i) {
        const Vec3 start = (c + Vec3d(0.01, 0, 0.01)).cast<float>();
        Vec3 end = (c + Vec3d(u(rng), u(rng), u(rng))).cast<float>(), vel(1, 1, 1);
        dish->constrain(start, end, vel);
        REQUIRE(dish->contains(end.cast<double>(), 0));
    }
}

TEST_CASE("container parameters are checked", "[container]") {
    ContainerParams p = boxParams(false);
    p.max.x() = p.min.x();
    CHECK_THROWS_AS(makeContainer(p, "s.toml:1"), SceneError);
    p = dishParams();
    p.radius = 0;
    CHECK_THROWS_AS(makeContainer(p, "s.toml:1"), SceneError);
    p = meshParams(kVessel);
    p.meshScale = 0;
    CHECK_THROWS_AS(makeContainer(p, "s.toml:1"), SceneError);

    ContainerParams none;
    const auto c = makeContainer(none, "s.toml:1");
    CHECK(c->sampleWalls(0.001).empty());
    CHECK(c->contains(Vec3d(1e6, -1e6, 3), 1));
    Vec3 x(1, 2, 3), v(4, 5, 6);
    CHECK_FALSE(c->constrain(Vec3(0, 0, 0), x, v));
    CHECK(x == Vec3(1, 2, 3));
    Vec3d lo, hi;
    c->bounds(lo, hi);
    CHECK(lo.maxCoeff() <= -1e29);
    CHECK(hi.minCoeff() >= 1e29);
}

TEST_CASE("mesh container loads the vessel and rejects open meshes", "[container]") {
    const auto cup = makeContainer(meshParams(kVessel), "scene.toml:7");
    Vec3d lo, hi;
    cup->bounds(lo, hi);
    CHECK(lo.x() == Approx(-kROut));
    CHECK(hi.y() == Approx(kROut));
    CHECK(lo.z() == 0.0);
    CHECK(hi.z() == Approx(2 * kRim)); // extended upward by the mesh height

    TempDir dir("container");
    const std::string open = dir.write("open.obj", cubeObj(false));
    try {
        makeContainer(meshParams(open), "scene.toml:7");
        FAIL("open mesh accepted");
    } catch (const SceneError& e) {
        const std::string msg = e.what();
        CHECK(msg.rfind("scene.toml:7: container.file:", 0) == 0);
        CHECK(msg.find("not closed (4 boundary edges)") != std::string::npos);
    }
    try {
        makeContainer(meshParams((dir.path / "missing.obj").string()), "scene.toml:7");
        FAIL("missing mesh accepted");
    } catch (const SceneError& e) {
        CHECK(std::string(e.what()).find("cannot load") != std::string::npos);
    }

    // Scale and translate apply in that order; explicit bounds replace the default box.
    ContainerParams p = meshParams(dir.write("cube.obj", cubeObj(true)), true);
    p.meshScale = 0.1;
    p.meshTranslate = Vec3d(1, 2, 3);
    p.hasBounds = true;
    p.boundsMin = Vec3d(0, 0, 0);
    p.boundsMax = Vec3d(5, 5, 5);
    const auto cube = makeContainer(p, "scene.toml:7");
    cube->bounds(lo, hi);
    CHECK(hi == Vec3d(5, 5, 5));
    CHECK(cube->contains(Vec3d(1.05, 2.05, 3.05), 0.01));
    CHECK_FALSE(cube->contains(Vec3d(1.05, 2.05, 3.05), 0.06));
    CHECK_FALSE(cube->contains(Vec3d(0.95, 2.05, 3.05), 0));
}

TEST_CASE("mesh container: contains() on the vessel", "[container]") {
    const auto cup = makeContainer(meshParams(kVessel), "scene.toml:7");
    // Cavity.
    CHECK(cup->contains(Vec3d(0, 0, 0.02), 0));
    CHECK(cup->contains(Vec3d(0, 0, 0.02), 0.01));
    CHECK(cup->contains(Vec3d(0.0299, 0, 0.02), 0));
    CHECK(cup->contains(Vec3d(0.02, -0.02, 0.001), 0));
    CHECK_FALSE(cup->contains(Vec3d(0.0299, 0, 0.02), 0.001)); // 0.1 mm from the wall
    CHECK_FALSE(cup->contains(Vec3d(0, 0, 0.001), 0.001));      // 0.5 mm above the floor
    // Above the rim, inside the safety box.
    CHECK(cup->contains(Vec3d(0, 0, 0.05), 0));
    CHECK(cup->contains(Vec3d(0.0302, 0, 0.0401), 0));
    CHECK_FALSE(cup->contains(Vec3d(0, 0, 0.09), 0));
    // Wall material: between the polygons along vertex directions, in the floor slab.
    for (int k = 0; k < 64; k += 5) {
        const double a = 2 * kPi * k / 64, r = 0.5 * (kRIn + kROut);
        CHECK_FALSE(cup->contains(Vec3d(r * std::cos(a), r * std::sin(a), 0.02), 0));
        CHECK_FALSE(cup->contains(Vec3d(r * std::cos(a), r * std::sin(a), 0.0399), 0));
    }
    CHECK_FALSE(cup->contains(Vec3d(0.01, 0.01, 0.00025), 0));
    CHECK_FALSE(cup->contains(Vec3d(0, 0, 0.00025), 0));
    // Outside the cup below the rim.
    CHECK_FALSE(cup->contains(Vec3d(0.035, 0, 0.02), 0));
    CHECK_FALSE(cup->contains(Vec3d(0, -0.04, 0.01), 0));
    CHECK_FALSE(cup->contains(Vec3d(0, 0, -0.001), 0));

    // fluid_inside flips the sides: then the wall material is the fluid domain.
    const auto solid = makeContainer(meshParams(kVessel, true), "scene.toml:7");
    CHECK(solid->contains(Vec3d(0.03025, 0, 0.02), 0));
    CHECK_FALSE(solid->contains(Vec3d(0, 0, 0.02), 0));
}

TEST_CASE("mesh container: wall samples cover the vessel surface", "[container]") {
    const auto cup = makeContainer(meshParams(kVessel), "scene.toml:7");
    const double s = 0.002;
    const std::vector<Vec3> w = cup->sampleWalls(s);
    const double area = 2 * kPi * kRIn * (kRim - kFloor) + 2 * kPi * kROut * kRim +
                        kPi * kRIn * kRIn + kPi * kROut * kROut + kPi * (kROut * kROut - kRIn * kRIn);
    const double ratio = double(w.size()) / (area / (s * s));
    INFO(w.size() << " samples, " << ratio << " x area/s^2");
    CHECK(ratio > 0.8);
    CHECK(ratio < 2.5);
    const double polygon = kROut * (1 - std::cos(kPi / 64)) + 1e-7, eps = 1e-7;
    for (const Vec3& q : w) {
        const double r = std::hypot(double(q.x()), double(q.y())), z = q.z();
        const bool inner = std::abs(r - kRIn) <= polygon && z > kFloor - eps && z < kRim + eps;
        const bool outer = std::abs(r - kROut) <= polygon && z > -eps && z < kRim + eps;
        const bool rim = std::abs(z - kRim) < eps && r > kRIn - polygon && r < kROut + eps;
        const bool floor = std::abs(z - kFloor) < eps && r < kRIn + eps;
        const bool bottom = std::abs(z) < eps && r < kROut + eps;
        INFO("sample " << q.transpose());
        REQUIRE((inner || outer || rim || floor || bottom));
    }
    CHECK(minPairDistance(w) >= 0.3 * s * 0.999);
    // Coverage: every point of the inner surface has a sample within the spacing.
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < 2000; ++i) {
        const double a = 2 * kPi * u(rng), z = kFloor + (kRim - kFloor) * u(rng);
        const Vec3 p = Vec3d(kRIn * std::cos(kPi / 64) * std::cos(a), kRIn * std::cos(kPi / 64) * std::sin(a), z).cast<float>();
        double best = 1;
        for (const Vec3& q : w) best = std::min(best, double((q - p).norm()));
        REQUIRE(best < s);
    }
}

namespace {

/// Runs one segment through constrain() and checks the end point: still on the cavity
/// side, by the container's own parity test and by the analytic cup geometry.
struct SegmentCheck {
    const Container& cup;
    Vec3d offset = Vec3d::Zero();
    long corrected = 0, crossedBefore = 0, failures = 0;

    void operator()(const Vec3& a, Vec3 b) {
        REQUIRE(cup.contains(a.cast<double>(), 0)); // a valid start
        Vec3 v = (b - a) * 100.0f;
        crossedBefore += !analyticCupFluid(b, offset);
        corrected += cup.constrain(a, b, v);
        const bool parity = cup.contains(b.cast<double>(), 0), analytic = analyticCupFluid(b, offset);
        if (!parity || !analytic) {
            if (failures++ < 5)
                FAIL_CHECK("leak: " << a.transpose() << " -> " << b.transpose() << " (contains " << parity
                                    << ", analytic " << analytic << ")");
        }
    }
};

} // namespace

TEST_CASE("mesh container: no motion crosses the thin wall (random segments)", "[container]") {
    // Also far from the origin, where float positions are coarser (~8 um steps at 100 m).
    const Vec3d offset = GENERATE(Vec3d(0, 0, 0), Vec3d(100, -50, 10));
    ContainerParams params = meshParams(kVessel);
    params.meshTranslate = offset;
    const auto cup = makeContainer(params, "scene.toml:7");
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> u(0, 1), jump(-0.003, 0.003);

    // Start points anywhere in the cavity, biased toward the walls where crossings happen.
    auto cavityPoint = [&]() {
        for (;;) {
            const double a = 2 * kPi * u(rng);
            double r, z;
            switch (int(u(rng) * 4)) {
            case 0: r = 0.0299 * std::sqrt(u(rng)), z = kFloor + (kRim - kFloor) * u(rng); break;
            case 1: r = 0.026 + 0.0039 * u(rng), z = kFloor + (kRim - kFloor) * u(rng); break;
            case 2: r = 0.0299 * std::sqrt(u(rng)), z = kFloor + 0.003 * u(rng); break;
            default: r = 0.0299 * std::sqrt(u(rng)), z = kRim - 0.003 * u(rng); break;
            }
            const Vec3 p = (offset + Vec3d(r * std::cos(a), r * std::sin(a), z)).cast<float>();
            if (analyticCupFluid(p, offset) && cup->contains(p.cast<double>(), 1e-6) &&
                double(p.z()) - offset.z() < kRim)
                return p;
        }
    };

    SegmentCheck check{*cup, offset};
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < 200000; ++i) {
        const Vec3 a = cavityPoint();
        check(a, a + Vec3d(jump(rng), jump(rng), jump(rng)).cast<float>());
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    INFO(check.corrected << " corrected, " << check.crossedBefore << " ended outside before, "
         << seconds << " s incl. sampling and checks");
    CHECK(check.failures == 0);
    CHECK(check.crossedBefore > 20000); // the test does push many particles through the wall
    CHECK(check.corrected >= check.crossedBefore);
}

TEST_CASE("mesh container: no motion crosses the wall at seam vertices and edges", "[container]") {
    const auto cup = makeContainer(meshParams(kVessel), "scene.toml:7");
    // The mesh's vertices exactly as a loader reads them (float).
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(kVessel, 0);
    REQUIRE(scene != nullptr);
    std::vector<Vec3> verts;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m)
        for (unsigned i = 0; i < scene->mMeshes[m]->mNumVertices; ++i) {
            const aiVector3D& v = scene->mMeshes[m]->mVertices[i];
            verts.emplace_back(v.x, v.y, v.z);
        }
    // The OBJ importer keeps one vertex per face corner.
    std::sort(verts.begin(), verts.end(), [](const Vec3& a, const Vec3& b) {
        return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
    });
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    // Seam targets on the cavity side: vertices of the inner surface and points on the
    // edges between them (inner ring at the floor and the rim, the floor centre).
    std::vector<std::pair<Vec3, Vec3>> edges; // seam = the segment between the two
    std::vector<Vec3> inner;
    for (const Vec3& v : verts) {
        const double r = std::hypot(double(v.x()), double(v.y()));
        if ((std::abs(r - kRIn) < 1e-6 || r < 1e-9) && v.z() > 0.0001f) inner.push_back(v);
    }
    REQUIRE(inner.size() == 2 * 64 + 1);
    for (const Vec3& a : inner)
        for (const Vec3& b : inner)
            if (&a < &b && (a - b).norm() < 0.04f) edges.emplace_back(a, b);

    SegmentCheck check{*cup};
    long exact = 0;
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> u(0.2, 1.0);
    auto inward = [](const Vec3& p) {
        // From a seam point into the cavity: toward the axis and up.
        Vec3d d(-double(p.x()), -double(p.y()), 0);
        if (d.norm() > 0) d.normalize();
        return Vec3d(d + Vec3d(0, 0, 1)).normalized();
    };
    for (const auto& [p0, p1] : edges) {
        for (const double f : {0.0, 0.5, 0.25}) {
            // Seam point s on the edge; a = s + w inside, b = s - w beyond the wall. For
            // dyadic w, a and b are often exact floats, so the segment meets the seam
            // exactly (a + b == 2 s, checked in double where it is exact).
            const Vec3d s = p0.cast<double>() + f * (p1 - p0).cast<double>();
            for (const double len : {1.0 / 1024, 1.0 / 2048, 1.0 / 4096}) {
                const Vec3d w = inward(s.cast<float>()) * len * u(rng);
                const Vec3 a = toFloat(s + w), b = toFloat(s - w);
                if (!cup->contains(a.cast<double>(), 1e-6)) continue;
                exact += (a.cast<double>() + b.cast<double>() == 2 * s);
                check(a, b);
                check(a, s.cast<float>()); // ending exactly on the seam
                // Sliding along the floor or wall into the seam and beyond.
                check(a, (s - 2.0 * Vec3d(w.x(), w.y(), 0)).cast<float>());
                check(a, (s - 2.0 * Vec3d(0, 0, w.z())).cast<float>());
            }
        }
    }
    // Exactly through the centre vertex of the floor fan, and through exact corners on
    // the axes (the mesh has exact zeros there).
    for (const double dz : {1.0 / 1024, 1.0 / 4096}) {
        const float f = float(kFloor);
        check(Vec3(0, 0, float(f + dz)), Vec3(0, 0, float(f - dz)));
        check(Vec3(0, 0, float(f + dz)), Vec3(0, 0, f));
        for (const Vec3& corner : {Vec3(float(kRIn), 0, f), Vec3(0, float(kRIn), f), Vec3(float(-kRIn), 0, f),
                                   Vec3(float(kRIn), 0, float(kRim)), Vec3(0, float(-kRIn), float(kRim))}) {
            const Vec3 dirIn = corner.normalized() * -1.0f;
            const Vec3 a(corner.x() + dirIn.x() * float(dz), corner.y() + dirIn.y() * float(dz), corner.z() + float(dz));
            const Vec3 b(corner.x() - dirIn.x() * float(dz), corner.y() - dirIn.y() * float(dz), corner.z() - float(dz));
            exact += (a.cast<double>() + b.cast<double>() == 2 * corner.cast<double>());
            check(a, b);
            // Horizontally: exactly along the rim's top plane through its inner edge, or
            // through the wall just above the floor.
            const float z = corner.z() == f ? f + 0.0001f : corner.z();
            check(Vec3(a.x(), a.y(), z), Vec3(b.x(), b.y(), z));
        }
    }
    INFO(check.corrected << " corrected, " << exact << " segments exactly through a seam");
    CHECK(check.failures == 0);
    CHECK(exact > 20);
}

TEST_CASE("mesh container: particles pushed against the wall step after step", "[container]") {
    // Random walks biased outward and downward, each step starting where constrain() left
    // the particle: slid particles (a hair off the wall) must be valid starts again.
    const auto cup = makeContainer(meshParams(kVessel), "scene.toml:7");
    std::mt19937 rng(77);
    std::uniform_real_distribution<double> u(-1, 1);
    long failures = 0, corrected = 0;
    for (int particle = 0; particle < 2000; ++particle) {
        const double a = kPi * (u(rng) + 1), r = 0.025 + 0.004 * std::abs(u(rng));
        Vec3 x = Vec3d(r * std::cos(a), r * std::sin(a), 0.001 + 0.0385 * std::abs(u(rng))).cast<float>();
        Vec3 v = Vec3::Zero();
        bool wentOver = false;
        for (int step = 0; step < 200; ++step) {
            const Vec3d outward = Vec3d(x.x(), x.y(), 0).normalized();
            const double push = 0.0015 * (particle % 2 ? 1.0 : 0.2);
            const Vec3d jump = push * outward + Vec3d(0, 0, -0.0005 + (particle % 7 == 0 ? 0.0009 : 0)) +
                               0.0015 * Vec3d(u(rng), u(rng), u(rng));
            const Vec3 xOld = x;
            x = (xOld.cast<double>() + jump).cast<float>();
            corrected += cup->constrain(xOld, x, v);
            wentOver = wentOver || x.z() >= float(kRim);
            const bool ok = cup->contains(x.cast<double>(), 0) && !analyticCupMaterial(x) &&
                            (wentOver || analyticCupFluid(x));
            if (!ok && failures++ < 5)
                FAIL_CHECK("leak at step " << step << ": " << xOld.transpose() << " -> " << x.transpose());
        }
    }
    INFO(corrected << " corrections");
    CHECK(failures == 0);
    CHECK(corrected > 100000);
}

TEST_CASE("mesh container: fluid inside a closed mesh stays inside", "[container]") {
    TempDir dir("container");
    const auto cube = makeContainer(meshParams(dir.write("cube.obj", cubeObj(true)), true), "s.toml:1");
    CHECK(cube->contains(Vec3d(0.5, 0.5, 0.5), 0.1));
    CHECK_FALSE(cube->contains(Vec3d(0.5, 0.5, 1.5), 0)); // above: outside the fluid domain
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> in(0.001, 0.999), jump(-0.05, 0.05);
    for (int i = 0; i < 50000; ++i) {
        Vec3 a(float(in(rng)), float(in(rng)), float(in(rng)));
        if (i % 4 == 0) a[i % 3] = 0.99999f; // hugging a face
        Vec3 b = a + Vec3d(jump(rng), jump(rng), jump(rng)).cast<float>(), v(1, 1, 1);
        cube->constrain(a, b, v);
        REQUIRE(cube->contains(b.cast<double>(), 0));
        REQUIRE((b.array() > 0.0f).all());
        REQUIRE((b.array() < 1.0f).all());
    }
    // A non-finite position (a blown-up step) is put back where it was, at rest.
    Vec3 nan(0.5f, std::numeric_limits<float>::quiet_NaN(), 0.5f), vn(1, 1, 1);
    CHECK(cube->constrain(Vec3(0.5f, 0.5f, 0.5f), nan, vn));
    CHECK(nan == Vec3(0.5f, 0.5f, 0.5f));
    CHECK(vn == Vec3::Zero());
    // Straight through an edge and a corner of the cube.
    Vec3 b(1.5f, 1.5f, 0.5f), v(1, 1, 0);
    CHECK(cube->constrain(Vec3(0.5f, 0.5f, 0.5f), b, v));
    CHECK(cube->contains(b.cast<double>(), 0));
    b = Vec3(1.5f, 1.5f, 1.5f);
    CHECK(cube->constrain(Vec3(0.5f, 0.5f, 0.5f), b, v));
    CHECK(cube->contains(b.cast<double>(), 0));
}

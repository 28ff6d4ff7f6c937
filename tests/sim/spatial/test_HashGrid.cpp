// HashGrid against brute force: radius queries, the nearest point, "any point closer than r",
// on random points spread over many cells (negative coordinates too) and on points placed on
// cell faces and at exactly the radius.
#include "sim/spatial/HashGrid.hpp"

#include <catch2/catch.hpp>

#include <random>
#include <set>
#include <vector>

using namespace ferro;

namespace {

std::vector<Vec3d> randomPoints(size_t n, double extent, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-extent, extent);
    std::vector<Vec3d> p(n);
    for (Vec3d& q : p) q = Vec3d(u(rng), u(rng), u(rng));
    return p;
}

} // namespace

TEST_CASE("HashGrid: radius queries and the nearest point equal brute force", "[spatial]") {
    const std::vector<Vec3d> points = randomPoints(2000, 1.0, 7);
    const HashGrid grid(points, 0.1);
    const std::vector<Vec3d> queries = randomPoints(300, 1.2, 11);
    for (const Vec3d& x : queries) {
        for (double r : {0.05, 0.1, 0.27}) {
            std::set<uint32_t> found, expected;
            grid.forEachWithin(x, r, [&](uint32_t i, double d2) {
                CHECK(d2 == Approx((points[i] - x).squaredNorm()));
                found.insert(i);
            });
            for (uint32_t i = 0; i < points.size(); ++i)
                if ((points[i] - x).squaredNorm() <= r * r) expected.insert(i);
            REQUIRE(found == expected);
            bool closer = false;
            for (const Vec3d& p : points) closer = closer || (p - x).squaredNorm() < r * r;
            CHECK(grid.anyCloserThan(x, r) == closer);
        }
        uint32_t best = 0;
        for (uint32_t i = 1; i < points.size(); ++i)
            if ((points[i] - x).squaredNorm() < (points[best] - x).squaredNorm()) best = i;
        CHECK(grid.nearest(x) == best);
    }
}

TEST_CASE("HashGrid: points on cell faces and at exactly the radius, add() one at a time", "[spatial]") {
    HashGrid grid(0.5);
    CHECK(grid.empty());
    CHECK(!grid.anyCloserThan(Vec3d::Zero(), 1.0));
    grid.add(Vec3d(0.5, 0, 0));   // on a cell face
    grid.add(Vec3d(-0.5, 0, 0));  // on the face of a negative cell
    grid.add(Vec3d(0, 0, 1.0));
    REQUIRE(grid.points().size() == 3);
    int within = 0;
    grid.forEachWithin(Vec3d::Zero(), 0.5, [&](uint32_t, double) { ++within; });
    CHECK(within == 2);                                 // radius inclusive
    CHECK(!grid.anyCloserThan(Vec3d::Zero(), 0.5));     // strictly closer: none
    CHECK(grid.anyCloserThan(Vec3d::Zero(), 0.5001));
    CHECK(grid.nearest(Vec3d(0.1, 0, 0.9)) == 2);
    CHECK(grid.nearest(Vec3d(-0.4, 0.1, 0)) == 1);
    CHECK(grid.nearestDistance(Vec3d(0, 0, 3), 1.0) == 1.0); // nothing within the cap
}

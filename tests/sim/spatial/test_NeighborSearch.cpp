// The uniform-grid neighbour search (sim/spatial/NeighborSearch.hpp) against a brute-force
// pair search: random points, points exactly on cell faces and on the bounding box, and a
// spread-out cloud for which the grid must coarsen its cells.
#include "sim/spatial/NeighborSearch.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <numeric>
#include <random>
#include <set>
#include <vector>

using namespace ferro;

namespace {

/// Sorts x with `grid`, then checks that the candidate ranges of every point hold every
/// point within `radius` (brute force over all pairs), that the ranges are valid and do
/// not repeat an index, and that the order is by (cell, id). Returns the candidate count.
size_t checkAgainstBruteForce(const std::vector<Vec3>& x, Real radius) {
    const size_t n = x.size();
    std::vector<uint32_t> ids(n), order;
    std::iota(ids.begin(), ids.end(), 0u);
    SortedGrid grid;
    grid.sort(x, ids, radius, order);
    REQUIRE(order.size() == n);
    std::vector<uint32_t> seen(order);
    std::sort(seen.begin(), seen.end());
    for (size_t k = 0; k < n; ++k) REQUIRE(seen[k] == k);   // a permutation
    std::vector<Vec3> sorted(n);
    for (size_t k = 0; k < n; ++k) sorted[k] = x[order[k]];
    grid.index(sorted, grid.geometry());
    const GridGeometry& g = grid.geometry();
    REQUIRE(g.cellSize >= radius);
    // Sorted by cell, ties by id.
    auto cellKey = [&](const Vec3& p) {
        int c[3];
        g.cellOf(p, c);
        for (int a = 0; a < 3; ++a) {
            REQUIRE(c[a] >= GridGeometry::kPad);
            REQUIRE(c[a] < g.dims[a] - GridGeometry::kPad);
        }
        return g.linear(c[0], c[1], c[2]);
    };
    for (size_t k = 1; k < n; ++k) {
        const uint32_t a = cellKey(sorted[k - 1]), b = cellKey(sorted[k]);
        REQUIRE((a < b || (a == b && order[k - 1] < order[k])));
    }
    size_t candidates = 0;
    const double r2 = double(radius) * radius;
    for (size_t i = 0; i < n; ++i) {
        std::vector<uint32_t> cand;
        grid.forEachCandidateRange(sorted[i], [&](uint32_t begin, uint32_t end) {
            REQUIRE(begin <= end);
            REQUIRE(end <= n);
            for (uint32_t j = begin; j < end; ++j) cand.push_back(j);
        });
        std::sort(cand.begin(), cand.end());
        REQUIRE(std::adjacent_find(cand.begin(), cand.end()) == cand.end());  // no index twice
        candidates += cand.size();
        for (size_t j = 0; j < n; ++j) {
            if ((sorted[i].cast<double>() - sorted[j].cast<double>()).squaredNorm() > r2) continue;
            CAPTURE(i, j, sorted[i].transpose(), sorted[j].transpose());
            REQUIRE(std::binary_search(cand.begin(), cand.end(), uint32_t(j)));
        }
    }
    return candidates;
}

} // namespace

TEST_CASE("the grid's candidate ranges hold every pair within the radius (random points)", "[neighbors]") {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-0.02f, 0.03f);
    std::vector<Vec3> x(3000);
    for (Vec3& p : x) p = Vec3(u(rng), u(rng), u(rng));
    const Real radius = 0.004f;
    const size_t candidates = checkAgainstBruteForce(x, radius);
    // 27 cells of the radius around each point: a bounded multiple of the pair count.
    const double density = double(x.size()) / std::pow(0.05, 3);
    CHECK(double(candidates) / double(x.size()) < 1.5 * 27 * std::pow(0.004, 3) * density + 27);
}

TEST_CASE("points on cell faces, at the box corners and at exactly the radius are found", "[neighbors]") {
    // A lattice at spacing = radius / 2 starting at the bounding box's low corner: every
    // other plane is a cell face, pairs at exactly the radius exist along every axis, and
    // the highest points lie on the box's far faces.
    const Real radius = 0.25f;
    std::vector<Vec3> x;
    for (int i = 0; i <= 8; ++i)
        for (int j = 0; j <= 8; ++j)
            for (int k = 0; k <= 8; ++k) x.push_back(Vec3(Real(i) * 0.125f, Real(j) * 0.125f, Real(k) * 0.125f) + Vec3(1, -2, 0.5f));
    // Duplicates and points nudged by one ulp across the faces.
    x.push_back(x[100]);
    x.push_back(x[100]);
    for (int a = 0; a < 3; ++a) {
        Vec3 p = x[200], q = x[200];
        p[a] = std::nextafter(p[a], 1e9f);
        q[a] = std::nextafter(q[a], -1e9f);
        x.push_back(p);
        x.push_back(q);
    }
    checkAgainstBruteForce(x, radius);
    // Shuffled input: the sorted order does not depend on the input order (ids tie-break).
    std::vector<uint32_t> ids(x.size()), order1, order2;
    std::iota(ids.begin(), ids.end(), 0u);
    SortedGrid g1, g2;
    g1.sort(x, ids, radius, order1);
    std::vector<size_t> perm(x.size());
    std::iota(perm.begin(), perm.end(), size_t(0));
    std::shuffle(perm.begin(), perm.end(), std::mt19937(3));
    std::vector<Vec3> y(x.size());
    std::vector<uint32_t> yIds(x.size());
    for (size_t k = 0; k < x.size(); ++k) {
        y[k] = x[perm[k]];
        yIds[k] = uint32_t(perm[k]);
    }
    g2.sort(y, yIds, radius, order2);
    for (size_t k = 0; k < x.size(); ++k) REQUIRE(yIds[order2[k]] == order1[k]);
}

TEST_CASE("a cloud too spread for the cell budget gets larger cells and stays correct", "[neighbors]") {
    GridGeometry g;
    g.fit(Vec3(0, 0, 0), Vec3(100, 100, 100), 0.01f, size_t(1) << 20);
    REQUIRE(g.cellCount() <= (size_t(1) << 20));
    REQUIRE(g.cellSize > 0.01f);
    // Two clusters 1000 radii apart along every axis (10^9 cells at the radius).
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0, 0.05f);
    std::vector<Vec3> x;
    for (int k = 0; k < 400; ++k) x.push_back(Vec3(u(rng), u(rng), u(rng)));
    for (int k = 0; k < 400; ++k) x.push_back(Vec3(10 + u(rng), 10 + u(rng), 10 + u(rng)));
    checkAgainstBruteForce(x, 0.01f);
    // Empty and single-point clouds.
    checkAgainstBruteForce({}, 0.01f);
    checkAgainstBruteForce({Vec3(1, 2, 3)}, 0.01f);
}

TEST_CASE("NeighborLists: slots, current counts, stored gradients", "[neighbors]") {
    NeighborLists l;
    l.clear(3);
    REQUIRE(l.offset == std::vector<uint32_t>{0, 0, 0, 0});
    REQUIRE(l.count == std::vector<uint32_t>{0, 0, 0});
    REQUIRE_FALSE(l.hasGradients());
    l.offset = {0, 2, 5, 6};
    l.count = {1, 3, 0};
    l.index = {1, 2, 0, 2, 1, 0};
    REQUIRE(l.begin(1) == 2);
    REQUIRE(l.end(1) == 5);
    REQUIRE(l.end(0) == 1);        // the current neighbours are the first count[i] slots
    REQUIRE(l.begin(2) == l.end(2));
    REQUIRE_FALSE(l.hasGradients());
    l.gradFactor.assign(l.index.size(), Real(0));
    REQUIRE(l.hasGradients());
    l.clear(2);
    REQUIRE(l.index.empty());
    REQUIRE(l.gradFactor.empty());
    REQUIRE(l.offset.size() == 3);
}

// The periodic image map (sim/spatial/PeriodicDomain.hpp): wrapping lands every coordinate in
// [lo, lo + period) and is idempotent, including the floats next to either face, and the
// four-lane offsets equal the scalar ones.
#include "sim/spatial/PeriodicDomain.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

using namespace ferro;

TEST_CASE("periodic wrap lands in the box, from lo up to lo + period, and is idempotent, next to the faces too",
          "[spatial][periodic]") {
    // Off-centre faces, as a box from a scene: lo is not 0, so x - lo is rounded.
    const Vec3 lo(-0.0117f, 0.0031f, 0), hi(0.0123f, 0.0271f, 0.01f);
    const PeriodicDomain d = PeriodicDomain::horizontal(lo, hi);
    REQUIRE(d.active());
    std::vector<Real> xs;
    for (int a = 0; a < 2; ++a) {
        // Every float within 64 ulps of each face, and one and two periods away.
        for (Real face : {lo[a], hi[a]}) {
            for (Real shift : {Real(0), d.period[a], -d.period[a], 2 * d.period[a]}) {
                Real x = face + shift;
                for (int k = 0; k < 64; ++k) x = std::nextafter(x, -1.0f);
                for (int k = 0; k < 128; ++k, x = std::nextafter(x, 1.0f)) xs.push_back(x);
            }
        }
    }
    std::mt19937 rng(7);
    std::uniform_real_distribution<Real> u(-0.1f, 0.1f);
    for (int k = 0; k < 2000; ++k) xs.push_back(u(rng));
    size_t moved = 0;
    for (Real x : xs) {
        for (int a = 0; a < 2; ++a) {
            Vec3 p(0.001f, 0.01f, 0.002f);
            p[a] = x;
            Vec3 w = p;
            d.wrap(w);
            INFO("axis " << a << " x = " << x);
            REQUIRE(w[a] >= d.lo[a]);
            REQUIRE(w[a] < d.lo[a] + d.period[a]);
            REQUIRE(w[2] == p[2]);
            // The wrapped point is an image of the original: a whole number of periods away
            // (within the rounding of one subtraction).
            const double turns = (double(p[a]) - double(w[a])) / d.period[a];
            REQUIRE(std::abs(turns - std::round(turns)) < 1e-5);
            if (w[a] != p[a]) ++moved;
            Vec3 again = w;
            d.wrap(again);
            REQUIRE(again[a] == w[a]); // idempotent, bit for bit
        }
    }
    CHECK(moved > 1000);
}

TEST_CASE("periodic offsets: the nearest image, unchanged on a closed axis, four lanes as one",
          "[spatial][periodic]") {
    const PeriodicDomain d = PeriodicDomain::horizontal(Vec3(0, 0, 0), Vec3(0.02f, 0, 0.01f));
    REQUIRE(d.period[0] == Approx(0.02f));
    REQUIRE(d.period[1] == 0); // y closed
    std::mt19937 rng(11);
    std::uniform_real_distribution<Real> u(-0.02f, 0.02f);
    for (int k = 0; k < 4000; ++k) {
        const Vec3 off(u(rng), u(rng), u(rng));
        const Vec3 o = d.offset(off);
        REQUIRE(std::abs(o[0]) <= 0.5f * d.period[0] * (1 + 1e-6f));
        REQUIRE(o[1] == off[1]); // a closed axis is returned bit for bit
        REQUIRE(o[2] == off[2]);
        const double turns = (double(off[0]) - double(o[0])) / d.period[0];
        REQUIRE(std::abs(turns - std::round(turns)) < 1e-5);
    }
#if defined(__SSE2__)
    for (int axis = 0; axis < 2; ++axis) {
        for (int k = 0; k < 1000; ++k) {
            alignas(16) float in[4], out[4];
            for (float& v : in) v = u(rng);
            _mm_store_ps(out, d.offset4(_mm_load_ps(in), axis));
            for (int l = 0; l < 4; ++l) {
                Vec3 v(0, 0, 0);
                v[axis] = in[l];
                REQUIRE(out[l] == d.offset(v)[axis]);
            }
        }
    }
#endif
}

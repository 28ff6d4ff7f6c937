// The tip tracker (spikes/tracker): tips found on a pool with bumps at known places and
// heights, and frame-to-frame matching on tip sets whose answer is known by construction.
#include "spikes/tracker/TipTracker.hpp"
#include "tests/spikes/SpikeTestMeshes.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using namespace ferro;

namespace {

constexpr double kSpacing = 5e-3;   // tip spacing of the synthetic lattice [m]

struct TrueTip { double x, y, h; };

/// Hexagonal lattice tips within radius R, heights falling from hCentre to a quarter at R.
std::vector<TrueTip> lattice(double R, double hCentre) {
    std::vector<TrueTip> tips;
    for (int i = -10; i <= 10; ++i)
        for (int j = -10; j <= 10; ++j) {
            const double x = kSpacing * (i + 0.5 * j), y = kSpacing * (std::sqrt(3.0) / 2 * j);
            const double r = std::hypot(x, y);
            if (r <= R) tips.push_back({x, y, hCentre * (1 - 0.75 * r / R)});
        }
    return tips;
}

/// The flat pool (depth 5 mm, radius 30 mm) with a smooth bump cos^2 of half-width 0.45 l
/// under every tip.
TriangleMesh spiky(const std::vector<TrueTip>& tips) {
    return spiketest::makePool(0.03, 120, [&](double r, double a) {
        const double x = r * std::cos(a), y = r * std::sin(a);
        double z = 0.005;
        for (const TrueTip& t : tips) {
            const double d = std::hypot(x - t.x, y - t.y) / (0.45 * kSpacing);
            if (d < 1) z += t.h * std::pow(std::cos(0.5 * M_PI * d), 2);
        }
        return z;
    });
}

SpikeTipSample sample(double x, double y, double h) { return {Vec3d(x, y, 0.005 + h), h}; }

} // namespace

TEST_CASE("findTips finds every bump of a pool at its place and height, and nothing on a flat pool", "[tips]") {
    const TriangleMesh surface = spiketest::makeFlatPool(0.03, 0.005, 120);
    REQUIRE(findTips(surface, surface).empty());

    const std::vector<TrueTip> truth = lattice(0.02, 3e-3);
    const std::vector<SpikeTipSample> found = findTips(spiky(truth), surface);
    REQUIRE(found.size() == truth.size());
    // The mesh has a vertex every 0.25 mm: a tip is found at the vertex nearest its apex.
    for (const TrueTip& t : truth) {
        double best = 1e9, h = 0;
        for (const SpikeTipSample& f : found) {
            const double d = std::hypot(f.position.x() - t.x, f.position.y() - t.y);
            if (d < best) best = d, h = f.height;
        }
        REQUIRE(best < 0.25e-3);
        REQUIRE(h == Approx(t.h).epsilon(0.02));
    }
    REQUIRE(medianTipSpacing(found) == Approx(kSpacing).epsilon(0.05));
}

TEST_CASE("findTips finds a leaning spike's foot where its axis meets the surface, not under its apex", "[tips][flow]") {
    // Bumps leaning along +x: the level at height b of a bump of height h is the disc of
    // radius 0.45 l (cos^2 profile) centred lambda b to the side, so its axis has slope
    // 1 / lambda and its apex stands lambda h off its foot (0.8 mm).
    const double lambda = 0.4, w = 0.45 * kSpacing;
    const std::vector<TrueTip> truth = lattice(0.012, 2e-3);
    const TriangleMesh surface = spiketest::makeFlatPool(0.03, 0.005, 120);
    const TriangleMesh leaning = spiketest::makePool(0.03, 120, [&](double r, double a) {
        const double x = r * std::cos(a), y = r * std::sin(a);
        double z = 0.005;
        for (const TrueTip& t : truth) {
            if (std::hypot(x - t.x, y - t.y) > w + lambda * t.h) continue;
            // b = h cos^2(pi/2 d(b) / w), d(b) = |(x - t.x - lambda b, y - t.y)|: increasing
            // in b minus the right-hand side, bisected.
            auto excess = [&](double b) {
                const double d = std::hypot(x - t.x - lambda * b, y - t.y) / w;
                return b - (d < 1 ? t.h * std::pow(std::cos(0.5 * M_PI * d), 2) : 0.0);
            };
            double lo = 0, hi = t.h;
            if (excess(lo) >= 0) continue;
            for (int k = 0; k < 60; ++k) (excess(0.5 * (lo + hi)) < 0 ? lo : hi) = 0.5 * (lo + hi);
            z += 0.5 * (lo + hi);
        }
        return z;
    });
    const std::vector<SpikeTipSample> found = findTips(leaning, surface);
    REQUIRE(found.size() == truth.size());
    for (const TrueTip& t : truth) {
        const SpikeTipSample* f = nullptr;
        for (const SpikeTipSample& s : found)
            if (!f || std::hypot(s.position.x() - t.x - lambda * t.h, s.position.y() - t.y) <
                          std::hypot(f->position.x() - t.x - lambda * t.h, f->position.y() - t.y))
                f = &s;
        INFO("tip at (" << t.x * 1e3 << ", " << t.y * 1e3 << ") mm, " << t.h * 1e3 << " mm tall");
        REQUIRE(f->hasBase);
        // The apex stands lambda h to the side (within the mesh's 0.25 mm vertex spacing)...
        REQUIRE(std::abs(f->position.x() - t.x - lambda * t.h) < 0.25e-3);
        // ...the foot is where the bump stands on the surface.
        CHECK(std::hypot(f->base.x() - t.x, f->base.y() - t.y) < 0.1e-3);
        CHECK(f->base.z() == Approx(0.005).margin(1e-6));
    }
}

TEST_CASE("matchTips counts matches, moves, births and deaths of known tip sets", "[tips]") {
    // Frame a: a row of five tips 5 mm apart, the last one small (the fading edge).
    const std::vector<SpikeTipSample> a = {sample(0, 0, 3e-3), sample(0.005, 0, 3e-3), sample(0.010, 0, 2e-3),
                                           sample(0.015, 0, 2e-3), sample(0.020, 0, 0.5e-3)};
    SECTION("all tips kept, shifted by 0.2 mm and 1 mm") {
        std::vector<SpikeTipSample> b = a;
        for (size_t i = 0; i < b.size(); ++i) b[i].position.y() += i < 3 ? 0.2e-3 : 1e-3;
        const TipFrameMatch m = matchTips(a, b);
        REQUIRE(m.matched == 5);
        REQUIRE(m.born + m.died == 0);
        REQUIRE(m.spacing == Approx(0.005));
        REQUIRE(m.medianMove == Approx(0.2e-3).margin(1e-9));
        REQUIRE(m.maxMove == Approx(1e-3).margin(1e-9));
        REQUIRE(m.stableFraction == Approx(3.0 / 5));          // 0.2 mm < 0.1 l = 0.5 mm < 1 mm
        REQUIRE(m.interiorStableFraction == Approx(3.0 / 4));  // the 0.5 mm tip is edge (< 0.25 x 3 mm)
        REQUIRE(m.maxHeightJump == 0);
    }
    SECTION("the small edge tip vanishes, a tall one appears inside, one grows") {
        std::vector<SpikeTipSample> b(a.begin(), a.end() - 1);
        b[1].height = 3.6e-3;
        b[1].position.z() += 0.6e-3;
        b.push_back(sample(0.0025, 0.004, 2.4e-3));
        const TipFrameMatch m = matchTips(a, b);
        REQUIRE(m.matched == 4);
        REQUIRE(m.died == 1);
        REQUIRE(m.interiorDied == 0);
        REQUIRE(m.born == 1);
        REQUIRE(m.interiorBorn == 1);
        REQUIRE(m.largestTip == Approx(3.6e-3));
        // The newcomer jumped from 0 to 2.4 mm: 2.4 / 3.6 of the largest tip.
        REQUIRE(m.maxHeightJump == Approx(2.4 / 3.6));
        // Of the interior tips (a's four tall ones, the newcomer), the grown tip moved 0.6 mm.
        REQUIRE(m.interiorStableFraction == Approx(3.0 / 5));
    }
    SECTION("a tip further than half a spacing is a death and a birth, not a move") {
        std::vector<SpikeTipSample> b = a;
        b[0].position.y() += 3e-3;
        const TipFrameMatch m = matchTips(a, b);
        REQUIRE(m.matched == 4);
        REQUIRE(m.born == 1);
        REQUIRE(m.died == 1);
    }
    SECTION("no tips in either frame") {
        const TipFrameMatch m = matchTips({}, {});
        REQUIRE(m.stableFraction == 1);
        REQUIRE(m.matched == 0);
    }
}

TEST_CASE("matchTips follows a contracting or sliding lattice and still catches a tip that jumps", "[tips]") {
    // A hexagonal patch of 8 rings (217 tips) 3 mm apart, all 3 mm tall.
    const double l = 3e-3;
    std::vector<SpikeTipSample> a;
    for (int i = -8; i <= 8; ++i)
        for (int j = -8; j <= 8; ++j)
            if (std::abs(i) <= 8 && std::abs(j) <= 8 && std::abs(i + j) <= 8)
                a.push_back(sample(l * (i + 0.5 * j), l * std::sqrt(0.75) * j, 3e-3));
    REQUIRE(a.size() == 217);
    SECTION("contracting by 8 % about the centre: the outer rings move up to 0.64 spacing, all matched") {
        std::vector<SpikeTipSample> b = a;
        for (auto& t : b) t.position.head<2>() *= 0.92;
        const TipFrameMatch raw = matchTips(a, b, 0.5, 0.25, false);
        REQUIRE(raw.born > 0);   // without prediction the outer rings are deaths and births
        const TipFrameMatch m = matchTips(a, b);
        REQUIRE(m.matched == 217);
        REQUIRE(m.born + m.died == 0);
        REQUIRE(m.maxMove == Approx(0.08 * 8 * l).epsilon(1e-6));
        REQUIRE(m.maxResidual < 1e-9);
        REQUIRE(m.maxHeightJump == 0);
    }
    SECTION("sliding by 0.2 spacing while contracting by 5 %: the outer rings move up to 0.6 spacing, all matched") {
        std::vector<SpikeTipSample> b = a;
        for (auto& t : b) {
            t.position.head<2>() *= 0.95;
            t.position.x() += 0.2 * l;
        }
        const TipFrameMatch m = matchTips(a, b);
        REQUIRE(m.matched == 217);
        REQUIRE(m.born + m.died == 0);
    }
    SECTION("one tip jumps 0.6 spacing while its neighbours stay: a death and a birth") {
        std::vector<SpikeTipSample> b = a;
        b[100].position.x() += 0.6 * l;
        const TipFrameMatch m = matchTips(a, b);
        REQUIRE(m.matched == 216);
        REQUIRE(m.born == 1);
        REQUIRE(m.died == 1);
    }
}

TEST_CASE("matchTips compares each tip's move with the surface velocity under it: 0 riding the flow, 1 standing still or moving twice as fast",
          "[tips][flow]") {
    // Tips 5 mm apart, the surface under them sliding at u (and heaving along the normal,
    // which does not count); frame b 1/30 s later.
    const double dt = 1.0 / 30;
    const Vec3d u(0.012, -0.005, 0.0), heave(0, 0, 0.02);
    std::vector<SpikeTipSample> a;
    for (const TrueTip& t : lattice(0.02, 2e-3)) {
        SpikeTipSample s;
        s.position = Vec3d(t.x, t.y, 0.005 + t.h);
        s.height = t.h;
        s.surfaceVelocity = u + heave;
        s.hasVelocity = true;
        a.push_back(s);
    }
    auto moved = [&](double factor) {
        std::vector<SpikeTipSample> b = a;
        for (auto& s : b) s.position += factor * u * dt;
        return b;
    };
    const TipFrameMatch riding = matchTips(a, moved(1.0), 0.5, 0.25, true, dt);
    REQUIRE(riding.flowTips == riding.matched);
    REQUIRE(riding.flowTips > 40);
    REQUIRE(riding.flowMismatch < 1e-9);
    REQUIRE(riding.surfaceSpeed == Approx(u.norm()).epsilon(1e-9));
    REQUIRE(riding.tipSpeed == Approx(u.norm()).epsilon(1e-9));
    REQUIRE(matchTips(a, moved(0.0), 0.5, 0.25, true, dt).flowMismatch == Approx(1.0).epsilon(1e-9));
    REQUIRE(matchTips(a, moved(2.0), 0.5, 0.25, true, dt).flowMismatch == Approx(1.0).epsilon(1e-9));
    REQUIRE(matchTips(a, moved(0.9), 0.5, 0.25, true, dt).flowMismatch == Approx(0.1).epsilon(1e-6));
    REQUIRE(matchTips(a, moved(0.9), 0.5, 0.25, true, dt).flowDifference == Approx(0.1 * u.norm()).epsilon(1e-6));
    // Tips that move on a surface that stands still do not ride it: an infinite mismatch.
    std::vector<SpikeTipSample> stillSurface = a;
    for (auto& s : stillSurface) s.surfaceVelocity = heave;
    std::vector<SpikeTipSample> shifted = stillSurface;
    for (auto& s : shifted) s.position += u * dt;
    REQUIRE(std::isinf(matchTips(stillSurface, shifted, 0.5, 0.25, true, dt).flowMismatch));
    // With their feet known, the feet's move is compared: spikes whose apexes swing by a
    // third of a spacing (a lean that changes) while their feet ride the flow ride it.
    std::vector<SpikeTipSample> footed = a;
    for (auto& s : footed) s.base = s.position - Vec3d(0, 0, s.height), s.hasBase = true;
    std::vector<SpikeTipSample> swung = footed;
    for (auto& s : swung) s.base += u * dt, s.position += u * dt + Vec3d(0.3 * kSpacing, 0, 0);
    const TipFrameMatch feet = matchTips(footed, swung, 0.5, 0.25, true, dt);
    REQUIRE(feet.flowTips > 40);
    REQUIRE(feet.flowMismatch < 1e-9);
    // Without an interval, or without velocities, nothing is compared.
    REQUIRE(matchTips(a, moved(1.0)).flowTips == 0);
    std::vector<SpikeTipSample> still = a;
    for (auto& s : still) s.hasVelocity = false;
    REQUIRE(matchTips(still, moved(1.0), 0.5, 0.25, true, dt).flowTips == 0);
}

// spikes.height_curve = "bifurcation": the hexagons' subcritical amplitude equation
// (SpikeBifurcation) against its stationary solutions, and a flat layer whose field is swept
// up and down: spikes appear at M_c with a jump and persist down to the lower threshold.
#include "SpikeTestMeshes.hpp"

#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/LangevinLaw.hpp"
#include "spikes/SpikeFrames.hpp"
#include "spikes/SpikeLattice.hpp"
#include "spikes/SpikePhysics.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

using namespace ferro;

TEST_CASE("the bifurcation's upper branch solves the stationary amplitude equation and is stable, with its thresholds and jump",
          "[spikes][physics][bifurcation]")
{
    for (double s : {1.0, 0.97, 0.9, 0.75})
        for (double full : {0.1, 0.25, 0.5}) {
            const SpikeBifurcation b = SpikeBifurcation::fromThresholds(s, full);
            INFO("M_s/M_c " << s << ", eps_full " << full);
            // The lower threshold is where the two nonzero stationary solutions meet.
            REQUIRE(b.lower == Approx(-b.gamma * b.gamma / (4 * b.g)).margin(1e-15));
            REQUIRE(b.lower == Approx(s - 1).margin(1e-15));
            REQUIRE(b.upperBranch(full) == Approx(1.0).epsilon(1e-12));
            REQUIRE(b.upperBranch(b.lower - 1e-9) == 0.0);
            for (double eps = b.lower; eps <= 1.0; eps += 0.01) {
                const double a = b.upperBranch(eps);
                // eps a + gamma a^2 - g a^3 = 0, and d/da of it < 0 (stable), except at the
                // fold eps_s where it is 0.
                REQUIRE(std::abs(eps * a + b.gamma * a * a - b.g * a * a * a) < 1e-12);
                if (eps > b.lower + 1e-6) REQUIRE(eps + 2 * b.gamma * a - 3 * b.g * a * a < 0);
            }
            // The jump at onset gamma / g (0 without hysteresis), half of it at the fold.
            REQUIRE(b.upperBranch(0) == Approx(b.gamma / b.g).margin(1e-15));
            REQUIRE(b.upperBranch(b.lower) == Approx(b.gamma / (2 * b.g)).margin(1e-7));
            if (s == 1.0) REQUIRE(b.upperBranch(0.3 * full) == Approx(std::sqrt(0.3)).epsilon(1e-12));
        }
}

namespace {

constexpr double kR = 0.03, kDepth = 0.01;

// A flat dish in a uniform vertical field swept from 0.8 H_c up to 1.3 H_c over 1 s and back
// over the next second (monotone cubic keys), with `spikes` in [spikes]. A growth time of
// 1 ms: the spikes follow the sweep (2.6 A/m a millisecond at most) quasi-statically, and
// sink within 4 ms (about 10 A/m) once the field leaves their branch.
SpikeScene sweepScene(double Hc, const std::string& spikes)
{
    std::ostringstream s;
    s << "[[magnets]]\nkind = \"uniform\"\ndirection = [0.0, 0.0, 1.0]\nfield = " << 0.8 * Hc << "\n"
      << "[[magnets.keys]]\ntime = 0.0\nfield = " << 0.8 * Hc << "\n"
      << "[[magnets.keys]]\ntime = 1.0\nfield = " << 1.3 * Hc << "\n"
      << "[[magnets.keys]]\ntime = 2.0\nfield = " << 0.8 * Hc << "\n"
      << "[spikes]\nalpha = 30.0\ngrowth_time = 0.001\n" << spikes;
    return parseSpikeScene(SceneDocument::parse(spiketest::dishScene(kR, s.str()), "sweep.toml"));
}

// ferro-spikes' frame at time t (the flat pool's `time` header), through the files as the
// stage reads them: the magnets and their past from the scene's tracks.
SpikeResult sweepFrame(const SpikeScene& sc, double t)
{
    static const ferro::test::TempDir dir("spike-sweep");
    TriangleMesh pool = spiketest::makeFlatPool(kR, kDepth, 16);
    setComment(pool, "time", formatNumber(t));
    writeMesh(dir.file("pool.ply"), pool);
    return spikeFrame(sc, dir.file("pool.ply"), "", dir.file("spiky.ply"));
}

// The field H [A/m] at which the fluid's law gives |M| = M.
double fieldFor(double M, const MagnetizationParams& law)
{
    double lo = 0, hi = 1e7;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (langevinMagnetization(mid, law.susceptibility, law.saturation) < M ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// The time in [a, b] where spikes appear (rising = true: none before, some after) or vanish.
double switchTime(const SpikeScene& sc, double a, double b, bool appear)
{
    for (int i = 0; i < 11; ++i) {
        const double mid = 0.5 * (a + b);
        const bool tips = !sweepFrame(sc, mid).tips.empty();
        ((tips == appear) ? b : a) = mid;
    }
    return 0.5 * (a + b);
}

} // namespace

TEST_CASE("height_curve = bifurcation: a swept field raises spikes at M_c with a jump, and they persist down to the lower threshold",
          "[spikes][bifurcation][slow]")
{
    const SpikeScene probe = sweepScene(10000, "");
    const MagnetizationParams& law = probe.fluid.law;
    const CriticalMagnetization crit = criticalMagnetization(probe.fluid.density - probe.params.ambientDensity,
                                                             probe.fluid.gravity.norm(), probe.fluid.surfaceTension, law);
    const double Hc = fieldFor(crit.magnetization, law);
    const double s = 0.9;
    const SpikeScene sc = sweepScene(Hc, "height_curve = \"bifurcation\"\nlower_threshold = 0.9\n");
    const SpikeScene fade = sweepScene(Hc, "");
    auto field = [&](double t) { return sc.magnets[0].at(t).strength; };
    const double Hs = fieldFor(s * crit.magnetization, law);
    INFO("H_c " << Hc << " A/m, H_s " << Hs << " A/m");

    // Onset on the way up, collapse on the way down, against the analytic fields.
    const double up = switchTime(sc, 0.0, 1.0, true), down = switchTime(sc, 1.0, 2.0, false);
    INFO("spikes appear at " << field(up) << " A/m, vanish at " << field(down) << " A/m");
    REQUIRE(std::abs(field(up) / Hc - 1) < 0.005);
    REQUIRE(std::abs(field(down) / Hs - 1) < 0.005);
    // The fade curve has no hysteresis: its spikes vanish where they appeared.
    const double fadeDown = switchTime(fade, 1.0, 2.0, false);
    REQUIRE(std::abs(field(fadeDown) / Hc - 1) < 0.01);

    // Heights on the branch: tip height / (3 C0) against a*(eps), on the way up and down. The
    // surface's gate takes the spikes down over 0.05 M_c above M_s (smoothstep), so they sink
    // smoothly in space at a pattern's edge: there the branch times that ramp.
    const SpikeBifurcation b = SpikeBifurcation::fromThresholds(s, sc.params.magnetizationFade);
    const SpikeParams P = spikeParamsAt(sc.params, 0);
    int checked = 0;
    for (double t : {up + 0.1, up + 0.2, 1.0, down - 0.2, down - 0.1, down - 0.05}) {
        const SpikeResult r = sweepFrame(sc, t);
        REQUIRE_FALSE(r.tips.empty());
        const double H = field(t);
        const double eps = langevinMagnetization(H, law.susceptibility, law.saturation) / crit.magnetization - 1;
        const double ramp = std::clamp((eps - b.lower) / 0.05, 0.0, 1.0);
        const double expected = std::min(1.0, b.upperBranch(eps)) * ramp * ramp * (3 - 2 * ramp);
        const double measured = r.maxHeight / (3 * spikeAmplitude(P, H, r.patterns.at(0).spacing));
        INFO("t " << t << " s, eps " << eps << ": a " << measured << ", branch " << expected);
        CHECK(std::abs(measured - expected) < 0.05 * expected);
        ++checked;
    }
    REQUIRE(checked == 6);
    // Between the thresholds the answer depends on the way there: none on the way up, the
    // branch's spikes on the way down.
    REQUIRE(field(up - 0.05) < Hc);
    REQUIRE(field(up - 0.05) > Hs);
    REQUIRE(sweepFrame(sc, up - 0.05).tips.empty());
    REQUIRE(field(down - 0.01) < Hc);
    REQUIRE_FALSE(sweepFrame(sc, down - 0.01).tips.empty());
}

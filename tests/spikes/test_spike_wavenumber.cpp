// spikes.spacing = "growth": the wavenumber of fastest growth of a deep layer's surface in a
// normal field (linear stability theory), against its closed forms in the inviscid and the
// very viscous limits, and the pattern a flat pool gets from it.
#include "SpikeTestMeshes.hpp"

#include "sim/core/SceneDocument.hpp"
#include "spikes/SpikeFrames.hpp"
#include "spikes/SpikePhysics.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using namespace ferro;
using spiketest::dishScene;
using spiketest::frameInput;
using spiketest::makeFlatPool;
using spiketest::uniformField;

namespace {

constexpr double kDepth = 0.01;

SurfaceModes labFluid(double supercriticality, double viscosity)
{
    SurfaceModes m;
    m.density = 1200;
    m.deltaRho = 1200;
    m.gravity = 9.81;
    m.surfaceTension = 0.025;
    m.viscosity = viscosity;
    m.supercriticality = supercriticality;
    return m;
}

double criticalWavenumber(const SurfaceModes& m) { return std::sqrt(m.deltaRho * m.gravity / m.surfaceTension); }

} // namespace

TEST_CASE("fastest growth without viscosity: the closed form k_c (2 m + sqrt(4 m^2 - 3)) / 3", "[spikes][physics][wavenumber]")
{
    for (double q : {1.001, 1.05, 1.2, 1.5, 2.0, 4.0}) {
        const SurfaceModes m = labFluid(q, 0.0);
        const double kc = criticalWavenumber(m);
        INFO("(M/M_c)^2 = " << q);
        // d/dk (C k^2 - delta_rho g k - sigma k^3) = 0 with C = 2 sigma k_c q.
        REQUIRE(fastestGrowingWavenumber(m) == Approx(kc * (2 * q + std::sqrt(4 * q * q - 3)) / 3).epsilon(1e-7));
        // The rate itself: sqrt(-w0^2).
        const double k = 1.3 * kc;
        const double w02 = (m.deltaRho * m.gravity * k + m.surfaceTension * k * k * k -
                            2 * std::sqrt(m.gravity * m.deltaRho * m.surfaceTension) * q * k * k) / m.density;
        REQUIRE(growthRate(m, k) == Approx(w02 < 0 ? std::sqrt(-w02) : 0.0).margin(1e-12));
    }
}

TEST_CASE("fastest growth of a very viscous layer: k_c at every field, the Stokes rate", "[spikes][physics][wavenumber]")
{
    // nu -> infinity: s = (C - delta_rho g / k - sigma k) / (2 rho nu), largest at k_c for
    // every field; at nu = 1 m^2/s (tar) the layer is there to 1e-3.
    for (double q : {1.2, 2.0, 4.0}) {
        const SurfaceModes m = labFluid(q, 1.0);
        const double kc = criticalWavenumber(m);
        INFO("(M/M_c)^2 = " << q);
        REQUIRE(fastestGrowingWavenumber(m) == Approx(kc).epsilon(1e-3));
        const double C = 2 * std::sqrt(m.gravity * m.deltaRho * m.surfaceTension) * q;
        const double stokes = (C - m.deltaRho * m.gravity / kc - m.surfaceTension * kc) / (2 * m.density * m.viscosity);
        REQUIRE(growthRate(m, kc) == Approx(stokes).epsilon(1e-3));
    }
}

TEST_CASE("fastest growth at the example fluid's viscosity, against an independent computation",
          "[spikes][physics][wavenumber]")
{
    // References from scripts/bench/field_jump.py, a separate Python implementation of the same
    // dispersion relation (its own root bracketing and a ternary search for the maximum), for
    // examples/annotated.toml's fluid (1200 kg/m^3, 0.025 N/m, nu = 5e-6 m^2/s).
    const struct {
        double ratio, kOverKc, rate;
    } refs[] = {{1.1, 1.323111, 57.192}, {1.2, 1.652530, 97.161}, {1.5, 2.717503, 239.019}};
    for (const auto& r : refs) {
        const SurfaceModes m = labFluid(r.ratio * r.ratio, 5e-6);
        const double k = fastestGrowingWavenumber(m);
        INFO("M/M_c = " << r.ratio);
        REQUIRE(k / criticalWavenumber(m) == Approx(r.kOverKc).epsilon(1e-5));
        REQUIRE(growthRate(m, k) == Approx(r.rate).epsilon(1e-4));
    }
    // Far past the Stokes regime the root stays accurate (the form without cancellation).
    for (double nu : {1e2, 1e3, 1e4}) {
        const SurfaceModes m = labFluid(4.0, nu);
        REQUIRE(fastestGrowingWavenumber(m) == Approx(criticalWavenumber(m)).epsilon(1e-4));
        REQUIRE(growthRate(m, criticalWavenumber(m)) > 0);
    }
}

TEST_CASE("fastest growth between the limits: slower and longer with viscosity, shorter with the field",
          "[spikes][physics][wavenumber]")
{
    for (double q : {1.1, 1.5, 3.0}) {
        double previousK = 1e30, previousRate = 1e30;
        for (double nu : {0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2}) {
            const SurfaceModes m = labFluid(q, nu);
            const double k = fastestGrowingWavenumber(m);
            const double rate = growthRate(m, k);
            INFO("(M/M_c)^2 = " << q << ", nu = " << nu << ": k / k_c = " << k / criticalWavenumber(m));
            REQUIRE(k < previousK);
            REQUIRE(k > criticalWavenumber(m));
            REQUIRE(rate < previousRate);
            REQUIRE(rate > 0);
            // A maximum: both neighbours grow slower.
            REQUIRE(growthRate(m, 0.97 * k) < rate);
            REQUIRE(growthRate(m, 1.03 * k) < rate);
            previousK = k, previousRate = rate;
        }
    }
    for (double nu : {0.0, 1e-5, 1e-3}) {
        double previous = 0;
        for (double q : {1.0, 1.05, 1.2, 1.5, 2.0}) {
            const double k = fastestGrowingWavenumber(labFluid(q, nu));
            REQUIRE(k >= previous);
            previous = k;
        }
    }
    // At and below M_c: the critical wavenumber, no growth; stable modes do not grow.
    REQUIRE(fastestGrowingWavenumber(labFluid(0.8, 1e-5)) == Approx(criticalWavenumber(labFluid(1, 0))));
    REQUIRE(fastestGrowingWavenumber(labFluid(1.0, 0)) == Approx(criticalWavenumber(labFluid(1, 0))));
    REQUIRE(growthRate(labFluid(1.0, 1e-5), criticalWavenumber(labFluid(1, 0))) == Approx(0).margin(1e-6));
    REQUIRE(growthRate(labFluid(1.2, 1e-5), 10 * criticalWavenumber(labFluid(1, 0))) == 0.0);
    SurfaceModes weightless = labFluid(1.5, 1e-5);
    weightless.gravity = 0;
    REQUIRE(fastestGrowingWavenumber(weightless) == 0.0);
}

TEST_CASE("spacing = \"growth\": a flat pool's tips stand at the fastest-growing wavenumber's distance",
          "[spikes][pool][wavenumber][slow]")
{
    const double R = 0.03;
    for (double H0 : {12000.0, 15000.0}) {
        const SpikeScene sc = parseSpikeScene(SceneDocument::parse(
            dishScene(R, uniformField(H0) + "[spikes]\nspacing = \"growth\"\nmin_spacing = 0.001\n"), "test.toml"));
        REQUIRE(sc.params.spacing == SpikeParams::Spacing::Growth);
        REQUIRE(sc.fluid.viscosity == 5e-6);   // the scene's fluid.viscosity reaches the spikes
        const SpikeResult res = addSpikes(frameInput(sc, makeFlatPool(R, kDepth, 20)), sc.params);
        REQUIRE(res.patterns.size() == 1);
        const SpikePattern& pat = res.patterns[0];
        SurfaceModes m;
        m.density = sc.fluid.density;
        m.deltaRho = sc.fluid.density - sc.params.ambientDensity;
        m.gravity = sc.fluid.gravity.norm();
        m.surfaceTension = sc.fluid.surfaceTension;
        m.viscosity = sc.fluid.viscosity;
        const double q = std::pow(pat.magnetization / res.critical.magnetization, 2);
        m.supercriticality = q;
        INFO("H0 " << H0 << ", (M/M_c)^2 " << q << ", spacing " << pat.spacing);
        REQUIRE(q > 1);
        REQUIRE(pat.spacing == Approx(tipSpacingForWavenumber(fastestGrowingWavenumber(m))).epsilon(1e-9));
        // Closer than the critical wavelength's tips, as the field is above critical.
        const double lambda = criticalWavelength(m.deltaRho, m.gravity, m.surfaceTension);
        REQUIRE(pat.spacing < 2 / std::sqrt(3.0) * lambda);
        // The tips are where the spacing says: nearest neighbours of the origin's tip.
        double nearest = 1e9;
        const SpikeTip* centre = nullptr;
        for (const SpikeTip& t : res.tips)
            if (t.i == 0 && t.j == 0) centre = &t;
        REQUIRE(centre != nullptr);
        for (const SpikeTip& t : res.tips)
            if (&t != centre) nearest = std::min(nearest, (t.base - centre->base).norm());
        REQUIRE(nearest == Approx(pat.spacing).epsilon(0.05));
    }
}

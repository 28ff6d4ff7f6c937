// DemagnetizationCurve: the body force's magnetization as a function of the applied field's
// strength, fitted to per-particle magnetizations.
#include "sim/magnetics/DemagnetizationCurve.hpp"
#include "sim/magnetics/MagnetizationSolver.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <vector>

using namespace ferro;

namespace {

/// 401 field strengths log-spaced over [lo, hi] with the particles' M at r = 1 (the plain
/// Langevin law) and surface samples whose pressure is `pressure(h)` plus a constant `offset`:
/// volume data that disagrees with the surface, for the fits that must follow the surface.
template <class Pressure>
std::tuple<std::vector<double>, std::vector<double>, std::vector<DemagnetizationCurve::SurfaceSample>>
disagreeingSamples(double lo, double hi, double chi0, double Ms, const Pressure& pressure, double offset = 1234.5) {
    std::vector<double> h, m;
    std::vector<DemagnetizationCurve::SurfaceSample> surface;
    for (int i = 0; i <= 400; ++i) {
        const double v = lo * std::pow(hi / lo, i / 400.0);
        h.push_back(v);
        m.push_back(langevinMagnetization(v, chi0, Ms));   // r = 1 in the volume
        surface.push_back({v, pressure(v) + offset, 1.0});
    }
    return {h, m, surface};
}

/// The reference potential of a ratio r: integral_0^h r(clamp(h', lo, hi)) M_law(h') dh' by
/// Simpson's rule in log h above 1 A/m, independent of the curve's own tables.
template <class Ratio>
double ratioPotential(const Ratio& r, double h, double lo, double hi, double chi0, double Ms) {
    const int steps = 20000;
    const double a = 0.0, b = std::log(h), dt = (b - a) / steps;
    auto f = [&](double t) {
        const double v = std::exp(t);
        return r(std::clamp(v, lo, hi)) * langevinMagnetization(v, chi0, Ms) * v;
    };
    double sum = f(a) + f(b);
    for (int i = 1; i < steps; ++i) sum += (i % 2 ? 4 : 2) * f(a + i * dt);
    return sum * dt / 3;
}

} // namespace

TEST_CASE("a demagnetization ratio that is a function of h is recovered exactly", "[magnetics][demagnetization]") {
    // r(h) linear in log h between 1 kA/m (0.4) and 100 kA/m (0.9): the curve's own shape.
    const double chi0 = 1.5, Ms = 35000, lo = 1e3, hi = 1e5;
    auto truth = [&](double h) { return 0.4 + 0.5 * std::log(h / lo) / std::log(hi / lo); };
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<double> h, m;
    h.push_back(lo);
    h.push_back(hi);
    for (int i = 0; i < 5000; ++i) h.push_back(lo * std::pow(hi / lo, u(rng)));
    for (double v : h) m.push_back(truth(v) * langevinMagnetization(v, chi0, Ms));
    DemagnetizationCurve curve(chi0, Ms);
    REQUIRE(!curve.fitted());
    REQUIRE(curve.ratio(5e3) == 1.0);
    curve.fit(h, m);
    REQUIRE(curve.fitted());
    for (double v : {1e3, 2.2e3, 1e4, 3.7e4, 1e5}) {
        CAPTURE(v);
        REQUIRE(curve.ratio(v) == Approx(truth(v)).epsilon(1e-6));
        REQUIRE(curve.magnetization(v) == Approx(truth(v) * langevinMagnetization(v, chi0, Ms)).epsilon(1e-6));
    }
    REQUIRE(curve.residual() < 1e-6);
    // Beyond the fitted range the ratio is held, not extrapolated.
    REQUIRE(curve.ratio(10.0) == Approx(0.4).epsilon(1e-6));
    REQUIRE(curve.ratio(1e7) == Approx(0.9).epsilon(1e-6));
}

TEST_CASE("scatter between particles at equal h is averaged out and reported as the residual", "[magnetics][demagnetization]") {
    // Every particle at r = 0.6 +- 0.1 (uniform): the least-squares ratio is 0.6 and the
    // residual the scatter's RMS over the RMS magnetization, (0.1 / sqrt(3)) / 0.6 ~ 9.6 %.
    const double chi0 = 0.5, Ms = 0;   // linear
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<double> h, m;
    for (int i = 0; i < 20000; ++i) {
        h.push_back(2e3 + 8e3 * u(rng));
        m.push_back((0.5 + 0.2 * u(rng)) * chi0 * h.back());
    }
    DemagnetizationCurve curve(chi0, Ms, 8);
    curve.fit(h, m);
    for (double v : {2e3, 4e3, 7e3, 1e4}) REQUIRE(curve.ratio(v) == Approx(0.6).margin(0.01));
    REQUIRE(curve.residual() == Approx(0.1 / std::sqrt(3.0) / 0.6).epsilon(0.05));
}

TEST_CASE("a uniform field, nodes without particles and unusable input", "[magnetics][demagnetization]") {
    const double chi0 = 1.5, Ms = 35000;
    DemagnetizationCurve curve(chi0, Ms);
    // One strength everywhere (a uniform magnet): one ratio.
    curve.fit({2e4, 2e4, 2e4}, {0.5 * langevinMagnetization(2e4, chi0, Ms), 0.5 * langevinMagnetization(2e4, chi0, Ms),
                                0.5 * langevinMagnetization(2e4, chi0, Ms)});
    REQUIRE(curve.ratio(2e4) == Approx(0.5).epsilon(1e-6));
    REQUIRE(std::isfinite(curve.ratio(1e9)));
    // Particles only at the two ends of the range: the nodes between are linear in log h.
    curve.fit({1e3, 1e3, 1e5, 1e5}, {0.2 * langevinMagnetization(1e3, chi0, Ms), 0.2 * langevinMagnetization(1e3, chi0, Ms),
                                     0.8 * langevinMagnetization(1e5, chi0, Ms), 0.8 * langevinMagnetization(1e5, chi0, Ms)});
    REQUIRE(curve.ratio(1e4) == Approx(0.5).epsilon(1e-6));
    // Zero fields and NaN are ignored; nothing usable leaves the ratio at 1.
    curve.fit({0.0, std::nan(""), 1e4}, {1.0, 1.0, std::nan("")});
    REQUIRE(curve.ratio(1e4) == 1.0);
    REQUIRE(curve.residual() == 0.0);
}

TEST_CASE("surface samples make the force's potential the surface pressure up to a constant", "[magnetics][demagnetization]") {
    // Surface pressures from a known ratio r_s(h) (0.3 .. 0.7 in log h) and a constant offset;
    // volume data that says otherwise (r = 1), at the tenth of the weight the fit gives it.
    // Over the surface's range of h the fitted potential follows the surface,
    // G(h2) - G(h1) = P(h2) - P(h1), within 6 % of its range (the volume rows' pull).
    const double chi0 = 1.5, Ms = 35000, lo = 2e3, hi = 5e4;
    auto rs = [&](double h) { return 0.3 + 0.4 * std::log(h / lo) / std::log(hi / lo); };
    DemagnetizationCurve exact(chi0, Ms);
    {   // the potential of r_s itself, as the reference
        std::vector<double> h, m;
        for (int i = 0; i <= 2000; ++i) {
            h.push_back(lo * std::pow(hi / lo, i / 2000.0));
            m.push_back(rs(h.back()) * langevinMagnetization(h.back(), chi0, Ms));
        }
        exact.fit(h, m);
    }
    const auto [h, m, surface] = disagreeingSamples(lo, hi, chi0, Ms, [&](double v) { return exact.potential(v); });
    DemagnetizationCurve curve(chi0, Ms);
    curve.fit(h, m, surface);
    const double range = exact.potential(hi) - exact.potential(lo);
    for (double v : {3e3, 8e3, 2e4, 5e4}) {
        CAPTURE(v);
        REQUIRE(curve.potential(v) - curve.potential(lo) == Approx(exact.potential(v) - exact.potential(lo)).margin(0.1 * range));
    }
    // The surface rows decide: the volume rows alone give r = 1 and another potential.
    DemagnetizationCurve volumeOnly(chi0, Ms);
    volumeOnly.fit(h, m);
    REQUIRE(std::abs((volumeOnly.potential(hi) - volumeOnly.potential(lo)) - range) > 0.5 * range);
    // potential() is the integral of magnetization(): a central difference of G is M_f.
    for (double v : {4e3, 3e4}) REQUIRE((curve.potential(v * 1.001) - curve.potential(v / 1.001)) / (v * 1.001 - v / 1.001) ==
                                        Approx(curve.magnetization(v)).epsilon(1e-2));
}

TEST_CASE("the free-surface fit: the force's potential is the samples' pressure up to a constant", "[magnetics][demagnetization]") {
    // Surface pressures from a known ratio r_s(h), quadratic in log h (0.3 at lo, 0.75 at hi,
    // bowed), plus a constant offset; the reference potential integral r_s M_law dh by
    // Simpson's rule here, independent of the curve's tables. Volume data that says otherwise
    // (r = 1) must not matter: the surface alone decides.
    const double chi0 = 1.5, Ms = 35000, lo = 2e3, hi = 5e4;
    const double span = std::log(hi / lo);
    auto rs = [&](double h) {
        const double u = std::log(h / lo) / span;
        return 0.3 + 0.25 * u + 0.2 * u * u;
    };
    auto reference = [&](double h) { return ratioPotential(rs, h, lo, hi, chi0, Ms); };
    // The offset as large as the pressures themselves, as on a real pool (the law's constant
    // is the rim's level, not zero): the fit must find it, C = G(h_s) - P_s = -offset. (Until
    // 2026-12-02 the fit held C at 0 and this test used an offset of 1e-4 of the pressures.)
    const double offset = -0.4 * reference(hi);
    const auto [h, m, surface] = disagreeingSamples(lo, hi, chi0, Ms, reference, offset);
    DemagnetizationCurve curve(chi0, Ms);
    curve.fit(h, m, surface, DemagnetizationCurve::Fit::FreeSurface);
    REQUIRE(curve.fittedToSurface());
    const double range = reference(hi) - reference(lo);
    REQUIRE(curve.surfaceFit()->C == Approx(-offset).margin(2e-3 * range));
    for (double v : {3e3, 8e3, 2e4, 4.5e4}) {
        CAPTURE(v);
        REQUIRE(curve.potential(v) - curve.potential(lo * 1.2) == Approx(reference(v) - reference(lo * 1.2)).margin(2e-3 * range));
        REQUIRE(curve.ratio(v) == Approx(rs(v)).margin(0.01));
    }
    // Beyond the samples' range (their 2nd to 98th percentile) r is held at its end values.
    REQUIRE(curve.ratio(1e3) == Approx(curve.ratio(lo * 1.1)).margin(0.01));
    REQUIRE(curve.ratio(1e5) == Approx(curve.ratio(hi / 1.1)).margin(0.01));
    // The particles alone (and the node fit) give r = 1 and another potential.
    DemagnetizationCurve volumeOnly(chi0, Ms);
    volumeOnly.fit(h, m);
    REQUIRE_FALSE(volumeOnly.fittedToSurface());
    REQUIRE(volumeOnly.ratio(1e4) == Approx(1.0).epsilon(1e-6));
    REQUIRE(std::abs((volumeOnly.potential(hi) - volumeOnly.potential(lo)) - range) > 0.5 * range);
    // Too few surface samples (under kMinSurfaceSamples) are no surface: the volume decides.
    DemagnetizationCurve sparse(chi0, Ms);
    sparse.fit(h, m, std::vector<DemagnetizationCurve::SurfaceSample>(surface.begin(), surface.begin() + DemagnetizationCurve::kMinSurfaceSamples - 1),
               DemagnetizationCurve::Fit::FreeSurface);
    REQUIRE_FALSE(sparse.fittedToSurface());
    // potential() is the integral of magnetization(): a central difference of G is M_f.
    for (double v : {4e3, 3e4}) REQUIRE((curve.potential(v * 1.001) - curve.potential(v / 1.001)) / (v * 1.001 - v / 1.001) ==
                                        Approx(curve.magnetization(v)).epsilon(2e-3));
}

TEST_CASE("the free-surface curve's memory blends fits, and a restored curve is the same curve", "[magnetics][demagnetization]") {
    // Two surfaces with known ratios (quadratic in log h, so each is exactly a free-surface
    // curve) over the same field strengths, pressures from a reference integral of each
    // that is independent of the curve's tables (ratioPotential), with different constants.
    const double chi0 = 1.5, Ms = 35000, lo = 2e3, hi = 5e4;
    const double span = std::log(hi / lo);
    auto rA = [&](double h) { return 0.3 + 0.25 * std::log(h / lo) / span; };
    auto rB = [&](double h) { const double u = std::log(h / lo) / span; return 0.6 - 0.1 * u + 0.3 * u * u; };
    auto PA = [&](double h) { return ratioPotential(rA, h, lo, hi, chi0, Ms); };
    auto PB = [&](double h) { return ratioPotential(rB, h, lo, hi, chi0, Ms); };
    const auto [h, m, surfaceA] = disagreeingSamples(lo, hi, chi0, Ms, PA, 2e6);
    const auto surfaceB = std::get<2>(disagreeingSamples(lo, hi, chi0, Ms, PB, -3e6));
    const double range = PB(hi) - PB(lo);
    DemagnetizationCurve curve(chi0, Ms);
    // Memory without a surface fit before it is ignored: the first fit is the samples' own.
    curve.fit(h, m, surfaceA, DemagnetizationCurve::Fit::FreeSurface, 0.9);
    const DemagnetizationCurve::SurfaceFit a = *curve.surfaceFit();
    for (double v : {3e3, 2e4}) REQUIRE(curve.ratio(v) == Approx(rA(v)).margin(0.01));
    // With memory 0.3 the targets are 0.3 x (curve A's G - C) + 0.7 x P_B at the same h: a
    // curve whose ratio is 0.3 r_A + 0.7 r_B and whose G - C is that blend everywhere.
    curve.fit(h, m, surfaceB, DemagnetizationCurve::Fit::FreeSurface, 0.3);
    const DemagnetizationCurve::SurfaceFit blend = *curve.surfaceFit();
    REQUIRE(blend.C == Approx(0.3 * a.C + 0.7 * 3e6).margin(2e-3 * range));
    for (double v : {2.5e3, 8e3, 2e4, 4.5e4}) {
        CAPTURE(v);
        REQUIRE(curve.ratio(v) == Approx(0.3 * rA(v) + 0.7 * rB(v)).margin(0.01));
    }
    // A curve restored from its numbers (what a particle file carries) is the same curve.
    DemagnetizationCurve restored(chi0, Ms);
    REQUIRE(restored.restoreSurfaceFit(blend));
    REQUIRE(restored.fittedToSurface());
    for (double v : {500.0, 2.5e3, 8e3, 2e4, 4.5e4, 2e5}) {
        CAPTURE(v);
        REQUIRE(restored.potential(v) == Approx(curve.potential(v)).epsilon(1e-12));
        REQUIRE(restored.ratio(v) == Approx(curve.ratio(v)).epsilon(1e-12));
    }
    // ... and its memory continues as the original's does.
    curve.fit(h, m, surfaceA, DemagnetizationCurve::Fit::FreeSurface, 0.5);
    restored.fit(h, m, surfaceA, DemagnetizationCurve::Fit::FreeSurface, 0.5);
    REQUIRE(restored.potential(2e4) == Approx(curve.potential(2e4)).epsilon(1e-12));
    // Numbers that are no curve are refused and change nothing.
    DemagnetizationCurve fresh(chi0, Ms);
    DemagnetizationCurve::SurfaceFit bad = blend;
    bad.hLo = 0;
    REQUIRE_FALSE(fresh.restoreSurfaceFit(bad));
    bad = blend;
    bad.c[1] = std::nan("");
    REQUIRE_FALSE(fresh.restoreSurfaceFit(bad));
    bad = blend;
    bad.hHi = bad.hLo / 2;
    REQUIRE_FALSE(fresh.restoreSurfaceFit(bad));
    REQUIRE_FALSE(fresh.fitted());
    REQUIRE_FALSE(fresh.surfaceFit());
}

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
/// Langevin law) and surface samples whose pressure is `pressure(h)` plus a constant offset:
/// volume data that disagrees with the surface, for the fits that must follow the surface.
template <class Pressure>
std::tuple<std::vector<double>, std::vector<double>, std::vector<DemagnetizationCurve::SurfaceSample>>
disagreeingSamples(double lo, double hi, double chi0, double Ms, const Pressure& pressure) {
    std::vector<double> h, m;
    std::vector<DemagnetizationCurve::SurfaceSample> surface;
    for (int i = 0; i <= 400; ++i) {
        const double v = lo * std::pow(hi / lo, i / 400.0);
        h.push_back(v);
        m.push_back(langevinMagnetization(v, chi0, Ms));   // r = 1 in the volume
        surface.push_back({v, pressure(v) + 1234.5, 1.0});
    }
    return {h, m, surface};
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
    auto reference = [&](double h) {   // integral_0^h r_s(clamp) M_law dh', Simpson in log h above 1 A/m
        const int steps = 20000;
        const double a = std::log(1.0), b = std::log(h), dt = (b - a) / steps;
        auto f = [&](double t) {
            const double v = std::exp(t);
            return rs(std::clamp(v, lo, hi)) * langevinMagnetization(v, chi0, Ms) * v;
        };
        double sum = f(a) + f(b);
        for (int i = 1; i < steps; ++i) sum += (i % 2 ? 4 : 2) * f(a + i * dt);
        return sum * dt / 3;
    };
    const auto [h, m, surface] = disagreeingSamples(lo, hi, chi0, Ms, reference);
    DemagnetizationCurve curve(chi0, Ms);
    curve.fit(h, m, surface, DemagnetizationCurve::Fit::FreeSurface);
    REQUIRE(curve.fittedToSurface());
    const double range = reference(hi) - reference(lo);
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

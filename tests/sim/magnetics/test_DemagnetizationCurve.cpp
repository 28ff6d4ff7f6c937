// DemagnetizationCurve: the body force's magnetization as a function of the applied field's
// strength, fitted to per-particle magnetizations.
#include "sim/magnetics/DemagnetizationCurve.hpp"
#include "sim/magnetics/MagnetizationSolver.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

using namespace ferro;

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

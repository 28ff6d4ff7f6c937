#include "sim/magnets/LangevinLaw.hpp"

#include <cmath>

namespace ferro {

namespace {
// Below this |xi| the Taylor series (through xi^11) is used: its truncation error there is
// < 1e-15 relative while coth(xi) - 1/xi would already cancel ~2 of 16 digits.
constexpr double kSeriesXi = 0.2;
} // namespace

double langevin(double xi) {
    if (!std::isfinite(xi)) return std::isnan(xi) ? 0.0 : (xi > 0 ? 1.0 : -1.0);
    const double ax = std::abs(xi);
    if (ax < kSeriesXi) {
        const double x2 = xi * xi;
        return xi * (1.0 / 3 + x2 * (-1.0 / 45 + x2 * (2.0 / 945 + x2 * (-1.0 / 4725 +
                     x2 * (2.0 / 93555 + x2 * (-1382.0 / 638512875))))));
    }
    const double l = 1.0 / std::tanh(ax) - 1.0 / ax;
    return std::copysign(std::min(l, 1.0), xi);
}

double langevinDerivative(double xi) {
    if (!std::isfinite(xi)) return std::isnan(xi) ? 1.0 / 3 : 0.0;
    const double ax = std::abs(xi);
    if (ax < kSeriesXi) {
        const double x2 = xi * xi;
        return 1.0 / 3 + x2 * (-1.0 / 15 + x2 * (2.0 / 189 + x2 * (-1.0 / 675 +
                     x2 * (2.0 / 10395 + x2 * (-15202.0 / 638512875)))));
    }
    const double s = std::sinh(ax); // overflows to inf for ax > ~710: 1/inf^2 = 0, as it should
    return std::max(0.0, 1.0 / (ax * ax) - 1.0 / (s * s));
}

double langevinMagnetization(double H, double chi0, double Ms) {
    if (!(Ms > 0)) return chi0 * H;
    return Ms * langevin(3.0 * chi0 * H / Ms);
}

double langevinSlope(double H, double chi0, double Ms) {
    if (!(Ms > 0)) return chi0;
    return 3.0 * chi0 * langevinDerivative(3.0 * chi0 * H / Ms);
}

double langevinSecant(double H, double chi0, double Ms) {
    if (!(Ms > 0)) return chi0;
    const double xi = 3.0 * chi0 * std::abs(H) / Ms;
    if (xi < kSeriesXi) {
        const double x2 = xi * xi; // L(xi) / xi by the series
        return 3.0 * chi0 * (1.0 / 3 + x2 * (-1.0 / 45 + x2 * (2.0 / 945 + x2 * (-1.0 / 4725 +
                             x2 * (2.0 / 93555 + x2 * (-1382.0 / 638512875))))));
    }
    return Ms * langevin(xi) / std::abs(H);
}

double langevinEnergy(double H, double chi0, double Ms) {
    const double h = std::abs(H);
    if (!(Ms > 0)) return 0.5 * chi0 * h * h;
    if (!(chi0 > 0)) return 0.0;
    const double xi = 3.0 * chi0 * h / Ms;
    const double scale = Ms * Ms / (3.0 * chi0);
    // ln(sinh xi / xi): the series xi^2/6 - xi^4/180 + xi^6/2835 where the difference would
    // cancel digits, else xi + ln((1 - e^{-2 xi}) / 2) - ln xi, which never overflows.
    if (xi < kSeriesXi) {
        const double x2 = xi * xi;
        return scale * x2 * (1.0 / 6 + x2 * (-1.0 / 180 + x2 * (1.0 / 2835)));
    }
    return scale * (xi + std::log1p(-std::exp(-2.0 * xi)) - std::log(2.0) - std::log(xi));
}

} // namespace ferro

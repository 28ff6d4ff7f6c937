#include "spikes/SpikePhysics.hpp"
#include "sim/core/Constants.hpp"

#include "sim/magnets/LangevinLaw.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

namespace {

/// |M| of `law` at field magnitude H (the simulator's Langevin law, one definition for all stages).
double lawMagnetization(double H, const MagnetizationParams& law)
{
    return langevinMagnetization(std::abs(H), law.susceptibility, law.saturation);
}
} // namespace

CriticalMagnetization criticalMagnetization(double deltaRho, double gravity, double surfaceTension,
                                            const MagnetizationParams& law)
{
    CriticalMagnetization c;
    const double inf = std::numeric_limits<double>::infinity();
    if (!(law.susceptibility > 0)) {
        c.magnetization = c.internalField = c.appliedField = inf;
        return c;
    }
    const double capillary = std::sqrt(std::max(0.0, gravity * deltaRho * surfaceTension));
    c.r0 = 1.0 + law.susceptibility;
    for (int iteration = 0; iteration < 50; ++iteration) {
        const double Mc = std::sqrt(2.0 / kMu0 * (1.0 + 1.0 / c.r0) * capillary);
        c.magnetization = Mc;
        if (law.saturation > 0 && Mc >= law.saturation) {
            c.magnetization = c.internalField = c.appliedField = inf;
            return c;
        }
        if (Mc == 0) {
            c.internalField = c.appliedField = 0;
            return c;
        }
        // Invert the monotone law by bisection: M(H) = Mc.
        double lo = 0, hi = Mc / law.susceptibility;
        while (lawMagnetization(hi, law) < Mc) hi *= 2;
        for (int i = 0; i < 100; ++i) {
            const double mid = 0.5 * (lo + hi);
            (lawMagnetization(mid, law) < Mc ? lo : hi) = mid;
        }
        const double H = 0.5 * (lo + hi);
        const double chiChord = Mc / H;
        const double chiTangent = langevinSlope(H, law.susceptibility, law.saturation);
        const double r0 = std::sqrt((1 + chiChord) * (1 + chiTangent));
        c.internalField = H;
        c.appliedField = H + Mc;
        if (std::abs(r0 - c.r0) < 1e-12 * r0) break;
        c.r0 = r0;
    }
    return c;
}

double criticalWavelength(double deltaRho, double gravity, double surfaceTension)
{
    if (!(deltaRho * gravity > 0)) return 0;
    return 2.0 * kPi * std::sqrt(std::max(0.0, surfaceTension) / (deltaRho * gravity));
}

double growthRate(const SurfaceModes& m, double k)
{
    if (!(k > 0) || !(m.density > 0)) return 0.0;
    const double capillary = std::sqrt(std::max(0.0, m.gravity * m.deltaRho * m.surfaceTension));
    const double magnetic = 2.0 * capillary * m.supercriticality; // mu0 M^2 / (1 + 1/r0)
    const double w02 = (m.deltaRho * m.gravity * k + m.surfaceTension * k * k * k - magnetic * k * k) / m.density;
    if (!(w02 < 0)) return 0.0;
    const double inviscid = std::sqrt(-w02);
    const double nu = std::max(0.0, m.viscosity);
    if (nu == 0) return inviscid;
    // F(s) = (s + 2 nu k^2)^2 + w0^2 - 4 nu^2 k^3 r with r = sqrt(k^2 + s / nu), written as
    //     F(s) = s^2 + 4 nu k^2 s r / (k + r) + w0^2
    // (4 nu^2 k^3 (k - r) = -4 nu k^3 s / (k + r)): the same function without the cancellation
    // of two terms that both grow as 4 nu^2 k^4 (which lost k to 17 % at nu = 1e3 m^2/s).
    // F rises monotonically in s, from w0^2 < 0 at s = 0 to >= 0 at the inviscid rate: one
    // root, by bisection.
    const auto F = [&](double s) {
        const double r = std::sqrt(k * k + s / nu);
        return s * s + 4 * nu * k * k * s * r / (k + r) + w02;
    };
    double lo = 0, hi = inviscid;
    for (int i = 0; i < 400 && hi - lo > 1e-14 * hi; ++i) {
        const double mid = 0.5 * (lo + hi);
        (F(mid) < 0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

double fastestGrowingWavenumber(const SurfaceModes& m)
{
    if (!(m.gravity * m.deltaRho > 0) || !(m.surfaceTension > 0)) return 0.0;
    const double kc = std::sqrt(m.deltaRho * m.gravity / m.surfaceTension);
    const double q = m.supercriticality;
    if (!(q > 1)) return kc;
    // The unstable band: sigma k^2 - C k + delta_rho g < 0 with C = 2 sqrt(g delta_rho sigma) q,
    // i.e. k / k_c in q -+ sqrt(q^2 - 1). The rate is unimodal over it: golden-section search.
    const double root = std::sqrt(q * q - 1);
    double a = kc * (q - root), b = kc * (q + root);
    const double r = 0.5 * (std::sqrt(5.0) - 1);
    double c = b - r * (b - a), d = a + r * (b - a);
    double fc = growthRate(m, c), fd = growthRate(m, d);
    for (int i = 0; i < 200 && b - a > 1e-12 * kc; ++i) {
        if (fc < fd) {
            a = c, c = d, fc = fd;
            d = a + r * (b - a), fd = growthRate(m, d);
        } else {
            b = d, d = c, fd = fc;
            c = b - r * (b - a), fc = growthRate(m, c);
        }
    }
    return 0.5 * (a + b);
}

double hexProfile(double a, double b)
{
    return std::cos(2 * kPi * (a + b)) + std::cos(2 * kPi * a) + std::cos(2 * kPi * b);
}

double squareProfile(double a, double b)
{
    const double g = 0.5 * (std::cos(2 * kPi * a) + std::cos(2 * kPi * b));
    return 2.25 * g + g * g - 0.25;
}

SpikeBifurcation SpikeBifurcation::fromThresholds(double lowerThreshold, double epsFull)
{
    SpikeBifurcation b;
    const double h = std::clamp(1.0 - lowerThreshold, 0.0, 1.0);
    b.gamma = 2 * h + std::sqrt(4 * h * h + 4 * h * epsFull);
    b.g = b.gamma + epsFull;
    b.lower = -h;
    return b;
}

double SpikeBifurcation::upperBranch(double eps) const
{
    if (eps < lower) return 0.0;
    return (gamma + std::sqrt(std::max(0.0, gamma * gamma + 4 * g * eps))) / (2 * g);
}

double sharpenedProfile(double F, double p)
{
    if (p == 1.0) return F;
    const double t = std::min(1.0, std::max(0.0, (F + 1.5) / 4.5));
    return 4.5 * std::pow(t, p) - 1.5;
}

} // namespace ferro

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

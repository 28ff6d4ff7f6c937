#pragma once
// Internal to sim/magnets: the scale of a field profile bounded by a body of radius a
// (DipoleMagnet.cpp, BarMagnet.cpp): S = (t^4 + a^8)^(1/4) of t = r^2 + eps^2, computed
// without overflow, with w = t / S <= 1 and S^-1/2.
#include <algorithm>
#include <cmath>

namespace ferro {

struct BodyScale {
    bool valid = false;        ///< false where t = a = 0 (the profile is 0 there)
    double S = 0, w = 0, rs = 0; ///< S, t / S, S^-1/2
    BodyScale(double t, double a) {
        const double a2 = a * a, c = std::max(t, a2);
        if (!(c > 0.0)) return;
        const double u = t / c, v = a2 / c;
        S = c * std::sqrt(std::sqrt(u * u * u * u + v * v * v * v));
        w = t / S;
        rs = 1.0 / std::sqrt(S);
        valid = true;
    }
};

} // namespace ferro

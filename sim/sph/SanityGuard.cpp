#include "sim/sph/SanityGuard.hpp"

#include <algorithm>
#include <cmath>

namespace ferro {

double SpeedBound::energySpeed() const {
    return std::sqrt(std::max(0.0, gravity2 + initial2 + magnets2 + magnetic2 + capillary2));
}

double SpeedBound::value() const {
    if (override > 0) return override;
    return std::max(SanityLimits::kMinSpeed, SanityLimits::kSpeedSafety * energySpeed());
}

} // namespace ferro

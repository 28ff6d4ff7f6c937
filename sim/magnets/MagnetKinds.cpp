#include "sim/magnets/MagnetKinds.hpp"

#include "sim/core/Constants.hpp"

#include <cmath>

#include <iterator>
#include <stdexcept>

namespace ferro {

double magnetBodyRadius(MagnetKind kind, double strength) {
    const double s = std::abs(strength);
    switch (kind) {
    case MagnetKind::Dipole: return std::cbrt(3.0 * s / (4.0 * kPi * kStrongestMagnetization));
    case MagnetKind::Bar: return std::sqrt(s / (kPi * kStrongestMagnetization));
    case MagnetKind::Loop: return std::sqrt(s / (kPi * kStrongestCurrentDensity));
    case MagnetKind::Uniform: return 0.0;
    }
    return 0.0;
}

const MagnetKindInfo& magnetKindInfo(MagnetKind kind) {
    const size_t i = static_cast<size_t>(kind);
    if (i >= std::size(kMagnetKinds) || kMagnetKinds[i].kind != kind)
        throw std::logic_error("kMagnetKinds is not in MagnetKind order");
    return kMagnetKinds[i];
}

const MagnetKindInfo* findMagnetKind(const std::string& name) {
    for (const MagnetKindInfo& k : kMagnetKinds)
        if (name == k.name) return &k;
    return nullptr;
}

std::vector<std::string> magnetKindNames() {
    std::vector<std::string> names;
    for (const MagnetKindInfo& k : kMagnetKinds) names.push_back(k.name);
    return names;
}

} // namespace ferro

#include "sim/magnets/MagnetKinds.hpp"

#include <iterator>
#include <stdexcept>

namespace ferro {

double magnetBodyRadius(MagnetKind kind, double strength) { return magnetKindInfo(kind).bodyRadius(strength); }

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

#include "sim/magnetics/MagnetState.hpp"

#include <cstdio>
#include <sstream>

namespace ferro {

const char* magnetKindName(Magnet::Kind kind)
{
    return magnetKindInfo(kind).name;
}

void writeMagnetComments(ParticleTable& table, const std::vector<Magnet>& magnets, const MagnetizationParams* law)
{
    table.comments.emplace_back("magnet_count", std::to_string(magnets.size()));
    for (const Magnet& m : magnets) {
        Vec3d d = m.direction.norm() > 0 ? Vec3d(m.direction.normalized()) : m.direction;
        char buf[400];
        std::snprintf(buf, sizeof buf, "%s %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g", magnetKindName(m.kind),
                      m.position.x(), m.position.y(), m.position.z(), d.x(), d.y(), d.z(), m.strength, m.length,
                      m.radius, m.softening);
        table.comments.emplace_back("magnet", buf);
    }
    if (law) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.9g", law->susceptibility);
        table.comments.emplace_back("susceptibility", buf);
        std::snprintf(buf, sizeof buf, "%.9g", law->saturation);
        table.comments.emplace_back("saturation", buf);
    }
}

std::vector<Magnet> readMagnetComments(const ParticleTable& table)
{
    std::vector<Magnet> magnets;
    long expected = -1;
    for (const auto& [key, value] : table.comments) {
        if (key == "magnet_count") {
            expected = std::strtol(value.c_str(), nullptr, 10);
            continue;
        }
        if (key != "magnet")
            continue;
        std::istringstream in(value);
        std::string kind;
        Magnet m;
        in >> kind >> m.position.x() >> m.position.y() >> m.position.z() >> m.direction.x() >> m.direction.y() >>
            m.direction.z() >> m.strength >> m.length >> m.radius >> m.softening;
        if (!in)
            throw ParticleFileError("malformed 'comment magnet " + value + "' (expected kind and 10 numbers)");
        const MagnetKindInfo* info = findMagnetKind(kind);
        if (!info) throw ParticleFileError("unknown magnet kind '" + kind + "' in header");
        m.kind = info->kind;
        magnets.push_back(m);
    }
    if (expected >= 0 && expected != long(magnets.size()))
        throw ParticleFileError("header says magnet_count " + std::to_string(expected) + " but lists " +
                                std::to_string(magnets.size()) + " magnets");
    return magnets;
}

} // namespace ferro

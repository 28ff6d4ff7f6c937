#include "sim/magnets/MagnetState.hpp"

#include "sim/core/SceneDocument.hpp"

#include <cmath>
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
        std::string line = buf;
        if (magnetKindInfo(m.kind).usesTurns) { // only a coil's line has the 11th number
            std::snprintf(buf, sizeof buf, " %.9g", m.turns);
            line += buf;
        }
        table.comments.emplace_back("magnet", line);
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
        if (info->usesTurns && !(in >> m.turns))
            throw ParticleFileError("malformed 'comment magnet " + value + "' (a " + kind +
                                    " needs kind and 11 numbers, the last its turns)");
        m.kind = info->kind;
        // What the scene parser (MagnetScene.cpp) guarantees, so that a hand-edited or foreign
        // header cannot give the field evaluation a magnet it would overflow on (fuzz finding).
        const std::string& line = value; // a lambda cannot capture a structured binding in C++17
        auto bad = [&](const std::string& why) {
            throw ParticleFileError("malformed 'comment magnet " + line + "' (" + why + ")");
        };
        if (!(std::abs(m.strength) <= info->maxStrength))
            bad(std::string(info->strengthKey) + " must be within +-" + formatNumber(info->maxStrength) + " " +
                info->strengthUnit + " for a " + info->name + " magnet");
        if (info->usesLength && !(m.length > 0)) bad("length must be > 0");
        if (info->usesRadius && !(m.radius > 0)) bad("radius must be > 0");
        if (info->usesTurns && !(m.turns >= 1 && m.turns <= kMostTurns))
            bad("turns must be within [1, " + formatNumber(kMostTurns) + "]");
        if (!(m.softening >= 0)) bad("softening must be >= 0");
        magnets.push_back(m);
    }
    if (expected >= 0 && expected != long(magnets.size()))
        throw ParticleFileError("header says magnet_count " + std::to_string(expected) + " but lists " +
                                std::to_string(magnets.size()) + " magnets");
    return magnets;
}

} // namespace ferro

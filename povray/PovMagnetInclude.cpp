// magnets_NNNN.inc: the magnets of a frame (from the mesh header or the scene's tracks) as
// POV-Ray arrays and bodies.
#include "povray/PovText.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/MagnetScene.hpp"
#include "sim/scene/SimSceneFile.hpp"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace ferro {

namespace fs = std::filesystem;

std::vector<Magnet> frameMagnets(const TriangleMesh& mesh, const std::vector<MagnetTrack>& tracks, double time)
{
    ParticleTable header;
    header.comments = mesh.comments;
    if (!header.comment("magnet_count").empty()) {
        try {
            return readMagnetComments(header);
        } catch (const ParticleFileError& e) {
            throw MeshFileError(std::string("mesh header: ") + e.what());
        }
    }
    std::vector<Magnet> magnets;
    for (const MagnetTrack& t : tracks)
        magnets.push_back(t.at(time));
    return magnets;
}

std::string magnetInclude(const std::vector<Magnet>& magnets, const RenderParams& render, int frame, double time)
{
    std::ostringstream out;
    out << "// magnets_" << frameTag(frame) << ".inc: the magnets at frame " << frame << " (t = " << number(time)
        << " s), written by ferro-pov.\n"
           "// POV-Ray millimetres, y up. Direction is the magnetic axis, south -> north (flipped\n"
           "// for a negative strength); Length and Radius are display sizes (render.magnet_length,\n"
           "// render.magnet_radius for point dipoles, the pole distance of bar magnets, the loop radius).\n";
    // Uniform fields have no place and no body: they are listed but get no object.
    const size_t n = magnets.size();
    out << "#declare FerroMagnetCount = " << n << ";\n";
    if (n == 0)
        return out.str();
    auto array = [&](const char* name, auto&& item) {
        out << "#declare " << name << " = array[" << n << "] {";
        for (size_t i = 0; i < n; ++i)
            out << (i ? ", " : " ") << item(magnets[i]);
        out << " }\n";
    };
    auto axis = [](const Magnet& m) -> Vec3d {
        const double len = m.direction.norm();
        Vec3d d = len > 0 ? Vec3d(m.direction / len) : Vec3d(0, 0, 1);
        return m.strength < 0 ? Vec3d(-d) : d;
    };
    auto length = [&](const Magnet& m) {
        return magnetKindInfo(m.kind).usesLength && m.length > 0 ? m.length : render.magnetLength;
    };
    auto radius = [&](const Magnet& m) {
        return magnetKindInfo(m.kind).usesRadius && m.radius > 0 ? m.radius : render.magnetRadius;
    };
    array("FerroMagnetKind", [](const Magnet& m) { return quoted(magnetKindName(m.kind)); });
    array("FerroMagnetPosition", [](const Magnet& m) { return vec(toPovPoint(m.position)); });
    array("FerroMagnetDirection", [&](const Magnet& m) { return vec(toPovDirection(axis(m))); });
    array("FerroMagnetLength", [&](const Magnet& m) { return number(length(m) * kPovUnitsPerMetre); });
    array("FerroMagnetRadius", [&](const Magnet& m) { return number(radius(m) * kPovUnitsPerMetre); });
    array("FerroMagnetStrength", [](const Magnet& m) {
        std::ostringstream s;
        s.precision(9);
        s << std::fabs(m.strength);
        return s.str();
    });

    // Bodies: a cylinder per dipole or bar magnet, split at the centre into its north and south
    // halves; a torus (wire) per current loop and a hollow cylinder (winding) per coil, counted
    // as "south" (the neutral body).
    std::vector<std::string> north, south;
    for (const Magnet& m : magnets) {
        const Vec3d c = toPovPoint(m.position);
        const Vec3d d = toPovDirection(axis(m));
        const double half = 0.5 * length(m) * kPovUnitsPerMetre;
        const double r = radius(m) * kPovUnitsPerMetre;
        const MagnetBody body = magnetKindInfo(m.kind).body;
        if (body == MagnetBody::Rod) {
            north.push_back("cylinder { " + vec(c) + ", " + vec(c + half * d) + ", " + number(r) + " }");
            south.push_back("cylinder { " + vec(c - half * d) + ", " + vec(c) + ", " + number(r) + " }");
        } else if (body == MagnetBody::Ring) {
            // A torus lies in the xz plane around y: map y onto the axis with an orthonormal
            // frame (any frame will do, the torus is round) and move it to the centre. POV-Ray's
            // matrix takes the images of x, y, z as rows, then the translation.
            const double wire = std::max(0.02 * r, 0.5);
            const Vec3d ex = (std::fabs(d.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitZ());
            const Vec3d bx = (ex - ex.dot(d) * d).normalized();
            const Vec3d bz(bx.y() * d.z() - bx.z() * d.y(), bx.z() * d.x() - bx.x() * d.z(), bx.x() * d.y() - bx.y() * d.x());
            auto row = [](const Vec3d& v) { return number(v.x()) + "," + number(v.y()) + "," + number(v.z()); };
            south.push_back("torus { " + number(r) + ", " + number(wire) + " matrix <" + row(bx) + ", " + row(d) + ", " +
                            row(bz) + ", " + row(c) + "> }");
        } else if (body == MagnetBody::Tube) {
            // A coil's winding: a hollow cylinder of the coil's radius and length, its wall a
            // twentieth of the radius thick (at least half a POV unit, as the loop's wire).
            const double wall = std::max(0.05 * r, 0.5);
            south.push_back("difference { cylinder { " + vec(c - half * d) + ", " + vec(c + half * d) + ", " +
                            number(r + 0.5 * wall) + " } cylinder { " + vec(c - (half + 1) * d) + ", " +
                            vec(c + (half + 1) * d) + ", " + number(r - 0.5 * wall) + " } }");
        }
    }
    auto group = [&](const char* name, const std::vector<std::string>& parts) {
        if (parts.empty())
            return;
        out << "#declare " << name << " = ";
        if (parts.size() == 1) {
            out << parts[0] << "\n";
            return;
        }
        out << "union {\n";
        for (const auto& p : parts)
            out << "  " << p << "\n";
        out << "}\n";
    };
    group("FerroMagnetsNorth", north);
    group("FerroMagnetsSouth", south);
    return out.str();
}

} // namespace ferro

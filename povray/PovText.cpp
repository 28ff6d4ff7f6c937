// POV-Ray's coordinates (millimetres, y up) and number format (fixed, no "-0").
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

Vec3d toPovPoint(const Vec3d& p)
{
    return kPovUnitsPerMetre * Vec3d(p.x(), p.z(), p.y());
}

Vec3d toPovDirection(const Vec3d& d)
{
    return Vec3d(d.x(), d.z(), d.y());
}

void appendNumber(std::string& out, double v, int decimals)
{
    if (!std::isfinite(v))
        v = 0.0;
    char buf[64];
    auto res = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
    char* end = res.ptr;
    if (res.ec != std::errc()) { // beyond 1e40 or so: never a mesh coordinate, but stay valid
        end = buf + std::snprintf(buf, sizeof buf, "%.9g", v);
    } else if (decimals > 0) {
        while (end[-1] == '0') --end;
        if (end[-1] == '.') --end;
    }
    // "-0" (a tiny negative rounded away) is just 0.
    if (end - buf == 2 && buf[0] == '-' && buf[1] == '0')
        out += '0';
    else
        out.append(buf, end);
}

void appendVector(std::string& out, const Vec3d& v, int decimals)
{
    out += '<';
    appendNumber(out, v.x(), decimals);
    out += ',';
    appendNumber(out, v.y(), decimals);
    out += ',';
    appendNumber(out, v.z(), decimals);
    out += '>';
}

} // namespace ferro

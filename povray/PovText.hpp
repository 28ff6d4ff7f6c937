#pragma once
// Internal to povray/: the small text helpers every include writer uses (frame tags, numbers
// and vectors through appendNumber, quoted strings).
#include "povray/PovExport.hpp"

#include <cstdio>
#include <string>

namespace ferro {

inline std::string frameTag(int frame)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%04d", frame);
    return buf;
}

inline std::string number(double v, int decimals = 6)
{
    std::string s;
    appendNumber(s, v, decimals);
    return s;
}

inline std::string vec(const Vec3d& v, int decimals = 6)
{
    std::string s;
    appendVector(s, v, decimals);
    return s;
}

inline std::string quoted(const std::string& s)
{
    std::string q = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') q += '\\';
        q += c;
    }
    return q + '"';
}

} // namespace ferro

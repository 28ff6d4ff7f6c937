#pragma once
// Error text for the stages' "ferro-<stage>: error: <reason>" lines. Header-only; every
// stage's main folds a library's multi-line message with it.
#include <cctype>
#include <cstdio>
#include <string>

namespace ferro {

/// `text` with its line breaks (and the blanks around them) folded into "; ", so that a
/// library's multi-line message (CGAL's precondition reports, ...) stays one line.
inline std::string oneLine(const std::string& text) {
    std::string out;
    for (size_t i = 0; i < text.size(); ++i) {
        if (text[i] != '\n' && text[i] != '\r') {
            out += text[i];
            continue;
        }
        while (!out.empty() && (out.back() == ' ' || out.back() == '\t')) out.pop_back();
        while (i + 1 < text.size() && std::isspace(static_cast<unsigned char>(text[i + 1]))) ++i;
        if (!out.empty() && i + 1 < text.size()) out += "; ";
    }
    return out;
}

/// `text` with its control characters but tab written as escapes (\n, \r, \xNN), for a
/// message that quotes the input (a TOML key, a PLY header line, a parser's "saw '\n'"):
/// the message stays one line and shows what the file holds.
inline std::string escapeControl(const std::string& text) {
    std::string out;
    for (char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if (c == '\n') out += "\\n";
        else if (c == '\r') out += "\\r";
        else if ((u < 0x20 && c != '\t') || u == 0x7f) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", u);
            out += buf;
        } else out += c;
    }
    return out;
}

} // namespace ferro

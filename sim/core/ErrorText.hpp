#pragma once
// Error text for the stages' "ferro-<stage>: error: <reason>" lines. Header-only; every
// stage's main folds a library's multi-line message with it.
#include <cctype>
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

} // namespace ferro

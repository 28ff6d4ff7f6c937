// The --set KEY=VALUE overrides of a scene document (see SceneDocument.hpp).
#include "sim/core/SceneDocument.hpp"
#include "sim/core/SceneToml.hpp"
#include "sim/core/StageErrors.hpp"

#include "sim/core/ErrorText.hpp"

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace ferro {
namespace scene_detail {

namespace {

std::string trim(const std::string& s)
{
    const char* ws = " \t\r\n";
    size_t b = s.find_first_not_of(ws);
    if (b == std::string::npos)
        return {};
    return s.substr(b, s.find_last_not_of(ws) - b + 1);
}

bool isIndex(const std::string& s)
{
    return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// A TOML basic string holding `s` verbatim.
std::string quoteToml(const std::string& s)
{
    std::string out = "\"";
    for (char c : s) {
        unsigned char u = static_cast<unsigned char>(c);
        if (c == '"' || c == '\\') {
            out += '\\';
            out += c;
        } else if (u < 0x20 || u == 0x7f) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", u);
            out += buf;
        } else {
            out += c;
        }
    }
    return out + "\"";
}

// Parses `text` (a single `v = ...` line) with `source` as its file name, so the node
// carries "--set key:1" as its location. Returns an empty table if it is not valid TOML.
toml::table parseOverrideLine(const std::string& text, const std::string& source)
{
    try {
        return toml::parse(text, source);
    } catch (const toml::parse_error&) {
        return {};
    }
}

// Applies one "a.b.c=value" override to `root`.

} // namespace

void applyOverride(toml::table& root, const std::string& arg)
{
    size_t eq = arg.find('=');
    if (eq == std::string::npos)
        throw SceneError("--set " + arg + ": expected section.key=value");
    std::string key = trim(arg.substr(0, eq));
    std::string value = trim(arg.substr(eq + 1));
    if (key.empty())
        throw SceneError("--set " + arg + ": empty key");

    std::vector<std::string> segments;
    std::stringstream ss(key);
    for (std::string seg; std::getline(ss, seg, '.');)
        segments.push_back(trim(seg));
    if (key.back() == '.' || std::any_of(segments.begin(), segments.end(),
                                         [](const std::string& s) { return s.empty(); }))
        throw SceneError("--set " + arg + ": empty key segment in '" + key + "'");

    const std::string source = "--set " + key;
    // A value that is not TOML is taken as a bare string, so `container.type=dish` works
    // without shell-quoting the quotes. Extra keys mean the value smuggled in more TOML
    // (e.g. a newline), which is not a single value either.
    toml::table parsed = parseOverrideLine("v = " + value, source);
    if (parsed.size() != 1 || !parsed.contains("v"))
        parsed = parseOverrideLine("v = " + quoteToml(value), source);
    if (!parsed.contains("v")) // only invalid UTF-8 fails even as a string
        throw SceneError("--set " + arg + ": value is neither TOML nor text");
    toml::node& newValue = *parsed.get("v");

    auto fail = [&](const std::string& prefix, const std::string& msg) -> SceneError {
        return SceneError("--set " + arg + ": " + prefix + ": " + msg);
    };

    toml::node* cur = &root;
    std::string walked; // dotted path of `cur`, for messages
    for (size_t i = 0; i < segments.size(); ++i) {
        const std::string& seg = segments[i];
        const bool last = i + 1 == segments.size();
        const std::string here = walked.empty() ? seg : walked + "." + seg;

        if (toml::array* arr = cur->as_array()) {
            if (!isIndex(seg))
                throw fail(here, "expected an array index");
            // Longer digit strings than any array could need would overflow stoul.
            size_t idx = seg.size() <= 9 ? std::stoul(seg) : arr->size();
            if (idx >= arr->size())
                throw fail(here, "index out of range (the array has " + std::to_string(arr->size()) +
                                     " elements)");
            if (last) {
                arr->replace(arr->cbegin() + static_cast<std::ptrdiff_t>(idx), std::move(newValue));
                return;
            }
            cur = arr->get(idx);
        } else if (toml::table* tbl = cur->as_table()) {
            if (last) {
                tbl->insert_or_assign(seg, std::move(newValue));
                return;
            }
            toml::node* child = tbl->get(seg);
            if (!child) {
                // Created tables get the override's location too, so a "required key
                // missing" in a section that only exists through --set points at the --set.
                toml::table made = parseOverrideLine("t = {}", source);
                toml::table& sub = *made.get_as<toml::table>("t");
                sub.is_inline(false);
                child = &tbl->insert_or_assign(seg, std::move(sub)).first->second;
            }
            cur = child;
        } else {
            throw fail(walked, std::string("not a table or array (got ") + typeName(*cur) + ")");
        }
        walked = here;
    }
}

// Errors without a position (an unreadable file) have line 0 and name only the file.

} // namespace scene_detail
} // namespace ferro

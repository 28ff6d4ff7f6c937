#include "sim/core/SceneDocument.hpp"
#include "sim/core/SceneToml.hpp"
#include "sim/core/StageErrors.hpp"

#include "sim/core/ErrorText.hpp"

#include <toml++/toml.h>

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

// Errors are reported through toml::parse_error exceptions; the no-exceptions build of
// toml++ returns parse_result objects instead and would need different code.
static_assert(TOML_EXCEPTIONS, "SceneDocument.cpp expects toml++ built with exceptions");

namespace ferro {

namespace fs = std::filesystem;

SceneError::SceneError(const std::string& what) : std::runtime_error(escapeControl(what)) {}

std::string formatNumber(double v)
{
    char buf[32];
    auto res = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, res.ptr);
}

std::string formatVec(const Vec3d& v)
{
    return "[" + formatNumber(v.x()) + ", " + formatNumber(v.y()) + ", " + formatNumber(v.z()) + "]";
}


using namespace scene_detail;

namespace {

SceneError syntaxError(const std::string& name, const toml::parse_error& e)
{
    std::string at = name;
    if (e.source().begin.line > 0)
        at += ":" + std::to_string(e.source().begin.line);
    return SceneError(at + ": " + std::string(e.description()));
}

std::uint64_t fnv1a64(const std::string& s)
{
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (unsigned char c : s) {
        h ^= c;
        h *= 0x100000001b3ull;
    }
    return h;
}

} // namespace

// ---------------------------------------------------------------------------------------
// SceneDocument

struct SceneDocument::ReadLog {
    std::map<std::string, std::string> values; // "path.key" -> TOML text or "(absent)"
    std::map<std::string, std::pair<std::string, std::string>> specs; // "path.key" -> type, default
};

SceneDocument::SceneDocument() : root_(std::make_shared<toml::table>()) {}
SceneDocument::SceneDocument(SceneDocument&&) noexcept = default;
SceneDocument::~SceneDocument() = default;

SceneDocument SceneDocument::load(const std::string& path, const std::vector<std::string>& overrides)
{
    // A missing or unreadable scene is a missing input (exit 4), as a missing PLY is in
    // every stage; what the file says is the scene's business (SceneError, exit 2).
    requireReadable(path);
    SceneDocument doc;
    doc.path_ = path;
    try {
        *doc.root_ = toml::parse_file(path);
    } catch (const toml::parse_error& e) {
        throw syntaxError(path, e);
    }
    for (const std::string& o : overrides)
        applyOverride(*doc.root_, o);
    return doc;
}

SceneDocument SceneDocument::parse(const std::string& text, const std::string& name,
                                   const std::vector<std::string>& overrides)
{
    SceneDocument doc;
    doc.path_ = name;
    try {
        *doc.root_ = toml::parse(text, name);
    } catch (const toml::parse_error& e) {
        throw syntaxError(name, e);
    }
    for (const std::string& o : overrides)
        applyOverride(*doc.root_, o);
    return doc;
}

const toml::table& SceneDocument::root() const
{
    return *root_;
}

bool SceneDocument::hasSection(const std::string& name) const
{
    return root_->contains(name);
}

std::shared_ptr<const SceneDocument> SceneDocument::subset(const std::string& name,
                                                           const std::vector<std::string>& keys) const
{
    auto out = std::shared_ptr<SceneDocument>(new SceneDocument());
    out->path_ = path_;
    out->root_ = root_;
    out->reads_ = reads_;
    out->subsetSection_ = name;
    out->subsetKeys_ = keys;
    return out;
}

TableReader SceneDocument::section(const std::string& name) const
{
    const toml::node* n = root_->get(name);
    if (!n)
        return TableReader(*this, emptyTable(), name);
    const toml::table* t = n->as_table();
    if (!t)
        throw SceneError(locate(*n, path_) + ": " + name + ": expected a table [" + name + "] (got " +
                         typeName(*n) + ")");
    TableReader reader(*this, *t, name);
    if (name == subsetSection_)
        for (const auto& [key, node] : *t)
            if (std::find(subsetKeys_.begin(), subsetKeys_.end(), std::string(key.str())) == subsetKeys_.end())
                reader.ignore(std::string(key.str()));
    return reader;
}

std::string SceneDocument::directory() const
{
    return fs::path(path_).parent_path().string();
}

void SceneDocument::checkSections(const std::vector<std::string>& known) const
{
    for (const auto& [key, n] : keysInFileOrder(*root_, path_))
        if (std::find(known.begin(), known.end(), key) == known.end())
            throw SceneError(locate(*n, path_) + ": " + key + ": unknown section");
}

std::string hashHex(const std::string& text)
{
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a64(text)));
    return hex;
}

std::string SceneDocument::fingerprint() const
{
    std::ostringstream text;
    text << toml::toml_formatter(*root_);
    return hashHex(text.str());
}

void SceneDocument::recordReads()
{
    if (!reads_)
        reads_ = std::make_shared<ReadLog>();
}

void SceneDocument::noteRead(const std::string& tablePath, const std::string& key, const toml::node* n) const
{
    if (!reads_)
        return;
    std::ostringstream text;
    if (!n)
        text << "(absent)";
    else if (const toml::table* t = n->as_table())
        text << "{ " << toml::toml_formatter(*t, toml::format_flags::none) << " }";
    else if (const toml::array* a = n->as_array())
        text << toml::toml_formatter(*a, toml::format_flags::none);
    else
        n->visit([&](const auto& v) { text << toml::toml_formatter(v, toml::format_flags::none); });
    std::string line = text.str();
    std::replace(line.begin(), line.end(), '\n', ' ');
    reads_->values[tablePath.empty() ? key : tablePath + "." + key] = line;
}

void SceneDocument::noteSpec(const std::string& tablePath, const std::string& key, const std::string& type,
                             const std::string& def) const
{
    if (reads_)
        reads_->specs[tablePath.empty() ? key : tablePath + "." + key] = {type, def};
}

std::string SceneDocument::keySpecsText() const
{
    std::string out;
    if (reads_)
        for (const auto& entry : reads_->values) {
            const auto s = reads_->specs.find(entry.first);
            out += entry.first + "\t" + (s == reads_->specs.end() ? "-\t-" : s->second.first + "\t" + s->second.second) + "\n";
        }
    return out;
}

std::string SceneDocument::readsText() const
{
    std::string out;
    if (reads_)
        for (const auto& [key, value] : reads_->values)
            out += key + " = " + value + "\n";
    return out;
}

std::string SceneDocument::readsFingerprint(const std::vector<std::string>& ignore) const
{
    std::string text;
    if (reads_)
        for (const auto& [key, value] : reads_->values)
            if (value != "(absent)" && std::find(ignore.begin(), ignore.end(), key) == ignore.end())
                text += key + " = " + value + "\n";
    return hashHex(text);
}

std::string SceneDocument::fingerprint(const std::vector<std::string>& sections) const
{
    std::ostringstream text;
    for (const std::string& name : sections) {
        text << "[" << name << "]\n";
        if (const toml::node* n = root_->get(name)) {
            if (const toml::table* t = n->as_table()) text << toml::toml_formatter(*t);
            else if (const toml::array* a = n->as_array()) text << toml::toml_formatter(*a);
        }
        text << "\n";
    }
    return hashHex(text.str());
}

} // namespace ferro

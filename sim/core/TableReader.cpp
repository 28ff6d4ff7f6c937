// TableReader: typed keys of one scene table (see SceneDocument.hpp).
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

using namespace scene_detail;
namespace fs = std::filesystem;

struct TableReader::Used {
    std::set<std::string> keys;
};

TableReader::TableReader(const SceneDocument& doc, const toml::table& table, std::string path)
    : doc_(&doc), table_(&table), path_(std::move(path)), used_(std::make_unique<Used>())
{
}

TableReader::~TableReader() = default;
TableReader::TableReader(TableReader&&) noexcept = default;

bool TableReader::has(const std::string& key) const
{
    const toml::node* n = table_->get(key);
    doc_->noteRead(path_, key, n);
    return n != nullptr;
}

const toml::node* TableReader::node(const std::string& key) const
{
    used_->keys.insert(key);
    const toml::node* n = table_->get(key);
    doc_->noteRead(path_, key, n);
    return n;
}

std::string TableReader::where(const std::string& key) const
{
    if (!key.empty())
        if (const toml::node* n = table_->get(key))
            return locate(*n, doc_->path());
    return locate(*table_, doc_->path());
}

void TableReader::fail(const std::string& key, const std::string& message) const
{
    std::string full = path_;
    if (!key.empty())
        full += (full.empty() ? "" : ".") + key;
    throw SceneError(where(key) + ": " + full + ": " + message);
}

void TableReader::spec(const std::string& key, const std::string& type, const std::string& def) const
{
    doc_->noteSpec(path_, key, type, def);
}

double TableReader::number(const std::string& key, double def) const
{
    const double v = has(key) ? number(key) : def;
    spec(key, "number", formatNumber(def));
    return v;
}

double TableReader::number(const std::string& key) const
{
    const toml::node* n = node(key);
    if (!n)
        fail(key, "required key missing");
    double v;
    if (auto i = n->as_integer())
        v = static_cast<double>(i->get());
    else if (auto f = n->as_floating_point())
        v = f->get();
    else
        fail(key, std::string("expected a number (got ") + typeName(*n) + ")");
    // TOML allows nan and inf; no physical parameter of a shot can be either.
    if (!std::isfinite(v))
        fail(key, "must be finite (got " + formatNumber(v) + ")");
    spec(key, "number", "required");
    return v;
}

double TableReader::positive(const std::string& key, double def) const
{
    double v = number(key, def);
    if (!(v > 0))
        fail(key, "must be > 0 (got " + formatNumber(v) + ")");
    spec(key, "number > 0", formatNumber(def));
    return v;
}

double TableReader::nonNegative(const std::string& key, double def) const
{
    double v = number(key, def);
    if (!(v >= 0))
        fail(key, "must be >= 0 (got " + formatNumber(v) + ")");
    spec(key, "number >= 0", formatNumber(def));
    return v;
}

long TableReader::integer(const std::string& key, long def) const
{
    spec(key, "integer", std::to_string(def));
    const toml::node* n = node(key);
    if (!n)
        return def;
    auto i = n->as_integer();
    if (!i)
        fail(key, std::string("expected an integer (got ") + typeName(*n) + ")");
    return static_cast<long>(i->get());
}

bool TableReader::boolean(const std::string& key, bool def) const
{
    spec(key, "boolean", def ? "true" : "false");
    const toml::node* n = node(key);
    if (!n)
        return def;
    auto b = n->as_boolean();
    if (!b)
        fail(key, std::string("expected true or false (got ") + typeName(*n) + ")");
    return b->get();
}

double TableReader::positive(const std::string& key) const
{
    const double v = number(key);
    if (!(v > 0))
        fail(key, "must be > 0 (got " + formatNumber(v) + ")");
    spec(key, "number > 0", "required");
    return v;
}

int TableReader::integerInRange(const std::string& key, int def, long lo, long hi) const
{
    const long v = integer(key, def);
    if (v < lo || v > hi)
        fail(key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " +
                      std::to_string(v) + ")");
    spec(key, "integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", std::to_string(def));
    return static_cast<int>(v);
}

double TableReader::numberInRange(const std::string& key, double def, double lo, double hi) const
{
    const double v = number(key, def);
    if (!(v >= lo && v <= hi))
        fail(key, "must be in [" + formatNumber(lo) + ", " + formatNumber(hi) + "] (got " + formatNumber(v) + ")");
    spec(key, "number in [" + formatNumber(lo) + ", " + formatNumber(hi) + "]", formatNumber(def));
    return v;
}

Vec3d TableReader::unitVector(const std::string& key, const Vec3d& def) const
{
    const Vec3d d = vec3(key, def);
    // Scaled by its largest component first: the norm of [1e308, 1e308, 0] overflows and
    // that of [1e-200, 0, 0] underflows, and either normalized to a zero vector that the
    // next reader of this default (a magnet key) then blamed on a key nobody set.
    const double big = d.cwiseAbs().maxCoeff();
    if (!(big > 0))
        fail(key, "must be a non-zero vector (got " + formatVec(d) + ")");
    spec(key, "direction [x, y, z], non-zero", formatVec(def));
    return (d / big).normalized();
}

void TableReader::box(const std::string& minKey, const std::string& maxKey, Vec3d& lo, Vec3d& hi) const
{
    lo = vec3(minKey);
    hi = vec3(maxKey);
    if (!(hi.array() > lo.array()).all())
        fail(maxKey, "must be > " + minKey + " on every axis (got " + minKey + " " + formatVec(lo) + ", " +
                         maxKey + " " + formatVec(hi) + ")");
}

std::string TableReader::string(const std::string& key, const std::string& def) const
{
    std::string v = has(key) ? string(key) : def;
    spec(key, "string", "\"" + def + "\"");
    return v;
}

std::string TableReader::string(const std::string& key) const
{
    const toml::node* n = node(key);
    if (!n)
        fail(key, "required key missing");
    auto s = n->as_string();
    if (!s)
        fail(key, std::string("expected a string (got ") + typeName(*n) + ")");
    spec(key, "string", "required");
    return s->get();
}

std::string TableReader::choice(const std::string& key, const std::vector<std::string>& choices,
                                const std::string& def) const
{
    std::string v = string(key, def);
    std::string list;
    for (const std::string& c : choices)
        list += (list.empty() ? "\"" : ", \"") + c + "\"";
    spec(key, "one of " + list, "\"" + def + "\"");
    if (std::find(choices.begin(), choices.end(), v) != choices.end())
        return v;
    fail(key, "must be one of " + list + " (got \"" + v + "\")");
}

Vec3d TableReader::vec3(const std::string& key, const Vec3d& def) const
{
    const Vec3d v = has(key) ? vec3(key) : def;
    spec(key, "[x, y, z]", formatVec(def));
    return v;
}

Vec3d TableReader::vec3(const std::string& key) const
{
    const toml::node* n = node(key);
    if (!n)
        fail(key, "required key missing");
    const toml::array* arr = n->as_array();
    if (!arr)
        fail(key, std::string("expected an array of 3 numbers (got ") + typeName(*n) + ")");
    if (arr->size() != 3)
        fail(key, "expected an array of 3 numbers (got " + std::to_string(arr->size()) + " elements)");
    Vec3d v;
    for (size_t i = 0; i < 3; ++i) {
        const toml::node& e = *arr->get(i);
        if (auto iv = e.as_integer())
            v[Eigen::Index(i)] = static_cast<double>(iv->get());
        else if (auto fv = e.as_floating_point())
            v[Eigen::Index(i)] = fv->get();
        else
            fail(key, std::string("expected an array of 3 numbers (element ") + std::to_string(i) +
                          " is a " + typeName(e) + ")");
    }
    // Checked once all three are read: the message shows the values given, never the
    // uninitialised elements after a nan.
    if (!v.allFinite())
        fail(key, "must be finite (got " + formatVec(v) + ")");
    spec(key, "[x, y, z]", "required");
    return v;
}

std::string TableReader::path(const std::string& key) const
{
    std::string raw = string(key);
    if (raw.empty())
        fail(key, "expected a file name (got \"\")");
    fs::path p(raw);
    if (p.is_relative())
        p = fs::path(doc_->directory()) / p;
    p = p.lexically_normal();
    std::error_code ec;
    if (!fs::is_regular_file(p, ec))
        fail(key, "file not found: " + p.string());
    spec(key, "file path, relative to the scene", "required");
    return p.string();
}

TableReader TableReader::table(const std::string& key) const
{
    std::string full = path_.empty() ? key : path_ + "." + key;
    spec(key, "table", "empty");
    const toml::node* n = node(key);
    if (!n)
        return TableReader(*doc_, emptyTable(), full);
    const toml::table* t = n->as_table();
    if (!t)
        fail(key, std::string("expected a table (got ") + typeName(*n) + ")");
    return TableReader(*doc_, *t, full);
}

std::vector<TableReader> TableReader::keyframes(const std::string& key, const std::string& label) const
{
    std::vector<TableReader> out = tables(key);
    double lastTime = -std::numeric_limits<double>::infinity();
    for (const TableReader& k : out) {
        const double time = k.nonNegative("time", 0.0);
        if (!k.has("time"))
            k.fail("time", "every [[" + label + "]] needs a time");
        if (time < lastTime)
            k.fail("time", "keys must be in time order (got " + formatNumber(time) + " after " +
                               formatNumber(lastTime) + ")");
        lastTime = time;
    }
    return out;
}

std::vector<TableReader> TableReader::tables(const std::string& key) const
{
    std::string full = path_.empty() ? key : path_ + "." + key;
    std::vector<TableReader> out;
    spec(key, "array of tables", "none");
    const toml::node* n = node(key);
    if (!n)
        return out;
    const toml::array* arr = n->as_array();
    if (!arr)
        fail(key, std::string("expected an array of tables [[") + full + "]] (got " + typeName(*n) + ")");
    for (size_t i = 0; i < arr->size(); ++i) {
        const toml::node& e = *arr->get(i);
        const toml::table* t = e.as_table();
        std::string elem = full + "[" + std::to_string(i) + "]";
        if (!t)
            throw SceneError(locate(e, doc_->path()) + ": " + elem + ": expected a table (got " +
                             typeName(e) + ")");
        out.emplace_back(*doc_, *t, elem);
    }
    return out;
}

std::vector<std::string> TableReader::unread() const
{
    std::vector<std::string> out;
    for (const auto& [key, n] : keysInFileOrder(*table_, doc_->path()))
        if (!used_->keys.count(key)) out.push_back(key);
    return out;
}

void TableReader::ignore(const std::string& key) const { used_->keys.insert(key); }

void TableReader::finish() const
{
    for (const auto& [key, n] : keysInFileOrder(*table_, doc_->path()))
        if (!used_->keys.count(key))
            fail(key, "unknown key");
}

} // namespace ferro

#include "sim/core/SceneDocument.hpp"
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

namespace {

// TOML's own names for the types, which is what users see in their file.
const char* typeName(const toml::node& n)
{
    switch (n.type()) {
    case toml::node_type::string: return "string";
    case toml::node_type::integer: return "integer";
    case toml::node_type::floating_point: return "float";
    case toml::node_type::boolean: return "boolean";
    case toml::node_type::array: return "array";
    case toml::node_type::table: return "table";
    case toml::node_type::date: return "date";
    case toml::node_type::time: return "time";
    case toml::node_type::date_time: return "date-time";
    case toml::node_type::none: break;
    }
    return "nothing";
}

// "file:line" of a node. Nodes built in code rather than parsed have no source; they
// fall back to the document itself.
std::string locate(const toml::node& n, const std::string& docPath)
{
    const toml::source_region& src = n.source();
    std::string file = src.path && !src.path->empty() ? *src.path : docPath;
    if (src.begin.line == 0)
        return file;
    return file + ":" + std::to_string(src.begin.line);
}

// A table with no keys, standing in for an absent section or sub-table.
const toml::table& emptyTable()
{
    static const toml::table empty;
    return empty;
}

// Keys of `table` in file order (toml::table iterates alphabetically), so that the
// first offending key reported is the first one the user wrote; keys set by --set
// come after those of the file.
std::vector<std::pair<std::string, const toml::node*>> keysInFileOrder(const toml::table& table,
                                                                       const std::string& docPath)
{
    std::vector<std::pair<std::string, const toml::node*>> keys;
    for (const auto& [k, v] : table)
        keys.emplace_back(std::string(k.str()), &v);
    auto order = [&](const toml::node* n) {
        const toml::source_region& src = n->source();
        return std::make_pair(!src.path || *src.path != docPath, src.begin.line);
    };
    std::stable_sort(keys.begin(), keys.end(),
                     [&](const auto& a, const auto& b) { return order(a.second) < order(b.second); });
    return keys;
}

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
// TableReader

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

double TableReader::number(const std::string& key, double def) const
{
    return has(key) ? number(key) : def;
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
    return v;
}

double TableReader::positive(const std::string& key, double def) const
{
    double v = number(key, def);
    if (!(v > 0))
        fail(key, "must be > 0 (got " + formatNumber(v) + ")");
    return v;
}

double TableReader::nonNegative(const std::string& key, double def) const
{
    double v = number(key, def);
    if (!(v >= 0))
        fail(key, "must be >= 0 (got " + formatNumber(v) + ")");
    return v;
}

long TableReader::integer(const std::string& key, long def) const
{
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
    return v;
}

int TableReader::integerInRange(const std::string& key, int def, long lo, long hi) const
{
    const long v = integer(key, def);
    if (v < lo || v > hi)
        fail(key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " +
                      std::to_string(v) + ")");
    return static_cast<int>(v);
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
    return has(key) ? string(key) : def;
}

std::string TableReader::string(const std::string& key) const
{
    const toml::node* n = node(key);
    if (!n)
        fail(key, "required key missing");
    auto s = n->as_string();
    if (!s)
        fail(key, std::string("expected a string (got ") + typeName(*n) + ")");
    return s->get();
}

std::string TableReader::choice(const std::string& key, const std::vector<std::string>& choices,
                                const std::string& def) const
{
    std::string v = string(key, def);
    if (std::find(choices.begin(), choices.end(), v) != choices.end())
        return v;
    std::string list;
    for (const std::string& c : choices)
        list += (list.empty() ? "\"" : ", \"") + c + "\"";
    fail(key, "must be one of " + list + " (got \"" + v + "\")");
}

Vec3d TableReader::vec3(const std::string& key, const Vec3d& def) const
{
    return has(key) ? vec3(key) : def;
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
    return p.string();
}

TableReader TableReader::table(const std::string& key) const
{
    std::string full = path_.empty() ? key : path_ + "." + key;
    const toml::node* n = node(key);
    if (!n)
        return TableReader(*doc_, emptyTable(), full);
    const toml::table* t = n->as_table();
    if (!t)
        fail(key, std::string("expected a table (got ") + typeName(*n) + ")");
    return TableReader(*doc_, *t, full);
}

std::vector<TableReader> TableReader::tables(const std::string& key) const
{
    std::string full = path_.empty() ? key : path_ + "." + key;
    std::vector<TableReader> out;
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

void TableReader::finish() const
{
    for (const auto& [key, n] : keysInFileOrder(*table_, doc_->path()))
        if (!used_->keys.count(key))
            fail(key, "unknown key");
}

// ---------------------------------------------------------------------------------------
// SceneDocument

struct SceneDocument::ReadLog {
    std::map<std::string, std::string> values; // "path.key" -> TOML text or "(absent)"
};

SceneDocument::SceneDocument() : root_(std::make_unique<toml::table>()) {}
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

TableReader SceneDocument::section(const std::string& name) const
{
    const toml::node* n = root_->get(name);
    if (!n)
        return TableReader(*this, emptyTable(), name);
    const toml::table* t = n->as_table();
    if (!t)
        throw SceneError(locate(*n, path_) + ": " + name + ": expected a table [" + name + "] (got " +
                         typeName(*n) + ")");
    return TableReader(*this, *t, name);
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
        reads_ = std::make_unique<ReadLog>();
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

std::string SceneDocument::readsText() const
{
    std::string out;
    if (reads_)
        for (const auto& [key, value] : reads_->values)
            out += key + " = " + value + "\n";
    return out;
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

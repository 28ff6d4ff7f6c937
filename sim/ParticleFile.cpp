// Particle files: binary PLY writer and a tolerant PLY reader (see ParticleFile.hpp).
#include "sim/ParticleFile.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <type_traits>

#include <unistd.h>

namespace ferro {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
    throw ParticleFileError(path + ": " + reason);
}

bool hostIsLittleEndian() {
    const uint32_t one = 1;
    unsigned char first = 0;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

bool isSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

bool hasSpace(const std::string& s) { return std::any_of(s.begin(), s.end(), isSpace); }

std::string trim(const std::string& s) {
    size_t b = 0, e = s.size();
    while (b < e && isSpace(s[b])) ++b;
    while (e > b && isSpace(s[e - 1])) --e;
    return s.substr(b, e - b);
}

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && isSpace(s[i])) ++i;
        size_t j = i;
        while (j < s.size() && !isSpace(s[j])) ++j;
        if (j > i) out.push_back(s.substr(i, j - i));
        i = j;
    }
    return out;
}

/// Locale-independent number parse of a whole (trimmed) string; std::strtod would follow
/// the C locale's decimal separator.
bool parseDouble(const std::string& text, double& out) {
    const std::string s = trim(text);
    const char* b = s.data();
    const char* e = b + s.size();
    if (b != e && *b == '+') ++b;
    auto r = std::from_chars(b, e, out);
    return r.ec == std::errc() && r.ptr == e && b != e;
}

// ---------------------------------------------------------------------------------------
// Reader
// ---------------------------------------------------------------------------------------

enum class Scalar { I8, U8, I16, U16, I32, U32, F32, F64 };

bool parseScalar(const std::string& name, Scalar& out) {
    static const std::pair<const char*, Scalar> table[] = {
        {"char", Scalar::I8},    {"int8", Scalar::I8},     {"uchar", Scalar::U8},
        {"uint8", Scalar::U8},   {"short", Scalar::I16},   {"int16", Scalar::I16},
        {"ushort", Scalar::U16}, {"uint16", Scalar::U16},  {"int", Scalar::I32},
        {"int32", Scalar::I32},  {"uint", Scalar::U32},    {"uint32", Scalar::U32},
        {"float", Scalar::F32},  {"float32", Scalar::F32}, {"double", Scalar::F64},
        {"float64", Scalar::F64},
    };
    for (const auto& [n, s] : table)
        if (name == n) {
            out = s;
            return true;
        }
    return false;
}

size_t scalarSize(Scalar s) {
    switch (s) {
    case Scalar::I8: case Scalar::U8: return 1;
    case Scalar::I16: case Scalar::U16: return 2;
    case Scalar::I32: case Scalar::U32: case Scalar::F32: return 4;
    case Scalar::F64: return 8;
    }
    return 0;
}

/// double -> float saturating to +-inf: a plain cast of an out-of-range value is undefined.
float toFloat(double v) {
    constexpr double maxF = std::numeric_limits<float>::max();
    if (v > maxF) return std::numeric_limits<float>::infinity();
    if (v < -maxF) return -std::numeric_limits<float>::infinity();
    return static_cast<float>(v);
}

template <typename T>
float load(const unsigned char* p, bool swap) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, p, sizeof(T));
    if (swap) std::reverse(bytes, bytes + sizeof(T));
    T v;
    std::memcpy(&v, bytes, sizeof(T));
    if constexpr (std::is_same_v<T, float>) return v; // keeps NaN payloads bit-exact
    else return toFloat(static_cast<double>(v));
}

float loadScalar(Scalar s, const unsigned char* p, bool swap) {
    switch (s) {
    case Scalar::I8: return load<int8_t>(p, swap);
    case Scalar::U8: return load<uint8_t>(p, swap);
    case Scalar::I16: return load<int16_t>(p, swap);
    case Scalar::U16: return load<uint16_t>(p, swap);
    case Scalar::I32: return load<int32_t>(p, swap);
    case Scalar::U32: return load<uint32_t>(p, swap);
    case Scalar::F32: return load<float>(p, swap);
    case Scalar::F64: return load<double>(p, swap);
    }
    return 0.0f;
}

enum class Format { Ascii, BinaryLE, BinaryBE };

struct Header {
    Format format = Format::Ascii;
    uint64_t vertexCount = 0;
    std::vector<Scalar> types; ///< per vertex property
    ParticleTable table;       ///< names and comments filled, values empty
};

/// Reads one header line (without '\n' and a trailing '\r'). False at end of file or when
/// the line is longer than `maxLen`, which keeps a binary file from being read as a line.
bool readLine(std::istream& in, std::string& line, size_t maxLen) {
    line.clear();
    std::streambuf* buf = in.rdbuf();
    for (;;) {
        const int c = buf->sbumpc();
        if (c == std::char_traits<char>::eof()) return false;
        if (c == '\n') break;
        if (line.size() >= maxLen) return false;
        line.push_back(static_cast<char>(c));
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
}

Header readHeader(std::istream& in, const std::string& path) {
    std::string line;
    if (!readLine(in, line, 16) || trim(line) != "ply") fail(path, "not a PLY file");

    Header h;
    bool haveFormat = false;
    int elements = 0;
    size_t headerBytes = 0;
    constexpr size_t maxHeaderBytes = 1 << 20;
    auto bad = [&](const std::string& why) { fail(path, "bad PLY header: " + why); };

    for (;;) {
        if (!readLine(in, line, maxHeaderBytes)) bad("no end_header");
        headerBytes += line.size() + 1;
        if (headerBytes > maxHeaderBytes) bad("longer than 1 MiB");
        const std::vector<std::string> tok = split(line);
        if (tok.empty()) continue;
        const std::string& key = tok[0];
        if (key == "end_header") break;
        if (key == "comment") {
            // "comment key value...": the value keeps its inner spacing.
            const std::string text = trim(line.substr(line.find("comment") + 7));
            if (text.empty()) continue;
            size_t k = 0;
            while (k < text.size() && !isSpace(text[k])) ++k;
            h.table.comments.emplace_back(text.substr(0, k), trim(text.substr(k)));
        } else if (key == "obj_info") {
            continue;
        } else if (key == "format") {
            if (haveFormat) bad("two format lines");
            if (tok.size() < 2) bad("format line without a format");
            if (tok[1] == "ascii") h.format = Format::Ascii;
            else if (tok[1] == "binary_little_endian") h.format = Format::BinaryLE;
            else if (tok[1] == "binary_big_endian") h.format = Format::BinaryBE;
            else bad("unknown format '" + tok[1] + "'");
            haveFormat = true;
        } else if (key == "element") {
            if (tok.size() != 3) bad("malformed element line '" + line + "'");
            ++elements;
            if (elements == 1) {
                if (tok[1] != "vertex")
                    bad("first element is '" + tok[1] + "', not 'vertex'");
                const std::string& n = tok[2];
                auto r = std::from_chars(n.data(), n.data() + n.size(), h.vertexCount);
                if (r.ec != std::errc() || r.ptr != n.data() + n.size())
                    bad("bad vertex count '" + n + "'");
            }
        } else if (key == "property") {
            if (elements == 0) bad("property before any element");
            if (elements > 1) continue; // later elements are never read
            if (tok.size() >= 2 && tok[1] == "list")
                bad("list property '" + tok.back() + "' in the vertex element");
            if (tok.size() != 3) bad("malformed property line '" + line + "'");
            Scalar s;
            if (!parseScalar(tok[1], s)) bad("unknown property type '" + tok[1] + "'");
            h.types.push_back(s);
            h.table.names.push_back(tok[2]);
        } else {
            bad("unexpected line '" + line + "'");
        }
    }
    if (!haveFormat) bad("no format line");
    if (elements == 0) bad("no vertex element");
    if (h.types.empty() && h.vertexCount > 0) bad("vertex element has no properties");
    return h;
}

void readBinary(std::istream& in, const std::string& path, Header& h) {
    const size_t cols = h.types.size();
    const auto dataStart = in.tellg();
    in.seekg(0, std::ios::end);
    const auto fileEnd = in.tellg();
    in.seekg(dataStart);
    if (dataStart < 0 || fileEnd < 0 || !in) fail(path, "cannot determine the file size");
    const uint64_t available = static_cast<uint64_t>(fileEnd - dataStart);

    size_t rowBytes = 0;
    for (Scalar s : h.types) rowBytes += scalarSize(s);
    const std::string truncated = "truncated (expected " + std::to_string(h.vertexCount) + " vertices)";
    // Compared before allocating, so a corrupt count cannot trigger a huge allocation.
    if (rowBytes > 0 && h.vertexCount > available / rowBytes) fail(path, truncated);
    const size_t n = static_cast<size_t>(h.vertexCount);
    h.table.values.resize(n * cols);

    const bool swap = (h.format == Format::BinaryLE) != hostIsLittleEndian();
    const bool allFloat = std::all_of(h.types.begin(), h.types.end(),
                                      [](Scalar s) { return s == Scalar::F32; });
    if (allFloat && !swap) {
        // The common case (Ferro's own files): one read straight into the table.
        in.read(reinterpret_cast<char*>(h.table.values.data()),
                static_cast<std::streamsize>(n * rowBytes));
        if (static_cast<size_t>(in.gcount()) != n * rowBytes) fail(path, truncated);
        return;
    }
    std::vector<unsigned char> bytes(n * rowBytes);
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (static_cast<size_t>(in.gcount()) != bytes.size()) fail(path, truncated);
    const unsigned char* p = bytes.data();
    float* out = h.table.values.data();
    for (size_t r = 0; r < n; ++r)
        for (size_t c = 0; c < cols; ++c) {
            *out++ = loadScalar(h.types[c], p, swap);
            p += scalarSize(h.types[c]);
        }
}

void readAscii(std::istream& in, const std::string& path, Header& h) {
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const size_t cols = h.types.size();
    const char* p = text.data();
    const char* end = p + text.size();
    // Every value needs at least two characters (digit and separator); checked before
    // allocating so that a corrupt count cannot trigger a huge allocation.
    const std::string truncated = "truncated (expected " + std::to_string(h.vertexCount) + " vertices)";
    if (cols > 0 && h.vertexCount > (text.size() + 1) / (2 * cols)) fail(path, truncated);
    const size_t total = static_cast<size_t>(h.vertexCount) * cols;
    h.table.values.resize(total);
    for (size_t i = 0; i < total; ++i) {
        while (p < end && isSpace(*p)) ++p;
        if (p == end) fail(path, truncated);
        if (*p == '+') ++p;
        double v = 0;
        auto r = std::from_chars(p, end, v);
        if (r.ec != std::errc() || (r.ptr < end && !isSpace(*r.ptr)))
            fail(path, "bad ascii value in vertex " + std::to_string(i / cols));
        h.table.values[i] = toFloat(v);
        p = r.ptr;
    }
}

// ---------------------------------------------------------------------------------------
// Writer
// ---------------------------------------------------------------------------------------

std::string makeHeader(const std::string& path, const ParticleTable& table) {
    const size_t cols = table.columns();
    if (cols == 0 ? !table.values.empty() : table.values.size() % cols != 0)
        fail(path, std::to_string(table.values.size()) + " values do not fill rows of " +
                       std::to_string(cols) + " columns");
    std::string header = "ply\nformat binary_little_endian 1.0\n";
    for (const auto& [key, value] : table.comments) {
        if (key.empty() || hasSpace(key)) fail(path, "bad comment key '" + key + "'");
        if (value.find_first_of("\r\n") != std::string::npos)
            fail(path, "comment '" + key + "' has a line break in its value");
        header += "comment " + key + (value.empty() ? "" : " " + value) + "\n";
    }
    header += "element vertex " + std::to_string(table.rows()) + "\n";
    for (const std::string& name : table.names) {
        if (name.empty() || hasSpace(name)) fail(path, "bad property name '" + name + "'");
        header += "property float " + name + "\n";
    }
    header += "end_header\n";
    return header;
}

/// Writes all of `data`; false (errno set) on failure.
bool writeAll(std::FILE* f, const void* data, size_t bytes) {
    return bytes == 0 || std::fwrite(data, 1, bytes, f) == bytes;
}

} // namespace

// ---------------------------------------------------------------------------------------

int ParticleTable::column(const std::string& name) const {
    for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == name) return static_cast<int>(i);
    return -1;
}

std::string ParticleTable::comment(const std::string& key, const std::string& def) const {
    for (const auto& [k, v] : comments)
        if (k == key) return v;
    return def;
}

double ParticleTable::commentNumber(const std::string& key, double def) const {
    for (const auto& [k, v] : comments)
        if (k == key) {
            double x;
            // A present but malformed value is an error, not silently the default: it
            // usually means the file came from an incompatible writer.
            if (!parseDouble(v, x))
                throw ParticleFileError("comment '" + key + "' is not a number: '" + v + "'");
            return x;
        }
    return def;
}

void ParticleTable::setComment(const std::string& key, const std::string& value) {
    auto it = std::find_if(comments.begin(), comments.end(),
                           [&](const auto& c) { return c.first == key; });
    if (it == comments.end()) {
        comments.emplace_back(key, value);
        return;
    }
    it->second = value;
    // Later duplicates would contradict the new value for readers that take the last one.
    comments.erase(std::remove_if(it + 1, comments.end(),
                                  [&](const auto& c) { return c.first == key; }),
                   comments.end());
}

std::vector<Vec3> ParticleTable::vec3(const std::string& a, const std::string& b,
                                      const std::string& c) const {
    const int ia = column(a), ib = column(b), ic = column(c);
    for (const auto& [name, index] : {std::pair{a, ia}, std::pair{b, ib}, std::pair{c, ic}})
        if (index < 0) throw ParticleFileError("particle table has no column '" + name + "'");
    std::vector<Vec3> out(rows());
    for (size_t r = 0; r < out.size(); ++r) out[r] = Vec3(at(r, ia), at(r, ib), at(r, ic));
    return out;
}

void writeParticleFile(const std::string& path, const ParticleTable& table) {
    const std::string header = makeHeader(path, table);
    const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) fail(path, "cannot create " + tmp + ": " + std::strerror(errno));

    auto abandon = [&](const char* what) {
        const int err = errno;
        if (f) std::fclose(f);
        std::remove(tmp.c_str());
        fail(path, std::string(what) + ": " + std::strerror(err));
    };
    if (!writeAll(f, header.data(), header.size())) abandon("write failed");
    const size_t count = table.values.size();
    if (hostIsLittleEndian()) {
        if (!writeAll(f, table.values.data(), count * sizeof(float))) abandon("write failed");
    } else {
        // Byte-swap through a bounded buffer rather than a copy of the whole table.
        std::vector<unsigned char> chunk;
        constexpr size_t chunkFloats = 1 << 16;
        for (size_t i = 0; i < count; i += chunkFloats) {
            const size_t m = std::min(chunkFloats, count - i);
            chunk.resize(m * sizeof(float));
            std::memcpy(chunk.data(), table.values.data() + i, chunk.size());
            for (size_t k = 0; k < m; ++k) std::reverse(&chunk[4 * k], &chunk[4 * k] + 4);
            if (!writeAll(f, chunk.data(), chunk.size())) abandon("write failed");
        }
    }
    const int closed = std::fclose(f);
    f = nullptr;
    if (closed != 0) abandon("write failed");
    if (std::rename(tmp.c_str(), path.c_str()) != 0) abandon("cannot rename the temporary file");
}

ParticleTable readParticleFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, "cannot open");
    Header h = readHeader(in, path);
    if (h.format == Format::Ascii) readAscii(in, path, h);
    else readBinary(in, path, h);
    return std::move(h.table);
}

std::string framePath(const std::string& pattern, int frame) {
    // Recognised placeholders: {} {:N} {:0N} {:d} {:0Nd} (Python/fmt) and %d %Nd %0Nd (printf).
    // Width is at most two digits; anything else is copied literally.
    auto placeholder = [&](size_t i, size_t& len, int& width, bool& zero) {
        const char open = pattern[i];
        size_t j = i + 1;
        if (open == '{') {
            if (j < pattern.size() && pattern[j] == '}') {
                len = 2, width = 0, zero = false;
                return true;
            }
            if (j >= pattern.size() || pattern[j] != ':') return false;
            ++j;
        } else if (open != '%') {
            return false;
        }
        zero = j < pattern.size() && pattern[j] == '0';
        if (zero) ++j;
        width = 0;
        size_t digits = 0;
        while (j < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[j])) && digits < 2)
            width = width * 10 + (pattern[j++] - '0'), ++digits;
        const bool d = j < pattern.size() && pattern[j] == 'd';
        if (d) ++j;
        if (open == '%') {
            if (!d) return false;
        } else {
            if (j >= pattern.size() || pattern[j] != '}') return false;
            ++j;
        }
        len = j - i;
        return true;
    };

    std::string out;
    for (size_t i = 0; i < pattern.size();) {
        size_t len;
        int width;
        bool zero;
        if (placeholder(i, len, width, zero)) {
            char buf[48];
            std::snprintf(buf, sizeof buf, zero ? "%0*d" : "%*d", width, frame);
            out += buf;
            i += len;
        } else {
            out += pattern[i++];
        }
    }
    return out;
}

FrameRange parseFrameRange(const std::string& text) {
    auto bad = [&](const std::string& why) {
        return std::invalid_argument("'" + text + "': " + why);
    };
    // One number of at most 7 digits (leading zeros allowed), surrounded by optional spaces.
    auto number = [&](const std::string& part) {
        const std::string t = trim(part);
        if (t.empty() || !std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; }))
            throw bad(t.size() > 0 && t[0] == '-' ? "frames cannot be negative" : "expected FIRST:LAST with non-negative integers");
        const size_t lead = std::min(t.find_first_not_of('0'), t.size() - 1);
        if (t.size() - lead > 7) throw bad("frame numbers above " + std::to_string(kMaxFrame) + " are not supported");
        return std::stoi(t.substr(lead));
    };
    const size_t colon = text.find(':');
    FrameRange r;
    r.first = number(text.substr(0, colon));
    r.last = colon == std::string::npos ? r.first : number(text.substr(colon + 1));
    if (r.last < r.first) throw bad("LAST must not be before FIRST");
    return r;
}

} // namespace ferro

// Particle files: binary PLY writer and a tolerant PLY reader (see ParticleFile.hpp).
#include "sim/core/ParticleFile.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/core/ErrorText.hpp"
#include "sim/core/PlyHeader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <type_traits>

namespace ferro {

ParticleFileError::ParticleFileError(const std::string& what) : std::runtime_error(escapeControl(what)) {}

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
    throw ParticleFileError(path + ": " + reason);
}

bool isSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

bool hasSpace(const std::string& s) { return std::any_of(s.begin(), s.end(), isSpace); }

std::string trim(const std::string& s) {
    size_t b = 0, e = s.size();
    while (b < e && isSpace(s[b])) ++b;
    while (e > b && isSpace(s[e - 1])) --e;
    return s.substr(b, e - b);
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

float loadScalar(PlyScalar s, const unsigned char* p, bool swap) {
    switch (s) {
    case PlyScalar::Int8: return load<int8_t>(p, swap);
    case PlyScalar::UInt8: return load<uint8_t>(p, swap);
    case PlyScalar::Int16: return load<int16_t>(p, swap);
    case PlyScalar::UInt16: return load<uint16_t>(p, swap);
    case PlyScalar::Int32: return load<int32_t>(p, swap);
    case PlyScalar::UInt32: return load<uint32_t>(p, swap);
    case PlyScalar::Float32: return load<float>(p, swap);
    case PlyScalar::Float64: return load<double>(p, swap);
    }
    return 0.0f;
}

struct Header {
    PlyFormat format = PlyFormat::Ascii;
    uint64_t vertexCount = 0;
    std::vector<PlyScalar> types; ///< per vertex property
    ParticleTable table;          ///< names and comments filled, values empty
};

/// The PLY header with what a particle file needs of it: a first element `vertex` whose
/// properties are all scalars; later elements are never read.
Header readHeader(std::istream& in, const std::string& path) {
    PlyHeader ply;
    try {
        ply = readPlyHeader(in);
    } catch (const PlyHeaderError& e) {
        fail(path, e.what());
    }
    auto bad = [&](const std::string& why) { fail(path, "bad PLY header: " + why); };
    if (ply.elements.empty()) bad("no vertex element");
    const PlyElement& vertex = ply.elements.front();
    if (vertex.name != "vertex") bad("first element is '" + vertex.name + "', not 'vertex'");

    Header h;
    h.format = ply.format;
    h.vertexCount = vertex.count;
    for (const PlyProperty& p : vertex.properties) {
        if (p.isList) bad("list property '" + p.name + "' in the vertex element");
        h.types.push_back(p.type);
        h.table.names.push_back(p.name);
    }
    if (h.types.empty() && h.vertexCount > 0) bad("vertex element has no properties");
    h.table.comments = std::move(ply.comments);
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
    for (PlyScalar s : h.types) rowBytes += plyScalarBytes(s);
    const std::string truncated = "truncated (expected " + std::to_string(h.vertexCount) + " vertices)";
    // Compared before allocating, so a corrupt count cannot trigger a huge allocation.
    if (rowBytes > 0 && h.vertexCount > available / rowBytes) fail(path, truncated);
    const size_t n = static_cast<size_t>(h.vertexCount);
    h.table.values.resize(n * cols);

    const bool swap = (h.format == PlyFormat::BinaryLittleEndian) != hostIsLittleEndian();
    const bool allFloat = std::all_of(h.types.begin(), h.types.end(),
                                      [](PlyScalar s) { return s == PlyScalar::Float32; });
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
            p += plyScalarBytes(h.types[c]);
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

/// `comments`: the lines to write instead of table.comments (null: the table's).
std::string makeHeader(const std::string& path, const ParticleTable& table,
                       const std::vector<std::pair<std::string, std::string>>* comments = nullptr) {
    const size_t cols = table.columns();
    if (cols == 0 ? !table.values.empty() : table.values.size() % cols != 0)
        fail(path, std::to_string(table.values.size()) + " values do not fill rows of " +
                       std::to_string(cols) + " columns");
    std::string header;
    try {
        header = binaryPlyHeaderStart(comments ? *comments : table.comments);
    } catch (const std::invalid_argument& e) {
        fail(path, e.what());
    }
    header += "element vertex " + std::to_string(table.rows()) + "\n";
    for (const std::string& name : table.names) {
        if (name.empty() || hasSpace(name)) fail(path, "bad property name '" + name + "'");
        const bool q = std::find(table.quantized.begin(), table.quantized.end(), name) != table.quantized.end();
        header += std::string(q ? "property short " : "property float ") + name + "\n";
    }
    header += "end_header\n";
    return header;
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

namespace {

/// The comment lines to write: the table's, with a scale line per quantized column (older
/// ones dropped); scales[c] > 0 for a quantized column, 0 for a float one.
std::vector<std::pair<std::string, std::string>> withScales(const std::string& path, const ParticleTable& table,
                                                            std::vector<float>& scales) {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& c : table.comments)
        if (c.first != "quantized") out.push_back(c);
    const size_t cols = table.columns(), rows = table.rows();
    scales.assign(cols, 0.0f);
    for (const std::string& name : table.quantized) {
        const int c = table.column(name);
        if (c < 0) fail(path, "quantized column '" + name + "' is not a column");
        float maxAbs = 0;
        for (size_t r = 0; r < rows; ++r) {
            const float v = table.at(r, c);
            if (!std::isfinite(v)) fail(path, "column '" + name + "' holds " + std::to_string(v) + ": cannot quantize it");
            maxAbs = std::max(maxAbs, std::fabs(v));
        }
        const float scale = maxAbs > 0 ? maxAbs / 32767.0f : 1.0f;
        scales[size_t(c)] = scale;
        char text[64];
        std::snprintf(text, sizeof text, "%s %.9g", name.c_str(), double(scale));
        out.emplace_back("quantized", text);
    }
    return out;
}

} // namespace

void writeParticleFile(const std::string& path, const ParticleTable& table) {
    std::vector<float> scales;
    const auto comments = table.quantized.empty() ? table.comments : withScales(path, table, scales);
    const std::string header = makeHeader(path, table, &comments);
    const size_t count = table.values.size();
    const size_t cols = table.columns();
    try {
        writeFileAtomically(path, [&](std::ostream& out) {
            out.write(header.data(), static_cast<std::streamsize>(header.size()));
            if (!table.quantized.empty()) {
                // Mixed rows (floats and shorts), little-endian, through a bounded buffer.
                std::vector<unsigned char> chunk;
                const size_t rows = table.rows();
                constexpr size_t chunkRows = 1 << 14;
                for (size_t r0 = 0; r0 < rows && out; r0 += chunkRows) {
                    chunk.clear();
                    for (size_t r = r0; r < std::min(rows, r0 + chunkRows); ++r)
                        for (size_t c = 0; c < cols; ++c) {
                            const float v = table.values[r * cols + c];
                            unsigned char b[4];
                            if (scales[c] > 0) {
                                const long q = std::clamp(std::lround(double(v) / double(scales[c])), -32767L, 32767L);
                                const uint16_t u = static_cast<uint16_t>(static_cast<int16_t>(q));
                                b[0] = static_cast<unsigned char>(u & 0xff);
                                b[1] = static_cast<unsigned char>(u >> 8);
                                chunk.insert(chunk.end(), b, b + 2);
                            } else {
                                uint32_t u;
                                std::memcpy(&u, &v, 4);
                                for (int k = 0; k < 4; ++k) b[k] = static_cast<unsigned char>(u >> (8 * k));
                                chunk.insert(chunk.end(), b, b + 4);
                            }
                        }
                    out.write(reinterpret_cast<const char*>(chunk.data()), static_cast<std::streamsize>(chunk.size()));
                }
                return;
            }
            if (hostIsLittleEndian()) {
                out.write(reinterpret_cast<const char*>(table.values.data()),
                          static_cast<std::streamsize>(count * sizeof(float)));
                return;
            }
            // Byte-swap through a bounded buffer rather than a copy of the whole table.
            std::vector<char> chunk;
            constexpr size_t chunkFloats = 1 << 16;
            for (size_t i = 0; i < count && out; i += chunkFloats) {
                const size_t m = std::min(chunkFloats, count - i);
                chunk.resize(m * sizeof(float));
                std::memcpy(chunk.data(), table.values.data() + i, chunk.size());
                for (size_t k = 0; k < m; ++k) std::reverse(&chunk[4 * k], &chunk[4 * k] + 4);
                out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
            }
        });
    } catch (const AtomicFileError& e) {
        fail(path, e.what());
    }
}

ParticleTable readParticleFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, "cannot open");
    Header h = readHeader(in, path);
    if (h.format == PlyFormat::Ascii) readAscii(in, path, h);
    else readBinary(in, path, h);
    // Quantized columns (ParticleTable::quantized): back to their values; the comments that
    // described the encoding go, so that a table written again is not scaled twice.
    ParticleTable& t = h.table;
    std::vector<std::pair<std::string, std::string>> kept;
    for (const auto& [key, value] : t.comments) {
        if (key != "quantized") { kept.emplace_back(key, value); continue; }
        const size_t space = value.find(' ');
        double scale = 0;
        const int c = space == std::string::npos ? -1 : t.column(value.substr(0, space));
        if (c < 0 || !parseDouble(value.substr(space + 1), scale) || !(scale > 0) || !std::isfinite(scale))
            fail(path, "bad 'comment quantized " + value + "' (expected a column and a scale > 0)");
        const float s = static_cast<float>(scale);
        for (size_t r = 0; r < t.rows(); ++r) t.values[r * t.columns() + size_t(c)] *= s;
    }
    t.comments = std::move(kept);
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

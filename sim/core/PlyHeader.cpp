// PLY header parsing (see PlyHeader.hpp).
#include "sim/core/PlyHeader.hpp"

#include "sim/core/ErrorText.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>
#include <istream>

namespace ferro {

namespace {

bool isSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

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

bool parseScalar(const std::string& name, PlyScalar& out) {
    static const std::pair<const char*, PlyScalar> table[] = {
        {"char", PlyScalar::Int8},      {"int8", PlyScalar::Int8},       {"uchar", PlyScalar::UInt8},
        {"uint8", PlyScalar::UInt8},    {"short", PlyScalar::Int16},     {"int16", PlyScalar::Int16},
        {"ushort", PlyScalar::UInt16},  {"uint16", PlyScalar::UInt16},   {"int", PlyScalar::Int32},
        {"int32", PlyScalar::Int32},    {"uint", PlyScalar::UInt32},     {"uint32", PlyScalar::UInt32},
        {"float", PlyScalar::Float32},  {"float32", PlyScalar::Float32}, {"double", PlyScalar::Float64},
        {"float64", PlyScalar::Float64},
    };
    for (const auto& [n, s] : table)
        if (name == n) {
            out = s;
            return true;
        }
    return false;
}

enum class LineEnd { Break, EndOfFile, TooLong };

/// Reads one header line into `line` (without "\n" and a trailing "\r"), adding the bytes
/// taken from the stream to `consumed`. Stops at a line break, at the end of the stream, or
/// when the line would exceed `maxLen`, which keeps a binary file from being read as a line.
LineEnd readLine(std::istream& in, std::string& line, size_t maxLen, uint64_t& consumed) {
    line.clear();
    std::streambuf* buf = in.rdbuf();
    for (;;) {
        const int c = buf->sbumpc();
        if (c == std::char_traits<char>::eof()) return LineEnd::EndOfFile;
        ++consumed;
        if (c == '\n') break;
        if (line.size() >= maxLen) return LineEnd::TooLong;
        line.push_back(static_cast<char>(c));
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return LineEnd::Break;
}

} // namespace

PlyHeaderError::PlyHeaderError(Kind kind, const std::string& what)
    : std::runtime_error(escapeControl(what)), kind_(kind) {}

bool hostIsLittleEndian() {
    const uint32_t one = 1;
    unsigned char first = 0;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

size_t plyScalarBytes(PlyScalar s) {
    switch (s) {
    case PlyScalar::Int8: case PlyScalar::UInt8: return 1;
    case PlyScalar::Int16: case PlyScalar::UInt16: return 2;
    case PlyScalar::Int32: case PlyScalar::UInt32: case PlyScalar::Float32: return 4;
    case PlyScalar::Float64: return 8;
    }
    return 0;
}

std::string binaryPlyHeaderStart(const std::vector<std::pair<std::string, std::string>>& comments) {
    std::string header = "ply\nformat binary_little_endian 1.0\n";
    for (const auto& [key, value] : comments) {
        if (key.empty() || std::any_of(key.begin(), key.end(), isSpace))
            throw std::invalid_argument("bad comment key '" + key + "'");
        if (value.find_first_of("\r\n") != std::string::npos)
            throw std::invalid_argument("comment '" + key + "' has a line break in its value");
        header += "comment " + key + (value.empty() ? "" : " " + value) + "\n";
    }
    return header;
}

PlyHeader readPlyHeader(std::istream& in) {
    PlyHeader h;
    std::string line;
    if (readLine(in, line, 16, h.dataOffset) != LineEnd::Break || trim(line) != "ply")
        throw PlyHeaderError(PlyHeaderError::Kind::NotPly, "not a PLY file");

    bool haveFormat = false;
    constexpr size_t maxHeaderBytes = 1 << 20;
    auto bad = [](const std::string& why) {
        return PlyHeaderError(PlyHeaderError::Kind::Malformed, "bad PLY header: " + why);
    };
    auto scalar = [&](const std::string& name) {
        PlyScalar s;
        if (!parseScalar(name, s)) throw bad("unknown property type '" + name + "'");
        return s;
    };

    for (;;) {
        const LineEnd end = readLine(in, line, maxHeaderBytes, h.dataOffset);
        if (end == LineEnd::EndOfFile && split(line) == std::vector<std::string>{"end_header"})
            throw PlyHeaderError(PlyHeaderError::Kind::EndWithoutLineBreak, "bad PLY header: no end_header");
        if (end != LineEnd::Break) throw bad("no end_header");
        if (h.dataOffset > maxHeaderBytes) throw bad("longer than 1 MiB");
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
            h.comments.emplace_back(text.substr(0, k), trim(text.substr(k)));
        } else if (key == "obj_info") {
            continue;
        } else if (key == "format") {
            if (haveFormat) throw bad("two format lines");
            if (tok.size() < 2) throw bad("format line without a format");
            if (tok[1] == "ascii") h.format = PlyFormat::Ascii;
            else if (tok[1] == "binary_little_endian") h.format = PlyFormat::BinaryLittleEndian;
            else if (tok[1] == "binary_big_endian") h.format = PlyFormat::BinaryBigEndian;
            else throw bad("unknown format '" + tok[1] + "'");
            haveFormat = true;
        } else if (key == "element") {
            if (tok.size() != 3) throw bad("malformed element line '" + line + "'");
            PlyElement e;
            e.name = tok[1];
            const std::string& n = tok[2];
            auto r = std::from_chars(n.data(), n.data() + n.size(), e.count);
            if (r.ec != std::errc() || r.ptr != n.data() + n.size())
                throw bad("bad " + e.name + " count '" + n + "'");
            h.elements.push_back(std::move(e));
        } else if (key == "property") {
            if (h.elements.empty()) throw bad("property before any element");
            PlyProperty p;
            if (tok.size() >= 2 && tok[1] == "list") {
                if (tok.size() != 5) throw bad("malformed property line '" + line + "'");
                p.isList = true;
                p.countType = scalar(tok[2]);
                p.type = scalar(tok[3]);
            } else {
                if (tok.size() != 3) throw bad("malformed property line '" + line + "'");
                p.type = scalar(tok[1]);
            }
            p.name = tok.back();
            h.elements.back().properties.push_back(std::move(p));
        } else {
            throw bad("unexpected line '" + line + "'");
        }
    }
    if (!haveFormat) throw bad("no format line");
    return h;
}

} // namespace ferro

// The shared PLY header reader (sim/core/PlyHeader): elements, properties, lists, comments, the
// offset of the data, and one-line errors that tell "not PLY" from "broken PLY".
#include "sim/core/PlyHeader.hpp"

#include <catch2/catch.hpp>

#include <sstream>

using namespace ferro;

namespace {

PlyHeaderError::Kind errorKind(const std::string& text, std::string* what = nullptr) {
    std::istringstream in(text);
    try {
        readPlyHeader(in);
    } catch (const PlyHeaderError& e) {
        if (what) *what = e.what();
        return e.kind();
    }
    FAIL("no error for '" << text << "'");
    return PlyHeaderError::Kind::NotPly;
}

} // namespace

TEST_CASE("readPlyHeader reads elements, properties, lists and comments", "[io][ply]") {
    const std::string header = "ply\r\nformat binary_big_endian 1.0\r\ncomment frame  12\r\nobj_info by hand\r\n"
                               "element vertex 3\r\nproperty float x\r\nproperty double y\r\n"
                               "comment note two  spaced words\r\n"
                               "element face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n";
    std::istringstream in(header + "DATA");
    const PlyHeader h = readPlyHeader(in);
    CHECK(h.format == PlyFormat::BinaryBigEndian);
    CHECK(h.comments == std::vector<std::pair<std::string, std::string>>{{"frame", "12"}, {"note", "two  spaced words"}});
    REQUIRE(h.elements.size() == 2);
    CHECK(h.elements[0].name == "vertex");
    CHECK(h.elements[0].count == 3);
    REQUIRE(h.elements[0].properties.size() == 2);
    CHECK(h.elements[0].properties[1].name == "y");
    CHECK(h.elements[0].properties[1].type == PlyScalar::Float64);
    CHECK_FALSE(h.elements[0].properties[1].isList);
    REQUIRE(h.elements[1].properties.size() == 1);
    const PlyProperty& list = h.elements[1].properties[0];
    CHECK(list.isList);
    CHECK(list.countType == PlyScalar::UInt8);
    CHECK(list.type == PlyScalar::Int32);
    CHECK(list.name == "vertex_indices");
    CHECK(h.dataOffset == header.size());
    std::string rest;
    in >> rest;
    CHECK(rest == "DATA"); // the stream is left at the first data byte
    CHECK(plyScalarBytes(PlyScalar::Float64) == 8);
    CHECK(plyScalarBytes(PlyScalar::UInt16) == 2);
}

TEST_CASE("readPlyHeader errors: other formats, broken headers, a last line without its break", "[io][ply]") {
    const std::string head = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n";
    std::string what;
    CHECK(errorKind("", &what) == PlyHeaderError::Kind::NotPly);
    CHECK(what == "not a PLY file");
    CHECK(errorKind("solid cube\nfacet normal 0 0 1\n") == PlyHeaderError::Kind::NotPly);
    CHECK(errorKind(std::string(4096, 'p')) == PlyHeaderError::Kind::NotPly); // no 4 KiB "line"

    CHECK(errorKind(head, &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: no end_header");
    CHECK(errorKind(head + "end_header", &what) == PlyHeaderError::Kind::EndWithoutLineBreak);
    CHECK(what == "bad PLY header: no end_header");
    CHECK(errorKind("ply\nelement vertex 1\nproperty float x\nend_header\n", &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: no format line");
    CHECK(errorKind(head + "format ascii 1.0\nend_header\n", &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: two format lines");
    CHECK(errorKind("ply\nformat ascii 1.0\nelement vertex -5\nend_header\n", &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: bad vertex count '-5'");
    CHECK(errorKind(head + "property quad q\nend_header\n", &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: unknown property type 'quad'");
    CHECK(errorKind("ply\nformat ascii 1.0\nproperty float x\nend_header\n", &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: property before any element");
    CHECK(errorKind(head + "property list uchar idx\nend_header\n") == PlyHeaderError::Kind::Malformed);
    CHECK(errorKind(head + "texture cube.png\nend_header\n", &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: unexpected line 'texture cube.png'");
    // A lone carriage return inside a quoted line is escaped: the message stays one line.
    CHECK(errorKind(head + "texture a\rb\x01\nend_header\n", &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: unexpected line 'texture a\\rb\\x01'");
    // A header of more than 1 MiB of comments is refused before it is all kept.
    std::string huge = head;
    while (huge.size() <= (1u << 20)) huge += "comment " + std::string(1000, 'c') + "\n";
    CHECK(errorKind(huge + "end_header\n", &what) == PlyHeaderError::Kind::Malformed);
    CHECK(what == "bad PLY header: longer than 1 MiB");
}

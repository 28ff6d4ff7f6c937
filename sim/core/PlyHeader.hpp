#pragma once
// The header of a PLY file (Turk's polygon file format), as the particle reader
// (sim/core/ParticleFile) and the mesh reader (sim/core/TriangleMesh) both read it.
//
//     ply
//     format binary_little_endian 1.0        (or ascii, binary_big_endian)
//     comment frame 12                        (any number, anywhere; `comment key value`)
//     obj_info ...                            (ignored)
//     element vertex 1000
//     property float x                        (scalar: char uchar short ushort int uint float
//     property list uchar int vertex_indices   double, or int8 ... float64)
//     end_header
//
// The reader only parses; what a caller requires of the elements (e.g. that the first one is
// `vertex` without list properties) it checks itself. Nothing is allocated from the counts in
// the header: they are the caller's to check against the bytes that follow.
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ferro {

/// A header that is not PLY or not well formed. what() is one line: "not a PLY file" or
/// "bad PLY header: <reason>".
class PlyHeaderError : public std::runtime_error {
public:
    enum class Kind {
        NotPly,            ///< the first line is not `ply`: some other format
        Malformed,         ///< a PLY header with a bad line, or one that ends before end_header
        EndWithoutLineBreak ///< `end_header` is the file's last line and has no line break
    };
    /// Control characters in `what` (a quoted header line may hold a lone "\r") are escaped.
    PlyHeaderError(Kind kind, const std::string& what);
    Kind kind() const { return kind_; }

private:
    Kind kind_;
};

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

enum class PlyScalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

/// True when this machine stores numbers little-endian, so that binary_little_endian data
/// can be copied to and from memory as it is.
bool hostIsLittleEndian();

/// Bytes of one binary value of type `s`.
size_t plyScalarBytes(PlyScalar s);

struct PlyProperty {
    std::string name;
    PlyScalar type = PlyScalar::Float32;      ///< the value type; for a list, its items' type
    bool isList = false;
    PlyScalar countType = PlyScalar::UInt8;   ///< a list's length type (lists only)
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;                       ///< as declared; not checked against the file size
    std::vector<PlyProperty> properties;      ///< in file order
};

struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<std::pair<std::string, std::string>> comments; ///< `comment key value`, in order;
                                                               ///< the value keeps inner spacing
    std::vector<PlyElement> elements;                          ///< in file order
    uint64_t dataOffset = 0; ///< bytes from the start of the file to the first data byte
};

/// Reads a PLY header from `in`, leaving `in` at the first data byte (dataOffset bytes after
/// where it started). Lines may end in "\n" or "\r\n". The first line may be at most 16
/// bytes and the header at most 1 MiB, so a large file of another format is never read as
/// a line. Exactly one format line is required.
/// @throw PlyHeaderError with a one-line reason (see its Kind).
PlyHeader readPlyHeader(std::istream& in);

/// The start of a binary little-endian PLY header as Ferro writes it: "ply", the format line
/// and one `comment key value` line per comment (`comment key` for an empty value), which
/// readPlyHeader reads back as the same keys and (trimmed) values. Element and property lines
/// and "end_header" are the caller's to append.
/// @throw std::invalid_argument "bad comment key '<key>'" (empty or with white space) or
///        "comment '<key>' has a line break in its value".
std::string binaryPlyHeaderStart(const std::vector<std::pair<std::string, std::string>>& comments);

} // namespace ferro

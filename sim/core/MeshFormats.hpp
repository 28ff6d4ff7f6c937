#pragma once
// Internal to sim/core: the mesh file formats behind readMesh and writeMesh (TriangleMesh.hpp):
// our binary PLY (MeshPly.cpp) and everything else through assimp (MeshAssimp.cpp), and the
// small helpers they share.
#include "sim/core/TriangleMesh.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/core/ErrorText.hpp"
#include "sim/core/PlyHeader.hpp"

#include <cctype>
#include <istream>
#include <string>
#include <utility>
#include <vector>

namespace ferro {
namespace mesh_detail {

[[noreturn]] inline void fail(const std::string& path, const std::string& reason, int code = kExitBadInput) {
    throw MeshFileError(path + ": " + reason, code);
}

inline std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

inline std::string extensionOf(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    const size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
    return lower(path.substr(dot + 1));
}

/// Checks that every index names a vertex: a bad index would crash whoever reads the file.
inline void checkIndices(const std::string& path, const TriangleMesh& mesh) {
    const size_t n = mesh.vertices.size();
    for (const auto& t : mesh.triangles)
        for (uint32_t i : t)
            if (i >= n)
                fail(path, "triangle index " + std::to_string(i) + " out of range (" +
                               std::to_string(n) + " vertices)");
}

/// Writes the byte ranges `parts` one after another to `path` atomically (see
/// sim/core/AtomicFile.hpp), so readers never see a half-written mesh.
inline void writeParts(const std::string& path, const std::vector<std::pair<const void*, size_t>>& parts) {
    try {
        writeFileAtomically(path, [&](std::ostream& out) {
            for (const auto& [data, size] : parts)
                out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
        });
    } catch (const AtomicFileError& e) {
        fail(path, e.what(), kExitIoError);
    }
}

/// Our binary little-endian PLY (MeshPly.cpp).
void writePly(const std::string& path, const TriangleMesh& mesh);
void checkPlyCounts(const std::string& path, const PlyHeader& h, std::istream& in);
void checkPlyLists(const std::string& path, const PlyHeader& h, std::istream& in);
/// Reads the PLY our writer makes (and any with the same layout); false: not that layout.
bool readOwnPly(const std::string& path, const PlyHeader& h, std::istream& in, TriangleMesh& mesh);

/// assimp (MeshAssimp.cpp).
std::string assimpFormatId(const std::string& format);
void writeWithAssimp(const std::string& path, const TriangleMesh& mesh, const std::string& id);
TriangleMesh readWithAssimp(const std::string& path);

} // namespace mesh_detail
} // namespace ferro

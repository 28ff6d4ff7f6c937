// Fuzz target: the mesh reader (readMesh): our binary PLY fast path, the PLY header checks,
// and assimp for every other layout and format.
//
// Input encoding: the first byte picks the file name's extension, which is how readMesh
// (and assimp) choose the importer: byte % 3 = 0 "ply", 1 "obj", 2 "stl" (the formats the
// scene's container.file documents). The remaining bytes are the file.
//
// The documented error is MeshFileError (one line naming the file). A mesh it returns has
// every triangle index in range and either no normals or one per vertex.
#include "tests/fuzz/FuzzTarget.hpp"

#include "sim/core/TriangleMesh.hpp"

using namespace ferro;
using ferro::fuzz::finding;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    static const char* const extensions[] = {"ply", "obj", "stl"};
    const std::string path = fuzz::writeInput(std::string("input.") + extensions[data[0] % 3], data + 1, size - 1);
    TriangleMesh mesh;
    try {
        mesh = readMesh(path);
    } catch (const MeshFileError& e) {
        fuzz::requireOneLine(e);
        return 0;
    }
    for (const auto& t : mesh.triangles)
        for (uint32_t i : t)
            if (i >= mesh.vertices.size())
                finding("triangle index " + std::to_string(i) + " of " + std::to_string(mesh.vertices.size()));
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.vertices.size())
        finding(std::to_string(mesh.normals.size()) + " normals for " + std::to_string(mesh.vertices.size()) +
                " vertices");
    return 0;
}

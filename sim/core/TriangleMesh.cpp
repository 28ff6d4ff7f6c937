// Mesh files (see TriangleMesh.hpp): readMesh and writeMesh pick the format (MeshFormats.hpp),
// and the mesh geometry helpers.
#include "sim/core/TriangleMesh.hpp"

#include "sim/core/MeshFormats.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

namespace ferro {

using namespace mesh_detail;

void writeMesh(const std::string& path, const TriangleMesh& mesh, const std::string& format) {
    const std::string requested = format.empty() ? extensionOf(path) : lower(format);
    checkIndices(path, mesh);
    if (requested.empty()) fail(path, "no mesh format given and the file name has no extension");
    if (requested == "ply" || requested == "plyb") {
        writePly(path, mesh);
        return;
    }
    const std::string id = assimpFormatId(requested);
    if (id.empty()) fail(path, "unknown mesh format '" + requested + "'");
    writeWithAssimp(path, mesh, id);
}

TriangleMesh readMesh(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno), kExitIoError);
    // A PLY header is read by us (comments, count checks); any other format goes to assimp.
    PlyHeader header;
    bool isPly = true;
    try {
        header = readPlyHeader(in);
    } catch (const PlyHeaderError& e) {
        if (e.kind() == PlyHeaderError::Kind::EndWithoutLineBreak)
            fail(path, "truncated (the header ends without a line break)");
        if (e.kind() == PlyHeaderError::Kind::Malformed) fail(path, e.what());
        // Not PLY by its first line, but a file named .ply or starting with "ply" would still
        // reach assimp's PLY importer, without the count checks below (a face count of
        // 4294967295 after "ply@" crashed it).
        in.clear();
        in.seekg(0);
        char magic[3] = {};
        in.read(magic, 3);
        if (extensionOf(path) == "ply" || lower(std::string(magic, static_cast<size_t>(in.gcount()))) == "ply")
            fail(path, e.what());
        isPly = false;
    }
    if (isPly) {
        // assimp's PLY importer takes positions and normals from different elements of the same
        // name (`vertex 4` with nx, then `vertex 6` with x) and frees an invalid pointer.
        // It also reads a name that starts with digits as the element's count
        // (`element 2222222222222222222face 1` asked for 35 GB).
        for (const PlyElement& e : header.elements)
            if (!e.name.empty() && std::isdigit(static_cast<unsigned char>(e.name[0])))
                fail(path, "bad PLY header: element name '" + escapeControl(e.name) + "' starts with a digit");
        for (size_t i = 0; i < header.elements.size(); ++i)
            for (size_t j = 0; j < i; ++j)
                if (header.elements[j].name == header.elements[i].name)
                    fail(path, "bad PLY header: element '" + escapeControl(header.elements[i].name) + "' appears twice");
        // assimp reads a vertex without x (or y, z) as 0 there: a mesh flattened without a word.
        for (const PlyElement& e : header.elements) {
            if (e.name != "vertex" || e.count == 0) continue;
            for (const char* axis : {"x", "y", "z"})
                if (std::none_of(e.properties.begin(), e.properties.end(),
                                 [&](const PlyProperty& p) { return p.name == axis && !p.isList; }))
                    fail(path, std::string("bad PLY header: the vertex element has no '") + axis + "' property");
        }
        in.clear();
        checkPlyCounts(path, header, in);
        TriangleMesh mesh;
        if (readOwnPly(path, header, in, mesh)) {
            mesh.comments = std::move(header.comments);
            return mesh;
        }
        checkPlyLists(path, header, in);
        // assimp splits header lines at blanks and tabs only: a vertical tab, form feed, NUL or
        // lone carriage return, blank to us, made it read the data from another offset than
        // the one checked above (`end_header` + vertical tab: SEGV).
        in.clear();
        in.seekg(0);
        std::string head(static_cast<size_t>(header.dataOffset), '\0');
        in.read(head.data(), static_cast<std::streamsize>(head.size()));
        for (size_t i = 0; i < head.size(); ++i)
            if (head[i] == '\v' || head[i] == '\f' || head[i] == '\0' ||
                (head[i] == '\r' && (i + 1 >= head.size() || head[i + 1] != '\n')))
                fail(path, "bad PLY header: a control character other than a line break, blank or tab");
    }
    in.close();
    TriangleMesh mesh = readWithAssimp(path);
    if (isPly) mesh.comments = std::move(header.comments);
    return mesh;
}

double meanEdgeLength(const TriangleMesh& mesh) {
    double sum = 0;
    size_t n = 0;
    for (const auto& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            sum += (mesh.vertices[t[size_t(k)]] - mesh.vertices[t[size_t((k + 1) % 3)]]).cast<double>().norm();
            ++n;
        }
    return n ? sum / double(n) : 0.0;
}

double enclosedVolume(const TriangleMesh& mesh) {
    if (mesh.triangles.empty()) return 0.0;
    // Tetrahedra against a point near the mesh rather than the origin: the sum of large
    // signed terms would otherwise cancel away digits for a mesh far from the origin.
    const Vec3d origin = mesh.vertices[mesh.triangles[0][0]].cast<double>();
    double sixTimes = 0.0;
    for (const auto& t : mesh.triangles) {
        const Vec3d a = mesh.vertices[t[0]].cast<double>() - origin;
        const Vec3d b = mesh.vertices[t[1]].cast<double>() - origin;
        const Vec3d c = mesh.vertices[t[2]].cast<double>() - origin;
        sixTimes += a.dot(b.cross(c));
    }
    return sixTimes / 6.0;
}

std::vector<Vec3d> vertexAreaVectors(const TriangleMesh& mesh) {
    std::vector<Vec3d> sum(mesh.vertices.size(), Vec3d::Zero());
    for (const auto& t : mesh.triangles) {
        const Vec3d a = mesh.vertices[t[0]].cast<double>();
        const Vec3d b = mesh.vertices[t[1]].cast<double>();
        const Vec3d c = mesh.vertices[t[2]].cast<double>();
        const Vec3d n = (b - a).cross(c - a); // length = twice the area: area weighting
        for (uint32_t i : t) sum[i] += n;
    }
    return sum;
}

std::vector<Vec3d> areaWeightedNormals(const TriangleMesh& mesh) {
    std::vector<Vec3d> sum = vertexAreaVectors(mesh);
    for (Vec3d& n : sum) {
        const double len = n.norm();
        // A vertex in no triangle (or only degenerate ones) has no direction; +z keeps the
        // normal unit length for renderers that expect one.
        n = len > 0 ? Vec3d(n / len) : Vec3d(0, 0, 1);
    }
    return sum;
}

void computeVertexNormals(TriangleMesh& mesh) {
    const std::vector<Vec3d> n = areaWeightedNormals(mesh);
    mesh.normals.resize(n.size());
    for (size_t i = 0; i < n.size(); ++i) mesh.normals[i] = n[i].cast<Real>();
}

void setComment(TriangleMesh& mesh, const std::string& key, const std::string& value) {
    for (auto& c : mesh.comments)
        if (c.first == key) {
            c.second = value;
            return;
        }
    mesh.comments.emplace_back(key, value);
}

} // namespace ferro

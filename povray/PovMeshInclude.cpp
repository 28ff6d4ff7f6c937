// mesh_NNNN.inc: a frame's mesh as a mesh2 with its bounds.
#include "povray/PovText.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/MagnetScene.hpp"
#include "sim/scene/SimSceneFile.hpp"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace ferro {

namespace fs = std::filesystem;

namespace {

// Unit vertex normals of `mesh`, computed from the triangles when the mesh has none.
std::vector<Vec3> vertexNormals(const TriangleMesh& mesh)
{
    if (mesh.normals.size() == mesh.vertices.size())
        return mesh.normals;
    std::vector<Vec3> normals;
    for (const Vec3d& n : areaWeightedNormals(mesh))
        normals.push_back(n.cast<Real>());
    return normals;
}

} // namespace

std::string meshInclude(const TriangleMesh& mesh, int frame, bool motion)
{
    const size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
    std::string out;
    // About 25 bytes per vertex position, 20 per normal, 20 per triangle.
    out.reserve(256 + nv * 50 + nt * 22);
    out += "// mesh_" + frameTag(frame) + ".inc: the fluid surface of frame " + std::to_string(frame) +
           ", written by ferro-pov.\n// POV-Ray millimetres, y up: <x, y, z> here is Ferro's (x, z, y) in mm.\n";
    out += "#declare FerroMeshVertices = " + std::to_string(nt ? nv : 0) + ";\n";
    out += "#declare FerroMeshTriangles = " + std::to_string(nt) + ";\n";
    if (nt == 0)
        return out + "// Empty surface: no FerroMesh is declared (POV-Ray rejects a mesh2 without faces).\n";

    for (const auto& t : mesh.triangles)
        for (uint32_t i : t)
            if (i >= nv)
                throw MeshFileError("triangle refers to vertex " + std::to_string(i) + " of " + std::to_string(nv));
    // POV-Ray has no literal for inf or NaN; writing them as anything would hide a broken mesh.
    for (size_t i = 0; i < nv; ++i)
        if (!mesh.vertices[i].allFinite())
            throw MeshFileError("vertex " + std::to_string(i) + " is not finite");
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const Vec3& v : mesh.vertices) {
        const Vec3d p = toPovPoint(v.cast<double>());
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    out += "#declare FerroMeshMin = " + vec(lo, kPositionDecimals) + ";\n";
    out += "#declare FerroMeshMax = " + vec(hi, kPositionDecimals) + ";\n";

    // Motion blur's sub-frames move each vertex along its velocity (mm/s here) by FerroShift
    // seconds; POV-Ray evaluates the sum once per vertex as it parses.
    const bool moving = motion && mesh.velocities.size() == nv;
    if (moving)
        out += "#ifndef (FerroShift) #declare FerroShift = 0; #end   // [s] from the frame's time\n";
    out += "#declare FerroMesh = mesh2 {\n vertex_vectors { " + std::to_string(nv);
    for (size_t i = 0; i < nv; ++i) {
        out += ",\n";
        appendVector(out, toPovPoint(mesh.vertices[i].cast<double>()), kPositionDecimals);
        if (moving) {
            out += "+FerroShift*";
            appendVector(out, toPovPoint(mesh.velocities[i].cast<double>()), kPositionDecimals);
        }
    }
    const std::vector<Vec3> normals = vertexNormals(mesh);
    out += "\n }\n normal_vectors { " + std::to_string(nv);
    for (const Vec3& n : normals) {
        Vec3d d = toPovDirection(n.cast<double>());
        const double len = d.norm();
        // A vertex without a defined normal (isolated, degenerate fan) gets "up": harmless,
        // POV-Ray only interpolates normals for shading.
        d = len > 0 && std::isfinite(len) ? Vec3d(d / len) : Vec3d(0, 1, 0);
        out += ",\n";
        appendVector(out, d, kNormalDecimals);
    }
    // Without normal_indices POV-Ray takes the face indices for the normals as well.
    out += "\n }\n face_indices { " + std::to_string(nt);
    char buf[48];
    for (const auto& t : mesh.triangles) {
        const int n = std::snprintf(buf, sizeof buf, ",\n<%u,%u,%u>", t[0], t[1], t[2]);
        out.append(buf, size_t(n));
    }
    out += "\n }\n}\n";
    return out;
}

} // namespace ferro

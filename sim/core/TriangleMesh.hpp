#pragma once
// Triangle meshes as the stages after ferro-surface pass them along, and their files.
//
// A foundation of every later stage, so it lives in sim/core: ferro-surface writes meshes,
// ferro-spikes reads and displaces them, ferro-pov exports them. This header includes no OpenVDB, CGAL or
// assimp header, so any stage may include it cheaply.
//
// Files: binary little-endian PLY is written directly (fast, and it carries `comment key
// value` header lines: frame, time, and the magnets' state copied from the particle file);
// every other format assimp can export (obj, stl, ...) goes through assimp. Reading accepts
// any format assimp imports. Writes are atomic (temporary file, then rename).
#include "sim/core/StageErrors.hpp"
#include "sim/core/Types.hpp"

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ferro {

/// A mesh file that cannot be read (malformed: exit 2; missing: exit 4) or written (exit 4).
class MeshFileError : public StageError {
public:
    explicit MeshFileError(const std::string& what, int code = kExitBadInput) : StageError(code, what) {}
};

struct TriangleMesh {
    std::vector<Vec3> vertices;                      ///< positions [m]
    std::vector<Vec3> normals;                       ///< unit outward normal per vertex; empty = none
    /// Velocity per vertex [m/s] (the fluid's motion, for motion blur and retiming); empty =
    /// none. PLY carries it as the vertex properties vx, vy, vz; other formats drop it.
    std::vector<Vec3> velocities;
    std::vector<std::array<uint32_t, 3>> triangles;  ///< counter-clockwise seen from outside
    /// `comment key value` metadata carried from stage to stage (frame, time, magnets).
    std::vector<std::pair<std::string, std::string>> comments;

    bool empty() const { return triangles.empty(); }
};

/// Writes `mesh` to `path` atomically. `format` is an assimp export id ("ply", "obj", "stl",
/// ...) or empty to take it from the file extension. Throws MeshFileError with a one-line reason.
void writeMesh(const std::string& path, const TriangleMesh& mesh, const std::string& format = {});
/// Reads a triangle mesh (any format assimp imports; PLY comments are kept).
/// Throws MeshFileError with a one-line reason.
TriangleMesh readMesh(const std::string& path);

/// Mean length [m] of the triangles' edges (each shared edge counted once a triangle); 0
/// without triangles.
double meanEdgeLength(const TriangleMesh& mesh);
/// Signed enclosed volume [m^3] (divergence theorem); positive for an outward-oriented closed mesh.
double enclosedVolume(const TriangleMesh& mesh);
/// Per vertex, the sum of (b - a) x (c - a) over its triangles (a, b, c in order): twice the
/// vector area of the triangles around it, along their area-weighted normal.
std::vector<Vec3d> vertexAreaVectors(const TriangleMesh& mesh);
/// Area-weighted unit vertex normals from the triangles (outward for counter-clockwise
/// triangles), in double precision; +z for a vertex in no triangle with area.
std::vector<Vec3d> areaWeightedNormals(const TriangleMesh& mesh);
/// Sets mesh.normals to areaWeightedNormals(mesh).
void computeVertexNormals(TriangleMesh& mesh);

/// Sets the first `comment key value` line of `mesh` to `value`, or appends one.
void setComment(TriangleMesh& mesh, const std::string& key, const std::string& value);

} // namespace ferro

#pragma once
// The shapes a scene can ask for by name instead of a mesh file: closed, outward-oriented
// triangle meshes in the solid's own frame (its base or centre at the origin, axis +z), with
// edges about `edge` [m] long, for the surface-charge solve (SurfaceChargeSolver.hpp) and the
// fluid's wall. Spirals and other sculptures come as mesh files (examples/meshes, made by
// scripts/meshes/).
#include "sim/solids/SurfaceChargeSolver.hpp"

namespace ferro {

/// Vertices and counter-clockwise (seen from outside) triangles.
struct ShapeMesh {
    std::vector<Vec3d> vertices;
    std::vector<std::array<uint32_t, 3>> triangles;
};

/// A sphere of `radius` about the origin: a subdivided icosahedron projected onto it, the
/// subdivision the smallest whose edges are at most `edge` (20 * 4^k panels).
ShapeMesh makeSphere(double radius, double edge);
/// A closed cylinder standing on the origin: radius `radius`, from z = 0 to `height`.
ShapeMesh makeCylinder(double radius, double height, double edge);
/// A closed cone (frustum with tipRadius > 0) standing on the origin: base `radius` at
/// z = 0, `tipRadius` (0: a point) at `height`.
ShapeMesh makeCone(double radius, double tipRadius, double height, double edge);

/// Edges shared by other than two triangles, and edges used twice in the same direction
/// (inconsistent orientation), after merging vertices at equal positions: both 0 for a
/// closed, consistently oriented mesh.
struct ClosedCheck {
    size_t openEdges = 0, crowdedEdges = 0, flippedEdges = 0;
    bool closed() const { return openEdges == 0 && crowdedEdges == 0 && flippedEdges == 0; }
};
ClosedCheck checkClosed(const ShapeMesh& mesh);
/// Merges vertices at bit-equal positions (a file's corners split by normals or UVs) and
/// drops triangles that become degenerate.
void weldVertices(ShapeMesh& mesh);
/// Signed enclosed volume [m^3]: positive for an outward-oriented closed mesh.
double signedVolume(const ShapeMesh& mesh);

} // namespace ferro

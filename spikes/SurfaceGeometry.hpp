#pragma once
// Geometry queries and mesh surgery on a TriangleMesh that ferro-spikes needs, all on CGAL.
// CGAL stays inside SurfaceGeometry.cpp: this header includes none of it.
#include "sim/core/TriangleMesh.hpp"

#include <memory>
#include <vector>

namespace ferro {

/// Line and ray queries against a fixed triangle mesh (an AABB tree over its triangles).
/// Built once per mesh; queries are thread-safe.
class SurfaceRayCaster {
public:
    explicit SurfaceRayCaster(const TriangleMesh& mesh);
    ~SurfaceRayCaster();
    SurfaceRayCaster(const SurfaceRayCaster&) = delete;
    SurfaceRayCaster& operator=(const SurfaceRayCaster&) = delete;

    struct Hit {
        Vec3d point;        ///< where the line meets the surface [m]
        uint32_t triangle;  ///< index into mesh.triangles
        double t;           ///< signed line parameter: point = p + t * unit(d)
    };
    /// Every intersection of the infinite line p + t d (d need not be unit, must be non-zero)
    /// with the mesh, sorted by |t| (nearest to p first). A line lying in a triangle's plane
    /// reports the point of that overlap nearest to p.
    std::vector<Hit> lineHits(const Vec3d& p, const Vec3d& d) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// Isotropic remeshing (CGAL Polygon_mesh_processing::isotropic_remeshing) of the triangles
/// with selected[t] != 0 to edges of about `targetEdge` [m], `iterations` rounds; the rest of
/// the mesh is kept (the border of the selection stays conforming, so a closed mesh stays
/// closed). New vertices lie on the input surface (tangential relaxation projects back).
/// Normals are dropped (recompute them); comments are kept. Returns false and leaves `mesh`
/// untouched if the mesh is not an oriented 2-manifold CGAL can load. Throws std::runtime_error
/// with a one-line "CGAL isotropic remeshing: ..." reason if CGAL fails on the selection.
bool remeshSelectedTriangles(TriangleMesh& mesh, const std::vector<char>& selected, double targetEdge,
                             int iterations);

/// Topological and geometric health of a mesh, for tests and diagnostics.
struct MeshHealth {
    bool loadable = false;        ///< an oriented 2-manifold (CGAL Surface_mesh accepts every face)
    bool closed = false;          ///< CGAL::is_closed: no border edges
    bool selfIntersecting = true; ///< CGAL Polygon_mesh_processing::does_self_intersect
};
MeshHealth checkMeshHealth(const TriangleMesh& mesh);

} // namespace ferro

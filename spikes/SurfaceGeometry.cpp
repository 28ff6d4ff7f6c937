// CGAL behind SurfaceGeometry.hpp: an AABB tree for line queries, isotropic remeshing of a
// face selection, and the closed / self-intersection checks.
#include "spikes/SurfaceGeometry.hpp"

#include "sim/core/ErrorText.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ferro {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using CgalMesh = CGAL::Surface_mesh<Point>;
using Triangles = std::vector<Kernel::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point toPoint(const Vec3& v) { return Point(v.x(), v.y(), v.z()); }
Vec3d toVec(const Point& p) { return Vec3d(p.x(), p.y(), p.z()); }

// Loads `mesh` into a Surface_mesh; false if a face breaks orientability or manifoldness.
bool toCgal(const TriangleMesh& mesh, CgalMesh& out, std::vector<CgalMesh::Face_index>* faces = nullptr)
{
    out.clear();
    out.reserve(CgalMesh::size_type(mesh.vertices.size()), CgalMesh::size_type(3 * mesh.triangles.size() / 2),
                CgalMesh::size_type(mesh.triangles.size()));
    for (const Vec3& v : mesh.vertices) out.add_vertex(toPoint(v));
    if (faces) faces->reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return false;
        const CgalMesh::Face_index f = out.add_face(CgalMesh::Vertex_index(t[0]), CgalMesh::Vertex_index(t[1]),
                                                    CgalMesh::Vertex_index(t[2]));
        if (f == CgalMesh::null_face()) return false;
        if (faces) faces->push_back(f);
    }
    return true;
}
} // namespace

struct SurfaceRayCaster::Impl {
    Triangles triangles;
    Tree tree;
};

SurfaceRayCaster::SurfaceRayCaster(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>())
{
    impl_->triangles.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles)
        impl_->triangles.emplace_back(toPoint(mesh.vertices[t[0]]), toPoint(mesh.vertices[t[1]]),
                                      toPoint(mesh.vertices[t[2]]));
    impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
    impl_->tree.build();
    impl_->tree.accelerate_distance_queries();
}

SurfaceRayCaster::~SurfaceRayCaster() = default;

std::vector<SurfaceRayCaster::Hit> SurfaceRayCaster::lineHits(const Vec3d& p, const Vec3d& d) const
{
    std::vector<Hit> hits;
    const double norm = d.norm();
    if (!(norm > 0) || impl_->triangles.empty()) return hits;
    const Vec3d u = d / norm;
    const Kernel::Line_3 line(Point(p.x(), p.y(), p.z()), Kernel::Vector_3(u.x(), u.y(), u.z()));
    using Intersection = Tree::Intersection_and_primitive_id<Kernel::Line_3>::Type;
    std::vector<Intersection> found;
    impl_->tree.all_intersections(line, std::back_inserter(found));
    for (const Intersection& hit : found) {
        Vec3d x;
        if (const Point* q = boost::get<Point>(&hit.first)) {
            x = toVec(*q);
        } else if (const Kernel::Segment_3* s = boost::get<Kernel::Segment_3>(&hit.first)) {
            const Vec3d a = toVec(s->source()), b = toVec(s->target());
            const double len2 = (b - a).squaredNorm();
            const double s01 = len2 > 0 ? std::clamp((p - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
            x = a + s01 * (b - a);
        } else {
            continue;
        }
        hits.push_back({x, uint32_t(hit.second - impl_->triangles.cbegin()), (x - p).dot(u)});
    }
    std::sort(hits.begin(), hits.end(), [](const Hit& a, const Hit& b) { return std::abs(a.t) < std::abs(b.t); });
    return hits;
}

bool remeshSelectedTriangles(TriangleMesh& mesh, const std::vector<char>& selected, double targetEdge,
                             int iterations)
{
    namespace PMP = CGAL::Polygon_mesh_processing;
    CgalMesh cg;
    std::vector<CgalMesh::Face_index> faces;
    if (!toCgal(mesh, cg, &faces)) return false;
    std::vector<CgalMesh::Face_index> patch;
    for (size_t t = 0; t < faces.size(); ++t)
        if (t < selected.size() && selected[t]) patch.push_back(faces[t]);
    if (patch.empty() || iterations <= 0 || !(targetEdge > 0)) return true;
    try {
        PMP::isotropic_remeshing(patch, targetEdge, cg,
                                 CGAL::parameters::number_of_iterations(iterations).protect_constraints(false));
    } catch (const std::exception& e) {
        // CGAL's precondition reports span several lines; ferro-spikes prints one.
        throw std::runtime_error("CGAL isotropic remeshing: " + oneLine(e.what()));
    }
    cg.collect_garbage();

    TriangleMesh out;
    out.comments = mesh.comments;
    out.vertices.reserve(cg.number_of_vertices());
    for (CgalMesh::Vertex_index v : cg.vertices()) {
        const Point& q = cg.point(v);
        out.vertices.emplace_back(float(q.x()), float(q.y()), float(q.z()));
    }
    out.triangles.reserve(cg.number_of_faces());
    for (CgalMesh::Face_index f : cg.faces()) {
        std::array<uint32_t, 3> t{};
        int i = 0;
        for (CgalMesh::Vertex_index v : CGAL::vertices_around_face(cg.halfedge(f), cg)) {
            if (i < 3) t[size_t(i)] = uint32_t(v.idx());
            ++i;
        }
        if (i == 3) out.triangles.push_back(t);
    }
    mesh = std::move(out);
    return true;
}

MeshHealth checkMeshHealth(const TriangleMesh& mesh)
{
    MeshHealth health;
    CgalMesh cg;
    health.loadable = toCgal(mesh, cg);
    if (!health.loadable) return health;
    health.closed = CGAL::is_closed(cg);
    health.selfIntersecting = CGAL::Polygon_mesh_processing::does_self_intersect(cg);
    return health;
}

} // namespace ferro

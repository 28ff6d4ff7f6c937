// The mesh of one closed blob is a closed, outward-oriented 2-manifold of sphere topology
// without self-intersections, as CGAL judges it (CGAL stays in this test).
#include "SurfaceTestShapes.hpp"

#include "surface/SurfaceExtractor.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <catch2/catch.hpp>

using namespace ferro;
using namespace ferro::test;

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

/// A blob with flat, curved and concave parts: a box with a sphere bulging out of one face.
std::vector<Vec3> blob(double s) {
    const int n[3] = {24, 24, 24};
    const Vec3 lo = Vec3::Constant(Real(-12 * s));
    const Vec3 bulge(0, 0, Real(5 * s));
    return latticeFill(lo, n, s, 0.15, [&](const Vec3& p) {
        const bool inBox = p.cwiseAbs().maxCoeff() < 8 * s && p.z() < 2 * s;
        return inBox || (p - bulge).norm() < 6 * s;
    });
}

void checkClosedManifold(const TriangleMesh& tm, bool selfIntersections = true) {
    REQUIRE_FALSE(tm.empty());
    std::vector<K::Point_3> points;
    for (const Vec3& v : tm.vertices) points.emplace_back(v.x(), v.y(), v.z());
    std::vector<std::vector<std::size_t>> polygons;
    for (const auto& t : tm.triangles) polygons.push_back({t[0], t[1], t[2]});
    // As written, without any repair: every edge in two triangles, consistently oriented,
    // every vertex a single umbrella.
    REQUIRE(PMP::is_polygon_soup_a_polygon_mesh(polygons));
    Mesh mesh;
    PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
    REQUIRE(mesh.is_valid());
    CHECK(CGAL::is_closed(mesh));
    CHECK(CGAL::is_triangle_mesh(mesh));
    if (selfIntersections) CHECK_FALSE(PMP::does_self_intersect(mesh));
    CHECK(PMP::is_outward_oriented(mesh));
    // One closed piece of genus 0: V - E + F = 2.
    const long euler = long(mesh.number_of_vertices()) - long(mesh.number_of_edges()) + long(mesh.number_of_faces());
    CHECK(euler == 2);
}

} // namespace

TEST_CASE("the surface of one closed blob is a closed 2-manifold without self-intersections", "[surface][cgal]") {
    const double s = 1.24e-3;
    const std::vector<Vec3> x = blob(s);
    for (SurfaceMethod m : {SurfaceMethod::Anisotropic, SurfaceMethod::Isotropic, SurfaceMethod::OpenVdb}) {
        INFO(methodName(m));
        SurfaceParams p;
        p.method = m;
        checkClosedManifold(extractSurface(x, p, s));
        // Adaptive meshing (fewer, larger triangles) keeps it closed and manifold too, but
        // OpenVDB's adaptive polygons may graze each other in tight spots (seen for the
        // isotropic field), so only adaptivity 0 promises no self-intersections.
        p.adaptivity = 0.5;
        checkClosedManifold(extractSurface(x, p, s), false);
    }
}


// The fluid's velocity on the surface: mesh vertices and the .vdb's "v" grid interpolated from
// the particles with the surface's kernels, against the analytic motion of a ball of particles
// (a uniform translation, exact; a rigid rotation, off only by how far inside the vertex the
// kernels' weighted centre lies).
#include "SurfaceTestShapes.hpp"

#include "surface/SurfaceExtractor.hpp"

#include <catch2/catch.hpp>

#include <openvdb/openvdb.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <unistd.h>

using namespace ferro;
using namespace ferro::test;

namespace {

constexpr double kS = 0.001; // particle spacing [m]

SurfaceParams withMethod(SurfaceMethod m) {
    SurfaceParams p;
    p.method = m;
    return p;
}

} // namespace

TEST_CASE("vertex velocities: a translating ball moves every vertex with it, exactly", "[surface][velocity]") {
    const std::vector<Vec3> x = sphereFill(8 * kS, kS, 0.1);
    const Vec3 u(0.12f, -0.05f, 0.3f);
    const std::vector<Vec3> v(x.size(), u);
    for (SurfaceMethod m : {SurfaceMethod::Anisotropic, SurfaceMethod::Isotropic, SurfaceMethod::OpenVdb}) {
        const TriangleMesh mesh = extractSurface(x, withMethod(m), kS, {}, nullptr, &v);
        REQUIRE(!mesh.empty());
        REQUIRE(mesh.velocities.size() == mesh.vertices.size());
        double worst = 0;
        for (const Vec3& w : mesh.velocities) worst = std::max(worst, double((w - u).norm()));
        INFO(methodName(m) << ": worst |v - u| " << worst << " m/s");
        CHECK(worst < 1e-6 * u.norm());
    }
    // Without velocities the mesh has none.
    CHECK(extractSurface(x, withMethod(SurfaceMethod::Anisotropic), kS).velocities.empty());
    // A velocity count that does not match the particles, or a NaN, is refused.
    std::vector<Vec3> shorter(v.begin(), v.end() - 1);
    CHECK_THROWS_AS(extractSurface(x, withMethod(SurfaceMethod::Anisotropic), kS, {}, nullptr, &shorter), SurfaceError);
    std::vector<Vec3> bad = v;
    bad[3].x() = std::nanf("");
    CHECK_THROWS_AS(extractSurface(x, withMethod(SurfaceMethod::Anisotropic), kS, {}, nullptr, &bad), SurfaceError);
}

TEST_CASE("vertex velocities: a rotating ball's surface turns with omega x r", "[surface][velocity]") {
    const double R = 10 * kS, omega = 20; // [m], [1/s]: 0.2 m/s at the equator
    const std::vector<Vec3> x = sphereFill(R, kS, 0.1);
    std::vector<Vec3> v(x.size());
    for (size_t i = 0; i < x.size(); ++i) v[i] = Vec3(Real(-omega * x[i].y()), Real(omega * x[i].x()), 0);
    const TriangleMesh mesh = extractSurface(x, withMethod(SurfaceMethod::Anisotropic), kS, {}, nullptr, &v);
    REQUIRE(mesh.velocities.size() == mesh.vertices.size());
    // Every vertex: the interpolated velocity is the motion of a point within about a spacing
    // of the vertex (the kernels' weighted centre lies inside it). Vertices at least R/2 from
    // the axis: the speed against omega r (about (R - s/2) / R) and the direction.
    double ratioSum = 0, worstAngle = 0, worstRatio = 1, worstError = 0;
    size_t counted = 0;
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Eigen::Vector3d p = mesh.vertices[i].cast<double>(), w = mesh.velocities[i].cast<double>();
        const Eigen::Vector3d exact(-omega * p.y(), omega * p.x(), 0);
        worstError = std::max(worstError, (w - exact).norm());
        if (std::hypot(p.x(), p.y()) < R / 2) continue;
        const double ratio = w.norm() / exact.norm();
        ratioSum += ratio;
        worstRatio = std::min(worstRatio, ratio);
        worstAngle = std::max(worstAngle, std::acos(std::clamp(w.dot(exact) / (w.norm() * exact.norm()), -1.0, 1.0)));
        ++counted;
    }
    REQUIRE(counted > 100);
    const double meanRatio = ratioSum / double(counted);
    WARN("rotating ball: worst |v - omega x r| " << worstError / (omega * kS) << " omega s; mean |v| / omega r "
                                                 << meanRatio << ", lowest " << worstRatio << ", worst angle "
                                                 << worstAngle << " rad over " << counted << " vertices");
    CHECK(worstError < 1.5 * omega * kS);
    CHECK(meanRatio == Approx(1.0 - 0.5 * kS / R).margin(0.03));
    CHECK(worstRatio > 0.8);
}

TEST_CASE("the .vdb file: a velocity grid v beside the level set, on the band's voxels", "[surface][velocity]") {
    const std::vector<Vec3> x = sphereFill(6 * kS, kS, 0.1);
    const Vec3 u(0.0f, 0.25f, -0.1f);
    const std::vector<Vec3> v(x.size(), u);
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("ferro_velocity_vdb_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "frame.vdb").string();
    extractSurface(x, withMethod(SurfaceMethod::Anisotropic), kS, path, nullptr, &v);
    openvdb::initialize();
    openvdb::io::File file(path);
    file.open();
    const openvdb::FloatGrid::Ptr surface = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("surface"));
    const openvdb::Vec3fGrid::Ptr vg = openvdb::gridPtrCast<openvdb::Vec3fGrid>(file.readGrid("v"));
    file.close();
    REQUIRE(surface);
    REQUIRE(vg);
    CHECK(vg->activeVoxelCount() == surface->activeVoxelCount());
    CHECK(vg->transform() == surface->transform());
    double worst = 0;
    for (auto it = vg->cbeginValueOn(); it; ++it)
        worst = std::max(worst, double((*it - openvdb::Vec3f(u.x(), u.y(), u.z())).length()));
    CHECK(worst < 1e-6);
    // Without velocities the file holds the level set alone.
    extractSurface(x, withMethod(SurfaceMethod::Anisotropic), kS, path);
    openvdb::io::File again(path);
    again.open();
    CHECK(!again.hasGrid("v"));
    again.close();
    std::filesystem::remove_all(dir);
}

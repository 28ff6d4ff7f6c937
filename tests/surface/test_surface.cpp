// Surface extraction: flatness, distance to known surfaces, volume, orientation, edge cases.
#include "SurfaceTestShapes.hpp"

#include "surface/DensityKernels.hpp"
#include "surface/SurfaceExtractor.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using namespace ferro;
using namespace ferro::test;

namespace {

constexpr double kSpacing = 1.24e-3; // the dish example's spacing

SurfaceParams withMethod(SurfaceMethod m) {
    SurfaceParams p;
    p.method = m;
    return p;
}

/// RMS deviation from their mean of the heights of upward-facing vertices over the middle
/// of a slab (away from its sides by `margin`).
double topRoughness(const TriangleMesh& mesh, double lo, double hi, double margin) {
    double sum = 0, sum2 = 0;
    size_t n = 0;
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Vec3& v = mesh.vertices[i];
        if (v.x() < lo + margin || v.x() > hi - margin || v.y() < lo + margin || v.y() > hi - margin) continue;
        if (mesh.normals[i].z() < 0.5f) continue;
        sum += v.z();
        sum2 += double(v.z()) * v.z();
        ++n;
    }
    REQUIRE(n > 100);
    const double mean = sum / n;
    return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
}

} // namespace

TEST_CASE("every kernel integrates to its particle's volume, also after rasterization", "[surface]") {
    const std::vector<Vec3> x = sphereFill(6 * kSpacing, kSpacing, 0.2);
    for (SurfaceMethod m : {SurfaceMethod::Anisotropic, SurfaceMethod::Isotropic}) {
        const std::vector<DensityKernel> k = buildKernels(x, withMethod(m), kSpacing);
        const double particles = double(x.size()) * std::pow(kSpacing, 3);
        CHECK(rasterizedVolume(k, kSpacing / 2) == Approx(particles).epsilon(0.01));
        CHECK(rasterizedVolume(k, kSpacing / 3) == Approx(particles).epsilon(0.005));
        // Inside the fluid the field is the rest density, 1.
        CHECK(densityAt(k, Vec3::Zero()) == Approx(1.0).epsilon(0.05));
        CHECK(densityAt(k, Vec3::Constant(Real(10 * kSpacing))) == 0.0);
    }
}

TEST_CASE("derived k_s gives interior particles unit axes, and the calibration is scale free", "[surface]") {
    SurfaceParams p;
    p.neighborRadius = 2.5;
    // Weighted variance (weight 1 - (r/R)^3) of the lattice offsets within 2.5 spacings,
    // per axis, summed by hand over the 81 points: 0.96763 s^2.
    CHECK(derivedKs(p, kSpacing) * kSpacing * kSpacing == Approx(1.0 / 0.96763).epsilon(1e-4));
    // Doubling the length scale quarters k_s (the paper's 1400 is bound to its scale).
    CHECK(derivedKs(p, 2 * kSpacing) == Approx(derivedKs(p, kSpacing) / 4));
    p = SurfaceParams{};
    for (SurfaceMethod m : {SurfaceMethod::Anisotropic, SurfaceMethod::Isotropic}) {
        p.method = m;
        const SurfaceCalibration cal = calibrateSurface(p, kSpacing);
        CHECK(cal.isoLevel == 0.5);
        // Yu-Turk smoothing pulls the outer layer in; isotropic kernels barely move it.
        if (m == SurfaceMethod::Isotropic) CHECK(std::abs(cal.offset) < 0.1 * kSpacing);
        else CHECK(cal.offset > 0.2 * kSpacing);
        CHECK(calibrateSurface(p, 3 * kSpacing).offset == Approx(3 * cal.offset).epsilon(1e-3));
    }
}

TEST_CASE("a resting pool: the anisotropic top surface is at least 3x flatter than the isotropic one", "[surface]") {
    const int n = 40;
    const std::vector<Vec3> x = jitteredSlab(n, n, 8, kSpacing, 0.15);
    const double side = n * kSpacing, margin = 6 * kSpacing;
    const TriangleMesh an = extractSurface(x, withMethod(SurfaceMethod::Anisotropic), kSpacing);
    const TriangleMesh iso = extractSurface(x, withMethod(SurfaceMethod::Isotropic), kSpacing);
    const double roughAn = topRoughness(an, 0, side, margin);
    const double roughIso = topRoughness(iso, 0, side, margin);
    INFO("RMS height deviation: anisotropic " << roughAn / kSpacing << " spacings, isotropic "
                                              << roughIso / kSpacing << " spacings");
    WARN("flat pool RMS height deviation / spacing: anisotropic " << roughAn / kSpacing << ", isotropic "
                                                                  << roughIso / kSpacing << ", ratio "
                                                                  << roughIso / roughAn);
    CHECK(roughIso > 3 * roughAn);
}

namespace {
/// A filled shape's surface: within a quarter spacing of the shape on average (`dist`, the
/// mean vertex distance), enclosing the particles' volume (count times s^3) within 3 %.
void checkShape(SurfaceMethod m, const char* shape, double dist, const std::vector<Vec3>& x, const TriangleMesh& mesh,
                double s) {
    const double particles = double(x.size()) * s * s * s;
    const double volume = enclosedVolume(mesh);
    WARN(methodName(m) << " " << shape << ": mean distance " << dist / s << " spacings, volume / particle volume "
                       << volume / particles);
    CHECK(dist < s / 4);
    CHECK(volume == Approx(particles).epsilon(0.03));
}
} // namespace

TEST_CASE("particles filling a sphere and a box: the surface and the volume are where they belong", "[surface]") {
    const double s = kSpacing;
    for (SurfaceMethod m : {SurfaceMethod::Anisotropic, SurfaceMethod::Isotropic}) {
        SECTION(std::string("sphere, ") + methodName(m)) {
            const double radius = 10 * s;
            const std::vector<Vec3> x = sphereFill(radius, s, 0.1);
            const TriangleMesh mesh = extractSurface(x, withMethod(m), s);
            double dist = 0;
            for (const Vec3& v : mesh.vertices) dist += std::abs(v.norm() - radius);
            checkShape(m, "sphere", dist / mesh.vertices.size(), x, mesh, s);
            // Outward: each vertex normal points away from the centre.
            size_t outward = 0;
            for (size_t i = 0; i < mesh.vertices.size(); ++i) outward += mesh.normals[i].dot(mesh.vertices[i]) > 0;
            CHECK(outward == mesh.vertices.size());
        }
        SECTION(std::string("box, ") + methodName(m)) {
            const int n[3] = {16, 12, 10};
            const Vec3 lo(Real(0.01), Real(-0.02), Real(0.003));
            const Vec3 hi = lo + Vec3(Real(n[0] * s), Real(n[1] * s), Real(n[2] * s));
            const std::vector<Vec3> x = latticeFill(lo, n, s, 0.1, [](const Vec3&) { return true; });
            const TriangleMesh mesh = extractSurface(x, withMethod(m), s);
            double dist = 0;
            for (const Vec3& v : mesh.vertices) {
                // Distance to the box surface, from outside or inside.
                const Vec3 out = (v - hi).cwiseMax(lo - v);
                const double outside = out.cwiseMax(Vec3::Zero()).norm();
                dist += outside > 0 ? outside : -double(out.maxCoeff());
            }
            checkShape(m, "box", dist / mesh.vertices.size(), x, mesh, s);
        }
    }
}

TEST_CASE("the OpenVDB union of spheres, moved in by half a spacing, is close", "[surface]") {
    // The rough knob: bumps of the spheres and rounded corners cost it a few percent.
    const double s = kSpacing;
    const std::vector<Vec3> x = sphereFill(10 * s, s, 0.1);
    const TriangleMesh mesh = extractSurface(x, withMethod(SurfaceMethod::OpenVdb), s);
    CHECK(enclosedVolume(mesh) == Approx(double(x.size()) * s * s * s).epsilon(0.06));
}

TEST_CASE("empty, single-particle and scattered frames mesh without trouble", "[surface]") {
    for (SurfaceMethod m : {SurfaceMethod::Anisotropic, SurfaceMethod::Isotropic, SurfaceMethod::OpenVdb}) {
        CHECK(extractSurface({}, withMethod(m), kSpacing).empty());
        CHECK(extractSurface({}, withMethod(m)).empty());
        const TriangleMesh one = extractSurface({Vec3(Real(0.1), 0, 0)}, withMethod(m), kSpacing);
        // A lone particle: Yu-Turk gives it a small round kernel (k_n), OpenVDB a sphere; the
        // plain isotropic kernel spreads it below the iso level, so it has no surface.
        CHECK(one.empty() == (m == SurfaceMethod::Isotropic));
        // An empty mesh encloses exactly nothing; a lone particle's blob a positive volume.
        if (m == SurfaceMethod::Isotropic) CHECK(enclosedVolume(one) == 0.0);
        else CHECK(enclosedVolume(one) > 0);
        CHECK(enclosedVolume(one) < 10 * std::pow(kSpacing, 3));
        // Without a spacing and with one particle, there is nothing to measure it by: any
        // scale will do, and the mesh is at most a small blob.
        SurfaceStats lone;
        const TriangleMesh loneMesh = extractSurface({Vec3(0, 0, 0)}, withMethod(m), 0.0, {}, &lone);
        const double loneVolume = enclosedVolume(loneMesh);
        CAPTURE(methodName(m), loneVolume);
        // Only Yu-Turk's round kernel leaves a blob here; the plain kernel and OpenVDB (at the
        // scale guessed from one particle) leave nothing, and nothing encloses exactly 0.
        CHECK(loneMesh.empty() == (m != SurfaceMethod::Anisotropic));
        if (loneMesh.empty()) CHECK(loneVolume == 0.0);
        else CHECK(loneVolume > 0);
        CHECK(loneVolume < 10 * std::pow(lone.spacing, 3));
        // Two far-apart particles: two blobs, no dense box between them.
        const TriangleMesh two = extractSurface({Vec3(0, 0, 0), Vec3(5, 0, 0)}, withMethod(m), kSpacing);
        CHECK(enclosedVolume(two) == Approx(2 * enclosedVolume(one)).epsilon(0.2));
    }
    CHECK_THROWS_AS(extractSurface({Vec3(0, NAN, 0)}, SurfaceParams{}, kSpacing), SurfaceError);
}

TEST_CASE("the spacing is estimated from the positions when not given", "[surface]") {
    const std::vector<Vec3> x = jitteredSlab(20, 20, 6, kSpacing, 0.0);
    CHECK(estimateSpacing(x) == Approx(kSpacing).epsilon(1e-4));
    CHECK(estimateSpacing({}) == 0);
    CHECK(estimateSpacing({Vec3(1, 2, 3)}) == 0);
}

TEST_CASE("the up-front grid estimate: a kernel box per isolated particle, about the grid OpenVDB fills for a ball", "[surface]") {
    SurfaceParams p; // anisotropic, kernel radius 1.5 spacings: cells of 3 spacings
    const double s = kSpacing, voxel = s / 4;
    // Eight particles 10 spacings apart: eight cells of (3 s / voxel)^3 = 12^3 voxels.
    std::vector<Vec3> spray;
    for (int i = 0; i < 8; ++i) spray.push_back(Vec3(Real(10 * s * (i & 1)), Real(10 * s * ((i >> 1) & 1)), Real(10 * s * (i >> 2))));
    const GridEstimate g = estimateGrid(spray, p, s, voxel);
    CHECK(g.cell == Approx(3 * s));
    CHECK(g.cells == 8);
    CHECK(g.voxels == Approx(8 * 12 * 12 * 12));
    CHECK(g.bytes == Approx(g.voxels * GridEstimate::kBytesPerVoxel));
    // Against the voxels OpenVDB's grid holds after meshing (its active count): the
    // estimate must neither miss most of the grid nor ask for many times its size.
    // Measured, estimate / active at 1/2, 1/4, 1/10 spacing: ball 1.03, 1.51, 1.79 (the
    // final grid keeps only a band inside the fluid; rasterizing, the peak, holds it all),
    // spray 0.30, 0.72, 0.85 (the estimate leaves out the distance band of a few voxels
    // around each surface: most of an isolated particle's grid at coarse voxels, which are
    // cheap; the fine voxels that exhaust memory are estimated closely).
    for (const auto& [name, x] : {std::pair<const char*, std::vector<Vec3>>{"ball", sphereFill(10 * s, s, 0.1)},
                                  {"spray", spray}})
        for (const double v : {s / 2, s / 4, s / 10}) {
            SurfaceParams q = p;
            q.voxelSize = v;
            SurfaceStats st;
            extractSurface(x, q, s, {}, &st);
            const double ratio = st.estimatedVoxels / double(st.activeVoxels);
            std::printf("grid estimate, %s of %zu particles, voxel 1/%.0f spacing: %.3g voxels estimated, %zu active, ratio %.2f\n",
                        name, x.size(), s / v, st.estimatedVoxels, st.activeVoxels, ratio);
            CAPTURE(name, v, st.estimatedVoxels, st.activeVoxels);
            CHECK(ratio < 2);
            CHECK(ratio > (v < s / 2 ? 0.45 : 0.25));
        }
}

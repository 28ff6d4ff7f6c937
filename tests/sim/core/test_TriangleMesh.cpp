// Mesh files: round trips, the enclosed volume, and other readers of our PLY.
#include "sim/core/TriangleMesh.hpp"
#include "sim/core/Constants.hpp"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <Eigen/Geometry>

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include <unistd.h>

using namespace ferro;
namespace fs = std::filesystem;

namespace {

fs::path scratchDir() {
    fs::path dir = fs::temp_directory_path() / ("ferro_mesh_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

/// Axis-aligned box [lo, hi] with outward counter-clockwise triangles.
TriangleMesh boxMesh(const Vec3& lo, const Vec3& hi) {
    TriangleMesh m;
    for (int i = 0; i < 8; ++i)
        m.vertices.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
    const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
    }
    return m;
}

/// Icosphere of `levels` subdivisions, vertices on the sphere, outward triangles.
TriangleMesh sphereMesh(double radius, int levels) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::array<uint32_t, 3>> f = {
        {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
        {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
        {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (auto& p : v) p.normalize();
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            v.push_back((v[a] + v[b]).normalized());
            return mid[key] = uint32_t(v.size() - 1);
        };
        std::vector<std::array<uint32_t, 3>> g;
        for (const auto& tri : f) {
            const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
            g.push_back({tri[0], a, c});
            g.push_back({tri[1], b, a});
            g.push_back({tri[2], c, b});
            g.push_back({a, b, c});
        }
        f = g;
    }
    TriangleMesh m;
    for (const auto& p : v) m.vertices.push_back((p * radius).cast<float>());
    m.triangles = f;
    return m;
}

} // namespace

TEST_CASE("enclosed volume of a box and a sphere", "[mesh]") {
    const TriangleMesh box = boxMesh(Vec3(1, 2, 3), Vec3(1.5f, 2.25f, 4));
    CHECK(enclosedVolume(box) == Approx(0.5 * 0.25 * 1.0).epsilon(1e-6));

    TriangleMesh flipped = box;
    for (auto& t : flipped.triangles) std::swap(t[1], t[2]);
    CHECK(enclosedVolume(flipped) == Approx(-0.125).epsilon(1e-6));

    // An inscribed polyhedron: its volume approaches 4/3 pi r^3 from below.
    const double r = 0.02;
    const TriangleMesh sphere = sphereMesh(r, 5);
    const double exact = 4.0 / 3.0 * kPi * r * r * r;
    CHECK(enclosedVolume(sphere) < exact);
    CHECK(enclosedVolume(sphere) == Approx(exact).epsilon(2e-3));
    CHECK(enclosedVolume(TriangleMesh{}) == 0.0);
}

TEST_CASE("vertex normals point outward and are unit length", "[mesh]") {
    TriangleMesh sphere = sphereMesh(1.0, 3);
    computeVertexNormals(sphere);
    REQUIRE(sphere.normals.size() == sphere.vertices.size());
    double worst = 1.0;
    for (size_t i = 0; i < sphere.vertices.size(); ++i) {
        CHECK(sphere.normals[i].norm() == Approx(1.0).epsilon(1e-5));
        worst = std::min(worst, double(sphere.normals[i].dot(sphere.vertices[i].normalized())));
    }
    CHECK(worst > 0.999);

    TriangleMesh box = boxMesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
    computeVertexNormals(box);
    // A corner's normal points away from the centre, along the diagonal.
    CHECK(box.normals[7].dot(Vec3(1, 1, 1).normalized()) > 0.9f);
    CHECK(box.normals[0].dot(Vec3(-1, -1, -1).normalized()) > 0.9f);
}

TEST_CASE("binary PLY round trip keeps vertices, normals, triangles and comments", "[mesh]") {
    const fs::path dir = scratchDir();
    TriangleMesh m = sphereMesh(0.01, 2);
    computeVertexNormals(m);
    m.comments = {{"frame", "12"}, {"time", "0.5"}, {"magnet_0", "dipole 0 0 -0.02 0 0 1 3.5"}};
    const std::string path = (dir / "round.ply").string();
    writeMesh(path, m);
    for (const auto& e : fs::directory_iterator(dir)) // no temporary file left behind
        CHECK(e.path().filename().string().find(".tmp-") == std::string::npos);

    const TriangleMesh r = readMesh(path);
    REQUIRE(r.vertices.size() == m.vertices.size());
    REQUIRE(r.normals.size() == m.normals.size());
    REQUIRE(r.triangles == m.triangles);
    for (size_t i = 0; i < m.vertices.size(); ++i) {
        CHECK(r.vertices[i] == m.vertices[i]);
        CHECK(r.normals[i] == m.normals[i]);
    }
    CHECK(r.comments == m.comments);
    CHECK(enclosedVolume(r) == Approx(enclosedVolume(m)));

    // Without normals the file has none, and reads back without.
    TriangleMesh bare = boxMesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
    writeMesh((dir / "bare.ply").string(), bare);
    const TriangleMesh rb = readMesh((dir / "bare.ply").string());
    CHECK(rb.normals.empty());
    CHECK(rb.triangles == bare.triangles);

    // Velocities (vx, vy, vz) round-trip with and without normals; a count that does not
    // match the vertices is refused.
    for (bool withNormals : {true, false}) {
        TriangleMesh mv = boxMesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
        if (withNormals) computeVertexNormals(mv);
        for (size_t i = 0; i < mv.vertices.size(); ++i) mv.velocities.push_back(Vec3(Real(i), -0.5f, Real(2 * i) + 0.25f));
        writeMesh((dir / "moving.ply").string(), mv);
        const TriangleMesh rv = readMesh((dir / "moving.ply").string());
        CHECK(rv.velocities == mv.velocities);
        CHECK(rv.normals == mv.normals);
        CHECK(rv.vertices == mv.vertices);
        mv.velocities.pop_back();
        CHECK_THROWS_AS(writeMesh((dir / "bad.ply").string(), mv), MeshFileError);
    }

    // An empty mesh is a valid file.
    writeMesh((dir / "empty.ply").string(), TriangleMesh{});
    CHECK(readMesh((dir / "empty.ply").string()).empty());
    fs::remove_all(dir);
}

TEST_CASE("assimp reads our PLY on its own", "[mesh]") {
    const fs::path dir = scratchDir();
    TriangleMesh m = sphereMesh(0.01, 2);
    computeVertexNormals(m);
    m.comments = {{"frame", "3"}};
    const std::string path = (dir / "for_assimp.ply").string();
    writeMesh(path, m);

    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(path, 0);
    REQUIRE(scene != nullptr);
    REQUIRE(scene->mNumMeshes == 1);
    const aiMesh* am = scene->mMeshes[0];
    CHECK(am->mNumFaces == m.triangles.size());
    REQUIRE(am->HasNormals());
    // Sum of positions and of normals is order independent (assimp may duplicate vertices).
    Vec3d area = Vec3d::Zero();
    double volume = 0;
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
        REQUIRE(am->mFaces[f].mNumIndices == 3);
        Vec3d p[3];
        for (int k = 0; k < 3; ++k) {
            const aiVector3D& v = am->mVertices[am->mFaces[f].mIndices[k]];
            p[k] = Vec3d(v.x, v.y, v.z);
        }
        volume += p[0].dot(p[1].cross(p[2])) / 6;
        area += (p[1] - p[0]).cross(p[2] - p[0]);
    }
    CHECK(volume == Approx(enclosedVolume(m)).epsilon(1e-5));
    CHECK(area.norm() < 1e-9); // closed surface: oriented areas cancel
    fs::remove_all(dir);
}

TEST_CASE("OBJ and STL export through assimp read back", "[mesh]") {
    const fs::path dir = scratchDir();
    TriangleMesh m = sphereMesh(0.01, 2);
    computeVertexNormals(m);
    for (const char* name : {"out.obj", "out.stl"}) {
        const std::string path = (dir / name).string();
        writeMesh(path, m);
        const TriangleMesh r = readMesh(path);
        CHECK(r.triangles.size() == m.triangles.size());
        CHECK(enclosedVolume(r) == Approx(enclosedVolume(m)).epsilon(1e-5));
    }
    // OBJ stays one file: no .mtl beside it.
    CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}) == 2);
    // An explicit format wins over the extension.
    writeMesh((dir / "mesh.dat").string(), m, "obj");
    std::ifstream in(dir / "mesh.dat");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    CHECK(text.find("\nv ") != std::string::npos);
    CHECK(text.find("\nf ") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("mesh file errors are one-line MeshFileErrors", "[mesh]") {
    const fs::path dir = scratchDir();
    CHECK_THROWS_AS(readMesh((dir / "missing.ply").string()), MeshFileError);
    {
        std::ofstream((dir / "garbage.ply").string()) << "this is not a mesh\n";
    }
    CHECK_THROWS_AS(readMesh((dir / "garbage.ply").string()), MeshFileError);
    TriangleMesh bad = boxMesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
    bad.triangles.push_back({0, 1, 99});
    CHECK_THROWS_AS(writeMesh((dir / "bad.ply").string(), bad), MeshFileError);
    CHECK_FALSE(fs::exists(dir / "bad.ply"));
    CHECK_THROWS_AS(writeMesh((dir / "x.nosuchformat").string(), boxMesh(Vec3(0, 0, 0), Vec3(1, 1, 1))),
                    MeshFileError);
    // A truncated PLY of our layout is an error, not a short mesh.
    TriangleMesh m = sphereMesh(1, 1);
    writeMesh((dir / "full.ply").string(), m);
    fs::resize_file(dir / "full.ply", fs::file_size(dir / "full.ply") - 7);
    CHECK_THROWS_AS(readMesh((dir / "full.ply").string()), MeshFileError);
    // A vertex element without x (assimp read it as x = 0: a flattened mesh): refused, named.
    {
        std::ofstream((dir / "nox.ply").string())
            << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float y\nproperty float z\nproperty float w\n"
               "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    }
    try {
        readMesh((dir / "nox.ply").string());
        FAIL("a mesh without x was read");
    } catch (const MeshFileError& e) {
        CHECK(std::string(e.what()).find("no 'x' property") != std::string::npos);
        CHECK(e.code() == kExitBadInput);
    }
    fs::remove_all(dir);
}

TEST_CASE("a PLY header that ends the file, with huge counts, is a MeshFileError, not an allocation",
          "[mesh]") {
    const fs::path dir = scratchDir();
    const std::string head = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                             "property float y\nproperty float z\nelement face 4000000000\n"
                             "property list uchar uint vertex_indices\n";
    auto expectOneLineError = [&](const std::string& name, const std::string& text) {
        {
            std::ofstream((dir / name).string(), std::ios::binary) << text;
        }
        INFO(name);
        try {
            readMesh((dir / name).string());
            FAIL("no error");
        } catch (const MeshFileError& e) {
            const std::string what = e.what();
            CHECK(what.find('\n') == std::string::npos);
            CHECK(what.find("truncated") != std::string::npos);
        }
    };
    // `end_header` without its line break: the header "ends" one byte past the file.
    expectOneLineError("no_newline.ply", head + "end_header");
    expectOneLineError("no_data.ply", head + "end_header\n");
    expectOneLineError("little_data.ply", head + "end_header\n" + std::string(100, '\0'));
    // Other layouts go to assimp, but only after the same check.
    expectOneLineError("ascii.ply", "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty double x\n"
                                    "property double y\nproperty double z\nend_header\n0 0 0\n");
    fs::remove_all(dir);
}

TEST_CASE("meshes that crashed assimp are one-line MeshFileErrors (fuzz findings)", "[mesh]") {
    // Each case is also an input of tests/fuzz/corpus/mesh (fuzz-replay-mesh).
    const fs::path dir = scratchDir();
    const std::string tri = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                            "end_header\n0 0 0\n1 0 0\n0 1 0\n";
    auto errorOf = [&](const std::string& name, const std::string& bytes) -> std::string {
        {
            std::ofstream((dir / name).string(), std::ios::binary) << bytes;
        }
        try {
            readMesh((dir / name).string());
        } catch (const MeshFileError& e) {
            const std::string what = e.what();
            CHECK(what.find('\n') == std::string::npos);
            CHECK(what.rfind((dir / name).string() + ": ", 0) == 0);
            return what;
        }
        FAIL("no MeshFileError for " << name);
        return {};
    };
    // A face index -5: assimp's post-processing read past its vertices (SEGV).
    CHECK_THAT(errorOf("negative_index.ply", tri + "3 0 1 -5\n"),
               Catch::Matchers::Contains("mIndices[2] is out of range"));
    // A face of 0 indices: assimp's Triangulate step aborted the process (ai_assert).
    CHECK_THAT(errorOf("empty_face.ply", tri + "0\n"), Catch::Matchers::EndsWith("face 0 has no vertex indices"));
    // Not PLY by its first line ("ply@") but named .ply, or starting with "ply": assimp's PLY
    // importer took it without the count checks and crashed on 4294967295 faces.
    const std::string almost = "ply@\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 4294967295\n"
                               "property list uchar uint vertex_indices\nend_header\n" + std::string(36, '\0');
    CHECK_THAT(errorOf("almost.ply", almost), Catch::Matchers::EndsWith(": not a PLY file"));
    CHECK_THAT(errorOf("almost.obj", almost), Catch::Matchers::EndsWith(": not a PLY file"));
    // Two elements of one name: assimp took positions and normals from different ones and
    // freed an invalid pointer.
    CHECK_THAT(errorOf("twice.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float nx\n"
                                    "element vertex 6\nproperty float x\nend_header\n" + std::string(13, '\0')),
               Catch::Matchers::EndsWith(": bad PLY header: element 'vertex' appears twice"));
    // A vertical tab after end_header: blank to us, not to assimp, which read the data from
    // another offset (SEGV).
    CHECK_THAT(errorOf("vtab.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                   "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                   "end_header\v\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
               Catch::Matchers::EndsWith("bad PLY header: a control character other than a line break, blank or tab"));
    // An element name of digits: assimp read it as the element's count (35 GB).
    CHECK_THAT(errorOf("digits.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                     "element 2222222222222222222face 1\nproperty float y\nend_header\n0\n1\n"),
               Catch::Matchers::EndsWith("bad PLY header: element name '2222222222222222222face' starts with a digit"));
    // A list length beyond the file (or a float one): assimp sized the list first (34 GB).
    std::string verts(36, '\0');
    CHECK_THAT(errorOf("long_list.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                                        "property float y\nproperty float z\nelement face 1\n"
                                        "property list uint uint vertex_indices\nend_header\n" + verts +
                                        std::string("\xf0\xff\xff\xff", 4) + std::string(12, '\0')),
               Catch::Matchers::EndsWith("truncated (face 0: list 'vertex_indices' is longer than the rest of the file)"));
    CHECK_THAT(errorOf("long_list_ascii.ply", tri + "4294967280 0 1 2\n"),
               Catch::Matchers::EndsWith("truncated (face 0: list 'vertex_indices' is longer than the rest of the file)"));
    CHECK_THAT(errorOf("float_list.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                                         "property float y\nproperty float z\nelement face 1\n"
                                         "property list float uint vertex_indices\nend_header\n" + verts + std::string(16, '\0')),
               Catch::Matchers::EndsWith("bad PLY header: list 'vertex_indices' has a floating-point length"));
    // What assimp reads well still reads.
    {
        std::ofstream((dir / "ok.ply").string(), std::ios::binary) << tri + "3 0 1 2\n";
    }
    CHECK(readMesh((dir / "ok.ply").string()).triangles.size() == 1);
    fs::remove_all(dir);
}

// [[solids]] (sim/solids/SolidScene.cpp): the keys, the pose track, and a one-line
// SceneError for every bad solid.
#include "sim/solids/SolidParams.hpp"

#include "sim/core/SceneDocument.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

using namespace ferro;
using ferro::test::TempDir;

namespace {

std::vector<SolidParams> solids(const std::string& text) { return parseSolids(SceneDocument::parse(text, "t.toml")); }

std::string errorOf(const std::string& text) {
    try {
        const std::vector<SolidParams> s = solids(text);
        for (const SolidParams& p : s) solidShape(p, 0.002, "t.toml");
    } catch (const SceneError& e) {
        return e.what();
    }
    return {};
}

// An OBJ of a unit cube (outward faces), with one face left out (`open`) or every face
// turned inward (`inverted`).
std::string cubeObj(bool open, bool inverted) {
    std::string s = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
    const int faces[12][3] = {{1, 3, 2}, {1, 4, 3}, {5, 6, 7}, {5, 7, 8}, {1, 2, 6}, {1, 6, 5},
                              {2, 3, 7}, {2, 7, 6}, {3, 4, 8}, {3, 8, 7}, {4, 1, 5}, {4, 5, 8}};
    for (int f = open ? 2 : 0; f < 12; ++f)
        s += "f " + std::to_string(faces[f][0]) + " " + std::to_string(inverted ? faces[f][2] : faces[f][1]) + " " +
             std::to_string(inverted ? faces[f][1] : faces[f][2]) + "\n";
    return s;
}

} // namespace

TEST_CASE("solids: shapes, permeability, saturation and a keyed pose", "[solids][scene]") {
    const std::vector<SolidParams> s = solids(R"(
[[solids]]
shape = "cone"
radius = 0.02
tip_radius = 0.002
height = 0.06
permeability = 2000
saturation = 1.6e6
position = [0.0, 0.0, 0.001]
[[solids.keys]]
time = 0.0
position = [0.0, 0.0, 0.001]
[[solids.keys]]
time = 1.0
position = [0.01, 0.0, 0.001]
axis = [1.0, 0.0, 1.0]
[[solids]]
shape = "sphere"
radius = 0.005
)");
    REQUIRE(s.size() == 2);
    CHECK(s[0].shape == SolidParams::Shape::Cone);
    CHECK(s[0].permeability == 2000);
    CHECK(s[0].saturation == 1.6e6);
    CHECK(s[0].moves());
    CHECK_FALSE(s[1].moves());
    CHECK(s[1].permeability == 1000); // the default, soft iron
    // The pose holds the keys at their times and turns the axis by slerp between them.
    CHECK((s[0].at(1.0).position - Vec3d(0.01, 0, 0.001)).norm() < 1e-12);
    CHECK(s[0].at(0.5).axis.dot(Vec3d(0, 0, 1)) == Approx(std::cos(3.14159265358979 / 8)).epsilon(1e-9));
    // The surface at t = 1 stands on the key's position, its axis along the key's axis.
    const ShapeMesh cone = solidShape(s[0], 0.004, "t.toml");
    const SolidSurface moved = solidSurfaceAt(s[0], cone, 1.0);
    Vec3d top = moved.vertices[0];
    for (const Vec3d& v : moved.vertices)
        if ((v - Vec3d(0.01, 0, 0.001)).dot(Vec3d(1, 0, 1).normalized()) > (top - Vec3d(0.01, 0, 0.001)).dot(Vec3d(1, 0, 1).normalized()))
            top = v;
    CHECK((top - Vec3d(0.01, 0, 0.001)).dot(Vec3d(1, 0, 1).normalized()) == Approx(0.06).epsilon(1e-9));
}

TEST_CASE("a bad solid is a one-line SceneError naming the key", "[solids][scene]") {
    TempDir dir("solids");
    const std::string open = dir.write("open.obj", cubeObj(true, false));
    const std::string inverted = dir.write("inverted.obj", cubeObj(false, true));
    const std::string good = dir.write("cube.obj", cubeObj(false, false));
    CHECK(errorOf("[[solids]]\nshape = \"mesh\"\nfile = \"" + good + "\"\n").empty());
    const std::pair<std::string, std::string> cases[] = {
        {"[[solids]]\nshape = \"sphere\"\nradius = 0.01\npermeability = 1.0\n", "solids[0].permeability: must be > 1"},
        {"[[solids]]\nshape = \"sphere\"\nradius = 0.01\npermeability = 2e5\n", "solids[0].permeability: must be > 1"},
        {"[[solids]]\nshape = \"cylinder\"\nradius = 0.01\n", "solids[0].height"},
        {"[[solids]]\nshape = \"cone\"\nradius = 0.01\nheight = 0.02\ntip_radius = 0.01\n", "tip_radius: must be smaller"},
        {"[[solids]]\nshape = \"cube\"\n", "solids[0].shape"},
        {"[[solids]]\nshape = \"sphere\"\nradius = 0.01\nsaturation = -1\n", "solids[0].saturation"},
        {"[[solids]]\nshape = \"mesh\"\nfile = \"" + open + "\"\n", "mesh is not closed (4 boundary edges"},
        {"[[solids]]\nshape = \"mesh\"\nfile = \"" + inverted + "\"\n", "mesh is inside out"},
        {"[[solids]]\nshape = \"mesh\"\nfile = \"" + dir.file("missing.obj") + "\"\n", "solids[0].file"},
        {"[[solids]]\nshape = \"sphere\"\nradius = 0.01\ncolour = 1\n", "colour"},
    };
    for (const auto& [text, expected] : cases) {
        const std::string e = errorOf(text);
        INFO(text << "\n-> " << e);
        CHECK(e.find(expected) != std::string::npos);
        CHECK(e.find('\n') == std::string::npos);
    }
}

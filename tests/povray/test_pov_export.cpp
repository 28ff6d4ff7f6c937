// ferro-pov: number formatting, the z-up -> y-up conversion, mesh2 and magnet includes, the
// shot files, and real renders with the povray binary (POV-Ray parses every file we write).
#include "PovTestUtil.hpp"
#include "sim/core/Constants.hpp"

#include "povray/PovExport.hpp"
#include "povray/RenderParams.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/MagnetScene.hpp"

#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <Eigen/LU>

using namespace ferro;
using namespace ferro::povtest;

namespace {

// The dish of examples/dish.toml, no magnets, small and quick; `extra` is appended.
std::string dishScene(const std::string& extra = {})
{
    return R"(
[shot]
fps = 10
duration = 0.5
[[fluid.block]]
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.05
height = 0.01
count = 500
[container]
type = "dish"
center = [0.0, 0.0, 0.0]
radius = 0.05
height = 0.02
)" + extra;
}

std::string format(double v, int decimals)
{
    std::string s;
    appendNumber(s, v, decimals);
    return s;
}

// Pixel (column, row) where Ferro point `p` appears for the camera of `r` in a W x H image:
// POV-Ray's perspective camera with `angle` as the horizontal field of view and z (Ferro) up.
std::pair<int, int> project(const RenderParams& r, const Vec3d& p, int width, int height)
{
    const Vec3d f = (r.cameraTarget - r.cameraPosition).normalized();
    const Vec3d right = f.cross(Vec3d(0, 0, 1)).normalized(); // right-handed, z up
    const Vec3d up = right.cross(f);
    const Vec3d d = p - r.cameraPosition;
    const double t = std::tan(r.cameraAngle * kPi / 360.0);
    const double aspect = double(width) / height;
    const double u = d.dot(right) / d.dot(f) / t;            // -1 .. 1 across the width
    const double v = d.dot(up) / d.dot(f) / (t / aspect);    // -1 .. 1 up the height
    return {int((u + 1) / 2 * width), int((1 - v) / 2 * height)};
}

} // namespace

TEST_CASE("numbers are written with the fewest digits that keep the precision", "[pov]")
{
    CHECK(format(1.5, 3) == "1.5");
    CHECK(format(3.0, 3) == "3");
    CHECK(format(12.3456, 3) == "12.346");
    CHECK(format(-0.002, 3) == "-0.002");
    CHECK(format(-0.0004, 3) == "0");   // never "-0"
    CHECK(format(0.0004, 3) == "0");
    CHECK(format(-120.0, 4) == "-120");
    CHECK(format(0.70710678, 4) == "0.7071");
    CHECK(format(std::nan(""), 3) == "0");
    std::string v;
    appendVector(v, Vec3d(1, -2.5, 0.125), 3);
    CHECK(v == "<1,-2.5,0.125>");
}

TEST_CASE("Ferro z-up metres map to POV-Ray y-up millimetres by a reflection", "[pov]")
{
    const Vec3d p = toPovPoint(Vec3d(0.001, 0.002, 0.003));
    CHECK(p.x() == Approx(1.0));
    CHECK(p.y() == Approx(3.0)); // Ferro's z (up) is POV-Ray's y (up)
    CHECK(p.z() == Approx(2.0));
    // The map's determinant is -1: it turns the right-handed frame into a left-handed one,
    // which is what POV-Ray's is, so the picture is not mirrored (checked on a render below).
    Eigen::Matrix3d m;
    m << toPovDirection(Vec3d::UnitX()), toPovDirection(Vec3d::UnitY()), toPovDirection(Vec3d::UnitZ());
    CHECK(m.determinant() == Approx(-1.0));
}

TEST_CASE("mesh2 include: counts, every vertex and normal, and an empty mesh", "[pov]")
{
    TriangleMesh tri;
    tri.vertices = {Vec3(0, 0, 0), Vec3(0.01f, 0, 0), Vec3(0, 0.01f, 0.002f)};
    tri.triangles = {{0, 1, 2}};
    const std::string text = meshInclude(tri, 7);
    CHECK(text.find("#declare FerroMeshTriangles = 1;") != std::string::npos);
    CHECK(text.find("vertex_vectors { 3,\n<0,0,0>,\n<10,0,0>,\n<0,2,10>\n }") != std::string::npos);
    // Normals computed from the triangle: Ferro (x,y,z) -> (x,z,y), the face faces +z.
    CHECK(text.find("normal_vectors { 3,\n<0") != std::string::npos);
    CHECK(text.find("face_indices { 1,\n<0,1,2>\n }") != std::string::npos);

    const std::string empty = meshInclude(TriangleMesh{}, 3);
    CHECK(empty.find("#declare FerroMeshTriangles = 0;") != std::string::npos);
    CHECK(empty.find("FerroMesh =") == std::string::npos);

    TriangleMesh bad = tri;
    bad.triangles = {{0, 1, 5}};
    CHECK_THROWS_AS(meshInclude(bad, 0), MeshFileError);
}

TEST_CASE("[render] defaults, overrides and unknown keys", "[pov]")
{
    const RenderParams def = parseRenderParams(SceneDocument::parse(dishScene(), "s.toml"));
    CHECK(def.width == 640);
    CHECK(def.cameraAngle == 40.0);
    const RenderParams r = parseRenderParams(
        SceneDocument::parse(dishScene("[render]\nwidth = 320\nheight = 200\nantialias = false\nlight_samples = 2\n"),
                             "s.toml", {"render.camera_angle=30"}));
    CHECK(def.lightSamples == 3);
    CHECK(r.lightSamples == 2);
    CHECK_THROWS_WITH(parseRenderParams(SceneDocument::parse(dishScene("[render]\nlight_samples = 0\n"), "s.toml")),
                      Catch::Contains("render.light_samples"));
    CHECK(r.width == 320);
    CHECK(r.height == 200);
    CHECK_FALSE(r.antialias);
    CHECK(r.cameraAngle == 30.0);
    CHECK_THROWS_WITH(parseRenderParams(SceneDocument::parse(dishScene("[render]\nwidht = 3\n"), "s.toml")),
                      Catch::Contains("widht"));
    CHECK_THROWS_WITH(parseRenderParams(SceneDocument::parse(dishScene("[render]\nquality = 12\n"), "s.toml")),
                      Catch::Contains("render.quality"));
    CHECK_THROWS_WITH(parseRenderParams(SceneDocument::parse(
                          dishScene("[render]\ncamera_position = [0, 0, 1]\ncamera_target = [0, 0, 0]\n"), "s.toml")),
                      Catch::Contains("straight"));
    // Fuzz finding: both corners finite, their distance not; the view direction was nan.
    CHECK_THROWS_WITH(parseRenderParams(SceneDocument::parse(
                          dishScene("[render]\ncamera_position = [1e308, 0, 0.1]\ncamera_target = [-1e308, 0, 0]\n"),
                          "s.toml")),
                      Catch::Contains("render.camera_target: is too far from render.camera_position"));

    ShotDescription shot = describeShot(SceneDocument::parse(dishScene("[render]\nwidth = 320\n"), "s.toml"));
    CHECK(shot.lastFrame == 5); // 0.5 s at 10 fps
    CHECK(renderIni(shot).find("Width=320\n") != std::string::npos);
    CHECK(masterScene(describeShot(SceneDocument::parse(dishScene("[render]\nlight_samples = 2\n"), "s.toml")))
              .find("#declare FerroLightSamples = 2;") != std::string::npos);
    CHECK(lookTemplate().find("area_light x * Size, z * Size, FerroLightSamples, FerroLightSamples") != std::string::npos);
    CHECK(shotIni(shot).find("Final_Frame=5\n") != std::string::npos);
    CHECK(shotIni(shot).find("Final_Clock=0.5\n") != std::string::npos);
    CHECK(masterScene(shot).find("#declare FerroDishRadius = 50;") != std::string::npos);

    // Motion blur: off by default (nothing of it in the shot files), 0..64 sub-frames, a
    // shutter in (0, 1].
    CHECK(def.motionBlur == 0);
    CHECK(def.shutter == 0.5);
    CHECK(masterScene(shot).find("FerroShift") == std::string::npos);
    CHECK_THROWS_WITH(parseRenderParams(SceneDocument::parse(dishScene("[render]\nmotion_blur = 65\n"), "s.toml")),
                      Catch::Contains("render.motion_blur"));
    CHECK_THROWS_WITH(parseRenderParams(SceneDocument::parse(dishScene("[render]\nshutter = 1.5\n"), "s.toml")),
                      Catch::Contains("render.shutter: must be in (0, 1]"));
    CHECK_THROWS_WITH(parseRenderParams(SceneDocument::parse(dishScene("[render]\nshutter = 0\n"), "s.toml")),
                      Catch::Contains("render.shutter"));
}

TEST_CASE("magnets come from the mesh header, else from the scene's tracks", "[pov]")
{
    const SceneDocument doc = SceneDocument::parse(dishScene(R"(
[[magnets]]
kind = "dipole"
position = [0.0, 0.0, -0.08]
moment = 1.5
[[magnets.keys]]
time = 0.0
position = [0.0, 0.0, -0.08]
[[magnets.keys]]
time = 1.0
position = [0.0, 0.0, -0.02]
)"),
                                                   "s.toml");
    const std::vector<MagnetTrack> tracks = parseMagnets(doc);
    TriangleMesh mesh;
    // No header: the track at t = 1 s.
    std::vector<Magnet> m = frameMagnets(mesh, tracks, 1.0);
    REQUIRE(m.size() == 1);
    CHECK(m[0].position.z() == Approx(-0.02));
    // A header wins over the tracks.
    ParticleTable header;
    Magnet bar;
    bar.kind = Magnet::Kind::Bar;
    bar.position = Vec3d(0.01, 0, -0.03);
    bar.strength = -2.0;
    bar.length = 0.03;
    writeMagnetComments(header, {bar});
    mesh.comments = header.comments;
    m = frameMagnets(mesh, tracks, 1.0);
    REQUIRE(m.size() == 1);
    CHECK(m[0].kind == Magnet::Kind::Bar);
    CHECK(m[0].position.x() == Approx(0.01));

    RenderParams render;
    const std::string text = magnetInclude(m, render, 4, 0.4);
    CHECK(text.find("#declare FerroMagnetCount = 1;") != std::string::npos);
    CHECK(text.find("FerroMagnetKind = array[1] { \"bar\" }") != std::string::npos);
    CHECK(text.find("FerroMagnetPosition = array[1] { <10,-30,0> }") != std::string::npos);
    // Negative strength: the axis (south -> north) is flipped.
    CHECK(text.find("FerroMagnetDirection = array[1] { <0,-1,0> }") != std::string::npos);
    CHECK(text.find("FerroMagnetLength = array[1] { 30 }") != std::string::npos);

    // No magnets anywhere: a count of zero and nothing else.
    const std::string none = magnetInclude({}, render, 0, 0);
    CHECK(none.find("#declare FerroMagnetCount = 0;") != std::string::npos);
    CHECK(none.find("array") == std::string::npos);
}

TEST_CASE("povray renders an exported frame: dark fluid, bright background, not mirrored", "[pov][povray]")
{
    const fs::path dir = freshDir("render");
    const SceneDocument doc = SceneDocument::parse(dishScene(R"(
[[magnets]]
kind = "dipole"
position = [0.0, 0.0, -0.03]
moment = 1.0
[[magnets]]
kind = "loop"
position = [0.0, 0.0, -0.05]
radius = 0.03
current = 100.0
)"),
                                                   (dir / "scene.toml").string());
    const PovExporter exporter(doc, dir.string());
    exporter.writeShotFiles(false);
    // A black ball to the right (+x) of the dish's centre and high above it.
    const Vec3d ball(0.025, 0.0, 0.035);
    exporter.exportFrame(sphereMesh(ball.cast<float>(), 0.012f), 2);
    const int W = 96, H = 72;
    const Result res = renderFrame(dir, 2, W, H, "frame");
    INFO(res.output);
    REQUIRE(res.code == 0);
    const Image img = readPpm(dir / "frame.ppm");
    REQUIRE(img.width == W);
    REQUIRE(img.height == H);

    const RenderParams render = exporter.shot().render;
    const auto [col, row] = project(render, ball, W, H);
    INFO("ball centre at pixel " << col << ", " << row);
    // The ball is on the right half and the upper half: +x is right, +z is up.
    CHECK(col > W / 2);
    CHECK(row < H / 2);
    CHECK(img.brightness(col, row, 1) < 0.12);                 // the fluid is black
    // Its mirror image across the vertical centre line shows the set, not the fluid.
    const auto [mcol, mrow] = project(render, Vec3d(-ball.x(), ball.y(), ball.z()), W, H);
    CHECK(img.brightness(mcol, mrow, 1) > 0.25);
    // The background (the image's top corners) is not dark.
    CHECK(img.brightness(2, 2, 2) > 0.25);
    CHECK(img.brightness(W - 3, 2, 2) > 0.25);
}

TEST_CASE("povray parses an empty frame and a frame without magnets", "[pov][povray]")
{
    const fs::path dir = freshDir("empty");
    const SceneDocument doc = SceneDocument::parse(dishScene(), (dir / "scene.toml").string());
    const PovExporter exporter(doc, dir.string());
    exporter.writeShotFiles(false);
    exporter.exportFrame(TriangleMesh{}, 0);
    CHECK(slurp(dir / "magnets_0000.inc").find("FerroMagnetCount = 0;") != std::string::npos);
    const Result res = renderFrame(dir, 0, 32, 24, "empty");
    INFO(res.output);
    CHECK(res.code == 0);
    CHECK(readPpm(dir / "empty.ppm").brightness(16, 2, 1) > 0.25);
}

TEST_CASE("povray shot.ini renders a frame range through POV-Ray's animation options", "[pov][povray]")
{
    const fs::path dir = freshDir("animation");
    const SceneDocument doc = SceneDocument::parse(dishScene(), (dir / "scene.toml").string());
    const PovExporter exporter(doc, dir.string());
    exporter.writeShotFiles(false);
    for (int f = 0; f <= 5; ++f)
        exporter.exportFrame(sphereMesh(Vec3(0, 0, 0.005f + 0.002f * f), 0.01f, 12, 6), f);
    const Result res = run("cd '" + dir.string() + "' && povray shot.ini -D +W16 +H12 +SF2 +EF3");
    INFO(res.output);
    REQUIRE(res.code == 0);
    // Final_Frame = 5 has one digit, so POV-Ray names the frames shot_2.png, shot_3.png.
    CHECK(fs::exists(dir / "frames" / "shot_2.png"));
    CHECK(fs::exists(dir / "frames" / "shot_3.png"));
    CHECK_FALSE(fs::exists(dir / "frames" / "shot_1.png"));
    CHECK_FALSE(fs::exists(dir / "frames" / "shot_4.png"));
}

namespace {
// sRGB's transfer: 8-bit code <-> linear light.
double srgbToLinear(int c)
{
    const double v = c / 255.0;
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}
double linearToSrgb(double l)
{
    return 255.0 * (l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1 / 2.4) - 0.055);
}
} // namespace

TEST_CASE("motion blur: each sub-frame is the mesh moved along its velocity over the shutter, the frame their mean in linear light",
          "[pov][povray][blur]")
{
    // A black ball crossing the view at 0.2 m/s, shutter 1 (the whole frame interval, 0.1 s at
    // 10 fps), three sub-frames: the ball at -1 cm, 0 and +1 cm of its frame position. The
    // references are sharp renders of the ball placed there by hand.
    const std::string blurred = "[render]\nmotion_blur = 3\nshutter = 1.0\nantialias = false\n";
    const fs::path dir = freshDir("blur"), ref = freshDir("blur-reference");
    const SceneDocument doc = SceneDocument::parse(dishScene(blurred), (dir / "scene.toml").string());
    const PovExporter exporter(doc, dir.string());
    exporter.writeShotFiles(false);
    for (const char* f : {"blur.ini", "average.ini", "average.pov"}) REQUIRE(fs::exists(dir / f));
    const Vec3 ball(0.0f, 0.0f, 0.03f), velocity(0.2f, 0.0f, 0.0f);
    TriangleMesh mesh = sphereMesh(ball, 0.01f, 24, 12);
    mesh.velocities.assign(mesh.vertices.size(), velocity);
    exporter.exportFrame(mesh, 2);
    CHECK(slurp(dir / "mesh_0002.inc").find("+FerroShift*<200,0,0>") != std::string::npos);   // mm/s, y up

    const int W = 48, H = 36;
    const std::string size = " +W" + std::to_string(W) + " +H" + std::to_string(H);
    fs::create_directories(dir / "sub");
    Result res = run("cd '" + dir.string() + "' && povray blur.ini -D Declare=FerroFrame=2 +FP" + size + " +Osub/frame_0002_.ppm");
    INFO(res.output);
    REQUIRE(res.code == 0);

    const PovExporter sharp(SceneDocument::parse(dishScene("[render]\nantialias = false\n"), (ref / "scene.toml").string()),
                            ref.string());
    sharp.writeShotFiles(false);
    std::vector<Image> refs;
    for (int k = 0; k < 3; ++k) {
        const float shift = (-0.5f + 0.5f * k) * 0.1f;   // clock -0.5 .. 0.5 times the shutter's 0.1 s
        sharp.exportFrame(sphereMesh(ball + shift * velocity, 0.01f, 24, 12), 2);
        REQUIRE(renderFrame(ref, 2, W, H, "ref" + std::to_string(k)).code == 0);
        refs.push_back(readPpm(ref / ("ref" + std::to_string(k) + ".ppm")));
        const Image sub = readPpm(dir / "sub" / ("frame_0002_" + std::to_string(k + 1) + ".ppm"));
        REQUIRE(sub.rgb.size() == refs[k].rgb.size());
        size_t differ = 0;
        for (size_t i = 0; i < sub.rgb.size(); ++i) differ += std::abs(int(sub.rgb[i]) - int(refs[k].rgb[i])) > 2;
        INFO("sub-frame " << k + 1 << ": " << differ << " of " << sub.rgb.size() << " values differ from the sharp render");
        CHECK(differ < sub.rgb.size() / 200);   // only where the positions' rounding tips an edge pixel
    }
    // The sub-frames differ from each other: the ball moved.
    CHECK(refs[0].rgb != refs[2].rgb);

    // The frame: the three sub-frames (as PNG, what shot.mk renders) averaged by average.ini.
    res = run("cd '" + dir.string() + "' && povray blur.ini -D Declare=FerroFrame=2" + size +
              " +Osub/frame_0002_.png && povray average.ini -D Declare=FerroFrame=2 +FP" + size + " +Oblur.ppm");
    INFO(res.output);
    REQUIRE(res.code == 0);
    const Image frame = readPpm(dir / "blur.ppm");
    REQUIRE(frame.rgb.size() == refs[0].rgb.size());
    double meanError = 0;
    size_t far = 0;
    for (size_t i = 0; i < frame.rgb.size(); ++i) {
        const double expected =
            linearToSrgb((srgbToLinear(refs[0].rgb[i]) + srgbToLinear(refs[1].rgb[i]) + srgbToLinear(refs[2].rgb[i])) / 3);
        const double e = std::abs(frame.rgb[i] - expected);
        meanError += e / frame.rgb.size();
        far += e > 3;
    }
    INFO("mean error " << meanError << " levels, " << far << " values more than 3 levels off");
    CHECK(meanError < 0.6);
    CHECK(far < frame.rgb.size() / 100);

    // Turned off again, the blur files go and the meshes are written as before.
    const PovExporter off(SceneDocument::parse(dishScene(), (dir / "scene.toml").string()), dir.string());
    off.writeShotFiles(false);
    off.exportFrame(mesh, 2);
    CHECK_FALSE(fs::exists(dir / "blur.ini"));
    CHECK_FALSE(fs::exists(dir / "average.pov"));
    CHECK(slurp(dir / "mesh_0002.inc").find("FerroShift") == std::string::npos);
}

TEST_CASE("a solid is drawn in brushed steel where it stands, and a scene without solids is unchanged", "[pov][povray][solids]")
{
    const fs::path dir = freshDir("solid");
    // A steel cylinder standing right of the dish's centre, taller than the (empty) fluid.
    const std::string magnets = R"(
[[magnets]]
kind = "coil"
position = [0.0, 0.0, -0.03]
radius = 0.02
length = 0.02
turns = 200
current = 2.0
)";
    const SceneDocument doc = SceneDocument::parse(dishScene(magnets + R"(
[[solids]]
shape = "cylinder"
radius = 0.008
height = 0.03
position = [0.025, 0.0, 0.0]
)"),
                                                   (dir / "scene.toml").string());
    const PovExporter exporter(doc, dir.string());
    exporter.writeShotFiles(false);
    exporter.exportFrame(TriangleMesh{}, 0);
    const std::string inc = slurp(dir / "magnets_0000.inc");
    CHECK(inc.find("#declare FerroSolidCount = 1;") != std::string::npos);
    CHECK(inc.find("#declare FerroSolids = union {") != std::string::npos);
    CHECK(slurp(dir / "look.inc").find("object { FerroSolids texture { LookSteel } }") != std::string::npos);
    const int W = 96, H = 72;
    const Result res = renderFrame(dir, 0, W, H, "frame");
    INFO(res.output);
    REQUIRE(res.code == 0);
    const Image img = readPpm(dir / "frame.ppm");
    // Halfway up the cylinder's axis: grey steel, and its mirror image left of the centre is the set.
    const RenderParams render = exporter.shot().render;
    const auto [col, row] = project(render, Vec3d(0.025, 0.0, 0.015), W, H);
    const auto [mcol, mrow] = project(render, Vec3d(-0.025, 0.0, 0.015), W, H);
    INFO("steel at " << col << ", " << row << ": " << img.brightness(col, row, 1) << "; mirror " << img.brightness(mcol, mrow, 1));
    CHECK(img.brightness(col, row, 1) > 0.08);
    CHECK(std::abs(img.brightness(col, row, 1) - img.brightness(mcol, mrow, 1)) > 0.03);

    // The same scene without the solid: no solid lines in the include at all.
    const fs::path plain = freshDir("solid_plain");
    const PovExporter plainExporter(SceneDocument::parse(dishScene(magnets), (plain / "scene.toml").string()), plain.string());
    plainExporter.exportFrame(TriangleMesh{}, 0);
    CHECK(slurp(plain / "magnets_0000.inc").find("FerroSolid") == std::string::npos);
}

// ferro-pov as users run it: the look template survives re-exports, frame ranges, one-line
// errors with exit code 2, outputs never half-written.
#include "PovTestUtil.hpp"

#include <catch2/catch.hpp>

using namespace ferro;
using namespace ferro::povtest;

namespace {

const std::string kPov = kBin + "ferro-pov";

const char* kScene = R"(
[shot]
fps = 10
duration = 0.3
[[fluid.block]]
shape = "box"
min = [-0.01, -0.01, 0.0]
max = [0.01, 0.01, 0.005]
count = 200
[container]
type = "box"
min = [-0.02, -0.02, 0.0]
max = [0.02, 0.02, 0.02]
[render]
width = 48
height = 36
)";

// A tetrahedron as ASCII PLY with a frame comment.
void writeTetrahedron(const fs::path& path, int frame)
{
    spit(path, "ply\nformat ascii 1.0\ncomment frame " + std::to_string(frame) +
                   "\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
                   "0 0 0\n0.01 0 0\n0 0.01 0\n0 0 0.01\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
}

} // namespace

TEST_CASE("ferro-pov keeps an edited look.inc, and --force-template replaces it", "[pov][cli]")
{
    const fs::path dir = freshDir("template");
    spit(dir / "scene.toml", kScene);
    writeTetrahedron(dir / "mesh.ply", 2);
    const std::string base = kPov + " '" + (dir / "mesh.ply").string() + "' --scene '" + (dir / "scene.toml").string() +
                             "' --out '" + (dir / "shot").string() + "' --quiet";
    REQUIRE(run(base).code == 0);
    const fs::path look = dir / "shot" / "look.inc";
    const std::string fresh = slurp(look);
    REQUIRE(fresh.find("LookFluid") != std::string::npos);
    CHECK(fs::exists(dir / "shot" / "mesh_0002.inc")); // frame from the mesh's comment

    // An artist turns the fluid red.
    std::string edited = fresh;
    const std::string from = "pigment { rgb 0.004 }";
    REQUIRE(edited.find(from) != std::string::npos);
    edited.replace(edited.find(from), from.size(), "pigment { rgb <0.8, 0, 0> }  // ARTIST EDIT");
    spit(look, edited);

    // Re-export with another [render] (the master scene changes): the edit survives.
    Result res = run(base + " --frame 3 --set render.width=64");
    INFO(res.output);
    REQUIRE(res.code == 0);
    CHECK(slurp(look) == edited);
    CHECK(slurp(dir / "shot" / "render.ini").find("Width=64") != std::string::npos);
    // ... and POV-Ray renders it red.
    res = renderFrame(dir / "shot", 3, 48, 36, "edited");
    INFO(res.output);
    REQUIRE(res.code == 0);

    res = run(base + " --frame 3 --force-template");
    REQUIRE(res.code == 0);
    CHECK(slurp(look) == fresh);
}

TEST_CASE("ferro-pov writes a frame range and leaves unchanged shot files alone", "[pov][cli]")
{
    const fs::path dir = freshDir("range");
    spit(dir / "scene.toml", kScene);
    fs::create_directories(dir / "m");
    for (int f = 0; f <= 3; ++f)
        writeTetrahedron(dir / "m" / ("spiky_000" + std::to_string(f) + ".ply"), f);
    const std::string cmd = kPov + " '" + (dir / "m" / "spiky_{:04}.ply").string() + "' --frames 1:3 --scene '" +
                            (dir / "scene.toml").string() + "' --out '" + (dir / "shot").string() + "' --quiet";
    Result res = run(cmd);
    INFO(res.output);
    REQUIRE(res.code == 0);
    CHECK_FALSE(fs::exists(dir / "shot" / "mesh_0000.inc"));
    for (int f = 1; f <= 3; ++f) {
        CHECK(fs::exists(dir / "shot" / ("mesh_000" + std::to_string(f) + ".inc")));
        CHECK(fs::exists(dir / "shot" / ("magnets_000" + std::to_string(f) + ".inc")));
    }
    CHECK(slurp(dir / "shot" / "shot.ini").find("Final_Frame=3\n") != std::string::npos);

    // A second export with the same scene does not touch shot.pov (make would re-render).
    const auto before = fs::last_write_time(dir / "shot" / "shot.pov");
    REQUIRE(run(cmd).code == 0);
    CHECK(fs::last_write_time(dir / "shot" / "shot.pov") == before);

    // Every exported frame renders (frame 0 was not exported).
    res = run("cd '" + (dir / "shot").string() + "' && povray shot.ini -D +FP +SF1 +EF3");
    INFO(res.output);
    CHECK(res.code == 0);
    CHECK(fs::exists(dir / "shot" / "frames" / "shot_3.ppm"));
}

TEST_CASE("ferro-pov rejects bad input with one line and exit code 2", "[pov][cli]")
{
    const fs::path dir = freshDir("errors");
    spit(dir / "scene.toml", kScene);
    spit(dir / "bad.toml", std::string(kScene) + "camera_angle = 500\n");
    writeTetrahedron(dir / "mesh.ply", 0);
    const std::string scene = " --scene '" + (dir / "scene.toml").string() + "' --out '" + (dir / "shot").string() + "'";

    auto oneLineError = [](const Result& r) {
        INFO(r.output);
        CHECK(r.code == 2);
        CHECK(r.output.rfind("ferro-pov: error: ", 0) == 0);
        CHECK(std::count(r.output.begin(), r.output.end(), '\n') == 1);
    };
    // Missing meshes are I/O errors (exit 4), like ferro-surface's and ferro-spikes' inputs.
    auto missingError = [](const Result& r) {
        INFO(r.output);
        CHECK(r.code == 4);
        CHECK(r.output.rfind("ferro-pov: error: ", 0) == 0);
        CHECK(std::count(r.output.begin(), r.output.end(), '\n') == 1);
    };
    missingError(run(kPov + " '" + (dir / "missing.ply").string() + "'" + scene + " --frame 0"));
    missingError(run(kPov + " '" + (dir / "m_{:04}.ply").string() + "'" + scene + " --frames 0:2"));
    oneLineError(run(kPov + " '" + (dir / "mesh.ply").string() + "'" + scene + " --frames 3:1"));
    // Frame numbers that would overflow an int (std::stoi used to abort here).
    for (const char* frames : {"0:99999999999", "0:2147483647", "-1:2", "1:2:3"}) {
        INFO(frames);
        oneLineError(run(kPov + " '" + (dir / "m_{:04}.ply").string() + "'" + scene + " --frames " + frames));
        oneLineError(run(kPov + scene + " --shot-frames " + frames));
    }
    // A mesh with a non-finite vertex: POV-Ray has no literal for it, and 0 would hide the fault.
    {
        TriangleMesh nan;
        nan.vertices = {Vec3(0, 0, 0), Vec3(std::nanf(""), 0, 0), Vec3(0, 0.01f, 0)};
        nan.triangles = {{0, 1, 2}};
        writeMesh((dir / "nan.ply").string(), nan);
    }
    {
        const Result r = run(kPov + " '" + (dir / "nan.ply").string() + "'" + scene + " --frame 0");
        oneLineError(r);
        CHECK(r.output.find("not finite") != std::string::npos);
    }
    oneLineError(run(kPov + " '" + (dir / "mesh.ply").string() + "'" + scene + " --set render.widht=3"));
    oneLineError(run(kPov + " '" + (dir / "mesh.ply").string() + "' --scene '" + (dir / "bad.toml").string() +
                     "' --out '" + (dir / "shot").string() + "'"));
    spit(dir / "garbage.ply", "ply\nthis is not a mesh\n");
    oneLineError(run(kPov + " '" + (dir / "garbage.ply").string() + "'" + scene + " --frame 0"));
    // Nothing was written by the failed runs.
    CHECK_FALSE(fs::exists(dir / "shot" / "mesh_0000.inc"));
}

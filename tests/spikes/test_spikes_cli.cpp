// ferro-spikes on files: the shipped scenes parse, one frame and a frame range run end to end,
// bad input is one line on stderr and exit code 2.
#include "SpikeTestMeshes.hpp"

#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "spikes/SpikeFrames.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace ferro;
namespace fs = std::filesystem;

namespace {

const std::string kExe = FERRO_BINARY_DIR "/bin/ferro-spikes";
const std::string kSource = FERRO_SOURCE_DIR;

fs::path scratch(const std::string& name)
{
    const fs::path dir = fs::temp_directory_path() / ("ferro_spikes_" + name);
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

// Runs ferro-spikes with `args`; returns its exit code and stderr.
int run(const std::string& args, std::string& err, const fs::path&)
{
    const test::CommandResult r = test::runCommand(kExe + " " + args, test::Capture::Stderr);
    err = r.output;
    return r.code;
}

std::string comment(const TriangleMesh& mesh, const std::string& key)
{
    for (const auto& kv : mesh.comments)
        if (kv.first == key) return kv.second;
    return {};
}

} // namespace

TEST_CASE("shipped scenes parse with their [spikes] sections", "[spikes][cli]")
{
    const SpikeScene lab = parseSpikeScene(SceneDocument::load(kSource + "/examples/rosensweig_uniform.toml"));
    REQUIRE(lab.params.spacing == SpikeParams::Spacing::Physical);
    REQUIRE(lab.magnets.size() == 1);
    // 1.5 times the critical applied field of a flat layer (eq. 16, normal B continuous).
    const CriticalMagnetization c = criticalMagnetization(lab.fluid.density - lab.params.ambientDensity,
                                                          lab.fluid.gravity.norm(), lab.fluid.surfaceTension,
                                                          lab.fluid.law);
    REQUIRE(lab.magnets[0].at(0.0).strength == Approx(1.5 * c.appliedField).epsilon(0.002));
    const SpikeScene annotated = parseSpikeScene(SceneDocument::load(kSource + "/examples/annotated.toml"));
    REQUIRE(annotated.params.resolution == SpikeParams().resolution);
    REQUIRE(annotated.params.alpha == SpikeParams().alpha);
    REQUIRE(annotated.params.beta == SpikeParams().beta);
}

TEST_CASE("ferro-spikes: one frame and a frame range from files", "[spikes][cli]")
{
    const fs::path dir = scratch("cli");
    const std::string scene = kSource + "/examples/rosensweig_uniform.toml";
    TriangleMesh pool = spiketest::makeFlatPool(0.05, 0.01, 30);
    pool.comments = {{"frame", "0"}, {"time", "0"}};
    writeMesh((dir / "surface_0000.ply").string(), pool);
    pool.comments = {{"frame", "1"}, {"time", "0.0333333"}};
    writeMesh((dir / "surface_0001.ply").string(), pool);

    std::string err;
    REQUIRE(run((dir / "surface_0000.ply").string() + " --scene " + scene + " --out " + (dir / "one.ply").string() +
                    " --quiet",
                err, dir) == 0);
    const TriangleMesh one = readMesh((dir / "one.ply").string());
    REQUIRE(one.triangles.size() > pool.triangles.size());
    REQUIRE(std::stoi(comment(one, "spike_tips")) >= 19);
    REQUIRE(std::stod(comment(one, "spike_spacing")) == Approx(0.0106).epsilon(0.01));
    REQUIRE(comment(one, "magnet_count") == "1");
    REQUIRE(std::abs(enclosedVolume(one) - enclosedVolume(pool)) < 0.005 * enclosedVolume(pool));

    REQUIRE(run("'" + (dir / "surface_{:04}.ply").string() + "' --frames 0:1 --threads 2 --scene " + scene +
                    " --out '" + (dir / "spiky_{:04}.ply").string() + "' --quiet",
                err, dir) == 0);
    const TriangleMesh f0 = readMesh((dir / "spiky_0000.ply").string());
    const TriangleMesh f1 = readMesh((dir / "spiky_0001.ply").string());
    REQUIRE(f0.vertices == f1.vertices); // still magnet, same surface: identical spikes
    REQUIRE(f0.vertices == one.vertices);
}

TEST_CASE("ferro-spikes: an empty surface (a frame without fluid) gives an empty spiky mesh", "[spikes][cli]")
{
    const fs::path dir = scratch("empty");
    const std::string scene = kSource + "/examples/rosensweig_uniform.toml";
    TriangleMesh empty;
    empty.comments = {{"frame", "4"}};
    writeMesh((dir / "surface_0004.ply").string(), empty);
    writeMesh((dir / "surface_0005.ply").string(), empty);
    std::string err;
    REQUIRE(run((dir / "surface_0004.ply").string() + " --scene " + scene + " --out " + (dir / "one.ply").string() +
                    " --quiet",
                err, dir) == 0);
    CHECK(err.empty());
    const TriangleMesh one = readMesh((dir / "one.ply").string());
    CHECK(one.vertices.empty());
    CHECK(one.triangles.empty());
    CHECK(comment(one, "frame") == "4");
    CHECK(comment(one, "spike_tips") == "0");
    REQUIRE(run("'" + (dir / "surface_{:04}.ply").string() + "' --frames 4:5 --scene " + scene + " --out '" +
                    (dir / "spiky_{:04}.ply").string() + "' --quiet",
                err, dir) == 0);
    CHECK(readMesh((dir / "spiky_0005.ply").string()).triangles.empty());
}

TEST_CASE("ferro-spikes: bad input is one line and exit code 2", "[spikes][cli]")
{
    const fs::path dir = scratch("bad");
    const std::string scene = kSource + "/examples/rosensweig_uniform.toml";
    writeMesh((dir / "pool.ply").string(), spiketest::makeFlatPool(0.05, 0.01, 8));
    std::string err;
    auto oneLine = [&](const std::string& e) {
        REQUIRE(e.rfind("ferro-spikes: error: ", 0) == 0);
        REQUIRE(std::count(e.begin(), e.end(), '\n') == 1);
    };
    // Missing input files are I/O errors (4), like ferro-surface's and ferro-pov's.
    REQUIRE(run((dir / "missing.ply").string() + " --scene " + scene + " --out " + (dir / "o.ply").string(), err,
                dir) == 4);
    oneLine(err);
    REQUIRE(run((dir / "pool.ply").string() + " --particles " + (dir / "missing.ply").string() + " --scene " + scene +
                    " --out " + (dir / "o.ply").string(),
                err, dir) == 4);
    oneLine(err);
    // A missing scene file is a missing input too (it used to be 2, bad input).
    REQUIRE(run((dir / "pool.ply").string() + " --scene " + (dir / "missing.toml").string() + " --out " +
                    (dir / "o.ply").string(),
                err, dir) == 4);
    oneLine(err);
    REQUIRE(run((dir / "pool.ply").string() + " --scene " + scene + " --set spikes.bogus=1 --out " +
                    (dir / "o.ply").string(),
                err, dir) == 2);
    oneLine(err);
    REQUIRE(err.find("bogus") != std::string::npos);
    REQUIRE(run((dir / "pool.ply").string() + " --scene " + scene + " --frames 3:1 --out " + (dir / "o.ply").string(),
                err, dir) == 2);
    oneLine(err);
    // Ranges whose last + 1 would overflow an int, and frames beyond seven digits.
    for (const char* frames : {"0:2147483647", "0:99999999999", "2147483647:2147483647", "-1:2"}) {
        INFO(frames);
        REQUIRE(run("'" + (dir / "s_{:04}.ply").string() + "' --scene " + scene + " --frames " + frames + " --out '" +
                        (dir / "o_{:04}.ply").string() + "'",
                    err, dir) == 2);
        oneLine(err);
        REQUIRE(err.find("--frames") != std::string::npos);
    }
    // A range needs a frame placeholder in the particle pattern too.
    REQUIRE(run("'" + (dir / "s_{:04}.ply").string() + "' --particles " + (dir / "p.ply").string() + " --scene " +
                    scene + " --frames 0:1 --out '" + (dir / "o_{:04}.ply").string() + "'",
                err, dir) == 2);
    oneLine(err);
    REQUIRE(err.find("--particles: a frame range needs a {:04} or %04d placeholder") != std::string::npos);
    // Particles with a NaN position.
    {
        ParticleTable t;
        t.names = {"x", "y", "z"};
        t.values = {0, 0, 0.01f, std::nanf(""), 0, 0.01f};
        writeParticleFile((dir / "nan.ply").string(), t);
    }
    REQUIRE(run((dir / "pool.ply").string() + " --particles " + (dir / "nan.ply").string() + " --scene " + scene +
                    " --out " + (dir / "o.ply").string(),
                err, dir) == 2);
    oneLine(err);
    REQUIRE(err.find("non-finite position") != std::string::npos);
    std::ofstream((dir / "garbage.ply").string()) << "ply\nformat nonsense\n";
    REQUIRE(run((dir / "garbage.ply").string() + " --scene " + scene + " --out " + (dir / "o.ply").string(), err,
                dir) == 2);
    oneLine(err);
    REQUIRE_FALSE(fs::exists(dir / "o.ply"));
}

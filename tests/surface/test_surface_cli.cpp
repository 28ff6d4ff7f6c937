// ferro-surface as artists run it: single frames, ranges, --vdb, --format, scenes, bad input.
#include "SurfaceTestShapes.hpp"

#include "sim/core/ParticleFile.hpp"
#include "sim/core/TriangleMesh.hpp"
#include "tests/TestUtil.hpp"

#include <openvdb/openvdb.h>

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include <unistd.h>

using namespace ferro;
namespace fs = std::filesystem;

namespace {

const std::string kExe = FERRO_BINARY_DIR "/bin/ferro-surface";
constexpr double kSpacing = 1.24e-3;

struct Scratch {
    fs::path dir;
    Scratch() {
        dir = fs::temp_directory_path() / ("ferro_surface_cli_" + std::to_string(::getpid()));
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
    ~Scratch() { fs::remove_all(dir); }
    std::string operator/(const std::string& name) const { return (dir / name).string(); }
};

/// Runs ferro-surface with `args`; returns its exit code, stderr in `err`.
int run(const std::string& args, const Scratch&, std::string* err = nullptr) {
    const test::CommandResult r = test::runCommand(kExe + " " + args, test::Capture::Stderr);
    if (err) *err = r.output;
    return r.code;
}

/// A particle file like ferro-sim's: a ball of particles and the header comments.
void writeBall(const std::string& path, int frame, double radius) {
    const std::vector<Vec3> x = test::sphereFill(radius, kSpacing, 0.1, uint64_t(frame + 1));
    ParticleTable t;
    t.names = {"x", "y", "z", "vx", "vy", "vz", "density"};
    for (const Vec3& p : x) t.values.insert(t.values.end(), {p.x(), p.y(), p.z(), 0, 0, 0, 1200});
    t.comments = {{"frame", std::to_string(frame)},
                  {"time", std::to_string(frame / 30.0)},
                  {"spacing", "0.00124"},
                  {"magnet_count", "1"},
                  {"magnet_0", "dipole 0 0 -0.02 0 0 1 3.5"},
                  {"susceptibility", "1.5"}};
    writeParticleFile(path, t);
}

} // namespace

TEST_CASE("ferro-surface meshes one particle file and carries its comments along", "[surface][cli]") {
    Scratch s;
    writeBall(s / "p.ply", 7, 6 * kSpacing);
    std::string err;
    REQUIRE(run("'" + (s / "p.ply") + "' --out '" + (s / "m.ply") + "' -q", s, &err) == 0);
    CHECK(err.empty());
    const TriangleMesh m = readMesh(s / "m.ply");
    REQUIRE_FALSE(m.empty());
    CHECK(m.normals.size() == m.vertices.size());
    const double particles = double(readParticleFile(s / "p.ply").rows()) * std::pow(kSpacing, 3);
    CHECK(enclosedVolume(m) == Approx(particles).epsilon(0.05));
    auto comment = [&](const std::string& key) {
        for (const auto& [k, v] : m.comments)
            if (k == key) return v;
        return std::string("<missing>");
    };
    CHECK(comment("frame") == "7");
    CHECK(comment("magnet_0") == "dipole 0 0 -0.02 0 0 1 3.5");
    CHECK(comment("susceptibility") == "1.5");
    CHECK(comment("surface_method") == "anisotropic");
}

TEST_CASE("ferro-surface meshes a frame range, writes .vdb level sets and other formats", "[surface][cli]") {
    Scratch s;
    for (int f = 3; f <= 5; ++f) writeBall(framePath(s / "particles_{:04}.ply", f), f, (4 + f) * kSpacing);
    std::string err;
    REQUIRE(run("'" + (s / "particles_{:04}.ply") + "' --frames 3:5 --out '" + (s / "surface_%04d.obj") +
                    "' --format obj --vdb '" + (s / "surface_{:04}.vdb") + "' --method isotropic",
                s, &err) == 0);
    // One progress line per frame.
    CHECK(std::count(err.begin(), err.end(), '\n') == 3);
    double previous = 0;
    for (int f = 3; f <= 5; ++f) {
        const std::string obj = framePath(s / "surface_{:04}.obj", f);
        REQUIRE(fs::exists(obj));
        std::ifstream in(obj);
        std::string first;
        std::getline(in, first);
        CHECK(first.find("ply") == std::string::npos);
        const TriangleMesh m = readMesh(obj);
        CHECK(enclosedVolume(m) > previous); // the balls grow with the frame
        previous = enclosedVolume(m);

        const std::string vdb = framePath(s / "surface_{:04}.vdb", f);
        REQUIRE(fs::exists(vdb));
        openvdb::initialize();
        openvdb::io::File file(vdb);
        file.open();
        openvdb::GridBase::Ptr base = file.readGrid("surface");
        file.close();
        auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
        REQUIRE(grid);
        CHECK(grid->getGridClass() == openvdb::GRID_LEVEL_SET);
        // Negative inside (the ball's centre is deep inside: the interior value), positive out.
        const auto acc = grid->getConstAccessor();
        CHECK(acc.getValue(grid->transform().worldToIndexCellCentered(openvdb::Vec3d(0, 0, 0))) < 0);
        CHECK(acc.getValue(grid->transform().worldToIndexCellCentered(openvdb::Vec3d(0.05, 0, 0))) > 0);
    }
}

TEST_CASE("ferro-surface reads [surface] from the scene and --set overrides it", "[surface][cli]") {
    Scratch s;
    writeBall(s / "p.ply", 0, 5 * kSpacing);
    {
        std::ofstream(s / "scene.toml") << "[surface]\nmethod = \"isotropic\"\nvoxel_size = 0.0005\n";
    }
    REQUIRE(run("'" + (s / "p.ply") + "' --out '" + (s / "a.ply") + "' -q --scene '" + (s / "scene.toml") + "'", s) == 0);
    bool iso = false;
    for (const auto& [k, v] : readMesh(s / "a.ply").comments) iso = iso || (k == "surface_method" && v == "isotropic");
    CHECK(iso);
    REQUIRE(run("'" + (s / "p.ply") + "' --out '" + (s / "b.ply") + "' -q --scene '" + (s / "scene.toml") +
                    "' --set surface.method=openvdb",
                s) == 0);
    bool vdb = false;
    for (const auto& [k, v] : readMesh(s / "b.ply").comments) vdb = vdb || (k == "surface_method" && v == "openvdb");
    CHECK(vdb);

    std::string err;
    {
        std::ofstream(s / "typo.toml") << "[surface]\nvoxel_sise = 0.0005\n";
    }
    CHECK(run("'" + (s / "p.ply") + "' --out '" + (s / "c.ply") + "' --scene '" + (s / "typo.toml") + "'", s, &err) == 2);
    CHECK(err.find("voxel_sise") != std::string::npos);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
    CHECK(run("'" + (s / "p.ply") + "' --out '" + (s / "c.ply") + "' --set surface.lambda=2", s, &err) == 2);
    CHECK(err.rfind("ferro-surface: error: ", 0) == 0);
    CHECK_FALSE(fs::exists(s / "c.ply"));
}

TEST_CASE("ferro-surface: bad input is a one-line error with exit 2, missing files exit 4", "[surface][cli]") {
    Scratch s;
    std::string err;
    CHECK(run("'" + (s / "missing.ply") + "' --out '" + (s / "m.ply") + "'", s, &err) == 4);
    CHECK(err.rfind("ferro-surface: error: ", 0) == 0);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);

    {
        std::ofstream(s / "garbage.ply") << "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
                                             "property float y\nproperty float z\nend_header\nshort";
    }
    CHECK(run("'" + (s / "garbage.ply") + "' --out '" + (s / "m.ply") + "'", s, &err) == 2);
    CHECK(err.rfind("ferro-surface: error: ", 0) == 0);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);

    // No position columns.
    ParticleTable t;
    t.names = {"density"};
    t.values = {1, 2, 3};
    writeParticleFile(s / "nox.ply", t);
    CHECK(run("'" + (s / "nox.ply") + "' --out '" + (s / "m.ply") + "'", s, &err) == 2);
    CHECK(err.find("'x'") != std::string::npos);

    // Non-finite positions.
    t.names = {"x", "y", "z"};
    t.values = {0, 0, 0, NAN, 0, 0};
    writeParticleFile(s / "nan.ply", t);
    CHECK(run("'" + (s / "nan.ply") + "' --out '" + (s / "m.ply") + "'", s, &err) == 2);
    CHECK_FALSE(fs::exists(s / "m.ply"));

    // An earlier output survives a failed run.
    writeBall(s / "p.ply", 0, 4 * kSpacing);
    REQUIRE(run("'" + (s / "p.ply") + "' --out '" + (s / "keep.ply") + "' -q", s) == 0);
    const auto before = fs::file_size(s / "keep.ply");
    CHECK(run("'" + (s / "garbage.ply") + "' --out '" + (s / "keep.ply") + "'", s) == 2);
    CHECK(fs::file_size(s / "keep.ply") == before);

    CHECK(run("'" + (s / "p.ply") + "' --out '" + (s / "m.ply") + "' --frames 5:2", s, &err) == 2);
    // Ranges whose count or last + 1 would overflow an int: one line, exit 2, nothing started.
    for (const char* frames : {"0:2147483647", "0:99999999999", "-1:3", "0:10000000"}) {
        INFO(frames);
        CHECK(run("'" + (s / "r_{:04}.ply") + "' --frames " + frames + " --out '" + (s / "rm_{:04}.ply") + "' -q", s,
                  &err) == 2);
        CHECK(err.rfind("ferro-surface: error: --frames ", 0) == 0);
        CHECK(std::count(err.begin(), err.end(), '\n') == 1);
    }
    CHECK(run("'" + (s / "p.ply") + "' --frames 0:1 --out '" + (s / "fixed.ply") + "'", s, &err) == 2);
    CHECK(err.find("placeholder") != std::string::npos);
    // An unknown output format is a bad option (2), like every stage's (sim/core/ExitCodes.hpp).
    CHECK(run("'" + (s / "p.ply") + "' --out '" + (s / "m.xyzformat") + "'", s, &err) == 2);
    CHECK(err.find("unknown mesh format 'xyzformat'") != std::string::npos);
    CHECK(run("--no-such-flag", s, &err) == 2);
    // Voxel sizes: NaN (which CLI11's number checks let through), one a million times finer
    // than the spacing (OpenVDB's "Non-zero scale values required"), one that would lose the
    // fluid: one line naming the size, exit 2, no mesh.
    for (const char* voxel : {"nan", "1e-12", "10"}) {
        INFO(voxel);
        CHECK(run("'" + (s / "p.ply") + "' --voxel-size " + voxel + " --out '" + (s / "v.ply") + "'", s, &err) == 2);
        CHECK(err.find("voxel") != std::string::npos);
        CHECK(std::count(err.begin(), err.end(), '\n') == 1);
        CHECK_FALSE(fs::exists(s / "v.ply"));
    }
    // A range with one missing frame: the run stops there (sim/core/FrameRunner.hpp), the exit
    // code says I/O and the line names the missing file.
    CHECK(run("'" + (s / "r_{:04}.ply") + "' --frames 0:1 --out '" + (s / "rm_{:04}.ply") + "' -q", s, &err) == 4);
}

TEST_CASE("ferro-surface: empty and one-particle files give an empty or tiny mesh", "[surface][cli]") {
    Scratch s;
    ParticleTable t;
    t.names = {"x", "y", "z"};
    t.comments = {{"frame", "0"}};
    writeParticleFile(s / "empty.ply", t);
    REQUIRE(run("'" + (s / "empty.ply") + "' --out '" + (s / "e.ply") + "' -q --vdb '" + (s / "e.vdb") + "'", s) == 0);
    CHECK(readMesh(s / "e.ply").empty());
    CHECK(fs::exists(s / "e.vdb"));

    t.values = {0.01f, 0.02f, 0.03f};
    writeParticleFile(s / "one.ply", t);
    REQUIRE(run("'" + (s / "one.ply") + "' --out '" + (s / "o.ply") + "' -q", s) == 0);
    const TriangleMesh one = readMesh(s / "o.ply");
    CHECK_FALSE(one.empty());
    CHECK(enclosedVolume(one) > 0);
}

TEST_CASE("ferro-surface refuses a grid larger than the machine's memory up front, naming --voxel-size (issue 15)", "[surface][cli]") {
    // 200,000 particles 10 spacings apart (a spray), a voxel of 1/50 spacing (the finest
    // accepted): each particle's kernel box (3 spacings across) alone is 150^3 voxels,
    // 6.75e11 in all, 13.5 TB at GridEstimate's 20 bytes per voxel. Refused before the kernels are built: one line naming the option and the sizes,
    // exit 2, no mesh. (Without the check this allocated until the OOM killer came.)
    Scratch s;
    ParticleTable t;
    t.names = {"x", "y", "z"};
    t.comments = {{"frame", "0"}, {"spacing", "0.001"}};
    for (int i = 0; i < 200000; ++i)
        t.values.insert(t.values.end(), {0.01f * float(i % 100), 0.01f * float((i / 100) % 100), 0.01f * float(i / 10000)});
    writeParticleFile(s / "spray.ply", t);
    std::string err;
    CHECK(run("'" + (s / "spray.ply") + "' --voxel-size 2e-5 --out '" + (s / "m.ply") + "'", s, &err) == 2);
    CAPTURE(err);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
    CHECK(err.find("--voxel-size") != std::string::npos);
    CHECK(err.find("the grid needs about 13.5 TB (6.75e+11 voxels around 200000 particles)") != std::string::npos);
    CHECK(err.find("this machine has available") != std::string::npos);
    CHECK_FALSE(fs::exists(s / "m.ply"));
}

TEST_CASE("ferro-surface never writes onto its particle input: single file, range, other spellings (issue 15)", "[surface][cli]") {
    // `ferro-surface 'x/particles_{:04}.ply' --frames 0:1 --out 'x/particles_{:04}.ply'` used
    // to replace the simulation's frames with meshes. Refused up front (exit 2, one line),
    // the particle files byte for byte as they were.
    Scratch s;
    writeBall(s / "r_0000.ply", 0, 4 * kSpacing);
    writeBall(s / "r_0001.ply", 1, 4 * kSpacing);
    const std::string before0 = test::slurp(s / "r_0000.ply"), before1 = test::slurp(s / "r_0001.ply");
    const std::string dir = s.dir.string();
    for (const std::string& args :
         {"'" + (s / "r_0000.ply") + "' --out '" + (s / "r_0000.ply") + "'",
          "'" + (s / "r_0000.ply") + "' --out '" + dir + "/./r_0000.ply'",
          "'" + (s / "r_{:04}.ply") + "' --frames 0:1 --out '" + (s / "r_{:04}.ply") + "'",
          "'" + (s / "r_{:04}.ply") + "' --frames 0:1 --out '" + dir + "/./r_%04d.ply'"}) {
        std::string err;
        INFO(args);
        CHECK(run(args, s, &err) == 2);
        CHECK(std::count(err.begin(), err.end(), '\n') == 1);
        CHECK(err.find("refusing to overwrite it") != std::string::npos);
    }
    CHECK(test::slurp(s / "r_0000.ply") == before0);
    CHECK(test::slurp(s / "r_0001.ply") == before1);
}

// ferro-sim as users run it: exit codes, one-line errors, particle files, --resume after
// a kill, never losing frames already written.
#include "sim/core/DirectoryLock.hpp"
#include "sim/core/ParticleFile.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace ferro;
using namespace ferro::test;

namespace {

const std::string kSim = std::string(FERRO_BINARY_DIR) + "/bin/ferro-sim";
std::string example(const std::string& name) { return std::string(FERRO_SOURCE_DIR) + "/examples/" + name; }

/// Runs a shell command, returning its exit code and standard error (in `output`).
CommandResult run(const std::string& cmd) { return runCommand(cmd, Capture::Stderr); }

fs::path freshDir(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("ferro_test_" + name + "_" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string frame(const fs::path& dir, int f) {
    char name[32];
    std::snprintf(name, sizeof name, "particles_%04d.ply", f);
    return (dir / name).string();
}

int lines(const std::string& s) { return int(std::count(s.begin(), s.end(), '\n')); }

} // namespace

TEST_CASE("ferro-sim writes readable frames with the documented header", "[cli]") {
    const fs::path dir = freshDir("frames");
    const CommandResult r = run(kSim + " " + example("dam_break.toml") + " --out " + dir.string() + " --max-frames 2 --quiet");
    REQUIRE(r.code == 0);
    REQUIRE(r.output.empty());
    for (int f = 0; f <= 2; ++f) {
        const ParticleTable t = readParticleFile(frame(dir, f));
        REQUIRE(t.names == std::vector<std::string>{"x", "y", "z", "vx", "vy", "vz", "density", "pressure", "hx", "hy", "hz", "mx", "my", "mz"});
        REQUIRE(t.rows() == 20 * 4 * 40);
        REQUIRE(std::stoi(t.comment("frame")) == f);
        REQUIRE(t.commentNumber("time", -1) == Approx(f / 100.0));
        REQUIRE(t.commentNumber("spacing", 0) == Approx(0.0028575));
    }
    REQUIRE(!fs::exists(frame(dir, 3)));
    // A second run refuses to overwrite the frames.
    const CommandResult again = run(kSim + " " + example("dam_break.toml") + " --out " + dir.string() + " --max-frames 2");
    REQUIRE(again.code == 2);
    REQUIRE(lines(again.output) == 1);
    REQUIRE(again.output.find("--resume") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("ferro-sim rejects bad input with one line and exit code 2 (a missing scene 4)", "[cli]") {
    const fs::path dir = freshDir("bad");
    struct Case {
        std::string args, needle;
    };
    const std::vector<Case> cases = {
        {"--set fluid.rest_density=-1000", "fluid.rest_density"},
        {"--set fluid.spacing=-0.001", "fluid.spacing"},
        {"--set fluid.colour=3", "fluid.colour"},
        {"--set sim.solver=magic", "sim.solver"},
        {"--set fluid.block.0.min=[-1.0,0.0,0.0]", "outside the container"},
        {"--set shot.fps=fast", "shot.fps"},
        {"--resume --overwrite", "--resume excludes --overwrite"},
        {"--max-frames -3", "--max-frames"},
        // Issue 15: these overflowed frameCount ("frames to -2147483648") and exited 0.
        {"--set shot.duration=1e9", "shot.duration: duration * fps makes"},
        {"--set shot.fps=1e30", "shot.fps: duration * fps makes"},
    };
    for (const Case& c : cases) {
        const CommandResult r = run(kSim + " " + example("dam_break.toml") + " --out " + dir.string() + " " + c.args);
        CAPTURE(c.args, r.output);
        REQUIRE(r.code == 2);
        REQUIRE(lines(r.output) == 1);
        REQUIRE(r.output.find(c.needle) != std::string::npos);
    }
    // A missing scene is a missing input: 4, as a missing PLY is in every stage.
    const CommandResult missing = run(kSim + " /nonexistent/scene.toml --out " + dir.string());
    REQUIRE(missing.code == 4);
    REQUIRE(lines(missing.output) == 1);
    fs::remove_all(dir);
}

TEST_CASE("magnet strengths: beyond the limit exit 2, at the limit the written frames stay finite (issue 15)", "[cli]") {
    // A 2 cm dish, 500 particles, one magnet of each kind at its kind's largest accepted
    // strength (MagnetKinds.hpp). field = 1e20 used to write NaN H with exit 0.
    const TempDir tmp("magnet_limits");
    // fps 3000: frame 1 is a few steps after frame 0, so each run takes well under a second.
    const std::string fluid = R"([shot]
fps = 3000
[fluid]
rest_density = 1200.0
[[fluid.block]]
shape = "cylinder"
radius = 0.01
height = 0.004
count = 500
[container]
type = "dish"
radius = 0.01
height = 0.01
[magnetization]
susceptibility = 1.0
saturation = 30000.0
[[magnets]]
)";
    struct Case {
        std::string magnet, key;
    };
    const std::vector<Case> cases = {
        {"kind = \"uniform\"\nfield = 1e9\n", "field=1e20"},
        // At these strengths a magnet's body is half a metre across (magnetBodyRadius: a
        // 0.58 m NdFeB sphere, a 0.52 m pole face, a 0.56 m wire) and solid: placed 5 mm
        // under the dish it would fill it (refused, exit 2, naming the magnet: checked below),
        // so these sit just outside their bodies, under the dish.
        {"kind = \"dipole\"\nposition = [0, 0, -0.6]\nmoment = 1e6\n", "moment=1e36"},
        {"kind = \"bar\"\nposition = [0, 0, -0.56]\nlength = 0.02\npole_strength = -1e6\n", "pole_strength=1e7"},
        {"kind = \"loop\"\nposition = [0, 0, -0.6]\nradius = 0.005\ncurrent = 1e9\n", "current=2e9"},
    };
    for (const Case& c : cases) {
        const std::string scene = tmp.write("s.toml", fluid + c.magnet);
        const std::string out = tmp.file("out");
        fs::remove_all(out);
        const CommandResult bad = run(kSim + " " + scene + " --out " + out + " --quiet --max-frames 1 --set magnets.0." + c.key);
        CAPTURE(c.magnet, bad.output);
        REQUIRE(bad.code == 2);
        REQUIRE(lines(bad.output) == 1);
        REQUIRE(bad.output.find("magnets[0]." + c.key.substr(0, c.key.find('=')) + ": must be within") != std::string::npos);
        REQUIRE(!fs::exists(frame(out, 0)));

        // The largest accepted strength: runs, or stops with the sanity guard's one line and
        // exit 3; every frame it wrote holds finite values only.
        const CommandResult r = run(kSim + " " + scene + " --out " + out + " --quiet --max-frames 1 --threads 2");
        CAPTURE(r.output);
        REQUIRE((r.code == 0 || (r.code == 3 && lines(r.output) == 1)));
        REQUIRE(fs::exists(frame(out, 0)));
        for (int f = 0; f <= 1 && fs::exists(frame(out, f)); ++f) {
            const ParticleTable t = readParticleFile(frame(out, f));
            REQUIRE(t.rows() == 500);
            size_t nonFinite = 0;
            for (float v : t.values) nonFinite += !std::isfinite(v);
            CAPTURE(f);
            REQUIRE(nonFinite == 0);
        }
    }
    // A magnet whose body fills the fluid is refused up front, naming it.
    const std::string scene = tmp.write("s.toml", fluid + "kind = \"dipole\"\nposition = [0, 0, -0.005]\nmoment = 1e6\n");
    const CommandResult r = run(kSim + " " + scene + " --out " + tmp.file("solid") + " --quiet --max-frames 1");
    CAPTURE(r.output);
    REQUIRE(r.code == 2);
    REQUIRE(lines(r.output) == 1);
    REQUIRE(r.output.find("magnets[0]: the magnet's body") != std::string::npos);
}

TEST_CASE("a blow-up stops with a clear message and keeps the frames written", "[cli]") {
    const fs::path dir = freshDir("nan");
    // Absurd gravity overflows float velocities within a few steps.
    const CommandResult r = run(kSim + " " + example("dam_break.toml") + " --out " + dir.string() +
                                " --quiet --set sim.gravity=[0.0,0.0,-1e37] --set sim.min_dt=1e-30");
    CAPTURE(r.output);
    REQUIRE(r.code == 3);
    REQUIRE(lines(r.output) == 1);
    REQUIRE(r.output.find("non-finite") != std::string::npos);
    REQUIRE(fs::exists(frame(dir, 0)));
    REQUIRE(readParticleFile(frame(dir, 0)).rows() == 3200);
    fs::remove_all(dir);
}

namespace {

/// A 2 cm dish of 500 particles, a 1 A m^2 dipole 1 cm under its floor: the scene of the
/// sanity guard's tests below (each sets what trips the guard).
const std::string kGuardDish = R"([shot]
fps = 1000
duration = 0.05
[fluid]
rest_density = 1200.0
[[fluid.block]]
shape = "cylinder"
radius = 0.01
height = 0.004
count = 500
[container]
type = "dish"
radius = 0.01
height = 0.01
[magnetization]
susceptibility = 1.5
saturation = 35000.0
[[magnets]]
kind = "dipole"
position = [0, 0, -0.01]
moment = 1.0
)";

/// Runs the guard dish with `overrides`; requires exit 3 with one line holding `cause`
/// after the progress lines, and every frame written before it intact: readable, 500
/// finite rows, its header's frame number its name's. Returns the frames written.
int requireGuardStop(const std::string& overrides, const std::string& cause) {
    const TempDir tmp("guard");
    const std::string scene = tmp.write("s.toml", kGuardDish);
    const std::string out = tmp.file("out");
    const CommandResult r = run(kSim + " " + scene + " --out " + out + " --threads 2 " + overrides);
    CAPTURE(overrides, r.output);
    REQUIRE(r.code == 3);
    const size_t at = r.output.find("ferro-sim: error: ");
    REQUIRE(at != std::string::npos);
    const std::string last = r.output.substr(at);
    REQUIRE(lines(last) == 1);
    REQUIRE(last.find(cause) != std::string::npos);
    int written = 0;
    while (fs::exists(frame(out, written))) {
        const ParticleTable t = readParticleFile(frame(out, written));
        REQUIRE(t.rows() == 500);
        REQUIRE(int(t.commentNumber("frame", -1)) == written);
        for (float v : t.values) REQUIRE(std::isfinite(v));
        ++written;
    }
    // The progress lines name every frame written after frame 0, so each was complete.
    REQUIRE(lines(r.output.substr(0, at)) >= written);
    std::printf("guard stop after %d frames: %s", written - 1, last.c_str());
    return written;
}

} // namespace

TEST_CASE("the sanity guard stops a run whose time step stays near sim.min_dt (exit 3, frames kept)", "[cli][guard]") {
    // sim.max_dt 1e-5 s with min_dt 5e-6 s: every step is below 4 x min_dt, 100 steps per
    // 1 ms frame (101 when rounding splits a frame's last step in two); the 1000th in a row
    // stops the run in frame 9 or 10. Frames end on a step shortened to the frame's end; it
    // must not restart the count (it did: this scene ran all 50 frames).
    const int written = requireGuardStop("--set sim.max_dt=1e-5 --set sim.min_dt=5e-6",
                                         "time step stayed below 4 x sim.min_dt = 2e-05 s for 1000 steps in a row");
    REQUIRE(written >= 9);
    REQUIRE(written <= 10);
}

TEST_CASE("the sanity guard stops a run whose magnetization solve ends at its cap every step (exit 3, frames kept)", "[cli][guard]") {
    // One field evaluation per solve cannot reach a tolerance of 1e-9; solved on every step,
    // the 50th unconverged solve in a row (the first is frame 0's) stops the run.
    const int written = requireGuardStop(
        "--set magnetization.max_iterations=1 --set magnetization.tolerance=1e-9 --set magnetization.resolve_every=1",
        "the magnetization solve ended at its iteration cap (magnetization.max_iterations = 1) without converging 50 times in a row");
    REQUIRE(written >= 2);
}

TEST_CASE("the sanity guard stops a run faster than sim.max_speed (exit 3, frames kept)", "[cli][guard]") {
    // The fluid heaps over the magnet at a few cm/s within the first frames.
    const int written = requireGuardStop("--set sim.max_speed=0.01", "faster than this scene can make it: bound 0.01 m/s (sim.max_speed)");
    REQUIRE(written >= 1);
}

TEST_CASE("resume trusts a frame only if its header agrees with its name and no earlier frame is missing (issue 15)", "[cli]") {
    // A stray particles_0099.ply whose header said frame 3 was resumed "after frame 99"
    // (frames 4.. never written); a missing middle frame was a silent gap.
    const TempDir tmp("resume_trust");
    const std::string scene = tmp.write("s.toml", R"([shot]
fps = 3000
[fluid]
[[fluid.block]]
min = [0, 0, 0]
max = [0.01, 0.01, 0.005]
count = 500
[container]
type = "box"
min = [0, 0, 0]
max = [0.01, 0.01, 0.02]
)");
    const fs::path out = tmp.path / "out";
    const std::string sim = kSim + " " + scene + " --out " + out.string() + " --threads 1";
    auto headerFrame = [&](int f) { return std::stoi(readParticleFile(frame(out, f)).comment("frame")); };
    auto fresh = [&](int frames) {
        fs::remove_all(out);
        REQUIRE(run(sim + " --quiet --max-frames " + std::to_string(frames)).code == 0);
    };

    SECTION("a stray later frame whose header disagrees is not resumed from, nor touched") {
        fresh(3);
        fs::copy_file(frame(out, 3), frame(out, 99));
        const std::string stray = slurp(frame(out, 99)), f3 = slurp(frame(out, 3));
        const CommandResult r = run(sim + " --max-frames 5 --resume");
        CAPTURE(r.output);
        REQUIRE(r.code == 0);
        REQUIRE(r.output.find("resuming after frame 3") != std::string::npos);
        REQUIRE(r.output.find("frames up to 99 exist (frame 4 is missing); frames 4 to 5 are rewritten, later ones left "
                              "as they are") != std::string::npos);
        for (int f = 0; f <= 5; ++f) REQUIRE(headerFrame(f) == f);
        REQUIRE(slurp(frame(out, 3)) == f3);
        REQUIRE(slurp(frame(out, 99)) == stray);  // beyond this run's frames: left as it was
    }
    SECTION("a missing middle frame: resume after the frame before it, and fill the gap") {
        fresh(3);
        const std::string f1 = slurp(frame(out, 1));
        fs::remove(frame(out, 2));
        const CommandResult r = run(sim + " --max-frames 4 --resume");
        CAPTURE(r.output);
        REQUIRE(r.code == 0);
        REQUIRE(r.output.find("resuming after frame 1") != std::string::npos);
        REQUIRE(r.output.find("frame 2 is missing") != std::string::npos);
        for (int f = 0; f <= 4; ++f) REQUIRE(headerFrame(f) == f);
        REQUIRE(slurp(frame(out, 1)) == f1);
    }
    SECTION("a frame whose header names another frame is not resumed from") {
        fresh(3);
        fs::copy_file(frame(out, 1), frame(out, 3), fs::copy_options::overwrite_existing);
        const std::string f2 = slurp(frame(out, 2));
        const CommandResult r = run(sim + " --max-frames 3 --resume");
        CAPTURE(r.output);
        REQUIRE(r.code == 0);
        REQUIRE(r.output.find("particles_0003.ply: its header says frame 1") != std::string::npos);
        REQUIRE(r.output.find("resuming after frame 2") != std::string::npos);
        for (int f = 0; f <= 3; ++f) REQUIRE(headerFrame(f) == f);
        REQUIRE(slurp(frame(out, 2)) == f2);
    }
    SECTION("a key the simulation does not read (the camera) keeps the frames resumable; one it reads does not") {
        fresh(2);
        const std::string f2 = slurp(frame(out, 2));
        const CommandResult camera =
            run(sim + " --max-frames 3 --resume --set render.camera_position=[0,-0.1,0.05] --set sim.threads=1");
        CAPTURE(camera.output);
        REQUIRE(camera.code == 0);
        REQUIRE(camera.output.find("resuming after frame 2") != std::string::npos);
        REQUIRE(slurp(frame(out, 2)) == f2);
        const CommandResult gravity = run(sim + " --max-frames 4 --resume --set sim.gravity=[0,0,-9.7]");
        CAPTURE(gravity.output);
        REQUIRE(gravity.code == 2);
        REQUIRE(lines(gravity.output) == 1);
        REQUIRE(gravity.output.find("particles_0003.ply: written from a different scene") != std::string::npos);
        REQUIRE(!fs::exists(frame(out, 4)));
    }
    SECTION("no frame 0: refused with one line, nothing touched") {
        fresh(2);
        fs::remove(frame(out, 0));
        const std::string f2 = slurp(frame(out, 2));
        const CommandResult r = run(sim + " --max-frames 4 --resume");
        CAPTURE(r.output);
        REQUIRE(r.code == 2);
        REQUIRE(lines(r.output) == 1);
        REQUIRE(r.output.find("particles_0000.ply: missing, so no frame in") != std::string::npos);
        REQUIRE(!fs::exists(frame(out, 0)));
        REQUIRE(!fs::exists(frame(out, 3)));
        REQUIRE(slurp(frame(out, 2)) == f2);
    }
}

TEST_CASE("a run killed mid-way and resumed matches an uninterrupted run", "[cli][slow]") {
    const fs::path ref = freshDir("ref"), cut = freshDir("cut");
    const std::string args = " --max-frames 8 --quiet --set sim.solver=wcsph --threads 2";
    REQUIRE(run(kSim + " " + example("dam_break.toml") + " --out " + ref.string() + args).code == 0);

    // Start the same run and kill it (SIGKILL, no chance to clean up) once frame 3 exists.
    const pid_t pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        execl(kSim.c_str(), kSim.c_str(), example("dam_break.toml").c_str(), "--out", cut.c_str(), "--max-frames", "8",
              "--quiet", "--set", "sim.solver=wcsph", "--threads", "2", (char*)nullptr);
        _exit(127);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (!fs::exists(frame(cut, 3)) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    REQUIRE(fs::exists(frame(cut, 3)));
    REQUIRE(!fs::exists(frame(cut, 8)));  // it really was cut short
    int written = 0;
    while (fs::exists(frame(cut, written))) ++written;
    std::vector<std::string> before;
    for (int f = 0; f < written; ++f) before.push_back(slurp(frame(cut, f)));

    const CommandResult resumed = run(kSim + " " + example("dam_break.toml") + " --out " + cut.string() + args + " --resume");
    CAPTURE(resumed.output);
    REQUIRE(resumed.code == 0);
    // Frames already written are untouched.
    for (int f = 0; f < written; ++f) REQUIRE(slurp(frame(cut, f)) == before[size_t(f)]);
    for (int f = 0; f <= 8; ++f) {
        const ParticleTable a = readParticleFile(frame(ref, f)), b = readParticleFile(frame(cut, f));
        REQUIRE(a.rows() == b.rows());
        double worst = 0;
        for (size_t i = 0; i < a.values.size(); ++i) {
            const double scale = std::max(1e-3, double(std::abs(a.values[i])));
            worst = std::max(worst, std::abs(double(a.values[i]) - double(b.values[i])) / scale);
        }
        CAPTURE(f, worst);
        REQUIRE(worst < 1e-5);
    }
    // No temporary files are left behind: frames, and the folder's lock file (DirectoryLock).
    for (const auto& e : fs::directory_iterator(cut))
        if (e.path().filename() != DirectoryLock::kFileName) REQUIRE(e.path().extension() == ".ply");
    fs::remove_all(ref);
    fs::remove_all(cut);
}

TEST_CASE("the compact particle cache: the later stages' columns at 26 bytes a particle, full frames to resume from", "[cli]") {
    // [shot] particle_cache = "compact", full_every = 3: frames 1, 2, 4 compact, 0, 3 and the
    // last (5) full. Against the same run with full frames: positions bit for bit, v, density
    // and M within half a quantization step; resuming after a kill goes back to frame 3.
    const TempDir tmp("compact_cache");
    const std::string scene = tmp.write("s.toml", R"([shot]
fps = 3000
[fluid]
[[fluid.block]]
min = [0, 0, 0]
max = [0.01, 0.01, 0.005]
count = 500
[container]
type = "box"
min = [0, 0, 0]
max = [0.01, 0.01, 0.02]
[[magnets]]
position = [0.005, 0.005, -0.01]
moment = 0.05
)");
    const fs::path full = tmp.path / "full", compact = tmp.path / "compact";
    const std::string base = kSim + " " + scene + " --threads 1 --quiet --max-frames 5 --out ";
    REQUIRE(run(base + full.string()).code == 0);
    const std::string compactRun = base + compact.string() + " --set shot.particle_cache=compact --set shot.full_every=3";
    REQUIRE(run(compactRun).code == 0);
    for (int f = 0; f <= 5; ++f) {
        INFO("frame " << f);
        const bool isFull = f % 3 == 0 || f == 5;
        const ParticleTable a = readParticleFile(frame(full, f)), b = readParticleFile(frame(compact, f));
        CHECK((b.comment("cache") == "compact") == !isFull);
        CHECK(b.columns() == (isFull ? 14u : 10u));
        CHECK(fs::file_size(frame(compact, f)) < (isFull ? 1000000u : 500 * 26 + 4096u));
        REQUIRE(a.rows() == b.rows());
        for (const char* name : {"x", "y", "z", "vx", "vy", "vz", "density", "mx", "my", "mz"}) {
            const int ca = a.column(name), cb = b.column(name);
            REQUIRE(cb >= 0);
            float maxAbs = 0, maxErr = 0;
            for (size_t r = 0; r < a.rows(); ++r) {
                maxAbs = std::max(maxAbs, std::fabs(a.at(r, ca)));
                maxErr = std::max(maxErr, std::fabs(a.at(r, ca) - b.at(r, cb)));
            }
            INFO(name << ": largest " << maxAbs << ", error " << maxErr);
            const bool exact = isFull || name[1] == 0; // x, y, z and full frames: bit for bit
            CHECK(maxErr <= (exact ? 0.0f : 0.5f * maxAbs / 32767.0f + maxAbs * 6.0e-8f));
        }
    }
    // A kill after frame 4: the run resumes after frame 3, the last full one, and ends with
    // the same frame 5 as the uninterrupted run.
    const std::string f5 = slurp(frame(compact, 5));
    fs::remove(frame(compact, 5));
    const CommandResult r = run(kSim + " " + scene + " --threads 1 --max-frames 5 --out " + compact.string() +
                                " --set shot.particle_cache=compact --set shot.full_every=3 --resume");
    INFO(r.output);
    REQUIRE(r.code == 0);
    CHECK(r.output.find("resuming after frame 3") != std::string::npos);
    CHECK(slurp(frame(compact, 5)) == f5);
}

TEST_CASE("one writer a folder: ferro-sim on an output folder in use is refused at once, a killed holder's lock taken over", "[cli][lock]") {
    const fs::path dir = freshDir("lock");
    const std::string scene = example("dish.toml");
    const std::string sim = kSim + " '" + scene + "' --out '" + dir.string() + "' --max-frames 0 --set shot.preroll=0 -q ";
    {
        // A holder in this process: the run is refused before it reads or removes anything,
        // with exit 4 and one line naming the holder and its pid.
        const DirectoryLock held(dir.string(), "test holder");
        const CommandResult res = run(sim + "--overwrite");
        CHECK(res.code == 4);
        CHECK(lines(res.output) == 1);
        CHECK(res.output.find("in use by test holder (pid " + std::to_string(getpid()) + ")") != std::string::npos);
        CHECK(!fs::exists(frame(dir, 0)));
    }
    // A holder killed with SIGKILL leaves its lock file naming it; the next run takes it over.
    const pid_t child = fork();
    REQUIRE(child >= 0);
    if (child == 0) {
        const DirectoryLock held(dir.string(), "a run about to be killed");
        ::pause();
        _exit(0);
    }
    // Wait until the child holds the lock (its words are in the file), then kill it.
    for (int k = 0; k < 500 && DirectoryLock::lastHolder(dir.string()).find("about to be killed") == std::string::npos; ++k)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    REQUIRE(DirectoryLock::lastHolder(dir.string()).find("about to be killed") != std::string::npos);
    REQUIRE(run(sim + "--overwrite").code == 4); // still held while the child lives
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    const CommandResult res = run(sim + "--overwrite");
    INFO(res.output);
    CHECK(res.code == 0);
    CHECK(fs::exists(frame(dir, 0)));
    CHECK(DirectoryLock::lastHolder(dir.string()).find("ferro-sim") == 0);
    fs::remove_all(dir);
}

// The determinism contract (docs/shots.md, "What is promised"): particle files are the same
// bytes whatever the thread count (1, 2 and 4 on this 2-core machine), whether the run was
// stopped after any frame and resumed, and whether the pre-roll came from its cache or was
// simulated again.
TEST_CASE("particle files are byte-identical across thread counts, a stop and resume after any frame, and a reused or rebuilt pre-roll", "[cli][determinism][slow]") {
    const fs::path dir = freshDir("determinism");
    {
        std::ofstream scene(dir / "pool.toml");
        scene << slurp(fs::path(FERRO_SOURCE_DIR) / "tests/data/small_pool.toml")
              << "\n[[magnets]]\nkind = \"dipole\"\nposition = [0.0, 0.0, -0.012]\ndirection = [0.0, 0.0, 1.0]\nmoment = 0.5\n"
                 "[[magnets.keys]]\ntime = 0.0\nposition = [0.0, 0.0, -0.012]\n"
                 "[[magnets.keys]]\ntime = 0.4\nposition = [0.006, 0.0, -0.012]\n";
    }
    constexpr int kLast = 4;
    const std::string base = kSim + " '" + (dir / "pool.toml").string() + "' --quiet --set shot.preroll=0.3 ";
    const auto runInto = [&](const std::string& name, const std::string& args) {
        const CommandResult r = run(base + "--out '" + (dir / name).string() + "' " + args);
        INFO(name << ": " << r.output);
        REQUIRE(r.code == 0);
    };
    // The reference: one thread, the pre-roll simulated (its cache in ref/preroll.ply).
    runInto("ref", "--threads 1 --max-frames " + std::to_string(kLast));
    const auto sameAsRef = [&](const std::string& name) {
        for (int f = 0; f <= kLast; ++f) {
            INFO(name << " frame " << f);
            REQUIRE(fs::exists(frame(dir / name, f)));
            CHECK(slurp(frame(dir / name, f)) == slurp(frame(dir / "ref", f)));
        }
    };
    // 2 and 4 threads, each simulating the pre-roll again (a fresh cache).
    for (int threads : {2, 4}) {
        const std::string name = "threads" + std::to_string(threads);
        runInto(name, "--threads " + std::to_string(threads) + " --max-frames " + std::to_string(kLast));
        sameAsRef(name);
    }
    // The pre-roll from the reference's cache, at 2 threads.
    runInto("reused", "--threads 2 --preroll-cache '" + (dir / "ref/preroll.ply").string() + "' --max-frames " + std::to_string(kLast));
    sameAsRef("reused");
    // Stopped after frame k and resumed, for every k before the last.
    for (int k = 0; k < kLast; ++k) {
        const std::string name = "resume" + std::to_string(k);
        const std::string cache = "--preroll-cache '" + (dir / "ref/preroll.ply").string() + "' ";
        runInto(name, cache + "--threads 2 --max-frames " + std::to_string(k));
        runInto(name, cache + "--threads 1 --resume --max-frames " + std::to_string(kLast));
        sameAsRef(name);
    }
    fs::remove_all(dir);
}

// The shot pipeline as users run it: scripts/shot.sh on a tiny shot (300 particles, 4 frames),
// then make's bookkeeping: a second make does nothing, touching one frame's particle file
// re-runs only that frame, a [render] change re-renders without re-meshing, and
// scripts/farm.sh renders a frame range through GNU parallel (--sshlogin : = this machine).
#include "PovTestUtil.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <map>
#include <regex>
#include <vector>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

using namespace ferro;
using namespace ferro::povtest;

namespace {

const char* kTinyScene = R"([shot]
fps = 10
duration = 0.3

[[fluid.block]]
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.02
height = 0.005
count = 300

[container]
type = "dish"
center = [0.0, 0.0, 0.0]
radius = 0.02
height = 0.01

# A weak dipole far under the dish: the shot has a magnet include to check, and the fluid
# barely feels it.
[[magnets]]
position = [0.0, 0.0, -0.1]
moment = 0.01

[render]
width = 48
height = 36
camera_position = [0.0, -0.07, 0.045]
)";

// The directory of executables the pipeline uses: every stage must be built (CMake builds
// them before this test's executable). A missing one fails the test, naming it, rather than
// skipping it: a pipeline test that passes with nothing run would hide a broken build.
std::string pipelineBin()
{
    for (const char* exe : {"ferro-sim", "ferro-surface", "ferro-spikes", "ferro-pov"}) {
        INFO("the pipeline needs " << kBin << exe << ", which is not built");
        REQUIRE(fs::exists(kBin + exe));
    }
    return kBin;
}

// Number of recipe lines in `text` that mention `what` for each frame tag "_0000".."_0003".
std::map<std::string, int> perFrame(const std::string& text, const std::string& what)
{
    std::map<std::string, int> count;
    std::istringstream in(text);
    std::string line;
    static const std::regex tag("(?:_|10#)(\\d{4})");
    while (std::getline(in, line)) {
        std::smatch m;
        if (line.find(what) != std::string::npos && std::regex_search(line, m, tag))
            ++count[m[1]];
    }
    return count;
}

// Makes `p` at least 2 s newer than every other file under `root`, with no pause: every other
// file's time moves 2 s back (their order is kept), then `p` gets the time now. This holds on
// file systems with coarse (1 s) times too, and leaves no file in the future: a future time
// would make every file made from `p` in the next 2 s look stale to make.
void touchNow(const fs::path& p, const fs::path& root)
{
    for (const auto& entry : fs::recursive_directory_iterator(root))
        if (entry.is_regular_file() && !entry.is_symlink() && entry.path() != p)
            fs::last_write_time(entry.path(), entry.last_write_time() - std::chrono::seconds(2));
    fs::last_write_time(p, fs::file_time_type::clock::now());
}

} // namespace

TEST_CASE("shot.sh renders a tiny shot, and make re-runs exactly the stale frames and stages", "[pov][pipeline][slow]")
{
    const fs::path dir = freshDir("pipeline");
    spit(dir / "tiny.toml", kTinyScene);
    const std::string bin = pipelineBin();
    const fs::path out = dir / "shot";
    const std::string make = "make -C '" + out.string() + "' --no-print-directory ";

    Result res = run("FERRO_BIN='" + bin + "' '" + kSource + "/scripts/shot.sh' '" + (dir / "tiny.toml").string() + "' '" +
                     out.string() + "' -j2");
    INFO(res.output);
    REQUIRE(res.code == 0);
    for (int f = 0; f <= 3; ++f)
        CHECK(fs::exists(out / "png" / ("frame_000" + std::to_string(f) + ".png")));
    if (!run("command -v ffmpeg").code) {
        CHECK(fs::file_size(out / "shot.mp4") > 0);
        CHECK(fs::file_size(out / "shot.gif") > 0);
    }

    // A second make has nothing to do.
    CHECK(run(make + "-q").code == 0);
    res = run(make + "-n");
    CHECK(res.output.find("Nothing to be done") != std::string::npos);

    // One frame's particles change: only that frame is re-meshed, re-exported, re-rendered.
    touchNow(out / "particles" / "particles_0002.ply", dir);
    std::map<int, fs::file_time_type> rendered;
    for (int f = 0; f <= 3; ++f)
        rendered[f] = fs::last_write_time(out / "png" / ("frame_000" + std::to_string(f) + ".png"));
    res = run(make + "-n frames");
    INFO(res.output);
    CHECK(perFrame(res.output, "ferro-surface particles") == std::map<std::string, int>{{"0002", 1}});
    CHECK(perFrame(res.output, "ferro-pov") == std::map<std::string, int>{{"0002", 1}});
    CHECK(perFrame(res.output, "povray render.ini") == std::map<std::string, int>{{"0002", 1}});
    res = run(make + "-j2 frames");
    REQUIRE(res.code == 0);
    for (int f = 0; f <= 3; ++f) {
        const auto now = fs::last_write_time(out / "png" / ("frame_000" + std::to_string(f) + ".png"));
        INFO("frame " << f);
        CHECK((now != rendered[f]) == (f == 2));
    }
    CHECK(run(make + "-q frames").code == 0);

    // [render] changes: every frame re-renders, none is re-meshed or re-exported.
    std::string scene = slurp(dir / "tiny.toml");
    scene.replace(scene.find("width = 48"), 10, "width = 40");
    spit(dir / "tiny.toml", scene);
    touchNow(dir / "tiny.toml", dir);
    res = run(make + "-n frames");
    INFO(res.output);
    CHECK(perFrame(res.output, "povray render.ini").size() == 4);
    CHECK(perFrame(res.output, "ferro-surface particles").empty());
    CHECK(perFrame(res.output, "--no-shot").empty());
    REQUIRE(run(make + "-j2 frames").code == 0);
    CHECK(run(make + "-q frames").code == 0);

    // render.magnet_length is the one [render] key the frame includes read (magnets_NNNN.inc
    // draws point dipoles that size): every frame is re-exported and re-rendered, none re-meshed.
    // (The export's stamp once listed only [magnets] and [shot], and this edit left the old
    // magnet includes in place.)
    scene = slurp(dir / "tiny.toml");
    scene.replace(scene.find("width = 40"), 10, "width = 40\nmagnet_length = 0.03");
    spit(dir / "tiny.toml", scene);
    touchNow(dir / "tiny.toml", dir);
    res = run(make + "-n frames");
    INFO(res.output);
    CHECK(perFrame(res.output, "--no-shot").size() == 4);
    CHECK(perFrame(res.output, "povray render.ini").size() == 4);
    CHECK(perFrame(res.output, "ferro-surface particles").empty());
    REQUIRE(run(make + "-j2 frames").code == 0);
    CHECK(slurp(out / "shot" / "magnets_0001.inc").find("FerroMagnetLength = array[1] { 30 }") != std::string::npos);
    CHECK(run(make + "-q frames").code == 0);

    // A scene the stages cannot read stops make before any stage runs, with the stage's own
    // one-line error, and leaves the frames alone.
    const std::string good = slurp(dir / "tiny.toml");
    spit(dir / "tiny.toml", good + "\n[surface]\nvoxel_size = -1\n");
    res = run(make + "frames");
    CHECK(res.code != 0);
    CHECK(res.output.find("surface.voxel_size: must be >= 0 (got -1)") != std::string::npos);
    CHECK(res.output.find("shot.mk: cannot read the scene for the surface stage") != std::string::npos);
    CHECK(fs::exists(out / "surface" / "surface_0001.ply"));
    spit(dir / "tiny.toml", good);
    touchNow(dir / "tiny.toml", dir);
    CHECK(run(make + "-q frames").code == 0);

    // A comment-only edit of the scene changes no section: nothing to do.
    spit(dir / "tiny.toml", slurp(dir / "tiny.toml") + "\n# a note\n");
    touchNow(dir / "tiny.toml", dir);
    CHECK(run(make + "-q frames").code == 0);

    // The artists' look changes: every frame re-renders.
    touchNow(out / "shot" / "look.inc", dir);
    res = run(make + "-n frames");
    CHECK(perFrame(res.output, "povray render.ini").size() == 4);
    CHECK(perFrame(res.output, "ferro-surface particles").empty());
    REQUIRE(run(make + "-j2 frames").code == 0);

    // The farm: frames 1..2 again on "this machine" through GNU parallel ("01": leading zeros
    // are decimal, not octal). GNU parallel is one of the packages install-deps installs: a
    // machine without it fails here rather than skipping the farm.
    REQUIRE(run("command -v parallel").code == 0);
    fs::remove(out / "png" / "frame_0001.png");
    fs::remove(out / "png" / "frame_0002.png");
    res = run("'" + kSource + "/scripts/farm.sh' '" + out.string() + "' --frames 01:02 --sshlogin : --no-video");
    INFO(res.output);
    REQUIRE(res.code == 0);
    CHECK(fs::exists(out / "png" / "frame_0001.png"));
    CHECK(fs::exists(out / "png" / "frame_0002.png"));
    CHECK(run(make + "-q frames").code == 0);

    // A [fluid] edit whose simulation fails (here a stand-in ferro-sim that writes one broken
    // frame and exits 3): the previous simulation's frames stay where they were.
    const fs::path failing = dir / "failing-bin";
    fs::create_directories(failing);
    spit(failing / "ferro-sim",
         "#!/usr/bin/env bash\n# stand-in for a ferro-sim run that fails after its first frame\n"
         "out=''; while [[ $# -gt 0 ]]; do [[ $1 == --out ]] && out=$2; shift; done\n"
         "mkdir -p \"$out\" && echo broken > \"$out/particles_0000.ply\"; exit 3\n");
    fs::permissions(failing / "ferro-sim", fs::perms::owner_all);
    const std::string frame0 = slurp(out / "particles" / "particles_0000.ply");
    scene = slurp(dir / "tiny.toml");
    scene.replace(scene.find("count = 300"), 11, "count = 290");
    spit(dir / "tiny.toml", scene);
    res = run(make + "prepare FERRO_BIN='" + failing.string() + "'");
    INFO(res.output);
    CHECK(res.code != 0);
    CHECK(slurp(out / "particles" / "particles_0000.ply") == frame0);
    CHECK(fs::exists(out / "particles" / "particles_0003.ply"));
    CHECK(fs::exists(out / "particles" / ".complete"));
}

TEST_CASE("shot.sh rejects bad arguments with one line and exit code 2 (a missing scene 4)", "[pov][pipeline]")
{
    const fs::path dir = freshDir("shot_errors");
    const std::string shot = "FERRO_BIN='" + pipelineBin() + "' '" + kSource + "/scripts/shot.sh' ";
    Result res = run(shot + "'" + (dir / "missing.toml").string() + "' '" + (dir / "out").string() + "'");
    CHECK(res.code == 4);   // a missing input, as in every stage
    CHECK(res.output.rfind("shot.sh: error: ", 0) == 0);
    spit(dir / "tiny.toml", kTinyScene);
    res = run(shot + "'" + (dir / "tiny.toml").string() + "' '" + (dir / "out").string() + "' --frames 5");
    CHECK(res.code == 2);
    res = run(shot + "'" + (dir / "tiny.toml").string() + "' '" + (dir / "out").string() + "' --frames 0:99");
    CHECK(res.code == 2);
    CHECK(res.output.find("ends at frame 3") != std::string::npos);
    // "08" is eight, not a bad octal number to bash.
    res = run(shot + "'" + (dir / "tiny.toml").string() + "' '" + (dir / "out").string() + "' --frames 08:09");
    INFO(res.output);
    CHECK(res.code == 2);
    CHECK(res.output.find("ends at frame 3") != std::string::npos);
    res = run(shot + "'" + (dir / "tiny.toml").string() + "' '" + (dir / "out").string() + "' --frames 0:99999999999");
    CHECK(res.code == 2);
    // A bad key of a later stage is bad input too, found before anything runs (inside make it
    // would be a failed stage, exit 3): one line from the stage that reads it, naming the key.
    for (const std::string set : {"surface.voxel_size=-1", "spikes.sharpness=9"}) {
        res = run(shot + "'" + (dir / "tiny.toml").string() + "' '" + (dir / "out").string() + "' --set " + set);
        INFO(set << ": " << res.output);
        CHECK(res.code == 2);
        CHECK(res.output.find(set.substr(0, set.find('='))) != std::string::npos);
        CHECK(std::count(res.output.begin(), res.output.end(), '\n') == 1);
        CHECK_FALSE(fs::exists(dir / "out" / "particles"));
    }
}

TEST_CASE("one writer a shot: shot.sh on a folder in use is refused at once with exit 4, and runs once it is free", "[pov][pipeline][lock]")
{
    // The lock is flock(1) on OUTDIR/.shot.lock (scripts/shot.sh); here this process holds it,
    // as a running shot.sh (or the make it started) would.
    const fs::path dir = freshDir("shot_lock");
    spit(dir / "tiny.toml", kTinyScene);
    const fs::path out = dir / "shot";
    fs::create_directories(out);
    const std::string shot = "FERRO_BIN='" + pipelineBin() + "' '" + kSource + "/scripts/shot.sh' '" +
                             (dir / "tiny.toml").string() + "' '" + out.string() + "' --no-run";
    const int fd = ::open((out / ".shot.lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    REQUIRE(fd >= 0);
    REQUIRE(::flock(fd, LOCK_EX | LOCK_NB) == 0);
    const std::string holder = "shot.sh tiny.toml (pid " + std::to_string(getpid()) + ")\n";
    REQUIRE(::write(fd, holder.data(), holder.size()) == ssize_t(holder.size()));
    Result res = run(shot);
    CHECK(res.code == 4);
    CHECK(res.output == "shot.sh: error: " + out.string() + ": in use by shot.sh tiny.toml (pid " + std::to_string(getpid()) +
                            "); wait for it to end or stop it\n");
    CHECK(!fs::exists(out / "Makefile"));
    ::close(fd); // released: the next run takes the lock over
    res = run(shot);
    INFO(res.output);
    CHECK(res.code == 0);
    CHECK(fs::exists(out / "Makefile"));
    fs::remove_all(dir);
}

TEST_CASE("shot.sh --preset passes the documented settings to the stages, and an unknown preset is exit 2", "[pov][pipeline]")
{
    // The presets are scripts/presets.conf, documented in scripts/README.md and the report
    // (tests/bench/report/README.md). Here: the values reach ferro-pov's render.ini (the tiny
    // scene's own [render] width 48 is overridden), the spike keys reach the spikes stamp, a
    // --set after the preset wins, and an unknown preset is one line with exit code 2.
    const fs::path dir = freshDir("shot_presets");
    spit(dir / "tiny.toml", kTinyScene);
    const std::string shot =
        "FERRO_BIN='" + pipelineBin() + "' '" + kSource + "/scripts/shot.sh' '" + (dir / "tiny.toml").string() + "' ";

    Result res = run(shot + "'" + (dir / "bad").string() + "' --preset fastest");
    CHECK(res.code == 2);
    CHECK(res.output.rfind("shot.sh: error: unknown preset 'fastest' (presets: final large preview)", 0) == 0);
    CHECK(std::count(res.output.begin(), res.output.end(), '\n') == 1);

    struct Expected {
        const char* preset;
        std::vector<std::string> ini;    // lines of shot/render.ini
        std::vector<std::string> spikes; // lines of the spikes stamp .scene/spikes.toml
    };
    const std::vector<Expected> presets = {
        {"preview", {"Width=320", "Height=240", "Quality=8", "Antialias=off"},
         {"spikes.resolution = 8", "spikes.remesh_iterations = 1"}},
        {"final", {"Width=640", "Height=480", "Quality=9", "Antialias=on", "Antialias_Threshold=0.3", "Antialias_Depth=3"},
         {"spikes.resolution = 16", "spikes.remesh_iterations = 3"}},
        {"large", {"Width=640", "Height=480", "Quality=9", "Antialias=on", "Antialias_Threshold=0.3", "Antialias_Depth=2"},
         {"spikes.resolution = 12", "spikes.remesh_iterations = 1"}},
    };
    for (const Expected& e : presets) {
        INFO("preset " << e.preset);
        const fs::path out = dir / e.preset;
        res = run(shot + "'" + out.string() + "' --no-run --preset " + e.preset);
        INFO(res.output);
        REQUIRE(res.code == 0);
        // Only ferro-pov's shot files: no simulation, no render.
        res = run("make -C '" + out.string() + "' --no-print-directory shot/shot.pov");
        INFO(res.output);
        REQUIRE(res.code == 0);
        const std::string ini = slurp(out / "shot" / "render.ini");
        for (const std::string& line : e.ini) CHECK(ini.find("\n" + line + "\n") != std::string::npos);
        const std::string stamp = slurp(out / ".scene" / "spikes.toml");
        for (const std::string& line : e.spikes) CHECK(stamp.find("\n" + line + "\n") != std::string::npos);
    }

    const fs::path out = dir / "override";
    res = run(shot + "'" + out.string() + "' --no-run --preset preview --set render.width=100");
    REQUIRE(res.code == 0);
    REQUIRE(run("make -C '" + out.string() + "' --no-print-directory shot/shot.pov").code == 0);
    CHECK(slurp(out / "shot" / "render.ini").find("\nWidth=100\n") != std::string::npos);
}

TEST_CASE("every stage walks the one exit-code table: missing input 4, bad input 2, run failed 3 (issue 15)", "[pov][pipeline]")
{
    // sim/core/ExitCodes.hpp: 0 done, 2 bad input, 3 the run failed, 4 an input missing.
    // Each stage's own tests check its messages; this walks the codes across all four.
    const std::string bin = pipelineBin();
    REQUIRE(fs::exists(bin + "ferro-spikes"));
    const fs::path dir = freshDir("exit_codes");
    spit(dir / "tiny.toml", kTinyScene);
    spit(dir / "garbage.ply", "not a ply file\n");
    const std::string scene = " --scene '" + (dir / "tiny.toml").string() + "'";
    const std::string missing = "'" + (dir / "missing.ply").string() + "'";
    const std::string garbage = "'" + (dir / "garbage.ply").string() + "'";
    const std::string out = " --out '" + (dir / "out").string() + "'";
    struct Case {
        std::string what, cmd;
        int code;
    };
    const std::vector<Case> cases = {
        {"ferro-sim, missing scene", bin + "ferro-sim '" + (dir / "missing.toml").string() + "'" + out, 4},
        {"ferro-sim, bad key", bin + "ferro-sim '" + (dir / "tiny.toml").string() + "'" + out + " --set fluid.colour=3", 2},
        {"ferro-sim, unknown option", bin + "ferro-sim '" + (dir / "tiny.toml").string() + "'" + out + " --no-such-flag", 2},
        {"ferro-sim, run failed (sanity guard)",
         bin + "ferro-sim '" + (dir / "tiny.toml").string() + "' --out '" + (dir / "sim").string() + "' --set sim.max_speed=1e-6", 3},
        {"ferro-surface, missing particles", bin + "ferro-surface " + missing + out + ".ply", 4},
        {"ferro-surface, garbage particles", bin + "ferro-surface " + garbage + out + ".ply", 2},
        {"ferro-surface, unknown option", bin + "ferro-surface " + garbage + out + ".ply --no-such-flag", 2},
        {"ferro-spikes, missing surface", bin + "ferro-spikes " + missing + scene + out + ".ply", 4},
        {"ferro-spikes, garbage surface", bin + "ferro-spikes " + garbage + scene + out + ".ply", 2},
        {"ferro-spikes, unknown option", bin + "ferro-spikes " + garbage + scene + out + ".ply --no-such-flag", 2},
        {"ferro-pov, missing mesh", bin + "ferro-pov " + missing + scene + out, 4},
        {"ferro-pov, garbage mesh", bin + "ferro-pov " + garbage + scene + out, 2},
        {"ferro-pov, unknown option", bin + "ferro-pov " + garbage + scene + out + " --no-such-flag", 2},
    };
    for (const Case& c : cases) {
        const Result r = run(c.cmd);
        INFO(c.what << ": " << r.output);
        CHECK(r.code == c.code);
        CHECK(std::count(r.output.begin(), r.output.end(), '\n') >= 1);
        CHECK(r.output.find(": error: ") != std::string::npos);
    }
    // The run that failed kept its frame 0.
    CHECK(fs::exists(dir / "sim" / "particles_0000.ply"));
}

TEST_CASE("a re-simulation re-meshes only the frames whose particles changed (issue 16)", "[pov][pipeline]")
{
    // scripts/shot.mk: after a re-simulation, a frame file that holds the same frame as the
    // previous run's (scripts/frame-unchanged.sh: every particle value and every header line
    // except the scene's name and hash) keeps the previous file's time, so make keeps its
    // meshes. Three re-simulations of the tiny scene, surfaces only (no render): a forced re-run
    // with nothing changed, a longer shot (one more frame), and a [sim] edit (every frame after
    // the first changes; frame 0 is the initial fill, which the edit does not move).
    const fs::path dir = freshDir("still_frames");
    spit(dir / "tiny.toml", kTinyScene);
    const fs::path out = dir / "shot";
    REQUIRE(run("FERRO_BIN='" + pipelineBin() + "' '" + kSource + "/scripts/shot.sh' '" + (dir / "tiny.toml").string() +
                "' '" + out.string() + "' --no-run")
                .code == 0);
    const std::string make = "make -C '" + out.string() + "' --no-print-directory ";
    auto surfaces = [](int last) {
        std::string t;
        for (int f = 0; f <= last; ++f) t += " surface/surface_000" + std::to_string(f) + ".ply";
        return t;
    };
    auto times = [&](int last) {
        std::map<int, fs::file_time_type> t;
        for (int f = 0; f <= last; ++f) t[f] = fs::last_write_time(out / "surface" / ("surface_000" + std::to_string(f) + ".ply"));
        return t;
    };
    Result res = run(make + surfaces(3));
    INFO(res.output);
    REQUIRE(res.code == 0);
    CHECK(res.output.find("frames unchanged: 0 of 4") != std::string::npos);   // the first run: nothing to keep
    CHECK(perFrame(res.output, "ferro-surface particles").size() == 4);
    CHECK(run(make + "-q" + surfaces(3)).code == 0);

    // Re-run with nothing changed (the sim stamp touched): every frame is rewritten with the
    // same content, none is re-meshed, and make is then up to date.
    touchNow(out / ".scene" / "sim.toml", dir);
    auto before = times(3);
    res = run(make + surfaces(3));
    INFO(res.output);
    REQUIRE(res.code == 0);
    CHECK(res.output.find("ferro-sim") != std::string::npos);
    CHECK(res.output.find("frames unchanged: 4 of 4") != std::string::npos);
    CHECK(perFrame(res.output, "ferro-surface particles").empty());
    CHECK(times(3) == before);
    CHECK(run(make + "-q" + surfaces(3)).code == 0);

    // A longer shot (duration 0.3 -> 0.4 s): frames 0-3 come out the same; only frame 4 is meshed.
    std::string scene = slurp(dir / "tiny.toml");
    scene.replace(scene.find("duration = 0.3"), 14, "duration = 0.4");
    spit(dir / "tiny.toml", scene);
    touchNow(dir / "tiny.toml", dir);
    before = times(3);
    res = run(make + surfaces(4));
    INFO(res.output);
    REQUIRE(res.code == 0);
    CHECK(res.output.find("frames unchanged: 4 of 5") != std::string::npos);
    CHECK(perFrame(res.output, "ferro-surface particles") == std::map<std::string, int>{{"0004", 1}});
    for (int f = 0; f <= 3; ++f) CHECK(fs::last_write_time(out / "surface" / ("surface_000" + std::to_string(f) + ".ply")) == before[f]);
    CHECK(run(make + "-q" + surfaces(4)).code == 0);

    // A [sim] edit that changes the motion: frames 1-4 are re-meshed, frame 0 (the fill) is not.
    spit(dir / "tiny.toml", slurp(dir / "tiny.toml") + "\n[sim]\nmax_dt = 0.0005\n");
    touchNow(dir / "tiny.toml", dir);
    res = run(make + surfaces(4));
    INFO(res.output);
    REQUIRE(res.code == 0);
    CHECK(res.output.find("frames unchanged: 1 of 5") != std::string::npos);
    CHECK(perFrame(res.output, "ferro-surface particles") ==
          std::map<std::string, int>{{"0001", 1}, {"0002", 1}, {"0003", 1}, {"0004", 1}});
    CHECK(run(make + "-q" + surfaces(4)).code == 0);

    // The helper itself: the same frame 0, two different frames, a missing old file, and a
    // file that is not PLY (one line, exit 2).
    const std::string cmp = "'" + kSource + "/scripts/frame-unchanged.sh' ";
    const std::string p0 = "'" + (out / "particles" / "particles_0000.ply").string() + "' ";
    const std::string p1 = "'" + (out / "particles" / "particles_0001.ply").string() + "' ";
    CHECK(run(cmp + p0 + p0).code == 0);
    CHECK(run(cmp + p0 + p1).code == 1);
    CHECK(run(cmp + "'" + (dir / "missing.ply").string() + "' " + p0).code == 1);
    spit(dir / "garbage.ply", "not a ply file\n");
    res = run(cmp + p0 + "'" + (dir / "garbage.ply").string() + "'");
    CHECK(res.code == 2);
    CHECK(res.output.rfind("frame-unchanged.sh: error: ", 0) == 0);
    CHECK(std::count(res.output.begin(), res.output.end(), '\n') == 1);
}

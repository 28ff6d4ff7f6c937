// The pre-roll ([shot] preroll): frame 0 is the settled fluid, with the magnets held as they
// are at t = 0, and the settled state is reused from its cache while nothing it depends on
// changes.
#include "sim/core/ParticleFile.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>

using namespace ferro;
using namespace ferro::test;

namespace {

const std::string kSim = std::string(FERRO_BINARY_DIR) + "/bin/ferro-sim";

// A 4 cm dish with a 5 mm layer (2,000 particles) over a dipole 12 mm under the floor that
// slides sideways from t = 0.6 s (three equal keys: Catmull-Rom's tangents are zero until
// then, the magnet is exactly still): the pre-roll must hold it where it is at t = 0.
const char* kSceneExtra = R"(
[[magnets]]
kind = "dipole"
position = [0.0, 0.0, -0.012]
direction = [0.0, 0.0, 1.0]
moment = 0.5
[[magnets.keys]]
time = 0.0
position = [0.0, 0.0, -0.012]
[[magnets.keys]]
time = 0.5
position = [0.0, 0.0, -0.012]
[[magnets.keys]]
time = 0.6
position = [0.0, 0.0, -0.012]
[[magnets.keys]]
time = 1.0
position = [0.01, 0.0, -0.012]

[magnetization]
susceptibility = 1.5
saturation = 35000
solver = "external"
)";

std::string framePath(const TempDir& d, const std::string& run, int f) {
    char name[48];
    std::snprintf(name, sizeof name, "/particles_%04d.ply", f);
    return d.file(run) + name;
}

double rmsSpeed(const ParticleTable& t) {
    const auto v = t.vec3("vx", "vy", "vz");
    double s = 0;
    for (const auto& u : v) s += double(u.squaredNorm());
    return std::sqrt(s / double(v.size()));
}

/// Highest particle within radius band [r0, r1) of the dish axis [m].
double topZ(const ParticleTable& t, double r0, double r1) {
    double top = -1;
    for (const auto& p : t.vec3("x", "y", "z")) {
        const double r = std::hypot(double(p.x()), double(p.y()));
        if (r >= r0 && r < r1) top = std::max(top, double(p.z()));
    }
    return top;
}

} // namespace

TEST_CASE("a pre-roll settles the fill before frame 0 with the magnets held at t = 0, cached and reused", "[cli][preroll][slow]") {
    TempDir d("preroll");
    const std::string scene = d.write("small.toml", smallPoolScene(kSceneExtra));
    const std::string sim = kSim + " " + scene + " --max-frames 3 ";

    // Without a pre-roll frame 0 is the lattice fill and the first frames move.
    const CommandResult raw = runCommand(sim + "--set shot.preroll=0 --quiet --out " + d.file("raw"));
    REQUIRE(raw.code == 0);
    const double rawSpeed = rmsSpeed(readParticleFile(framePath(d, "raw", 3)));

    const CommandResult settled = runCommand(sim + "--out " + d.file("settled"));
    INFO(settled.output);
    REQUIRE(settled.code == 0);
    REQUIRE(settled.output.find("ferro-sim: pre-roll ") != std::string::npos);
    REQUIRE(settled.output.find("cached in") != std::string::npos);
    const ParticleTable f0 = readParticleFile(framePath(d, "settled", 0));
    REQUIRE(f0.commentNumber("time", -1) == 0.0);
    double worst = 0;
    for (int f = 0; f <= 3; ++f) worst = std::max(worst, rmsSpeed(readParticleFile(framePath(d, "settled", f))));
    WARN("RMS speed over frames 0-3: without pre-roll " << 1e3 * rawSpeed << " mm/s at frame 3, after it at most "
                                                       << 1e3 * worst << " mm/s");
    // The pre-roll ends once the RMS speed is below shot.preroll_rest_speed (1 mm/s), and the
    // fluid stays at rest (within half that criterion again) while the magnet is still.
    REQUIRE(rmsSpeed(f0) < 1e-3);
    REQUIRE(worst < 1.5e-3);
    REQUIRE(rawSpeed > 5 * worst);
    // The magnet was held under the centre: the fluid heaps there (by more than one
    // spacing, 1.3 mm) against the layer near the wall.
    const double heap = topZ(f0, 0, 0.004) - topZ(f0, 0.012, 0.016);
    WARN("heap over the magnet at frame 0: " << 1e3 * heap << " mm");
    REQUIRE(heap > 1.3e-3);

    {   // the cache can live outside the output directory
        const CommandResult again = runCommand(sim + "--preroll-cache " + d.file("settled/preroll.ply") +
                                               " --out " + d.file("elsewhere"));
        INFO(again.output);
        REQUIRE(again.code == 0);
        REQUIRE(again.output.find("pre-roll reused from") != std::string::npos);
        REQUIRE(readParticleFile(framePath(d, "elsewhere", 0)).values == f0.values);
    }
    {   // a later magnet key does not invalidate the cache; frame 0 is the same state
        const CommandResult again =
            runCommand(sim + "--set magnets.0.keys.3.time=0.8 --overwrite --out " + d.file("settled"));
        INFO(again.output);
        REQUIRE(again.code == 0);
        REQUIRE(again.output.find("pre-roll reused from") != std::string::npos);
        const ParticleTable g0 = readParticleFile(framePath(d, "settled", 0));
        REQUIRE(g0.values == f0.values);
    }
    // Last, as it replaces the cache.
    {   // a change the pre-roll depends on simulates it again
        const CommandResult again = runCommand(sim + "--set shot.preroll=0.1 --overwrite --out " + d.file("settled"));
        INFO(again.output);
        REQUIRE(again.code == 0);
        REQUIRE(again.output.find("pre-roll reused") == std::string::npos);
        REQUIRE(again.output.find("ferro-sim: pre-roll 0.100 s simulated") != std::string::npos);
    }
}

TEST_CASE("a negative pre-roll is refused with one line naming the key", "[cli][preroll]") {
    TempDir d("preroll_bad");
    const std::string scene = d.write("small.toml", smallPoolScene(kSceneExtra));
    const CommandResult r = runCommand(kSim + " " + scene + " --set shot.preroll=-1 --out " + d.file("o"));
    REQUIRE(r.code == 2);
    REQUIRE(std::count(r.output.begin(), r.output.end(), '\n') == 1);
    REQUIRE(r.output.find("preroll") != std::string::npos);
}

#include "sim/app/Preroll.hpp"

#include "sim/app/FrameTable.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnetics/MagnetState.hpp"
#include "sim/sph/FluidSimulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>

namespace ferro {

namespace {

double rmsSpeed(const FluidSimulation& sim) {
    double sum = 0;
    for (const Vec3& v : sim.velocities()) sum += double(v.squaredNorm());
    return sim.size() ? std::sqrt(sum / double(sim.size())) : 0.0;
}

/// Height the fluid can fall [m]: the walls' extent along gravity, or the fluid's without walls.
double fallHeight(const FluidSimulation& sim, const Vec3d& g) {
    const double gn = g.norm();
    if (gn <= 0) return 0;
    const Vec3d down = g / gn;
    const auto& pts = sim.boundaryPositions().empty() ? sim.positions() : sim.boundaryPositions();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& p : pts) {
        const double d = down.dot(p.cast<double>());
        lo = std::min(lo, d);
        hi = std::max(hi, d);
    }
    return hi > lo ? hi - lo : 0.0;
}

std::string num(double d) {
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", d);
    return b;
}

} // namespace

SimScene frozenAtStart(const SimScene& scene) {
    SimScene s = scene;
    for (MagnetTrack& t : s.magnets) {
        t.base = t.at(0.0);
        t.keys.clear();
    }
    return s;
}

std::string prerollFingerprint(const SimScene& scene, const PrerollOptions& opt) {
    // The magnets enter only through their state at t = 0 (later keys do not change the
    // pre-roll), in the same text the particle files carry.
    ParticleTable magnets;
    std::vector<Magnet> atStart;
    for (const MagnetTrack& t : scene.magnets) atStart.push_back(t.at(0.0));
    writeMagnetComments(magnets, atStart);
    std::string key = opt.sceneFingerprint + "|preroll " + num(scene.shot.preroll) + " " +
                      num(scene.shot.prerollRestSpeed) + " " + num(scene.shot.fps);
    for (const auto& [k, v] : magnets.comments) key += "|" + k + " " + v;
    return hashHex(key);
}

PrerollState settleInitialState(const SimScene& scene, const PrerollOptions& opt) {
    const std::string fingerprint = prerollFingerprint(scene, opt);
    PrerollState out;
    FluidSimulation sim(frozenAtStart(scene));

    if (!opt.cachePath.empty() && std::filesystem::exists(opt.cachePath)) {
        try {
            const ParticleTable t = readParticleFile(opt.cachePath);
            if (t.comment("preroll_fingerprint") == fingerprint && t.rows() == sim.size()) {
                out.x = t.vec3("x", "y", "z");
                out.v = t.vec3("vx", "vy", "vz");
                if (const int col = t.column("pressure"); col >= 0)
                    for (size_t i = 0; i < t.rows(); ++i) out.p.push_back(t.at(i, col));
                if (t.column("hx") >= 0 && t.column("mx") >= 0) {
                    out.H = t.vec3("hx", "hy", "hz");
                    out.M = t.vec3("mx", "my", "mz");
                }
                out.simulated = t.commentNumber("preroll_time", 0);
                out.rmsSpeed = t.commentNumber("preroll_rms_speed", 0);
                out.fromCache = true;
                if (!opt.quiet)
                    std::fprintf(stderr, "ferro-sim: pre-roll reused from %s (%.3f s simulated, RMS speed %.2f mm/s)\n",
                                 opt.cachePath.c_str(), out.simulated, 1e3 * out.rmsSpeed);
                return out;
            }
        } catch (const ParticleFileError& e) {
            if (!opt.quiet) std::cerr << "ferro-sim: warning: pre-roll cache not used: " << e.what() << "\n";
        }
    }

    const double fps = scene.shot.fps;
    const double gn = scene.solver.gravity.norm();
    const double restFrom = gn > 0 ? std::sqrt(2 * fallHeight(sim, scene.solver.gravity) / gn) : 0.0;
    const auto start = std::chrono::steady_clock::now();
    // Whole frame intervals, the last one shortened to end exactly at `preroll`.
    for (int k = 1;; ++k) {
        const double t = std::min(k / fps, scene.shot.preroll);
        sim.advanceTo(t);
        out.rmsSpeed = rmsSpeed(sim);
        if (!opt.quiet)
            std::fprintf(stderr, "pre-roll  t %.4f s  RMS speed %.2f mm/s  %zu steps\n", t, 1e3 * out.rmsSpeed,
                         sim.stepCount());
        if (t >= scene.shot.preroll) break;
        if (t >= restFrom && out.rmsSpeed < scene.shot.prerollRestSpeed) break;
    }
    out.simulated = sim.time();
    out.x = sim.positionsById();
    out.v = sim.velocitiesById();
    out.p = sim.pressuresById();
    out.H = sim.fieldById();
    out.M = sim.magnetizationById();

    if (!opt.cachePath.empty()) {
        ParticleTable t = frameTable(sim, -1, {});
        t.setComment("preroll_fingerprint", fingerprint);
        t.setComment("preroll_time", num(out.simulated));
        t.setComment("preroll_rms_speed", num(out.rmsSpeed));
        writeParticleFile(opt.cachePath, t);
    }
    if (!opt.quiet) {
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::fprintf(stderr, "ferro-sim: pre-roll %.3f s simulated in %.1f s wall, RMS speed %.2f mm/s%s%s\n",
                     out.simulated, wall, 1e3 * out.rmsSpeed,
                     opt.cachePath.empty() ? "" : ", cached in ", opt.cachePath.c_str());
    }
    return out;
}

} // namespace ferro

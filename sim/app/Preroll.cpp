#include "sim/app/Preroll.hpp"

#include "sim/app/FrameTable.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/MagnetState.hpp"
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

/// Height the fluid can fall [m]: the extent along gravity of the walls and the fluid together
/// (the walls alone are a flat floor in a box with periodic sides and an open top).
double fallHeight(const FluidSimulation& sim, const Vec3d& g) {
    const double gn = g.norm();
    if (gn <= 0) return 0;
    const Vec3d down = g / gn;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto* pts : {&sim.boundaryPositions(), &sim.positions()})
        for (const Vec3& p : *pts) {
            const double d = down.dot(p.cast<double>());
            lo = std::min(lo, d);
            hi = std::max(hi, d);
        }
    return hi > lo ? hi - lo : 0.0;
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
    std::string key = opt.sceneFingerprint + "|preroll " + formatNumber(scene.shot.preroll) + " " +
                      formatNumber(scene.shot.prerollRestSpeed) + " " + formatNumber(scene.shot.fps);
    for (const auto& [k, v] : magnets.comments) key += "|" + k + " " + v;
    return hashHex(key);
}

PrerollState settleInitialState(const SimScene& scene, const PrerollOptions& opt) {
    const std::string fingerprint = prerollFingerprint(scene, opt);
    PrerollState out;
    if (!opt.cachePath.empty() && std::filesystem::exists(opt.cachePath)) {
        try {
            const ParticleTable t = readParticleFile(opt.cachePath);
            if (t.comment("preroll_fingerprint") == fingerprint && t.rows() == opt.particles) {
                out.state = frameState(t);
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

    // Only on a cache miss: the frozen scene's simulation.
    FluidSimulation sim(frozenAtStart(scene));
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
    // The state as the cache holds it (float columns), so a run from the cache and this one
    // start from the same numbers.
    ParticleTable t = frameTable(sim, -1, {});
    out.state = frameState(t);
    if (!opt.cachePath.empty()) {
        t.setComment("preroll_fingerprint", fingerprint);
        t.setComment("preroll_time", formatNumber(out.simulated));
        t.setComment("preroll_rms_speed", formatNumber(out.rmsSpeed));
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

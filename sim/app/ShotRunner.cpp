#include "sim/app/ShotRunner.hpp"
#include "sim/core/DirectoryLock.hpp"

#include "sim/app/FrameTable.hpp"
#include "sim/app/Preroll.hpp"

#include "sim/sph/FluidSimulation.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <regex>
#include <sstream>
#include <utility>
#include <vector>

namespace fs = std::filesystem;

namespace ferro {

std::string particleFramePath(const std::string& dir, int frame) {
    char name[64];
    std::snprintf(name, sizeof name, "particles_%04d.ply", frame);
    return (fs::path(dir) / name).string();
}

namespace {

std::string formatSeconds(double s) {
    std::ostringstream o;
    if (s >= 3600) o << int(s / 3600) << "h" << int(std::fmod(s, 3600) / 60) << "m";
    else if (s >= 60) o << int(s / 60) << "m" << int(std::fmod(s, 60)) << "s";
    else o << int(std::ceil(s)) << "s";
    return o.str();
}

/// Frame indices of complete-looking particle files in `dir` (sorted), removing
/// temporary files that a killed writer left behind.
std::vector<int> existingFrames(const std::string& dir) {
    std::vector<int> frames;
    if (!fs::is_directory(dir)) return frames;
    static const std::regex frameName(R"(particles_(\d+)\.ply)");
    static const std::regex tempName(R"(particles_\d+\.ply\.tmp-.*)");
    for (const auto& e : fs::directory_iterator(dir)) {
        const std::string name = e.path().filename().string();
        std::smatch m;
        if (std::regex_match(name, m, frameName)) frames.push_back(std::stoi(m[1]));
        else if (std::regex_match(name, tempName)) fs::remove(e.path());
    }
    std::sort(frames.begin(), frames.end());
    return frames;
}

/// One line, once a run, when a frame's pressure solves keep stopping at the iteration cap
/// (more than a tenth of its steps): the density they leave is then not the tolerance's.
/// Printed in quiet runs too.
void warnAboutSolverCap(const FluidSimulation& sim, int frame, bool& warned) {
    const SolverCapCount& caps = sim.frameSolverCaps();
    if (warned || 10 * caps.atCap() <= caps.steps) return;
    warned = true;
    const std::string why = sim.pressureSolverCapWarning(caps);
    if (!why.empty()) std::fprintf(stderr, "ferro-sim: warning: frame %d: %s\n", frame, why.c_str());
}

std::string magnetSummary(const FluidSimulation& sim) {
    const FluidMagnetics* fm = sim.magnetics();
    if (!fm) return {};
    std::ostringstream o;
    o << ", " << sim.scene().magnets.size() << " magnet" << (sim.scene().magnets.size() == 1 ? "" : "s");
    if (fm->magnetic()) o << ", chi0 " << fm->law().susceptibility << ", Ms " << fm->law().saturation << " A/m";
    else o << " (fluid not magnetic: magnetization.susceptibility = 0)";
    return o.str();
}

// The viscosity method in use; for "auto", which one it chose (said, so a user can see why
// a thick fluid's steps cost what they do).
std::string viscositySummary(const FluidSimulation& sim) {
    const bool chosen = sim.scene().fluid.viscosityMethod == FluidParams::ViscosityMethod::Auto;
    return std::string(sim.implicitViscosity() ? "implicit" : "explicit") + " viscosity" + (chosen ? " (auto)" : "");
}

} // namespace

void runShot(const SimScene& scene, const RunOptions& opt) {
    if (opt.outDir.empty()) throw SceneError("--out: an output directory is required");
    std::error_code ec;
    fs::create_directories(opt.outDir, ec);
    if (ec) throw ParticleFileError(opt.outDir + ": cannot create directory: " + ec.message());
    // One writer a folder, taken before anything in it is read, removed or written.
    const DirectoryLock lock(opt.outDir, "ferro-sim " + scene.path);

    std::vector<int> frames = existingFrames(opt.outDir);
    if (!frames.empty() && !opt.resume && !opt.overwrite)
        throw SceneError(opt.outDir + ": already holds particle frames; pass --resume to continue or --overwrite to start over");
    if (opt.overwrite && !opt.resume) {
        for (int f : frames) fs::remove(particleFramePath(opt.outDir, f));
        frames.clear();
    }

    FluidSimulation sim(scene);
    const int lastFrame = opt.maxFrames >= 0 ? std::min(opt.maxFrames, scene.shot.frameCount()) : scene.shot.frameCount();
    const double fps = scene.shot.fps;

    int frame = 0;
    bool resumed = false;
    // A frame is trusted only if every earlier frame file exists and its header's `frame`
    // comment is the number in its name: frames 0..gap-1 are the candidates. Resume from
    // the newest candidate that reads back completely (writes are atomic, so normally the
    // newest). Frames after the resume point (a damaged or mislabelled candidate, frames
    // after a gap, stray files) are left as they are until the run reaches and rewrites them.
    int gap = 0;
    while (gap < int(frames.size()) && frames[size_t(gap)] == gap) ++gap;
    if (opt.resume && !frames.empty() && gap == 0)
        throw SceneError(particleFramePath(opt.outDir, 0) + ": missing, so no frame in " + opt.outDir +
                         " can be trusted to resume from (found " +
                         fs::path(particleFramePath(opt.outDir, frames.front())).filename().string() +
                         "); pass --overwrite to start over");
    for (auto it = frames.rend() - gap; opt.resume && it != frames.rend(); ++it) {
        ParticleTable t;
        try {
            t = readParticleFile(particleFramePath(opt.outDir, *it));
        } catch (const ParticleFileError& e) {
            std::cerr << "ferro-sim: warning: skipping unreadable " << e.what() << "\n";
            continue;
        }
        if (t.comment("cache") == "compact")
            continue; // a compact frame holds no full state: resume from an earlier full one
        if (t.commentNumber("frame", -1) != *it) {
            std::cerr << "ferro-sim: warning: skipping " << particleFramePath(opt.outDir, *it)
                      << ": its header says frame " << t.comment("frame", "(none)") << "\n";
            continue;
        }
        const std::string fp = t.comment("scene_fingerprint");
        if (fp != opt.fingerprint && (opt.legacyFingerprint.empty() || fp != opt.legacyFingerprint))
            throw SceneError(particleFramePath(opt.outDir, *it) +
                             ": written from a different scene or --set overrides; resume with the same ones, or --overwrite");
        if (t.rows() != sim.size())
            throw SceneError(particleFramePath(opt.outDir, *it) + ": holds " + std::to_string(t.rows()) +
                             " particles, the scene makes " + std::to_string(sim.size()));
        const FrameState state = frameState(t);
        sim.setState(*it / fps, state.x, state.v, state.p, state.H, state.M);
        sim.setMagnetizationInterval(size_t(t.commentNumber("magnetization_interval", 0)));
        if (state.curve) sim.setMagnetizationCurve({*state.curve, state.curveTime});
        frame = *it;
        resumed = true;
        break;
    }
    if (resumed && frames.back() > frame) {
        // Say which frames the run will rewrite, and why it did not resume after them.
        const std::string why = gap < int(frames.size())
            ? "frame " + std::to_string(gap) + " is missing"
            : "frame " + std::to_string(frame + 1) + " cannot be trusted";
        std::cerr << "ferro-sim: warning: resuming after frame " << frame << " although frames up to "
                  << frames.back() << " exist (" << why << "); "
                  << (lastFrame > frame ? "frames " + std::to_string(frame + 1) + " to " + std::to_string(lastFrame) +
                                              " are rewritten, later ones left as they are"
                                        : std::string("they are left as they are"))
                  << "\n";
    }
    if (!resumed) {
        if (opt.resume && !frames.empty())
            throw ParticleFileError(opt.outDir + ": no readable particle frame to resume from");
        if (scene.shot.preroll > 0) {
            PrerollOptions po;
            po.cachePath = opt.prerollCache.empty() ? (fs::path(opt.outDir) / "preroll.ply").string() : opt.prerollCache;
            po.sceneFingerprint = opt.prerollFingerprint.empty() ? opt.fingerprint : opt.prerollFingerprint;
            po.quiet = opt.quiet;
            po.particles = sim.size();
            const PrerollState preroll = settleInitialState(scene, po);
            const FrameState& settled = preroll.state;
            sim.setState(0.0, settled.x, settled.v, settled.p, settled.H, settled.M);
            // The pre-roll's clock ended at preroll.simulated; the shot's starts at 0.
            if (settled.curve) sim.setMagnetizationCurve({*settled.curve, settled.curveTime - preroll.simulated});
        }
        writeParticleFile(particleFramePath(opt.outDir, 0), frameTable(sim, 0, opt.fingerprint));
    }
    if (!opt.quiet)
        std::cerr << "ferro-sim: " << sim.size() << " particles, spacing " << sim.spacing() * 1e3 << " mm, "
                  << sim.pressureSolverSummary() << ", " << viscositySummary(sim) << ", "
                  << sim.boundaryPositions().size() << " boundary particles"
                  << magnetSummary(sim) << "; "
                  << (resumed ? "resuming after frame " + std::to_string(frame) : std::string("starting"))
                  << ", frames to " << lastFrame << "\n";
    if (!opt.quiet)
        if (const std::string advice = sim.pressureSolverAdvice(); !advice.empty()) std::cerr << "ferro-sim: note: " << advice << "\n";

    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    const size_t startSteps = sim.stepCount();
    const int firstFrame = frame;
    bool capWarned = false;
    while (frame < lastFrame) {
        ++frame;
        const auto frameStart = Clock::now();
        const size_t stepsBefore = sim.stepCount();
        sim.resetMagneticsCounters();
        sim.advanceTo(frame / fps);
        writeParticleFile(particleFramePath(opt.outDir, frame),
                          frameTable(sim, frame, opt.fingerprint, !scene.shot.fullFrame(frame, lastFrame)));
        warnAboutSolverCap(sim, frame, capWarned);
        if (!opt.quiet) {
            const double now = std::chrono::duration<double>(Clock::now() - start).count();
            const double frameSec = std::chrono::duration<double>(Clock::now() - frameStart).count();
            const size_t steps = sim.stepCount() - stepsBefore;
            const double eta = now / (frame - firstFrame) * (lastFrame - frame);
            const StepStats& st = sim.lastStep();
            std::string mag;
            if (const FluidMagnetics* fm = sim.magnetics(); fm && fm->magnetic()) {
                // How often the magnetization was re-solved: the field changes far more
                // slowly than the step, so most steps reuse the induced field.
                char buf[160];
                std::snprintf(buf, sizeof buf, "  M solves %zu/%zu (%s, %d it, drift %.2g%%)", fm->stats().solves,
                              fm->stats().steps, fm->stats().solver.c_str(), fm->stats().iterations,
                              100 * fm->stats().cacheError);
                mag = buf;
                if (!fm->stats().converged) { // stays on the frame's one line
                    std::snprintf(buf, sizeof buf, " NOT CONVERGED (residual %.1e > tolerance/10)", fm->stats().residual);
                    mag += buf;
                }
                if (fm->stats().solidPanels > 0) { // [[solids]]: their charge solve and its cost this frame
                    std::snprintf(buf, sizeof buf, "  solids %zu panels (%d it, %.1f s)%s", fm->stats().solidPanels,
                                  fm->stats().solidIterations, fm->stats().solidSeconds,
                                  fm->stats().solidConverged ? "" : " NOT CONVERGED");
                    mag += buf;
                }
            }
            if (const SolverCapCount& caps = sim.frameSolverCaps(); caps.atCap() > 0) {
                // Steps whose pressure solve stopped at its cap above the tolerance.
                char buf[160];
                std::snprintf(buf, sizeof buf, "  AT CAP p %zu d %zu of %zu steps (err up to %.3f%% / %.3f%%)",
                              caps.densityAtCap, caps.divergenceAtCap, caps.steps, 100 * caps.densityError,
                              100 * caps.divergenceError);
                mag += buf;
            }
            if (sim.implicitViscosity()) { // the implicit viscosity solve of the frame's last step
                char buf[80];
                std::snprintf(buf, sizeof buf, "  visc it %d (res %.1e)", st.viscosityIterations, st.viscosityResidual);
                mag += buf;
            }
            // The pressure solves' mean iterations over the frame's steps, and how the density
            // solve iterated (sim.pressure_iteration): the steps that ran conjugate gradients,
            // when any did; otherwise Jacobi alone.
            const SolverCapCount& fc = sim.frameSolverCaps();
            const double perStep = 1.0 / double(std::max<size_t>(fc.steps, 1));
            std::string how;
            if (fc.densityByCg > 0) how = " (cg " + std::to_string(fc.densityByCg) + "/" + std::to_string(fc.steps) + ")";
            // What bounded the frame's steps, most often first (FluidSimulation::chooseTimeStep).
            std::string bounds;
            {
                std::vector<std::pair<size_t, int>> order;
                for (int b = 0; b < int(TimeStepBound::Count); ++b)
                    if (fc.dtBounds[b] > 0) order.emplace_back(fc.dtBounds[b], b);
                std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
                for (const auto& [count, b] : order)
                    bounds += (bounds.empty() ? " (" : ", ") + std::string(timeStepBoundName(TimeStepBound(b))) + " " +
                              std::to_string(count);
                if (!bounds.empty()) bounds += ")";
            }
            std::fprintf(stderr,
                         "frame %4d/%d  t %.4f s  %5zu steps  %6.1f steps/s  dt %.2e s%s  iter p %.1f%s d %.1f  "
                         "rho err %.3f%%%s  ETA %s\n",
                         frame, lastFrame, sim.time(), steps, steps / std::max(frameSec, 1e-9), st.dt, bounds.c_str(),
                         double(fc.pressureIterations) * perStep, how.c_str(), double(fc.divergenceIterations) * perStep,
                         100 * st.densityError, mag.c_str(), formatSeconds(eta).c_str());
        }
    }
    if (!opt.quiet) {
        const double wall = std::chrono::duration<double>(Clock::now() - start).count();
        // The sanity guard's margin: the fastest particle over the speed all of the scene's
        // energy would give one particle (the guard stops at SanityLimits::kSpeedSafety).
        const SolverCapCount& caps = sim.runSolverCaps();
        std::string cap;
        if (caps.atCap() > 0)
            cap = ", " + std::to_string(caps.densityAtCap) + " density and " + std::to_string(caps.divergenceAtCap) +
                  " divergence solves stopped at the iteration cap";
        std::fprintf(stderr, "ferro-sim: done, %zu steps in %.1f s wall, max speed %.2f x the scene's energy speed %.3g m/s%s\n",
                     sim.stepCount() - startSteps, wall, sim.maxSpeedRatio(), sim.speedBound().energySpeed(), cap.c_str());
    }
}

} // namespace ferro

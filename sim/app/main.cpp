// ferro-sim: simulates a shot's fluid and writes one particle file per frame.
// Parses arguments and calls the ferro_app library; nothing else lives here.
#include "sim/core/CommandLine.hpp"
#include "sim/sph/FluidSimulation.hpp"
#include "sim/sph/PressureSolver.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimSceneFile.hpp"
#include "sim/app/ShotRunner.hpp"

#include "sim/sph/FluidSeed.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>

int main(int argc, char** argv) {
    using namespace ferro;
    CLI::App app{"ferro-sim: SPH simulation of a ferrofluid shot; writes DIR/particles_NNNN.ply per frame"};
    std::string scenePath;
    RunOptions opt;
    std::vector<std::string> overrides;
    int threads = -1;
    bool printInputs = false, printSize = false;
    app.add_option("scene", scenePath, "scene file (TOML)")->required();
    auto* out = app.add_option("--out,-o", opt.outDir, "output directory for particle files");
    addSceneInputsFlag(app, printInputs, {out}, {&printSize});
    app.add_flag("--print-size", printSize,
                 "print the run's estimated size (particles, boundary particles, peak bytes, frames) and "
                 "the scene fingerprint its frames carry, as key=value words, and exit: for "
                 "schedulers (scripts/slurm/)");
    addSetOption(app, overrides, "override a scene key by its TOML path: --set section.key=value");
    app.add_option("--max-frames", opt.maxFrames, "stop after writing frame N (N frames after the initial one)")
        ->check(CLI::NonNegativeNumber);
    auto* resume = app.add_flag("--resume", opt.resume, "continue from the last complete frame in the output directory");
    app.add_flag("--overwrite", opt.overwrite, "delete frames already in the output directory and start over")
        ->excludes(resume);
    app.add_option("--preroll-cache", opt.prerollCache,
                   "particle file caching the settled pre-roll state (default OUT/preroll.ply)");
    app.add_flag("--quiet,-q", opt.quiet, "no progress lines on stderr");
    addThreadsOption(app, threads, "worker threads (default: sim.threads, 0 = all cores)");
    const std::vector<ErrorExit> errors = {
        exitOn<SceneError>(kExitBadInput),
        exitOn<SimulationError>(kExitSimulationFailed, " (frames written so far are kept)"),
        exitOn<ParticleFileError>(kExitIoError),
    };
    return runCommandLine("ferro-sim", app, argc, argv, errors, [&] {
        SceneDocument doc = SceneDocument::load(scenePath, overrides);
        if (printInputs)
            return printSceneInputs(doc, [](const SceneDocument& d) {
                const SimScene scene = parseSimScene(d);
                parsePressureSolverKeys(scene.solver, scene.path);
            });
        // The fingerprint hashes the keys the simulation reads, so that a render, surface or
        // spikes key edited mid-shot leaves its frames resumable (sim.threads changes no bit).
        doc.recordReads();
        const SimScene scene = parseSimScene(doc);
        parsePressureSolverKeys(scene.solver, scene.path);   // its own [sim] keys, checked before any run
        const std::string fingerprint = doc.readsFingerprint({"sim.threads"});
        if (printSize) {
            const RunSize size = estimateRunSize(scene);
            const int lastFrame = opt.maxFrames >= 0 ? std::min(opt.maxFrames, scene.shot.frameCount())
                                                     : scene.shot.frameCount();
            std::cout << "particles=" << std::llround(size.fluidParticles)
                      << " boundary_particles=" << std::llround(size.boundaryParticles)
                      << " bytes=" << std::llround(size.bytes) << " spacing=" << size.spacing << " frames=" << lastFrame + 1
                      << " fps=" << scene.shot.fps << " preroll=" << scene.shot.preroll
                      << " scene_fingerprint=" << fingerprint << "\n";
            return kExitOk;
        }
        opt.fingerprint = fingerprint;
        opt.legacyFingerprint = doc.fingerprint();
        // The solids are walls the pre-roll settles against; a scene without them keeps the
        // fingerprint it always had (its cached pre-roll stays valid).
        std::vector<std::string> prerollSections{"fluid", "container", "sim", "magnetization"};
        if (doc.hasSection("solids")) prerollSections.push_back("solids");
        opt.prerollFingerprint = doc.fingerprint(prerollSections);
        const auto limit = limitThreads(threads >= 0 ? threads : scene.solver.threads);
        runShot(scene, opt);
        return kExitOk;
    });
}

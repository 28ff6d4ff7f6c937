// ferro-sim: simulates a shot's fluid and writes one particle file per frame.
// Parses arguments and calls the ferro_sim library; nothing else lives here.
#include "sim/FluidSimulation.hpp"
#include "sim/ParticleFile.hpp"
#include "sim/SceneFile.hpp"
#include "sim/ShotRunner.hpp"

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <iostream>
#include <memory>

int main(int argc, char** argv) {
    using namespace ferro;
    CLI::App app{"ferro-sim: SPH simulation of a ferrofluid shot; writes DIR/particles_NNNN.ply per frame"};
    std::string scenePath;
    RunOptions opt;
    std::vector<std::string> overrides;
    int threads = -1;
    app.add_option("scene", scenePath, "scene file (TOML)")->required();
    app.add_option("--out,-o", opt.outDir, "output directory for particle files")->required();
    app.add_option("--set", overrides, "override a scene key by its TOML path: --set section.key=value")
        ->type_name("KEY=VALUE");
    app.add_option("--max-frames", opt.maxFrames, "stop after writing frame N (N frames after the initial one)")
        ->check(CLI::NonNegativeNumber);
    auto* resume = app.add_flag("--resume", opt.resume, "continue from the last complete frame in the output directory");
    app.add_flag("--overwrite", opt.overwrite, "delete frames already in the output directory and start over")
        ->excludes(resume);
    app.add_flag("--quiet,-q", opt.quiet, "no progress lines on stderr");
    app.add_option("--threads", threads, "worker threads (default: sim.threads, 0 = all cores)")
        ->check(CLI::NonNegativeNumber);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "ferro-sim: error: " << e.what() << " (see --help)\n";
        return kExitBadInput;
    }

    try {
        const SceneDocument doc = SceneDocument::load(scenePath, overrides);
        const SimScene scene = parseSimScene(doc);
        opt.fingerprint = doc.fingerprint();
        const int n = threads >= 0 ? threads : scene.solver.threads;
        std::unique_ptr<tbb::global_control> limit;
        if (n > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(n));
        runShot(scene, opt);
    } catch (const SceneError& e) {
        std::cerr << "ferro-sim: error: " << e.what() << "\n";
        return kExitBadInput;
    } catch (const SimulationError& e) {
        std::cerr << "ferro-sim: error: " << e.what() << " (frames written so far are kept)\n";
        return kExitSimulationFailed;
    } catch (const ParticleFileError& e) {
        std::cerr << "ferro-sim: error: " << e.what() << "\n";
        return kExitIoError;
    } catch (const std::exception& e) {
        std::cerr << "ferro-sim: error: " << e.what() << "\n";
        return kExitFailure;
    }
    return kExitOk;
}

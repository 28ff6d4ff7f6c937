// ferro-spikes: the paper's procedural Rosensweig spikes on a surface mesh, one frame or a range.
// Parses arguments and calls the ferro_spikes library; nothing else lives here.
#include "sim/ParticleFile.hpp"
#include "sim/SceneFile.hpp"
#include "sim/ShotRunner.hpp"
#include "spikes/SpikeFrames.hpp"
#include "surface/ErrorText.hpp"

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <iostream>
#include <memory>

int main(int argc, char** argv) {
    using namespace ferro;
    CLI::App app{"ferro-spikes: hexagonal ferrofluid spikes (paper section 4.3) mapped onto a surface mesh\n"
                 "  ferro-spikes SURFACE.ply --particles PARTICLES.ply --scene SCENE.toml --out SPIKY.ply\n"
                 "  ferro-spikes 'meshes/surface_{:04}.ply' --particles 'frames/particles_{:04}.ply' --frames A:B \\\n"
                 "               --scene SCENE.toml --out 'spiky/spiky_{:04}.ply'"};
    std::string surface, particles, scenePath, out, frames;
    std::vector<std::string> overrides;
    int threads = 0;
    bool quiet = false;
    app.add_option("surface", surface, "surface mesh (PLY from ferro-surface), or a pattern with {:04} / %04d")
        ->required();
    app.add_option("--particles,-p", particles,
                   "particle file (or pattern) of the same frame: |M| for the mapping area; optional");
    app.add_option("--scene,-s", scenePath, "scene file (TOML): fluid, container, magnets, [spikes]")->required();
    app.add_option("--out,-o", out, "output mesh (or pattern); PLY unless the extension says otherwise")->required();
    app.add_option("--frames", frames, "frame range A:B (inclusive) for patterns")->type_name("A:B");
    app.add_option("--set", overrides, "override a scene key: --set spikes.alpha=80")->type_name("KEY=VALUE");
    app.add_option("--threads", threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber);
    app.add_flag("--quiet,-q", quiet, "no progress lines on stderr");
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "ferro-spikes: error: " << e.what() << " (see --help)\n";
        return kExitBadInput;
    }
    int first = -1, last = -1;
    if (!frames.empty()) {
        try {
            const FrameRange range = parseFrameRange(frames);
            first = range.first;
            last = range.last;
        } catch (const std::invalid_argument& e) {
            std::cerr << "ferro-spikes: error: --frames " << e.what() << "\n";
            return kExitBadInput;
        }
    }

    try {
        std::unique_ptr<tbb::global_control> limit;
        if (threads > 0)
            limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(threads));
        const SpikeScene scene = parseSpikeScene(SceneDocument::load(scenePath, overrides));
        if (first < 0) {
            const SpikeResult res = spikeFrame(scene, surface, particles, out);
            if (!quiet)
                std::cerr << "ferro-spikes: " << res.tips.size() << " tips, " << res.mesh.triangles.size()
                          << " triangles -> " << out << "\n";
        } else {
            spikeFrames(scene, surface, particles, out, first, last, quiet);
        }
    } catch (const SceneError& e) {
        std::cerr << "ferro-spikes: error: " << e.what() << "\n";
        return kExitBadInput;
    } catch (const SpikeInputError& e) {
        std::cerr << "ferro-spikes: error: " << e.what() << "\n";
        return kExitBadInput;
    } catch (const SpikeIoError& e) {
        std::cerr << "ferro-spikes: error: " << e.what() << "\n";
        return kExitIoError;
    } catch (const MeshFileError& e) {
        std::cerr << "ferro-spikes: error: " << e.what() << "\n";
        return kExitIoError;
    } catch (const std::exception& e) {
        // Internal failures (CGAL, out of memory, ...): their messages may span lines.
        std::cerr << "ferro-spikes: error: " << oneLine(e.what()) << "\n";
        return kExitFailure;
    }
    return kExitOk;
}

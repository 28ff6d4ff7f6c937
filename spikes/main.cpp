// ferro-spikes: the paper's procedural Rosensweig spikes on a surface mesh, one frame or a range.
// Parses arguments and calls the ferro_spikes library; nothing else lives here.
#include "sim/core/CommandLine.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/core/ExitCodes.hpp"
#include "spikes/SpikeFrames.hpp"
#include "sim/core/ErrorText.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

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
    bool printInputs = false;
    auto* surfaceOpt = app.add_option("surface", surface, "surface mesh (PLY from ferro-surface), or a pattern with {:04} / %04d");
    app.add_option("--particles,-p", particles,
                   "particle file (or pattern) of the same frame: |M| for the mapping area; optional");
    app.add_option("--scene,-s", scenePath, "scene file (TOML): fluid, container, magnets, [spikes]")->required();
    auto* outOpt = app.add_option("--out,-o", out, "output mesh (or pattern); PLY unless the extension says otherwise");
    addSceneInputsFlag(app, printInputs, {surfaceOpt, outOpt});
    std::string history;
    app.add_option("--particle-history", history,
                   "particle files of earlier frames ({:04} / %04d pattern) for [spikes] response_time: the tips "
                   "ride the flow they hold (default with --frames: the --particles pattern)");
    app.add_option("--frames", frames, "frame range A:B (inclusive) for patterns")->type_name("A:B");
    addSetOption(app, overrides, "override a scene key: --set spikes.alpha=80");
    addThreadsOption(app, threads, "worker threads (0 = all cores)");
    app.add_flag("--quiet,-q", quiet, "no progress lines on stderr");
    const std::vector<ErrorExit> errors = {
        exitOn<SceneError>(kExitBadInput),
        // Missing (4) or unusable (2) inputs and failed writes are StageErrors with their code.
        // Internal failures (CGAL, out of memory, ...): their messages may span lines.
        exitOn<std::exception>(kExitFailure, "", oneLine),
    };
    return runCommandLine("ferro-spikes", app, argc, argv, errors, [&] {
        const FrameRange range = frames.empty() ? FrameRange{-1, -1} : frameRangeArgument("--frames", frames);
        SceneDocument doc = SceneDocument::load(scenePath, overrides);
        if (printInputs)
            return printSceneInputs(doc, [](const SceneDocument& d) { parseSpikeScene(d); });
        const auto limit = limitThreads(threads);
        const SpikeScene scene = parseSpikeScene(doc);
        if (range.first < 0) {
            const SpikeResult res = spikeFrame(scene, surface, particles, out, -1, history);
            if (!quiet)
                std::cerr << "ferro-spikes: " << res.tips.size() << " tips, " << res.mesh.triangles.size()
                          << " triangles -> " << out << "\n";
        } else {
            if (!history.empty() && history != particles)
                throw SpikeInputError("--particle-history: with --frames the history is the --particles pattern");
            spikeFrames(scene, surface, particles, out, range.first, range.last, quiet);
        }
        return kExitOk;
    });
}

// ferro-pov: exports meshes as POV-Ray includes plus the shot's master scene, .ini files and
// look template. Parses arguments and calls the ferro_pov library; nothing else lives here.
#include "povray/PovExport.hpp"
#include "sim/core/CommandLine.hpp"
#include "sim/core/FrameRunner.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/core/ExitCodes.hpp"
#include "sim/core/ErrorText.hpp"

#include <CLI/CLI.hpp>

#include <iostream>


int main(int argc, char** argv)
{
    using namespace ferro;
    CLI::App app{"ferro-pov: writes a mesh as a POV-Ray mesh2 include (SHOTDIR/mesh_NNNN.inc) with its magnets\n"
                 "(SHOTDIR/magnets_NNNN.inc), and the shot's shot.pov, render.ini, shot.ini and look.inc.\n"
                 "  ferro-pov SPIKY.ply --scene S.toml --frame N --out SHOTDIR\n"
                 "  ferro-pov 'spiky/spiky_{:04}.ply' --frames A:B --scene S.toml --out SHOTDIR\n"
                 "  ferro-pov --scene S.toml --out SHOTDIR          (shot files only)\n"
                 "Then: cd SHOTDIR && povray shot.ini +SF10 +EF20"};
    std::string input, scenePath, outDir, framesText, shotFramesText;
    std::vector<std::string> overrides;
    int frame = -1, threads = 0;
    bool forceTemplate = false, noShot = false, quiet = false, printInputs = false;
    app.add_option("mesh", input, "mesh file (PLY, OBJ, ...), or a pattern with {:04} / %04d together with --frames");
    app.add_option("--scene,-s", scenePath, "scene file (TOML): [render], [container], [shot], [[magnets]], [[solids]]")->required();
    auto* outOpt = app.add_option("--out,-o", outDir, "shot directory");
    addSceneInputsFlag(app, printInputs, {outOpt});
    auto* frameOpt = app.add_option("--frame", frame, "frame number of a single mesh (default: the mesh's `comment frame`)")
                         ->check(CLI::NonNegativeNumber);
    app.add_option("--frames", framesText, "frame range FIRST:LAST of a mesh pattern")->excludes(frameOpt);
    app.add_option("--shot-frames", shotFramesText, "frame range of shot.ini (default: the whole shot, 0 .. duration*fps)");
    app.add_flag("--no-shot", noShot, "write only the frame includes, not shot.pov, the .ini files or look.inc");
    app.add_flag("--force-template", forceTemplate, "overwrite look.inc with a fresh template (discards edits)");
    addSetOption(app, overrides, "override a scene key: --set render.width=320");
    addThreadsOption(app, threads, "worker threads for a frame range (0 = all cores)");
    app.add_flag("--quiet,-q", quiet, "no progress lines on stderr");

    const std::vector<ErrorExit> errors = {
        exitOn<SceneError>(kExitBadInput),
        // Missing or malformed meshes and failed writes are StageErrors: they carry their code.
        exitOn<std::exception>(kExitFailure, "", oneLine),
    };
    return runCommandLine("ferro-pov", app, argc, argv, errors, [&] {
        // Checks CLI11 cannot express: reported like its own parse errors.
        std::pair<int, int> frames{-1, -1}, shotFrames{-1, -1};
        if (!framesText.empty())
            { const FrameRange r = frameRangeArgument("--frames", framesText); frames = {r.first, r.last}; }
        if (!shotFramesText.empty())
            { const FrameRange r = frameRangeArgument("--shot-frames", shotFramesText); shotFrames = {r.first, r.last}; }
        const PovOutput what = noShot ? PovOutput::FramesOnly : PovOutput::ShotAndFrames;
        if (printInputs) {
            SceneDocument doc = SceneDocument::load(scenePath, overrides);
            return printSceneInputs(doc, [&](const SceneDocument& d) { parsePovScene(d, shotFrames.first, shotFrames.second, what); });
        }
        if (!framesText.empty() && input.empty())
            throw CLI::ValidationError("--frames", "needs a mesh pattern");
        if (framesText.empty() && input.empty() && noShot)
            throw CLI::ValidationError("--no-shot", "without a mesh there is nothing to write");

        const auto limit = limitThreads(threads);
        const SceneDocument doc = SceneDocument::load(scenePath, overrides);
        const PovExporter exporter(doc, outDir, shotFrames.first, shotFrames.second, what);
        if (!input.empty() && frames.first >= 0) {
            runFrames({frames.first, frames.second}, {{"mesh pattern", input}}, [&](int f) {
                exporter.exportFrameFile(framePath(input, f), f);
                if (!quiet)
                    std::cerr << "ferro-pov: frame " + std::to_string(f) + " -> " + exporter.meshIncludePath(f) + "\n";
            });
        } else if (!input.empty()) {
            requireReadable(input);
            const TriangleMesh mesh = readMesh(input);
            int f = frame;
            if (f < 0) {
                ParticleTable header;
                header.comments = mesh.comments;
                const double commented = header.commentNumber("frame", -1);
                if (!(commented >= 0))
                    throw MeshFileError(input + ": no `comment frame` in the file; give --frame N");
                f = int(commented);
            }
            try {
                exporter.exportFrame(mesh, f);
            } catch (const MeshFileError& e) {
                throw MeshFileError(input + ": " + e.what());
            }
            if (!quiet)
                std::cerr << "ferro-pov: frame " << f << " -> " << exporter.meshIncludePath(f) << "\n";
        }
        if (!noShot && exporter.writeShotFiles(forceTemplate) && !quiet)
            std::cerr << "ferro-pov: wrote the look template " << outDir << "/look.inc\n";
        return kExitOk;
    });
}

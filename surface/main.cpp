// ferro-surface: meshes particle files into fluid surfaces (Yu-Turk anisotropic kernels).
// Parses arguments and calls the ferro_surface library; nothing else lives here.
#include "sim/core/ErrorText.hpp"
#include "surface/SurfaceParams.hpp"
#include "surface/SurfaceShot.hpp"

#include "sim/core/CommandLine.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimSceneFile.hpp"
#include "sim/core/ExitCodes.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <utility>

#include <iostream>

int main(int argc, char** argv) {
    using namespace ferro;
    CLI::App app{"ferro-surface: fluid surface meshes from particle files (Yu & Turk anisotropic kernels on OpenVDB)\n"
                 "  ferro-surface particles.ply --out surface.ply\n"
                 "  ferro-surface 'frames/particles_{:04}.ply' --frames 0:90 --out 'meshes/surface_{:04}.ply'"};
    SurfaceRun run;
    std::string scenePath, frames, method, format;
    std::vector<std::string> overrides;
    double voxelSize = -1, kernelRadius = -1, adaptivity = -1;
    int smoothing = -1, threads = 0;
    bool printInputs = false;
    auto* input = app.add_option("particles", run.input, "particle file (PLY), or a pattern with {:04} or %04d for --frames");
    auto* out = app.add_option("--out,-o", run.output, "mesh file, or a pattern for --frames (PLY; others via --format)");
    addSceneInputsFlag(app, printInputs, {input, out});
    app.add_option("--frames", frames, "frame range A:B (inclusive): INPUT and --out are patterns")->type_name("A:B");
    app.add_option("--scene", scenePath, "scene file: parameters from its [surface] section");
    addSetOption(app, overrides, "override a scene key: --set surface.voxel_size=5e-4");
    app.add_option("--method", method, "anisotropic (Yu-Turk, default), isotropic (fastest, bumpier), or openvdb (ParticlesToLevelSet spheres, roughest)")
        ->check(CLI::IsMember({"anisotropic", "isotropic", "openvdb"}));
    app.add_option("--voxel-size", voxelSize, "voxel edge [m] (default: half the particle spacing)")
        ->check(CLI::PositiveNumber);
    app.add_option("--kernel-radius", kernelRadius, "kernel support radius in particle spacings (default 1.5; the Yu-Turk neighbourhood scales with it)")
        ->check(CLI::PositiveNumber);
    app.add_option("--adaptivity", adaptivity, "mesh adaptivity 0..1 (default 0: uniform triangles)")
        ->check(CLI::Range(0.0, 1.0));
    app.add_option("--smoothing", smoothing, "Gaussian smoothing passes over the density (default 0)")
        ->check(CLI::Range(0, 100));
    app.add_option("--format", format, "mesh format: ply (default), obj, stl, ... (any assimp export id)");
    app.add_option("--vdb", run.vdb, "also write the level set (grid surface) and, when the particle file has velocities, the fluid velocity (grid v) as an OpenVDB .vdb file (a pattern for --frames)");
    addThreadsOption(app, threads, "worker threads (default 0 = all cores)");
    app.add_flag("--quiet,-q", run.quiet, "no progress lines");
    const std::vector<ErrorExit> errors = {
        exitOn<SceneError>(kExitBadInput),
        // Internal failures (OpenVDB, out of memory, ...): their messages may span lines.
        exitOn<std::exception>(kExitFailure, "", oneLine),
    };
    return runCommandLine("ferro-surface", app, argc, argv, errors, [&]() -> int {
        if (!frames.empty()) {
            const FrameRange range = frameRangeArgument("--frames", frames);
            run.firstFrame = range.first;
            run.lastFrame = range.last;
            run.range = true;
        }
        SurfaceParams params;
        if (!scenePath.empty()) {
            SceneDocument doc = SceneDocument::load(scenePath, overrides);
            doc.checkSections(shotSceneSections());
            if (printInputs)
                return printSceneInputs(doc, [](const SceneDocument& d) { parseSurfaceParams(d); });
            params = parseSurfaceParams(doc);
        } else if (printInputs) {
            throw CLI::ValidationError("--print-scene-inputs", "needs --scene");
        } else if (!overrides.empty()) {
            params = parseSurfaceParams(SceneDocument::parse("", "--set", overrides));
        }
        if (!method.empty())
            params.method = method == "anisotropic" ? SurfaceMethod::Anisotropic
                          : method == "isotropic"   ? SurfaceMethod::Isotropic
                                                    : SurfaceMethod::OpenVdb;
        // CLI11's number checks let NaN through (every comparison with it is false).
        for (const auto& [name, v] : {std::pair<const char*, double>{"--voxel-size", voxelSize},
                                      {"--kernel-radius", kernelRadius}, {"--adaptivity", adaptivity}})
            if (!std::isfinite(v)) throw BadInputError(std::string(name) + ": must be a finite number");
        if (voxelSize > 0) params.voxelSize = voxelSize;
        if (kernelRadius > 0) {
            // Yu-Turk's neighbourhood follows the kernel (r_i = 2h, our default 2.75 / 1.5).
            params.neighborRadius *= kernelRadius / params.kernelRadius;
            params.kernelRadius = kernelRadius;
        }
        if (adaptivity >= 0) params.adaptivity = adaptivity;
        if (smoothing >= 0) params.smoothing = smoothing;
        if (!format.empty()) params.format = format;

        const auto limit = limitThreads(threads);
        return runSurface(run, params, std::cerr, std::cerr);
    });
}

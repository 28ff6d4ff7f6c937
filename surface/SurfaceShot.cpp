// One particle file -> one mesh file, and frame ranges (see SurfaceShot.hpp).
#include "surface/SurfaceShot.hpp"

#include "sim/core/FrameRunner.hpp"

#include "sim/core/ParticleFile.hpp"
#include "sim/core/ExitCodes.hpp"

#include <tbb/parallel_for.h>
#include <tbb/tick_count.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <sstream>

namespace ferro {

SurfaceStats meshParticleFile(const std::string& inPath, const std::string& outPath, const SurfaceParams& params,
                              const std::string& vdbPath) {
    // A missing or unopenable file is an I/O problem (wrong path, frame not simulated yet,
    // permissions); a file that opens but is unreadable as particles is bad input.
    refuseToOverwriteInputs("--out", outPath, {inPath});
    refuseToOverwriteInputs("--vdb", vdbPath, {inPath, outPath});
    requireReadable(inPath);
    ParticleTable table;
    std::vector<Vec3> x, v;
    double spacing = 0;
    try {
        table = readParticleFile(inPath);
        x = table.vec3("x", "y", "z");
        // The mesh carries the fluid's motion when the file has it (every ferro-sim file does).
        if (table.column("vx") >= 0 && table.column("vy") >= 0 && table.column("vz") >= 0) v = table.vec3("vx", "vy", "vz");
        spacing = table.commentNumber("spacing", 0.0);
    } catch (const ParticleFileError& e) {
        const std::string what = e.what();
        const bool prefixed = what.compare(0, inPath.size(), inPath) == 0;
        throw SurfaceRunError(kExitBadInput, prefixed ? what : inPath + ": " + what);
    }
    if (!(spacing > 0) || !std::isfinite(spacing)) spacing = params.spacing;
    else if (params.spacing > 0) spacing = params.spacing; // the scene overrides the file

    SurfaceStats stats;
    TriangleMesh mesh;
    try {
        mesh = extractSurface(x, params, spacing, vdbPath, &stats, v.empty() ? nullptr : &v);
    } catch (const SurfaceError& e) {
        throw SurfaceRunError(kExitBadInput, inPath + ": " + e.what());
    }
    mesh.comments = table.comments;
    setComment(mesh, "surface_method", methodName(params.method));
    std::ostringstream sp;
    sp << std::setprecision(9) << stats.spacing;
    setComment(mesh, "spacing", sp.str());
    writeMesh(outPath, mesh, params.format); // MeshFileError: a StageError with its code
    return stats;
}

int runSurface(const SurfaceRun& run, const SurfaceParams& params, std::ostream& log, std::ostream& err) {
    std::mutex io;
    auto one = [&](const std::string& in, const std::string& out, const std::string& vdb, const std::string& label) {
        const tbb::tick_count t0 = tbb::tick_count::now();
        const SurfaceStats st = meshParticleFile(in, out, params, vdb);
        if (!run.quiet) {
            std::lock_guard<std::mutex> lock(io);
            log << "ferro-surface: " << label << out << " (" << std::fixed << std::setprecision(2)
                << (tbb::tick_count::now() - t0).seconds() << " s, voxel " << std::setprecision(3)
                << st.voxelSize * 1e3 << " mm)\n";
        }
        if (st.emptyFromParticles) {
            // Not an error (a frame may hold no fluid), but never silent.
            std::lock_guard<std::mutex> lock(io);
            err << "ferro-surface: warning: " << out << ": " << st.particles
                << " particles gave an empty mesh (check the voxel size and iso level)\n";
        }
    };
    try {
        if (!run.range) {
            one(run.input, run.output, run.vdb, "");
            return kExitOk;
        }
        if (run.firstFrame < 0 || run.lastFrame < run.firstFrame || run.lastFrame > kMaxFrame)
            throw BadInputError("--frames " + std::to_string(run.firstFrame) + ":" + std::to_string(run.lastFrame) +
                                ": need 0 <= FIRST <= LAST <= " + std::to_string(kMaxFrame));
        // Distinct outputs per frame, or every frame would overwrite the same file.
        runFrames({run.firstFrame, run.lastFrame}, {{"input", run.input}, {"--out", run.output}, {"--vdb", run.vdb}},
                  [&](int f) {
                      one(framePath(run.input, f), framePath(run.output, f),
                          run.vdb.empty() ? std::string() : framePath(run.vdb, f),
                          "frame " + std::to_string(f) + " -> ");
                  });
        return kExitOk;
    } catch (const StageError& e) {
        err << "ferro-surface: error: " << e.what() << "\n";
        return e.code();
    }
}

} // namespace ferro

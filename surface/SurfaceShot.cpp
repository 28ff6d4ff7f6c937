// One particle file -> one mesh file, and frame ranges (see SurfaceShot.hpp).
#include "surface/SurfaceShot.hpp"

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

namespace {

/// Empty if `path` opens for reading, else why not ("No such file or directory", ...).
std::string openProblem(const std::string& path) {
    std::ifstream probe(path, std::ios::binary);
    return probe ? std::string() : std::string(std::strerror(errno));
}

} // namespace

SurfaceStats meshParticleFile(const std::string& inPath, const std::string& outPath, const SurfaceParams& params,
                              const std::string& vdbPath) {
    // A missing or unopenable file is an I/O problem (wrong path, frame not simulated yet,
    // permissions); a file that opens but is unreadable as particles is bad input.
    const std::string problem = openProblem(inPath);
    if (!problem.empty()) throw SurfaceRunError(kExitIoError, inPath + ": cannot open: " + problem);
    ParticleTable table;
    std::vector<Vec3> x;
    double spacing = 0;
    try {
        table = readParticleFile(inPath);
        x = table.vec3("x", "y", "z");
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
        mesh = extractSurface(x, params, spacing, vdbPath, &stats);
    } catch (const SurfaceError& e) {
        throw SurfaceRunError(kExitBadInput, inPath + ": " + e.what());
    } catch (const MeshFileError& e) {
        throw SurfaceRunError(kExitIoError, e.what());
    }
    mesh.comments = table.comments;
    setComment(mesh, "surface_method", methodName(params.method));
    std::ostringstream sp;
    sp << std::setprecision(9) << stats.spacing;
    setComment(mesh, "spacing", sp.str());
    try {
        writeMesh(outPath, mesh, params.format);
    } catch (const MeshFileError& e) {
        throw SurfaceRunError(kExitIoError, e.what());
    }
    return stats;
}

int runSurface(const SurfaceRun& run, const SurfaceParams& params, std::ostream& log, std::ostream& err) {
    std::mutex io;
    auto one = [&](const std::string& in, const std::string& out, const std::string& vdb, const std::string& label) {
        const tbb::tick_count t0 = tbb::tick_count::now();
        try {
            const SurfaceStats st = meshParticleFile(in, out, params, vdb);
            if (!run.quiet) {
                std::lock_guard<std::mutex> lock(io);
                log << "ferro-surface: " << label << out << " (" << std::fixed << std::setprecision(2)
                    << (tbb::tick_count::now() - t0).seconds() << " s, voxel " << std::setprecision(3)
                    << st.voxelSize * 1e3 << " mm)\n";
            }
            return int(kExitOk);
        } catch (const SurfaceRunError& e) {
            std::lock_guard<std::mutex> lock(io);
            err << "ferro-surface: error: " << e.what() << "\n";
            return e.code();
        }
    };
    if (!run.range) return one(run.input, run.output, run.vdb, "");

    if (run.firstFrame < 0 || run.lastFrame < run.firstFrame || run.lastFrame > kMaxFrame) {
        err << "ferro-surface: error: --frames " << run.firstFrame << ":" << run.lastFrame
            << ": need 0 <= FIRST <= LAST <= " << kMaxFrame << "\n";
        return kExitBadInput;
    }
    // Distinct outputs per frame, or every frame would overwrite the same file.
    for (const std::string* pattern : {&run.input, &run.output, &run.vdb}) {
        if (pattern->empty()) continue;
        if (run.firstFrame != run.lastFrame && framePath(*pattern, run.firstFrame) == framePath(*pattern, run.lastFrame)) {
            err << "ferro-surface: error: '" << *pattern << "' has no frame placeholder such as {:04} or %04d\n";
            return kExitBadInput;
        }
    }
    const int64_t count = int64_t(run.lastFrame) - int64_t(run.firstFrame) + 1;
    std::vector<int> codes(size_t(count), kExitOk);
    // Frames in flight at once; each also runs its own steps in parallel.
    tbb::parallel_for(int64_t(0), count, [&](int64_t k) {
        const int f = int(run.firstFrame + k);
        codes[size_t(k)] = one(framePath(run.input, f), framePath(run.output, f),
                               run.vdb.empty() ? std::string() : framePath(run.vdb, f),
                               "frame " + std::to_string(f) + " -> ");
    });
    for (int c : codes)
        if (c != kExitOk) return c;
    return kExitOk;
}

} // namespace ferro

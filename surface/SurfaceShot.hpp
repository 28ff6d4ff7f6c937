#pragma once
// ferro-surface's work on files: one particle file -> one mesh file, or a range of frames
// with several in flight. main.cpp only parses arguments and calls this.
#include "sim/core/StageErrors.hpp"
#include "surface/SurfaceExtractor.hpp"
#include "surface/SurfaceParams.hpp"

#include <ostream>
#include <string>

namespace ferro {

/// What to mesh and where to put it. For a range, `input`, `output` and `vdb` are patterns
/// with a frame placeholder ({:04} or %04d, see framePath).
struct SurfaceRun {
    std::string input;
    std::string output;
    std::string vdb;        ///< also write the level set as .vdb here (empty = no)
    bool range = false;
    int firstFrame = 0, lastFrame = 0;
    bool quiet = false;     ///< no per-frame lines on the log stream
};

/// A frame that failed, with the exit code it maps to (kExitBadInput, kExitIoError, ...).
using SurfaceRunError = StageError;

/// Meshes one particle file into `outPath` (format from params.format or the extension).
/// The particle file's `comment` lines (frame, time, spacing, magnets, ...) are copied into
/// the mesh, plus `surface_method`. The spacing is the particle file's `comment spacing`,
/// else params.spacing, else estimated. Throws SurfaceRunError with a one-line reason.
SurfaceStats meshParticleFile(const std::string& inPath, const std::string& outPath,
                              const SurfaceParams& params, const std::string& vdbPath = {});

/// Runs a single file or a frame range (frames in parallel, TBB). Writes one line per frame
/// to `log` unless quiet. A range follows every stage's policy (sim/core/FrameRunner.hpp):
/// no new frame starts after one failed. Returns kExitOk, or writes "ferro-surface: error:
/// <reason>" for the lowest failed frame to `err` and returns its exit code.
int runSurface(const SurfaceRun& run, const SurfaceParams& params, std::ostream& log, std::ostream& err);

} // namespace ferro

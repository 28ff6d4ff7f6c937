#pragma once
// Runs a shot: simulates frame by frame and writes one particle file per frame.
#include "sim/scene/SimParams.hpp"

#include <string>

namespace ferro {

struct RunOptions {
    std::string outDir;        ///< where particles_NNNN.ply go
    int maxFrames = -1;        ///< stop after this frame index (previews, tests); -1 = whole shot
    bool resume = false;       ///< continue from the last complete frame in outDir
    bool overwrite = false;    ///< discard frames already in outDir and start over
    bool quiet = false;        ///< no progress lines on stderr
    std::string fingerprint;   ///< scene fingerprint written to each file and checked on resume
    /// Also accepted on resume: the whole scene document's hash, which frames written before
    /// 2026-12-07 carry (empty = none).
    std::string legacyFingerprint;
    /// [shot] preroll: where the settled state is cached (empty = outDir/preroll.ply), and
    /// the hash of the sections it depends on (empty = `fingerprint`, the whole scene).
    std::string prerollCache;
    std::string prerollFingerprint;
};

/// Name of frame `frame`'s particle file in `dir`.
std::string particleFramePath(const std::string& dir, int frame);

/// Simulates `scene` into `opt.outDir`. Throws SceneError (bad input, exit 2),
/// SimulationError (blow-up, exit 3; frames written so far stay), ParticleFileError (I/O).
void runShot(const SimScene& scene, const RunOptions& opt);

} // namespace ferro

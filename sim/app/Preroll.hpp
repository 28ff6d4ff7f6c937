#pragma once
// The pre-roll ([shot] preroll): the scene's initial fill simulated towards rest before
// frame 0, with every magnet held as it is at t = 0, so a shot starts from a settled fluid
// (no ring wave from a released block). The settled state is cached in a particle file and
// reused while everything it depends on stays the same.
#include "sim/app/FrameTable.hpp"
#include "sim/scene/SimParams.hpp"

#include <string>
#include <vector>

namespace ferro {

struct PrerollOptions {
    std::string cachePath;    ///< particle file holding the settled state (read if valid, else written)
    /// Hash of the scene sections the pre-roll depends on ([fluid], [container], [sim],
    /// [magnetization]); the magnets at t = 0 and the [shot] pre-roll keys are added to it.
    std::string sceneFingerprint;
    size_t particles = 0;     ///< the scene's particle count: a cache holding another count is stale
    bool quiet = false;       ///< no progress lines on stderr
};

/// The settled initial state.
struct PrerollState {
    FrameState state;         ///< in id order
    double simulated = 0;     ///< pre-roll time simulated [s]
    double rmsSpeed = 0;      ///< RMS particle speed at its end [m/s]
    bool fromCache = false;   ///< read from opt.cachePath rather than simulated
};

/// The scene with every magnet frozen at its t = 0 state (no keys).
SimScene frozenAtStart(const SimScene& scene);

/// The full cache key: opt.sceneFingerprint, the magnets at t = 0 and the pre-roll keys.
std::string prerollFingerprint(const SimScene& scene, const PrerollOptions& opt);

/// Returns the settled state: from the cache when its `preroll_fingerprint` comment equals
/// prerollFingerprint() and it holds opt.particles particles, else by simulating
/// frozenAtStart(scene) for scene.shot.preroll seconds or until the RMS speed is below
/// scene.shot.prerollRestSpeed (checked every 1/fps once t >= sqrt(2 H / g), H the height of
/// the container's walls or of the fluid without one), then writing the cache atomically.
/// Requires scene.shot.preroll > 0. Throws SimulationError (blow-up) or ParticleFileError
/// (the cache cannot be written).
PrerollState settleInitialState(const SimScene& scene, const PrerollOptions& opt);

} // namespace ferro

#pragma once
// The shot's description as the scene file gives it: [shot], [fluid], [container], [sim]
// here and the magnets' sections through sim/magnets/MagnetScene. Errors are SceneErrors
// naming file, line and key (exit 2).
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimParams.hpp"

#include <string>
#include <vector>

namespace ferro {

/// Every top-level section of the scene file format, whichever stage reads it.
const std::vector<std::string>& shotSceneSections();

/// What a stage needs of the shot: Simulate reads all of [shot]; PerFrame (a stage that
/// works on frames already simulated) reads only shot.fps, so that lengthening the shot or
/// its pre-roll does not re-run that stage on frames whose particles did not change (its
/// make stamp lists only the keys it reads: see --print-scene-inputs).
enum class SceneUse { Simulate, PerFrame };

/// Parses the sections ferro-sim owns ([shot], [fluid], [container], [sim]) plus the
/// magnets, and validates them (positive densities and spacings, ...).
SimScene parseSimScene(const SceneDocument& doc, SceneUse use = SceneUse::Simulate);
/// shot.fps alone (validated as parseSimScene does), for a stage that needs only the frame rate.
double parseShotFps(const SceneDocument& doc);
/// load + parseSimScene.
SimScene loadSimScene(const std::string& path, const std::vector<std::string>& overrides = {});
/// SolverParams::solverKeys from the text of [sim] keys ("max_density_error = 2e-5"), for a
/// scene made in code (tests, benchmarks); `name` stands in for the file in messages.
std::shared_ptr<const SceneDocument> solverKeysFromText(const std::string& keys, const std::string& name = "(code)");

} // namespace ferro

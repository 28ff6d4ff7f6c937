#pragma once
// The shot's description as the scene file gives it: [shot], [fluid], [container], [sim]
// here and the magnets' sections through sim/magnetics/MagnetScene. Errors are SceneErrors
// naming file, line and key (exit 2).
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimParams.hpp"

#include <string>
#include <vector>

namespace ferro {

/// Every top-level section of the scene file format, whichever stage reads it.
const std::vector<std::string>& shotSceneSections();

/// Parses the sections ferro-sim owns ([shot], [fluid], [container], [sim]) plus the
/// magnets, and validates them (positive densities and spacings, ...).
SimScene parseSimScene(const SceneDocument& doc);
/// load + parseSimScene.
SimScene loadSimScene(const std::string& path, const std::vector<std::string>& overrides = {});

} // namespace ferro

#pragma once
// The scene sections of the magnets: [[magnets]] (with their [[magnets.keys]]) and
// [magnetization]. Every stage that evaluates the field (ferro-sim, ferro-spikes,
// ferro-pov) reads them through these two functions; errors are SceneErrors naming
// file, line and key (exit 2).
#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/magnets/MagnetizationParams.hpp"

#include <vector>

namespace ferro {

std::vector<MagnetTrack> parseMagnets(const SceneDocument& doc);
MagnetizationParams parseMagnetization(const SceneDocument& doc);

} // namespace ferro

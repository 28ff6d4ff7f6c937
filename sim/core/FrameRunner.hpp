#pragma once
// One frame runner for every stage after ferro-sim: runs a piece of work per frame of a
// range, several frames in flight (TBB; the caller limits threads), with one failure policy:
//   - a range over several frames needs a frame placeholder ({:04} or %04d) in every
//     pattern, checked before any work (BadInputError naming the option);
//   - frames start in ascending order, several at a time;
//   - at the first failing frame no new frame starts; frames already in flight finish;
//     the error of the lowest failing frame is rethrown; every file written stays.
// So `--frames 0:9999999` over three existing frames stops at the first missing one with
// one line, and make or a farm can re-run just what failed.
#include "sim/core/ParticleFile.hpp" // FrameRange, framePath

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace ferro {

/// A file-name pattern and the option it came from, for the placeholder check's message.
struct FramePattern {
    std::string option;   ///< "--out", "input", ...
    std::string pattern;  ///< may be empty (an optional input that is not given)
};

/// Throws BadInputError("<option>: a frame range needs a {:04} or %04d placeholder (got
/// '<pattern>')") if `range` spans several frames and a non-empty pattern names one file.
void checkFramePatterns(const FrameRange& range, const std::vector<FramePattern>& patterns);

/// checkFramePatterns, then work(frame) for every frame of `range` under the policy above.
void runFrames(const FrameRange& range, const std::vector<FramePattern>& patterns,
               const std::function<void(int frame)>& work);

} // namespace ferro

#pragma once
// Files in, files out: one frame (surface mesh + particle file + scene -> spiky mesh) and
// frame ranges with several frames in flight. This is what ferro-spikes' main calls.
#include "sim/core/StageErrors.hpp"
#include "sim/solids/SolidParams.hpp"
#include "spikes/SpikeMapper.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace ferro {

class SceneDocument;

/// Input that cannot be used (malformed mesh or particle file, inconsistent options): exit 2.
using SpikeInputError = BadInputError;
/// An input file (surface mesh or particle file) that is missing or cannot be opened: exit 4.
using SpikeIoError = InputMissingError;

/// What a run takes from the scene file, parsed and validated once.
struct SpikeScene {
    SpikeParams params;                ///< [spikes]
    SpikeFluid fluid;                  ///< [fluid], [container], [sim].gravity, [magnetization]
    std::vector<MagnetTrack> magnets;  ///< [[magnets]]: fallback when files carry no magnet state
    double fps = 30.0;                 ///< [shot].fps: frame -> time when files carry no time
    std::vector<SolidParams> solids;   ///< [[solids]]: their field and their films (SpikeSolids.hpp)
    std::string path;                  ///< the scene file, for messages
};

/// Parses the scene (the whole sim scene must be valid, plus [spikes]). Throws SceneError.
SpikeScene parseSpikeScene(const SceneDocument& doc);

/// Reads one frame's input. `particlePath` may be empty (the law then gives |M| at the field).
/// Magnets, in order of preference: the particle file's header, the mesh's header, the scene's
/// tracks at the frame's time (header `time`, else `frame` / fps, else `frameHint` / fps).
/// The magnetic law likewise: headers (susceptibility, saturation), else [magnetization].
/// With [[solids]], their magnetization is solved in the magnets' and particles' field
/// (addSolids).
/// An empty surface is valid (a frame without fluid). Throws SpikeIoError when a file cannot
/// be opened, SpikeInputError when one is unusable (malformed, non-finite positions, ...).
SpikeInput loadSpikeInput(const SpikeScene& scene, const std::string& surfacePath,
                          const std::string& particlePath, int frameHint = -1);

/// The same frame `interval` [s] earlier, for the spikes' own velocity (addSpikes' `earlier`):
/// the magnets moved back along the scene's tracks, their past with them, the particles' |M|
/// scaled by the law at the magnets' field then and now; the same surface and particle
/// positions. False (and `earlier` untouched) when the magnets do not come from the scene's
/// tracks, or when the field was still over the interval and the spikes' whole past: then the
/// spikes stand still on the surface.
bool earlierSpikeInput(const SpikeScene& scene, const SpikeInput& in, double interval, SpikeInput& earlier);

/// One frame: load, addSpikes (with the spikes' own motion when the surface has velocities), write `outPath` atomically (PLY with normals and the input's
/// comments plus spike_tips, spike_spacing, critical_magnetization). With [spikes]
/// response_time > 0 and a `historyPattern` (the particle files' pattern, {:04} / %04d), the
/// tips are carried by the flow of the earlier frames' files (SurfaceFlow.hpp); the frame's
/// number is frameHint, else its time times the shot's fps. Throws SpikeIoError or
/// SpikeInputError as loadSpikeInput, MeshFileError when the output cannot be written, and
/// std::runtime_error (never writing) if the result had a non-finite vertex.
SpikeResult spikeFrame(const SpikeScene& scene, const std::string& surfacePath, const std::string& particlePath,
                       const std::string& outPath, int frameHint = -1, const std::string& historyPattern = {});

/// A frame range: patterns with a {:04} / %04d placeholder, frames first..last inclusive
/// (the particle pattern is also the flow's history for response_time),
/// several in flight (TBB; the caller limits threads). Progress lines on stderr unless quiet.
/// The policy of every stage's frame range (sim/core/FrameRunner.hpp): stops at the first
/// failing frame and rethrows its error (frames already written are kept).
void spikeFrames(const SpikeScene& scene, const std::string& surfacePattern, const std::string& particlePattern,
                 const std::string& outPattern, int first, int last, bool quiet);

} // namespace ferro

// Fuzz target: the particle PLY reader (readParticleFile), as every stage reads particles,
// and the magnets in its header (readMagnetComments).
//
// Input encoding: the input is the file's bytes, read from a scratch file `input.ply`.
//
// The documented error is ParticleFileError (one line naming the file). A table it returns
// is consistent: as many values as rows times columns, one name per column; its comments
// read as numbers or fail with a ParticleFileError, and its magnets hold what the scene parser
// promises of a magnet (strength within the kind's maximum, lengths and radii > 0).
#include "tests/fuzz/FuzzTarget.hpp"

#include "sim/core/ParticleFile.hpp"
#include "sim/magnets/MagnetKinds.hpp"
#include "sim/magnets/MagnetState.hpp"

#include <cmath>

using namespace ferro;
using ferro::fuzz::finding;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = fuzz::writeInput("input.ply", data, size);
    ParticleTable t;
    try {
        t = readParticleFile(path);
    } catch (const ParticleFileError& e) {
        fuzz::requireOneLine(e);
        return 0;
    }
    if (t.columns() == 0 ? !t.values.empty() : t.values.size() != t.rows() * t.columns())
        finding(std::to_string(t.values.size()) + " values for " + std::to_string(t.columns()) + " columns");
    for (const std::string& name : t.names) (void)t.column(name);
    // The stages read frame, time and spacing comments as numbers: a malformed one is a
    // ParticleFileError too.
    for (const auto& [key, value] : t.comments) {
        try {
            (void)t.commentNumber(key, 0.0);
        } catch (const ParticleFileError& e) {
            fuzz::requireOneLine(e);
        }
    }
    // The magnets of the header (ferro-spikes and ferro-pov evaluate their field): what the
    // scene parser promises for a magnet holds for them too.
    try {
        for (const Magnet& m : readMagnetComments(t)) {
            const MagnetKindInfo& info = magnetKindInfo(m.kind);
            if (!m.position.allFinite() || !m.direction.allFinite()) finding("non-finite magnet position or direction");
            if (!(std::abs(m.strength) <= info.maxStrength)) finding("magnet strength beyond the kind's maximum");
            if (info.usesLength && !(m.length > 0)) finding("bar magnet without length");
            if (info.usesRadius && !(m.radius > 0)) finding("loop magnet without radius");
            if (!(m.softening >= 0 && std::isfinite(m.softening))) finding("bad magnet softening");
        }
    } catch (const ParticleFileError& e) {
        fuzz::requireOneLine(e);
    }
    return 0;
}

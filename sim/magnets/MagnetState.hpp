#pragma once
// The magnets' state at a frame, carried in the particle file's header so later stages
// (ferro-spikes, ferro-pov) evaluate the same field at any point without the simulation.
//
// One `comment magnet ...` line per magnet, in scene order, after `comment magnet_count N`:
//     comment magnet_count 1
//     comment magnet dipole px py pz dx dy dz strength length radius softening
// (a coil's line adds its turns as an 11th number; the other kinds' lines never change)
// kind is a name of sim/magnets/MagnetKinds.hpp (dipole, bar, ...); position [m], unit direction, strength in the kind's unit
// (moment A m^2, pole strength A m, field A/m, current A, current a turn A), length, radius, softening [m];
// numbers are printed with 9 significant digits (float-exact, more than enough for a field).
// The fluid's magnetic law is carried as `comment susceptibility chi0` and
// `comment saturation Ms` (A/m, 0 = linear).
#include "sim/magnets/MagnetField.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/magnets/MagnetizationParams.hpp"

#include <string>
#include <vector>

namespace ferro {

/// The kind's name in the table of sim/magnets/MagnetKinds.hpp.
const char* magnetKindName(Magnet::Kind kind);

/// Appends magnet_count and one magnet comment per magnet to `table` (and the fluid's
/// magnetic law when `law` is given).
void writeMagnetComments(ParticleTable& table, const std::vector<Magnet>& magnets,
                         const MagnetizationParams* law = nullptr);

/// The magnets of a particle file's header. Throws ParticleFileError on a malformed line
/// (including values the scene would refuse: a strength beyond the kind's maxStrength, a bar
/// without length, a loop without radius, a negative softening) or a count that does not
/// match; a file without `magnet_count` has no magnets.
std::vector<Magnet> readMagnetComments(const ParticleTable& table);

} // namespace ferro

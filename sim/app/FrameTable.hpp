#pragma once
// One frame of the simulation as the particle file every later stage reads.
#include "sim/core/ParticleFile.hpp"

#include <string>

namespace ferro {

class FluidSimulation;

/// The particle table of `sim`'s current state as frame `frame`: x y z vx vy vz density
/// pressure hx hy hz mx my mz in id order, and the header comments (frame, time, fps,
/// spacing, support_radius, particle_mass, rest_density, scene, scene_fingerprint, the magnets
/// at the current time with the fluid's law, magnetization_interval).
ParticleTable frameTable(const FluidSimulation& sim, int frame, const std::string& fingerprint);

} // namespace ferro

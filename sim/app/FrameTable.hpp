#pragma once
// One frame of the simulation as the particle file every later stage reads.
#include "sim/core/ParticleFile.hpp"
#include "sim/magnetics/DemagnetizationCurve.hpp"

#include <optional>

#include <string>
#include <vector>

namespace ferro {

class FluidSimulation;

/// The particle table of `sim`'s current state as frame `frame`: x y z vx vy vz density
/// pressure hx hy hz mx my mz in id order, and the header comments (frame, time, fps,
/// spacing, support_radius, particle_mass, rest_density, scene, scene_fingerprint, the magnets
/// at the current time with the fluid's law, magnetization_interval, and magnetization_curve:
/// the free-surface curve's hLo hHi c0 c1 c2 C and the time of its fit, when there is one).
/// `compact`: only what the later stages read (x y z vx vy vz density mx my mz), v, density
/// and M quantized to 16 bits, and `comment cache compact` (not a frame to resume from).
ParticleTable frameTable(const FluidSimulation& sim, int frame, const std::string& fingerprint, bool compact = false);

/// The simulation state a particle file holds, in id order: what FluidSimulation::setState
/// takes to continue from it (resume, the pre-roll cache).
struct FrameState {
    std::vector<Vec3> x, v;   ///< positions [m], velocities [m/s]
    std::vector<Real> p;      ///< pressures [Pa] (the pressure solver's, which DFSPH warm-starts from); empty without the column
    std::vector<Vec3> H, M;   ///< field, magnetization [A/m] (the solve's warm start); empty without
    /// The force's free-surface curve and the time [s] of its last fit (FluidMagnetics::CurveMemory).
    std::optional<DemagnetizationCurve::SurfaceFit> curve;
    double curveTime = 0;
};
/// Reads a FrameState from a frameTable. Throws ParticleFileError without x y z vx vy vz, or
/// with a magnetization_curve comment that is not seven finite numbers.
FrameState frameState(const ParticleTable& t);

} // namespace ferro

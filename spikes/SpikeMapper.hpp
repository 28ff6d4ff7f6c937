#pragma once
// The paper's spike synthesis (section 4.3, eqs. 12-16, Fig. 7) on one frame's surface mesh.
//
// What addSpikes does, in order:
//  1. Field and magnetization on the surface: H = magnets (at the frame's time) + the
//     magnetized particles' own field when available; |M| from the particles around a surface
//     point (Shepard average of their M), or from the fluid's law at H when there are none.
//     Surface closer than wall_margin to the container is wetted wall and never spiky.
//  2. One pattern per magnet whose field makes the fluid supercritical (|M| > M_c, eq. 16) where
//     the magnet's axis meets the free surface: that point is the pattern origin x0 (for a
//     uniform field: the line along the field through [spikes] origin, else through the
//     container's centre). The lattice axes come from a fixed world direction projected into
//     the tangent plane at x0, so a still magnet gives the same tips in every frame.
//  3. Tips, as in Fig. 7: from x0 trace the six axis directions along the surface with step
//     l (eq. 15, or the physical spacing), each next tip where the field line through the
//     stepped point meets the surface; tips between two axes interpolate the two n-th axis
//     tips and are again dropped along the field line onto the surface.
//     On a surface with solids (SpikeFluid::solids: a coat on a sculpture), the tips are
//     traced in rows along the surface, no two closer than 0.8 l, a line ends where the
//     normal has turned 75 degrees from the origin's, and every part of the
//     supercritical surface no pattern reached seeds a pattern of its own (at its vertex
//     nearest its centroid; SpikePattern::region). Surface within film_thickness of a solid (its bare wall,
//     a wetting film) is never spiky, and the field includes the solids' (SpikeSolids.hpp).
//  4. Refinement: CGAL isotropic remeshing of the supercritical region to l / resolution.
//  5. Displacement: each vertex gets the lattice coordinates of eq. 13 from its nearby tips
//     (each tip's local lattice basis, from its neighbours' positions, maps the vertex to
//     coordinates; a smooth partition of unity over tips blends them, exact on a regular
//     lattice), height C0 F (C0 = beta |H|, eq. 14) times the fades (magnetization from M_c,
//     distance from the wetted wall, coverage of the traced lattice), along the local field
//     direction (tilted at most max_tilt from the normal). Several patterns blend by field
//     dominance |H_i|^2 / sum |H_j|^2, so they meet without cracks.
//  6. Volume: a normal offset over the spiky region, weighted like the heights, restores the
//     input's enclosed volume (the paper's first listed limitation).
#include "spikes/SpikeTypes.hpp"
#include "spikes/SpikeParams.hpp"

namespace ferro {

/// The field H [A/m] at x: the magnets plus, when given, the magnetized particles and solids.
Vec3d totalFieldAt(const SpikeInput& input, const Vec3d& x);

/// Synthesizes the spikes on input.surface. Deterministic: the same input gives the same
/// output. Below M_c everywhere (or with spikes disabled) the surface is returned unchanged.
/// When the input surface has vertex velocities, so does the result (mesh.velocities [m/s]):
/// the surface's, except that along the surface the spikes move as their tips do (they stand
/// where the field lays them out, not where the fluid flows), and their displacement grows
/// with their tips' amplitude. How the tips moved comes from `earlier`: the same surface and
/// particles with the magnets and their past `interval` [s] before (earlierSpikeInput), each
/// tip found again there by its lattice coordinates; null = the tips stand still (a field
/// still over the spikes' whole past).
SpikeResult addSpikes(const SpikeInput& input, const SpikeParams& params, const SpikeInput* earlier = nullptr,
                      double interval = 0);

} // namespace ferro

#pragma once
// The hexagonal lattice of spike tips on the fluid surface (paper section 4.3, Fig. 7, eq. 15):
// the free surface the tips are dropped onto, one pattern's tips, and the tracing that lays
// them out from the pattern's origin. Phase 3 of addSpikes. Internal to ferro_spikes.
#include "sim/spatial/HashGrid.hpp"
#include "spikes/SpikeTypes.hpp"
#include "spikes/SurfaceFields.hpp"
#include "spikes/SurfaceGeometry.hpp"

#include <Eigen/Dense>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace ferro {

/// The free part of the input surface: triangles with at least one vertex that is not wetted
/// wall. References; the mesh, its ray caster and the per-vertex wetted flags outlive it.
struct FreeSurface {
    const TriangleMesh& mesh;
    const SurfaceRayCaster& caster;
    const std::vector<char>& wetted; ///< per vertex of mesh: 1 = wetted wall
    /// A triangle of mesh is free unless all three of its vertices are wetted wall.
    bool isFree(const std::array<uint32_t, 3>& t) const { return !(wetted[t[0]] && wetted[t[1]] && wetted[t[2]]); }
};

/// Where the line through p along d (non-zero) meets the free surface nearest to p, if no
/// farther than maxDistance [m] from p: the point `hit` [m] and that triangle's unit normal.
/// `aheadOnTie`: of two free hits within 1 % of the same distance, the one ahead along d (a
/// line through the middle of a symmetric coat meets it twice; the nearest would go to
/// whichever side the surface's noise favours); else the first found.
bool nearestFreeHit(const FreeSurface& surface, const Vec3d& p, const Vec3d& d, double maxDistance, Vec3d& hit,
                    Vec3d& normal, bool aheadOnTie = false);

/// Eq. 14's C0 [m] for the field |H| = field [A/m] and tip spacing [m]: beta |H|, capped at
/// maxAspect spacing / 3 (the tip stands 3 C0 above the mean level), times heightGain.
double spikeAmplitude(const SpikeParams& P, double field, double spacing);

/// One tip of a pattern on the undisplaced surface.
struct Tip {
    int i, j;                              // lattice coordinates (eq. 13's e1, e2 steps from x0)
    Vec3d position, normal;                // on the surface [m], outward unit normal there
    Eigen::Matrix<double, 2, 3> toLattice; // maps an offset from the tip [m] to lattice coordinates
    double amplitude = 0;                  // C0 at the tip (eq. 14, capped) [m]
    Vec3d direction{0, 0, 1};              // growth direction at the tip
    double ownership = 1;                  // 0..1: how much of a spike it keeps where patterns meet
                                           // (settleSeams; 1 with a single pattern)
    double presence = 1;                   // 0..1: 0 = left out by SpikeParams::defects (its profile,
                                           // troughs included, is scaled by it in the displacement)
};

/// One magnet's pattern: its public description (origin x0, normal, first axis e1, spacing l),
/// its tips (after traceLattice) and a grid over their positions with cell l.
struct Pattern {
    SpikePattern info;
    std::vector<Tip> tips;
    std::unique_ptr<HashGrid> grid;
};

/// Phase 3, the tips of Fig. 7 for a pattern whose info (origin x0 and normal n0 on the free
/// surface, axis e1, spacing l [m]) is set. From x0 the six lattice axes are traced along the
/// surface with step l (eq. 15: each step along the tangent plane at the previous tip, that of
/// the surface's mean normal within l / 2, the next tip where the field line through the
/// stepped point meets the surface, within 0.75 l), for at
/// most ceil(diagonal / l) + 1 rings [diagonal in m] and until two tips in a row are subcritical
/// (|M| <= Mc [A/m]); tips between two axes interpolate the two n-th axis tips (Fig. 7c) and
/// are dropped the same way. With P.jitter each tip then moves by its fixed random offset (up
/// to jitter l, from seed, magnet and (i, j)) and is dropped again. Fills pat.tips (each with its lattice map from its neighbours'
/// positions, its amplitude spikeAmplitude times the magnetization fade and its presence under
/// P.defects, eq. 14, and its growth direction), pat.info.rings and pat.grid.
/// On a surface with solids (SpikeFluid::solids) the tips are traced in rows, as a morphing
/// lattice's are, no tip stands closer than 0.8 l to one of this pattern traced before it (a
/// coat's lattice meets itself round the back of a solid) or to a tip of the `earlier`
/// patterns, and a line ends where the surface's normal has turned more than 75 degrees from
/// the origin's.
void traceLattice(Pattern& pat, const FreeSurface& surface, const SurfaceFields& fields, const SpikeParams& P,
                  double Mc, double diagonal, const std::vector<Pattern>& earlier = {});

/// Phase 3b, where two or more patterns meet (issue 14's "two magnets brought together"):
/// each tip's ownership (0..1, Tip::ownership) starts from its pattern's share of the summed
/// fieldDominance at the tip (none under 0.2, full over 0.4); two tips of different patterns
/// closer than 0.6 of the smaller spacing merge, fully from 0.3 l in: the tip with the smaller
/// share moves onto the other and gives up its ownership; at a tie both meet at the midpoint
/// with half each. The displacement then blends the tips of all patterns with these weights
/// (one partition of unity over the union of tips) instead of blending whole patterns point by
/// point, which averaged two unrelated lattices into low bumps along the seam. Only tip
/// positions and the field enter, so merges move smoothly with the magnets. With one pattern
/// nothing changes (ownership 1).
void settleSeams(std::vector<Pattern>& patterns, const std::vector<Magnet>& magnets);

// ---- Which pattern owns a point: the blend of several patterns by field dominance ----------

/// Unnormalized weight of a pattern whose magnet makes field H [A/m] here: |H|^6. Patterns blend
/// only where their magnets' fields are within ~30 % of each other (a dipole's |H| ~ r^-3 makes
/// that a band a few millimetres wide); elsewhere one pattern is in sole charge, so a spike is
/// not skewed by a faint copy of the other lattice. The band is smooth: no cracks.
inline double fieldDominance(const Vec3d& H)
{
    const double h2 = H.squaredNorm();
    return h2 * h2 * h2;
}

/// Each pattern's fieldDominance at a point (from its own magnet's field) and their sum over
/// the magnets (a magnet with several patterns, SpikePattern::region, counted once).
struct Dominance {
    std::vector<double> dominance; ///< per pattern
    double sum = 0;
    /// The pattern's share of the blend (equal shares where no magnet has a field).
    double share(size_t p) const { return sum > 0 ? dominance[p] / sum : 1.0 / double(dominance.size()); }
};

/// The patterns' field dominance at x [m]; Pattern::info.magnet indexes `magnets`.
Dominance patternDominance(const std::vector<Pattern>& patterns, const std::vector<Magnet>& magnets, const Vec3d& x);

} // namespace ferro

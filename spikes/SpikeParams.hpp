#pragma once
// [spikes]: parameters of the procedural Rosensweig spikes (paper section 4.3), SI units.
// Every default here is the documented default of the scene key in examples/annotated.toml.
#include "sim/core/Types.hpp"

#include <cstdint>
#include <vector>

namespace ferro {

class SceneDocument;

/// One [[spikes.keys]] entry: the look's animated values at `time` [s]. A key that leaves a
/// value out holds the [spikes] section's value there.
struct SpikeKey {
    double time = 0;        ///< [s]
    double heightGain = 1;  ///< SpikeParams::heightGain at this time
    double sharpness = 1;   ///< SpikeParams::sharpness
    double jitter = 0;      ///< SpikeParams::jitter
    double defects = 0;     ///< SpikeParams::defects
    double squareness = 0;  ///< SpikeParams::squareness
};

struct SpikeParams {
    /// The planform of a magnet's spikes (eq. 12 with three or two wave vectors).
    enum class Lattice {
        Hexagon, ///< eq. 13: three wave vectors 120 degrees apart, tips on a triangular lattice (the paper)
        Square   ///< two wave vectors 90 degrees apart, tips on a square lattice (squareProfile)
    };
    /// How the tip spacing l (distance between neighbouring tips) is chosen.
    enum class Spacing {
        Paper,    ///< eq. 15: l = alpha / |H(x0)|, so tips crowd as the field grows
        Physical, ///< the critical wavelength lambda_c = 2 pi sqrt(sigma / (delta_rho g)) of
                  ///< linear theory: k = 2 pi / lambda_c, tips 2/sqrt(3) lambda_c apart on a
                  ///< hexagon (eq. 13), lambda_c on a square, lambda_c / sin theta between
                  ///< (squareness)
        Growth    ///< the wavenumber of fastest growth at the strongest |M| of the growth time
                  ///< (fastestGrowingWavenumber: a deep layer of the scene's viscosity): k_c at
                  ///< onset, growing with the field as measured after field jumps (Reimann et
                  ///< al. 2000); the same tip distances for that k. For a field switched on
                  ///< fast: under an approaching magnet the lattice re-lays and tips pop
                  ///< (measured with ferro-tips, docs/physics/spikes.md)
    };
    bool enabled = true;             ///< false: copy the surface unchanged
    Spacing spacing = Spacing::Paper;
    Lattice lattice = Lattice::Hexagon; ///< every magnet's planform unless magnetLattice says otherwise
    std::vector<std::pair<int, Lattice>> magnetLattice; ///< [[spikes.magnets]]: (magnet index, planform)
    /// The planform of magnet m's spikes (m indexes the scene's [[magnets]]).
    Lattice latticeOf(int m) const
    {
        for (const auto& [magnet, l] : magnetLattice)
            if (magnet == m) return l;
        return lattice;
    }
    /// How far magnet m's lattice has morphed from hexagons (0) to squares (1): a magnet's own
    /// [[spikes.magnets]] pattern pins it (0 or 1); otherwise `squareness`, or 1 where [spikes]
    /// sets pattern = "square".
    double squarenessOf(int m) const
    {
        for (const auto& [magnet, l] : magnetLattice)
            if (magnet == m) return l == Lattice::Square ? 1.0 : 0.0;
        return lattice == Lattice::Square ? 1.0 : squareness;
    }
    /// The tips are traced in rows (traceLattice) for every frame of a shot whose hexagons
    /// morph: `squareness` above 0 in [spikes] or any key. Then the tips a frame lays out do
    /// not switch between the ring trace (the paper's hexagons) and the rows mid-shot.
    bool morphs() const
    {
        if (squareness > 0) return true;
        for (const SpikeKey& k : keys)
            if (k.squareness > 0) return true;
        return false;
    }
    double alpha = 60.0;             ///< eq. 15 constant [A]: l = 1 cm at |H(x0)| = 6 kA/m
    double beta = 1.5e-7;            ///< eq. 14 constant [m per A/m]: C0 = beta |H|; tips stand 3 C0
                                     ///< above the mean level, troughs 1.5 C0 below
    double minSpacing = 2e-3;        ///< clamp of l [m] (a huge field cannot shrink spikes to nothing)
    double maxSpacing = 0.05;        ///< clamp of l [m]
    double maxAspect = 1.0;          ///< cap of tip height (3 C0) over tip spacing l, > 0
    double sharpness = 1.0;          ///< profile exponent p >= 1: 1 = eq. 13 exactly; larger p narrows
                                     ///< the spikes into cones over flat troughs (same tips, same spacing).
                                     ///< 1 is the shape measured near onset (Gollwitzer et al. 2007).
                                     ///< Measurements: docs/physics/spikes.md, "Against the full
                                     ///< force: the periodic layer"
    // The art director's keys (keyframable with [[spikes.keys]]). They change the look, not
    // where the physics puts the pattern: the defaults leave the paper's spikes untouched.
    double heightGain = 1.0;         ///< factor on every tip's height (after the aspect cap), >= 0,
                                     ///< at most 4; 0 = a flat, heaped surface
    double jitter = 0.0;             ///< tip positions moved along the surface by up to this fraction
                                     ///< of the tip spacing l, in [0, 0.35]; each tip's offset is a
                                     ///< fixed function of seed, magnet and lattice coordinates, so a
                                     ///< tip keeps its offset from frame to frame as the pattern moves
    double defects = 0.0;            ///< missing spikes, in [0, 0.9]: about defects - 0.025 of the tips
                                     ///< are left out (each sinks over a band of 0.05 below its
                                     ///< threshold, so raising it over keys sinks tips one by one);
                                     ///< which tips is fixed by seed and lattice coordinates
    double squareness = 0.0;         ///< the hexagons' morph into squares, in [0, 1]: eq. 12's lattice
                                     ///< with e2 at 60 + 30 squareness degrees from e1 and the profile
                                     ///< blended from eq. 13 to the square one; 0 = the paper's
                                     ///< hexagons, 1 = `pattern = "square"`. Keyed over frames, each tip
                                     ///< keeps its lattice coordinates and slides to its new site, so
                                     ///< none is born or dies inside the pattern. The field at which a
                                     ///< real layer turns to squares could not be read here (Abou et
                                     ///< al. 2001, Gollwitzer et al. 2006): the art director keys it
    uint32_t seed = 0;               ///< the irregularity's random seed (jitter and defects)
    std::vector<SpikeKey> keys;      ///< [[spikes.keys]] in time order; empty = the values above
    /// How a spike's height follows the supercriticality eps = |M| / M_c - 1.
    enum class HeightCurve {
        Fade,        ///< smooth ramp from 0 at M_c to full at (1 + magnetizationFade) M_c, no
                     ///< hysteresis (the look since the paper's port)
        Bifurcation  ///< the hexagons' subcritical amplitude equation (SpikeBifurcation): a jump
                     ///< at M_c, full at (1 + magnetizationFade) M_c, and spikes that stand
                     ///< persist down to lowerThreshold M_c as the field falls
    };
    HeightCurve heightCurve = HeightCurve::Fade;
    double lowerThreshold = 0.9;     ///< M_s / M_c of the bifurcation curve, in [0.5, 1]: spikes that
                                     ///< stand collapse below M_s; 1 = no hysteresis (then no jump).
                                     ///< 0.9: where the full-force layer's pattern sank as the
                                     ///< field was held lower (docs/physics/magnetization.md,
                                     ///< "The field swept up and down (csf)")
    double magnetizationFade = 0.25; ///< height ramps from 0 at |M| = M_c to full at (1 + fade) M_c
    /// Spikes follow the field with this time constant [s], >= 0: a spike's height is the
    /// heights its |M| gave over the past, averaged with weight exp(-(t - t') / growthTime),
    /// the past taken from the scene's magnet tracks (so a frame is still made alone, in any
    /// order). A field that jumps on grows spikes over a few frames instead of popping them in;
    /// one that goes lets them sink; a still field gives the instantaneous pattern. 0 = the
    /// paper (instantaneous). 0.2 s, not 0.1: at 0.1 s the new outer rings of a growing
    /// pattern are born too tall in one frame. Measurements: docs/physics/spikes.md, the
    /// opening section (the demo's approach).
    double growthTime = 0.2;
    /// Tips carried by the fluid's flow (SurfaceFlow.hpp) [s], in [0, 5]: each tip moves with
    /// the surface velocity under it and the field pulls it back to its lattice site with this
    /// time constant, dX/dt = u + s (L - X) / response_time, s in [0, 1] the height the field
    /// supports there (a strong field pins its tips; where it has fallen away they drift with
    /// the fluid as they sink). A sloshing layer rocks the spikes with it; a magnet that
    /// slides faster than the pattern follows leaves them trailing.
    /// 0 = the paper: the tips are laid out anew from the field in every frame. Needs the
    /// particle files of the frames 4 response times back (ferro-spikes reads them from the
    /// --particles pattern; a single frame without a pattern is laid out anew).
    double responseTime = 0.0;
    double wallMargin = 0.0;         ///< surface closer than this to a container wall is wetted wall,
                                     ///< never spiky [m]; 0 = 1.5 particle spacings (2 mm if unknown)
    double filmThickness = 0.0;      ///< surface closer than this to a solid ([[solids]]) is its bare
                                     ///< wall or a wetting film on it, never spiky [m]; 0 = 3 particle
                                     ///< spacings (4 mm if unknown)
    double wallFade = 0.0;           ///< height ramps in over this distance from the wetted wall [m];
                                     ///< 0 = one tip spacing l. Not l / 2: a ramp narrower than a
                                     ///< spike tilts its peak off the lattice point, and the outer
                                     ///< tips of a still magnet's pattern wander with the mesh's
                                     ///< wall distance (docs/physics/spikes.md, the opening section)
    double resolution = 16.0;        ///< target mesh edges per tip spacing in the spiky area, >= 3
    int remeshIterations = 3;        ///< CGAL isotropic remeshing iterations, >= 0 (0 = no refinement)
    double ambientDensity = 1.2;     ///< density of the medium above the fluid (air) [kg/m^3]
    bool hasOrigin = false;          ///< origin given: the pattern of a uniform field is anchored on
    Vec3d origin{0, 0, 0};           ///< the line through it along the field [m]
    double orientation = 0.0;        ///< lattice axis angle from the world x axis [deg]
    double maxTilt = 60.0;           ///< spikes grow along the field, but at most this far from the
                                     ///< surface normal [deg] (a grazing field would fold the surface)
    bool particleField = true;       ///< add the magnetized particles' own field to the magnets'
    bool conserveVolume = true;      ///< restore the enclosed volume after displacement
};

/// The parameters at time t [s]: heightGain, sharpness, jitter, defects and squareness interpolated between
/// the keys (monotone cubic, sim/core/Keyframes.hpp: never past a key's value), the rest as
/// given. No keys: a copy of p.
SpikeParams spikeParamsAt(const SpikeParams& p, double t);

/// Parses the scene's [spikes] section (absent = defaults); unknown keys are errors (SceneError).
SpikeParams parseSpikeParams(const SceneDocument& doc);

} // namespace ferro

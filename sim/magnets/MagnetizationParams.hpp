#pragma once
// [magnetization]: the fluid's magnetic law and how its self-consistent field is solved.
// Filled from the scene file by sim/magnets/MagnetScene.cpp.

namespace ferro {

/// [magnetization]: how the fluid magnetizes (paper eq. 5 with Langevin saturation) and how
/// the particle-particle field is computed. The solvers trade speed for accuracy:
/// External ignores the particles' own field (exact as chi0 -> 0, O(N)), Direct sums all
/// pairs (O(N^2), the reference), Tree is a Barnes-Hut octree (O(N log N), error set by the
/// opening angle), Auto picks the cheapest whose estimated error is under `tolerance`.
struct MagnetizationParams {
    enum class Solver { External, Direct, Tree, Auto };
    double susceptibility = 0.0;   ///< initial susceptibility chi0 (dimensionless); 0 = not magnetic
    double saturation = 0.0;       ///< saturation magnetization Ms [A/m]; 0 = never saturates (M = chi0 H)
    Solver solver = Solver::Auto;
    double tolerance = 0.01;       ///< accepted relative RMS field error (auto's choice, re-solve trigger)
    double openingAngle = 0.5;     ///< Barnes-Hut opening angle theta (cell size / distance)
    int resolveEvery = 0;          ///< re-solve every K steps; 0 = when the field may have changed by > tolerance
    int maxIterations = 50;        ///< self-consistency iterations per solve (direct, tree)
    /// Particle model: each particle's moment V M is spread over a Wendland C2 kernel of
    /// support radius smoothing * V^(1/3) (dimensionless, in particle spacings; see
    /// sim/particlefield/DipoleTree.hpp). Default 2.5, a little over the SPH support of 2
    /// spacings: measured on balls of ~10 spacings' radius, 2.0 leaves 1.3-1.4x the
    /// per-particle scatter on a jittered set, 3.0-3.5 add 1.5-3 % to the interior field's
    /// error at chi0 = 10 on a settled SPH ball (a wider surface layer). 0 = the older
    /// model: uniformly magnetized spheres of volume V, exact on a cubic lattice only.
    double smoothing = 2.5;
    /// Local consistency correction of the smoothed model (sim/particlefield/DipoleTree.hpp):
    /// each interior particle's field operator is corrected so that a uniform magnetization
    /// gives a field without particle-scale noise. Costs three field evaluations per solve.
    /// Measured on a ball jittered by 0.2 spacings at chi0 = 10: 11.5 % RMS field error per
    /// particle without it, 2.2 % with it; on a ball cut from a settled SPH tank 0.93 -> 0.86 %.
    /// With it the surface term also sets in smoothly (deficits 0.05-0.15, DipoleTree.hpp).
    /// OFF by default: what it removes is the scatter of artificially jittered particles, not
    /// of settled SPH states. Measured 2026-12-02 (ferro_magnetics_tests "[.figures]", direct):
    /// on a ball cut from a settled SPH tank the uncorrected field is already within 0.14-0.93 %
    /// RMS, worst particle 0.5-2.6 %, for chi0 0.5-10 (corrected 0.11-0.86 %, 0.4-2.9 %); only
    /// the 0.2-spacing jittered ball needs it (uncorrected 1.5-11.5 % RMS). Its cost
    /// (bench-magnetization --threads 1 --sizes 40960 --direct-max 40960 --local-correction
    /// true|false, two runs each): a cold tree solve 2.6-3.6 s instead of 1.4-1.6 s, a warm
    /// one 2.2-2.7 s instead of 0.73-0.75 s, and the tree's lead over the direct solve (which
    /// the correction also makes dearer, 40-44 s against 36 s) 12-15x instead of 20-22x. On the resting pool of
    /// tests/sim/sph/test_FluidMagnetics.cpp (2 s, examples/ferrohydrostatic_pool.toml; each
    /// curve fit blended into the last at 0.2, without which it did not rest under WCSPH) the
    /// Bernoulli deviation was 13.3 / 43.7 / 35.6 % of the centre rise (chi0 0.5 DFSPH, 1.5
    /// DFSPH, 1.5 WCSPH) against 13.1 / 38.8 / 43.5 % without it, RMS speed 0.55 / 0.76 /
    /// 0.62 mm/s against 0.42-0.49 (both with the curve fitted to the floor and walls, as it
    /// was then; measured 2026-12-02). Off is exactly the model before it (surface term from any
    /// deficit).
    bool localCorrection = false;
    /// How the magnetic force enters the fluid (sim/sph/FluidMagnetics.hpp has the
    /// derivation):
    ///   Body     (default) a body force per particle from the magnets' field gradient,
    ///            mu0 M_f(|H_magnets|) grad |H_magnets|: with `external` M_f is the Langevin
    ///            law, with a self-consistent solver a curve fitted at each solve so that its
    ///            potential at free-surface samples is their F(H) + M_n^2 / 2,
    ///            normal traction included (sim/magnetics/DemagnetizationCurve.hpp).
    ///   Surface  (experimental) the Kelvin force density mu0 (M . grad) H of the TOTAL
    ///            field, which for M parallel to H is the gradient of the magnetic pressure
    ///            mu0 F(H), taken into the pressure: what remains is a pressure on the free
    ///            surface, C - mu0 (F(H) + M_n^2 / 2) (Rosensweig's ferrohydrostatic
    ///            boundary condition, normal traction included).
    enum class Force { Surface, Body };
    Force force = Force::Body;
    bool enabled() const { return susceptibility > 0; }
};

} // namespace ferro

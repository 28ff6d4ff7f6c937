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
    /// Particle model: each moment V M spread over a Wendland C2 kernel of support radius
    /// smoothing * V^(1/3) (in particle spacings); 0 = uniformly magnetized spheres, exact on a
    /// cubic lattice only (docs/physics/magnetization.md: why 2.5).
    double smoothing = 2.5;
    /// Local consistency correction (sim/particlefield/DipoleTree.hpp): removes the
    /// particle-scale noise of the field operator for three field evaluations a solve. Off:
    /// settled SPH states do not need it, and it makes the solve dearer. Measurements:
    /// docs/physics/magnetization.md, "local_correction (default off)".
    bool localCorrection = false;
    /// How the magnetic force enters the fluid (sim/sph/FluidMagnetics.hpp): Body (default),
    /// the magnets' field gradient times a magnetization curve fitted to the free surface;
    /// Surface (experimental), the total field's Kelvin force taken into the pressure, leaving
    /// Rosensweig's surface condition (docs/physics/magnetization.md).
    enum class Force { Surface, Body };
    Force force = Force::Body;
    bool enabled() const { return susceptibility > 0; }
};

} // namespace ferro

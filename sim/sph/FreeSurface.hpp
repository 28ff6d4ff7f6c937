#pragma once
// The free surface as the particles see it, shared by the forces that act on it (the magnetic
// surface traction, magnetization.force = "surface", and the "csf" surface tension):
// - the colour gradient grad c_i = V sum_j grad W_ij + sum_b V_b grad W_ib (fluid and walls,
//   so a wetted wall is no surface), pointing into the fluid, ~ 1 / spacing at a surface;
// - the exposure in [0, 1]: 1 when no fluid particle stands in the cone of half-angle ~40
//   degrees along the outward direction -grad c within 1.5 spacings, falling smoothly to 0 as
//   one enters it (the scan region of Marrone et al. 2010). In a moving, disordered fluid
//   |grad c| alone does not tell the surface from the inside (docs/physics/magnetization.md,
//   "The surface force");
// - FlatSurface: the scales of a flat cubic lattice surface (the seed's lattice, support 2
//   spacings) that turn these into a surface weight and spread a traction over the layers.
// A traction t [Pa] (a pressure on the surface, positive inward) is applied as the
// acceleration a_i = w_i t grad c_i / (rho0 kappa), w_i = FlatSurface::weight(|grad c_i|) times
// the exposure, kappa = FlatSurface::layerFactor(): the column sum of w V |grad c| / s^2, so
// that the accelerations of a flat surface's column of particles add up to t per unit area.
#include "sim/core/Types.hpp"
#include "sim/spatial/NeighborSearch.hpp"
#include "sim/spatial/PeriodicDomain.hpp"
#include "sim/sph/Kernel.hpp"

#include <vector>

namespace ferro {

/// The particles and their neighbours (current sorted order).
struct FreeSurfaceInput {
    const std::vector<Vec3>& x;
    const NeighborLists& fluid;
    const NeighborLists& boundary;
    const std::vector<Vec3>& bx;
    const std::vector<Real>& bVolume;
    const CubicSplineKernel& kernel;
    const PeriodicDomain& periodic;
    Real volume;  ///< particle volume V = m / rho0 [m^3]
    Real spacing; ///< particle spacing [m]
};

/// grad c_i [1/m] of every particle (see above).
void computeColorGradient(const FreeSurfaceInput& in, std::vector<Vec3>& gradC);
/// The exposure in [0, 1] of every particle, from its colour gradient (see above).
void computeExposure(const FreeSurfaceInput& in, const std::vector<Vec3>& gradC, std::vector<Real>& exposure);

/// A flat cubic lattice surface's scales, for a particle spacing s [m] and volume V [m^3].
class FlatSurface {
public:
    FlatSurface(double spacing, double volume);
    /// Surface weight in [0, 1] from |grad c|: 0 below a quarter of the flat surface's, 1 from
    /// half of it on (smoothstep between). Not the fill rho / rho0: the pressure solver
    /// squeezes the top layer until its deficient density sum reaches rest density.
    double weight(double gradient) const;
    /// kappa = sum over the lattice's layers of weight V |grad c| / s^2 (dimensionless).
    double layerFactor() const { return layerFactor_; }

private:
    double gradient_ = 0, layerFactor_ = 1;
};

} // namespace ferro

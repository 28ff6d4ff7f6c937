#pragma once
// The fluid's density field as a sum of (anisotropic) kernels, after Yu & Turk (2010),
// "Reconstructing surfaces of particle-based fluids using anisotropic kernels".
//
// Each particle j contributes  V * sigma * det(G_j) * P(|G_j (x - c_j)|)  with
// P(u) = (1 - u^2)^3 for u < 1 and sigma = 315 / (64 pi), so every kernel integrates to the
// particle's volume V = spacing^3 whatever its shape: inside the fluid the field is 1, outside
// 0. For an isotropic kernel G = I / h. For Yu-Turk, G_j = (1/h) R Sigma~^-1 R^T from the
// weighted covariance of the particle's neighbours, and c_j is the smoothed centre.
//
// No OpenVDB here: the rasterizer (SurfaceExtractor.cpp) consumes these kernels.
#include "surface/SurfaceParams.hpp"

#include "sim/core/Types.hpp"

#include <cstdint>
#include <vector>

namespace ferro {

/// One kernel in the form the rasterizer wants: W(x) = amplitude * (1 - q)^3 for
/// q = (x - c)^T M (x - c) < 1, else 0. M = G^T G.
struct DensityKernel {
    Vec3 centre;
    float m[6];       ///< M as xx, xy, xz, yy, yz, zz [1/m^2]
    float amplitude;  ///< V sigma det(G) [1]
    Vec3 halfExtent;  ///< half size of the kernel's axis-aligned bounding box [m]
    uint32_t source = 0; ///< the particle it stands for (index into buildKernels' positions)

    float q(const Vec3& x) const {
        const Vec3 d = x - centre;
        return m[0] * d.x() * d.x() + m[3] * d.y() * d.y() + m[5] * d.z() * d.z() +
               2 * (m[1] * d.x() * d.y() + m[2] * d.x() * d.z() + m[4] * d.y() * d.z());
    }
    float value(const Vec3& x) const {
        const float t = 1 - q(x);
        return t > 0 ? amplitude * t * t * t : 0.0f;
    }
};

/// Kernels for `positions` with the given method (Anisotropic or Isotropic) and a resolved
/// `spacing` > 0. Parallel (TBB). The output order is unspecified (spatially sorted).
std::vector<DensityKernel> buildKernels(const std::vector<Vec3>& positions, const SurfaceParams& params,
                                        double spacing);

/// The density at `x` by a direct sum over all kernels (reference and calibration only).
double densityAt(const std::vector<DensityKernel>& kernels, const Vec3& x);

/// k_s [1/m^2] that gives a particle in a full simple-cubic neighbourhood unit kernel axes:
/// the inverse of the weighted variance of its neighbours' offsets within neighborRadius.
double derivedKs(const SurfaceParams& params, double spacing);

/// Where the mesh goes: the density's iso level and an outward offset [m] of the extracted
/// surface along its normals.
struct SurfaceCalibration {
    double isoLevel = 0.5;
    double offset = 0.0;
};

/// Calibrates the offset on a flat sheet of particles (simple cubic lattice): the sheet's
/// surface belongs half a spacing beyond its outer layer, i.e. where the sheet keeps its
/// volume. Yu-Turk's centre smoothing pulls the outer layer inward by about half a spacing
/// (a systematic shift, the same for every flat stretch of surface); the offset puts the
/// surface back. Zero when params.volumeCorrection is off.
SurfaceCalibration calibrateSurface(const SurfaceParams& params, double spacing);

/// A particle spacing [m] from the positions: the median nearest-neighbour distance of a
/// sample. 0 for fewer than two distinct positions.
double estimateSpacing(const std::vector<Vec3>& positions);

} // namespace ferro

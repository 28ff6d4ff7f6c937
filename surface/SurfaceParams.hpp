#pragma once
// Parameters of ferro-surface, from the scene's [surface] section or the command line.
//
// Lengths that scale with the particles (kernel and neighbourhood radii) are given in
// particle spacings, so one scene works for any resolution; the spacing itself comes from
// the particle file's `comment spacing` unless set here.
#include <string>

namespace ferro {

class SceneDocument;

enum class SurfaceMethod {
    Anisotropic, ///< Yu & Turk (2010) anisotropic kernels: flat where the fluid is flat
    Isotropic,   ///< the same density field with plain spherical kernels: faster, bumpier
    OpenVdb,     ///< OpenVDB's ParticlesToLevelSet (union of spheres): fastest, bumpiest
};

struct SurfaceParams {
    SurfaceMethod method = SurfaceMethod::Anisotropic;
    /// Particle spacing [m]; 0 = the particle file's `comment spacing`, else estimated from
    /// the nearest-neighbour distances.
    double spacing = 0;
    /// Edge of a voxel of the density grid [m]; 0 = spacing / 2.
    double voxelSize = 0;
    /// Support radius h of the isotropic kernel, in spacings. An anisotropic kernel reaches
    /// h * sigma_k along its axis k (sigma = 1 inside the fluid).
    double kernelRadius = 1.5;
    /// Yu-Turk neighbourhood radius r_i for the covariance and the centre smoothing, in
    /// spacings (Yu-Turk: about twice the kernel radius).
    double neighborRadius = 2.75;
    /// Largest ratio of the largest to the smallest kernel axis (Yu-Turk k_r).
    double kr = 4.0;
    /// Scale of the covariance's eigenvalues [1/m^2] (Yu-Turk k_s); 0 = derived so that a
    /// particle with a full neighbourhood gets the isotropic kernel (unit axes).
    double ks = 0.0;
    /// Axis scale of particles with fewer than nEps neighbours (Yu-Turk k_n).
    double kn = 0.5;
    int nEps = 25;
    /// Kernel centre smoothing towards the neighbourhood's weighted mean (Yu-Turk lambda), 0..1.
    double lambda = 0.9;
    /// Density (1 = fluid at rest) at which the surface lies.
    double isoLevel = 0.5;
    /// Move the surface along its normals so that a flat sheet of particles keeps its volume
    /// (its surface half a spacing beyond the outer layer; calibrated per method).
    bool volumeCorrection = true;
    /// volumeToMesh adaptivity, 0 (uniform triangles) .. 1 (fewest triangles).
    double adaptivity = 0.0;
    /// Gaussian smoothing passes over the density grid before meshing (0 = none).
    int smoothing = 0;
    /// Mesh file format (assimp export id or extension: "ply", "obj", "stl", ...); empty = from
    /// the output file's extension.
    std::string format;
};

/// Reads the [surface] section of `doc` on top of `defaults`; rejects unknown keys and
/// out-of-range values with a SceneError naming file, line and key.
SurfaceParams parseSurfaceParams(const SceneDocument& doc, const SurfaceParams& defaults = {});

const char* methodName(SurfaceMethod m);

} // namespace ferro

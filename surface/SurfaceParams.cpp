// [surface] section of a scene file (see SurfaceParams.hpp).
#include "surface/SurfaceParams.hpp"

#include "sim/core/SceneDocument.hpp"

namespace ferro {

const char* methodName(SurfaceMethod m) {
    switch (m) {
    case SurfaceMethod::Anisotropic: return "anisotropic";
    case SurfaceMethod::Isotropic: return "isotropic";
    case SurfaceMethod::OpenVdb: return "openvdb";
    }
    return "?";
}

SurfaceParams parseSurfaceParams(const SceneDocument& doc, const SurfaceParams& defaults) {
    SurfaceParams p = defaults;
    TableReader r = doc.section("surface");
    const std::string method =
        r.choice("method", {"anisotropic", "isotropic", "openvdb"}, methodName(defaults.method));
    p.method = method == "anisotropic" ? SurfaceMethod::Anisotropic
             : method == "isotropic"   ? SurfaceMethod::Isotropic
                                       : SurfaceMethod::OpenVdb;
    p.spacing = r.nonNegative("spacing", p.spacing);
    p.voxelSize = r.nonNegative("voxel_size", p.voxelSize);
    p.kernelRadius = r.positive("kernel_radius", p.kernelRadius);
    p.neighborRadius = r.positive("neighbor_radius", p.neighborRadius);
    p.kr = r.number("k_r", p.kr);
    if (!(p.kr >= 1)) r.fail("k_r", "must be >= 1");
    p.ks = r.nonNegative("k_s", p.ks);
    p.kn = r.positive("k_n", p.kn);
    p.nEps = r.integerInRange("n_eps", p.nEps, 0, 100000);
    p.lambda = r.numberInRange("lambda", p.lambda, 0, 1);
    p.isoLevel = r.positive("iso_level", p.isoLevel);
    p.volumeCorrection = r.boolean("volume_correction", p.volumeCorrection);
    p.adaptivity = r.numberInRange("adaptivity", p.adaptivity, 0, 1);
    p.smoothing = r.integerInRange("smoothing", p.smoothing, 0, 100);
    p.format = r.string("format", p.format);
    r.finish();
    return p;
}

} // namespace ferro

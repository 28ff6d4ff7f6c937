#pragma once
// [render]: how ferro-pov frames and renders a shot. Plain struct, SI units, Ferro's z-up
// coordinates (the conversion to POV-Ray's y-up, left-handed frame happens on export, see
// PovExport.hpp). Every default here is the documented default of the scene key
// (examples/annotated.toml, [render]); the camera defaults frame examples/dish.toml's 10 cm
// dish at the origin from the front, slightly above.
#include "sim/core/Types.hpp"

namespace ferro {

class SceneDocument;

struct RenderParams {
    Vec3d cameraPosition{0.0, -0.16, 0.105};  ///< camera location [m]
    Vec3d cameraTarget{0.0, 0.0, 0.004};      ///< point the camera looks at [m]
    double cameraAngle = 40.0;                ///< horizontal field of view [deg], (0, 180)
    int width = 640;                          ///< image width [pixels], >= 1
    int height = 480;                         ///< image height [pixels], >= 1
    int quality = 9;                          ///< POV-Ray +Q, 0..11 (9 = everything but radiosity)
    bool antialias = true;                    ///< POV-Ray +A (adaptive supersampling)
    double antialiasThreshold = 0.3;          ///< +A threshold, > 0 (smaller = more samples)
    int antialiasDepth = 3;                   ///< +R, 1..9: sub-samples per pixel edge
    /// Soft-box lights of look.inc (area lights): an N x N grid of samples, 1..9 (adaptive, no
    /// jitter). Measured on frame 60 of the demo at 640x480: 2 renders in 0.56 of the time of
    /// 3 (8.4 vs 15.1 s) for RMSE 0.0096 against 3, the shadows of thin objects faintly stepped.
    int lightSamples = 3;
    /// Display size of magnets that have none of their own (point dipoles); bar magnets use
    /// their pole distance as length, loops their radius.
    double magnetLength = 0.02;               ///< [m], > 0
    double magnetRadius = 0.006;              ///< [m], > 0
};

/// Parses [render] (absent section = all defaults). Throws SceneError on a bad or unknown key.
RenderParams parseRenderParams(const SceneDocument& doc);
/// Only render.magnet_length and render.magnet_radius (the rest default, no unknown-key
/// check): what the per-frame magnet includes need. Throws SceneError on a bad value.
RenderParams parseRenderMagnetSizes(const SceneDocument& doc);

} // namespace ferro

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
    /// jitter). Fewer samples render faster, the shadows of thin objects faintly stepped.
    /// Measurements: docs/physics/demo-shot.md.
    int lightSamples = 3;
    /// Display size of magnets that have none of their own (point dipoles); bar magnets use
    /// their pole distance as length, loops their radius.
    double magnetLength = 0.02;               ///< [m], > 0
    double magnetRadius = 0.006;              ///< [m], > 0
    /// Motion blur: each frame the mean of this many sub-frame renders, the meshes moved along
    /// their vertex velocities across the shutter (blur.ini, average.ini); 0 or 1 = off, 0..64.
    int motionBlur = 0;
    /// The shutter's open time as a fraction of the frame interval (0.5: a 180-degree shutter),
    /// centred on the frame's time; (0, 1].
    double shutter = 0.5;
};

/// Parses [render] (absent section = all defaults). Throws SceneError on a bad or unknown key.
RenderParams parseRenderParams(const SceneDocument& doc);
/// Only what the per-frame includes need (the rest default, no unknown-key check): the
/// magnets' display sizes, and motion_blur (whether meshes carry their velocities). Throws
/// SceneError on a bad value.
RenderParams parseRenderFrameParams(const SceneDocument& doc);

} // namespace ferro

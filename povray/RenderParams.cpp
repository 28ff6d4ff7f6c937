#include "povray/RenderParams.hpp"

#include "sim/core/SceneDocument.hpp"

#include <climits>
#include <cmath>
#include <string>

namespace ferro {

namespace {

// The keys the per-frame includes read (PovExport's FramesOnly scene).
void readFrameKeys(const TableReader& r, RenderParams& p)
{
    p.magnetLength = r.positive("magnet_length", p.magnetLength);
    p.magnetRadius = r.positive("magnet_radius", p.magnetRadius);
    p.motionBlur = r.integerInRange("motion_blur", p.motionBlur, 0, 64);
}

} // namespace

RenderParams parseRenderFrameParams(const SceneDocument& doc)
{
    RenderParams p;
    readFrameKeys(doc.section("render"), p);
    return p;
}

RenderParams parseRenderParams(const SceneDocument& doc)
{
    TableReader r = doc.section("render");
    RenderParams p;
    p.cameraPosition = r.vec3("camera_position", p.cameraPosition);
    p.cameraTarget = r.vec3("camera_target", p.cameraTarget);
    const double distance = (p.cameraTarget - p.cameraPosition).norm();
    if (!(distance > 0))
        r.fail("camera_target", "must differ from render.camera_position");
    // Far enough apart to overflow (e.g. 1e308 and -1e308), the view direction would be nan.
    if (!std::isfinite(distance))
        r.fail("camera_target", "is too far from render.camera_position (the distance overflows a double)");
    // The image's up is +z (POV-Ray's sky), so the camera cannot look straight along z.
    const Vec3d view = (p.cameraTarget - p.cameraPosition).normalized();
    if (std::abs(view.z()) > 0.9999)
        r.fail("camera_target", "the camera must not look straight up or down (the image's up is +z)");
    p.cameraAngle = r.number("camera_angle", p.cameraAngle);
    if (!(p.cameraAngle > 0 && p.cameraAngle < 180))
        r.fail("camera_angle", "must be in (0, 180) degrees (got " + std::to_string(p.cameraAngle) + ")");
    p.width = r.integerInRange("width", p.width, 1, 65535);
    p.height = r.integerInRange("height", p.height, 1, 65535);
    p.quality = r.integerInRange("quality", p.quality, 0, 11);
    p.antialias = r.boolean("antialias", p.antialias);
    p.antialiasThreshold = r.positive("antialias_threshold", p.antialiasThreshold);
    p.antialiasDepth = r.integerInRange("antialias_depth", p.antialiasDepth, 1, 9);
    p.lightSamples = r.integerInRange("light_samples", p.lightSamples, 1, 9);
    readFrameKeys(r, p);
    p.shutter = r.positive("shutter", p.shutter);
    if (p.shutter > 1) r.fail("shutter", "must be in (0, 1]: a fraction of the frame interval (got " + std::to_string(p.shutter) + ")");
    r.finish();
    return p;
}

} // namespace ferro

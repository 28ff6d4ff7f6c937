// The shot files: what the scene says about the shot (ShotDescription), the master scene
// shot.pov, render.ini and shot.ini.
#include "povray/PovText.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/core/TriangleMesh.hpp"
#include "sim/magnets/MagnetScene.hpp"
#include "sim/scene/SimSceneFile.hpp"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace ferro {

namespace fs = std::filesystem;

ShotDescription describeShot(const SceneDocument& doc, int first, int last)
{
    const SimScene scene = parseSimScene(doc);
    ShotDescription shot;
    shot.render = parseRenderParams(doc);
    shot.container = scene.container;
    shot.fps = scene.shot.fps;
    shot.firstFrame = first >= 0 ? first : 0;
    shot.lastFrame = last >= 0 ? last : scene.shot.frameCount();
    if (shot.lastFrame < shot.firstFrame)
        shot.lastFrame = shot.firstFrame;

    // The set: the vessel if there is one, else the fluid's starting blocks.
    const ContainerParams& c = scene.container;
    double bottom = 0.0;
    if (c.type == ContainerParams::Type::Dish) {
        shot.setCenter = c.center;
        shot.setRadius = c.radius;
        bottom = c.center.z() - 0.002; // the look's dish has a floor 1.5 mm thick
    } else if (c.type == ContainerParams::Type::Box) {
        shot.setCenter = 0.5 * (c.min + c.max);
        shot.setCenter.z() = c.min.z();
        shot.setRadius = 0.5 * (c.max - c.min).head<2>().norm();
        bottom = c.min.z();
    } else {
        Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
        for (const FluidBlock& b : scene.fluid.blocks) {
            const bool box = b.shape == FluidBlock::Shape::Box;
            const Vec3d blo = box ? b.min : Vec3d(b.center - Vec3d(b.radius, b.radius, 0));
            const Vec3d bhi = box ? b.max : Vec3d(b.center + Vec3d(b.radius, b.radius, b.height));
            lo = lo.cwiseMin(blo);
            hi = hi.cwiseMax(bhi);
        }
        // A mesh vessel: the set spans it too, and the floor goes under it (fluid poured into
        // a cup ends below the block it was poured from).
        if (c.type == ContainerParams::Type::Mesh) {
            const TriangleMesh vessel = readMesh(c.meshFile);
            for (const Vec3& v : vessel.vertices) {
                const Vec3d p = c.meshScale * v.cast<double>() + c.meshTranslate;
                lo = lo.cwiseMin(p);
                hi = hi.cwiseMax(p);
            }
        }
        shot.setCenter = Vec3d(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), lo.z());
        shot.setRadius = std::max(0.5 * (hi - lo).head<2>().norm(), 1e-3);
        bottom = lo.z();
    }
    // The floor lies under the vessel and under every magnet at every frame of the shot, so a
    // magnet that approaches from below is seen under the dish instead of vanishing in the floor.
    double floor = bottom;
    const int frames = scene.shot.frameCount();
    for (const MagnetTrack& track : scene.magnets) {
        if (magnetKindInfo(track.base.kind).body == MagnetBody::None)
            continue;
        for (int f = 0; f <= frames; ++f) {
            const Magnet m = track.at(f / scene.shot.fps);
            const double len = magnetKindInfo(m.kind).usesLength ? m.length : shot.render.magnetLength;
            const double rad = magnetKindInfo(m.kind).usesRadius ? m.radius : shot.render.magnetRadius;
            const Vec3d d = m.direction.norm() > 0 ? Vec3d(m.direction.normalized()) : Vec3d(0, 0, 1);
            const double extent = 0.5 * len * std::fabs(d.z()) + rad * std::sqrt(std::max(0.0, 1 - d.z() * d.z()));
            floor = std::min(floor, m.position.z() - extent - 0.002);
        }
    }
    shot.floorLevel = floor;
    return shot;
}

std::string masterScene(const ShotDescription& shot)
{
    const RenderParams& r = shot.render;
    const ContainerParams& c = shot.container;
    std::ostringstream s;
    s << "// shot.pov: master scene of the shot, written by ferro-pov on every export.\n"
         "// Do not edit: your changes would be lost. The look (camera, lights, materials, dish,\n"
         "// floor, magnets) lives in look.inc, which ferro-pov never overwrites.\n"
         "//\n"
         "// Render: povray shot.ini (all frames), povray shot.ini +SF10 +EF20 (frames 10..20),\n"
         "//         povray render.ini Declare=FerroFrame=12 +Oframe.png (one frame, no animation).\n"
         "//\n"
         "// Coordinates: POV-Ray units are millimetres, y is up, left-handed. A Ferro point\n"
         "// (x, y, z) [m] (z up, right-handed) is <1000 x, 1000 z, 1000 y> here; swapping y and z\n"
         "// is the reflection that maps the right-handed frame onto POV-Ray's left-handed one.\n"
         "#version 3.7;\n\n"
         "// The frame: POV-Ray's animation frame_number unless given as Declare=FerroFrame=N.\n"
         "#ifndef (FerroFrame) #declare FerroFrame = frame_number; #end\n"
      << "#declare FerroFps = " << number(shot.fps) << ";\n"
      << "#declare FerroTime = FerroFrame / FerroFps;   // [s]\n"
      << "#declare FerroFirstFrame = " << shot.firstFrame << ";\n"
      << "#declare FerroLastFrame = " << shot.lastFrame << ";\n\n"
      << "// [render]\n"
      << "#declare FerroCameraLocation = " << vec(toPovPoint(r.cameraPosition)) << ";\n"
      << "#declare FerroCameraLookAt = " << vec(toPovPoint(r.cameraTarget)) << ";\n"
      << "#declare FerroCameraAngle = " << number(r.cameraAngle) << ";   // horizontal field of view [deg]\n"
      << "#declare FerroAspect = image_width / image_height;\n"
      << "#declare FerroLightSamples = " << r.lightSamples << ";   // area light grid N x N (look.inc's soft boxes)\n\n"
      << "// The set: its centre (on the vessel's floor) and radius, for lights and backdrop.\n"
      << "#declare FerroSetCenter = " << vec(toPovPoint(shot.setCenter)) << ";\n"
      << "#declare FerroSetRadius = " << number(shot.setRadius * kPovUnitsPerMetre) << ";\n"
      << "#declare FerroFloorLevel = " << number(shot.floorLevel * kPovUnitsPerMetre)
      << ";   // y of the floor: under the vessel and every magnet of the shot\n\n"
      << "// [container]\n";
    switch (c.type) {
    case ContainerParams::Type::Dish:
        s << "#declare FerroContainerType = \"dish\";\n"
          << "#declare FerroDishCenter = " << vec(toPovPoint(c.center)) << ";   // centre of the inner floor\n"
          << "#declare FerroDishRadius = " << number(c.radius * kPovUnitsPerMetre) << ";   // inner radius\n"
          << "#declare FerroDishHeight = " << number(c.height * kPovUnitsPerMetre) << ";   // wall height\n";
        break;
    case ContainerParams::Type::Box:
        s << "#declare FerroContainerType = \"box\";\n"
          << "#declare FerroBoxMin = " << vec(toPovPoint(c.min)) << ";\n"
          << "#declare FerroBoxMax = " << vec(toPovPoint(c.max)) << ";\n";
        break;
    case ContainerParams::Type::Mesh:
        s << "#declare FerroContainerType = \"mesh\";   // not drawn: model it in look.inc\n";
        break;
    case ContainerParams::Type::None:
        s << "#declare FerroContainerType = \"none\";\n";
        break;
    }
    if (r.motionBlur > 1)
        s << "\n// Motion blur ([render] motion_blur, shutter): blur.ini renders FerroMotionBlur\n"
             "// sub-frames whose clock runs -0.5 .. 0.5; each moves the meshes along their\n"
             "// velocities by FerroShift seconds, and average.ini averages them into the frame.\n"
          << "#declare FerroMotionBlur = " << r.motionBlur << ";\n"
          << "#declare FerroShutter = " << number(r.shutter) << ";   // of the frame interval\n"
          << "#ifdef (FerroBlur) #declare FerroShift = clock * FerroShutter / FerroFps; #end\n";
    s << "\n// The frame's data: FerroMesh (if the surface has triangles) and the magnets.\n"
         "#include concat(\"mesh_\", str(FerroFrame, -4, 0), \".inc\")\n"
         "#include concat(\"magnets_\", str(FerroFrame, -4, 0), \".inc\")\n\n"
         "// Everything that makes the picture.\n"
         "#include \"look.inc\"\n";
    return s.str();
}

std::string renderIni(const ShotDescription& shot)
{
    const RenderParams& r = shot.render;
    std::ostringstream s;
    s << "; render.ini: image settings from the scene's [render], written by ferro-pov on every export.\n"
         "; One frame: povray render.ini Declare=FerroFrame=12 +Oframe_0012.png\n"
      << "Input_File_Name=shot.pov\n"
      << "Width=" << r.width << "\nHeight=" << r.height << "\n"
      << "Quality=" << r.quality << "\n"
      << "Antialias=" << (r.antialias ? "on" : "off") << "\n"
      << "Antialias_Threshold=" << number(r.antialiasThreshold) << "\n"
      << "Antialias_Depth=" << r.antialiasDepth << "\n"
      << "Sampling_Method=2\n"
      << "Jitter=off\n"
      << "Output_File_Type=N\n"
      << "Output_Alpha=off\n"
      << "Display=off\n"
      << "Verbose=off\n";
    return s.str();
}

std::string shotIni(const ShotDescription& shot)
{
    std::ostringstream s;
    s << "; shot.ini: the shot as a POV-Ray animation, written by ferro-pov on every export.\n"
         "; povray shot.ini             renders every frame into frames/\n"
         "; povray shot.ini +SF10 +EF20 renders frames 10..20 (POV-Ray pads the frame number in\n"
         ";                             the file name to the digits of Final_Frame)\n"
         "render.ini\n"
      << "Initial_Frame=" << shot.firstFrame << "\n"
      << "Final_Frame=" << shot.lastFrame << "\n"
      << "Initial_Clock=" << number(shot.firstFrame / shot.fps) << "\n"
      << "Final_Clock=" << number(shot.lastFrame / shot.fps) << "\n"
      << "Cyclic_Animation=off\n"
      << "Output_File_Name=frames/shot_\n";
    return s.str();
}

namespace {
int digits(int n) { return int(std::to_string(n).size()); }
} // namespace

std::string blurIni(const ShotDescription& shot)
{
    const int n = shot.render.motionBlur;
    std::ostringstream s;
    s << "; blur.ini: one frame's motion blur sub-frames, written by ferro-pov while\n"
         "; render.motion_blur > 1. Frame 12: povray blur.ini Declare=FerroFrame=12 +Osub/frame_0012_.png\n"
         "; (sub/frame_0012_" << std::string(size_t(digits(n) - 1), '0') << "1.png ...), then\n"
         "; povray average.ini Declare=FerroFrame=12 +Oframe_0012.png. scripts/shot.mk does both.\n"
         "render.ini\n"
         "Declare=FerroBlur=1\n"
      << "Initial_Frame=1\n"
      << "Final_Frame=" << n << "\n"
      << "Initial_Clock=-0.5\n"
      << "Final_Clock=0.5\n"
      << "Cyclic_Animation=off\n";
    return s.str();
}

std::string averageIni(const ShotDescription& shot)
{
    std::ostringstream s;
    s << "; average.ini: the mean of a frame's motion blur sub-frames (average.pov), written by\n"
         "; ferro-pov while render.motion_blur > 1: povray average.ini Declare=FerroFrame=12 +Oframe_0012.png\n"
         "render.ini\n"
         "Input_File_Name=average.pov\n"
         "Antialias=off\n"
         "Quality=0\n";
    (void)shot;
    return s.str();
}

std::string averageScene(const ShotDescription& shot)
{
    const int n = shot.render.motionBlur;
    std::ostringstream s;
    s << "// average.pov: the mean of frame FerroFrame's sub-frames sub/frame_NNNN_K.png, written by\n"
         "// ferro-pov while render.motion_blur > 1. Each sub-frame is an image map on the unit\n"
         "// square, seen by an orthographic camera pixel for pixel; the maps are averaged in\n"
         "// linear light (assumed_gamma 1) and the result is encoded like any render.\n"
         "#version 3.7;\n"
         "global_settings { assumed_gamma 1.0 }\n"
         "#ifndef (FerroFrame) #declare FerroFrame = 0; #end\n"
      << "#declare FerroSubframes = " << n << ";\n"
      << "#declare FerroSubDigits = " << digits(n) << ";\n"
      << "camera { orthographic location <0.5, 0.5, -1> look_at <0.5, 0.5, 0> right x up y }\n"
         "plane { z, 0\n"
         "  texture {\n"
         "    pigment { average pigment_map {\n"
         "      #for (K, 1, FerroSubframes)\n"
         "        [1 image_map { png concat(\"sub/frame_\", str(FerroFrame, -4, 0), \"_\", str(K, -FerroSubDigits, 0), \".png\") once }]\n"
         "      #end\n"
         "    } }\n"
         "    finish { emission 1 diffuse 0 ambient 0 specular 0 }\n"
         "  }\n"
         "}\n";
    return s.str();
}

} // namespace ferro

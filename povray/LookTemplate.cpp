// The look template (look.inc): ferro-pov writes it once per shot directory; artists own it.
#include "povray/PovExport.hpp"

namespace ferro {

std::string lookTemplate()
{
    return R"POV(// look.inc: the look of the shot: camera, lights, materials, dish, floor, magnets.
// Written once by ferro-pov and then yours: re-exports never overwrite it
// (ferro-pov --force-template writes a fresh copy and discards your edits).
//
// shot.pov includes this file last, after the frame's data. Units are millimetres, y is up
// (Ferro's z); x is Ferro's x and z is Ferro's y (POV-Ray is left-handed).
// Values you can use (declared by shot.pov and the frame's includes):
//   FerroFrame, FerroTime, FerroFps, FerroFirstFrame, FerroLastFrame
//   FerroCameraLocation, FerroCameraLookAt, FerroCameraAngle, FerroAspect     ([render])
//   FerroSetCenter, FerroSetRadius, FerroFloorLevel
//   FerroContainerType: "dish" (FerroDishCenter, FerroDishRadius, FerroDishHeight),
//                       "box" (FerroBoxMin, FerroBoxMax), "mesh" or "none"
//   FerroMeshTriangles, FerroMeshVertices; FerroMesh, FerroMeshMin, FerroMeshMax if > 0 triangles
//   FerroMagnetCount; if > 0: arrays FerroMagnetKind, FerroMagnetPosition, FerroMagnetDirection
//   (south -> north), FerroMagnetLength, FerroMagnetRadius, FerroMagnetStrength, and the
//   objects FerroMagnetsNorth, FerroMagnetsSouth (each only if some magnet has that part).
//   FerroSolids: the magnetizable solids ([[solids]]), if the scene has any.

// max_trace_level 5: reflections of reflections of reflections; 10 costs about 40 % more time
// for no visible change on the opaque fluid.
global_settings { assumed_gamma 1.0 max_trace_level 5 }
#default { finish { ambient 0 diffuse 0.8 } }

// ---- Camera ---------------------------------------------------------------------------
camera {
  perspective
  location FerroCameraLocation
  look_at FerroCameraLookAt
  right x * FerroAspect
  up y
  sky y
  angle FerroCameraAngle
}

// ---- Studio ------------------------------------------------------------------------------
// A seamless grey backdrop and three soft boxes (area lights). The fluid is a black mirror:
// what it shows is the reflection of these, so the soft boxes are visible to reflected rays
// (looks_like) and the backdrop is a gradient rather than a flat colour.
#declare LookR = FerroSetRadius;
#declare LookC = FerroSetCenter;
sky_sphere {
  pigment {
    gradient y
    color_map { [0.0 rgb <0.62, 0.64, 0.68>] [0.5 rgb <0.30, 0.31, 0.34>] [1.0 rgb <0.10, 0.10, 0.12>] }
  }
}

// A square soft box of side Size at Pos facing the set, brightness Power.
// Samples: FerroLightSamples x FerroLightSamples ([render] light_samples, default 3), adaptive,
// no jitter (jitter flickers from frame to frame); 5x5 gives softer shadows at about twice the
// render time of 3x3, 2x2 about half of it with faintly stepped shadows of thin objects.
#ifndef (FerroLightSamples) #declare FerroLightSamples = 3; #end
#macro LookSoftBox(Pos, Size, Power)
  light_source {
    Pos, rgb Power
    area_light x * Size, z * Size, FerroLightSamples, FerroLightSamples
    adaptive 1
    circular
    orient
    fade_distance 6 * LookR fade_power 0
    looks_like {
      sphere { 0, Size / 2 scale <1, 0.15, 1>
        texture { pigment { rgb 1 } finish { emission Power * 1.5 diffuse 0 } } }
    }
  }
#end
LookSoftBox(LookC + <-2.2, 3.2, -1.6> * LookR, 1.6 * LookR, 1.0)   // key, front left, high
LookSoftBox(LookC + < 2.6, 1.6, -1.2> * LookR, 1.2 * LookR, 0.45)  // fill, front right, low
LookSoftBox(LookC + < 0.5, 2.4,  3.0> * LookR, 1.4 * LookR, 0.7)   // rim, behind

// ---- Materials ------------------------------------------------------------------------------
// Ferrofluid: black, very glossy, sharp reflections. The paper (section 5) notes that the
// fluid's albedo is tiny, so light scattered inside it (subsurface scattering) is negligible:
// an opaque black dielectric with Fresnel reflection is all it takes. ior 1.48 (a light oil)
// gives about 4 % reflectance head-on, rising to a full mirror at grazing angles.
#declare LookFluid = material {
  texture {
    pigment { rgb 0.004 }
    finish {
      diffuse 0.03
      specular 0.6 roughness 0.0008
      reflection { 0.0, 1.0 fresnel on }
      conserve_energy
    }
  }
  interior { ior 1.48 }
}

// Dish: clear glass. Cheap glass: no reflection (add `reflection { 0, 1 fresnel on }` to the
// finish for real glass, about 2.5x the render time of the whole frame) and no shadow.
#declare LookGlass = material {
  texture {
    pigment { rgbf <0.97, 0.99, 1.0, 0.96> }
    finish { diffuse 0.02 specular 0.5 roughness 0.002 }
  }
  interior { ior 1.5 }
}
#declare LookFloor = texture {
  pigment { rgb <0.74, 0.74, 0.76> }
  finish { diffuse 0.85 specular 0.05 roughness 0.05 }
}
#declare LookMagnetNorth = texture { pigment { rgb <0.55, 0.05, 0.04> } finish { diffuse 0.7 specular 0.4 roughness 0.01 reflection 0.05 } }
#declare LookMagnetSouth = texture { pigment { rgb <0.45, 0.47, 0.50> } finish { diffuse 0.5 specular 0.6 roughness 0.005 reflection 0.25 metallic } }
// Brushed steel for the solids: a metallic grey whose fine streaks run along y (the bumps
// stretched 40 times along the axis); raise the reflection for polished steel.
#declare LookSteel = texture {
  pigment { rgb <0.56, 0.57, 0.59> }
  normal { bumps 0.04 scale <0.02, 0.8, 0.02> }
  finish { diffuse 0.45 specular 0.7 roughness 0.008 reflection { 0.2 metallic } metallic }
}

// ---- The set -----------------------------------------------------------------------------------
plane { y, FerroFloorLevel texture { LookFloor } }

#declare LookWall = 1.5;   // glass thickness [mm]
#if (strcmp(FerroContainerType, "dish") = 0)
  #declare LookDishBottom = FerroDishCenter.y - LookWall;
  difference {
    cylinder { FerroDishCenter - y * LookWall, FerroDishCenter + y * FerroDishHeight, FerroDishRadius + LookWall }
    // The inner floor sits a hair below the fluid's lowest point so the two never coincide.
    cylinder { FerroDishCenter - y * 0.01, FerroDishCenter + y * (FerroDishHeight + 1), FerroDishRadius }
    material { LookGlass }
    no_shadow
  }
  // A dish lifted above the floor (a magnet passes under it) stands on three steel legs.
  #if (LookDishBottom - FerroFloorLevel > 0.5)
    #for (LookLeg, 0, 2)
      cylinder { <0, FerroFloorLevel, 0>, <0, LookDishBottom, 0>, 1.2
        translate vrotate(x * 0.85 * FerroDishRadius, y * (90 + 120 * LookLeg)) + <FerroDishCenter.x, 0, FerroDishCenter.z>
        texture { LookMagnetSouth } }
    #end
  #end
#end

// ---- Magnets ------------------------------------------------------------------------------------
#ifdef (FerroMagnetsNorth) object { FerroMagnetsNorth texture { LookMagnetNorth } } #end
#ifdef (FerroMagnetsSouth) object { FerroMagnetsSouth texture { LookMagnetSouth } } #end

// ---- Solids -------------------------------------------------------------------------------------
#ifdef (FerroSolids) object { FerroSolids texture { LookSteel } } #end

// ---- The fluid ----------------------------------------------------------------------------------
#if (FerroMeshTriangles > 0)
  object { FerroMesh material { LookFluid } }
#end
)POV";
}

} // namespace ferro

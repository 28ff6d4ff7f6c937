#pragma once
// A magnetizable solid of the scene ([[solids]]), SI units; SolidScene.cpp parses it.
#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/solids/SolidShapes.hpp"

#include <string>
#include <vector>

namespace ferro {

/// Where a solid stands at one key: its shape's origin at `position`, its shape's +z axis
/// turned onto `axis` by the shortest rotation.
struct SolidKeyframe {
    double time = 0;           ///< [s]
    Vec3d position{0, 0, 0};   ///< [m]
    Vec3d axis{0, 0, 1};       ///< unit
};

struct SolidParams {
    enum class Shape { Sphere, Cylinder, Cone, Mesh };
    Shape shape = Shape::Cylinder;
    double radius = 0;          ///< sphere, cylinder, cone (base) [m]
    double height = 0;          ///< cylinder, cone [m]
    double tipRadius = 0;       ///< cone: radius at the top [m] (0: a point)
    std::string meshFile;       ///< mesh: closed triangle mesh, resolved path
    double meshScale = 1;       ///< mesh: uniform scale of the file's coordinates
    /// Relative permeability mu_r, 1 < mu_r <= 1e5 (soft iron 1000-5000, mild steel ~
    /// 100-2000); default 1000.
    double permeability = 1000;
    /// Saturation magnetization Ms [A/m], 0 = linear; iron 1.7e6, mild steel ~1.6e6.
    double saturation = 0;
    /// Panels' edge length [m] for the surface-charge solve; 0 = twice the fluid spacing.
    double panelSize = 0;
    Vec3d position{0, 0, 0};    ///< [m]
    Vec3d axis{0, 0, 1};        ///< unit
    std::vector<SolidKeyframe> keys;

    /// The pose at time t [s]: position on a Catmull-Rom spline, axis by slerp, holding the
    /// first and last keys outside them (the magnets' interpolation, MagnetTrack).
    SolidKeyframe at(double t) const;
    /// True when the keys move the solid.
    bool moves() const;
};

/// The solid's surface in its own frame (origin at the base centre, axis +z; a sphere about
/// its centre; a mesh as the file has it, scaled), edges about `edge` [m]. Throws
/// SceneError (naming `where`) for a mesh that cannot be read, is not closed, or is
/// inside out.
ShapeMesh solidShape(const SolidParams& solid, double edge, const std::string& where);
/// `shape` moved to the pose of `solid` at time t, as the surface-charge solve takes it.
SolidSurface solidSurfaceAt(const SolidParams& solid, const ShapeMesh& shape, double t);

/// [[solids]] (with [[solids.keys]]) of a scene; SceneErrors name file, line and key (exit 2).
std::vector<SolidParams> parseSolids(const SceneDocument& doc);

} // namespace ferro

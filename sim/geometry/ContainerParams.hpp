#pragma once
// The container's parameters ([container] of a scene), in SI units; sim/scene parses them.
#include "sim/core/Types.hpp"

#include <string>

namespace ferro {

/// [container]: the vessel. Walls are sampled with boundary particles (Akinci 2012) and,
/// as a hard guarantee, particle motion is never allowed to cross a wall.
struct ContainerParams {
    enum class Type { None, Box, Dish, Mesh };
    Type type = Type::None;
    // box
    Vec3d min{0, 0, 0}, max{0, 0, 0}; ///< box corners [m]
    bool closedTop = false;           ///< box: sample a lid too (the top is always a hard limit)
    bool periodicSides = false;       ///< box: x and y faces glued to the opposite ones (no side
                                      ///< walls; sim/spatial/PeriodicDomain.hpp), for a layer without rim
    // dish: a cylinder with a floor, axis +z
    Vec3d center{0, 0, 0};            ///< centre of the dish floor [m]
    double radius = 0;                ///< inner radius [m]
    double height = 0;                ///< wall height [m]
    // mesh
    std::string meshFile;             ///< closed triangle mesh (OBJ, STL, PLY), resolved path
    double meshScale = 1.0;           ///< uniform scale applied to the file's coordinates
    Vec3d meshTranslate{0, 0, 0};     ///< translation applied after scaling [m]
    bool fluidInside = false;         ///< true: the mesh interior is the fluid domain;
                                      ///< false: the mesh is the solid vessel (fluid outside it)
    bool hasBounds = false;           ///< mesh: explicit safety box given
    Vec3d boundsMin{0, 0, 0}, boundsMax{0, 0, 0}; ///< mesh: safety box [m]
    double wallFriction = 0.0;        ///< boundary viscosity factor (0 = free slip, 1 = as fluid)
};

} // namespace ferro

#pragma once
// Containers: the vessel the fluid lives in.
//
// A container provides (1) boundary particles sampled on its walls (Akinci et al. 2012),
// which give the pressure solver a smooth wall, and (2) a hard guarantee: `constrain`
// never lets a particle's motion cross a wall, however thin, or leave the container's
// safety box. Boundary particles do the physics; `constrain` is the safety net.
#include "sim/geometry/ContainerParams.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ferro {

class Container {
public:
    virtual ~Container() = default;
    /// Boundary particle positions about `spacing` apart on the walls moved `offset` into
    /// the solid. The solver passes half a spacing: a wall layer there stands where the mirror
    /// image of the first fluid layer would be. Mesh walls may be thinner than that and
    /// ignore the offset (their samples lie on the surface).
    virtual std::vector<Vec3> sampleWalls(double spacing, double offset = 0) const = 0;
    /// True if `p` is a place fluid may be (inside the vessel, at least `margin` from walls).
    virtual bool contains(const Vec3d& p, double margin) const = 0;
    /// Moves `x` back so that the segment `xOld -> x` crosses no wall and ends inside;
    /// removes the velocity component into the wall that was hit. `xOld` is valid.
    /// Returns true if the particle was corrected.
    virtual bool constrain(const Vec3& xOld, Vec3& x, Vec3& v) const = 0;
    /// Axis-aligned bounds of the region fluid may occupy (may be huge for None).
    virtual void bounds(Vec3d& lo, Vec3d& hi) const = 0;
};

/// Builds the container of `params`. Throws SceneError for an unreadable or open mesh.
std::unique_ptr<Container> makeContainer(const ContainerParams& params, const std::string& where);

/// A solid inside the vessel (a magnetizable sculpture, sim/solids): a closed, outward
/// triangle mesh in world coordinates [m] that the fluid stays outside of.
struct SolidWall {
    std::vector<Vec3d> vertices;
    std::vector<std::array<uint32_t, 3>> triangles;
};
/// The container of `params` with `solids` standing in it: the mesh container's walls on
/// each solid (boundary samples on its surface, the watertight motion constraint), fluid
/// where the vessel holds it and no solid is. Without solids, makeContainer(params).
std::unique_ptr<Container> makeContainerWithSolids(const ContainerParams& params, const std::vector<SolidWall>& solids,
                                                   const std::string& where);

} // namespace ferro

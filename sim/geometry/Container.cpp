// Containers (see Container.hpp): the kinds None, Box, Dish and Mesh, one file each.
//
// Box and Dish are convex, so projecting a point back into them can never cross a wall:
// their constrain() is a clamp. A mesh can be any closed shape (a thin-walled cup), so its
// constrain() tests the motion segment against the triangles (MeshContainer.cpp).
#include "sim/geometry/ContainerKinds.hpp"

#include "sim/core/SceneDocument.hpp"

#include <cmath>

namespace ferro {
namespace container_detail {
namespace {

class NoneContainer final : public Container {
public:
    std::vector<Vec3> sampleWalls(double, double) const override { return {}; }
    bool contains(const Vec3d&, double) const override { return true; }
    bool constrain(const Vec3&, Vec3&, Vec3&) const override { return false; }
    void bounds(Vec3d& lo, Vec3d& hi) const override {
        lo.setConstant(-kHuge);
        hi.setConstant(kHuge);
    }
};

} // namespace

std::unique_ptr<Container> makeNoneContainer() { return std::make_unique<NoneContainer>(); }

} // namespace container_detail

using namespace container_detail;

std::unique_ptr<Container> makeContainer(const ContainerParams& params, const std::string& where) {
    auto ordered = [](const Vec3d& lo, const Vec3d& hi) {
        return lo.allFinite() && hi.allFinite() && (lo.array() < hi.array()).all();
    };
    switch (params.type) {
    case ContainerParams::Type::None:
        return makeNoneContainer();
    case ContainerParams::Type::Box:
        if (!ordered(params.min, params.max))
            throw SceneError(where + ": container: max must exceed min on every axis");
        return makeBoxContainer(params.min, params.max, params.closedTop, params.periodicSides);
    case ContainerParams::Type::Dish:
        if (!(params.radius > 0 && std::isfinite(params.radius)))
            throw SceneError(where + ": container.radius: must be > 0");
        if (!(params.height > 0 && std::isfinite(params.height)))
            throw SceneError(where + ": container.height: must be > 0");
        if (!params.center.allFinite()) throw SceneError(where + ": container.center: must be finite");
        return makeDishContainer(params.center, params.radius, params.height);
    case ContainerParams::Type::Mesh: {
        if (!(params.meshScale > 0 && std::isfinite(params.meshScale)))
            throw SceneError(where + ": container.scale: must be > 0");
        if (params.hasBounds && !ordered(params.boundsMin, params.boundsMax))
            throw SceneError(where + ": container.bounds: max must exceed min on every axis");
        return makeMeshContainer(params, where);
    }
    }
    throw SceneError(where + ": container: unknown type");
}

} // namespace ferro

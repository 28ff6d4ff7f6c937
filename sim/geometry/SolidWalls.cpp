// Solids standing in the vessel (makeContainerWithSolids): the vessel and one mesh obstacle
// per solid, composed. A particle is where fluid may be when every part says so; a motion is
// constrained by each part in turn.
#include "sim/geometry/ContainerKinds.hpp"

namespace ferro {
namespace container_detail {
namespace {

class ContainerWithSolids final : public Container {
public:
    ContainerWithSolids(std::unique_ptr<Container> vessel, std::vector<std::unique_ptr<Container>> solids)
        : vessel_(std::move(vessel)), solids_(std::move(solids)) {}

    std::vector<Vec3> sampleWalls(double spacing, double offset) const override {
        std::vector<Vec3> out = vessel_->sampleWalls(spacing, offset);
        for (const auto& s : solids_) {
            // A solid's samples inside another solid or outside the vessel stand for no wall
            // the fluid meets (a base on the floor, two solids touching).
            for (const Vec3& p : s->sampleWalls(spacing, offset)) {
                bool keep = vessel_->contains(p.cast<double>(), -spacing);
                for (const auto& o : solids_)
                    if (keep && o != s) keep = o->contains(p.cast<double>(), 0);
                if (keep) out.push_back(p);
            }
        }
        return out;
    }

    bool contains(const Vec3d& p, double margin) const override {
        if (!vessel_->contains(p, margin)) return false;
        for (const auto& s : solids_)
            if (!s->contains(p, margin)) return false;
        return true;
    }

    bool constrain(const Vec3& xOld, Vec3& x, Vec3& v) const override {
        // Each part once (a wall's constraint is not idempotent: the dish's, run twice on a
        // particle at its wall, took the velocity twice), the solids again only when the
        // vessel moved the particle (off the floor a solid stands on, into the solid).
        bool corrected = false;
        for (const auto& s : solids_) corrected |= s->constrain(xOld, x, v);
        if (vessel_->constrain(xOld, x, v)) {
            corrected = true;
            for (const auto& s : solids_) s->constrain(xOld, x, v);
        }
        return corrected;
    }

    void bounds(Vec3d& lo, Vec3d& hi) const override { vessel_->bounds(lo, hi); }

private:
    std::unique_ptr<Container> vessel_;
    std::vector<std::unique_ptr<Container>> solids_;
};

} // namespace
} // namespace container_detail

std::unique_ptr<Container> makeContainerWithSolids(const ContainerParams& params, const std::vector<SolidWall>& solids,
                                                   const std::string& where) {
    std::unique_ptr<Container> vessel = makeContainer(params, where);
    if (solids.empty()) return vessel;
    std::vector<std::unique_ptr<Container>> walls;
    for (const SolidWall& s : solids) walls.push_back(container_detail::makeMeshObstacle(s.vertices, s.triangles));
    return std::make_unique<container_detail::ContainerWithSolids>(std::move(vessel), std::move(walls));
}

} // namespace ferro

// The solids of a spike frame (SpikeSolids.hpp).
#include "spikes/SpikeSolids.hpp"

#include "sim/particlefield/ParticleField.hpp"

#include "sim/core/StageErrors.hpp"
#include "sim/geometry/Container.hpp"
#include "sim/solids/SurfaceChargeSolver.hpp"

#include <cmath>
#include <memory>

namespace ferro {

void addSolids(const std::vector<SolidParams>& solids, double spacing, const std::string& where, SpikeInput& in)
{
    if (solids.empty()) return;
    std::vector<SolidSurface> surfaces;
    std::vector<SolidWall> walls;
    for (const SolidParams& s : solids) {
        const double edge = s.panelSize > 0 ? s.panelSize : spacing > 0 ? 2 * spacing : s.radius / 8;
        surfaces.push_back(solidSurfaceAt(s, solidShape(s, edge, where), in.time));
        walls.push_back({surfaces.back().vertices, surfaces.back().triangles});
    }
    ContainerParams none; // the solids alone: the vessel's walls are in.fluid.container
    in.fluid.solids = std::shared_ptr<const Container>(makeContainerWithSolids(none, walls, where));

    auto solver = std::make_shared<SurfaceChargeSolver>();
    solver->setSurfaces(surfaces);
    const std::vector<Magnet> magnets = in.magnets;
    const SurfaceChargeSolver::Stats st =
        solver->solve([&](const Vec3d& p) { return magnetField(magnets, p) + particleFieldAt(in, p); });
    if (!st.converged)
        throw BadInputError(where + ": the solids' magnetization did not converge (residual " +
                            std::to_string(st.residual) + " after " + std::to_string(st.iterations) + " steps)");
    for (double q : solver->charge())
        if (!std::isfinite(q)) throw BadInputError(where + ": the solids' magnetization is not finite");
    in.solids = solver;
}

Vec3d particleFieldAt(const SpikeInput& in, const Vec3d& x)
{
    return in.particleField ? in.particleField->inducedField(x) : Vec3d::Zero();
}

Vec3d solidFieldAt(const SpikeInput& in, const Vec3d& x)
{
    if (!in.solids) return Vec3d::Zero();
    // The particles' path (one float pass, 0.2-0.3 % on the sphere): the spikes ask for the
    // field at every vertex of the refined surface.
    Vec3d H;
    Mat3d J;
    in.solids->fieldAndGradient(x, H, J);
    return H;
}

} // namespace ferro

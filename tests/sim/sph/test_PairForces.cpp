// The pair-force table and the fused sweep: names and the error for an unknown one, and the
// sweep's pair forces conserving momentum (the pair models are symmetric in i and j; "csf" is
// a traction, not a pair force, and is left out)
// on a jittered blob in the air, where the four-pair and the one-pair forms of a model both
// take pairs (a pair i may sum in four lanes while j sums it in the scalar tail).
#include "sim/sph/FluidSimulation.hpp"
#include "sim/sph/forces/PairForces.hpp"
#include "sim/core/SceneDocument.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace ferro;

namespace {

/// A 12 x 12 x 12 block in the air, no gravity, no walls, its particles jittered and moving at
/// random, so that every pair carries viscosity and tension.
SimScene blobScene(const std::string& viscosityModel, const std::string& tensionModel) {
    SimScene scene;
    scene.path = "blob.toml";
    scene.fluid.restDensity = 1000;
    scene.fluid.viscosity = 1e-4;
    scene.fluid.viscosityMethod = FluidParams::ViscosityMethod::Explicit;
    scene.fluid.surfaceTension = 0.07;
    scene.fluid.viscosityModel = viscosityModel;
    scene.fluid.surfaceTensionModel = tensionModel;
    scene.fluid.spacing = 0.001;
    FluidBlock block;
    block.min = Vec3d(0, 0, 0);
    block.max = Vec3d(0.012, 0.012, 0.012);
    scene.fluid.blocks.push_back(block);
    scene.solver.gravity = Vec3d::Zero();
    scene.solver.artificialViscosity = 0;
    return scene;
}

} // namespace

TEST_CASE("pair-force models: the table's names, and an unknown name names the key and the choices", "[forces]") {
    CHECK(viscosityModelNames() == std::vector<std::string>{"standard"});
    CHECK(surfaceTensionModelNames() == std::vector<std::string>{"akinci2013", "csf"});
    SimScene scene = blobScene("laplace", "akinci2013");
    scene.fluid.viscosityModelWhere = "blob.toml:7";
    try {
        FluidSimulation sim(scene);
        FAIL("unknown viscosity model accepted");
    } catch (const SceneError& e) {
        CHECK(std::string(e.what()) == "blob.toml:7: fluid.viscosity_model: must be one of \"standard\" (got \"laplace\")");
    }
    scene = blobScene("standard", "brackbill");
    try {
        FluidSimulation sim(scene);
        FAIL("unknown surface tension model accepted");
    } catch (const SceneError& e) {
        CHECK(std::string(e.what()) ==
              "blob.toml: fluid.surface_tension_model: must be one of \"akinci2013\", \"csf\" (got \"brackbill\")");
    }
}

TEST_CASE("the fused sweep's pair forces conserve momentum (viscosity and tension, jittered blob)", "[forces]") {
    FluidSimulation sim(blobScene("standard", "akinci2013"));
    REQUIRE(!sim.implicitViscosity());
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> jitter(-0.2, 0.2), speed(-0.05, 0.05);
    std::vector<Vec3> x = sim.positionsById(), v(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
        x[i] += Vec3(Real(jitter(rng)), Real(jitter(rng)), Real(jitter(rng))) * Real(sim.spacing());
        v[i] = Vec3(Real(speed(rng)), Real(speed(rng)), Real(speed(rng)));
    }
    sim.setState(0, x, v, std::vector<Real>(x.size(), 0));
    sim.computeAccelerations(nullptr);
    // Sum of the forces against the sum of their sizes: zero for symmetric pair forces, up to
    // float rounding (a few 1e-7 a term).
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    double size = 0;
    for (const Vec3& a : sim.accelerations()) {
        total += a.cast<double>();
        size += a.cast<double>().norm();
    }
    INFO("|sum a| = " << total.norm() << ", sum |a| = " << size);
    REQUIRE(size > 0);
    CHECK(total.norm() < 1e-5 * size);
}

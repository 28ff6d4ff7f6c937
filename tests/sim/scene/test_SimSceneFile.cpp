// Scene files: parsing, defaults, validation messages and --set overrides.
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimSceneFile.hpp"
#include "tests/TestUtil.hpp"

#include "sim/core/StageErrors.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <functional>

using namespace ferro;
using ferro::test::TempDir;
using Catch::Matchers::Contains;

namespace {

// One box of fluid with an explicit particle count, and the smallest valid scene.
const std::string kBlock = R"([[fluid.block]]
min = [0, 0, 0]
max = [0.01, 0.01, 0.01]
count = 1000
)";
const std::string kMinimal = "[fluid]\n" + kBlock;

// The message of the SceneError `f` throws (fails the test if it throws none).
std::string errorOf(const std::function<void()>& f)
{
    try {
        f();
    } catch (const SceneError& e) {
        return e.what();
    }
    FAIL("expected a SceneError");
    return {};
}

std::string sceneError(const std::string& text, const std::vector<std::string>& overrides = {})
{
    return errorOf([&] { parseSimScene(SceneDocument::parse(text, "t.toml", overrides)); });
}

SimScene scene(const std::string& text, const std::vector<std::string>& overrides = {})
{
    return parseSimScene(SceneDocument::parse(text, "t.toml", overrides));
}

} // namespace

TEST_CASE("minimal scene takes the documented defaults", "[scene]")
{
    SimScene s = scene(kMinimal);
    CHECK(s.path == "t.toml");
    CHECK(s.shot.fps == 30.0);
    CHECK(s.shot.duration == 1.0);
    CHECK(s.shot.frameCount() == 30);

    CHECK(s.fluid.restDensity == 1000.0);
    CHECK(s.fluid.viscosity == 1e-6);
    CHECK(s.fluid.surfaceTension == 0.0);
    CHECK(s.fluid.spacing == 0.0);
    REQUIRE(s.fluid.blocks.size() == 1);
    const FluidBlock& b = s.fluid.blocks[0];
    CHECK(b.shape == FluidBlock::Shape::Box);
    CHECK(b.min == Vec3d(0, 0, 0));
    CHECK(b.max == Vec3d(0.01, 0.01, 0.01));
    CHECK(b.velocity == Vec3d(0, 0, 0));
    CHECK(b.count == 1000);
    CHECK(b.where == "t.toml:2");

    CHECK(s.container.type == ContainerParams::Type::None);
    CHECK(s.container.wallFriction == 0.0);

    CHECK(s.solver.pressureSolver == "dfsph");
    CHECK(s.solver.gravity == Vec3d(0, 0, -9.81));
    CHECK(s.solver.cfl == 0.4);
    CHECK(s.solver.maxDt == 0.001);
    CHECK(s.solver.minDt == 1e-7);
    // No key left for the pressure solver (its own defaults: tests/sim/sph).
    REQUIRE(s.solver.solverKeys != nullptr);
    CHECK(s.solver.solverKeys->section("sim").unread().empty());
    CHECK(s.solver.artificialViscosity == 0.02);
    CHECK(s.solver.threads == 0);
}

TEST_CASE("every sim key is read", "[scene]")
{
    SimScene s = scene(R"([shot]
fps = 24
duration = 0.5

[fluid]
rest_density = 1200
viscosity = 5e-6
surface_tension = 0.025
spacing = 0.001

[[fluid.block]]
min = [-0.01, -0.01, 0]
max = [0.01, 0.01, 0.005]
velocity = [0, 0, -0.1]

[[fluid.block]]
shape = "cylinder"
center = [0, 0, 0.02]
radius = 0.005
height = 0.01
count = 500

[container]
type = "box"
min = [-0.05, -0.05, 0]
max = [0.05, 0.05, 0.1]
closed_top = true
wall_friction = 0.5

[sim]
solver = "wcsph"
gravity = [0, -9.81, 0]
cfl = 0.25
max_dt = 0.003
min_dt = 1e-8
sound_speed = 20
max_density_error = 0.002
max_divergence_error = 0.01
max_iterations = 50
artificial_viscosity = 0.1
threads = 2
)");
    CHECK(s.shot.fps == 24.0); // an integer where a float is expected
    CHECK(s.shot.duration == 0.5);
    CHECK(s.shot.frameCount() == 12);
    CHECK(s.fluid.restDensity == 1200.0);
    CHECK(s.fluid.viscosity == 5e-6);
    CHECK(s.fluid.surfaceTension == 0.025);
    CHECK(s.fluid.spacing == 0.001);
    REQUIRE(s.fluid.blocks.size() == 2);
    CHECK(s.fluid.blocks[0].shape == FluidBlock::Shape::Box);
    CHECK(s.fluid.blocks[0].min == Vec3d(-0.01, -0.01, 0));
    CHECK(s.fluid.blocks[0].max == Vec3d(0.01, 0.01, 0.005));
    CHECK(s.fluid.blocks[0].velocity == Vec3d(0, 0, -0.1));
    CHECK(s.fluid.blocks[0].count == 0);
    CHECK(s.fluid.blocks[0].where == "t.toml:11");
    const FluidBlock& c = s.fluid.blocks[1];
    CHECK(c.shape == FluidBlock::Shape::Cylinder);
    CHECK(c.center == Vec3d(0, 0, 0.02));
    CHECK(c.radius == 0.005);
    CHECK(c.height == 0.01);
    CHECK(c.count == 500);
    CHECK(c.where == "t.toml:16");

    CHECK(s.container.type == ContainerParams::Type::Box);
    CHECK(s.container.min == Vec3d(-0.05, -0.05, 0));
    CHECK(s.container.max == Vec3d(0.05, 0.05, 0.1));
    CHECK(s.container.closedTop);
    CHECK(s.container.wallFriction == 0.5);

    CHECK(s.solver.pressureSolver == "wcsph");
    CHECK(s.solver.gravity == Vec3d(0, -9.81, 0));
    CHECK(s.solver.cfl == 0.25);
    CHECK(s.solver.maxDt == 0.003);
    CHECK(s.solver.minDt == 1e-8);
    // The pressure solvers' own keys are left to them (their registry rows read them:
    // tests/sim/sph), with their lines.
    REQUIRE(s.solver.solverKeys != nullptr);
    const TableReader own = s.solver.solverKeys->section("sim");
    CHECK(own.unread() == std::vector<std::string>{"sound_speed", "max_density_error", "max_divergence_error", "max_iterations"});
    CHECK(own.number("sound_speed", 0) == 20.0);
    CHECK(own.where("max_iterations") == "t.toml:39");
    CHECK(own.number("max_iterations", 0) == 50);
    CHECK(own.unread() == std::vector<std::string>{"max_density_error", "max_divergence_error"});
    CHECK(s.solver.artificialViscosity == 0.1);
    CHECK(s.solver.threads == 2);
}

TEST_CASE("dish container and its defaults", "[scene]")
{
    SimScene s = scene(kMinimal + "[container]\ntype = \"dish\"\nradius = 0.05\nheight = 0.02\n");
    CHECK(s.container.type == ContainerParams::Type::Dish);
    CHECK(s.container.center == Vec3d(0, 0, 0));
    CHECK(s.container.radius == 0.05);
    CHECK(s.container.height == 0.02);
}

TEST_CASE("mesh container resolves its file next to the scene", "[scene]")
{
    TempDir tmp("mesh");
    tmp.write("meshes/bowl.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    std::string path = tmp.write("dish.toml", kMinimal + R"([container]
type = "mesh"
file = "meshes/bowl.obj"
scale = 0.01
translate = [0, 0, 0.1]
fluid_side = "inside"
bounds_min = [-1, -1, -1]
bounds_max = [1, 1, 1]
)");
    SimScene s = loadSimScene(path);
    const ContainerParams& c = s.container;
    CHECK(c.type == ContainerParams::Type::Mesh);
    CHECK(std::filesystem::equivalent(c.meshFile, tmp.path / "meshes" / "bowl.obj"));
    CHECK(c.meshScale == 0.01);
    CHECK(c.meshTranslate == Vec3d(0, 0, 0.1));
    CHECK(c.fluidInside);
    CHECK(c.hasBounds);
    CHECK(c.boundsMin == Vec3d(-1, -1, -1));
    CHECK(c.boundsMax == Vec3d(1, 1, 1));

    // Defaults of the optional mesh keys.
    SimScene d = loadSimScene(path, {"container.fluid_side=outside"});
    CHECK_FALSE(d.container.fluidInside);
    std::string bare = tmp.write("bare.toml", kMinimal +
                                                  "[container]\ntype = \"mesh\"\nfile = \"meshes/bowl.obj\"\n");
    SimScene e = loadSimScene(bare);
    CHECK(e.container.meshScale == 1.0);
    CHECK(e.container.meshTranslate == Vec3d(0, 0, 0));
    CHECK_FALSE(e.container.fluidInside);
    CHECK_FALSE(e.container.hasBounds);

    // A missing mesh file is reported against the key that names it.
    std::string missing = tmp.write("missing.toml", kMinimal +
                                                        "[container]\ntype = \"mesh\"\nfile = \"nope.obj\"\n");
    std::string msg = errorOf([&] { loadSimScene(missing); });
    CHECK_THAT(msg, Contains("missing.toml:8: container.file: file not found") && Contains("nope.obj"));

    // Bounds come in pairs.
    msg = errorOf([&] { loadSimScene(bare, {"container.bounds_min=[0,0,0]"}); });
    CHECK_THAT(msg, Contains("container.bounds_max: required key missing"));
}

TEST_CASE("unknown keys are errors", "[scene]")
{
    std::string msg = sceneError(R"([fluid]
rest_density = 1000
rest_densty = 1100
[[fluid.block]]
min = [0, 0, 0]
max = [1, 1, 1]
count = 10
)");
    CHECK_THAT(msg, Contains("t.toml:3: fluid.rest_densty: unknown key"));

    // Inside an array of tables the element index is part of the key.
    msg = sceneError(kMinimal + "[[fluid.block]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\ncolour = \"red\"\n");
    CHECK_THAT(msg, Contains("t.toml:9: fluid.block[1].colour: unknown key"));

    // A key of another container type does not belong to the chosen one.
    msg = sceneError(kMinimal + "[container]\ntype = \"dish\"\nradius = 0.05\nheight = 0.02\nclosed_top = true\n");
    CHECK_THAT(msg, Contains("t.toml:10: container.closed_top: unknown key"));

    // Cylinder keys on a box block.
    msg = sceneError(kMinimal + "[[fluid.block]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nradius = 0.1\n");
    CHECK_THAT(msg, Contains("t.toml:9: fluid.block[1].radius: unknown key"));

    // The first unknown key in file order is reported, not the first alphabetically.
    msg = sceneError(kMinimal + "[shot]\nzeta = 1\nalpha = 2\n");
    CHECK_THAT(msg, Contains("t.toml:7: shot.zeta: unknown key"));
    // [sim]'s keys that the scene parser does not read are the pressure solvers', who refuse
    // the unknown ones: tests/sim/sph/test_FluidSimulation.cpp.
}

TEST_CASE("unknown sections are errors", "[scene]")
{
    std::string msg = sceneError(kMinimal + "\n[magnetisation]\nchi = 1.2\n");
    CHECK_THAT(msg, Contains("t.toml:7: magnetisation: unknown section"));

    // Sections of later stages are accepted.
    SceneDocument doc = SceneDocument::parse(kMinimal + "[render]\n[surface]\n", "t.toml");
    CHECK_NOTHROW(doc.checkSections(shotSceneSections()));
    CHECK_THROWS_AS(doc.checkSections({"fluid"}), SceneError);
}

TEST_CASE("wrong types are errors", "[scene]")
{
    CHECK_THAT(sceneError("[fluid]\nrest_density = \"heavy\"\n"),
               Contains("t.toml:2: fluid.rest_density: expected a number (got string)"));
    CHECK_THAT(sceneError(kMinimal + "[sim]\ngravity = [0, -9.81]\n"),
               Contains("t.toml:7: sim.gravity: expected an array of 3 numbers (got 2 elements)"));
    CHECK_THAT(sceneError(kMinimal + "[sim]\ngravity = [0, \"down\", 0]\n"),
               Contains("t.toml:7: sim.gravity: expected an array of 3 numbers"));
    CHECK_THAT(sceneError(kMinimal + "[container]\ntype = \"box\"\nmin = [0,0,0]\nmax = [1,1,1]\nclosed_top = 1\n"),
               Contains("t.toml:10: container.closed_top: expected true or false (got integer)"));
    CHECK_THAT(sceneError(kMinimal + "[container]\ntype = 3\n"),
               Contains("t.toml:7: container.type: expected a string (got integer)"));
    CHECK_THAT(sceneError("fluid = 3\n"), Contains("t.toml:1: fluid: expected a table"));
    CHECK_THAT(sceneError("[fluid]\nspacing = nan\n"), Contains("t.toml:2: fluid.spacing: must be finite (got nan)"));
}

TEST_CASE("missing required keys name the table's line", "[scene]")
{
    CHECK_THAT(sceneError("[fluid]\nspacing = 0.001\n\n[[fluid.block]]\nmin = [0, 0, 0]\n"),
               Contains("t.toml:4: fluid.block[0].max: required key missing"));
    CHECK_THAT(sceneError(kMinimal + "[container]\ntype = \"dish\"\nheight = 0.02\n"),
               Contains("t.toml:6: container.radius: required key missing"));
    CHECK_THAT(sceneError("[fluid]\nspacing = 0.001\n[[fluid.block]]\nshape = \"cylinder\"\nradius = 1\n"),
               Contains("t.toml:3: fluid.block[0].height: required key missing"));
    CHECK_THAT(sceneError("[fluid]\nspacing = 0.001\n"),
               Contains("t.toml:1: fluid.block: at least one [[fluid.block]] is required"));
}

TEST_CASE("range violations are errors", "[scene]")
{
    CHECK_THAT(sceneError("[fluid]\nrest_density = -1200\n"),
               Contains("t.toml:2: fluid.rest_density: must be > 0 (got -1200)"));
    CHECK_THAT(sceneError("[fluid]\nspacing = -0.001\n[[fluid.block]]\nmin = [0,0,0]\nmax = [1,1,1]\ncount = 5\n"),
               Contains("t.toml:2: fluid.spacing: must be >= 0 (got -0.001)"));
    CHECK_THAT(sceneError("[fluid]\nviscosity = -1e-6\n"),
               Contains("t.toml:2: fluid.viscosity: must be >= 0 (got -1e-06)"));
    CHECK_THAT(sceneError(kMinimal + "[shot]\nfps = 0\n"),
               Contains("t.toml:7: shot.fps: must be > 0 (got 0)"));
    CHECK_THAT(sceneError(kMinimal + "[sim]\ncfl = 1.5\n"),
               Contains("t.toml:7: sim.cfl: must be in (0, 1] (got 1.5)"));
    CHECK_THAT(sceneError(kMinimal + "[sim]\nmax_dt = 1e-3\nmin_dt = 1e-3\n"),
               Contains("t.toml:8: sim.min_dt: must be < sim.max_dt"));
    CHECK_THAT(sceneError(kMinimal + "[sim]\nthreads = -1\n"),
               Contains("t.toml:7: sim.threads: must be in [0,"));
    CHECK_THAT(sceneError(kMinimal + "[sim]\nartificial_viscosity = 2\n"),
               Contains("t.toml:7: sim.artificial_viscosity: must be in [0, 1] (got 2)"));
    CHECK_THAT(sceneError("[fluid]\n[[fluid.block]]\nmin = [0,0,0]\nmax = [1,1,1]\ncount = -5\n"),
               Contains("t.toml:5: fluid.block[0].count: must be >= 0 (got -5)"));
    CHECK_THAT(sceneError("[fluid]\n[[fluid.block]]\nshape = \"cylinder\"\nradius = 0\nheight = 1\n"),
               Contains("t.toml:4: fluid.block[0].radius: must be > 0 (got 0)"));

    // Neither a spacing nor a counted block leaves the particle size undetermined.
    CHECK_THAT(sceneError("[fluid]\n[[fluid.block]]\nmin = [0,0,0]\nmax = [1,1,1]\n"),
               Contains("t.toml:1: fluid.spacing: must be > 0 unless a [[fluid.block]] has count > 0"));
    CHECK_NOTHROW(scene("[fluid]\nspacing = 0.01\n[[fluid.block]]\nmin = [0,0,0]\nmax = [1,1,1]\n"));
}

TEST_CASE("a shot longer than kMaxFrame frames is refused, naming the key set (issue 15)", "[scene]")
{
    // duration * fps used to overflow ShotParams::frameCount's int: "frames to -2147483648".
    CHECK_THAT(sceneError(kMinimal, {"shot.duration=1e9"}),
               Contains("--set shot.duration:1: shot.duration: duration * fps makes 3e+10 frames, more than 9999999 "
                        "(got duration 1e+09 s, fps 30)"));
    CHECK_THAT(sceneError(kMinimal, {"shot.fps=1e30"}), Contains("--set shot.fps:1: shot.fps: duration * fps makes 1e+30 frames"));
    CHECK_THAT(sceneError(kMinimal + "[shot]\nfps = 1000\nduration = 10000\n"), Contains("t.toml:8: shot.duration:"));
    // The largest shot that fits is accepted.
    CHECK(scene(kMinimal, {"shot.fps=1", "shot.duration=9999999"}).shot.frameCount() == 9999999);
    // frameCount never overflows, even for fields set in code.
    ShotParams p;
    p.duration = 1e9;
    CHECK(p.frameCount() == 9999999);
    p.fps = std::nan("");
    CHECK(p.frameCount() == 0);
}

TEST_CASE("non-finite numbers are refused by every numeric getter, showing the values given (issue 15)", "[scene]")
{
    // vec3 used to fail on the first nan with the later elements uninitialised:
    // "got [nan, 4e-323, 1.14e+243]".
    CHECK(sceneError(kMinimal + "[sim]\ngravity = [nan, 0, 0]\n") ==
          "t.toml:7: sim.gravity: must be finite (got [nan, 0, 0])");
    CHECK(sceneError("[fluid]\n[[fluid.block]]\nshape = \"cylinder\"\nradius = 1\nheight = 1\ncount = 5\n",
                     {"fluid.block.0.center=[nan,0,0]"}) ==
          "--set fluid.block.0.center:1: fluid.block[0].center: must be finite (got [nan, 0, 0])");
    CHECK(sceneError(kMinimal + "[sim]\ngravity = [1, 2, -inf]\n") ==
          "t.toml:7: sim.gravity: must be finite (got [1, 2, -inf])");
    // box, unitVector, number, positive, nonNegative.
    CHECK(sceneError("[fluid]\n[[fluid.block]]\nmin = [0, inf, 0]\nmax = [1, 1, 1]\ncount = 5\n") ==
          "t.toml:3: fluid.block[0].min: must be finite (got [0, inf, 0])");
    CHECK(sceneError(kMinimal + "[[magnets]]\ndirection = [0, nan, 1]\n") ==
          "t.toml:7: magnets[0].direction: must be finite (got [0, nan, 1])");
    CHECK(sceneError(kMinimal + "[sim]\ncfl = nan\n") == "t.toml:7: sim.cfl: must be finite (got nan)");
    CHECK(sceneError(kMinimal + "[sim]\nmax_dt = inf\n") == "t.toml:7: sim.max_dt: must be finite (got inf)");
    CHECK(sceneError("[fluid]\nviscosity = -inf\n") == "t.toml:2: fluid.viscosity: must be finite (got -inf)");
}

TEST_CASE("a huge or tiny direction is normalized, and errors name the key the user set (issue 15)", "[scene]")
{
    // The norm of [1e308, 1e308, 0] overflowed: the magnet's direction became [0, 0, 0]
    // and the error blamed magnets[0].keys[0].direction, a key not set.
    const std::string keyed = kMinimal + "[[magnets]]\nmoment = 1\n[[magnets.keys]]\ntime = 0\n";
    const double r = std::sqrt(0.5);
    for (const char* set : {"magnets.0.direction=[1e308,1e308,0]", "magnets.0.direction=[1e-200,1e-200,0]",
                            "magnets.0.direction=[5e-324,5e-324,0]"}) {
        CAPTURE(set);
        const SimScene s = scene(keyed, {set});
        REQUIRE(s.magnets.size() == 1);
        CHECK(s.magnets[0].base.direction.isApprox(Vec3d(r, r, 0)));
        REQUIRE(s.magnets[0].keys.size() == 1);
        CHECK(s.magnets[0].keys[0].direction.isApprox(Vec3d(r, r, 0)));
    }
    CHECK(sceneError(keyed, {"magnets.0.direction=[0,0,0]"}) ==
          "--set magnets.0.direction:1: magnets[0].direction: must be a non-zero vector (got [0, 0, 0])");
    CHECK(sceneError(keyed, {"magnets.0.keys.0.direction=[0,0,0]"}) ==
          "--set magnets.0.keys.0.direction:1: magnets[0].keys[0].direction: must be a non-zero vector (got [0, 0, 0])");
    CHECK(scene(keyed, {"magnets.0.keys.0.direction=[0,-1e308,-1e308]"}).magnets[0].keys[0].direction.isApprox(Vec3d(0, -r, -r)));
}

TEST_CASE("magnet strengths beyond the kind's maxStrength are refused, naming the key (issue 15)", "[scene]")
{
    // field = 1e20 A/m made every particle's H NaN (H^2 overflows a float); moment = 1e36 gave inf.
    const std::string uniform = kMinimal + "[[magnets]]\nkind = \"uniform\"\nfield = 1\n[[magnets.keys]]\ntime = 0\n";
    CHECK(sceneError(uniform, {"magnets.0.field=1e20"}) ==
          "--set magnets.0.field:1: magnets[0].field: must be within +-1e+09 A/m for a uniform magnet (got 1e+20; "
          "stronger fields overflow the solver's floats)");
    CHECK_THAT(sceneError(uniform, {"magnets.0.keys.0.field=-2e9"}),
               Contains("--set magnets.0.keys.0.field:1: magnets[0].keys[0].field: must be within +-1e+09 A/m"));
    CHECK(scene(uniform, {"magnets.0.field=-1e9"}).magnets[0].base.strength == -1e9);
    CHECK_THAT(sceneError(kMinimal + "[[magnets]]\nmoment = 1e36\n"),
               Contains("t.toml:7: magnets[0].moment: must be within +-1e+06 A m^2 for a dipole magnet (got 1e+36;"));
    CHECK_THAT(sceneError(kMinimal + "[[magnets]]\nkind = \"bar\"\nlength = 0.01\npole_strength = 2e6\n"),
               Contains("t.toml:9: magnets[0].pole_strength: must be within +-1e+06 A m for a bar magnet"));
    CHECK_THAT(sceneError(kMinimal + "[[magnets]]\nkind = \"loop\"\nradius = 0.01\ncurrent = -1e10\n"),
               Contains("t.toml:9: magnets[0].current: must be within +-1e+09 A for a loop magnet (got -1e+10;"));
    CHECK_NOTHROW(scene(kMinimal + "[[magnets]]\nmoment = 1e6\n"));
}

TEST_CASE("boxes need max > min on every axis", "[scene]")
{
    std::string msg = sceneError("[fluid]\n[[fluid.block]]\nmin = [0, 0, 0]\nmax = [1, -1, 1]\ncount = 5\n");
    CHECK_THAT(msg, Contains("t.toml:4: fluid.block[0].max: must be > min on every axis") &&
                        Contains("[1, -1, 1]"));
    msg = sceneError(kMinimal + "[container]\ntype = \"box\"\nmin = [0, 0, 0]\nmax = [1, 1, 0]\n");
    CHECK_THAT(msg, Contains("t.toml:9: container.max: must be > min on every axis"));
}

TEST_CASE("choices list the allowed values", "[scene]")
{
    std::string msg = sceneError(kMinimal + "[container]\ntype = \"bowl\"\n");
    CHECK_THAT(msg, Contains("t.toml:7: container.type: must be one of \"none\", \"box\", \"dish\", \"mesh\" (got \"bowl\")"));
    msg = sceneError("[fluid]\n[[fluid.block]]\nshape = \"sphere\"\n");
    CHECK_THAT(msg, Contains("t.toml:3: fluid.block[0].shape: must be one of \"box\", \"cylinder\""));
}

TEST_CASE("command-line overrides (--set)", "[scene]")
{
    SECTION("a number replaces a key of the file")
    {
        SimScene s = scene("[fluid]\nrest_density = 1000\n" + kBlock,
                           {"fluid.rest_density=1200"});
        CHECK(s.fluid.restDensity == 1200.0);
    }
    SECTION("a value that is not TOML is a bare string, and sections are created")
    {
        SimScene s = scene(kMinimal, {"container.type=dish", "container.radius=0.05", "container.height = 0.02"});
        CHECK(s.container.type == ContainerParams::Type::Dish);
        CHECK(s.container.radius == 0.05);
        CHECK(s.container.height == 0.02);
    }
    SECTION("a quoted TOML string works too")
    {
        SimScene s = scene(kMinimal, {"sim.solver=\"wcsph\""});
        CHECK(s.solver.pressureSolver == "wcsph");
    }
    SECTION("a numeric segment indexes an array of tables")
    {
        std::string two = kMinimal + "[[fluid.block]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n";
        SimScene s = scene(two, {"fluid.block.1.count=100", "fluid.block.0.velocity=[1, 2, 3]",
                                 "fluid.block.1.max.2=2"});
        REQUIRE(s.fluid.blocks.size() == 2);
        CHECK(s.fluid.blocks[0].count == 1000);
        CHECK(s.fluid.blocks[0].velocity == Vec3d(1, 2, 3));
        CHECK(s.fluid.blocks[1].count == 100);
        CHECK(s.fluid.blocks[1].max == Vec3d(1, 1, 2));
    }
    SECTION("a new key in an existing section")
    {
        SimScene s = scene(kMinimal, {"fluid.surface_tension=0.025", "shot.duration=2"});
        CHECK(s.fluid.surfaceTension == 0.025);
        CHECK(s.shot.duration == 2.0);
    }
    SECTION("errors in an override name the --set")
    {
        CHECK_THAT(sceneError(kMinimal, {"fluid.rest_density=-5"}),
                   Contains("--set fluid.rest_density:1: fluid.rest_density: must be > 0 (got -5)"));
        CHECK_THAT(sceneError(kMinimal, {"fluid.block.0.count=many"}),
                   Contains("--set fluid.block.0.count:1: fluid.block[0].count: expected an integer (got string)"));
        CHECK_THAT(sceneError(kMinimal, {"shot.bogus=1"}), Contains("--set shot.bogus:1: shot.bogus: unknown key"));
        CHECK_THAT(sceneError(kMinimal, {"magnetisation.chi=1"}),
                   Contains("--set magnetisation.chi:1: magnetisation: unknown section"));
        // A section that only exists through --set is located at the --set.
        CHECK_THAT(sceneError(kMinimal, {"container.type=dish"}),
                   Contains("--set container.type:1: container.radius: required key missing"));
    }
    SECTION("malformed overrides")
    {
        CHECK_THAT(sceneError(kMinimal, {"fluid.rest_density"}), Contains("--set fluid.rest_density"));
        CHECK_THROWS_AS(scene(kMinimal, {"=5"}), SceneError);
        CHECK_THROWS_AS(scene(kMinimal, {"fluid..spacing=5"}), SceneError);
        CHECK_THROWS_AS(scene(kMinimal, {"fluid.=5"}), SceneError);
        CHECK_THAT(sceneError(kMinimal, {"fluid.block.3.count=5"}), Contains("--set fluid.block.3.count=5") &&
                                                                        Contains("out of range"));
        CHECK_THAT(sceneError(kMinimal, {"fluid.block.99999999999999999999.count=5"}), Contains("out of range"));
        CHECK_THAT(sceneError(kMinimal, {"fluid.block.x=5"}), Contains("expected an array index"));
        CHECK_THAT(sceneError(kMinimal, {"container.type=\xff"}), Contains("--set container.type=\xff: value is"));
        CHECK_THAT(sceneError(kMinimal, {"fluid.block.0.count.x=5"}), Contains("fluid.block.0.count: not a table or array (got integer)"));
    }
}

TEST_CASE("loading files", "[scene]")
{
    TempDir tmp("load");
    SECTION("a missing file")
    {
        // A missing input, exit 4 in every stage, like a missing PLY (not a bad scene, 2).
        std::string path = (tmp.path / "absent.toml").string();
        try {
            SceneDocument::load(path);
            FAIL("a missing scene file was loaded");
        } catch (const InputMissingError& e) {
            CHECK(std::string(e.what()) == path + ": cannot open: No such file or directory");
            CHECK(e.code() == 4);
        }
        CHECK_THROWS_AS(SceneDocument::load(tmp.path.string()), InputMissingError);   // a directory
    }
    SECTION("a syntax error names file and line")
    {
        std::string path = tmp.write("broken.toml", "[fluid]\nrest_density = 1000\nviscosity = = 3\n");
        CHECK_THAT(errorOf([&] { SceneDocument::load(path); }), Contains(path + ":3: "));
    }
    SECTION("errors name the file")
    {
        std::string path = tmp.write("scene.toml", "[fluid]\nrest_density = -1200\n" + kBlock);
        CHECK(errorOf([&] { loadSimScene(path); }) == path + ":2: fluid.rest_density: must be > 0 (got -1200)");
        SimScene s = loadSimScene(path, {"fluid.rest_density=1100"});
        CHECK(s.fluid.restDensity == 1100.0);
        CHECK(s.path == path);
        CHECK(s.fluid.blocks[0].where == path + ":3");
    }
}

TEST_CASE("TableReader", "[scene]")
{
    SceneDocument doc = SceneDocument::parse(R"([render]
width = 640
exposure = 1
name = "dish"
[render.camera]
position = [0, -0.2, 0.1]
[[render.light]]
power = 2
)",
                                             "r.toml");
    TableReader r = doc.section("render");
    CHECK(r.tablePath() == "render");
    CHECK(r.has("width"));
    CHECK_FALSE(r.has("height"));
    CHECK(r.integer("width", 0) == 640);
    CHECK(r.integer("height", 480) == 480);
    CHECK(r.number("exposure") == 1.0);
    CHECK(r.string("name") == "dish");
    CHECK(r.where() == "r.toml:1");
    CHECK(r.where("name") == "r.toml:4");
    CHECK(r.where("absent") == "r.toml:1");
    CHECK_THAT(errorOf([&] { r.number("gamma"); }), Contains("r.toml:1: render.gamma: required key missing"));

    TableReader cam = r.table("camera");
    CHECK(cam.vec3("position") == Vec3d(0, -0.2, 0.1));
    CHECK(cam.vec3("target", Vec3d(1, 2, 3)) == Vec3d(1, 2, 3));
    CHECK_NOTHROW(cam.finish());
    std::vector<TableReader> lights = r.tables("light");
    REQUIRE(lights.size() == 1);
    CHECK(lights[0].tablePath() == "render.light[0]");
    CHECK(lights[0].number("power") == 2.0);
    // Sub-tables read through table()/tables() count as used.
    CHECK_NOTHROW(r.finish());

    CHECK(r.table("absent").tablePath() == "render.absent");
    CHECK(r.tables("absent").empty());
    CHECK_THAT(errorOf([&] { r.table("width"); }), Contains("r.toml:2: render.width: expected a table (got integer)"));

    // An absent section reads as an empty table.
    TableReader spikes = doc.section("spikes");
    CHECK_FALSE(doc.hasSection("spikes"));
    CHECK(spikes.number("k", 7) == 7.0);
    CHECK(spikes.node("k") == nullptr);
    CHECK_NOTHROW(spikes.finish());
}

TEST_CASE("fingerprint", "[scene]")
{
    std::string a = SceneDocument::parse(kMinimal, "a.toml").fingerprint();
    CHECK(a.size() == 16);
    CHECK(a.find_first_not_of("0123456789abcdef") == std::string::npos);
    // Stable, and blind to comments, layout and file name.
    CHECK(SceneDocument::parse(kMinimal, "a.toml").fingerprint() == a);
    CHECK(SceneDocument::parse(std::string("# a comment\n") + kMinimal + "\n\n", "b.toml").fingerprint() == a);
    // Overrides change it; an override to the same value does not.
    CHECK(SceneDocument::parse(kMinimal, "a.toml", {"fluid.block.0.count=2000"}).fingerprint() != a);
    CHECK(SceneDocument::parse(kMinimal, "a.toml", {"fluid.block.0.count=1000"}).fingerprint() == a);
    CHECK(SceneDocument::parse(kMinimal, "a.toml", {"shot.fps=30"}).fingerprint() != a);
}

TEST_CASE("the simulation's fingerprint hashes the keys it reads and sets, nothing else", "[scene]")
{
    auto simFingerprint = [](const std::string& text, const std::vector<std::string>& overrides = {}) {
        SceneDocument doc = SceneDocument::parse(text, "a.toml", overrides);
        doc.recordReads();
        parseSimScene(doc);
        return doc.readsFingerprint({"sim.threads"});
    };
    const std::string a = simFingerprint(kMinimal);
    CHECK(a.size() == 16);
    CHECK(simFingerprint(kMinimal) == a);
    // Sections and keys the simulation does not read, and the ignored sim.threads.
    CHECK(simFingerprint(kMinimal + "[render]\nwidth = 64\n[spikes]\nresolution = 4\n") == a);
    CHECK(simFingerprint(kMinimal, {"render.camera_position=[0,-0.1,0.05]", "sim.threads=1"}) == a);
    // Keys it reads: set to a value, even its default, they change it.
    CHECK(simFingerprint(kMinimal, {"fluid.block.0.count=2000"}) != a);
    CHECK(simFingerprint(kMinimal, {"sim.gravity=[0,0,-9.7]"}) != a);
    CHECK(simFingerprint(kMinimal, {"shot.fps=30"}) != a);
}

TEST_CASE("examples/annotated.toml parses", "[scene]")
{
    SimScene s = loadSimScene(std::string(FERRO_SOURCE_DIR) + "/examples/annotated.toml");
    CHECK(s.shot.fps == 30.0);
    CHECK(s.shot.duration == 2.0);
    CHECK(s.shot.frameCount() == 60);
    CHECK(s.fluid.restDensity == 1200.0);
    CHECK(s.fluid.viscosity == 5e-6);
    CHECK(s.fluid.surfaceTension == 0.025);
    CHECK(s.fluid.spacing == 0.0);
    REQUIRE(s.fluid.blocks.size() == 1);
    CHECK(s.fluid.blocks[0].shape == FluidBlock::Shape::Cylinder);
    CHECK(s.fluid.blocks[0].radius == 0.0495);
    CHECK(s.fluid.blocks[0].height == 0.01);
    CHECK(s.fluid.blocks[0].count == 40960);
    CHECK(s.container.type == ContainerParams::Type::Dish);
    CHECK(s.container.radius == 0.05);
    CHECK(s.container.height == 0.02);
    CHECK(s.solver.pressureSolver == "dfsph");

    // The documented defaults are the struct defaults.
    SimScene defaults;
    CHECK(s.solver.gravity == defaults.solver.gravity);
    CHECK(s.solver.cfl == defaults.solver.cfl);
    CHECK(s.solver.maxDt == defaults.solver.maxDt);
    CHECK(s.solver.minDt == defaults.solver.minDt);
}

TEST_CASE("magnetization.opening_angle is refused outside the tree's working range [0.05, 1]", "[scene]")
{
    // The tree clamped 1.2 to 1 without a word (a bench report's "theta 1.2" rows were 1.0).
    CHECK(scene(kMinimal + "[magnetization]\nopening_angle = 1\n").magnetization.openingAngle == 1.0);
    CHECK(scene(kMinimal + "[magnetization]\nopening_angle = 0.05\n").magnetization.openingAngle == 0.05);
    for (const char* bad : {"1.2", "0.01", "0", "-0.5"})
        CHECK_THAT(sceneError(kMinimal + "[magnetization]\nopening_angle = " + bad + "\n"),
                   Contains("magnetization.opening_angle: must be in [0.05, 1]"));
}

TEST_CASE("magnetization.curve_fit chooses what the body force's curve is fitted to", "[scene]")
{
    CHECK_NOTHROW(scene(kMinimal + "[magnetization]\ncurve_fit = \"free_surface\"\n"));
    CHECK_THAT(sceneError(kMinimal + "[magnetization]\ncurve_fit = \"boundary\"\n"), Contains("retired"));
    CHECK_THAT(sceneError(kMinimal + "[magnetization]\ncurve_fit = \"surface\"\n"), Contains("curve_fit"));
}

TEST_CASE("magnetization.smoothing selects the particle model", "[scene]")
{
    CHECK(scene(kMinimal).magnetization.smoothing == 2.5); // smoothed dipoles by default
    CHECK(scene(kMinimal + "[magnetization]\nsmoothing = 3\n").magnetization.smoothing == 3.0);
    CHECK(scene(kMinimal + "[magnetization]\nsmoothing = 0\n").magnetization.smoothing == 0.0); // spheres
    CHECK_THAT(sceneError(kMinimal + "[magnetization]\nsmoothing = 0.5\n"),
               Contains("magnetization.smoothing: must be 0 (uniformly magnetized spheres) or in [1, 6]"));
}

TEST_CASE("magnetization.local_correction switches the smoothed model's local correction", "[scene]")
{
    CHECK_FALSE(scene(kMinimal).magnetization.localCorrection); // off by default
    CHECK(scene(kMinimal + "[magnetization]\nlocal_correction = true\n").magnetization.localCorrection);
    CHECK_THAT(sceneError(kMinimal + "[magnetization]\nlocal_correction = 1\n"), Contains("magnetization.local_correction"));
}

TEST_CASE("a table header with three brackets is a syntax error on its line (fuzz finding)", "[scene]")
{
    // toml++ 3.3.0 asserts on it in a build with assertions; the library Ferro links reports
    // the error, as here (tests/fuzz/corpus/scene holds the input the fuzzer found).
    CHECK_THAT(sceneError("[fluid]\n[[[fluid.block]]\n"), Contains("t.toml:2: ") && Contains("saw '['"));
    // In an override the same text is no TOML value, so it is taken as a string.
    CHECK_THAT(sceneError(kMinimal, {"a=1\n[[[b]"}), Contains("--set a:1: a: unknown section"));
    // toml++ 3.3.0 reaches __builtin_unreachable() deciding whether U+00A1 at the start of a
    // line is white space; Debian's build of it says no, and the error names the character.
    CHECK_THAT(sceneError("\xc2\xa1 = 1\n"), Contains("t.toml:1: ") && Contains("saw '\xc2\xa1'"));
}

TEST_CASE("scene errors quoting a line break stay one line (fuzz finding)", "[scene]")
{
    // toml++ quotes the character it saw, here the line break after "i".
    const std::string syntax = sceneError("[shot]\nfps = i\n");
    CHECK(syntax.find_first_of("\r\n") == std::string::npos);
    CHECK_THAT(syntax, Contains("t.toml:2: ") && Contains("\\n"));
    // A quoted key may hold any character; the message shows it escaped.
    const std::string key = sceneError(kMinimal + "[shot]\n\"a\\nb\\r\" = 1\n");
    CHECK(key.find_first_of("\r\n") == std::string::npos);
    CHECK_THAT(key, Contains("shot.a\\nb\\r: unknown key"));
}

TEST_CASE("a stage's scene inputs are exactly the keys its parser read, with their values after --set", "[scene]")
{
    // scripts/shot.mk stamps each stage with this text (--print-scene-inputs): a value the
    // parser read must show, an unread section must not, and a default is an input too.
    SceneDocument doc = SceneDocument::parse("[shot]\nfps = 24\nduration = 3.0\n[render]\nwidth = 64\n", "t.toml",
                                             {"shot.fps=25"});
    doc.recordReads();
    CHECK(parseShotFps(doc) == 25.0);
    CHECK(doc.readsText() == "shot.fps = 25\n");

    SceneDocument full = SceneDocument::parse("[shot]\nfps = 24\n[[fluid.block]]\nmin = [0, 0, 0]\nmax = [0.01, 0.01, 0.01]\n"
                                              "count = 10\n[render]\nwidth = 64\n",
                                              "t.toml");
    full.recordReads();
    const SimScene scene = parseSimScene(full, SceneUse::PerFrame);
    const std::string text = full.readsText();
    CHECK(text.find("shot.fps = 24\n") != std::string::npos);
    CHECK(text.find("shot.duration") == std::string::npos);          // PerFrame: not the shot's length
    CHECK(text.find("fluid.block[0].count = 10\n") != std::string::npos);
    CHECK(text.find("fluid.rest_density = (absent)\n") != std::string::npos);
    CHECK(text.find("render.") == std::string::npos);                // not ferro-sim's section
    CHECK(scene.shot.fps == 24.0);

    SceneDocument quiet = SceneDocument::parse("[shot]\nfps = 24\n", "t.toml");
    parseShotFps(quiet);
    CHECK(quiet.readsText().empty()); // not recording
}

TEST_CASE("the key table names each key's type, range and default as its getter checks them", "[scene]")
{
    // The scene reference (docs/reference/scene.md) is made from this table: the outermost
    // getter wins (positive() over the number() it calls), a present key still shows the
    // default it would have had, and required keys say so.
    SceneDocument doc = SceneDocument::parse("[t]\na = 2.5\nmode = \"b\"\nv = [1, 2, 3]\n", "t.toml");
    doc.recordReads();
    const TableReader t = doc.section("t");
    CHECK(t.positive("a", 1.0) == 2.5);
    CHECK(t.nonNegative("b", 0.25) == 0.25);
    CHECK(t.integerInRange("n", 3, 1, 9) == 3);
    CHECK(t.choice("mode", {"a", "b"}, "a") == "b");
    CHECK(t.boolean("flag", true));
    CHECK(t.vec3("v") == Vec3d(1, 2, 3));
    CHECK_FALSE(t.has("raw"));
    CHECK(doc.keySpecsText() == "t.a\tnumber > 0\t1\n"
                                "t.b\tnumber >= 0\t0.25\n"
                                "t.flag\tboolean\ttrue\n"
                                "t.mode\tone of \"a\", \"b\"\t\"a\"\n"
                                "t.n\tinteger in [1, 9]\t3\n"
                                "t.raw\t-\t-\n"
                                "t.v\t[x, y, z]\trequired\n");
}

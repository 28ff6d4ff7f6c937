#include "sim/scene/SimSceneFile.hpp"

#include "sim/magnets/MagnetScene.hpp"

#include <algorithm>
#include <climits>

namespace ferro {

const std::vector<std::string>& shotSceneSections()
{
    // The file format's table of sections: one place, so a misspelt section ([surfce])
    // is refused by whichever stage reads the file first. Each stage parses its own.
    static const std::vector<std::string> sections = {
        "shot", "fluid", "container", "sim",   // ferro-sim: SimSceneFile.cpp
        "magnets", "magnetization",            // sim/magnets/MagnetScene.cpp
        "solids",                              // sim/solids/SolidScene.cpp
        "surface",                             // surface/SurfaceParams.cpp
        "spikes",                              // spikes/SpikeParams.cpp
        "render"};                             // povray/RenderParams.cpp
    return sections;
}

namespace {

double readFps(const TableReader& r)
{
    return r.positive("fps", ShotParams{}.fps);
}

ShotParams parseShot(const SceneDocument& doc)
{
    TableReader r = doc.section("shot");
    ShotParams p;
    p.fps = readFps(r);
    p.duration = r.positive("duration", p.duration);
    p.preroll = r.nonNegative("preroll", p.preroll);
    p.prerollRestSpeed = r.nonNegative("preroll_rest_speed", p.prerollRestSpeed);
    p.particleCache = r.choice("particle_cache", {"full", "compact"}, "full") == "compact"
                          ? ShotParams::ParticleCache::Compact
                          : ShotParams::ParticleCache::Full;
    p.fullEvery = r.integerInRange("full_every", p.fullEvery, 1, kMaxFrame);
    // Frame numbers are ints with seven digits in file names: blame the key that is
    // further from its default (the one the user most likely set).
    const double frames = p.duration * p.fps;
    if (!(frames + 0.5 < kMaxFrame + 1.0)) {
        const ShotParams def;
        const std::string key = p.fps / def.fps > p.duration / def.duration ? "fps" : "duration";
        r.fail(key, "duration * fps makes " + formatNumber(frames) + " frames, more than " +
                        std::to_string(kMaxFrame) + " (got duration " + formatNumber(p.duration) + " s, fps " +
                        formatNumber(p.fps) + ")");
    }
    r.finish();
    return p;
}

FluidBlock parseBlock(const TableReader& r)
{
    FluidBlock b;
    b.where = r.where();
    if (r.choice("shape", {"box", "cylinder"}, "box") == "box") {
        b.shape = FluidBlock::Shape::Box;
        r.box("min", "max", b.min, b.max);
    } else {
        b.shape = FluidBlock::Shape::Cylinder;
        b.center = r.vec3("center", b.center);
        b.radius = r.positive("radius");
        b.height = r.positive("height");
    }
    b.velocity = r.vec3("velocity", b.velocity);
    b.count = r.integer("count", b.count);
    if (b.count < 0)
        r.fail("count", "must be >= 0 (got " + std::to_string(b.count) + ")");
    r.finish();
    return b;
}

FluidParams parseFluid(const SceneDocument& doc)
{
    TableReader r = doc.section("fluid");
    FluidParams p;
    p.restDensity = r.positive("rest_density", p.restDensity);
    p.viscosity = r.nonNegative("viscosity", p.viscosity);
    const std::string method = r.choice("viscosity_method", {"auto", "explicit", "implicit"}, "auto");
    p.viscosityMethod = method == "explicit"   ? FluidParams::ViscosityMethod::Explicit
                        : method == "implicit" ? FluidParams::ViscosityMethod::Implicit
                                               : FluidParams::ViscosityMethod::Auto;
    p.surfaceTension = r.nonNegative("surface_tension", p.surfaceTension);
    p.viscosityModel = r.string("viscosity_model", p.viscosityModel);
    p.viscosityModelWhere = r.where("viscosity_model");
    p.surfaceTensionModel = r.string("surface_tension_model", p.surfaceTensionModel);
    p.surfaceTensionModelWhere = r.where("surface_tension_model");
    p.spacing = r.nonNegative("spacing", p.spacing);
    for (const TableReader& block : r.tables("block"))
        p.blocks.push_back(parseBlock(block));
    if (p.blocks.empty())
        r.fail("block", "at least one [[fluid.block]] is required");
    // The particle size comes from the spacing or, failing that, from a block's count.
    bool counted = std::any_of(p.blocks.begin(), p.blocks.end(), [](const FluidBlock& b) { return b.count > 0; });
    if (p.spacing == 0 && !counted)
        r.fail("spacing", "must be > 0 unless a [[fluid.block]] has count > 0");
    r.finish();
    return p;
}

ContainerParams parseContainer(const SceneDocument& doc)
{
    TableReader r = doc.section("container");
    ContainerParams p;
    // Only the chosen type's keys are read, so finish() rejects the others: a dish
    // radius left in a box container is a mistake, not something to ignore silently.
    const std::string type = r.choice("type", {"none", "box", "dish", "mesh"}, "none");
    if (type == "box") {
        p.type = ContainerParams::Type::Box;
        r.box("min", "max", p.min, p.max);
        p.closedTop = r.boolean("closed_top", p.closedTop);
        p.periodicSides = r.boolean("periodic_sides", p.periodicSides);
    } else if (type == "dish") {
        p.type = ContainerParams::Type::Dish;
        p.center = r.vec3("center", p.center);
        p.radius = r.positive("radius");
        p.height = r.positive("height");
    } else if (type == "mesh") {
        p.type = ContainerParams::Type::Mesh;
        p.meshFile = r.path("file");
        p.meshScale = r.positive("scale", p.meshScale);
        p.meshTranslate = r.vec3("translate", p.meshTranslate);
        p.fluidInside = r.choice("fluid_side", {"outside", "inside"}, "outside") == "inside";
        if (r.has("bounds_min") || r.has("bounds_max")) {
            p.hasBounds = true;
            r.box("bounds_min", "bounds_max", p.boundsMin, p.boundsMax);
        }
    }
    p.wallFriction = r.nonNegative("wall_friction", p.wallFriction);
    r.finish();
    return p;
}

SolverParams parseSolver(const SceneDocument& doc)
{
    TableReader r = doc.section("sim");
    SolverParams p;
    p.pressureSolver = r.string("solver", p.pressureSolver);
    p.pressureSolverWhere = r.where("solver");
    p.gravity = r.vec3("gravity", p.gravity);
    p.cfl = r.number("cfl", p.cfl);
    if (!(p.cfl > 0 && p.cfl <= 1))
        r.fail("cfl", "must be in (0, 1] (got " + formatNumber(p.cfl) + ")");
    p.maxDt = r.positive("max_dt", p.maxDt);
    p.minDt = r.positive("min_dt", p.minDt);
    if (!(p.minDt < p.maxDt))
        r.fail("min_dt", "must be < sim.max_dt (got " + formatNumber(p.minDt) + " >= " + formatNumber(p.maxDt) + ")");
    p.artificialViscosity = r.numberInRange("artificial_viscosity", p.artificialViscosity, 0, 1);
    p.viscosityTolerance = r.number("viscosity_tolerance", p.viscosityTolerance);
    if (!(p.viscosityTolerance > 0 && p.viscosityTolerance < 1))
        r.fail("viscosity_tolerance", "must be in (0, 1) (got " + formatNumber(p.viscosityTolerance) + ")");
    p.viscosityMaxIterations = r.integerInRange("viscosity_max_iterations", p.viscosityMaxIterations, 1, INT_MAX);
    p.threads = r.integerInRange("threads", p.threads, 0, INT_MAX);
    p.maxSpeed = r.nonNegative("max_speed", p.maxSpeed);
    // The rest belongs to the pressure solver, whose registry row reads and checks it
    // (unknown keys included) when the simulation is made.
    p.solverKeys = doc.subset("sim", r.unread());
    return p;
}

} // namespace

SimScene parseSimScene(const SceneDocument& doc, SceneUse use)
{
    doc.checkSections(shotSceneSections());
    SimScene scene;
    scene.path = doc.path();
    if (use == SceneUse::Simulate)
        scene.shot = parseShot(doc);
    else
        scene.shot.fps = readFps(doc.section("shot"));
    scene.fluid = parseFluid(doc);
    scene.container = parseContainer(doc);
    scene.solver = parseSolver(doc);
    scene.magnets = parseMagnets(doc);
    scene.magnetization = parseMagnetization(doc);
    scene.solids = parseSolids(doc);
    for (size_t k = 0; k < scene.solids.size(); ++k)
        if (use == SceneUse::Simulate && scene.solids[k].moves())
            throw SceneError(scene.path + ": solids[" + std::to_string(k) +
                             "].keys: ferro-sim keeps solids still for now (a keyed solid that moves is not simulated); key only a still pose");
    return scene;
}

double parseShotFps(const SceneDocument& doc)
{
    doc.checkSections(shotSceneSections());
    return readFps(doc.section("shot"));
}

SimScene loadSimScene(const std::string& path, const std::vector<std::string>& overrides)
{
    return parseSimScene(SceneDocument::load(path, overrides));
}

std::shared_ptr<const SceneDocument> solverKeysFromText(const std::string& keys, const std::string& name)
{
    return std::make_shared<SceneDocument>(SceneDocument::parse("[sim]\n" + keys + "\n", name));
}

} // namespace ferro

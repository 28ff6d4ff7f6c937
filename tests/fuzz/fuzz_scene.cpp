// Fuzz target: the scene file with --set overrides, through every section parser a stage
// runs on it (ferro-sim's parseSimScene and fingerprint, ferro-surface's [surface],
// ferro-spikes' [spikes], ferro-pov's [render]).
//
// Input encoding: the TOML text, optionally followed by a line that is exactly `%%`; each
// line after it is one `--set` argument (verbatim, "\r\n" or "\n" line ends). Without a
// `%%` line the whole input is the TOML text and there are no overrides.
//
// The one documented error is SceneError; numbers the parsers return are finite (TOML
// allows nan and inf, the scene format does not) and directions are unit vectors.
#include "tests/fuzz/FuzzTarget.hpp"

#include "povray/RenderParams.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimSceneFile.hpp"
#include "spikes/SpikeParams.hpp"
#include "surface/SurfaceParams.hpp"

#include <cmath>
#include <optional>
#include <string>
#include <vector>

using namespace ferro;
using ferro::fuzz::finding;

namespace {

void finite(double v, const char* what) {
    if (!std::isfinite(v)) finding(std::string(what) + " is not finite: " + formatNumber(v));
}

void finite(const Vec3d& v, const char* what) {
    if (!v.allFinite()) finding(std::string(what) + " is not finite: " + formatVec(v));
}

void unit(const Vec3d& v, const char* what) {
    finite(v, what);
    if (!(std::abs(v.norm() - 1.0) < 1e-9)) finding(std::string(what) + " is not a unit vector: " + formatVec(v));
}

void check(const SimScene& s) {
    finite(s.shot.fps, "shot.fps");
    finite(s.shot.duration, "shot.duration");
    if (s.shot.frameCount() < 0 || s.shot.frameCount() > kMaxFrame) finding("shot frame count out of range");
    const FluidParams& f = s.fluid;
    finite(f.restDensity, "fluid.rest_density");
    finite(f.viscosity, "fluid.viscosity");
    finite(f.surfaceTension, "fluid.surface_tension");
    finite(f.spacing, "fluid.spacing");
    if (f.blocks.empty()) finding("no fluid block");
    for (const FluidBlock& b : f.blocks) {
        finite(b.min, "block.min");
        finite(b.max, "block.max");
        if (b.shape == FluidBlock::Shape::Box && !(b.max.array() > b.min.array()).all()) finding("empty block box");
        finite(b.center, "block.center");
        finite(b.radius, "block.radius");
        finite(b.height, "block.height");
        finite(b.velocity, "block.velocity");
        if (b.count < 0) finding("negative block count");
    }
    const ContainerParams& c = s.container;
    finite(c.min, "container.min");
    finite(c.max, "container.max");
    finite(c.center, "container.center");
    finite(c.radius, "container.radius");
    finite(c.height, "container.height");
    finite(c.meshScale, "container.scale");
    finite(c.meshTranslate, "container.translate");
    finite(c.boundsMin, "container.bounds_min");
    finite(c.boundsMax, "container.bounds_max");
    finite(c.wallFriction, "container.wall_friction");
    const SolverParams& p = s.solver;
    finite(p.gravity, "sim.gravity");
    finite(p.cfl, "sim.cfl");
    finite(p.maxDt, "sim.max_dt");
    finite(p.minDt, "sim.min_dt");
    // The pressure solvers' own keys (sim.sound_speed, sim.max_density_error, ...) are read
    // when the simulation is made, by their registry rows in sim/sph, through the same
    // TableReader getters (positive, nonNegative) this target checks on every other key.
    finite(p.artificialViscosity, "sim.artificial_viscosity");
    for (const MagnetTrack& t : s.magnets) {
        finite(t.base.position, "magnets.position");
        unit(t.base.direction, "magnets.direction");
        finite(t.base.strength, "magnets strength");
        finite(t.base.length, "magnets.length");
        finite(t.base.radius, "magnets.radius");
        finite(t.base.softening, "magnets.softening");
        for (const MagnetKeyframe& k : t.keys) {
            finite(k.time, "magnets.keys.time");
            finite(k.position, "magnets.keys.position");
            unit(k.direction, "magnets.keys.direction");
            finite(k.strength, "magnets.keys strength");
        }
    }
    const MagnetizationParams& m = s.magnetization;
    finite(m.susceptibility, "magnetization.susceptibility");
    finite(m.saturation, "magnetization.saturation");
    finite(m.tolerance, "magnetization.tolerance");
    finite(m.openingAngle, "magnetization.opening_angle");
}

void check(const SurfaceParams& p) {
    finite(p.spacing, "surface.spacing");
    finite(p.voxelSize, "surface.voxel_size");
    finite(p.kernelRadius, "surface.kernel_radius");
    finite(p.neighborRadius, "surface.neighbor_radius");
    finite(p.kr, "surface.k_r");
    finite(p.ks, "surface.k_s");
    finite(p.kn, "surface.k_n");
    finite(p.lambda, "surface.lambda");
    finite(p.isoLevel, "surface.iso_level");
    finite(p.adaptivity, "surface.adaptivity");
}

void check(const SpikeParams& p) {
    finite(p.alpha, "spikes.alpha");
    finite(p.beta, "spikes.beta");
    finite(p.minSpacing, "spikes.min_spacing");
    finite(p.maxSpacing, "spikes.max_spacing");
    finite(p.maxAspect, "spikes.max_aspect");
    finite(p.sharpness, "spikes.sharpness");
    finite(p.magnetizationFade, "spikes.magnetization_fade");
    finite(p.wallMargin, "spikes.wall_margin");
    finite(p.wallFade, "spikes.wall_fade");
    finite(p.resolution, "spikes.resolution");
    finite(p.ambientDensity, "spikes.ambient_density");
    finite(p.origin, "spikes.origin");
    finite(p.orientation, "spikes.orientation");
    finite(p.maxTilt, "spikes.max_tilt");
}

void check(const RenderParams& p) {
    finite(p.cameraPosition, "render.camera_position");
    finite(p.cameraTarget, "render.camera_target");
    // The parser promises a usable view direction: the export normalizes this.
    unit(Vec3d((p.cameraTarget - p.cameraPosition).normalized()), "render view direction");
    finite(p.cameraAngle, "render.camera_angle");
    finite(p.antialiasThreshold, "render.antialias_threshold");
    finite(p.magnetLength, "render.magnet_length");
    finite(p.magnetRadius, "render.magnet_radius");
}

/// A SceneError is the documented way to refuse the input; its message is one line.
void refused(const SceneError& e) {
    fuzz::requireOneLine(e);
}

/// Runs one stage's parser on the document.
template <class Parse>
void stage(Parse parse) {
    try {
        check(parse());
    } catch (const SceneError& e) {
        refused(e);
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string input(reinterpret_cast<const char*>(data), size);
    std::string text = input;
    std::vector<std::string> overrides;
    bool separated = false;
    for (size_t b = 0;;) {
        const size_t e = input.find('\n', b);
        std::string line = input.substr(b, e == std::string::npos ? std::string::npos : e - b);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (!separated && line == "%%") {
            text = input.substr(0, b);
            separated = true;
        } else if (separated && (e != std::string::npos || !line.empty())) {
            overrides.push_back(line);
        }
        if (e == std::string::npos) break;
        b = e + 1;
    }

    std::optional<SceneDocument> doc;
    try {
        doc.emplace(SceneDocument::parse(text, "fuzz.toml", overrides));
    } catch (const SceneError& e) {
        refused(e);
        return 0;
    }
    (void)doc->fingerprint();
    stage([&] { return parseSimScene(*doc); });
    stage([&] { return parseSurfaceParams(*doc); });
    stage([&] { return parseSpikeParams(*doc); });
    stage([&] { return parseRenderParams(*doc); });
    return 0;
}

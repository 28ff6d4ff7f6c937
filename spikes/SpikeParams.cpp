#include "spikes/SpikeParams.hpp"

#include "sim/core/SceneDocument.hpp"

namespace ferro {

SpikeParams parseSpikeParams(const SceneDocument& doc)
{
    TableReader r = doc.section("spikes");
    SpikeParams p;
    p.enabled = r.boolean("enabled", p.enabled);
    p.spacing = r.choice("spacing", {"paper", "physical"}, "paper") == "physical" ? SpikeParams::Spacing::Physical
                                                                                 : SpikeParams::Spacing::Paper;
    p.alpha = r.positive("alpha", p.alpha);
    p.beta = r.nonNegative("beta", p.beta);
    p.minSpacing = r.positive("min_spacing", p.minSpacing);
    p.maxSpacing = r.positive("max_spacing", p.maxSpacing);
    if (p.maxSpacing < p.minSpacing)
        r.fail("max_spacing", "must be >= min_spacing");
    p.maxAspect = r.positive("max_aspect", p.maxAspect);
    p.sharpness = r.numberInRange("sharpness", p.sharpness, 1, 8);
    p.magnetizationFade = r.positive("magnetization_fade", p.magnetizationFade);
    p.growthTime = r.nonNegative("growth_time", p.growthTime);
    p.wallMargin = r.nonNegative("wall_margin", p.wallMargin);
    p.wallFade = r.nonNegative("wall_fade", p.wallFade);
    p.resolution = r.numberInRange("resolution", p.resolution, 3, 100);
    p.remeshIterations = r.integerInRange("remesh_iterations", p.remeshIterations, 0, 20);
    p.ambientDensity = r.nonNegative("ambient_density", p.ambientDensity);
    p.hasOrigin = r.has("origin");
    p.origin = r.vec3("origin", p.origin);
    p.orientation = r.number("orientation", p.orientation);
    p.maxTilt = r.numberInRange("max_tilt", p.maxTilt, 0, 80);   // degrees
    p.particleField = r.boolean("particle_field", p.particleField);
    p.conserveVolume = r.boolean("conserve_volume", p.conserveVolume);
    r.finish();
    return p;
}

} // namespace ferro

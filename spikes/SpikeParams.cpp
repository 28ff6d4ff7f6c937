#include "spikes/SpikeParams.hpp"

#include "sim/core/Keyframes.hpp"
#include "sim/core/SceneDocument.hpp"

#include <climits>
#include <limits>

namespace ferro {

namespace {

// The ranges of the animated keys, shared by [spikes] and [[spikes.keys]].
double heightGain(const TableReader& r, double def) { return r.numberInRange("height_gain", def, 0, 4); }
double sharpness(const TableReader& r, double def) { return r.numberInRange("sharpness", def, 1, 8); }
double jitter(const TableReader& r, double def) { return r.numberInRange("jitter", def, 0, 0.35); }
double defects(const TableReader& r, double def) { return r.numberInRange("defects", def, 0, 0.9); }
double squareness(const TableReader& r, double def) { return r.numberInRange("squareness", def, 0, 1); }

} // namespace

SpikeParams spikeParamsAt(const SpikeParams& p, double t)
{
    SpikeParams q = p;
    if (p.keys.empty()) return q;
    q.heightGain = monotoneKeyValue(p.keys, t, [](const SpikeKey& k) { return k.heightGain; }, p.heightGain);
    q.sharpness = monotoneKeyValue(p.keys, t, [](const SpikeKey& k) { return k.sharpness; }, p.sharpness);
    q.jitter = monotoneKeyValue(p.keys, t, [](const SpikeKey& k) { return k.jitter; }, p.jitter);
    q.defects = monotoneKeyValue(p.keys, t, [](const SpikeKey& k) { return k.defects; }, p.defects);
    q.squareness = monotoneKeyValue(p.keys, t, [](const SpikeKey& k) { return k.squareness; }, p.squareness);
    return q;
}

SpikeParams parseSpikeParams(const SceneDocument& doc)
{
    TableReader r = doc.section("spikes");
    SpikeParams p;
    p.enabled = r.boolean("enabled", p.enabled);
    const std::string spacing = r.choice("spacing", {"paper", "physical", "growth"}, "paper");
    p.spacing = spacing == "physical" ? SpikeParams::Spacing::Physical
                : spacing == "growth" ? SpikeParams::Spacing::Growth
                                      : SpikeParams::Spacing::Paper;
    p.alpha = r.positive("alpha", p.alpha);
    p.beta = r.nonNegative("beta", p.beta);
    p.minSpacing = r.positive("min_spacing", p.minSpacing);
    p.maxSpacing = r.positive("max_spacing", p.maxSpacing);
    if (p.maxSpacing < p.minSpacing)
        r.fail("max_spacing", "must be >= min_spacing");
    p.maxAspect = r.positive("max_aspect", p.maxAspect);
    p.sharpness = sharpness(r, p.sharpness);
    p.heightGain = heightGain(r, p.heightGain);
    p.jitter = jitter(r, p.jitter);
    p.defects = defects(r, p.defects);
    p.squareness = squareness(r, p.squareness);
    p.seed = uint32_t(r.integerInRange("seed", 0, 0, INT_MAX));
    p.magnetizationFade = r.positive("magnetization_fade", p.magnetizationFade);
    p.heightCurve = r.choice("height_curve", {"fade", "bifurcation"}, "fade") == "bifurcation"
                        ? SpikeParams::HeightCurve::Bifurcation
                        : SpikeParams::HeightCurve::Fade;
    p.lowerThreshold = r.numberInRange("lower_threshold", p.lowerThreshold, 0.5, 1.0);
    p.growthTime = r.nonNegative("growth_time", p.growthTime);
    p.responseTime = r.numberInRange("response_time", p.responseTime, 0, 5);
    p.wallMargin = r.nonNegative("wall_margin", p.wallMargin);
    p.filmThickness = r.nonNegative("film_thickness", p.filmThickness);
    p.wallFade = r.nonNegative("wall_fade", p.wallFade);
    p.resolution = r.numberInRange("resolution", p.resolution, 3, 100);
    p.remeshIterations = r.integerInRange("remesh_iterations", p.remeshIterations, 0, 20);
    p.ambientDensity = r.nonNegative("ambient_density", p.ambientDensity);
    auto lattice = [](const TableReader& t, SpikeParams::Lattice def) {
        return t.choice("pattern", {"hexagon", "square"}, def == SpikeParams::Lattice::Square ? "square" : "hexagon") ==
                       "square"
                   ? SpikeParams::Lattice::Square
                   : SpikeParams::Lattice::Hexagon;
    };
    p.lattice = lattice(r, p.lattice);
    for (const TableReader& m : r.tables("magnets")) {
        if (!m.has("magnet"))
            m.fail("magnet", "every [[spikes.magnets]] names the magnet it overrides (its index in [[magnets]], from 0)");
        const int index = m.integerInRange("magnet", 0, 0, INT_MAX);
        if (!m.has("pattern"))
            m.fail("pattern", "every [[spikes.magnets]] gives its magnet a pattern (\"hexagon\" or \"square\")");
        for (const auto& [other, l] : p.magnetLattice)
            if (other == index) m.fail("magnet", "magnet " + std::to_string(index) + " is overridden twice");
        p.magnetLattice.emplace_back(index, lattice(m, p.lattice));
        m.finish();
    }
    p.hasOrigin = r.has("origin");
    p.origin = r.vec3("origin", p.origin);
    p.orientation = r.number("orientation", p.orientation);
    p.maxTilt = r.numberInRange("max_tilt", p.maxTilt, 0, 80);   // degrees
    p.particleField = r.boolean("particle_field", p.particleField);
    p.conserveVolume = r.boolean("conserve_volume", p.conserveVolume);
    for (const TableReader& k : r.keyframes("keys", "spikes.keys")) {
        SpikeKey key;
        key.time = k.nonNegative("time", 0.0);
        key.heightGain = heightGain(k, p.heightGain);
        key.sharpness = sharpness(k, p.sharpness);
        key.jitter = jitter(k, p.jitter);
        key.defects = defects(k, p.defects);
        key.squareness = squareness(k, p.squareness);
        k.finish();
        p.keys.push_back(key);
    }
    r.finish();
    return p;
}

} // namespace ferro

#include "sim/magnets/MagnetScene.hpp"

#include <cmath>
#include <limits>

namespace ferro {

namespace {

// The strength key of `r`, or `def` if absent; refused beyond the kind's maxStrength.
double strength(const TableReader& r, const MagnetKindInfo& info, double def)
{
    const double s = r.number(info.strengthKey, def);
    if (!(std::abs(s) <= info.maxStrength))
        r.fail(info.strengthKey, "must be within +-" + formatNumber(info.maxStrength) + " " + info.strengthUnit +
                                     " for a " + info.name + " magnet (got " + formatNumber(s) +
                                     "; stronger fields overflow the solver's floats)");
    return s;
}

MagnetTrack parseMagnet(const TableReader& r)
{
    MagnetTrack track;
    Magnet& m = track.base;
    // The kind's row in the table says which keys it reads.
    const MagnetKindInfo& info = *findMagnetKind(r.choice("kind", magnetKindNames(), "dipole"));
    m.kind = info.kind;
    if (info.positioned)
        m.position = r.vec3("position", m.position);
    m.direction = r.unitVector("direction", m.direction);
    m.strength = strength(r, info, 0.0);
    if (info.usesLength)
        m.length = r.positive("length");
    if (info.usesRadius)
        m.radius = r.positive("radius");
    if (info.usesTurns)
        m.turns = r.numberInRange("turns", m.turns, 1, kMostTurns);
    if (info.positioned)
        m.softening = r.nonNegative("softening", m.softening);
    for (const TableReader& k : r.keyframes("keys", "magnets.keys")) {
        MagnetKeyframe key;
        key.time = k.nonNegative("time", 0.0);
        key.position = info.positioned ? k.vec3("position", m.position) : m.position;
        key.direction = k.unitVector("direction", m.direction);
        key.strength = strength(k, info, m.strength);
        k.finish();
        track.keys.push_back(key);
    }
    r.finish();
    return track;
}

} // namespace

std::vector<MagnetTrack> parseMagnets(const SceneDocument& doc)
{
    std::vector<MagnetTrack> tracks;
    for (const TableReader& r : TableReader(doc, doc.root(), "").tables("magnets"))
        tracks.push_back(parseMagnet(r));
    return tracks;
}

MagnetizationParams parseMagnetization(const SceneDocument& doc)
{
    TableReader r = doc.section("magnetization");
    MagnetizationParams p;
    p.susceptibility = r.nonNegative("susceptibility", p.susceptibility);
    p.saturation = r.nonNegative("saturation", p.saturation);
    const std::string solver = r.choice("solver", {"auto", "external", "direct", "tree"}, "auto");
    p.solver = solver == "external" ? MagnetizationParams::Solver::External
             : solver == "direct" ? MagnetizationParams::Solver::Direct
             : solver == "tree" ? MagnetizationParams::Solver::Tree : MagnetizationParams::Solver::Auto;
    p.tolerance = r.positive("tolerance", p.tolerance);
    // The tree clamps the angle to [0.05, 1] (DipoleTree::build); a value outside used to be
    // changed without a word. Above 1 cells as large as their distance would be expanded
    // (1.0 already gives 0.3 % RMS field error on a settled pool, tests/bench/report); below
    // 0.05 it is the direct sum at a tree's overhead.
    p.openingAngle = r.numberInRange("opening_angle", p.openingAngle, 0.05, 1);
    p.smoothing = r.number("smoothing", p.smoothing);
    if (!(p.smoothing == 0 || (p.smoothing >= 1 && p.smoothing <= 6)))
        r.fail("smoothing", "must be 0 (uniformly magnetized spheres) or in [1, 6] particle spacings (got " +
                                formatNumber(p.smoothing) + ")");
    p.localCorrection = r.boolean("local_correction", p.localCorrection);
    p.resolveEvery = r.integerInRange("resolve_every", p.resolveEvery, 0, INT_MAX);
    p.maxIterations = r.integerInRange("max_iterations", p.maxIterations, 1, 10000);
    if (r.has("induced_force"))
        r.fail("induced_force", "was replaced by force = \"body\" (the default: the magnets' field gradient) or "
                                "\"surface\" (the total field and the normal traction, as a surface pressure)");
    const std::string force = r.choice("force", {"body", "surface"}, "body");
    p.force = force == "body" ? MagnetizationParams::Force::Body : MagnetizationParams::Force::Surface;
    // The force's curve is fitted to the free surface. "boundary" (the floor and walls, the
    // default until 2026-12-02) missed the Bernoulli law by 13 % (chi0 0.5) and 39-44 % (1.5)
    // of the heap's rise against 4.4 / 4.5 %, and was retired on 2026-12-04.
    if (r.has("curve_fit") && r.string("curve_fit", "free_surface") == "boundary")
        r.fail("curve_fit", "\"boundary\" was retired (it missed the Bernoulli law by up to 44 % of the heap's rise); the force's curve is fitted to the free surface, remove the key");
    r.choice("curve_fit", {"free_surface"}, "free_surface");
    r.finish();
    return p;
}

} // namespace ferro

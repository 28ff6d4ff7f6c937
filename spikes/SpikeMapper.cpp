// The spike synthesis of SpikeMapper.hpp: addSpikes and its phases. Phase 3 (the lattice of
// tips) is in SpikeLattice.cpp, phase 4 (the refinement) in SpikeRefinement.cpp, phase 5 (the
// displacement) in SpikeDisplacement.cpp, the velocities in SpikeVelocity.cpp; the per-point
// fields in SurfaceFields.cpp.
#include "spikes/SpikeMapper.hpp"
#include "sim/core/Constants.hpp"

#include "spikes/SpikeDisplacement.hpp"
#include "spikes/SpikeLattice.hpp"
#include "spikes/SpikeRefinement.hpp"
#include "spikes/SpikeVelocity.hpp"
#include "spikes/SurfaceFields.hpp"
#include "spikes/SurfaceGeometry.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace ferro {

namespace {

// The result when there is nothing to displace: the input surface with vertex normals.
SpikeResult unchangedResult(SpikeResult res, const TriangleMesh& surface)
{
    res.refined = surface;
    res.mesh = surface;
    computeVertexNormals(res.mesh);
    res.volumeOut = res.volumeIn;
    return res;
}

// Phase 1 output, per vertex of the input surface.
struct InputRegion {
    std::vector<char> wetted; // 1 = wetted wall (SurfaceFields::wetted)
    std::vector<char> active; // 1 = spiky (SurfaceFields::spiky; never on the wetted wall)
};

// Phase 1: the wetted wall and the supercritical part of the input surface: where spikes
// stand, grow or sink at each free vertex (SurfaceFields::spiky, from the field there with the
// input's area-weighted normals: |M| above M_c of eq. 16, or the bifurcation's hysteresis).
InputRegion classifyInputSurface(const TriangleMesh& input, const SurfaceFields& fields)
{
    const size_t nIn = input.vertices.size();
    const std::vector<Vec3d> inputNormals = areaWeightedNormals(input);
    InputRegion region{std::vector<char>(nIn, 0), std::vector<char>(nIn, 0)};
    tbb::parallel_for(size_t(0), nIn, [&](size_t v) {
        const Vec3d x = toD(input.vertices[v]);
        region.wetted[v] = fields.wetted(x);
        if (region.wetted[v]) return;
        region.active[v] = fields.spiky(x, fields.field(x, inputNormals[v]));
    });
    return region;
}

// The length of the diagonal of the mesh's bounding box [m].
double boundingDiagonal(const TriangleMesh& mesh)
{
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const Vec3& v : mesh.vertices) {
        lo = lo.cwiseMin(toD(v));
        hi = hi.cwiseMax(toD(v));
    }
    return (hi - lo).norm();
}

// What placing the patterns needs (references, all outliving it).
struct PlacementContext {
    const SpikeInput& in;
    const SpikeParams& P;
    const SurfaceFields& fields;
    const FreeSurface& surface;
    const std::vector<char>& active; // per input vertex, from phase 1
    double diagonal;                 // of the input's bounding box [m]
};

// Where a magnet's axis (unit axisDir through its position; for a magnet without a position,
// through P.origin, else the container's centre, else the centroid of the supercritical
// vertices) meets the free surface nearest the anchor: x0 [m] and the normal n0 there. If the
// axis misses the fluid, the supercritical vertex where this magnet's field is strongest, with
// the normal of the free surface just above it (else `up`). False if there is no such vertex.
bool patternOrigin(const PlacementContext& c, const Magnet& magnet, const Vec3d& axisDir, const Vec3d& up, Vec3d& x0,
                   Vec3d& n0)
{
    const TriangleMesh& input = c.surface.mesh;
    const size_t nIn = input.vertices.size();
    Vec3d anchor = magnet.position;
    if (!magnetKindInfo(magnet.kind).positioned) {
        if (c.P.hasOrigin) {
            anchor = c.P.origin;
        } else if (c.in.fluid.hasCenter) {
            anchor = c.in.fluid.center;
        } else {
            Vec3d sum = Vec3d::Zero();
            size_t count = 0;
            for (size_t v = 0; v < nIn; ++v)
                if (c.active[v]) sum += toD(input.vertices[v]), ++count;
            anchor = sum / double(std::max<size_t>(count, 1));
        }
    }
    // A coat round a solid: the axis through the anchor often meets it twice at the same
    // distance (a uniform field across a cylinder through its axis); the tie goes to the hit
    // ahead along the axis, so the pattern does not change faces with the surface's noise.
    if (nearestFreeHit(c.surface, anchor, axisDir, std::numeric_limits<double>::max(), x0, n0,
                       c.in.fluid.solids != nullptr))
        return true;
    // The axis misses the fluid: anchor the pattern where this magnet's field is strongest.
    double best = -1;
    for (size_t v = 0; v < nIn; ++v) {
        if (!c.active[v]) continue;
        const double h = magnetField(magnet, toD(input.vertices[v])).squaredNorm();
        if (h > best) best = h, x0 = toD(input.vertices[v]);
    }
    if (best < 0) return false;
    n0 = up;
    Vec3d hit, normal;
    if (nearestFreeHit(c.surface, x0, up, 1e-3 * c.diagonal + 1e-9, hit, normal)) n0 = normal;
    return true;
}

// The tip spacing l [m], clamped to [P.minSpacing, P.maxSpacing]: eq. 15, l = alpha / |H(x0)|
// with |H0| [A/m] at the origin (SurfaceFields::fieldHistoryPeak: the strongest of the growth
// time's history), or the tip distance of a wavenumber k on the planform of that squareness:
// 2 pi / (k sin theta), theta = 60 + 30 squareness degrees between e1 and e2 (the lattice whose
// two shortest wave vectors have length k: 4 pi / (sqrt3 k) on a hexagon, 2 pi / k on a
// square); k the critical k_c = 2 pi / lambda_c, or the fastest-growing one at M0 [A/m] (the
// strongest |M| of the growth time) against Mc [A/m]. g [m/s^2].
double tipSpacing(const SpikeInput& in, const SpikeParams& P, double g, double H0, double M0, double Mc,
                  double squareness)
{
    double l = 0;
    if (P.spacing == SpikeParams::Spacing::Paper) {
        l = P.alpha / std::max(H0, 1e-30);
    } else {
        const double lambda = criticalWavelength(in.fluid.density - P.ambientDensity, g, in.fluid.surfaceTension);
        double k = lambda > 0 ? 2 * kPi / lambda : 0;
        if (P.spacing == SpikeParams::Spacing::Growth && std::isfinite(Mc) && Mc > 0) {
            SurfaceModes modes;
            modes.density = in.fluid.density;
            modes.deltaRho = in.fluid.density - P.ambientDensity;
            modes.gravity = g;
            modes.surfaceTension = in.fluid.surfaceTension;
            modes.viscosity = in.fluid.viscosity;
            modes.supercriticality = (M0 / Mc) * (M0 / Mc);
            k = fastestGrowingWavenumber(modes);
        }
        l = !(k > 0) ? 0.0 : squareness > 0 ? 2 * kPi / (k * std::sin(latticeAngle(squareness))) : tipSpacingForWavenumber(k);
    }
    return std::clamp(l, P.minSpacing, P.maxSpacing);
}

// The first lattice axis e1 (unit, tangent at the origin with unit normal n0): a fixed world
// direction, x (or y where n0 is near x) projected into the tangent plane, rotated by
// `orientation` [deg] about n0; so a still magnet gives the same tips in every frame.
Vec3d latticeAxis(const Vec3d& n0, double orientation)
{
    Vec3d ref = std::abs(n0.x()) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    Vec3d e1 = (ref - ref.dot(n0) * n0).normalized();
    const double phi = orientation * kPi / 180.0;
    e1 = std::cos(phi) * e1 + std::sin(phi) * n0.cross(e1);
    return e1;
}

// Phase 2: one pattern (info only, no tips yet) per magnet with a non-zero strength and
// direction whose origin (patternOrigin) is supercritical (|M| > Mc [A/m], eq. 16) and whose
// field there is at least 30 % of the magnets' summed |H|^2 (two coaxial magnets make one
// pattern); a pattern closer than either's spacing to an earlier one is dropped. g [m/s^2].
std::vector<Pattern> placePatterns(const PlacementContext& c, double g, double Mc)
{
    const SpikeInput& in = c.in;
    std::vector<Pattern> patterns;
    const Vec3d up = g > 0 ? Vec3d(-in.fluid.gravity / g) : Vec3d(0, 0, 1);
    for (size_t m = 0; m < in.magnets.size(); ++m) {
        const Magnet& magnet = in.magnets[m];
        const double dirNorm = magnet.direction.norm();
        if (magnet.strength == 0 || !(dirNorm > 0)) continue;
        const Vec3d axisDir = magnet.direction / dirNorm;
        Vec3d x0, n0;
        if (!patternOrigin(c, magnet, axisDir, up, x0, n0)) continue;
        const Vec3d H0 = c.fields.field(x0, n0);
        // The origin is the lattice's anchor, not its trigger: the pattern exists as soon as
        // any of the surface is supercritical (addSpikes returns early otherwise). A heap's
        // top can be less magnetized than its flanks; waiting for the origin to pass M_c let
        // the flanks' tips appear already 30 % tall, all in one frame.
        const double M0 = c.fields.magnetization(x0, H0);
        // The magnet must dominate its own origin (two coaxial magnets make one pattern).
        double total2 = 0;
        for (const Magnet& other : in.magnets) total2 += magnetField(other, x0).squaredNorm();
        if (magnetField(magnet, x0).squaredNorm() < 0.3 * total2) continue;

        Pattern pat;
        pat.info.magnet = int(m);
        pat.info.origin = x0;
        pat.info.normal = n0;
        pat.info.field = H0.norm();
        pat.info.magnetization = M0;
        pat.info.lattice = c.P.latticeOf(int(m));
        pat.info.squareness = c.P.squarenessOf(int(m));
        pat.info.spacing = tipSpacing(in, c.P, g, c.fields.fieldHistoryPeak(x0, n0, H0), M0, Mc, pat.info.squareness);
        pat.info.axis = latticeAxis(n0, c.P.orientation);
        bool duplicate = false;
        for (const Pattern& other : patterns)
            if ((other.info.origin - x0).norm() < std::max(other.info.spacing, pat.info.spacing)) duplicate = true;
        if (!duplicate) patterns.push_back(std::move(pat));
    }
    return patterns;
}

// Per vertex: the area of a third of each adjacent triangle [m^2].
std::vector<double> vertexAreas(const TriangleMesh& mesh);

// Phase 2-3 on a surface with solids: a pattern of its own (SpikePattern::region) for each part
// of the supercritical surface that no pattern reached. A magnet's pattern starts where its
// axis meets the surface and is traced along it, and on a dish that is where its heap stands;
// a sculpture gathers the field at its edges and tips, away from the axis and on both sides
// of a solid (a horizontal field across a steel cylinder makes two supercritical faces, one
// each side). Round by round: the supercritical free vertices farther than a spacing from
// every traced tip fall into connected parts (along the mesh's edges); the part with the
// largest area (at least l^2 / 2: room for a spike) seeds a pattern at its vertex nearest its
// centroid weighted by area and |H|, traced with the earlier patterns' tips kept clear
// (traceLattice). A centroid is an integral of the surface, so a surface's noise moves it
// little: the seed, and so the pattern, stays from frame to frame. Ties (a ring round a
// symmetric solid, whose centroid lies on its axis) go by distance in steps of l / 4, then
// by a fixed order of space. The magnet is the one whose own field is strongest at the seed;
// its planform and the spacing from the field there. At most kMostRegions patterns.
void addRegionPatterns(const PlacementContext& c, double g, double Mc, std::vector<Pattern>& patterns)
{
    constexpr int kMostRegions = 32;
    const TriangleMesh& input = c.surface.mesh;
    const size_t nV = input.vertices.size();
    const std::vector<Vec3d> normals = areaWeightedNormals(input);
    const std::vector<double> area = vertexAreas(input);
    std::vector<std::vector<uint32_t>> neighbours(nV);
    for (const auto& t : input.triangles)
        for (int k = 0; k < 3; ++k) {
            neighbours[t[size_t(k)]].push_back(t[size_t((k + 1) % 3)]);
            neighbours[t[size_t((k + 1) % 3)]].push_back(t[size_t(k)]);
        }
    // The field at every supercritical vertex, once (the solids' field is a sum over panels).
    std::vector<double> field(nV, 0.0);
    tbb::parallel_for(size_t(0), nV, [&](size_t v) {
        if (c.active[v]) field[v] = c.fields.field(toD(input.vertices[v]), normals[v]).norm();
    });
    auto covered = [&](const Vec3d& x) {
        for (const Pattern& p : patterns) {
            bool near = false;
            p.grid->forEachWithin(x, p.info.spacing, [&](uint32_t, double) { near = true; });
            if (near) return true;
        }
        return false;
    };
    for (int region = 1; region <= kMostRegions; ++region) {
        double l = std::numeric_limits<double>::infinity();
        for (const Pattern& p : patterns) l = std::min(l, p.info.spacing);
        std::vector<char> open(nV, 0);
        for (size_t v = 0; v < nV; ++v) open[v] = c.active[v] && field[v] > 0 && !covered(toD(input.vertices[v]));
        // The largest open part.
        std::vector<uint32_t> best, part;
        double bestArea = 0;
        std::vector<char> seen(nV, 0);
        for (size_t v0 = 0; v0 < nV; ++v0) {
            if (!open[v0] || seen[v0]) continue;
            part.assign(1, uint32_t(v0));
            seen[v0] = 1;
            double partArea = 0;
            for (size_t k = 0; k < part.size(); ++k) {
                partArea += area[part[k]];
                for (uint32_t u : neighbours[part[k]])
                    if (open[u] && !seen[u]) seen[u] = 1, part.push_back(u);
            }
            if (partArea > bestArea) bestArea = partArea, best = part;
        }
        if (best.empty() || (std::isfinite(l) && bestArea < 0.5 * l * l)) return;
        Vec3d centroid = Vec3d::Zero();
        double weight = 0;
        for (uint32_t v : best) {
            centroid += area[v] * field[v] * toD(input.vertices[v]);
            weight += area[v] * field[v];
        }
        centroid /= weight;
        const double step = std::isfinite(l) ? 0.25 * l : 1e-3;
        auto rank = [&](uint32_t v) { // smaller is better
            const Vec3d x = toD(input.vertices[v]);
            const Vec3d cell = (x / step).array().floor();
            return std::make_tuple(std::floor((x - centroid).norm() / step), cell.x(), cell.y(), cell.z());
        };
        uint32_t seed = best.front();
        for (uint32_t v : best)
            if (rank(v) < rank(seed)) seed = v;
        const Vec3d x0 = toD(input.vertices[seed]), n0 = normals[seed];
        int magnet = -1;
        double strongest = -1;
        for (size_t m = 0; m < c.in.magnets.size(); ++m) {
            if (c.in.magnets[m].strength == 0) continue;
            const double h = magnetField(c.in.magnets[m], x0).squaredNorm();
            if (h > strongest) strongest = h, magnet = int(m);
        }
        if (magnet < 0) return;
        const Vec3d H0 = c.fields.field(x0, n0);
        Pattern pat;
        pat.info.magnet = magnet;
        pat.info.region = region;
        pat.info.origin = x0;
        pat.info.normal = n0;
        pat.info.field = H0.norm();
        pat.info.magnetization = c.fields.magnetization(x0, H0);
        pat.info.lattice = c.P.latticeOf(magnet);
        pat.info.squareness = c.P.squarenessOf(magnet);
        pat.info.spacing = tipSpacing(c.in, c.P, g, c.fields.fieldHistoryPeak(x0, n0, H0), pat.info.magnetization, Mc,
                                      pat.info.squareness);
        pat.info.axis = latticeAxis(n0, c.P.orientation);
        traceLattice(pat, c.surface, c.fields, c.P, Mc, c.diagonal, patterns);
        if (pat.tips.empty()) return; // the seed was crowded out: nothing more to place
        patterns.push_back(std::move(pat));
    }
}

// Per vertex: the area of a third of each adjacent triangle [m^2].
std::vector<double> vertexAreas(const TriangleMesh& mesh)
{
    std::vector<double> area(mesh.vertices.size(), 0.0);
    for (const auto& t : mesh.triangles) {
        const Vec3d a = toD(mesh.vertices[t[0]]), b = toD(mesh.vertices[t[1]]), c = toD(mesh.vertices[t[2]]);
        const double third = (b - a).cross(c - a).norm() / 6.0;
        for (uint32_t v : t) area[v] += third;
    }
    return area;
}

// Phase 6 (the paper's first listed limitation): moves the vertices of `out` (the displaced
// refined mesh) along the refined normals by offset * weight until out encloses volumeIn
// [m^3] again; the offset [m] is the excess volume over the weight-weighted area of the
// refined mesh, at most four rounds, stopping below 1e-12 m.
void conserveVolume(TriangleMesh& out, const RefinedSurface& refined, const std::vector<double>& weight,
                    double volumeIn)
{
    const size_t n = refined.mesh.vertices.size();
    const std::vector<double> area = vertexAreas(refined.mesh);
    double weightedArea = 0;
    for (size_t v = 0; v < n; ++v) weightedArea += area[v] * weight[v];
    for (int iteration = 0; iteration < 4 && weightedArea > 0; ++iteration) {
        const double excess = enclosedVolume(out) - volumeIn;
        const double offset = excess / weightedArea;
        if (std::abs(offset) < 1e-12) break;
        for (size_t v = 0; v < n; ++v)
            if (weight[v] > 0)
                out.vertices[v] = (toD(out.vertices[v]) - offset * weight[v] * refined.normals[v]).cast<float>();
    }
}

// Whether a tip of pattern p stands for a peak of the surface: the ownership of the tips of
// every pattern within 0.3 l of it (a merged pair: settleSeams) sums to at least 0.5, and
// none of those keeps more than it (a tie: the earlier pattern reports the peak).
bool ownsPeak(const std::vector<Pattern>& patterns, size_t p, const Tip& tip)
{
    double total = tip.ownership;
    bool owns = true;
    for (size_t q = 0; q < patterns.size(); ++q) {
        if (q == p) continue;
        const double l = std::min(patterns[p].info.spacing, patterns[q].info.spacing);
        patterns[q].grid->forEachWithin(tip.position, 0.3 * l, [&](uint32_t u, double) {
            const double other = patterns[q].tips[u].ownership;
            total += other;
            if (other > tip.ownership || (other == tip.ownership && q < p)) owns = false;
        });
    }
    return owns && total >= 0.5;
}

// The tips that grew (displacement > 0 at the tip) and own their peak (ownsPeak), pattern by
// pattern, into res.tips and res.maxHeight [m]; every pattern's info into res.patterns.
void reportTips(const SpikeSurface& surface, SpikeResult& res)
{
    const std::vector<Pattern>& patterns = surface.patterns;
    for (size_t p = 0; p < patterns.size(); ++p) {
        for (const Tip& tip : patterns[p].tips) {
            if (!ownsPeak(patterns, p, tip)) continue;
            double w;
            Vec3d dir;
            const double z = spikeDisplacement(surface, tip.position, tip.normal, w, dir);
            if (!(z > 0)) continue;
            SpikeTip t;
            t.pattern = int(p);
            t.i = tip.i;
            t.j = tip.j;
            t.base = tip.position;
            t.direction = dir;
            t.height = z;
            t.apex = tip.position + z * dir;
            res.tips.push_back(t);
            res.maxHeight = std::max(res.maxHeight, z);
        }
        res.patterns.push_back(patterns[p].info);
    }
}

// Phases 1-3 for one input: the wetted wall and the supercritical part of the input surface
// (region) and the traced patterns; empty when nothing is supercritical.
std::vector<Pattern> tracePatterns(const SpikeInput& in, const SpikeParams& P, const SurfaceFields& fields, double Mc,
                                   InputRegion& region)
{
    const TriangleMesh& input = in.surface;
    const double g = in.fluid.gravity.norm();
    // 1. Wetted walls and the supercritical part of the input surface.
    region = classifyInputSurface(input, fields);
    if (std::none_of(region.active.begin(), region.active.end(), [](char a) { return a != 0; })) return {};
    const double diagonal = boundingDiagonal(input);
    const SurfaceRayCaster caster(input);
    const FreeSurface freeSurface{input, caster, region.wetted};

    // 2. One pattern per magnet with a supercritical origin.
    std::vector<Pattern> patterns =
        placePatterns(PlacementContext{in, P, fields, freeSurface, region.active, diagonal}, g, Mc);
    if (patterns.empty() && !in.fluid.solids) return {};

    // 3. Tips (Fig. 7): a hexagon traces six axes along the surface and fills the rings between
    // them; a square traces the i axis both ways and rows along e2 from its tips; a rhombic
    // lattice, and every lattice of a shot whose hexagons morph, also the rows along e1 from the
    // e2 axis (traceRows).
    std::vector<Pattern> traced;
    for (Pattern& pat : patterns) {
        traceLattice(pat, freeSurface, fields, P, Mc, diagonal, traced);
        traced.push_back(std::move(pat));
    }
    if (in.fluid.solids)
        addRegionPatterns(PlacementContext{in, P, fields, freeSurface, region.active, diagonal}, g, Mc, traced);
    if (traced.empty()) return {};
    settleSeams(traced, in.magnets);
    return traced;
}

// Phases 5-6 on a refined surface into `out`: heights and directions, then the volume
// offset. Returns the wetted wall it found on the refined surface and each vertex's weight of
// the displacement (0 off the spikes, 1 on them).
struct Displaced {
    WettedWall wall;
    std::vector<double> weight;
};
Displaced displaceAndConserve(const SurfaceFields& fields, const std::vector<Pattern>& patterns, const SpikeInput& in,
                              const SpikeParams& P, const RefinedSurface& refined, double volumeIn, TriangleMesh& out)
{
    WettedWall wall = findWettedWall(refined.mesh, fields, P, refined.minSpacing);
    const SpikeSurface spikes{fields, patterns, in.magnets, P, wall};
    std::vector<double> weight = displaceVertices(spikes, refined, out);
    if (P.conserveVolume) conserveVolume(out, refined, weight, volumeIn);
    return {std::move(wall), std::move(weight)};
}

// The lattice the earlier input had (phases 1-3 on it), for the spikes' own motion since then.
struct EarlierLattice {
    EarlierLattice(const SpikeInput& earlier, const SpikeParams& P, double Mc) : input(earlier), params(P), fields(earlier, P, Mc)
    {
        InputRegion region;
        patterns = tracePatterns(earlier, P, fields, Mc, region);
    }
    const SpikeInput& input;
    const SpikeParams& params;
    const SurfaceFields fields;
    std::vector<Pattern> patterns;
};

// `surface` displaced as the earlier lattice displaced it (unrefined): what the spikes that
// have gone since stood as.
TriangleMesh earlierSpikySurface(const TriangleMesh& surface, const EarlierLattice& then, double volumeIn)
{
    RefinedSurface unrefined{surface, areaWeightedNormals(surface), std::numeric_limits<double>::infinity(), false};
    for (const Pattern& p : then.patterns) unrefined.minSpacing = std::min(unrefined.minSpacing, p.info.spacing);
    TriangleMesh out = surface;
    displaceAndConserve(then.fields, then.patterns, then.input, then.params, unrefined, volumeIn, out);
    return out;
}

} // namespace

Vec3d totalFieldAt(const SpikeInput& input, const Vec3d& x)
{
    Vec3d H = magnetField(input.magnets, x);
    H += particleFieldAt(input, x) + solidFieldAt(input, x);
    return H;
}

SpikeResult addSpikes(const SpikeInput& in, const SpikeParams& params, const SpikeInput* earlier, double interval)
{
    SpikeResult res;
    // The look at the frame's time ([[spikes.keys]]), and at the earlier input's for the velocities.
    const SpikeParams P = spikeParamsAt(params, in.time);
    const double g = in.fluid.gravity.norm();
    res.critical = criticalMagnetization(in.fluid.density - P.ambientDensity, g, in.fluid.surfaceTension, in.fluid.law);
    res.volumeIn = enclosedVolume(in.surface);
    const double Mc = res.critical.magnetization;
    const SpikeInput* before = interval > 0 ? earlier : nullptr;
    const SpikeParams Pthen = before ? spikeParamsAt(params, before->time) : P;
    if (!P.enabled || in.magnets.empty() || !std::isfinite(Mc) || in.surface.empty())
        return unchangedResult(std::move(res), in.surface);

    // 1-3. The supercritical region and the patterns' tips.
    const SurfaceFields fields(in, P, Mc);
    InputRegion region;
    const std::vector<Pattern> patterns = tracePatterns(in, P, fields, Mc, region);
    if (patterns.empty()) {
        // No spikes now; spikes that were there a moment ago sink where they stood.
        res = unchangedResult(std::move(res), in.surface);
        if (before && !res.mesh.velocities.empty()) {
            const EarlierLattice then(*before, Pthen, Mc);
            if (!then.patterns.empty())
                addSinkingVelocity(res.mesh.velocities, in.surface, earlierSpikySurface(in.surface, then, res.volumeIn),
                                   interval);
        }
        return res;
    }

    // 4. Refine the supercritical region (and one ring around it) to l / resolution.
    RefinedSurface refined = refineSpikyRegion(in.surface, region.active, patterns, P);
    res.refinedOk = refined.remeshed;

    // 5-6. Heights and directions on the refined surface; the volume offset.
    const Displaced displaced = displaceAndConserve(fields, patterns, in, P, refined, res.volumeIn, res.mesh);
    res.volumeOut = enclosedVolume(res.mesh);
    const std::vector<Vec3> surfaceVelocity = surfaceVelocityAt(in.surface, refined.mesh.vertices);
    if (!surfaceVelocity.empty()) {
        const std::optional<EarlierLattice> then =
            before ? std::make_optional<EarlierLattice>(*before, Pthen, Mc) : std::nullopt;
        res.mesh.velocities = spikyVelocities(res.mesh, refined, surfaceVelocity, displaced.weight, patterns,
                                              tipMotions(patterns, then ? &then->patterns : nullptr, interval));
    }
    computeVertexNormals(res.mesh);
    res.refined = std::move(refined.mesh);

    reportTips(SpikeSurface{fields, patterns, in.magnets, P, displaced.wall}, res);
    return res;
}

} // namespace ferro

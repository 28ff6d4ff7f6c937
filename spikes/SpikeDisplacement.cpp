// The displacement of SpikeDisplacement.hpp.
#include "spikes/SpikeDisplacement.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace ferro {

namespace {

// One pattern's tips around a point: the partition-of-unity sums of eq. 13's profile (s, over
// weights w, radius l) and the narrow-kernel sums of amplitude and direction (a, dir, over
// weights wa, radius 0.75 l).
struct TipSums {
    double s = 0, w = 0, a = 0, wa = 0;
    Vec3d dir = Vec3d::Zero();
};

TipSums sumNearbyTips(const Pattern& pat, const Vec3d& x)
{
    const double R = pat.info.spacing, Rn = 0.75 * R;
    const double squareness = pat.info.squareness;
    TipSums sums;
    pat.grid->forEachWithin(x, R, [&](uint32_t t, double d2) {
        const Tip& tip = pat.tips[t];
        if (!(tip.ownership > 0)) return;
        const double q = 1.0 - d2 / (R * R);
        const double wt = q * q * tip.ownership;
        const Eigen::Vector2d ab = tip.toLattice * (x - tip.position);
        // A tip left out (defects) lends the blend a flat surface instead of its profile, so
        // the gap is a smooth patch rather than a peakless ring of troughs; at the tip itself
        // the height is its presence times its full height.
        sums.s += wt * tip.presence * morphProfile(ab.x(), ab.y(), squareness);
        sums.w += wt;
        if (d2 < Rn * Rn) {
            const double qn = 1.0 - d2 / (Rn * Rn);
            const double wn = qn * qn * qn * qn * tip.ownership;
            sums.a += wn * tip.amplitude;
            sums.dir += wn * tip.direction;
            sums.wa += wn;
        }
    });
    return sums;
}

} // namespace

WettedWall findWettedWall(const TriangleMesh& mesh, const SurfaceFields& fields, const SpikeParams& P,
                          double minSpacing)
{
    const size_t n = mesh.vertices.size();
    std::vector<char> wetted(n, 0);
    tbb::parallel_for(size_t(0), n, [&](size_t v) { wetted[v] = fields.wetted(toD(mesh.vertices[v])); });
    std::vector<Vec3d> wettedPoints;
    for (size_t v = 0; v < n; ++v)
        if (wetted[v]) wettedPoints.push_back(toD(mesh.vertices[v]));
    const double wallFade = P.wallFade > 0 ? P.wallFade : minSpacing;
    return WettedWall{std::move(wetted), HashGrid(wettedPoints, wallFade), wallFade};
}

double spikeDisplacement(const SpikeSurface& surface, const Vec3d& x, const Vec3d& nx, double& weight,
                         Vec3d& direction)
{
    const SurfaceFields& fields = surface.fields;
    const std::vector<Pattern>& patterns = surface.patterns;
    const SpikeParams& P = surface.P;
    const WettedWall& wall = surface.wall;
    weight = 0;
    direction = nx;
    if (fields.wetted(x)) return 0;
    const Vec3d H = fields.field(x, nx);
    const double fade = fields.surfaceGate(x, H) *
                        (wall.grid.empty() ? 1.0 : smoothstep01(wall.grid.nearestDistance(x, wall.fade) / wall.fade));
    if (fade <= 0) return 0;
    // Eq. 13 from every nearby tip's lattice map, blended by a smooth partition of unity
    // (radius l; exact on a regular lattice), and each spike's amplitude and direction from its
    // own tip (a narrow kernel, radius 0.75 l, so each spike is a rigid, symmetric cone leaning
    // along the field at its tip; blended between spikes). One partition over the tips of all
    // patterns, each tip weighted by its ownership (settleSeams): where two patterns meet, the
    // surface peaks at the tips that won the seam instead of averaging two lattices. Where a
    // pattern's share of the field dominance falls under 0.3 its tips fade out of the blend
    // (gone under 0.1): a pattern of wider spacing would otherwise reach with its kernel deep
    // into its neighbour's domain and bend the neighbour's spikes.
    double S = 0, W = 0, A = 0, WA = 0;
    Vec3d D = Vec3d::Zero();
    const Dominance dominance = patternDominance(patterns, surface.magnets, x);
    for (size_t p = 0; p < patterns.size(); ++p) {
        const double gate = patterns.size() == 1 ? 1.0 : smoothstep01((dominance.share(p) - 0.1) / 0.2);
        if (!(gate > 0)) continue;
        const TipSums sums = sumNearbyTips(patterns[p], x);
        S += gate * sums.s;
        W += gate * sums.w;
        A += gate * sums.a;
        D += gate * sums.dir;
        WA += gate * sums.wa;
    }
    if (!(W > 0)) return 0;
    const double coverage = smoothstep01(W / 0.4);
    const double F = sharpenedProfile(S / W, P.sharpness);
    // Far from every tip (trough centres of a stretched lattice) the local field takes over.
    constexpr double eps = 1e-3;
    double spacing = 0;
    for (size_t p = 0; p < patterns.size(); ++p) spacing += dominance.share(p) * patterns[p].info.spacing;
    const double localC0 = spikeAmplitude(P, H.norm(), spacing) * fields.heightFade(x, H);
    const double C0 = (A + eps * localC0) / (WA + eps);
    const Vec3d dir = growthDirection(D + eps * growthDirection(H, nx, P.maxTilt), nx, P.maxTilt);
    weight = fade * coverage;
    direction = dir;
    return weight * C0 * F;
}

std::vector<double> displaceVertices(const SpikeSurface& surface, const RefinedSurface& refined, TriangleMesh& out)
{
    const size_t n = refined.mesh.vertices.size();
    std::vector<double> weight(n, 0.0);
    out = refined.mesh;
    tbb::parallel_for(size_t(0), n, [&](size_t v) {
        if (surface.wall.wetted[v]) return;
        Vec3d dir;
        const double z = spikeDisplacement(surface, toD(refined.mesh.vertices[v]), refined.normals[v], weight[v], dir);
        out.vertices[v] = (toD(refined.mesh.vertices[v]) + z * dir).cast<float>();
    });
    return weight;
}

} // namespace ferro

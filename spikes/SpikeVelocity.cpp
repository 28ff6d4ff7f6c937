// The spiky surface's velocity of SpikeVelocity.hpp.
#include "spikes/SpikeVelocity.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <map>
#include <tuple>

namespace ferro {

std::vector<std::vector<TipMotion>> tipMotions(const std::vector<Pattern>& patterns,
                                               const std::vector<Pattern>* before, double interval)
{
    std::vector<std::vector<TipMotion>> motion(patterns.size());
    for (size_t p = 0; p < patterns.size(); ++p) motion[p].resize(patterns[p].tips.size());
    if (!before) return motion;
    std::map<std::tuple<int, int, int>, const Tip*> then;
    for (const Pattern& pat : *before)
        for (const Tip& tip : pat.tips) then[{pat.info.noiseKey(), tip.i, tip.j}] = &tip;
    for (size_t p = 0; p < patterns.size(); ++p)
        for (size_t t = 0; t < patterns[p].tips.size(); ++t) {
            const Tip& tip = patterns[p].tips[t];
            TipMotion& m = motion[p][t];
            const auto it = then.find({patterns[p].info.noiseKey(), tip.i, tip.j});
            if (it != then.end()) {
                m.drift = (tip.position - it->second->position) / interval;
                if (tip.amplitude > 0) m.growth = (tip.amplitude - it->second->amplitude) / (interval * tip.amplitude);
            } else if (tip.amplitude > 0) {
                m.growth = 1.0 / interval;
            }
        }
    return motion;
}

std::vector<Vec3> surfaceVelocityAt(const TriangleMesh& surface, const std::vector<Vec3>& points)
{
    if (surface.velocities.size() != surface.vertices.size() || surface.vertices.empty()) return {};
    const double edge = meanEdgeLength(surface);
    std::vector<Vec3d> vertices(surface.vertices.size());
    for (size_t i = 0; i < vertices.size(); ++i) vertices[i] = toD(surface.vertices[i]);
    const HashGrid grid(vertices, edge > 0 ? std::max(2 * edge, 1e-9) : 1e-3);
    std::vector<Vec3> out(points.size());
    tbb::parallel_for(size_t(0), points.size(),
                      [&](size_t i) { out[i] = surface.velocities[grid.nearest(toD(points[i]))]; });
    return out;
}

std::vector<Vec3> spikyVelocities(const TriangleMesh& now, const RefinedSurface& refined,
                                  const std::vector<Vec3>& surfaceVelocity, const std::vector<double>& weight,
                                  const std::vector<Pattern>& patterns,
                                  const std::vector<std::vector<TipMotion>>& motion)
{
    std::vector<Vec3> v(now.vertices.size());
    tbb::parallel_for(size_t(0), v.size(), [&](size_t k) {
        const Vec3d x = toD(refined.mesh.vertices[k]);
        const Vec3d n = refined.normals[k];
        Vec3d vs = toD(surfaceVelocity[k]);
        vs -= weight[k] * (vs - vs.dot(n) * n);   // along the surface: the spikes' own drift instead
        double W = 0, growth = 0;
        Vec3d drift = Vec3d::Zero();
        for (size_t p = 0; p < patterns.size(); ++p) {
            const double l = patterns[p].info.spacing;
            patterns[p].grid->forEachWithin(x, l, [&](uint32_t t, double d2) {
                const double q = 1.0 - d2 / (l * l);
                const double w = patterns[p].tips[t].ownership * q * q * q;
                W += w;
                drift += w * motion[p][t].drift;
                growth += w * motion[p][t].growth;
            });
        }
        if (W > 0) vs += weight[k] * drift / W + growth / W * (toD(now.vertices[k]) - x);
        v[k] = vs.cast<Real>();
    });
    return v;
}

void addSinkingVelocity(std::vector<Vec3>& velocity, const TriangleMesh& surface, const TriangleMesh& then,
                        double interval)
{
    for (size_t i = 0; i < velocity.size(); ++i) velocity[i] += (surface.vertices[i] - then.vertices[i]) / Real(interval);
}

} // namespace ferro

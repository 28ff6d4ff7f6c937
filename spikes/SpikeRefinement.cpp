// The refinement of SpikeRefinement.hpp.
#include "spikes/SpikeRefinement.hpp"

#include <algorithm>
#include <limits>

namespace ferro {

namespace {

// Per triangle of `mesh`: 1 where a vertex is active, and on the ring of triangles around those.
std::vector<char> spikyTriangles(const TriangleMesh& mesh, const std::vector<char>& active)
{
    std::vector<char> near(mesh.vertices.size(), 0), selected(mesh.triangles.size(), 0);
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (uint32_t v : mesh.triangles[t])
            if (active[v]) selected[t] = 1;
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        if (selected[t])
            for (uint32_t v : mesh.triangles[t]) near[v] = 1;
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (uint32_t v : mesh.triangles[t])
            if (near[v]) selected[t] = 1;
    return selected;
}

// Put a vertex exactly on every tip: the apex of each spike is then a vertex (a sharp,
// well-placed tip for the renderer, and the same vertex position in every frame while the
// magnet is still). The nearest vertex is less than an edge (`cell` [m]) away, inside its own
// 1-ring; tips with no vertex within 1.5 cell are left alone.
void pinVerticesToTips(TriangleMesh& mesh, const std::vector<Pattern>& patterns, double cell)
{
    const size_t n = mesh.vertices.size();
    std::vector<Vec3d> points(n);
    for (size_t v = 0; v < n; ++v) points[v] = toD(mesh.vertices[v]);
    const HashGrid grid(points, cell);
    for (const Pattern& pat : patterns)
        for (const Tip& tip : pat.tips) {
            long nearest = -1;
            double best = std::numeric_limits<double>::max();
            grid.forEachWithin(tip.position, 1.5 * cell, [&](uint32_t v, double d2) {
                if (d2 < best) best = d2, nearest = long(v);
            });
            if (nearest >= 0) mesh.vertices[size_t(nearest)] = tip.position.cast<float>();
        }
}

} // namespace

RefinedSurface refineSpikyRegion(const TriangleMesh& input, const std::vector<char>& active,
                                 const std::vector<Pattern>& patterns, const SpikeParams& P)
{
    RefinedSurface refined;
    refined.minSpacing = std::numeric_limits<double>::max();
    for (const Pattern& pat : patterns) refined.minSpacing = std::min(refined.minSpacing, pat.info.spacing);
    refined.mesh = input;
    const std::vector<char> selected = spikyTriangles(input, active);
    if (P.remeshIterations > 0)
        refined.remeshed =
            remeshSelectedTriangles(refined.mesh, selected, refined.minSpacing / P.resolution, P.remeshIterations);
    pinVerticesToTips(refined.mesh, patterns, refined.minSpacing / P.resolution);
    refined.normals = areaWeightedNormals(refined.mesh);
    return refined;
}

} // namespace ferro

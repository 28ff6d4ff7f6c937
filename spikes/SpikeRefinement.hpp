#pragma once
// Refinement of the spiky region (phase 4 of addSpikes): CGAL isotropic remeshing of the
// supercritical part of the surface to the spikes' scale, and a vertex on every tip.
// Internal to ferro_spikes.
#include "spikes/SpikeLattice.hpp"

#include <vector>

namespace ferro {

/// The surface the spikes are displaced on.
struct RefinedSurface {
    TriangleMesh mesh;          ///< the input, remeshed where spiky, with a vertex on every tip
    std::vector<Vec3d> normals; ///< area-weighted vertex normals of mesh (unit, outward)
    double minSpacing = 0;      ///< the smallest tip spacing l of the patterns [m]
    bool remeshed = true;       ///< false: CGAL could not load the mesh, which stays unrefined
};

/// Phase 4: the triangles with a supercritical vertex (active[v] != 0, per input vertex), and
/// one ring of triangles around them, are remeshed (CGAL isotropic remeshing,
/// P.remeshIterations rounds, none if 0) to edges of min l / P.resolution [m]; then the
/// vertex nearest to each tip of `patterns` (within 1.5 such edges) is moved onto the tip,
/// so every apex is a vertex, at the same place in every frame while the magnet is still.
/// Throws std::runtime_error as remeshSelectedTriangles when CGAL fails on the selection.
RefinedSurface refineSpikyRegion(const TriangleMesh& input, const std::vector<char>& active,
                                 const std::vector<Pattern>& patterns, const SpikeParams& P);

} // namespace ferro

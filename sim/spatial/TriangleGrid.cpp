#include "sim/spatial/TriangleGrid.hpp"

#include <algorithm>
#include <cmath>

namespace ferro {

void TriangleGrid::build(const std::vector<std::array<Vec3d, 3>>& tris, const Vec3d& lo, const Vec3d& hi,
                         double pad) {
    const Vec3d size = hi - lo;
    origin = lo;
    // About two cells per triangle, capped at 4M cells; the mesh's own proportions
    // set the cell size, since the particle spacing is not known here.
    const double volume = size.prod();
    h = std::cbrt(volume / (2.0 * double(tris.size())));
    h = std::max(h, std::cbrt(volume / double(1 << 22)));
    for (int a = 0; a < 3; ++a) n[a] = std::max(1L, long(std::ceil(size[a] / h)));

    const size_t cells = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
    std::vector<uint32_t> count(cells + 1, 0);
    auto forCells = [&](const std::array<Vec3d, 3>& t, auto&& fn) {
        const Vec3d tlo = (t[0].cwiseMin(t[1]).cwiseMin(t[2]).array() - pad).matrix();
        const Vec3d thi = (t[0].cwiseMax(t[1]).cwiseMax(t[2]).array() + pad).matrix();
        long i0[3], i1[3];
        if (!range(tlo, thi, i0, i1)) return;
        for (long k = i0[2]; k <= i1[2]; ++k)
            for (long j = i0[1]; j <= i1[1]; ++j)
                for (long i = i0[0]; i <= i1[0]; ++i) fn(cell(i, j, k));
    };
    for (const auto& t : tris) forCells(t, [&](size_t c) { ++count[c + 1]; });
    for (size_t c = 0; c < cells; ++c) count[c + 1] += count[c];
    start = count;
    items.resize(start[cells]);
    for (uint32_t id = 0; id < uint32_t(tris.size()); ++id)
        forCells(tris[id], [&](size_t c) { items[count[c]++] = id; });
}

} // namespace ferro

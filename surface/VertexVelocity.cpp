#include "surface/VertexVelocity.hpp"

#include "sim/spatial/NeighborSearch.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <numeric>

namespace ferro {

std::vector<Vec3> interpolateVelocities(const std::vector<DensityKernel>& kernels, const std::vector<Vec3>& v,
                                        const std::vector<Vec3>& at) {
    std::vector<Vec3> out(at.size(), Vec3::Zero());
    if (kernels.empty() || at.empty()) return out;
    // Kernel centres sorted into cells as wide as the widest kernel's half extent: every
    // kernel whose support holds a point has its centre within the 3 x 3 x 3 cells around it.
    Real reach = 0;
    std::vector<Vec3> centres(kernels.size());
    for (size_t k = 0; k < kernels.size(); ++k) {
        reach = std::max(reach, kernels[k].halfExtent.maxCoeff());
        centres[k] = kernels[k].centre;
    }
    std::vector<uint32_t> tie(kernels.size()), order;
    std::iota(tie.begin(), tie.end(), 0u);
    SortedGrid grid;
    grid.sort(centres, tie, reach, order);
    std::vector<Vec3> sorted(centres.size());
    for (size_t k = 0; k < order.size(); ++k) sorted[k] = centres[order[k]];
    const GridGeometry geometry = grid.geometry();
    grid.index(sorted, geometry);

    tbb::parallel_for(tbb::blocked_range<size_t>(0, at.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const Vec3 x = at[i];
            double sumW = 0;
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            uint32_t nearest = 0;
            double nearest2 = std::numeric_limits<double>::infinity();
            grid.forEachCandidateRange(x, [&](uint32_t b, uint32_t e) {
                for (uint32_t s = b; s < e; ++s) {
                    const DensityKernel& k = kernels[order[s]];
                    const double w = k.value(x);
                    if (w > 0) {
                        sumW += w;
                        sum += w * v[k.source].cast<double>();
                    }
                    const double d2 = (k.centre - x).squaredNorm();
                    if (d2 < nearest2 || (d2 == nearest2 && order[s] < nearest)) {
                        nearest2 = d2;
                        nearest = order[s];
                    }
                }
            });
            if (sumW > 0) {
                out[i] = (sum / sumW).cast<Real>();
            } else if (std::isfinite(nearest2)) {
                out[i] = v[kernels[nearest].source];
            } else {
                // Beyond every cell: the nearest kernel by a full scan (rare: a stray vertex).
                for (size_t k = 0; k < kernels.size(); ++k) {
                    const double d2 = (kernels[k].centre - x).squaredNorm();
                    if (d2 < nearest2) nearest2 = d2, nearest = uint32_t(k);
                }
                out[i] = v[kernels[nearest].source];
            }
        }
    });
    return out;
}

} // namespace ferro

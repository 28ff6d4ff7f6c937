#include "sim/sph/FluidSeed.hpp"

#include "sim/core/SceneDocument.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace ferro {

namespace {

std::string fmtVec(const Vec3d& p) {
    std::ostringstream s;
    s.precision(5);
    s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
    return s.str();
}

/// Lattice points of a block at spacing s, offset s/2 from its faces.
void latticeOfBlock(const FluidBlock& b, double s, std::vector<Vec3d>& out) {
    out.clear();
    Vec3d lo, hi;
    if (b.shape == FluidBlock::Shape::Box) {
        lo = b.min;
        hi = b.max;
    } else {
        lo = b.center - Vec3d(b.radius, b.radius, 0);
        hi = b.center + Vec3d(b.radius, b.radius, b.height);
    }
    int n[3];
    for (int a = 0; a < 3; ++a) n[a] = std::max(0, int(std::floor((hi[a] - lo[a]) / s + 1e-9)));
    // Centre the lattice in the block so the leftover gap is split on both sides.
    Vec3d start;
    for (int a = 0; a < 3; ++a) start[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * (n[a] - 1) * s;
    const double r2 = (b.radius - 0.5 * s) * (b.radius - 0.5 * s);
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
                const Vec3d p = start + s * Vec3d(i, j, k);
                if (b.shape == FluidBlock::Shape::Cylinder) {
                    const double dx = p.x() - b.center.x(), dy = p.y() - b.center.y();
                    if (dx * dx + dy * dy > r2) continue;
                }
                out.push_back(p);
            }
}

double blockVolume(const FluidBlock& b) {
    if (b.shape == FluidBlock::Shape::Box) return (b.max - b.min).prod();
    return kPi * b.radius * b.radius * b.height;
}

} // namespace

FluidSeed seedFluid(const SimScene& scene, const Container& container) {
    FluidSeed seed;
    const auto& blocks = scene.fluid.blocks;
    seed.spacing = scene.fluid.spacing;
    std::vector<Vec3d> pts;
    if (seed.spacing <= 0) {
        // Derive the spacing from the first block with a count: the largest spacing
        // whose lattice still holds that many particles (found by bisection).
        const FluidBlock* first = nullptr;
        for (const auto& b : blocks)
            if (b.count > 0) { first = &b; break; }
        if (!first) throw SceneError(scene.path + ": fluid.spacing: set a spacing or a block count");
        const double guess = std::cbrt(blockVolume(*first) / double(first->count));
        double lo = 0.5 * guess, hi = 1.5 * guess;
        for (int it = 0; it < 60; ++it) {
            const double mid = 0.5 * (lo + hi);
            latticeOfBlock(*first, mid, pts);
            (long(pts.size()) >= first->count ? lo : hi) = mid;
        }
        seed.spacing = lo;
    }
    const double s = seed.spacing;
    for (size_t bi = 0; bi < blocks.size(); ++bi) {
        const FluidBlock& b = blocks[bi];
        const std::string key = "fluid.block[" + std::to_string(bi) + "]";
        latticeOfBlock(b, s, pts);
        if (b.count > 0) {
            if (long(pts.size()) < b.count)
                throw SceneError(b.where + ": " + key + ".count: the block holds only " +
                                 std::to_string(pts.size()) + " particles at spacing " +
                                 std::to_string(s) + " m (asked " + std::to_string(b.count) + ")");
            // Keep the lowest particles: the trimmed layer is the free surface.
            std::stable_sort(pts.begin(), pts.end(), [](const Vec3d& a, const Vec3d& c) { return a.z() < c.z(); });
            pts.resize(size_t(b.count));
        }
        if (pts.empty())
            throw SceneError(b.where + ": " + key + ": block is smaller than one particle spacing");
        for (const Vec3d& p : pts) {
            if (!container.contains(p, 0.25 * s))
                throw SceneError(b.where + ": " + key + ": fluid outside the container (particle at " +
                                 fmtVec(p) + ")");
            seed.positions.push_back(p.cast<Real>());
            seed.velocities.push_back(b.velocity.cast<Real>());
        }
    }
    if (seed.positions.size() >= (size_t(1) << 32) - 1) throw SceneError(scene.path + ": too many particles");
    return seed;
}

} // namespace ferro

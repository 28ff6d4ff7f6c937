#include "sim/sph/FreeSurface.hpp"

#include "sim/core/ParticleLoops.hpp"

#include <algorithm>
#include <cmath>

namespace ferro {

void computeColorGradient(const FreeSurfaceInput& in, std::vector<Vec3>& gradC) {
    // Tried and dropped: the fluid's gradient alone with its part away from a wall removed
    // (the same 18 mm/s at the rim of a pool over a magnet, and faster outliers).
    const size_t n = in.x.size();
    gradC.resize(n);
    const PeriodicDomain periodic = in.periodic; // a copy: see ForceSweep
    forEachParticle(n, [&](size_t i) {
        Vec3 fluid = Vec3::Zero(), wall = Vec3::Zero();
        for (uint32_t k = in.fluid.begin(i); k < in.fluid.end(i); ++k) {
            const Vec3 xij = periodic.offset(in.x[i] - in.x[in.fluid.index[k]]);
            fluid += in.kernel.gradW(xij, xij.norm());
        }
        fluid *= in.volume;
        for (uint32_t k = in.boundary.begin(i); k < in.boundary.end(i); ++k) {
            const uint32_t b = in.boundary.index[k];
            const Vec3 xib = periodic.offset(in.x[i] - in.bx[b]);
            wall += in.bVolume[b] * in.kernel.gradW(xib, xib.norm());
        }
        gradC[i] = fluid + wall;
    });
}

void computeExposure(const FreeSurfaceInput& in, const std::vector<Vec3>& gradC, std::vector<Real>& exposure) {
    const size_t n = in.x.size();
    exposure.resize(n);
    const Real s = in.spacing;
    const PeriodicDomain periodic = in.periodic;
    forEachParticle(n, [&](size_t i) {
        const Vec3 g = gradC[i];
        const Real gn = g.norm();
        if (!(gn > 0)) {
            exposure[i] = 0;
            return;
        }
        const Vec3 out = -g / gn;
        Real covered = 0;
        for (uint32_t k = in.fluid.begin(i); k < in.fluid.end(i); ++k) {
            const Vec3 d = periodic.offset(in.x[in.fluid.index[k]] - in.x[i]);
            const Real r = d.norm();
            if (!(r > 0) || r > 2 * s) continue;
            const Real cosine = d.dot(out) / r;
            const Real inCone = std::clamp((cosine - Real(0.65)) / Real(0.2), Real(0), Real(1));
            const Real near = std::clamp((2 * s - r) / (Real(0.5) * s), Real(0), Real(1));
            covered = std::max(covered, inCone * near);
        }
        exposure[i] = 1 - covered;
    });
}

FlatSurface::FlatSurface(double spacing, double volume) {
    // |grad c| of the top four layers of a cubic lattice, support 2 spacings (as
    // FluidSimulation uses), then the column sum.
    const double s = spacing;
    const CubicSplineKernel kernel(Real(2 * s));
    std::vector<double> gradient;
    for (int depth = 0; depth <= 3; ++depth) {
        double gz = 0;
        for (int a = -2; a <= 2; ++a)
            for (int b = -2; b <= 2; ++b)
                for (int k = -2; k <= 2; ++k) {
                    if (k > depth) continue; // above the top layer
                    const Vec3 rij = Vec3(Real(a), Real(b), Real(k)) * Real(-s);
                    gz += volume * double(kernel.gradW(rij, rij.norm()).z());
                }
        gradient.push_back(std::abs(gz));
    }
    gradient_ = gradient[0];
    double column = 0;
    for (double g : gradient) column += weight(g) * g;
    layerFactor_ = volume * column / (s * s);
}

double FlatSurface::weight(double gradient) const {
    if (!(gradient_ > 0)) return 0;
    const double t = std::clamp((gradient / gradient_ - 0.25) / 0.25, 0.0, 1.0);
    return t * t * (3 - 2 * t);
}

} // namespace ferro

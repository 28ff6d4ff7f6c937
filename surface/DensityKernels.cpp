// Yu-Turk anisotropic and plain isotropic density kernels (see DensityKernels.hpp).
#include "surface/DensityKernels.hpp"
#include "sim/core/Constants.hpp"

#include "sim/spatial/NeighborSearch.hpp"

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <tuple>
#include <numeric>

namespace ferro {

namespace {

/// 1 / integral of (1 - u^2)^3 over the unit ball.
constexpr double kSigma = 315.0 / (64.0 * kPi);

/// Sorts positions by cell of a SortedGrid with cells `radius` wide.
struct SortedPoints {
    SortedGrid grid;
    std::vector<Vec3> x; ///< positions in grid order
    std::vector<uint32_t> order; ///< order[k]: the input index of x[k]

    SortedPoints(const std::vector<Vec3>& positions, Real radius) {
        std::vector<uint32_t> tie(positions.size());
        std::iota(tie.begin(), tie.end(), 0u);
        grid.sort(positions, tie, radius, order);
        x.resize(positions.size());
        for (size_t k = 0; k < order.size(); ++k) x[k] = positions[order[k]];
        const GridGeometry g = grid.geometry();
        grid.index(x, g);
    }
};

DensityKernel isotropicKernel(const Vec3& centre, double h, double volume) {
    DensityKernel k;
    k.centre = centre;
    const float inv = float(1.0 / (h * h));
    k.m[0] = k.m[3] = k.m[5] = inv;
    k.m[1] = k.m[2] = k.m[4] = 0;
    k.amplitude = float(volume * kSigma / (h * h * h));
    k.halfExtent = Vec3::Constant(Real(h));
    return k;
}

/// The Yu-Turk kernel of axes h * s_k along the columns of `axes`.
DensityKernel ellipsoidKernel(const Vec3& centre, const Eigen::Matrix3d& axes, const Eigen::Vector3d& s,
                              double h, double volume) {
    DensityKernel k;
    k.centre = centre;
    // M = G^T G = (1/h^2) R diag(1/s^2) R^T; G^-1 = h R diag(s) R^T, whose rows' lengths are
    // the half extents of the ellipsoid |G r| <= 1 along x, y, z.
    const Eigen::Vector3d invS2 = s.cwiseProduct(s).cwiseInverse() / (h * h);
    const Eigen::Matrix3d M = axes * invS2.asDiagonal() * axes.transpose();
    const Eigen::Matrix3d Ginv = h * axes * s.asDiagonal() * axes.transpose();
    k.m[0] = float(M(0, 0));
    k.m[1] = float(M(0, 1));
    k.m[2] = float(M(0, 2));
    k.m[3] = float(M(1, 1));
    k.m[4] = float(M(1, 2));
    k.m[5] = float(M(2, 2));
    k.amplitude = float(volume * kSigma / (h * h * h * s.prod()));
    for (int a = 0; a < 3; ++a) k.halfExtent[a] = Real(Ginv.row(a).norm());
    return k;
}

} // namespace

double derivedKs(const SurfaceParams& params, double spacing) {
    if (params.ks > 0) return params.ks;
    const double R = params.neighborRadius;
    const int n = int(std::ceil(R));
    double sumW = 0, sumWd2 = 0;
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int k = -n; k <= n; ++k) {
                const double r = std::sqrt(double(i * i + j * j + k * k));
                if (r >= R) continue;
                const double w = 1 - std::pow(r / R, 3);
                sumW += w;
                sumWd2 += w * i * i;
            }
    const double variance = sumWd2 / sumW * spacing * spacing; // per axis, equal by symmetry
    return 1.0 / variance;
}

std::vector<DensityKernel> buildKernels(const std::vector<Vec3>& positions, const SurfaceParams& params,
                                        double spacing) {
    const size_t n = positions.size();
    const double h = params.kernelRadius * spacing;
    const double volume = spacing * spacing * spacing;
    std::vector<DensityKernel> kernels(n);
    if (n == 0) return kernels;
    if (params.method != SurfaceMethod::Anisotropic) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                kernels[i] = isotropicKernel(positions[i], h, volume);
                kernels[i].source = uint32_t(i);
            }
        });
        return kernels;
    }

    const Real R = Real(params.neighborRadius * spacing);
    const Real R2 = R * R, invR = 1 / R;
    const double ks = derivedKs(params, spacing);
    const double kr = params.kr, kn = params.kn, lambda = params.lambda;
    const size_t nEps = size_t(std::max(0, params.nEps));
    const SortedPoints sorted(positions, R);
    const std::vector<Vec3>& x = sorted.x;

    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 512), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
            const Vec3 p = x[i];
            // Offsets from p rather than absolute positions: float keeps its digits.
            float sw = 0, sx = 0, sy = 0, sz = 0;
            float cxx = 0, cxy = 0, cxz = 0, cyy = 0, cyz = 0, czz = 0;
            size_t count = 0;
            sorted.grid.forEachCandidateRange(p, [&](uint32_t b, uint32_t e) {
                for (uint32_t j = b; j < e; ++j) {
                    const float dx = x[j].x() - p.x(), dy = x[j].y() - p.y(), dz = x[j].z() - p.z();
                    const float r2 = dx * dx + dy * dy + dz * dz;
                    if (r2 >= R2) continue;
                    const float t = std::sqrt(r2) * invR;
                    const float w = 1 - t * t * t; // Yu-Turk's weight 1 - (r/R)^3
                    ++count;
                    sw += w;
                    sx += w * dx;
                    sy += w * dy;
                    sz += w * dz;
                    cxx += w * dx * dx;
                    cxy += w * dx * dy;
                    cxz += w * dx * dz;
                    cyy += w * dy * dy;
                    cyz += w * dy * dz;
                    czz += w * dz * dz;
                }
            });
            const Eigen::Vector3d mean = Eigen::Vector3d(sx, sy, sz) / double(sw);
            const Vec3 centre = p + (lambda * mean).cast<Real>();
            Eigen::Matrix3d C;
            C << cxx, cxy, cxz, cxy, cyy, cyz, cxz, cyz, czz;
            C = C / double(sw) - mean * mean.transpose();
            Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
            eig.computeDirect(C);
            const Eigen::Vector3d ev = eig.eigenvalues().cwiseMax(0.0); // ascending
            const double largest = ev[2];
            if (count < nEps || !(largest > 0) || !std::isfinite(largest)) {
                // Too few neighbours for a meaningful shape: a small round kernel (k_n).
                kernels[i] = isotropicKernel(centre, h * kn, volume);
                kernels[i].source = sorted.order[i];
                continue;
            }
            Eigen::Vector3d s;
            for (int a = 0; a < 3; ++a) s[a] = ks * std::max(ev[a], largest / kr);
            kernels[i] = ellipsoidKernel(centre, eig.eigenvectors(), s, h, volume);
            kernels[i].source = sorted.order[i];
        }
    });
    return kernels;
}

double densityAt(const std::vector<DensityKernel>& kernels, const Vec3& x) {
    double sum = 0;
    for (const DensityKernel& k : kernels) sum += k.value(x);
    return sum;
}

namespace {
SurfaceCalibration calibrateUncached(const SurfaceParams& params, double spacing) {
    SurfaceCalibration cal;
    cal.isoLevel = params.isoLevel;
    if (params.method == SurfaceMethod::OpenVdb) {
        // ParticlesToLevelSet gives a distance field: spheres of one spacing radius reach half a
        // spacing beyond where a flat sheet's surface belongs.
        cal.isoLevel = 0;
        cal.offset = params.volumeCorrection ? -0.5 * spacing : 0.0; // an SDF: inward is negative
        return cal;
    }
    if (!params.volumeCorrection) return cal;
    // A slab of simple cubic lattice wide enough that its centre column sees no edge, and
    // thick enough that the top layers see a full interior below them.
    const double reach = params.neighborRadius + 1.5 * params.kernelRadius;
    const int half = int(std::ceil(reach)) + 1;
    const int layers = 2 * half;
    std::vector<Vec3> lattice;
    for (int i = -half; i <= half; ++i)
        for (int j = -half; j <= half; ++j)
            for (int k = 0; k < layers; ++k)
                lattice.emplace_back(Real(i * spacing), Real(j * spacing), Real(k * spacing));
    const std::vector<DensityKernel> all = buildKernels(lattice, params, spacing);
    // Only kernels that reach the sampled columns matter.
    std::vector<DensityKernel> kernels;
    for (const DensityKernel& k : all)
        if (std::abs(k.centre.x()) <= k.halfExtent.x() + spacing && std::abs(k.centre.y()) <= k.halfExtent.y() + spacing)
            kernels.push_back(k);
    // Where the iso surface crosses columns through one lattice cell, scanning down from
    // above the sheet; the sheet's own surface is half a spacing above its top layer.
    const double top = (layers - 1) * spacing;
    const double step = spacing / 64;
    double sum = 0;
    int found = 0;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
            const Real x = Real(a * spacing / 4), y = Real(b * spacing / 4);
            double zPrev = top + 2 * params.kernelRadius * spacing, rhoPrev = 0;
            for (double z = zPrev; z > top - 2 * spacing; z -= step) {
                const double rho = densityAt(kernels, Vec3(x, y, Real(z)));
                if (rho >= cal.isoLevel) {
                    sum += z + (zPrev - z) * (rho - cal.isoLevel) / std::max(rho - rhoPrev, 1e-12);
                    ++found;
                    break;
                }
                zPrev = z;
                rhoPrev = rho;
            }
        }
    if (found > 0) cal.offset = top + 0.5 * spacing - sum / found;
    return cal;
}
} // namespace

SurfaceCalibration calibrateSurface(const SurfaceParams& params, double spacing) {
    // The calibration is scale free: computed once per parameter set at unit spacing and
    // scaled, so a frame range pays for it once.
    using Key = std::tuple<int, double, double, double, double, double, int, double, double, bool>;
    const Key key{int(params.method), params.kernelRadius, params.neighborRadius, params.kr,
                  params.ks * spacing * spacing, params.kn, params.nEps, params.lambda, params.isoLevel,
                  params.volumeCorrection};
    static std::mutex mutex;
    static std::map<Key, SurfaceCalibration> cache;
    {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = cache.find(key);
        if (it != cache.end()) return {it->second.isoLevel, it->second.offset * spacing};
    }
    SurfaceParams unit = params;
    unit.ks = params.ks * spacing * spacing;
    const SurfaceCalibration cal = calibrateUncached(unit, 1.0);
    std::lock_guard<std::mutex> lock(mutex);
    cache[key] = cal;
    return {cal.isoLevel, cal.offset * spacing};
}

double estimateSpacing(const std::vector<Vec3>& positions) {
    const size_t n = positions.size();
    if (n < 2) return 0;
    Vec3 lo = positions[0], hi = positions[0];
    for (const Vec3& p : positions) {
        if (!p.allFinite()) continue;
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    const double extent = (hi - lo).maxCoeff();
    if (!(extent > 0)) return 0;
    double radius = extent / std::cbrt(double(n));
    const size_t stride = std::max<size_t>(1, n / 4096);
    for (int attempt = 0; attempt < 8; ++attempt, radius *= 2) {
        const SortedPoints sorted(positions, Real(radius));
        std::vector<double> nearest;
        for (size_t i = 0; i < n; i += stride) {
            const Vec3 p = sorted.x[i];
            float best = std::numeric_limits<float>::max();
            sorted.grid.forEachCandidateRange(p, [&](uint32_t b, uint32_t e) {
                for (uint32_t j = b; j < e; ++j) {
                    const float d2 = (sorted.x[j] - p).squaredNorm();
                    if (d2 > 0 && d2 < best) best = d2;
                }
            });
            if (best < float(radius * radius)) nearest.push_back(std::sqrt(double(best)));
        }
        if (nearest.size() * 2 >= (n + stride - 1) / stride) {
            std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
            return nearest[nearest.size() / 2];
        }
    }
    return 0;
}

} // namespace ferro

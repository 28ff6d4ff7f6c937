// The two local terms at particle centres (DipoleTree.hpp): the surface term of particles
// near the free surface and the local consistency correction.
#include "sim/particlefield/DipoleMultipoles.hpp"

#include <Eigen/Cholesky>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

using namespace dipole_detail;

void DipoleTree::addSurfaceTerm(size_t k, double h[3]) const {
    if (!(vol_[k] > 0)) return;
    if (!localCorrection_.empty()) {
        // h -= D_k M_k (D_k row-major, see computeLocalCorrection); M = moment / volume.
        const float* D = &localCorrection_[9 * k];
        const double m[3] = {mx_[k] / double(vol_[k]), my_[k] / double(vol_[k]), mz_[k] / double(vol_[k])};
        for (int a = 0; a < 3; ++a) h[a] -= D[3 * a] * m[0] + D[3 * a + 1] * m[1] + D[3 * a + 2] * m[2];
    }
    if (surfaceWeight_.empty() || !(surfaceWeight_[k] > 0)) return;
    const float* nk = &surfaceNormal_[3 * k];
    // M = moment / volume (both in scaled units: A/m).
    const double mn = (double(mx_[k]) * nk[0] + double(my_[k]) * nk[1] + double(mz_[k]) * nk[2]) / vol_[k];
    for (int a = 0; a < 3; ++a) h[a] -= double(surfaceWeight_[k]) * mn * nk[a];
}

void DipoleTree::leavesWithin(const Node& target, double reach, std::vector<uint32_t>& stack,
                              std::vector<uint32_t>& ranges) const {
    auto boxGap = [](const Node& a, const Node& b) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k) {
            const double g = std::max({0.0, double(a.lo[k]) - b.hi[k], double(b.lo[k]) - a.hi[k]});
            d2 += g * g;
        }
        return std::sqrt(d2);
    };
    ranges.clear();
    stack.assign(1, 0);
    while (!stack.empty()) {
        const Node& node = nodes_[stack.back()];
        stack.pop_back();
        if (boxGap(node, target) >= reach) continue;
        if (node.childCount > 0) {
            for (uint32_t c = 0; c < node.childCount; ++c) stack.push_back(node.firstChild + c);
        } else {
            ranges.push_back(node.begin);
            ranges.push_back(node.end);
        }
    }
}

void DipoleTree::computeSurfaceTerms() {
    // n_k = sum_j V_j W_j(x_k - x_j), the filled fraction of particle k's kernel (1 inside
    // the fluid), and its gradient. Targets are grouped by leaf: one range search of the
    // octree per leaf (cells whose box is within the largest support of the leaf's box),
    // then every target of the leaf runs over those candidates. Outward normal = -grad n.
    const size_t n = size();
    surfaceWeight_.assign(n, 0.0f);
    surfaceNormal_.assign(3 * n, 0.0f);
    if (n == 0 || nodes_.empty()) return;
    const float reach = nodes_[0].maxA; // largest support
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint32_t> stack, ranges;
        for (size_t l = r.begin(); l < r.end(); ++l) {
            if (!leafHasTarget(l)) continue; // periodic copies: never evaluated
            const Node& target = nodes_[leaves_[l]];
            leavesWithin(target, reach, stack, ranges);
            for (uint32_t k = target.begin; k < target.end; ++k) {
                const float px = px_[k], py = py_[k], pz = pz_[k];
                double dens = 0, grad[3] = {0, 0, 0};
                for (size_t q = 0; q < ranges.size(); q += 2)
                    for (uint32_t j = ranges[q]; j < ranges[q + 1]; ++j) {
                        const float dx = px - px_[j], dy = py - py_[j], dz = pz - pz_[j];
                        const float r2 = dx * dx + dy * dy + dz * dz;
                        if (!(r2 < a2_[j])) continue;
                        const float ai = ainv_[j], rr = std::sqrt(r2), qq = rr * ai, u = 1 - qq;
                        const float c = float(21.0 / (2.0 * kPi)) * ai * ai * ai * vol_[j];
                        dens += c * u * u * u * u * (1 + 4 * qq);
                        if (rr > 0) {
                            const float dW = -20.0f * c * ai * qq * u * u * u / rr; // (dW/dr) / r
                            grad[0] += dW * dx;
                            grad[1] += dW * dy;
                            grad[2] += dW * dz;
                        }
                    }
                const double g = std::sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]);
                // Onset: the deficit 1 - n ramps in between 0.05 and 0.15. Inside a disordered
                // fluid n scatters by a few percent (5 % RMS on a 0.2-jittered lattice), and
                // every interior particle with n < 1 got a term along a random "normal" that
                // only ever lowers H: on the jittered ball of the tests that was a bias of
                // ~1 % of the interior field at chi0 = 10 and part of the scatter. A real
                // surface has deficits of 0.1-0.5 (0.5 in the top layer of a flat surface).
                const double deficit = 1 - dens;
                const double t = surfaceOnset_ ? std::clamp((deficit - 0.05) / 0.10, 0.0, 1.0) : (deficit > 0 ? 1.0 : 0.0);
                if (t > 0 && g > 0) {
                    surfaceWeight_[k] = float(t * t * (3 - 2 * t) * deficit);
                    for (int a = 0; a < 3; ++a) surfaceNormal_[3 * k + a] = float(-grad[a] / g);
                }
            }
        }
    });
}

void DipoleTree::computeLocalCorrection(bool useTree) {
    // K_k = the field at particle k of a uniform unit magnetization along each axis (one
    // column per axis): the full operator, surface term included, tree or exact as the
    // solve will evaluate it. K_k = N(x_k) + noise_k: N is the body's demagnetization
    // tensor, smooth on the body's scale; the noise is the particle-scale part (the
    // neighbours' positions). D_k = K_k - <K>_k, <K>_k the kernel-weighted mean of the
    // neighbours' K (k itself excluded, support kCorrectionReach times the particle's),
    // keeps N and removes the noise; it is applied only in the interior (fill ramp).
    const size_t n = size();
    localCorrection_.clear();
    if (n == 0 || coreOf(smoothing_) != Core::Wendland || nodes_.empty()) return;
    if (useTree && !(theta_ > 0)) useTree = false;
    const std::vector<float> mx = mx_, my = my_, mz = mz_; // restored below
    std::vector<double> K(9 * n);
    Eigen::VectorXd unit(3 * n), H;
    for (int c = 0; c < 3; ++c) {
        unit.setZero();
        for (size_t k = 0; k < n; ++k) unit[3 * k + c] = 1.0;
        setMagnetization(unit);
        fieldAtParticles(H, useTree);
        for (size_t k = 0; k < n; ++k)
            for (int a = 0; a < 3; ++a) K[9 * k + 3 * a + c] = H[3 * k + a];
    }
    mx_ = mx;
    my_ = my;
    mz_ = mz;
    sumCellMoments();

    std::vector<float> D(9 * n, 0.0f);
    const double reach = kCorrectionReach * nodes_[0].maxA;
    auto wendland = [](double r2, double A2) { // 2 pi A^3 / 21 * W(r; A): the shape only
        const double q = std::sqrt(r2 / A2), u = 1 - q;
        return u * u * u * u * (1 + 4 * q);
    };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint32_t> stack, ranges;
        for (size_t l = r.begin(); l < r.end(); ++l) {
            if (!leafHasTarget(l)) continue; // periodic copies: take their particle's D below
            const Node& target = nodes_[leaves_[l]];
            leavesWithin(target, reach, stack, ranges);
            for (uint32_t k = target.begin; k < target.end; ++k) {
                // Smooth part of K at x_k: a weighted linear least-squares fit over the
                // neighbours (moving least squares), its value at x_k. A plain weighted mean
                // is biased wherever the neighbourhood is one-sided (within two supports of a
                // surface or a floor) and N(x) varies: it would put the body's own field
                // variation into D.
                Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
                Eigen::Matrix<double, 4, 9> B = Eigen::Matrix<double, 4, 9>::Zero();
                double fill = 0;
                for (size_t q = 0; q < ranges.size(); q += 2)
                    for (uint32_t j = ranges[q]; j < ranges[q + 1]; ++j) {
                        const double dx = px_[j] - px_[k], dy = py_[j] - py_[k], dz = pz_[j] - pz_[k];
                        const double r2 = dx * dx + dy * dy + dz * dz;
                        const double a2 = a2_[j], A2 = kCorrectionReach * kCorrectionReach * a2;
                        if (!(r2 < A2)) continue;
                        // fill n_k with the particle kernel (as computeSurfaceTerms)
                        if (r2 < a2) fill += 21.0 / (2.0 * kPi) * ainv_[j] * ainv_[j] * ainv_[j] * vol_[j] * wendland(r2, a2);
                        if (j == k) continue;
                        const double w = vol_[j] * wendland(r2, A2);
                        const double sA = std::sqrt(A2);
                        const Eigen::Vector4d p(1.0, dx / sA, dy / sA, dz / sA);
                        A.noalias() += w * p * p.transpose();
                        for (int e = 0; e < 9; ++e) B.col(e) += (w * K[9 * size_t(j) + e]) * p;
                    }
                // Interior ramp on the fill: 0 below 0.7, 1 above 0.8 (a flat surface's top
                // layer has 0.5, the next ~0.85-0.9; the noise to remove is a few percent).
                const double t = std::clamp((fill - 0.7) / 0.1, 0.0, 1.0);
                const double wgt = t * t * (3 - 2 * t);
                if (wgt > 0 && A(0, 0) > 0) {
                    const Eigen::LDLT<Eigen::Matrix4d> ldlt(A);
                    const Eigen::Matrix<double, 4, 9> C = ldlt.solve(B);
                    if (ldlt.info() == Eigen::Success && C.allFinite())
                        for (int e = 0; e < 9; ++e) D[9 * k + e] = float(wgt * (K[9 * size_t(k) + e] - C(0, e)));
                }
            }
        }
    });
    copyToImages(D.data(), 9);
    localCorrection_ = std::move(D);
}

} // namespace ferro

// The field of the particles at any point (and at one particle): exact double sums and the
// tree walk with double-precision near and far terms (ParticleFieldEvaluator's queries).
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

Eigen::Vector3d DipoleTree::fieldAtParticleDirect(size_t k) const {
    const double p[3] = {px_[k], py_[k], pz_[k]};
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    Eigen::Vector3d h = kInv4Pi * directFieldD(p, src, size(), coreOf(smoothing_)) + farField_;
    addSurfaceTerm(k, h.data());
    return h;
}

Eigen::Vector3d DipoleTree::fieldAtDirect(const Eigen::Vector3d& point) const {
    const Eigen::Vector3d q = (point - origin_) / scale_;
    const double p[3] = {q.x(), q.y(), q.z()};
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    return kInv4Pi * directFieldD(p, src, size(), coreOf(smoothing_)) + farField_;
}

template <class Leaf, class Cell>
void DipoleTree::traverse(const Eigen::Vector3d& q, Leaf&& leaf, Cell&& cell) const {
    if (nodes_.empty()) return;
    uint32_t stack[64 * 8];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes_[stack[--top]];
        const uint32_t self = uint32_t(&node - nodes_.data());
        const double d = (q - Eigen::Vector3d(node.c[0], node.c[1], node.c[2])).norm();
        const bool ok = theta_ > 0 && accept(node, d);
        if (ok && node.end - node.begin > kMinCellCount) cell(self);
        else if (ok || node.childCount == 0) leaf(node.begin, node.end);
        else
            for (uint32_t c = node.childCount; c-- > 0;) stack[top++] = node.firstChild + c;
    }
}

Eigen::Vector3d DipoleTree::fieldAt(const Eigen::Vector3d& point) const {
    const Eigen::Vector3d q = (point - origin_) / scale_;
    const double p[3] = {q.x(), q.y(), q.z()};
    double h[3] = {0, 0, 0};
    traverse(
        q,
        [&](uint32_t b, uint32_t e) {
            for (uint32_t j = b; j < e; ++j)
                addDipoleD(p, px_[j], py_[j], pz_[j], mx_[j], my_[j], mz_[j], a2_[j], ainv_[j], coreOf(smoothing_), h);
        },
        [&](uint32_t c) {
            cellSumD<FieldTerm>(p, nodes_[c].c, &cell_[size_t(c) * kCellFloats], h);
        });
    return kInv4Pi * Eigen::Vector3d(h[0], h[1], h[2]) + farField_;
}

Mat3d DipoleTree::gradientAt(const Eigen::Vector3d& point) const {
    const Eigen::Vector3d q = (point - origin_) / scale_;
    const double p[3] = {q.x(), q.y(), q.z()};
    Mat3d G = Mat3d::Zero();
    traverse(
        q,
        [&](uint32_t b, uint32_t e) {
            for (uint32_t j = b; j < e; ++j)
                addDipoleGradientD(p, px_[j], py_[j], pz_[j], mx_[j], my_[j], mz_[j], a2_[j], ainv_[j], coreOf(smoothing_), G);
        },
        [&](uint32_t c) {
            double g[6] = {0, 0, 0, 0, 0, 0};
            cellSumD<GradientTerm>(p, nodes_[c].c, &cell_[size_t(c) * kCellFloats], g);
            G += symmetricMatrix(g);
        });
    return (kInv4Pi / scale_) * G;
}

Eigen::Vector3d DipoleTree::centroid() const {
    double v = 0;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < size(); ++k) {
        if (!isTarget(k)) continue; // a periodic copy
        v += vol_[k];
        c += double(vol_[k]) * Eigen::Vector3d(px_[k], py_[k], pz_[k]);
    }
    return v > 0 ? Eigen::Vector3d(origin_ + scale_ * c / v) : origin_;
}

Eigen::Vector3d DipoleTree::totalMoment() const {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < size(); ++k)
        if (isTarget(k)) m += Eigen::Vector3d(mx_[k], my_[k], mz_[k]); // not a periodic copy
    return scale_ * scale_ * scale_ * m;
}

} // namespace ferro

#include "sim/magnetics/DemagnetizationCurve.hpp"

#include "sim/magnetics/MagnetizationSolver.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace ferro {

DemagnetizationCurve::DemagnetizationCurve(double chi0, double Ms, int nodes)
    : chi0_(chi0), Ms_(Ms), nodes_(std::max(nodes, 2)), r_(size_t(std::max(nodes, 2)), 1.0) {}

double DemagnetizationCurve::nodePosition(double h) const {
    return std::clamp((std::log(h) - logLow_) / logSpan_ * double(nodes_ - 1), 0.0, double(nodes_ - 1));
}

void DemagnetizationCurve::fit(const std::vector<double>& h, const std::vector<double>& mAlong) {
    fitted_ = true;
    residual_ = 0;
    r_.assign(size_t(nodes_), 1.0);
    const size_t n = std::min(h.size(), mAlong.size());
    auto usable = [&](size_t i) { return h[i] > 0 && std::isfinite(h[i]) && std::isfinite(mAlong[i]); };
    double lo = 0, hi = 0;
    bool any = false;
    for (size_t i = 0; i < n; ++i) {
        if (!usable(i)) continue;
        lo = any ? std::min(lo, h[i]) : h[i];
        hi = any ? std::max(hi, h[i]) : h[i];
        any = true;
    }
    if (!any) return;
    logLow_ = std::log(lo);
    // A field of one strength everywhere (a uniform magnet) is one node's worth of data.
    logSpan_ = std::max(std::log(hi) - logLow_, 1e-9);

    // Least squares: minimise sum_i (m_i - r(h_i) M_law(h_i))^2 over the node values, r a
    // sum of hat functions (tridiagonal normal equations), plus a vanishing first-difference
    // penalty (1e-9 of the mean diagonal) that only decides nodes without particles: linear
    // between fitted nodes, constant beyond the ends.
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(nodes_, nodes_);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(nodes_);
    for (size_t i = 0; i < n; ++i) {
        if (!usable(i)) continue;
        const double law = langevinMagnetization(h[i], chi0_, Ms_);
        const double u = nodePosition(h[i]);
        const int b = std::min(int(u), nodes_ - 2);
        const double f = u - double(b);
        const double w0 = (1 - f) * law, w1 = f * law;
        A(b, b) += w0 * w0;
        A(b, b + 1) += w0 * w1;
        A(b + 1, b) += w0 * w1;
        A(b + 1, b + 1) += w1 * w1;
        y(b) += w0 * mAlong[i];
        y(b + 1) += w1 * mAlong[i];
    }
    const double scale = A.trace() / double(nodes_);
    if (!(scale > 0)) return;
    const double lambda = 1e-9 * scale;
    for (int b = 0; b + 1 < nodes_; ++b) {
        A(b, b) += lambda;
        A(b + 1, b + 1) += lambda;
        A(b, b + 1) -= lambda;
        A(b + 1, b) -= lambda;
    }
    const Eigen::VectorXd r = A.ldlt().solve(y);
    for (int b = 0; b < nodes_; ++b) r_[size_t(b)] = std::isfinite(r(b)) ? std::max(0.0, r(b)) : 1.0;
    double miss2 = 0, total2 = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!usable(i)) continue;
        const double d = mAlong[i] - magnetization(h[i]);
        miss2 += d * d;
        total2 += mAlong[i] * mAlong[i];
    }
    residual_ = total2 > 0 ? std::sqrt(miss2 / total2) : 0.0;
}

double DemagnetizationCurve::ratio(double h) const {
    if (!fitted_ || !(h > 0)) return r_.front();
    const double u = nodePosition(h);
    const int b = std::min(int(u), nodes_ - 2);
    const double f = u - double(b);
    return (1 - f) * r_[size_t(b)] + f * r_[size_t(b) + 1];
}

double DemagnetizationCurve::magnetization(double h) const {
    return ratio(h) * langevinMagnetization(h, chi0_, Ms_);
}

} // namespace ferro

#include "sim/solids/PanelTree.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace ferro {

void PanelTree::build(const std::vector<Panel>& panels) {
    const size_t n = panels.size();
    cells_.clear();
    order_.resize(n);
    std::iota(order_.begin(), order_.end(), 0u);
    panel_ = panels;
    centroid_.resize(n);
    for (size_t j = 0; j < n; ++j) centroid_[j] = panels[j].centroid;
    q_.assign(n, 0.0);
    if (n == 0) return;
    cells_.reserve(4 * n / kLeafSize + 2);
    buildCell(0, uint32_t(n));
    // Tree order, so a leaf reads contiguous memory.
    std::vector<Panel> p(n);
    reach2_.resize(n);
    for (size_t k = 0; k < n; ++k) {
        p[k] = panels[order_[k]];
        centroid_[k] = p[k].centroid;
        reach2_[k] = p[k].pointReach * p[k].pointReach;
    }
    panel_.swap(p);
}

int32_t PanelTree::buildCell(uint32_t begin, uint32_t end) {
    const int32_t id = int32_t(cells_.size());
    cells_.emplace_back();
    Vec3d lo = Vec3d::Constant(1e300), hi = Vec3d::Constant(-1e300);
    double reach = 0;
    for (uint32_t k = begin; k < end; ++k) {
        lo = lo.cwiseMin(centroid_[order_[k]]);
        hi = hi.cwiseMax(centroid_[order_[k]]);
        reach = std::max(reach, panel_[order_[k]].expandReach);
    }
    Cell cell;
    cell.center = 0.5 * (lo + hi);
    cell.begin = begin;
    cell.end = end;
    cell.reach = reach;
    for (uint32_t k = begin; k < end; ++k)
        cell.radius = std::max(cell.radius, (centroid_[order_[k]] - cell.center).norm() + panel_[order_[k]].radius);
    if (end - begin > uint32_t(kLeafSize)) {
        // Split at the median along the box's longest side (ties by index: the same tree
        // on every run).
        int axis = 0;
        (hi - lo).maxCoeff(&axis);
        const uint32_t mid = begin + (end - begin) / 2;
        std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](uint32_t a, uint32_t b) {
            const double ca = centroid_[a][axis], cb = centroid_[b][axis];
            return ca < cb || (ca == cb && a < b);
        });
        cell.child[0] = buildCell(begin, mid);
        cell.child[1] = buildCell(mid, end);
    }
    cells_[size_t(id)] = cell;
    return id;
}

void PanelTree::setCharges(const std::vector<double>& q) {
    for (size_t k = 0; k < order_.size(); ++k) q_[k] = q[order_[k]];
    // Moments of every cell from its own panels: O(P log P) a solve, beside the solve's own
    // O(P^2) operator, so no upward pass from the children.
    for (Cell& c : cells_) {
        c.q = 0;
        c.absQ = 0;
        c.dipole.setZero();
        std::fill(std::begin(c.second), std::end(c.second), 0.0);
        for (uint32_t k = c.begin; k < c.end; ++k) {
            const Vec3d s = centroid_[k] - c.center;
            const double qk = q_[k];
            c.q += qk;
            c.absQ += std::abs(qk);
            c.dipole += qk * s;
            const double* own = panel_[k].second;
            c.second[0] += qk * (s.x() * s.x() + own[0]);
            c.second[1] += qk * (s.y() * s.y() + own[1]);
            c.second[2] += qk * (s.z() * s.z() + own[2]);
            c.second[3] += qk * (s.x() * s.y() + own[3]);
            c.second[4] += qk * (s.x() * s.z() + own[4]);
            c.second[5] += qk * (s.y() * s.z() + own[5]);
        }
    }
}

void PanelTree::evaluate(const Vec3d& x, double openingAngle, double tolerance, double minGap, Eigen::Vector3d& h,
                         Eigen::Matrix3d& g, std::vector<uint32_t>& near) const {
    if (cells_.empty()) return;
    // The sums in scalars: the field and the Jacobian's six independent entries (the Hessian
    // of a potential is symmetric).
    double hx = 0, hy = 0, hz = 0, gxx = 0, gyy = 0, gzz = 0, gxy = 0, gxz = 0, gyz = 0;
    int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Cell& c = cells_[size_t(stack[--top])];
        const double rx = x.x() - c.center.x(), ry = x.y() - c.center.y(), rz = x.z() - c.center.z();
        const double d2 = rx * rx + ry * ry + rz * rz;
        const double d = std::sqrt(d2);
        const double gap = d - c.radius;
        if (c.radius < openingAngle * d && gap >= c.reach && gap > 0 && gap >= minGap &&
            c.absQ * c.radius * c.radius * c.radius <= tolerance * gap * gap * gap * gap * gap) {
            // The cell's multipole: phi = Q/r - D . grad(1/r) + M : grad grad(1/r) / 2,
            // H = -grad phi, J = -grad grad phi (the derivative tensors of 1/r to fourth order):
            //   H_a  = Q r_a / r^3 + D_i T2_ia - M_ij T3_ija / 2
            //   J_ab = -Q T2_ab + D_i T3_iab - M_ij T4_ijab / 2
            const double inv = 1.0 / d, inv2 = inv * inv;
            const double inv3 = inv * inv2, inv5 = inv3 * inv2, inv7 = inv5 * inv2, inv9 = inv7 * inv2;
            const double Dx = c.dipole.x(), Dy = c.dipole.y(), Dz = c.dipole.z();
            const double Mxx = c.second[0], Myy = c.second[1], Mzz = c.second[2], Mxy = c.second[3], Mxz = c.second[4],
                         Myz = c.second[5];
            const double Dr = Dx * rx + Dy * ry + Dz * rz, trM = Mxx + Myy + Mzz;
            const double Mrx = Mxx * rx + Mxy * ry + Mxz * rz, Mry = Mxy * rx + Myy * ry + Myz * rz,
                         Mrz = Mxz * rx + Myz * ry + Mzz * rz;
            const double rMr = rx * Mrx + ry * Mry + rz * Mrz;
            // H: a r + D terms + Mr terms.
            const double ar = c.q * inv3 + 3.0 * Dr * inv2 * inv3 + 7.5 * rMr * inv7 - 1.5 * trM * inv5;
            hx += ar * rx - Dx * inv3 - 3.0 * inv5 * Mrx;
            hy += ar * ry - Dy * inv3 - 3.0 * inv5 * Mry;
            hz += ar * rz - Dz * inv3 - 3.0 * inv5 * Mrz;
            // J = A rr^T + B I + C (D r^T + r D^T) + E (Mr r^T + r Mr^T) + F M.
            const double A = -3.0 * c.q * inv5 - 15.0 * Dr * inv7 - 52.5 * rMr * inv9 + 7.5 * trM * inv7;
            const double B = c.q * inv3 + 3.0 * Dr * inv5 + 7.5 * rMr * inv7 - 1.5 * trM * inv5;
            const double C = 3.0 * inv5, E = 15.0 * inv7, F = -3.0 * inv5;
            gxx += A * rx * rx + B + 2.0 * C * Dx * rx + 2.0 * E * Mrx * rx + F * Mxx;
            gyy += A * ry * ry + B + 2.0 * C * Dy * ry + 2.0 * E * Mry * ry + F * Myy;
            gzz += A * rz * rz + B + 2.0 * C * Dz * rz + 2.0 * E * Mrz * rz + F * Mzz;
            gxy += A * rx * ry + C * (Dx * ry + Dy * rx) + E * (Mrx * ry + Mry * rx) + F * Mxy;
            gxz += A * rx * rz + C * (Dx * rz + Dz * rx) + E * (Mrx * rz + Mrz * rx) + F * Mxz;
            gyz += A * ry * rz + C * (Dy * rz + Dz * ry) + E * (Mry * rz + Mrz * ry) + F * Myz;
            continue;
        }
        if (c.child[0] >= 0) {
            // Children in a fixed order: the sum's order is a function of x alone.
            stack[top++] = c.child[1];
            stack[top++] = c.child[0];
            continue;
        }
        for (uint32_t k = c.begin; k < c.end; ++k) {
            const double sx = x.x() - centroid_[k].x(), sy = x.y() - centroid_[k].y(), sz = x.z() - centroid_[k].z();
            const double s2 = sx * sx + sy * sy + sz * sz;
            if (!(s2 >= reach2_[k])) {
                near.push_back(order_[k]);
                continue;
            }
            const double invs2 = 1.0 / s2;
            const double w = q_[k] * invs2 * std::sqrt(invs2), w3 = 3.0 * w * invs2;
            hx += w * sx;
            hy += w * sy;
            hz += w * sz;
            gxx += w - w3 * sx * sx;
            gyy += w - w3 * sy * sy;
            gzz += w - w3 * sz * sz;
            gxy -= w3 * sx * sy;
            gxz -= w3 * sx * sz;
            gyz -= w3 * sy * sz;
        }
    }
    h += Eigen::Vector3d(hx, hy, hz);
    Eigen::Matrix3d j;
    j << gxx, gxy, gxz, gxy, gyy, gyz, gxz, gyz, gzz;
    g += j;
}

} // namespace ferro

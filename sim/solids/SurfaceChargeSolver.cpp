#include "sim/solids/SurfaceChargeSolver.hpp"

#include "sim/core/Constants.hpp"
#include "sim/core/Gmres.hpp"
#include "sim/solids/PanelIntegral.hpp"

#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace ferro {

namespace {


template <class F>
void parallelFor(size_t n, F&& f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
}

} // namespace

std::vector<double> SurfaceChargeSolver::curvatureTerms(const std::vector<SolidSurface>& surfaces) const {
    // The flat panel's principal value at its own centroid is 0 along its normal, but the
    // curved surface it stands for bends away from the tangent plane by kappa r^2 / 2, which
    // gives n . (x - y) / |x - y|^3 ~ (kappa_1 cos^2 + kappa_2 sin^2) / (2 |x - y|): over the
    // panel, H_mean / 2 * integral_T dA / |x - y| (H_mean = (kappa_1 + kappa_2) / 2). Without
    // it the solve's error falls only as the panel size (2.7 % of a sphere's moment at 5,120
    // panels), with it as its square. The mean curvature comes from the edge neighbours,
    // (n_j - n_i) . (c_j - c_i) / |c_j - c_i|^2 (1 / radius on a sphere, convex positive),
    // averaged over the neighbours across smooth edges; a crease (normals more than 30
    // degrees apart) is the panels' own edge, which the neighbour's exact field already has.
    std::vector<double> out(centroid_.size(), 0.0);
    size_t offset = 0;
    for (const SolidSurface& s : surfaces) {
        std::unordered_map<uint64_t, uint32_t> edgeOwner;
        for (size_t t = 0; t < s.triangles.size(); ++t)
            for (int k = 0; k < 3; ++k)
                edgeOwner[(uint64_t(s.triangles[t][k]) << 32) | s.triangles[t][(k + 1) % 3]] = uint32_t(t);
        for (size_t t = 0; t < s.triangles.size(); ++t) {
            const size_t i = offset + t;
            double sum = 0;
            int count = 0;
            for (int k = 0; k < 3; ++k) {
                const auto it = edgeOwner.find((uint64_t(s.triangles[t][(k + 1) % 3]) << 32) | s.triangles[t][k]);
                if (it == edgeOwner.end()) continue;
                const size_t j = offset + it->second;
                if (normal_[i].dot(normal_[j]) < std::cos(kPi / 6)) continue;
                const Vec3d dc = centroid_[j] - centroid_[i];
                sum += (normal_[j] - normal_[i]).dot(dc) / dc.squaredNorm();
                ++count;
            }
            if (count == 0) continue;
            // integral_T dA / |x - y| at the centroid: sum over edges of the distance to the
            // edge's line times the edge's integral of 1 / |x - y|.
            double inv = 0;
            for (int k = 0; k < 3; ++k) {
                const Vec3d& p = corner_[i][k];
                const Vec3d& q = corner_[i][(k + 1) % 3];
                const Vec3d t3 = (q - p).normalized();
                const Vec3d u = t3.cross(normal_[i]);
                const double dist = (p - centroid_[i]).dot(u);
                const double sp = (p - centroid_[i]).dot(t3), sq = (q - centroid_[i]).dot(t3);
                inv += dist * std::log(((q - centroid_[i]).norm() + sq) / ((p - centroid_[i]).norm() + sp));
            }
            out[i] = 0.5 * (sum / count) * inv;
        }
        offset += s.triangles.size();
    }
    return out;
}

void SurfaceChargeSolver::setSurfaces(const std::vector<SolidSurface>& surfaces) {
    corner_.clear();
    centroid_.clear();
    normal_.clear();
    area_.clear();
    radius_.clear();
    rule_.clear();
    body_.clear();
    chi0_.clear();
    saturation_.clear();
    bodyArea_.assign(surfaces.size(), 0.0);
    for (size_t b = 0; b < surfaces.size(); ++b) {
        const SolidSurface& s = surfaces[b];
        for (const auto& t : s.triangles) {
            const std::array<Vec3d, 3> p{s.vertices[t[0]], s.vertices[t[1]], s.vertices[t[2]]};
            const Vec3d cross = (p[1] - p[0]).cross(p[2] - p[0]);
            const double a2 = cross.norm();
            const Vec3d c = (p[0] + p[1] + p[2]) / 3.0;
            corner_.push_back(p);
            centroid_.push_back(c);
            normal_.push_back(a2 > 0 ? Vec3d(cross / a2) : Vec3d::UnitZ());
            area_.push_back(0.5 * a2);
            radius_.push_back(std::max({(p[0] - c).norm(), (p[1] - c).norm(), (p[2] - c).norm()}));
            rule_.push_back({(4 * p[0] + p[1] + p[2]) / 6.0, (p[0] + 4 * p[1] + p[2]) / 6.0, (p[0] + p[1] + 4 * p[2]) / 6.0});
            body_.push_back(uint32_t(b));
            chi0_.push_back(s.permeability - 1.0);
            saturation_.push_back(s.saturation);
            bodyArea_[b] += 0.5 * a2;
        }
    }
    const size_t n = centroid_.size();
    const std::vector<double> selfCurvature = curvatureTerms(surfaces);
    // Near lists: every source within kRuleReach of its own radius, with its accurate field
    // at the target less the point charge the far sum gives it (so the far sum runs over all
    // panels, branch-free, and the list corrects it).
    std::vector<std::vector<std::pair<uint32_t, Vec3d>>> lists(n);
    parallelFor(n, [&](size_t i) {
        const Vec3d& x = centroid_[i];
        for (size_t j = 0; j < n; ++j) {
            const Vec3d r = x - centroid_[j];
            const double d = r.norm();
            if (d >= kRuleReach * radius_[j]) continue;
            Vec3d exact;
            if (j == i)
                exact = uniformTriangleField(x, corner_[j][0], corner_[j][1], corner_[j][2], true) +
                        selfCurvature[i] * normal_[i];
            else if (d < kExactReach * radius_[j]) {
                exact = Vec3d::Zero();
                for (const Vec3d& xt : rule_[i]) exact += uniformTriangleField(xt, corner_[j][0], corner_[j][1], corner_[j][2]) / 3.0;
            }
            else {
                exact = Vec3d::Zero();
                for (const Vec3d& y : rule_[j]) {
                    const Vec3d ry = x - y;
                    exact += ry / std::pow(ry.squaredNorm(), 1.5);
                }
                exact *= area_[j] / 3.0;
            }
            const Vec3d point = d > 0 ? Vec3d(area_[j] * r / (d * d * d)) : Vec3d::Zero();
            lists[i].emplace_back(uint32_t(j), exact - point);
        }
    });
    nearStart_.assign(n + 1, 0);
    for (size_t i = 0; i < n; ++i) nearStart_[i + 1] = nearStart_[i] + uint32_t(lists[i].size());
    nearIndex_.resize(nearStart_[n]);
    nearField_.resize(nearStart_[n]);
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < lists[i].size(); ++k) {
            nearIndex_[nearStart_[i] + k] = lists[i][k].first;
            nearField_[nearStart_[i] + k] = lists[i][k].second;
        }
    sigma_.clear(); // no warm start across a new set of panels
    tau_.clear();
    chi_ = chi0_;
    secantField_.clear();
    lastField_.clear();
    magnitude_.assign(n, 0.0);
    interiorSolved_ = false;
    // fieldAndGradient's float arrays: centroids about their mean (float keeps its digits
    // there) and each panel's near reach; the charges follow each solve.
    origin_ = Vec3d::Zero();
    for (const Vec3d& c : centroid_) origin_ += c / double(n);
    pcx_.resize(n);
    pcy_.resize(n);
    pcz_.resize(n);
    preach2_.resize(n);
    for (size_t j = 0; j < n; ++j) {
        const Vec3d c = centroid_[j] - origin_;
        pcx_[j] = float(c.x());
        pcy_[j] = float(c.y());
        pcz_[j] = float(c.z());
        preach2_[j] = float(kPointRuleReach * radius_[j] * kPointRuleReach * radius_[j]);
    }
    pq_.clear(); // no charge until a solve
    tree_ = PanelTree();
    if (params_.openingAngle > 0 && n >= params_.treeMinPanels) {
        std::vector<PanelTree::Panel> panels(n);
        for (size_t j = 0; j < n; ++j) {
            PanelTree::Panel& p = panels[j];
            p.centroid = centroid_[j];
            p.radius = radius_[j];
            p.expandReach = kPointExactReach * radius_[j];
            p.pointReach = kPointRuleReach * radius_[j];
            // A uniform triangle's second moment about its centroid: its 3-point rule's, the
            // points halfway from the centroid to the corners, (1/12) sum (v - c)(v - c)^T.
            for (const Vec3d& v : corner_[j]) {
                const Vec3d d = v - centroid_[j];
                p.second[0] += d.x() * d.x() / 12;
                p.second[1] += d.y() * d.y() / 12;
                p.second[2] += d.z() * d.z() / 12;
                p.second[3] += d.x() * d.y() / 12;
                p.second[4] += d.x() * d.z() / 12;
                p.second[5] += d.y() * d.z() / 12;
            }
        }
        tree_.build(panels);
    }
    // The normal operator as a dense float matrix when it fits (kDenseLimit panels, 151 MB):
    // a GMRES step is then a matrix-vector product instead of the O(P^2) pair sweep.
    dense_.resize(0, 0);
    if (n > 0 && n <= kDenseLimit) {
        dense_.resize(Eigen::Index(n), Eigen::Index(n));
        parallelFor(n, [&](size_t i) {
            const Vec3d& x = centroid_[i];
            for (size_t j = 0; j < n; ++j) {
                const Vec3d r = x - centroid_[j];
                const double r2 = r.squaredNorm();
                dense_(Eigen::Index(i), Eigen::Index(j)) = r2 > 0 ? float(area_[j] * normal_[i].dot(r) / (r2 * std::sqrt(r2))) : 0.0f;
            }
            for (uint32_t k = nearStart_[i]; k < nearStart_[i + 1]; ++k)
                dense_(Eigen::Index(i), Eigen::Index(nearIndex_[k])) += float(normal_[i].dot(nearField_[k]));
        });
    }
}

void SurfaceChargeSolver::collocationField(const std::vector<double>& d, std::vector<Vec3d>& out) const {
    const size_t n = centroid_.size();
    out.resize(n);
    std::vector<double> q(n);
    for (size_t j = 0; j < n; ++j) q[j] = d[j] * area_[j];
    parallelFor(n, [&](size_t i) {
        const Vec3d& x = centroid_[i];
        double hx = 0, hy = 0, hz = 0;
        for (size_t j = 0; j < n; ++j) {
            const double rx = x.x() - centroid_[j].x(), ry = x.y() - centroid_[j].y(), rz = x.z() - centroid_[j].z();
            const double r2 = rx * rx + ry * ry + rz * rz;
            if (!(r2 > 0)) continue;
            const double w = q[j] / (r2 * std::sqrt(r2));
            hx += w * rx;
            hy += w * ry;
            hz += w * rz;
        }
        Vec3d h(hx, hy, hz);
        for (uint32_t k = nearStart_[i]; k < nearStart_[i + 1]; ++k) h += d[nearIndex_[k]] * nearField_[k];
        out[i] = h;
    });
}

Vec3d SurfaceChargeSolver::densityField(const std::vector<double>& d, const Vec3d& x) const {
    Vec3d h = Vec3d::Zero();
    if (d.size() != centroid_.size()) return h; // nothing solved: no charge
    for (size_t j = 0; j < centroid_.size(); ++j) {
        if (d[j] == 0) continue;
        const Vec3d r = x - centroid_[j];
        const double dist = r.norm();
        if (dist < kExactReach * radius_[j]) {
            h += d[j] * uniformTriangleField(x, corner_[j][0], corner_[j][1], corner_[j][2]);
        } else if (dist < kRuleReach * radius_[j]) {
            Vec3d s = Vec3d::Zero();
            for (const Vec3d& y : rule_[j]) {
                const Vec3d ry = x - y;
                s += ry / std::pow(ry.squaredNorm(), 1.5);
            }
            h += d[j] * area_[j] / 3.0 * s;
        } else {
            h += d[j] * area_[j] * r / (dist * dist * dist);
        }
    }
    return h;
}

std::vector<double> SurfaceChargeSolver::bodyCharges(const std::vector<double>& d) const {
    std::vector<double> total(bodyArea_.size(), 0.0);
    for (size_t i = 0; i < d.size(); ++i) total[body_[i]] += area_[i] * d[i];
    return total;
}

void SurfaceChargeSolver::normalField(const std::vector<double>& d, std::vector<double>& out) const {
    const size_t n = centroid_.size();
    out.resize(n);
    if (dense_.rows() == Eigen::Index(n)) {
        Eigen::VectorXf v(n);
        for (size_t j = 0; j < n; ++j) v[Eigen::Index(j)] = float(d[j]);
        const Eigen::VectorXf r = dense_ * v;
        for (size_t i = 0; i < n; ++i) out[i] = double(r[Eigen::Index(i)]);
        return;
    }
    std::vector<Vec3d> F;
    collocationField(d, F);
    for (size_t i = 0; i < n; ++i) out[i] = normal_[i].dot(F[i]);
}

int SurfaceChargeSolver::solveLayer(double diag, const std::vector<double>& lambda, const std::vector<double>& rhs,
                                    std::vector<double>& u, double& residual) const {
    const size_t n = centroid_.size();
    const double sign = diag > 0 ? 1.0 : -1.0;
    std::vector<double> tmp(n), Fn;
    auto apply = [&](const std::vector<double>& v, Eigen::VectorXd& out) {
        normalField(v, Fn);
        const std::vector<double> total = bodyCharges(v); // the deflation of each conductor mode
        out.resize(Eigen::Index(n));
        for (size_t i = 0; i < n; ++i) {
            const double b = bodyArea_[body_[i]];
            out[Eigen::Index(i)] = diag * v[i] - lambda[i] * kInv4Pi * Fn[i] + sign * (b > 0 ? total[body_[i]] / b : 0.0);
        }
    };
    auto op = [&](const Eigen::VectorXd& v) {
        for (size_t i = 0; i < n; ++i) tmp[i] = v[Eigen::Index(i)];
        Eigen::VectorXd out;
        apply(tmp, out);
        return out;
    };
    Eigen::VectorXd b(n), x;
    for (size_t i = 0; i < n; ++i) b[Eigen::Index(i)] = rhs[i];
    const double bn = b.norm();
    if (!(bn > 0)) {
        u.assign(n, 0.0);
        residual = 0;
        return 0;
    }
    // Warm start: the last solution (the magnets and the fluid move little between solves),
    // GMRES on the correction.
    int applied = 0;
    const bool warm = u.size() == n;
    if (warm) {
        Eigen::VectorXd Au;
        apply(u, Au);
        ++applied;
        b -= Au;
    } else {
        u.assign(n, 0.0);
    }
    double res = b.norm();
    if (res > params_.tolerance * bn)
        applied += gmres(op, b, x, params_.tolerance * bn, params_.maxIterations, 60, res);
    else
        x.setZero(Eigen::Index(n));
    for (size_t i = 0; i < n; ++i) u[i] += x[Eigen::Index(i)];
    residual = res / bn;
    return applied;
}

SurfaceChargeSolver::Stats SurfaceChargeSolver::solve(const std::function<Vec3d(const Vec3d&)>& applied) {
    Stats st;
    const size_t n = centroid_.size();
    if (n == 0) return st;
    std::vector<double> h0n(n);
    parallelFor(n, [&](size_t i) { h0n[i] = applied(centroid_[i]).dot(normal_[i]); });
    const bool saturating = std::any_of(saturation_.begin(), saturation_.end(), [](double m) { return m > 0; });
    // The saturation's secants cost an interior solve and an all-pairs field sweep a step, so
    // they are kept between solves and fitted again only when due: after a cold start, or once
    // the applied field at the panels has moved by kSecantRefresh since their last fit.
    bool due = saturating && (chi_.size() != n || secantField_.size() != n);
    if (saturating && !due) {
        double d2 = 0, s2 = 0;
        for (size_t i = 0; i < n; ++i) {
            d2 += (h0n[i] - secantField_[i]) * (h0n[i] - secantField_[i]);
            s2 += secantField_[i] * secantField_[i];
        }
        due = d2 > kSecantRefresh * kSecantRefresh * s2;
    }
    if (chi_.size() != n) chi_ = chi0_;
    // The warm start scaled by the applied field's change along its last pattern: a coil's
    // current ramping up or down (the charge is linear in it) then starts at the answer.
    if (sigma_.size() == n && lastField_.size() == n) {
        double along = 0, last2 = 0;
        for (size_t i = 0; i < n; ++i) {
            along += h0n[i] * lastField_[i];
            last2 += lastField_[i] * lastField_[i];
        }
        if (last2 > 0)
            for (double& v : sigma_) v *= along / last2;
    }
    lastField_ = h0n;
    std::vector<double> lambda(n), rhs(n);
    for (int step = 0;; ++step) {
        for (size_t i = 0; i < n; ++i) {
            lambda[i] = chi_[i] / (chi_[i] + 2.0);
            rhs[i] = lambda[i] * h0n[i];
        }
        double res = 0;
        st.iterations += solveLayer(0.5, lambda, rhs, sigma_, res);
        // A body's net charge is zero (div B = 0); the flat panels' quadrature leaves ~1 % of
        // its charge as a net monopole (a cone in a coil's field), whose 1/r^2 field would
        // outlast the dipole far away: removed as a uniform density.
        const std::vector<double> total = bodyCharges(sigma_);
        for (size_t i = 0; i < n; ++i)
            if (bodyArea_[body_[i]] > 0) sigma_[i] -= total[body_[i]] / bodyArea_[body_[i]];
        st.residual = res;
        st.converged = st.converged && res <= params_.tolerance * 1.0001;
        interiorSolved_ = false;
        if (!due) break; // the interior layer waits until asked for (interiorField)
        st.iterations += solveInterior();
        double change = 0;
        for (size_t i = 0; i < n; ++i) {
            const double h = magnitude_[i] / chi_[i];
            if (saturation_[i] > 0) {
                // The Froehlich-Kennelly secant at the panel's field. The map chi -> secant is
                // monotone (a lower chi shields less, the field inside rises, the secant
                // falls further) with a slope under 1 on a sphere (0.53 at its knee), so the
                // plain iteration converges without overshoot; a geometric-mean damping took
                // over 30 steps at the knee.
                const double next = chi0_[i] / (1.0 + chi0_[i] * h / saturation_[i]);
                change = std::max(change, std::abs(next - chi_[i]) / chi_[i]);
                chi_[i] = next;
            }
        }
        if (change < 1e-3 || step + 1 >= params_.saturationSteps) {
            st.secantSteps = step + 1;
            secantField_ = h0n;
            break;
        }
    }
    // The charges of fieldAndGradient's float pass.
    pq_.resize(n);
    std::vector<double> q(n);
    double s2 = 0, area = 0;
    for (size_t j = 0; j < n; ++j) {
        q[j] = sigma_[j] * area_[j];
        pq_[j] = float(q[j]);
        s2 += sigma_[j] * sigma_[j] * area_[j];
        area += area_[j];
    }
    if (!tree_.empty()) {
        tree_.setCharges(q);
        // The field at the surface is of the order of the charge density (H_n outside = sigma
        // + H_n inside); 4 pi: the sums carry no 1/(4 pi).
        treeTolerance_ = params_.treeTolerance * 4.0 * kPi * std::sqrt(s2 / std::max(area, 1e-300));
    }
    return st;
}

int SurfaceChargeSolver::solveInterior() const {
    if (interiorSolved_ || sigma_.size() != centroid_.size()) return 0;
    // The interior layer: -tau/2 + K'[tau] = sigma / chi (the inside normal field);
    // solveLayer's "- lambda K'" with lambda -1.
    const size_t n = centroid_.size();
    std::vector<double> rhs(n), minusOnes(n, -1.0);
    for (size_t i = 0; i < n; ++i) rhs[i] = chi_[i] > 0 ? sigma_[i] / chi_[i] : 0.0;
    double res = 0;
    const int it = solveLayer(-0.5, minusOnes, rhs, tau_, res);
    std::vector<Vec3d> F;
    collocationField(tau_, F);
    for (size_t i = 0; i < n; ++i) magnitude_[i] = chi_[i] * (kInv4Pi * F[i] - 0.5 * tau_[i] * normal_[i]).norm();
    interiorSolved_ = true;
    return it;
}

Vec3d SurfaceChargeSolver::field(const Vec3d& x) const { return kInv4Pi * densityField(sigma_, x); }

void SurfaceChargeSolver::pointSum(const Vec3d& x, Vec3d& h, Mat3d& g, std::vector<uint32_t>& near, double keepNear) const {
    const size_t n = centroid_.size();
    if (!tree_.empty()) {
        near.clear();
        h.setZero();
        g.setZero();
        tree_.evaluate(x, params_.openingAngle, treeTolerance_, keepNear, h, g, near);
        return;
    }
    // Pass 1, branch-free over every panel (float, centroids about origin_): the point-charge
    // field and Jacobian of the panels beyond kPointRuleReach radii, and a flag for the rest.
    // Eight lanes of partial sums, panel j into lane j % 8, added in a fixed order at the end:
    // the compiler keeps each lane's adds in order, so the loop vectorizes (SSE or wider)
    // without reordering a sum, and the result is the same bits on every thread count.
    thread_local std::vector<float> nearFlag;
    nearFlag.resize(n);
    const Vec3d xl = x - origin_;
    const float X = float(xl.x()), Y = float(xl.y()), Z = float(xl.z());
    constexpr size_t kLanes = 8;
    alignas(32) float acc[9][kLanes] = {};
    const float* cx = pcx_.data();
    const float* cy = pcy_.data();
    const float* cz = pcz_.data();
    const float* q = pq_.data();
    const float* reach2 = preach2_.data();
    float* flag = nearFlag.data();
    auto panel = [&](size_t j, size_t k) {
        const float dx = X - cx[j], dy = Y - cy[j], dz = Z - cz[j];
        const float r2 = dx * dx + dy * dy + dz * dz;
        const bool far = r2 >= reach2[j];
        flag[j] = far ? 0.0f : 1.0f;
        const float safe = far ? r2 : 1.0f;
        const float inv = 1.0f / std::sqrt(safe);
        const float inv2 = inv * inv;
        const float w = far ? q[j] * inv2 * inv : 0.0f; // q / r^3
        const float w3 = 3.0f * w * inv2;
        acc[0][k] += w * dx;
        acc[1][k] += w * dy;
        acc[2][k] += w * dz;
        acc[3][k] += w - w3 * dx * dx;
        acc[4][k] += w - w3 * dy * dy;
        acc[5][k] += w - w3 * dz * dz;
        acc[6][k] -= w3 * dx * dy;
        acc[7][k] -= w3 * dx * dz;
        acc[8][k] -= w3 * dy * dz;
    };
    size_t j0 = 0;
    for (; j0 + kLanes <= n; j0 += kLanes)
        for (size_t k = 0; k < kLanes; ++k) panel(j0 + k, k);
    for (size_t k = 0; j0 + k < n; ++k) panel(j0 + k, k);
    float sum[9];
    for (int c = 0; c < 9; ++c) {
        sum[c] = 0;
        for (size_t k = 0; k < kLanes; ++k) sum[c] += acc[c][k];
    }
    const float hx = sum[0], hy = sum[1], hz = sum[2], gxx = sum[3], gyy = sum[4], gzz = sum[5], gxy = sum[6],
                gxz = sum[7], gyz = sum[8];
    h = Vec3d(hx, hy, hz);
    g << gxx, gxy, gxz, gxy, gyy, gyz, gxz, gyz, gzz;
    near.clear();
    for (size_t j = 0; j < n; ++j)
        if (flag[j] != 0.0f) near.push_back(uint32_t(j));
}

void SurfaceChargeSolver::addNearPanels(const Vec3d& x, const std::vector<uint32_t>& near, Vec3d& h, Mat3d& g) const {
    // The near panels by their closed form (within kPointExactReach radii) or the 3-point rule.
    for (const uint32_t j : near) {
        const double d = sigma_[j];
        if (d == 0) continue;
        const double dist = (x - centroid_[j]).norm();
        if (dist < kPointExactReach * radius_[j]) {
            h += d * uniformTriangleField(x, corner_[j][0], corner_[j][1], corner_[j][2]);
            g += d * uniformTriangleGradient(x, corner_[j][0], corner_[j][1], corner_[j][2]);
            continue;
        }
        for (const Vec3d& y : rule_[j]) {
            const Vec3d ry = x - y;
            const double s2 = ry.squaredNorm();
            const double inv3 = d * area_[j] / 3.0 / (s2 * std::sqrt(s2));
            h += inv3 * ry;
            g += inv3 * (Mat3d::Identity() - 3.0 * ry * ry.transpose() / s2);
        }
    }
}

void SurfaceChargeSolver::fieldAndGradient(const Vec3d& x, Vec3d& H, Mat3d& J, double standoff) const {
    const size_t n = centroid_.size();
    if (sigma_.size() != n || pq_.size() != n) { // nothing solved: no charge
        H.setZero();
        J.setZero();
        return;
    }
    thread_local std::vector<uint32_t> near;
    Vec3d h;
    Mat3d g;
    pointSum(x, h, g, near, standoff);
    if (standoff > 0) {
        // The nearest surface point among the panels that can be within the standoff (each
        // such panel is a near one: the tree expands no cell within the standoff, and
        // kPointRuleReach radii exceed radius + standoff for any standoff under 5 radii; a
        // larger one still finds the nearest of these).
        double best = standoff;
        Vec3d foot = Vec3d::Zero(), normal = Vec3d::Zero();
        bool inside = false;
        for (const uint32_t j : near) {
            if ((x - centroid_[j]).norm() > radius_[j] + best) continue;
            const Vec3d p = closestPointOnTriangle(x, corner_[j][0], corner_[j][1], corner_[j][2]);
            const double d = (x - p).norm();
            if (d < best) {
                best = d;
                foot = p;
                // Outside, the direction from the foot (the distance field's gradient: the
                // moved point is continuous across an edge or corner between panels of
                // different normals); inside or on the surface, the panel's normal.
                inside = normal_[j].dot(x - p) <= 1e-3 * standoff;
                normal = inside ? normal_[j] : Vec3d((x - p) / d);
            }
        }
        if (best < standoff || inside) {
            // Evaluated at the moved point x' = foot + standoff n. On a panel's face (and
            // about an edge, along it) dx'/dx = P = I - n n^T, and the callers use J as J v (J symmetric: grad|H| =
            // J H / |H|, (M . grad) H = J M), so J = P J(x') gives the exact gradient of the
            // moved field, P J(x') H / |H|: the force stays conservative.
            const Vec3d xs = foot + standoff * normal;
            pointSum(xs, h, g, near);
            addNearPanels(xs, near, h, g);
            H = kInv4Pi * h;
            J = kInv4Pi * (Mat3d::Identity() - normal * normal.transpose()) * g;
            return;
        }
    }
    addNearPanels(x, near, h, g);
    H = kInv4Pi * h;
    J = kInv4Pi * g;
}

Vec3d SurfaceChargeSolver::interiorField(const Vec3d& x) const {
    solveInterior();
    return kInv4Pi * densityField(tau_, x);
}

const std::vector<double>& SurfaceChargeSolver::magnetizationMagnitude() const {
    solveInterior();
    return magnitude_;
}

} // namespace ferro

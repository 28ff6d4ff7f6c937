// The dipole tree: the octree over the particles (Morton order), its interaction lists and
// cell moments, and the tree sums of the field and its Jacobian at every particle.
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

void DipoleTree::build(const std::vector<Vec3>& x, const std::vector<Real>& volume, double openingAngle,
                       int leafSize) {
    targetCount_ = x.size();
    farImages_.setZero();
    farField_.setZero(); // set again with the magnetization
    if (!periodic() || x.empty()) {
        buildFrom(x, volume, openingAngle, leafSize);
        return;
    }
    // The particles, then their copies shifted by one period to every side (input i of the
    // tree is particle i % n).
    std::vector<Vec3> xe;
    std::vector<Real> ve;
    const size_t n = x.size();
    const int reach[2] = {period_[0] > 0 ? 1 : 0, period_[1] > 0 ? 1 : 0};
    std::vector<std::pair<int, int>> shifts{{0, 0}};
    for (int b = -reach[1]; b <= reach[1]; ++b)
        for (int a = -reach[0]; a <= reach[0]; ++a)
            if (a || b) shifts.emplace_back(a, b);
    xe.reserve(shifts.size() * n);
    ve.reserve(shifts.size() * n);
    for (const auto& [a, b] : shifts) {
        const Vec3 s(Real(a * period_[0]), Real(b * period_[1]), 0);
        for (size_t i = 0; i < n; ++i) {
            xe.push_back(x[i] + s);
            ve.push_back(i < volume.size() ? volume[i] : Real(0));
        }
    }
    buildFrom(xe, ve, openingAngle, leafSize);

    // The farther copies: each as its total moment at its centre, G(r) = (3 r r^T / r^2 - I)
    // / (4 pi r^3) summed over the lattice out to kFar periods (the near copies are in the
    // tree), then the continuum beyond, a sheet of moment density m / (Lx Ly) outside the
    // radius R of a disc of the summed area: the sheet's field at the centre is -1/(2R) of
    // the moment density along z and +1/(4R) in the plane (the mean of 3 cos^2 - 1 over
    // the circle is 1/2).
    constexpr int kFar = 200;
    const int far[2] = {period_[0] > 0 ? kFar : 0, period_[1] > 0 ? kFar : 0};
    Eigen::Matrix3d T = Eigen::Matrix3d::Zero();
    for (int b = -far[1]; b <= far[1]; ++b)
        for (int a = -far[0]; a <= far[0]; ++a) {
            if (std::abs(a) <= reach[0] && std::abs(b) <= reach[1]) continue;
            const Eigen::Vector3d r(a * period_[0], b * period_[1], 0);
            const double r2 = r.squaredNorm(), r1 = std::sqrt(r2);
            T += (3.0 * r * r.transpose() / r2 - Eigen::Matrix3d::Identity()) / (4.0 * kPi * r2 * r1);
        }
    if (period_[0] > 0 && period_[1] > 0) {
        const double area = period_[0] * period_[1];
        const double R = double(2 * kFar + 1) * std::sqrt(area / kPi);
        T += Eigen::Vector3d(1.0 / (4.0 * R), 1.0 / (4.0 * R), -1.0 / (2.0 * R)).asDiagonal() * (1.0 / area);
    }
    farImages_ = T;
}

void DipoleTree::buildFrom(const std::vector<Vec3>& x, const std::vector<Real>& volume, double openingAngle,
                           int leafSize) {
    const size_t n = x.size();
    theta_ = openingAngle > 0 ? std::clamp(openingAngle, 0.05, 1.0) : 0.0;
    leafSize = std::max(leafSize, 1);
    auto vol = [&](size_t i) {
        const double v = i < volume.size() ? double(volume[i]) : 0.0;
        return std::isfinite(v) && v > 0 ? v : 0.0;
    };
    auto pos = [&](size_t i) {
        const Vec3d p = x[i].cast<double>();
        return p.allFinite() ? p : Vec3d::Zero();
    };
    // Length unit: mean particle radius; origin: centre of the bounding box.
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    double sumA = 0;
    size_t countA = 0;
    for (size_t i = 0; i < n; ++i) {
        const Vec3d p = pos(i);
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
        if (vol(i) > 0) {
            sumA += std::cbrt(3.0 * vol(i) / (4.0 * kPi));
            ++countA;
        }
    }
    if (n == 0) lo = hi = Vec3d::Zero();
    scale_ = countA > 0 && sumA > 0 ? sumA / double(countA) : 1.0;
    origin_ = 0.5 * (lo + hi);
    // A cubic root cell: octants are then cubes, the shape Barnes-Hut cells should have (a
    // per-axis scale would make flat pancakes of a fluid layer, with large radii).
    const Vec3d extent = Vec3d::Constant(std::max((hi - lo).maxCoeff(), 1e-30));

    std::vector<std::pair<uint64_t, uint32_t>> keys(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3d u = (pos(i) - lo).cwiseQuotient(extent) * double((1 << 21) - 1);
            const uint64_t code = spread21(uint64_t(std::clamp(u.x(), 0.0, 2097151.0))) |
                                  spread21(uint64_t(std::clamp(u.y(), 0.0, 2097151.0))) << 1 |
                                  spread21(uint64_t(std::clamp(u.z(), 0.0, 2097151.0))) << 2;
            keys[i] = {code, uint32_t(i)};
        }
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    order_.resize(n);
    std::vector<uint64_t> codes(n);
    for (size_t k = 0; k < n; ++k) {
        order_[k] = keys[k].second;
        codes[k] = keys[k].first;
    }
    for (auto* v : {&px_, &py_, &pz_, &a2_, &ainv_, &vol_, &mx_, &my_, &mz_}) v->assign(n, 0.0f);
    const double inv = 1.0 / scale_;
    for (size_t k = 0; k < n; ++k) {
        const size_t i = order_[k];
        const Vec3d p = (pos(i) - origin_) * inv;
        px_[k] = float(p.x());
        py_[k] = float(p.y());
        pz_[k] = float(p.z());
        const double v = vol(i) * inv * inv * inv;
        vol_[k] = float(v);
        // Core radius: the sphere of volume v, or the smoothing kernel's support.
        const double a = smoothing_ > 0 ? smoothing_ * std::cbrt(v) : std::cbrt(3.0 * v / (4.0 * kPi));
        a2_[k] = float(a * a);
        ainv_[k] = a > 0 ? float(1.0 / a) : 0.0f;
    }

    nodes_.clear();
    leaves_.clear();
    leafBegin_.clear();
    leafSize_ = uint32_t(leafSize);
    if (n > 0) {
        nodes_.emplace_back();
        fillNode(0, 0, uint32_t(n), 0, codes);
        for (uint32_t i = 0; i < nodes_.size(); ++i)
            if (nodes_[i].childCount == 0) leaves_.push_back(i);
        std::sort(leaves_.begin(), leaves_.end(),
                  [&](uint32_t a, uint32_t b) { return nodes_[a].begin < nodes_[b].begin; });
        for (uint32_t l : leaves_) leafBegin_.push_back(nodes_[l].begin);
    }
    sourceSlot_.clear();
    leafHasTarget_.clear();
    if (targetCount_ < n) { // periodic copies: where each place's particle sits, which leaves hold one
        std::vector<uint32_t> slotOf(targetCount_);
        for (size_t k = 0; k < n; ++k)
            if (order_[k] < targetCount_) slotOf[order_[k]] = uint32_t(k);
        sourceSlot_.resize(n);
        for (size_t k = 0; k < n; ++k) sourceSlot_[k] = slotOf[order_[k] % targetCount_];
        leafHasTarget_.assign(leaves_.size(), 0);
        for (size_t l = 0; l < leaves_.size(); ++l) {
            const Node& node = nodes_[leaves_[l]];
            for (uint32_t k = node.begin; k < node.end && !leafHasTarget_[l]; ++k) leafHasTarget_[l] = order_[k] < targetCount_;
        }
    }
    cell_.assign(nodes_.size() * kCellFloats, 0.0f);
    farStart_.assign(1, 0);
    nearStart_.assign(1, 0);
    farCells_.clear();
    nearRanges_.clear();
    surfaceWeight_.clear();
    surfaceNormal_.clear();
    localCorrection_.clear();
    if (coreOf(smoothing_) == Core::Wendland) computeSurfaceTerms();
    if (theta_ > 0 && n > 0) buildInteractionLists();
}

void DipoleTree::fillNode(uint32_t index, uint32_t begin, uint32_t end, int level,
                          const std::vector<uint64_t>& codes) {
    nodes_[index].begin = begin;
    nodes_[index].end = end;
    finishNode(nodes_[index]);
    if (end - begin <= leafSize_) return;
    // Descend until the range splits into more than one octant (skips empty levels).
    std::vector<uint32_t> cuts;
    for (; level < 21; ++level) {
        const int shift = 3 * (20 - level);
        cuts.assign(1, begin);
        for (uint32_t digit = 1; digit < 8; ++digit) {
            const auto it = std::partition_point(codes.begin() + begin, codes.begin() + end, [&](uint64_t c) {
                return ((c >> shift) & 7u) < digit;
            });
            cuts.push_back(uint32_t(it - codes.begin()));
        }
        cuts.push_back(end);
        int nonEmpty = 0;
        for (int d = 0; d < 8; ++d) nonEmpty += cuts[d + 1] > cuts[d];
        if (nonEmpty > 1) break;
    }
    if (level >= 21) return; // identical codes: one leaf however many particles
    const uint32_t first = uint32_t(nodes_.size());
    uint32_t count = 0;
    for (int d = 0; d < 8; ++d)
        if (cuts[d + 1] > cuts[d]) ++count;
    nodes_.resize(nodes_.size() + count);
    nodes_[index].firstChild = first;
    nodes_[index].childCount = count;
    uint32_t c = first;
    const std::vector<uint32_t> myCuts = cuts; // fillNode below reuses no state, but be explicit
    for (int d = 0; d < 8; ++d)
        if (myCuts[d + 1] > myCuts[d]) fillNode(c++, myCuts[d], myCuts[d + 1], level + 1, codes);
}

void DipoleTree::finishNode(Node& node) const {
    double vs = 0, c[3] = {0, 0, 0};
    float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                   std::numeric_limits<float>::max()};
    float hi[3] = {-lo[0], -lo[1], -lo[2]};
    float maxA2 = 0;
    for (uint32_t k = node.begin; k < node.end; ++k) {
        const double w = vol_[k];
        vs += w;
        c[0] += w * px_[k];
        c[1] += w * py_[k];
        c[2] += w * pz_[k];
        const float p[3] = {px_[k], py_[k], pz_[k]};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
        maxA2 = std::max(maxA2, a2_[k]);
    }
    if (vs > 0) {
        for (double& v : c) v /= vs;
    } else { // no volume: plain mean (the cell has no moment anyway)
        c[0] = c[1] = c[2] = 0;
        for (uint32_t k = node.begin; k < node.end; ++k) {
            c[0] += px_[k];
            c[1] += py_[k];
            c[2] += pz_[k];
        }
        for (double& v : c) v /= double(std::max<uint32_t>(1, node.end - node.begin));
    }
    double r2 = 0;
    for (uint32_t k = node.begin; k < node.end; ++k) {
        const double dx = px_[k] - c[0], dy = py_[k] - c[1], dz = pz_[k] - c[2];
        r2 = std::max(r2, dx * dx + dy * dy + dz * dz);
    }
    for (int a = 0; a < 3; ++a) {
        node.c[a] = float(c[a]);
        node.lo[a] = lo[a];
        node.hi[a] = hi[a];
    }
    // Round the radius up so float centres never make a cell look smaller than it is.
    node.radius = float(std::sqrt(r2) * (1 + 1e-6) + 1e-6);
    node.maxA = std::sqrt(maxA2);
}

bool DipoleTree::accept(const Node& cell, double d) const {
    // Barnes-Hut: cell size (largest side of its particles' box) over distance below theta;
    // and every particle sphere of the cell nearer to its centre than the target is, so the
    // expansion converges and the target lies outside all of the cell's spheres.
    const double size = std::max({cell.hi[0] - cell.lo[0], cell.hi[1] - cell.lo[1], cell.hi[2] - cell.lo[2]});
    return size < theta_ * d && cell.radius + cell.maxA < d;
}

void DipoleTree::buildInteractionLists() {
    const size_t L = leaves_.size();
    std::vector<std::vector<uint32_t>> far(L), near(L);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, L, 8), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint32_t> stack;
        for (size_t l = r.begin(); l < r.end(); ++l) {
            if (!leafHasTarget(l)) continue; // periodic copies only: never evaluated
            const Node& target = nodes_[leaves_[l]];
            auto& f = far[l];
            auto& nr = near[l];
            stack.assign(1, 0);
            while (!stack.empty()) {
                const uint32_t ni = stack.back();
                stack.pop_back();
                const Node& cell = nodes_[ni];
                const bool ok = accept(cell, boxDistance(cell.c, target.lo, target.hi));
                if (ok && cell.end - cell.begin > kMinCellCount) {
                    f.push_back(ni);
                } else if (ok || cell.childCount == 0) {
                    if (!nr.empty() && nr.back() == cell.begin) nr.back() = cell.end;
                    else {
                        nr.push_back(cell.begin);
                        nr.push_back(cell.end);
                    }
                } else {
                    for (uint32_t c = cell.childCount; c-- > 0;) stack.push_back(cell.firstChild + c);
                }
            }
        }
    });
    farStart_.resize(L + 1);
    nearStart_.resize(L + 1);
    farStart_[0] = nearStart_[0] = 0;
    for (size_t l = 0; l < L; ++l) {
        farStart_[l + 1] = farStart_[l] + uint32_t(far[l].size());
        nearStart_[l + 1] = nearStart_[l] + uint32_t(near[l].size());
    }
    farCells_.resize(farStart_[L]);
    nearRanges_.resize(nearStart_[L]);
    for (size_t l = 0; l < L; ++l) {
        std::copy(far[l].begin(), far[l].end(), farCells_.begin() + farStart_[l]);
        std::copy(near[l].begin(), near[l].end(), nearRanges_.begin() + nearStart_[l]);
    }
}

void DipoleTree::interactionCounts(double& farPerTarget, double& nearPerTarget) const {
    double f = 0, nn = 0;
    for (size_t l = 0; l + 1 < farStart_.size(); ++l) {
        const double targets = nodes_[leaves_[l]].end - nodes_[leaves_[l]].begin;
        f += targets * (farStart_[l + 1] - farStart_[l]);
        double s = 0;
        for (uint32_t q = nearStart_[l]; q < nearStart_[l + 1]; q += 2) s += nearRanges_[q + 1] - nearRanges_[q];
        nn += targets * s;
    }
    const double n = std::max<double>(1, double(size()));
    farPerTarget = f / n;
    nearPerTarget = nn / n;
}

void DipoleTree::setMagnetization(const Eigen::VectorXd& M) {
    const size_t n = size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8192), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
            mx_[k] = float(vol_[k] * M[3 * k]);
            my_[k] = float(vol_[k] * M[3 * k + 1]);
            mz_[k] = float(vol_[k] * M[3 * k + 2]);
        }
    });
    sumCellMoments();
}

void DipoleTree::setMagnetizationUnsorted(const std::vector<Vec3>& M) {
    const size_t n = size();
    for (size_t k = 0; k < n; ++k) {
        const size_t i = targetCount_ > 0 ? order_[k] % targetCount_ : order_[k];
        const Vec3 m = i < M.size() && M[i].allFinite() ? M[i] : Vec3::Zero();
        mx_[k] = vol_[k] * m.x();
        my_[k] = vol_[k] * m.y();
        mz_[k] = vol_[k] * m.z();
    }
    sumCellMoments();
}

void DipoleTree::sumCellMoments() {
    // Raw moments about each cell's centre, bottom-up: leaves from their particles, parents
    // by shifting their children's moments (children have larger indices than their parent:
    // one backward sweep). Then the symmetric trace-free parts go to cell_.
    const size_t nn = nodes_.size();
    std::vector<RawMoments> raw(nn);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t l = r.begin(); l < r.end(); ++l) {
            const Node& node = nodes_[leaves_[l]];
            RawMoments& R = raw[leaves_[l]];
            for (uint32_t k = node.begin; k < node.end; ++k) {
                const double m[3] = {mx_[k], my_[k], mz_[k]};
                const double s[3] = {px_[k] - double(node.c[0]), py_[k] - double(node.c[1]),
                                     pz_[k] - double(node.c[2])};
                R.addDipole(m, s);
            }
        }
    });
    for (size_t i = nn; i-- > 0;) {
        const Node& node = nodes_[i];
        for (uint32_t ch = node.firstChild; ch < node.firstChild + node.childCount; ++ch) {
            const double s[3] = {double(nodes_[ch].c[0]) - node.c[0], double(nodes_[ch].c[1]) - node.c[1],
                                 double(nodes_[ch].c[2]) - node.c[2]};
            raw[i].addShifted(raw[ch], s);
        }
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nn, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) raw[i].storeTraceFree(&cell_[i * kCellFloats]);
    });
    farField_.setZero();
    if (periodic()) { // the far copies' uniform field: one period's moment sum V M (the targets), SI
        Eigen::Vector3d m = Eigen::Vector3d::Zero();
        for (size_t k = 0; k < size(); ++k)
            if (isTarget(k)) m += Eigen::Vector3d(mx_[k], my_[k], mz_[k]);
        farField_ = farImages_ * (scale_ * scale_ * scale_ * m);
    }
}

void DipoleTree::gatherFar(size_t leaf, std::vector<float>& buf, size_t& count) const {
    const uint32_t b = farStart_[leaf], e = farStart_[leaf + 1];
    count = e - b;
    buf.resize(kFarArrays * std::max<size_t>(count, 1));
    for (uint32_t q = b; q < e; ++q) {
        const uint32_t c = farCells_[q];
        const size_t j = q - b;
        for (int a = 0; a < 3; ++a) buf[a * count + j] = nodes_[c].c[a];
        const float* mom = &cell_[size_t(c) * kCellFloats];
        for (int k = 0; k < kCellFloats; ++k) buf[(3 + k) * count + j] = mom[k];
    }
}

template <class Term>
void DipoleTree::treeSum(size_t leaf, size_t k, const std::vector<float>& buf, size_t farCount, float* out) const {
    const float t[3] = {px_[k], py_[k], pz_[k]};
    farSum<Term>(t, buf.data(), farCount, out);
    const Sources near{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                       ainv_.data()};
    for (uint32_t q = nearStart_[leaf]; q < nearStart_[leaf + 1]; q += 2)
        Term::addParticles(coreOf(smoothing_), t, near, nearRanges_[q], nearRanges_[q + 1], out);
}

template <class Visit>
void DipoleTree::forEachTreeTarget(Visit&& visit) const {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<float> buf;
        for (size_t l = r.begin(); l < r.end(); ++l) {
            if (!leafHasTarget(l)) continue;
            size_t farCount = 0;
            gatherFar(l, buf, farCount);
            const Node& node = nodes_[leaves_[l]];
            for (uint32_t k = node.begin; k < node.end; ++k) visit(l, k, buf, farCount);
        }
    });
}

void DipoleTree::treeFieldAt(size_t leaf, size_t k, const std::vector<float>& buf, size_t farCount,
                             double h[3]) const {
    float acc[3] = {0, 0, 0};
    treeSum<FieldTerm>(leaf, k, buf, farCount, acc);
    for (int a = 0; a < 3; ++a) h[a] = kInv4Pi * double(acc[a]);
    addSurfaceTerm(k, h);
}

void DipoleTree::fieldAtParticles(Eigen::VectorXd& H, bool useTree) const {
    const size_t n = size();
    H.setZero(3 * Eigen::Index(n));
    if (n == 0) return;
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    if (useTree && theta_ > 0) {
        forEachTreeTarget([&](size_t l, size_t k, const std::vector<float>& buf, size_t farCount) {
            treeFieldAt(l, k, buf, farCount, &H[3 * k]);
        });
        if (periodic()) {
            addFarImages(H.data());
            copyToImages(H.data(), 3);
        }
        return;
    }
    const size_t blocks = (n + kDirectTargetBlock - 1) / kDirectTargetBlock;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t blk = r.begin(); blk < r.end(); ++blk) {
            const size_t tb = blk * kDirectTargetBlock, te = std::min(n, tb + kDirectTargetBlock);
            for (size_t sb = 0; sb < n; sb += kDirectChunk) {
                const size_t se = std::min(n, sb + kDirectChunk);
                for (size_t k = tb; k < te; ++k) {
                    if (!isTarget(k)) continue;
                    const float t[3] = {px_[k], py_[k], pz_[k]};
                    float acc[3] = {0, 0, 0};
                    FieldTerm::addParticles(coreOf(smoothing_), t, src, sb, se, acc);
                    for (int a = 0; a < 3; ++a) H[3 * k + a] += kInv4Pi * double(acc[a]);
                }
            }
            for (size_t k = tb; k < te; ++k)
                if (isTarget(k)) addSurfaceTerm(k, &H[3 * k]);
        }
    });
    if (periodic()) {
        addFarImages(H.data());
        copyToImages(H.data(), 3);
    }
}

template <class T>
void DipoleTree::copyToImages(T* values, int stride) const {
    if (sourceSlot_.empty()) return;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
            const size_t s = sourceSlot_[k];
            if (s != k)
                for (int a = 0; a < stride; ++a) values[size_t(stride) * k + a] = values[size_t(stride) * s + a];
        }
    });
}

void DipoleTree::addFarImages(double* H) const {
    const Eigen::Vector3d& h = farField_;
    for (size_t k = 0; k < size(); ++k)
        if (isTarget(k))
            for (int a = 0; a < 3; ++a) H[3 * k + a] += h[a];
}

void DipoleTree::fieldAtParticlesDirect(const std::vector<uint32_t>& targets, Eigen::VectorXd& H) const {
    const size_t n = size();
    H.setZero(3 * Eigen::Index(targets.size()));
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, targets.size(), 8), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t q = r.begin(); q < r.end(); ++q) {
            const size_t k = targets[q];
            const float t[3] = {px_[k], py_[k], pz_[k]};
            for (size_t sb = 0; sb < n; sb += kDirectChunk) {
                float acc[3] = {0, 0, 0};
                FieldTerm::addParticles(coreOf(smoothing_), t, src, sb, std::min(n, sb + kDirectChunk), acc);
                for (int a = 0; a < 3; ++a) H[3 * q + a] += kInv4Pi * double(acc[a]);
            }
            addSurfaceTerm(k, &H[3 * q]);
            for (int a = 0; a < 3; ++a) H[3 * q + a] += farField_[a]; // periodic: the far copies
        }
    });
}

void DipoleTree::gradientAtParticles(std::vector<Mat3f>& J, bool useTree) const {
    const size_t n = size();
    J.assign(n, Mat3f::Zero());
    if (n == 0) return;
    const float s = float(kInv4Pi / scale_);
    const Sources src{px_.data(), py_.data(), pz_.data(), mx_.data(), my_.data(), mz_.data(), a2_.data(),
                      ainv_.data()};
    if (useTree && theta_ > 0) {
        forEachTreeTarget([&](size_t l, size_t k, const std::vector<float>& buf, size_t farCount) {
            float g[6] = {0, 0, 0, 0, 0, 0};
            treeSum<GradientTerm>(l, k, buf, farCount, g);
            J[k] = symmetric(g, s);
        });
        copyToImages(J.data()->data(), 9);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
            if (!isTarget(k)) continue;
            const float t[3] = {px_[k], py_[k], pz_[k]};
            double gd[6] = {0, 0, 0, 0, 0, 0};
            for (size_t sb = 0; sb < n; sb += kDirectChunk) {
                float g[6] = {0, 0, 0, 0, 0, 0};
                GradientTerm::addParticles(coreOf(smoothing_), t, src, sb, std::min(n, sb + kDirectChunk), g);
                for (int a = 0; a < 6; ++a) gd[a] += g[a];
            }
            const float g[6] = {float(gd[0]), float(gd[1]), float(gd[2]), float(gd[3]), float(gd[4]), float(gd[5])};
            J[k] = symmetric(g, s);
        }
    });
    copyToImages(J.data()->data(), 9);
}

size_t DipoleTree::leafOf(size_t k) const {
    const auto it = std::upper_bound(leafBegin_.begin(), leafBegin_.end(), uint32_t(k));
    return size_t(it - leafBegin_.begin()) - 1;
}

Eigen::Vector3d DipoleTree::fieldAtParticleTree(size_t k) const {
    if (!(theta_ > 0)) return fieldAtParticleDirect(k);
    const size_t l = leafOf(k);
    std::vector<float> buf;
    size_t fc = 0;
    gatherFar(l, buf, fc);
    double h[3];
    treeFieldAt(l, k, buf, fc, h);
    return Eigen::Vector3d(h[0], h[1], h[2]) + farField_;
}

template void DipoleTree::copyToImages<float>(float*, int) const;
template void DipoleTree::copyToImages<double>(double*, int) const;

} // namespace ferro

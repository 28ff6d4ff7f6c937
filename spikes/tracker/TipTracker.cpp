#include "spikes/tracker/TipTracker.hpp"

#include "sim/core/ParticleFile.hpp"
#include "sim/spatial/HashGrid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <cstdint>
#include <limits>

namespace ferro {

std::vector<SpikeTipSample> findTips(const TriangleMesh& spiky, const TriangleMesh& surface,
                                     const TipFinderParams& params) {
    std::vector<SpikeTipSample> tips;
    if (spiky.empty() || surface.empty()) return tips;
    const std::vector<Vec3d> normals = areaWeightedNormals(surface);
    const double edge = meanEdgeLength(surface);
    std::vector<Vec3d> surfacePoints(surface.vertices.size());
    for (size_t i = 0; i < surfacePoints.size(); ++i) surfacePoints[i] = surface.vertices[i].cast<double>();
    const HashGrid near(surfacePoints, std::max(2 * edge, 1e-9));

    const size_t n = spiky.vertices.size();
    std::vector<double> h(n, 0.0);
    for (size_t i = 0; i < n; ++i) {
        const Vec3d p = spiky.vertices[i].cast<double>();
        const uint32_t j = near.nearest(p);
        h[i] = (p - surface.vertices[j].cast<double>()).dot(normals[j]);
    }
    // One-ring maxima above minHeight.
    std::vector<char> isMax(n, 1);
    for (size_t i = 0; i < n; ++i) isMax[i] = h[i] >= params.minHeight;
    for (const auto& t : spiky.triangles)
        for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l)
                if (k != l && h[t[size_t(l)]] > h[t[size_t(k)]]) isMax[t[size_t(k)]] = 0;
    std::vector<uint32_t> maxima;
    for (size_t i = 0; i < n; ++i)
        if (isMax[i]) maxima.push_back(uint32_t(i));
    std::sort(maxima.begin(), maxima.end(), [&](uint32_t a, uint32_t b) { return h[a] > h[b] || (h[a] == h[b] && a < b); });
    for (uint32_t i : maxima) tips.push_back({spiky.vertices[i].cast<double>(), h[i]});

    // Two maxima on one spike (a flat-topped tip, remeshing noise): keep the higher of any
    // two closer than half the median spacing.
    const double radius = 0.5 * medianTipSpacing(tips);
    std::vector<SpikeTipSample> kept;
    std::vector<uint32_t> keptVertex;
    for (size_t k = 0; k < tips.size(); ++k) {
        bool near2 = false;
        for (const auto& other : kept) near2 = near2 || (other.position - tips[k].position).norm() < radius;
        if (!near2) kept.push_back(tips[k]), keptVertex.push_back(maxima[k]);
    }
    // Each tip's foot. The spike is what is reached from the apex going downhill over the
    // mesh's edges, down to 5 % of its height and within 0.75 tip spacings of the apex along
    // the surface (a saddle to a taller neighbour above 5 % does not let the fill far into its
    // flank). A spike that leans is a stack of slices each
    // shifted along the lean, so its volume's centroid lies on its axis: the axis runs from
    // the apex through that centroid (the columns between the surface and the mesh, at their
    // mid-height, weighted by height times the area seen along the normal).
    // The area seen along the normal weighs each column (twice it: a constant factor cancels).
    const std::vector<Vec3d> vectorArea = vertexAreaVectors(spiky);
    std::vector<std::vector<uint32_t>> ring(n);
    for (const auto& t : spiky.triangles)
        for (int k = 0; k < 3; ++k) {
            ring[t[size_t(k)]].push_back(t[size_t((k + 1) % 3)]);
            ring[t[size_t(k)]].push_back(t[size_t((k + 2) % 3)]);
        }
    std::vector<char> seen(n, 0);
    std::vector<uint32_t> visited, stack;
    // Within 0.75 of the median tip spacing of the apex along the surface (0 with one tip: no
    // limit): past a saddle a neighbour's flank begins, but a leaning spike's own far flank
    // reaches beyond half a spacing.
    const double reach = 1.5 * radius;
    auto alongPlane = [](const Vec3d& d, const Vec3d& normal) { return (d - d.dot(normal) * normal).norm(); };
    // The surface under each tip: the nearest surface vertex to its foot (without a foot, to
    // the point the tip's height below the apex along the normal there).
    const bool velocities = surface.velocities.size() == surface.vertices.size();
    for (size_t k = 0; k < kept.size(); ++k) {
        SpikeTipSample& t = kept[k];
        const uint32_t j0 = near.nearest(t.position);
        const Vec3d n0 = normals[j0];
        Vec3d foot = t.position - t.height * n0;
        const uint32_t apex = keptVertex[k];
        if (t.height > 0) {
            Vec3d moment = Vec3d::Zero();
            double volume = 0;
            stack.assign(1, apex);
            seen[apex] = 1;
            visited.assign(1, apex);
            while (!stack.empty()) {
                const uint32_t v = stack.back();
                stack.pop_back();
                const double column = std::max(0.0, vectorArea[v].dot(n0)) * h[v];
                moment += column * (spiky.vertices[v].cast<double>() - 0.5 * h[v] * n0);
                volume += column;
                for (uint32_t w : ring[v])
                    if (!seen[w] && h[w] <= h[v] + 1e-12 && h[w] >= 0.05 * t.height &&
                        !(reach > 0 && alongPlane(spiky.vertices[w].cast<double>() - t.position, n0) > reach)) {
                        seen[w] = 1;
                        visited.push_back(w);
                        stack.push_back(w);
                    }
            }
            for (uint32_t v : visited) seen[v] = 0;
            if (visited.size() >= 7 && volume > 0) {
                const Vec3d axis = (t.position - moment / volume).normalized();
                if (axis.dot(n0) > 0.3) { // a spike leaning more than 73 degrees has no clear foot
                    foot = t.position - (t.height / axis.dot(n0)) * axis;
                    t.base = foot;
                    t.hasBase = true;
                }
            }
        }
        const uint32_t j = near.nearest(foot);
        t.normal = normals[j];
        if (velocities) t.surfaceVelocity = surface.velocities[j].cast<double>();
        t.hasVelocity = velocities;
    }
    return kept;
}

double medianTipSpacing(const std::vector<SpikeTipSample>& tips) {
    if (tips.size() < 2) return 0.0;
    std::vector<double> d(tips.size(), std::numeric_limits<double>::infinity());
    for (size_t i = 0; i < tips.size(); ++i)
        for (size_t j = 0; j < tips.size(); ++j)
            if (i != j) d[i] = std::min(d[i], (tips[i].position - tips[j].position).norm());
    std::nth_element(d.begin(), d.begin() + long(d.size() / 2), d.end());
    return d[d.size() / 2];
}

namespace {

/// Tips of a matched to tips of b (index into b, or -1), greedily by increasing distance
/// between a's predicted place and b's tip, each tip used once, only closer than maxD.
std::vector<int> greedyMatch(const std::vector<Vec3d>& predicted, const std::vector<SpikeTipSample>& b, double maxD) {
    struct Pair { double d; uint32_t i, j; };
    std::vector<Pair> pairs;
    for (uint32_t i = 0; i < predicted.size(); ++i)
        for (uint32_t j = 0; j < b.size(); ++j) {
            const double d = (predicted[i] - b[j].position).norm();
            if (d < maxD) pairs.push_back({d, i, j});
        }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& p, const Pair& q) {
        return p.d < q.d || (p.d == q.d && (p.i < q.i || (p.i == q.i && p.j < q.j)));
    });
    std::vector<int> toB(predicted.size(), -1);
    std::vector<char> usedB(b.size(), 0);
    for (const Pair& p : pairs) {
        if (toB[p.i] >= 0 || usedB[p.j]) continue;
        toB[p.i] = int(p.j);
        usedB[p.j] = 1;
    }
    return toB;
}

/// Neighbours whose motion predicts a tip's: enough for a least-squares scale, few enough to
/// stay local (two magnets' patterns contract about different centres).
constexpr size_t kMotionNeighbours = 8;

/// Where each tip of a is expected in b from the motion of its nearest matched tips: their
/// least-squares isotropic scale s and shift about their centroids ca, cb, p = cb + s (x - ca).
/// A single neighbour, or neighbours too close together to fix a scale, give the shift only;
/// none, the tip where it was. Rotation is left out: between two frames the lattice turns by
/// far less than the gate, and locally a small turn is a shift.
std::vector<Vec3d> predictPositions(const std::vector<SpikeTipSample>& a, const std::vector<SpikeTipSample>& b,
                                    const std::vector<int>& toB, double spacing) {
    std::vector<uint32_t> matched;
    for (uint32_t i = 0; i < a.size(); ++i)
        if (toB[i] >= 0) matched.push_back(i);
    std::vector<Vec3d> out(a.size());
    std::vector<std::pair<double, uint32_t>> near;
    for (uint32_t i = 0; i < a.size(); ++i) {
        out[i] = a[i].position;
        if (matched.empty()) continue;
        near.clear();
        for (uint32_t k : matched) near.push_back({(a[k].position - a[i].position).squaredNorm(), k});
        const size_t n = std::min(kMotionNeighbours, near.size());
        std::partial_sort(near.begin(), near.begin() + long(n), near.end());
        Vec3d ca = Vec3d::Zero(), cb = Vec3d::Zero();
        for (size_t k = 0; k < n; ++k) {
            ca += a[near[k].second].position / double(n);
            cb += b[size_t(toB[near[k].second])].position / double(n);
        }
        double num = 0, den = 0;
        for (size_t k = 0; k < n; ++k) {
            const Vec3d da = a[near[k].second].position - ca, db = b[size_t(toB[near[k].second])].position - cb;
            num += da.dot(db);
            den += da.squaredNorm();
        }
        // A scale needs neighbours spread over about a spacing; it is kept to a plausible
        // range (a lattice does not halve or double its spacing in one frame).
        const double scale = n >= 3 && den > double(n) * 0.25 * spacing * spacing ? std::clamp(num / den, 0.8, 1.25) : 1.0;
        out[i] = cb + scale * (a[i].position - ca);
    }
    return out;
}

} // namespace

TipFrameMatch matchTips(const std::vector<SpikeTipSample>& a, const std::vector<SpikeTipSample>& b, double gate,
                        double edgeFraction, bool predict, double interval) {
    TipFrameMatch m;
    m.tipsA = int(a.size());
    m.tipsB = int(b.size());
    m.spacing = a.size() >= 2 ? medianTipSpacing(a) : medianTipSpacing(b);
    double hA = 0, hB = 0;
    for (const auto& t : a) hA = std::max(hA, t.height);
    for (const auto& t : b) hB = std::max(hB, t.height);
    m.largestTip = std::max(hA, hB);
    if (a.empty() && b.empty()) return m;

    const double maxD = m.spacing > 0 ? gate * m.spacing : std::numeric_limits<double>::infinity();
    std::vector<Vec3d> predicted(a.size());
    for (size_t i = 0; i < a.size(); ++i) predicted[i] = a[i].position;
    std::vector<int> toB;
    if (predict && m.spacing > 0) {
        // Seeds: tips that moved less than a quarter spacing. Only there is the nearest tip
        // surely the same one; a lattice contracting by 8 % a frame moves its sixth ring by
        // 0.48 l, and there a's tip is nearer to b's seventh-ring tip than to its own. From
        // the seeds the prediction grows outward: each round predicts every tip from the
        // matched ones and keeps the matches within a quarter spacing of the prediction,
        // until no more tips are added; the last prediction is matched within the gate.
        const double seedD = std::min(0.25, 0.5 * gate) * m.spacing;
        toB = greedyMatch(predicted, b, seedD);
        auto count = [](const std::vector<int>& v) { return std::count_if(v.begin(), v.end(), [](int j) { return j >= 0; }); };
        for (int round = 0; round < 64 && count(toB) > 0; ++round) {
            const std::vector<Vec3d> next = predictPositions(a, b, toB, m.spacing);
            std::vector<int> nextToB = greedyMatch(next, b, seedD);
            predicted = next;
            if (count(nextToB) <= count(toB)) break;
            toB = std::move(nextToB);
        }
    }
    toB = greedyMatch(predicted, b, maxD);

    std::vector<char> usedB(b.size(), 0);
    std::vector<double> moves;
    double sumU = 0, sumV = 0, sumDiff = 0;
    int stable = 0, interior = 0, interiorStable = 0;
    const auto inside = [&](double h, double hmax) { return h >= edgeFraction * hmax; };
    for (uint32_t i = 0; i < a.size(); ++i) {
        if (toB[i] < 0) continue;
        const size_t j = size_t(toB[i]);
        usedB[j] = 1;
        const double d = (a[i].position - b[j].position).norm();
        moves.push_back(d);
        m.maxResidual = std::max(m.maxResidual, (predicted[i] - b[j].position).norm());
        if (d < 0.1 * m.spacing) ++stable;
        if (inside(a[i].height, hA) || inside(b[j].height, hB)) {
            ++interior;
            interiorStable += d < 0.1 * m.spacing;
            if (interval > 0 && a[i].hasVelocity && b[j].hasVelocity) {
                Vec3d n = a[i].normal + b[j].normal;
                n = n.norm() > 0 ? Vec3d(n.normalized()) : Vec3d(0, 0, 1);
                auto along = [&](const Vec3d& v) { return Vec3d(v - v.dot(n) * n); };
                const bool feet = a[i].hasBase && b[j].hasBase;
                const Vec3d v = along(((feet ? b[j].base : b[j].position) - (feet ? a[i].base : a[i].position)) / interval);
                const Vec3d u = along(0.5 * (a[i].surfaceVelocity + b[j].surfaceVelocity));
                sumU += u.norm();
                sumV += v.norm();
                sumDiff += (v - u).norm();
                ++m.flowTips;
            }
        }
        m.maxHeightJump = std::max(m.maxHeightJump, std::abs(a[i].height - b[j].height));
    }
    for (uint32_t i = 0; i < a.size(); ++i)
        if (toB[i] < 0) {
            ++m.died;
            m.interiorDied += inside(a[i].height, hA);
            interior += inside(a[i].height, hA);
            m.maxHeightJump = std::max(m.maxHeightJump, a[i].height);
        }
    for (uint32_t j = 0; j < b.size(); ++j)
        if (!usedB[j]) {
            ++m.born;
            m.interiorBorn += inside(b[j].height, hB);
            interior += inside(b[j].height, hB);
            m.maxHeightJump = std::max(m.maxHeightJump, b[j].height);
        }
    m.matched = int(moves.size());
    if (!moves.empty()) {
        std::sort(moves.begin(), moves.end());
        m.medianMove = moves[moves.size() / 2];
        m.maxMove = moves.back();
    }
    if (m.flowTips > 0) {
        m.surfaceSpeed = sumU / m.flowTips;
        m.tipSpeed = sumV / m.flowTips;
        m.flowDifference = sumDiff / m.flowTips;
        m.flowMismatch = sumU > 0 ? sumDiff / sumU : (sumDiff > 0 ? std::numeric_limits<double>::infinity() : 0.0);
    }
    m.stableFraction = double(stable) / double(std::max(a.size(), b.size()));
    m.interiorStableFraction = interior ? double(interiorStable) / double(interior) : 1.0;
    m.maxHeightJump = m.largestTip > 0 ? m.maxHeightJump / m.largestTip : 0.0;
    return m;
}

TipTrack trackTips(const std::string& spikyPattern, const std::string& surfacePattern, int first, int last,
                   const TipFinderParams& params, double gate, double edgeFraction, bool predict) {
    TipTrack track;
    track.first = first;
    double lastTime = std::nan("");
    for (int f = first; f <= last; ++f) {
        const TriangleMesh spiky = readMesh(framePath(spikyPattern, f));
        const TriangleMesh surface = readMesh(framePath(surfacePattern, f));
        track.tips.push_back(findTips(spiky, surface, params));
        ParticleTable header; // the mesh's `comment key value` lines, read as particle files' are
        header.comments = surface.comments;
        const double time = header.commentNumber("time", std::nan(""));
        const double interval = time - lastTime; // NaN without both times: no flow statistics
        lastTime = time;
        if (track.tips.size() >= 2)
            track.steps.push_back(matchTips(track.tips[track.tips.size() - 2], track.tips.back(), gate, edgeFraction,
                                            predict, interval > 0 ? interval : 0.0));
    }
    return track;
}

std::string tipTrackCsv(const TipTrack& track) {
    std::ostringstream o;
    o << "frame,tips,matched,born,died,interior_born,interior_died,spacing_mm,median_move_mm,max_move_mm,"
         "stable_fraction,interior_stable_fraction,max_height_jump,largest_tip_mm,max_residual_mm,flow_tips,"
         "surface_speed_mm_s,tip_speed_mm_s,flow_difference_mm_s,flow_mismatch\n";
    for (size_t k = 0; k < track.steps.size(); ++k) {
        const TipFrameMatch& m = track.steps[k];
        char row[384];
        std::snprintf(row, sizeof row, "%d,%d,%d,%d,%d,%d,%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%.4f,%.4f,%.4f,%.4f\n",
                      track.first + int(k) + 1, m.tipsB, m.matched, m.born, m.died, m.interiorBorn, m.interiorDied,
                      1e3 * m.spacing, 1e3 * m.medianMove, 1e3 * m.maxMove, m.stableFraction, m.interiorStableFraction,
                      m.maxHeightJump, 1e3 * m.largestTip, 1e3 * m.maxResidual, m.flowTips, 1e3 * m.surfaceSpeed,
                      1e3 * m.tipSpeed, 1e3 * m.flowDifference, m.flowMismatch);
        o << row;
    }
    return o.str();
}

} // namespace ferro

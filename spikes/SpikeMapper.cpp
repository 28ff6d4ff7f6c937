// The spike synthesis of SpikeMapper.hpp.
#include "spikes/SpikeMapper.hpp"
#include "sim/core/Constants.hpp"

#include "spikes/PointGrid.hpp"
#include "spikes/SurfaceFields.hpp"
#include "spikes/SurfaceGeometry.hpp"

#include <Eigen/Dense>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace ferro {

namespace {

// Lattice axes A_k of the six trace directions in (e1, e2) coordinates, e2 = e1 rotated by 60 deg.
const int kAxis[6][2] = {{1, 0}, {0, 1}, {-1, 1}, {-1, 0}, {0, -1}, {1, -1}};

int64_t latticeKey(int i, int j) { return (int64_t(i) << 32) ^ int64_t(uint32_t(j)); }

struct Tip {
    int i, j;
    Vec3d position, normal;
    Eigen::Matrix<double, 2, 3> toLattice; // maps an offset from the tip to lattice coordinates
    double amplitude = 0;                  // C0 at the tip (eq. 14, capped) [m]
    Vec3d direction{0, 0, 1};              // growth direction at the tip
};

// Unnormalized weight of a pattern whose magnet makes field H here: |H|^6. Patterns blend only
// where their magnets' fields are within ~30 % of each other (a dipole's |H| ~ r^-3 makes that
// a band a few millimetres wide); elsewhere one pattern is in sole charge, so a spike is not
// skewed by a faint copy of the other lattice. The band is smooth: no cracks.
double fieldDominance(const Vec3d& H)
{
    const double h2 = H.squaredNorm();
    return h2 * h2 * h2;
}

struct Pattern {
    SpikePattern info;
    std::vector<Tip> tips;
    std::unique_ptr<PointGrid> grid;
};

Vec3d faceNormal(const TriangleMesh& mesh, uint32_t t)
{
    const auto& tri = mesh.triangles[t];
    const Vec3d a = toD(mesh.vertices[tri[0]]), b = toD(mesh.vertices[tri[1]]), c = toD(mesh.vertices[tri[2]]);
    const Vec3d n = (b - a).cross(c - a);
    const double len = n.norm();
    return len > 0 ? Vec3d(n / len) : Vec3d(0, 0, 1);
}

std::vector<double> vertexAreas(const TriangleMesh& mesh)
{
    std::vector<double> area(mesh.vertices.size(), 0.0);
    for (const auto& t : mesh.triangles) {
        const Vec3d a = toD(mesh.vertices[t[0]]), b = toD(mesh.vertices[t[1]]), c = toD(mesh.vertices[t[2]]);
        const double third = (b - a).cross(c - a).norm() / 6.0;
        for (uint32_t v : t) area[v] += third;
    }
    return area;
}

// The free surface a line meets nearest to p (triangles with a non-wetted vertex).
bool nearestFreeHit(const SurfaceRayCaster& caster, const TriangleMesh& mesh, const std::vector<char>& wetted,
                    const Vec3d& p, const Vec3d& d, double maxDistance, Vec3d& hit, Vec3d& normal)
{
    for (const SurfaceRayCaster::Hit& h : caster.lineHits(p, d)) {
        if (std::abs(h.t) > maxDistance) break;
        const auto& t = mesh.triangles[h.triangle];
        if (wetted[t[0]] && wetted[t[1]] && wetted[t[2]]) continue;
        hit = h.point;
        normal = faceNormal(mesh, h.triangle);
        return true;
    }
    return false;
}

} // namespace

Vec3d totalFieldAt(const SpikeInput& input, const Vec3d& x)
{
    Vec3d H = magnetField(input.magnets, x);
    if (input.particleField) H += input.particleField(x);
    return H;
}

SpikeResult addSpikes(const SpikeInput& in, const SpikeParams& P)
{
    SpikeResult res;
    const double g = in.fluid.gravity.norm();
    res.critical = criticalMagnetization(in.fluid.density - P.ambientDensity, g, in.fluid.surfaceTension, in.fluid.law);
    res.volumeIn = enclosedVolume(in.surface);
    auto unchanged = [&]() {
        res.refined = in.surface;
        res.mesh = in.surface;
        computeVertexNormals(res.mesh);
        res.volumeOut = res.volumeIn;
        return res;
    };
    const double Mc = res.critical.magnetization;
    if (!P.enabled || in.magnets.empty() || !std::isfinite(Mc) || in.surface.empty()) return unchanged();

    const SurfaceFields fields(in, P, Mc);
    const TriangleMesh& input = in.surface;
    const size_t nIn = input.vertices.size();

    // 1. Wetted walls and the supercritical part of the input surface.
    const std::vector<Vec3d> inputNormals = areaWeightedNormals(input);
    std::vector<char> wettedIn(nIn, 0), activeIn(nIn, 0);
    std::vector<double> magnetizationIn(nIn, 0.0);
    tbb::parallel_for(size_t(0), nIn, [&](size_t v) {
        const Vec3d x = toD(input.vertices[v]);
        wettedIn[v] = fields.wetted(x);
        if (wettedIn[v]) return;
        magnetizationIn[v] = fields.magnetization(x, fields.field(x, inputNormals[v]));
        activeIn[v] = magnetizationIn[v] > Mc;
    });
    if (std::none_of(activeIn.begin(), activeIn.end(), [](char a) { return a != 0; })) return unchanged();

    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const Vec3& v : input.vertices) {
        lo = lo.cwiseMin(toD(v));
        hi = hi.cwiseMax(toD(v));
    }
    const double diagonal = (hi - lo).norm();
    const SurfaceRayCaster caster(input);

    // 2. One pattern per magnet with a supercritical origin.
    std::vector<Pattern> patterns;
    const Vec3d up = g > 0 ? Vec3d(-in.fluid.gravity / g) : Vec3d(0, 0, 1);
    for (size_t m = 0; m < in.magnets.size(); ++m) {
        const Magnet& magnet = in.magnets[m];
        const double dirNorm = magnet.direction.norm();
        if (magnet.strength == 0 || !(dirNorm > 0)) continue;
        const Vec3d axisDir = magnet.direction / dirNorm;
        Vec3d anchor = magnet.position;
        if (!magnetKindInfo(magnet.kind).positioned) {
            if (P.hasOrigin) {
                anchor = P.origin;
            } else if (in.fluid.hasCenter) {
                anchor = in.fluid.center;
            } else {
                Vec3d sum = Vec3d::Zero();
                size_t count = 0;
                for (size_t v = 0; v < nIn; ++v)
                    if (activeIn[v]) sum += toD(input.vertices[v]), ++count;
                anchor = sum / double(std::max<size_t>(count, 1));
            }
        }
        Vec3d x0, n0;
        if (!nearestFreeHit(caster, input, wettedIn, anchor, axisDir, std::numeric_limits<double>::max(), x0, n0)) {
            // The axis misses the fluid: anchor the pattern where this magnet's field is strongest.
            double best = -1;
            for (size_t v = 0; v < nIn; ++v) {
                if (!activeIn[v]) continue;
                const double h = magnetField(magnet, toD(input.vertices[v])).squaredNorm();
                if (h > best) best = h, x0 = toD(input.vertices[v]);
            }
            if (best < 0) continue;
            n0 = up;
            Vec3d hit, normal;
            if (nearestFreeHit(caster, input, wettedIn, x0, up, 1e-3 * diagonal + 1e-9, hit, normal)) n0 = normal;
        }
        const Vec3d H0 = fields.field(x0, n0);
        const double M0 = fields.magnetization(x0, H0);
        if (!(M0 > Mc)) continue;
        // The magnet must dominate its own origin (two coaxial magnets make one pattern).
        double total2 = 0;
        for (const Magnet& other : in.magnets) total2 += magnetField(other, x0).squaredNorm();
        if (magnetField(magnet, x0).squaredNorm() < 0.3 * total2) continue;

        Pattern pat;
        pat.info.magnet = int(m);
        pat.info.origin = x0;
        pat.info.normal = n0;
        pat.info.field = H0.norm();
        pat.info.magnetization = M0;
        double l = P.spacing == SpikeParams::Spacing::Paper
                       ? P.alpha / std::max(H0.norm(), 1e-30)
                       : 2.0 / std::sqrt(3.0) *
                             criticalWavelength(in.fluid.density - P.ambientDensity, g, in.fluid.surfaceTension);
        pat.info.spacing = std::clamp(l, P.minSpacing, P.maxSpacing);
        // Fixed frame: world x (or y) projected into the tangent plane, rotated by `orientation`.
        Vec3d ref = std::abs(n0.x()) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
        Vec3d e1 = (ref - ref.dot(n0) * n0).normalized();
        const double phi = P.orientation * kPi / 180.0;
        e1 = std::cos(phi) * e1 + std::sin(phi) * n0.cross(e1);
        pat.info.axis = e1;
        bool duplicate = false;
        for (const Pattern& other : patterns)
            if ((other.info.origin - x0).norm() < std::max(other.info.spacing, pat.info.spacing)) duplicate = true;
        if (!duplicate) patterns.push_back(std::move(pat));
    }
    if (patterns.empty()) return unchanged();

    // 3. Tips (Fig. 7): trace six axes along the surface, fill the rings between them.
    for (Pattern& pat : patterns) {
        const double l = pat.info.spacing;
        const Vec3d x0 = pat.info.origin, n0 = pat.info.normal, e1 = pat.info.axis, e1perp = n0.cross(e1);
        std::unordered_map<int64_t, size_t> index;
        auto addTip = [&](int i, int j, const Vec3d& x, const Vec3d& n) {
            if (index.count(latticeKey(i, j))) return;
            index[latticeKey(i, j)] = pat.tips.size();
            pat.tips.push_back({i, j, x, n, Eigen::Matrix<double, 2, 3>::Zero()});
        };
        // The field line through x meets the surface: the next mapping coordinate.
        auto dropOnSurface = [&](const Vec3d& x, Vec3d& s, Vec3d& n) {
            Vec3d H = fields.field(x, n0);
            if (!(H.norm() > 0)) H = n0;
            return nearestFreeHit(caster, input, wettedIn, x, H, 0.75 * l, s, n);
        };
        auto alive = [&](const Vec3d& s, const Vec3d& n) { return fields.magnetization(s, fields.field(s, n)) > Mc; };
        addTip(0, 0, x0, n0);
        const int maxRings = int(std::ceil(diagonal / l)) + 1;
        std::vector<Vec3d> axisTips[6], axisNormals[6];
        for (int k = 0; k < 6; ++k) {
            Vec3d s = x0, n = n0;
            Vec3d d = std::cos(k * kPi / 3) * e1 + std::sin(k * kPi / 3) * e1perp;
            axisTips[k].push_back(x0);
            axisNormals[k].push_back(n0);
            int dead = 0;
            for (int ring = 1; ring <= maxRings && dead < 2; ++ring) {
                d = d - d.dot(n) * n; // eq. 15: step along the tangent at the previous tip
                if (!(d.norm() > 1e-12)) break;
                d.normalize();
                Vec3d next, nextNormal;
                if (!dropOnSurface(s + l * d, next, nextNormal)) break;
                s = next;
                n = nextNormal;
                axisTips[k].push_back(s);
                axisNormals[k].push_back(n);
                addTip(ring * kAxis[k][0], ring * kAxis[k][1], s, n);
                dead = alive(s, n) ? 0 : dead + 1;
            }
        }
        for (int k = 0; k < 6; ++k) {
            const int k1 = (k + 1) % 6;
            const int rings = int(std::min(axisTips[k].size(), axisTips[k1].size())) - 1;
            pat.info.rings = std::max(pat.info.rings, int(std::max(axisTips[k].size(), axisTips[k1].size())) - 1);
            for (int ring = 2; ring <= rings; ++ring)
                for (int step = 1; step < ring; ++step) {
                    const double f = double(step) / ring; // Fig. 7c: between the two n-th axis tips
                    const Vec3d x = (1 - f) * axisTips[k][size_t(ring)] + f * axisTips[k1][size_t(ring)];
                    Vec3d s, n;
                    if (!dropOnSurface(x, s, n)) continue;
                    addTip(ring * kAxis[k][0] + step * (kAxis[k1][0] - kAxis[k][0]),
                           ring * kAxis[k][1] + step * (kAxis[k1][1] - kAxis[k][1]), s, n);
                }
        }
        // Each tip's lattice basis from its neighbours (central differences where both exist).
        auto position = [&](int i, int j, Vec3d& x) {
            auto it = index.find(latticeKey(i, j));
            if (it == index.end()) return false;
            x = pat.tips[it->second].position;
            return true;
        };
        for (Tip& tip : pat.tips) {
            auto basis = [&](int di, int dj, const Vec3d& flat) {
                Vec3d plus, minus;
                const bool hasPlus = position(tip.i + di, tip.j + dj, plus);
                const bool hasMinus = position(tip.i - di, tip.j - dj, minus);
                if (hasPlus && hasMinus) return Vec3d(0.5 * (plus - minus));
                if (hasPlus) return Vec3d(plus - tip.position);
                if (hasMinus) return Vec3d(tip.position - minus);
                return Vec3d(l * (flat - flat.dot(tip.normal) * tip.normal).normalized());
            };
            const Vec3d f1 = e1, f2 = 0.5 * e1 + std::sqrt(0.75) * e1perp;
            auto frame = [&](const Vec3d& b1, const Vec3d& b2) {
                Eigen::Matrix3d A;
                A.col(0) = b1;
                A.col(1) = b2;
                const Vec3d c = b1.cross(b2);
                A.col(2) = c.norm() > 0 ? Vec3d(c.normalized() * l) : Vec3d::Zero();
                return A;
            };
            // Neighbours that (nearly) line up with the tip give b1 x b2 ~ 0 and no inverse:
            // that tip takes the flat basis projected on its tangent plane, and where even
            // that degenerates (a normal in the pattern's plane), the pattern's own frame.
            const double minDet = 1e-9 * l * l * l;
            Eigen::Matrix3d A = frame(basis(1, 0, f1), basis(0, 1, f2));
            if (!(std::abs(A.determinant()) >= minDet) || !A.allFinite()) {
                auto project = [&](const Vec3d& f) {
                    const Vec3d t = f - f.dot(tip.normal) * tip.normal;
                    return t.norm() > 1e-12 ? Vec3d(l * t.normalized()) : Vec3d::Zero();
                };
                A = frame(project(f1), project(f2));
            }
            if (!(std::abs(A.determinant()) >= minDet) || !A.allFinite()) {
                A.col(0) = l * f1;
                A.col(1) = l * f2;
                A.col(2) = l * n0;
            }
            tip.toLattice = A.inverse().topRows<2>();
        }
        for (Tip& tip : pat.tips) {
            const Vec3d H = fields.field(tip.position, tip.normal);
            tip.amplitude = std::min(P.beta * H.norm(), P.maxAspect * l / 3.0) *
                            fields.magnetizationFade(fields.magnetization(tip.position, H));
            tip.direction = growthDirection(H, tip.normal, P.maxTilt);
        }
        std::vector<Vec3d> positions;
        for (const Tip& tip : pat.tips) positions.push_back(tip.position);
        pat.grid = std::make_unique<PointGrid>(positions, l);
    }

    // 4. Refine the supercritical region (and one ring around it) to l / resolution.
    double minSpacing = std::numeric_limits<double>::max();
    for (const Pattern& pat : patterns) minSpacing = std::min(minSpacing, pat.info.spacing);
    TriangleMesh refined = input;
    {
        std::vector<char> near(nIn, 0), selected(input.triangles.size(), 0);
        for (size_t t = 0; t < input.triangles.size(); ++t)
            for (uint32_t v : input.triangles[t])
                if (activeIn[v]) selected[t] = 1;
        for (size_t t = 0; t < input.triangles.size(); ++t)
            if (selected[t])
                for (uint32_t v : input.triangles[t]) near[v] = 1;
        for (size_t t = 0; t < input.triangles.size(); ++t)
            for (uint32_t v : input.triangles[t])
                if (near[v]) selected[t] = 1;
        if (P.remeshIterations > 0)
            res.refinedOk = remeshSelectedTriangles(refined, selected, minSpacing / P.resolution, P.remeshIterations);
    }
    const size_t n = refined.vertices.size();
    // Put a vertex exactly on every tip: the apex of each spike is then a vertex (a sharp,
    // well-placed tip for the renderer, and the same vertex position in every frame while the
    // magnet is still). The nearest vertex is less than an edge away, inside its own 1-ring.
    {
        std::vector<Vec3d> points(n);
        for (size_t v = 0; v < n; ++v) points[v] = toD(refined.vertices[v]);
        const double cell = minSpacing / P.resolution;
        const PointGrid grid(points, cell);
        for (const Pattern& pat : patterns)
            for (const Tip& tip : pat.tips) {
                long nearest = -1;
                double best = std::numeric_limits<double>::max();
                grid.forEachWithin(tip.position, 1.5 * cell, [&](uint32_t v, double d2) {
                    if (d2 < best) best = d2, nearest = long(v);
                });
                if (nearest >= 0) refined.vertices[size_t(nearest)] = tip.position.cast<float>();
            }
    }
    const std::vector<Vec3d> normals = areaWeightedNormals(refined);

    // 5. Heights and directions on the refined surface.
    std::vector<char> wetted(n, 0);
    tbb::parallel_for(size_t(0), n, [&](size_t v) { wetted[v] = fields.wetted(toD(refined.vertices[v])); });
    std::vector<Vec3d> wettedPoints;
    for (size_t v = 0; v < n; ++v)
        if (wetted[v]) wettedPoints.push_back(toD(refined.vertices[v]));
    const double wallFade = P.wallFade > 0 ? P.wallFade : 0.5 * minSpacing;
    const PointGrid wallGrid(wettedPoints, wallFade);

    // The displacement at a surface point x with normal nx; `weight` is its fade factor.
    auto displacement = [&](const Vec3d& x, const Vec3d& nx, double& weight, Vec3d& direction) -> double {
        weight = 0;
        direction = nx;
        if (fields.wetted(x)) return 0;
        const Vec3d H = fields.field(x, nx);
        const double M = fields.magnetization(x, H);
        const double fade = fields.magnetizationGate(M) *
                            (wallGrid.empty() ? 1.0 : smoothstep01(wallGrid.nearestDistance(x, wallFade) / wallFade));
        if (fade <= 0) return 0;
        // Per pattern: eq. 13 from every nearby tip's lattice map, blended by a smooth partition
        // of unity (radius l; exact on a regular lattice), and each spike's amplitude and
        // direction from its own tip (a narrow kernel, radius 0.75 l, so each spike is a rigid,
        // symmetric cone leaning along the field at its tip; blended between spikes).
        double sumDominance = 0, S = 0, W = 0, A = 0, WA = 0;
        Vec3d D = Vec3d::Zero();
        std::vector<double> dominance(patterns.size());
        for (size_t p = 0; p < patterns.size(); ++p) {
            dominance[p] = fieldDominance(magnetField(in.magnets[size_t(patterns[p].info.magnet)], x));
            sumDominance += dominance[p];
        }
        for (size_t p = 0; p < patterns.size(); ++p) {
            const double d = sumDominance > 0 ? dominance[p] / sumDominance : 1.0 / double(patterns.size());
            if (d < 1e-4) continue;
            const Pattern& pat = patterns[p];
            const double R = pat.info.spacing, Rn = 0.75 * R;
            double s = 0, w = 0, a = 0, wa = 0;
            Vec3d dir = Vec3d::Zero();
            pat.grid->forEachWithin(x, R, [&](uint32_t t, double d2) {
                const Tip& tip = pat.tips[t];
                const double q = 1.0 - d2 / (R * R);
                const double wt = q * q;
                const Eigen::Vector2d ab = tip.toLattice * (x - tip.position);
                s += wt * hexProfile(ab.x(), ab.y());
                w += wt;
                if (d2 < Rn * Rn) {
                    const double qn = 1.0 - d2 / (Rn * Rn);
                    const double wn = qn * qn * qn * qn;
                    a += wn * tip.amplitude;
                    dir += wn * tip.direction;
                    wa += wn;
                }
            });
            S += d * s;
            W += d * w;
            A += d * a;
            D += d * dir;
            WA += d * wa;
        }
        if (!(W > 0)) return 0;
        const double coverage = smoothstep01(W / 0.4);
        const double F = sharpenedProfile(S / W, P.sharpness);
        // Far from every tip (trough centres of a stretched lattice) the local field takes over.
        constexpr double eps = 1e-3;
        double spacing = 0;
        for (size_t p = 0; p < patterns.size(); ++p)
            spacing += (sumDominance > 0 ? dominance[p] / sumDominance : 1.0 / double(patterns.size())) *
                       patterns[p].info.spacing;
        const double localC0 = std::min(P.beta * H.norm(), P.maxAspect * spacing / 3.0) * fields.magnetizationFade(M);
        const double C0 = (A + eps * localC0) / (WA + eps);
        const Vec3d dir = growthDirection(D + eps * growthDirection(H, nx, P.maxTilt), nx, P.maxTilt);
        weight = fade * coverage;
        direction = dir;
        return weight * C0 * F;
    };

    std::vector<double> weight(n, 0.0);
    TriangleMesh& out = res.mesh;
    out = refined;
    tbb::parallel_for(size_t(0), n, [&](size_t v) {
        if (wetted[v]) return;
        Vec3d dir;
        const double z = displacement(toD(refined.vertices[v]), normals[v], weight[v], dir);
        out.vertices[v] = (toD(refined.vertices[v]) + z * dir).cast<float>();
    });

    // 6. Volume: offset the spiky region along the normals, weighted like the heights.
    if (P.conserveVolume) {
        const std::vector<double> area = vertexAreas(refined);
        double weightedArea = 0;
        for (size_t v = 0; v < n; ++v) weightedArea += area[v] * weight[v];
        for (int iteration = 0; iteration < 4 && weightedArea > 0; ++iteration) {
            const double excess = enclosedVolume(out) - res.volumeIn;
            const double offset = excess / weightedArea;
            if (std::abs(offset) < 1e-12) break;
            for (size_t v = 0; v < n; ++v)
                if (weight[v] > 0) out.vertices[v] = (toD(out.vertices[v]) - offset * weight[v] * normals[v]).cast<float>();
        }
    }
    res.volumeOut = enclosedVolume(out);
    computeVertexNormals(out);
    res.refined = std::move(refined);

    // Report the tips that grew.
    for (size_t p = 0; p < patterns.size(); ++p) {
        for (const Tip& tip : patterns[p].tips) {
            double w;
            Vec3d dir;
            const double z = displacement(tip.position, tip.normal, w, dir);
            if (!(z > 0)) continue;
            // Only where this pattern is in charge is the tip a peak of the blended surface.
            double own = 0, all = 0;
            for (const Pattern& q : patterns) {
                const double h2 = fieldDominance(magnetField(in.magnets[size_t(q.info.magnet)], tip.position));
                all += h2;
                if (&q == &patterns[p]) own = h2;
            }
            if (all > 0 && own < 0.5 * all) continue;
            SpikeTip t;
            t.pattern = int(p);
            t.i = tip.i;
            t.j = tip.j;
            t.base = tip.position;
            t.direction = dir;
            t.height = z;
            t.apex = tip.position + z * dir;
            res.tips.push_back(t);
            res.maxHeight = std::max(res.maxHeight, z);
        }
        res.patterns.push_back(patterns[p].info);
    }
    return res;
}

} // namespace ferro

// The mesh container: any closed triangle mesh (a thin-walled cup), read with core's readMesh.
// A mesh need not be convex, so constrain() tests the motion segment against the triangles
// with a conservative, watertight test and slides the particle along the wall it would have
// crossed; contains() votes with the parity of three rays.
#include "sim/geometry/ContainerKinds.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/core/TriangleMesh.hpp"
#include "sim/spatial/HashGrid.hpp"
#include "sim/spatial/TriangleGrid.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace ferro {
namespace container_detail {
namespace {

struct LoadedMesh {
    std::vector<Vec3d> verts;                  ///< merged by position, scaled and translated
    std::vector<std::array<uint32_t, 3>> tris; ///< no repeated index within a triangle
};

struct PositionHash {
    size_t operator()(const std::array<double, 3>& p) const {
        const std::hash<double> h;
        size_t s = h(p[0]);
        s ^= h(p[1]) + 0x9e3779b97f4a7c15ull + (s << 6) + (s >> 2);
        s ^= h(p[2]) + 0x9e3779b97f4a7c15ull + (s << 6) + (s >> 2);
        return s;
    }
};

LoadedMesh loadMesh(const ContainerParams& params, const std::string& where) {
    const std::string ctx = where + ": container.file: '" + params.meshFile + "': ";
    TriangleMesh file;
    try {
        file = readMesh(params.meshFile);
    } catch (const MeshFileError& e) {
        throw SceneError(ctx + "cannot load: " + e.what());
    }
    // readMesh joins vertices only where all attributes match (an OBJ corner with three
    // normals stays three vertices), so the topology is rebuilt from positions.
    LoadedMesh out;
    std::unordered_map<std::array<double, 3>, uint32_t, PositionHash> index;
    std::vector<uint32_t> merged(file.vertices.size());
    for (size_t i = 0; i < file.vertices.size(); ++i) {
        Vec3d q = params.meshScale * file.vertices[i].cast<double>() + params.meshTranslate;
        if (!q.allFinite()) throw SceneError(ctx + "non-finite vertex coordinates");
        q.array() += 0.0; // -0.0 -> +0.0, so equal positions are bitwise equal too
        const std::array<double, 3> key{q.x(), q.y(), q.z()};
        auto [it, added] = index.emplace(key, uint32_t(out.verts.size()));
        if (added) out.verts.push_back(q);
        merged[i] = it->second;
    }
    for (const auto& f : file.triangles) {
        const std::array<uint32_t, 3> tri{merged[f[0]], merged[f[1]], merged[f[2]]};
        if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) out.tris.push_back(tri);
    }
    const bool anyArea = std::any_of(out.tris.begin(), out.tris.end(), [&](const auto& t) {
        return (out.verts[t[1]] - out.verts[t[0]]).cross(out.verts[t[2]] - out.verts[t[0]]).squaredNorm() > 0;
    });
    if (!anyArea) throw SceneError(ctx + "mesh has no triangles");

    // Closed: every edge is shared by exactly two triangles. Ray parity and "the segment
    // crosses no triangle" both rely on it.
    std::unordered_map<uint64_t, int> edges;
    for (const auto& t : out.tris)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = t[k], b = t[(k + 1) % 3];
            ++edges[(uint64_t(std::min(a, b)) << 32) | std::max(a, b)];
        }
    size_t open = 0, crowded = 0;
    for (const auto& e : edges) {
        open += e.second == 1;
        crowded += e.second > 2;
    }
    if (open > 0 || crowded > 0) {
        std::string detail = std::to_string(open) + " boundary edges";
        if (crowded > 0)
            detail += ", " + std::to_string(crowded) + " edges shared by more than two triangles";
        throw SceneError(ctx + "mesh is not closed (" + detail + ")");
    }
    return out;
}


/// A triangle prepared for the segment test, in the container's local frame.
///
/// The segment test is watertight by construction: "the line passes through the triangle"
/// is decided with Plücker side products against the edges, and an edge shared by two
/// triangles yields the same product (up to sign) for both, so a segment through a shared
/// edge is caught by at least one of them. A small tolerance on the products additionally
/// accepts lines passing within `lineTol` of an edge or vertex, which covers fans of
/// triangles around a vertex where rounding could otherwise reject every triangle.
struct TriTest {
    Vec3d n;           ///< unit normal
    double w;          ///< plane: n . p = w
    Vec3d ed[3];       ///< edge directions (Plücker)
    Vec3d em[3];       ///< edge moments (Plücker)
    double etol[3];    ///< |ed| * lineTol: accepted side product per unit segment length
};

/// Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection 5.1.5).
double distanceSquared(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
    const Vec3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return (ap - ab * (d1 / (d1 - d3))).squaredNorm();
    const Vec3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return (ap - ac * (d2 / (d2 - d6))).squaredNorm();
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return (bp - (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))).squaredNorm();
    const double denom = 1.0 / (va + vb + vc);
    return (ap - ab * (vb * denom) - ac * (vc * denom)).squaredNorm();
}

/// Adds p to `points` unless an earlier point is closer than `radius`.
void addIfApart(HashGrid& points, double radius, const Vec3d& p) {
    if (!points.anyCloserThan(p, radius)) points.add(p);
}

class MeshContainer final : public Container {
public:
    /// `obstacle`: a solid standing in the vessel (makeMeshObstacle): the fluid is anywhere
    /// outside it, so there is no safety box (contains() and constrain() test the mesh alone).
    MeshContainer(const LoadedMesh& mesh, const ContainerParams& params, bool obstacle = false)
        : fluidInside_(params.fluidInside), obstacle_(obstacle) {
        Vec3d lo = mesh.verts[0], hi = mesh.verts[0];
        for (const Vec3d& v : mesh.verts) {
            lo = lo.cwiseMin(v);
            hi = hi.cwiseMax(v);
        }
        if (obstacle_) {
            boxLo_ = Vec3d::Constant(-kHuge);
            boxHi_ = Vec3d::Constant(kHuge);
        } else if (params.hasBounds) {
            boxLo_ = params.boundsMin;
            boxHi_ = params.boundsMax;
        } else {
            // Extended upward by the mesh's own height, so fluid can be poured in from above.
            boxLo_ = lo;
            boxHi_ = hi;
            boxHi_.z() += hi.z() - lo.z();
        }
        for (int a = 0; a < 3; ++a) {
            boxLoF_[a] = inwardLo(boxLo_[a]);
            boxHiF_[a] = inwardHi(boxHi_[a]);
        }

        // Local frame centred on the mesh: the Plücker moments (cross products of
        // positions) keep their precision however far the vessel sits from the origin.
        origin_ = 0.5 * (lo + hi);
        const double radius = std::max(0.5 * (hi - lo).norm(), std::numeric_limits<double>::min());
        lineTol_ = 1e-9 * radius;

        verts_.reserve(mesh.tris.size());
        tris_.reserve(mesh.tris.size());
        for (const auto& t : mesh.tris) {
            const std::array<Vec3d, 3> p{mesh.verts[t[0]] - origin_, mesh.verts[t[1]] - origin_,
                                         mesh.verts[t[2]] - origin_};
            const Vec3d cross = (p[1] - p[0]).cross(p[2] - p[0]);
            // A zero-area sliver blocks nothing its neighbours do not already block.
            if (!(cross.norm() > 0)) continue;
            TriTest tt;
            tt.n = cross.normalized();
            tt.w = tt.n.dot(p[0]);
            for (int k = 0; k < 3; ++k) {
                // Computed from the lower vertex index to the higher one and negated when
                // the triangle runs the other way: both triangles of an edge then get
                // bit-identical products up to sign (IEEE negation is exact).
                const uint32_t ia = t[k], ib = t[(k + 1) % 3];
                const Vec3d& a = ia < ib ? p[k] : p[(k + 1) % 3];
                const Vec3d& b = ia < ib ? p[(k + 1) % 3] : p[k];
                const double sign = ia < ib ? 1.0 : -1.0;
                tt.ed[k] = sign * (b - a);
                tt.em[k] = sign * a.cross(b);
                tt.etol[k] = (b - a).norm() * lineTol_;
            }
            tris_.push_back(tt);
            verts_.push_back(p);
        }

        const Vec3d pad = Vec3d::Constant(1e-3 * radius);
        gridPad_ = 1e-6 * radius;
        grid_.build(verts_, lo - origin_ - pad, hi - origin_ + pad, gridPad_);

        // Slide offset: ~1e-4 of a cell, and several float steps (rounding moves a stored
        // position by half a step per axis), so a slid particle stays on its side.
        // (An obstacle's box is unbounded: its own extent sets the float steps.)
        const double maxAbs = obstacle_ ? lo.cwiseAbs().cwiseMax(hi.cwiseAbs()).maxCoeff()
                                        : boxLo_.cwiseAbs().cwiseMax(boxHi_.cwiseAbs()).maxCoeff();
        delta_ = std::max(1e-4 * grid_.h, 8.0 * maxAbs * double(std::numeric_limits<float>::epsilon()));
        planeTol_ = 0.25 * delta_;
    }

    std::vector<Vec3> sampleWalls(double spacing, double /*offset: walls may be thin*/) const override {
        checkSpacing(spacing);
        HashGrid dedup(0.3 * spacing);
        // Vertices, then edges, then interiors: points on shared features come first and
        // win the de-duplication, so edges are sampled evenly from either side.
        for (const auto& t : verts_)
            for (const Vec3d& p : t) addIfApart(dedup, 0.3 * spacing, p);
        for (const auto& t : verts_)
            for (int k = 0; k < 3; ++k) {
                const Vec3d &a = t[k], &b = t[(k + 1) % 3];
                const long n = long(std::ceil((b - a).norm() / spacing));
                for (long i = 1; i < n; ++i) addIfApart(dedup, 0.3 * spacing, a + (b - a) * (double(i) / double(n)));
            }
        for (const auto& t : verts_) {
            // Lattice along the two edges at the vertex opposite the longest edge; the
            // steps along each edge are <= spacing, so long slivers are not oversampled.
            int apex = 0;
            double longest = -1;
            for (int k = 0; k < 3; ++k) {
                const double len = (t[(k + 2) % 3] - t[(k + 1) % 3]).norm();
                if (len > longest) longest = len, apex = k;
            }
            const Vec3d& a = t[apex];
            const Vec3d u = t[(apex + 1) % 3] - a, v = t[(apex + 2) % 3] - a;
            const long nu = long(std::ceil(u.norm() / spacing)), nv = long(std::ceil(v.norm() / spacing));
            for (long i = 1; i < nu; ++i)
                for (long j = 1; i * nv + j * nu < nu * nv; ++j)
                    addIfApart(dedup, 0.3 * spacing, a + u * (double(i) / double(nu)) + v * (double(j) / double(nv)));
        }
        std::vector<Vec3> out;
        out.reserve(dedup.points().size());
        for (const Vec3d& p : dedup.points()) out.push_back(toVec3(p + origin_));
        return out;
    }

    bool contains(const Vec3d& p, double margin) const override {
        for (int a = 0; a < 3; ++a)
            if (!(p[a] >= boxLo_[a] + margin && p[a] <= boxHi_[a] - margin)) return false;
        const Vec3d q = p - origin_;
        if (margin > 0 && nearTriangle(q, margin)) return false;
        // Parity of three rays in irrational directions, majority vote: a ray that grazes
        // an edge or vertex (and so miscounts) cannot outvote the other two.
        static const Vec3d dirs[3] = {
            Vec3d(0.5773502691896258, 0.7071067811865476, 0.4142135623730950).normalized(),
            Vec3d(-0.6180339887498949, 0.3183098861837907, 0.7320508075688772).normalized(),
            Vec3d(0.2718281828459045, -0.8660254037844386, -0.4472135954999579).normalized()};
        int inside = 0;
        for (const Vec3d& d : dirs) inside += crossings(q, d) % 2;
        return (inside >= 2) == fluidInside_;
    }

    bool constrain(const Vec3& xOld, Vec3& x, Vec3& v) const override {
        if (parkIfNonFinite(xOld, x, v)) return true;
        bool corrected = clampBox(x, v);
        const Vec3d p = xOld.cast<double>() - origin_;
        // Each round either finds the motion clear or slides the end point onto the
        // xOld side of the first wall it crosses. Three slides settle a particle into a
        // corner of three walls; if it still crosses, it stays where it was.
        for (int round = 0; round <= 3; ++round) {
            const Vec3d q = x.cast<double>() - origin_;
            Hit hit;
            if (!firstHit(p, q, hit)) return corrected;
            if (round == 3) break;
            const TriTest& t = tris_[hit.tri];
            x = toStoredVec3(q - (hit.dQ - hit.side * delta_) * t.n + origin_);
            const double vn = v.cast<double>().dot(t.n);
            if (vn * hit.side < 0) v = (v.cast<double>() - vn * t.n).cast<Real>();
            clampBox(x, v);
            corrected = true;
        }
        x = xOld;
        v.setZero();
        return true;
    }

    void bounds(Vec3d& lo, Vec3d& hi) const override {
        lo = boxLo_;
        hi = boxHi_;
    }

private:
    struct Hit {
        double t = 0;      ///< segment parameter of the crossing
        double dQ = 0;     ///< signed plane distance of the end point
        double side = 0;   ///< +1 or -1: the side of the plane the start point is on
        uint32_t tri = 0;
    };

    bool clampBox(Vec3& x, Vec3& v) const {
        if (obstacle_) return false;
        bool corrected = false;
        for (int a = 0; a < 3; ++a) corrected |= clampAxis(x[a], v[a], boxLoF_[a], boxHiF_[a]);
        return corrected;
    }

    /// First triangle the segment p -> q crosses (local frame). An end point within
    /// planeTol of a triangle, on p's side, counts as crossing too: it is pushed to
    /// delta, so that no particle is left on a wall where inside/outside is ambiguous.
    bool firstHit(const Vec3d& p, const Vec3d& q, Hit& hit) const {
        const Vec3d d = q - p;
        const double len = d.norm();
        if (len == 0) return false;
        const Vec3d m = p.cross(q);
        const double pad = planeTol_ + gridPad_;
        long i0[3], i1[3];
        if (!grid_.range((p.cwiseMin(q).array() - pad).matrix(), (p.cwiseMax(q).array() + pad).matrix(), i0, i1))
            return false;
        bool found = false;
        for (long k = i0[2]; k <= i1[2]; ++k)
            for (long j = i0[1]; j <= i1[1]; ++j)
                for (long i = i0[0]; i <= i1[0]; ++i) {
                    const size_t c = grid_.cell(i, j, k);
                    for (uint32_t e = grid_.start[c]; e < grid_.start[c + 1]; ++e) {
                        const uint32_t id = grid_.items[e];
                        const TriTest& t = tris_[id];
                        const double dP = t.n.dot(p) - t.w;
                        // xOld is valid, hence off every wall; exactly on a plane it has no side.
                        if (dP == 0) continue;
                        const double side = dP > 0 ? 1.0 : -1.0;
                        const double dQ = t.n.dot(q) - t.w;
                        if (side * dQ > planeTol_) continue;
                        bool pos = true, neg = true;
                        for (int s = 0; s < 3; ++s) {
                            const double prod = d.dot(t.em[s]) + t.ed[s].dot(m);
                            const double tol = t.etol[s] * len;
                            pos = pos && prod >= -tol;
                            neg = neg && prod <= tol;
                        }
                        if (!pos && !neg) continue;
                        const double tt = dP != dQ ? std::clamp(dP / (dP - dQ), 0.0, 1.0) : 1.0;
                        if (!found || tt < hit.t) {
                            hit.t = tt;
                            hit.dQ = dQ;
                            hit.side = side;
                            hit.tri = id;
                            found = true;
                        }
                    }
                }
        return found;
    }

    /// True if a triangle is closer than `margin` to q (local frame).
    bool nearTriangle(const Vec3d& q, double margin) const {
        long i0[3], i1[3];
        const double pad = margin + gridPad_;
        if (!grid_.range((q.array() - pad).matrix(), (q.array() + pad).matrix(), i0, i1)) return false;
        for (long k = i0[2]; k <= i1[2]; ++k)
            for (long j = i0[1]; j <= i1[1]; ++j)
                for (long i = i0[0]; i <= i1[0]; ++i) {
                    const size_t c = grid_.cell(i, j, k);
                    for (uint32_t e = grid_.start[c]; e < grid_.start[c + 1]; ++e) {
                        const auto& t = verts_[grid_.items[e]];
                        if (distanceSquared(q, t[0], t[1], t[2]) < margin * margin) return true;
                    }
                }
        return false;
    }

    /// Number of triangles the ray q + t dir (t > 0) crosses, walking the grid cell by
    /// cell (Amanatides & Woo). A triangle listed in several cells is counted only in the
    /// cell whose stretch [enter, exit) of the ray holds the crossing.
    int crossings(const Vec3d& q, const Vec3d& dir) const {
        const Vec3d lo = grid_.origin;
        double tEnter = 0, tEnd = std::numeric_limits<double>::infinity();
        for (int a = 0; a < 3; ++a) {
            const double t0 = (lo[a] - q[a]) / dir[a];
            const double t1 = (lo[a] + double(grid_.n[a]) * grid_.h - q[a]) / dir[a];
            tEnter = std::max(tEnter, std::min(t0, t1));
            tEnd = std::min(tEnd, std::max(t0, t1));
        }
        if (!(tEnter < tEnd)) return 0;

        long cell[3], step[3];
        double tNext[3], tDelta[3];
        for (int a = 0; a < 3; ++a) {
            const double f = std::floor((q[a] + tEnter * dir[a] - lo[a]) / grid_.h);
            cell[a] = std::clamp(long(std::clamp(f, -1.0, double(grid_.n[a]))), 0L, grid_.n[a] - 1);
            step[a] = dir[a] > 0 ? 1 : -1;
            tNext[a] = (lo[a] + double(cell[a] + (dir[a] > 0 ? 1 : 0)) * grid_.h - q[a]) / dir[a];
            tDelta[a] = grid_.h / std::abs(dir[a]);
        }
        const Vec3d m = q.cross(dir);
        int count = 0;
        for (;;) {
            const int axis = tNext[0] < tNext[1] ? (tNext[0] < tNext[2] ? 0 : 2) : (tNext[1] < tNext[2] ? 1 : 2);
            const double tExit = std::min(tNext[axis], tEnd);
            const size_t c = grid_.cell(cell[0], cell[1], cell[2]);
            for (uint32_t e = grid_.start[c]; e < grid_.start[c + 1]; ++e) {
                const TriTest& t = tris_[grid_.items[e]];
                const double nd = t.n.dot(dir);
                if (nd == 0) continue;
                const double th = (t.w - t.n.dot(q)) / nd;
                if (!(th > 0 && th >= tEnter && th < tExit)) continue;
                bool pos = true, neg = true;
                for (int s = 0; s < 3; ++s) {
                    const double prod = dir.dot(t.em[s]) + t.ed[s].dot(m);
                    pos = pos && prod > 0;
                    neg = neg && prod < 0;
                }
                count += pos || neg;
            }
            if (tExit >= tEnd) break;
            cell[axis] += step[axis];
            if (cell[axis] < 0 || cell[axis] >= grid_.n[axis]) break;
            tEnter = tExit;
            tNext[axis] += tDelta[axis];
        }
        return count;
    }

    bool fluidInside_;
    bool obstacle_ = false;
    Vec3d boxLo_, boxHi_;
    float boxLoF_[3], boxHiF_[3];
    Vec3d origin_;
    double lineTol_ = 0, gridPad_ = 0, delta_ = 0, planeTol_ = 0;
    std::vector<TriTest> tris_;
    std::vector<std::array<Vec3d, 3>> verts_; ///< corners of tris_[i], local frame
    TriangleGrid grid_;
};

} // namespace

std::unique_ptr<Container> makeMeshContainer(const ContainerParams& params, const std::string& where) {
    return std::make_unique<MeshContainer>(loadMesh(params, where), params);
}

std::unique_ptr<Container> makeMeshObstacle(const std::vector<Vec3d>& vertices,
                                            const std::vector<std::array<uint32_t, 3>>& triangles) {
    LoadedMesh mesh;
    mesh.verts = vertices;
    for (const auto& t : triangles)
        if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) mesh.tris.push_back(t);
    // The fluid is outside the mesh and not boxed in by it: the vessel bounds the fluid.
    ContainerParams params;
    params.type = ContainerParams::Type::Mesh;
    params.fluidInside = false;
    return std::make_unique<MeshContainer>(mesh, params, true);
}

} // namespace container_detail
} // namespace ferro

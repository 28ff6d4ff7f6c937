// Containers (see Container.hpp): None, Box, Dish and Mesh.
//
// Box and Dish are convex, so projecting a point back into them can never cross a wall:
// their constrain() is a clamp. A mesh can be any closed shape (a thin-walled cup), so its
// constrain() tests the motion segment against the triangles with a conservative,
// watertight test and slides the particle along the wall it would have crossed.
#include "sim/sph/Container.hpp"
#include "sim/core/Constants.hpp"

#include "sim/core/SceneDocument.hpp"

#include <Eigen/Geometry>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <unordered_map>

namespace ferro {
namespace {

constexpr double kHuge = 1e30;

/// The float closest to `lo` that is not below it. Clamping float coordinates to these
/// (and to inwardHi) keeps them inside the double-precision bounds, so a clamped point
/// passes contains(p, 0) exactly.
float inwardLo(double lo) {
    float f = static_cast<float>(lo);
    if (static_cast<double>(f) < lo) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

float inwardHi(double hi) {
    float f = static_cast<float>(hi);
    if (static_cast<double>(f) > hi) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
}

/// Clamps one coordinate into [lo, hi] and stops the velocity that pushed it out.
bool clampAxis(float& x, float& v, float lo, float hi) {
    if (x < lo) {
        x = lo;
        v = std::max(v, 0.0f);
        return true;
    }
    if (x > hi) {
        x = hi;
        v = std::min(v, 0.0f);
        return true;
    }
    return false;
}

/// A non-finite position goes back to its (valid) old one, at rest. The solver reports
/// blow-ups before it calls constrain(); this only keeps the container's promise.
bool parkIfNonFinite(const Vec3& xOld, Vec3& x, Vec3& v) {
    if (x.allFinite()) return false;
    x = xOld;
    v.setZero();
    return true;
}

void checkSpacing(double spacing) {
    if (!(spacing > 0) || !std::isfinite(spacing))
        throw std::invalid_argument("Container::sampleWalls: spacing must be > 0");
}

long intervals(double length, double spacing) {
    return std::max(1L, std::lround(length / spacing));
}

Vec3 toVec3(const Vec3d& p) { return p.cast<Real>(); }

/// Rounds to float through a volatile, so that code re-testing a corrected position sees
/// exactly the float that is stored. A plain cast is not enough: GCC 12.2's SLP vectorizer
/// (-O2 and up) was seen to drop a double -> float -> double round trip entirely.
Vec3 toStoredVec3(const Vec3d& p) {
    volatile Real f[3] = {Real(p.x()), Real(p.y()), Real(p.z())};
    const Real x = f[0], y = f[1], z = f[2];
    return Vec3(x, y, z);
}

// ---------------------------------------------------------------------------------------

class NoneContainer final : public Container {
public:
    std::vector<Vec3> sampleWalls(double, double) const override { return {}; }
    bool contains(const Vec3d&, double) const override { return true; }
    bool constrain(const Vec3&, Vec3&, Vec3&) const override { return false; }
    void bounds(Vec3d& lo, Vec3d& hi) const override {
        lo.setConstant(-kHuge);
        hi.setConstant(kHuge);
    }
};

// ---------------------------------------------------------------------------------------

class BoxContainer final : public Container {
public:
    BoxContainer(const Vec3d& lo, const Vec3d& hi, bool closedTop)
        : lo_(lo), hi_(hi), closedTop_(closedTop) {
        for (int a = 0; a < 3; ++a) {
            loF_[a] = inwardLo(lo[a]);
            hiF_[a] = inwardHi(hi[a]);
        }
    }

    std::vector<Vec3> sampleWalls(double spacing, double offset) const override {
        checkSpacing(spacing);
        const Vec3d lo = lo_ - Vec3d::Constant(offset);
        const Vec3d hi = hi_ + Vec3d(offset, offset, closedTop_ ? offset : 0.0);
        const Vec3d ext = hi - lo;
        const long nx = intervals(ext.x(), spacing), ny = intervals(ext.y(), spacing),
                   nz = intervals(ext.z(), spacing);
        std::vector<Vec3> out;
        auto put = [&](long i, long j, long k) {
            out.push_back(toVec3(lo + Vec3d(ext.x() * double(i) / double(nx),
                                             ext.y() * double(j) / double(ny),
                                             ext.z() * double(k) / double(nz))));
        };
        // One lattice over the whole box surface: every lattice point is visited once, so
        // shared edges and corners carry no duplicates.
        for (long k = 0; k <= nz; ++k) {
            if (k == 0 || (k == nz && closedTop_)) {
                for (long j = 0; j <= ny; ++j)
                    for (long i = 0; i <= nx; ++i) put(i, j, k);
                continue;
            }
            for (long i = 0; i <= nx; ++i) {
                put(i, 0, k);
                put(i, ny, k);
            }
            for (long j = 1; j < ny; ++j) {
                put(0, j, k);
                put(nx, j, k);
            }
        }
        return out;
    }

    bool contains(const Vec3d& p, double margin) const override {
        for (int a = 0; a < 3; ++a)
            if (!(p[a] >= lo_[a] + margin && p[a] <= hi_[a] - margin)) return false;
        return true;
    }

    bool constrain(const Vec3& xOld, Vec3& x, Vec3& v) const override {
        if (parkIfNonFinite(xOld, x, v)) return true;
        bool corrected = false;
        for (int a = 0; a < 3; ++a) corrected |= clampAxis(x[a], v[a], loF_[a], hiF_[a]);
        return corrected;
    }

    void bounds(Vec3d& lo, Vec3d& hi) const override {
        lo = lo_;
        hi = hi_;
    }

private:
    Vec3d lo_, hi_;
    bool closedTop_;
    float loF_[3], hiF_[3];
};

// ---------------------------------------------------------------------------------------

class DishContainer final : public Container {
public:
    DishContainer(const Vec3d& center, double radius, double height)
        : c_(center), r_(radius), h_(height), floorF_(inwardLo(center.z())) {}

    std::vector<Vec3> sampleWalls(double spacing, double offset) const override {
        checkSpacing(spacing);
        const double R = r_ + offset, floorZ = c_.z() - offset, wallH = h_ + offset;
        std::vector<Vec3> out;
        auto ring = [&](double radius, double z, long count, bool stagger) {
            // Alternate rings are turned by half a step, which packs them hexagonally.
            const double phase = stagger ? kPi / double(count) : 0.0;
            for (long i = 0; i < count; ++i) {
                const double a = phase + 2.0 * kPi * double(i) / double(count);
                out.push_back(toVec3(Vec3d(c_.x() + radius * std::cos(a),
                                           c_.y() + radius * std::sin(a), z)));
            }
        };
        // Floor: centre point and concentric rings; its outermost ring (r = R) is the
        // wall's bottom ring, emitted once below.
        out.push_back(toVec3(Vec3d(c_.x(), c_.y(), floorZ)));
        const long rings = intervals(R, spacing);
        for (long k = 1; k < rings; ++k) {
            const double r = R * double(k) / double(rings);
            ring(r, floorZ, std::max(3L, std::lround(2.0 * kPi * r / spacing)), k % 2 == 1);
        }
        const long around = std::max(3L, std::lround(2.0 * kPi * R / spacing));
        const long levels = intervals(wallH, spacing);
        for (long j = 0; j <= levels; ++j)
            ring(R, floorZ + wallH * double(j) / double(levels), around, (rings + j) % 2 == 1);
        return out;
    }

    bool contains(const Vec3d& p, double margin) const override {
        const double dx = p.x() - c_.x(), dy = p.y() - c_.y();
        return p.z() - c_.z() >= margin && std::sqrt(dx * dx + dy * dy) <= r_ - margin;
    }

    bool constrain(const Vec3& xOld, Vec3& x, Vec3& v) const override {
        if (parkIfNonFinite(xOld, x, v)) return true;
        bool corrected = false;
        if (x.z() < floorF_) {
            x.z() = floorF_;
            v.z() = std::max(v.z(), 0.0f);
            corrected = true;
        }
        const double dx = double(x.x()) - c_.x(), dy = double(x.y()) - c_.y();
        const double r2 = dx * dx + dy * dy;
        if (r2 <= r_ * r_) return corrected;

        // Radial projection onto the wall (extended upward: the wall is a safety net at
        // any height), pulled slightly inward so that the rounded float lands inside too.
        // Far from the origin floats are coarse, hence the growing pull and the fallback.
        const double r = std::sqrt(r2), nx = dx / r, ny = dy / r;
        for (double pull = 1e-6; pull < 1e-2; pull *= 8) {
            const Vec3 moved = toStoredVec3(Vec3d(c_.x() + nx * r_ * (1.0 - pull),
                                                  c_.y() + ny * r_ * (1.0 - pull), x.z()));
            const double ex = double(moved.x()) - c_.x(), ey = double(moved.y()) - c_.y();
            if (ex * ex + ey * ey > r_ * r_) continue;
            x = moved;
            const double vn = double(v.x()) * nx + double(v.y()) * ny;
            if (vn > 0) {
                v.x() = float(double(v.x()) - vn * nx);
                v.y() = float(double(v.y()) - vn * ny);
            }
            return true;
        }
        x = xOld;
        v.setZero();
        return true;
    }

    void bounds(Vec3d& lo, Vec3d& hi) const override {
        // Open top with no ceiling: the fluid may rise arbitrarily high.
        lo = Vec3d(c_.x() - r_, c_.y() - r_, c_.z());
        hi = Vec3d(c_.x() + r_, c_.y() + r_, kHuge);
    }

private:
    Vec3d c_;
    double r_, h_;
    float floorF_;
};

// ---------------------------------------------------------------------------------------
// Mesh container
// ---------------------------------------------------------------------------------------

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
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(
        params.meshFile, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
    if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
        throw SceneError(ctx + "cannot load: " + importer.GetErrorString());

    // Assimp joins vertices per mesh and only when all attributes match (an OBJ corner
    // with three normals stays three vertices), so the topology is rebuilt from positions.
    LoadedMesh out;
    std::unordered_map<std::array<double, 3>, uint32_t, PositionHash> index;
    auto vertexId = [&](const Eigen::Vector4d& p) {
        Vec3d q = params.meshScale * p.head<3>() + params.meshTranslate;
        if (!q.allFinite()) throw SceneError(ctx + "non-finite vertex coordinates");
        q.array() += 0.0; // -0.0 -> +0.0, so equal positions are bitwise equal too
        const std::array<double, 3> key{q.x(), q.y(), q.z()};
        auto [it, added] = index.emplace(key, uint32_t(out.verts.size()));
        if (added) out.verts.push_back(q);
        return it->second;
    };

    // Walk the node tree so that node transforms are honoured (they are identity for
    // typical OBJ/STL/PLY files, but not for every exporter).
    struct Item { const aiNode* node; Eigen::Matrix4d transform; };
    std::vector<Item> stack{{scene->mRootNode, Eigen::Matrix4d::Identity()}};
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        const aiMatrix4x4& m = item.node->mTransformation;
        Eigen::Matrix4d local;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) local(r, c) = m[r][c];
        const Eigen::Matrix4d transform = item.transform * local;
        for (unsigned i = 0; i < item.node->mNumMeshes; ++i) {
            const aiMesh* mesh = scene->mMeshes[item.node->mMeshes[i]];
            for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
                const aiFace& face = mesh->mFaces[f];
                if (face.mNumIndices != 3) continue; // points and lines bound nothing
                std::array<uint32_t, 3> tri;
                for (int k = 0; k < 3; ++k) {
                    const aiVector3D& v = mesh->mVertices[face.mIndices[k]];
                    tri[k] = vertexId(transform * Eigen::Vector4d(v.x, v.y, v.z, 1.0));
                }
                if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) out.tris.push_back(tri);
            }
        }
        for (unsigned c = 0; c < item.node->mNumChildren; ++c)
            stack.push_back({item.node->mChildren[c], transform});
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

/// Uniform grid of triangle indices; a triangle is listed in every cell its (slightly
/// padded) bounding box overlaps.
struct TriangleGrid {
    Vec3d origin{0, 0, 0};
    double h = 1;
    long n[3] = {1, 1, 1};
    std::vector<uint32_t> start; ///< cell -> first entry in items; size cells + 1
    std::vector<uint32_t> items;

    size_t cell(long i, long j, long k) const {
        return (size_t(k) * size_t(n[1]) + size_t(j)) * size_t(n[0]) + size_t(i);
    }

    /// Cell index range overlapping [lo, hi]; false if the box misses the grid.
    bool range(const Vec3d& lo, const Vec3d& hi, long i0[3], long i1[3]) const {
        for (int a = 0; a < 3; ++a) {
            // Clamped in double first: far-away points must not overflow the integer cast.
            const double f0 = std::floor((lo[a] - origin[a]) / h);
            const double f1 = std::floor((hi[a] - origin[a]) / h);
            if (!(f1 >= 0) || !(f0 < double(n[a]))) return false;
            i0[a] = long(std::max(f0, 0.0));
            i1[a] = long(std::min(f1, double(n[a] - 1)));
        }
        return true;
    }

    void build(const std::vector<std::array<Vec3d, 3>>& tris, const Vec3d& lo, const Vec3d& hi,
               double pad) {
        const Vec3d size = hi - lo;
        origin = lo;
        // About two cells per triangle, capped at 4M cells; the mesh's own proportions
        // set the cell size, since the particle spacing is not known here.
        const double volume = size.prod();
        h = std::cbrt(volume / (2.0 * double(tris.size())));
        h = std::max(h, std::cbrt(volume / double(1 << 22)));
        for (int a = 0; a < 3; ++a) n[a] = std::max(1L, long(std::ceil(size[a] / h)));

        const size_t cells = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
        std::vector<uint32_t> count(cells + 1, 0);
        auto forCells = [&](const std::array<Vec3d, 3>& t, auto&& fn) {
            const Vec3d tlo = (t[0].cwiseMin(t[1]).cwiseMin(t[2]).array() - pad).matrix();
            const Vec3d thi = (t[0].cwiseMax(t[1]).cwiseMax(t[2]).array() + pad).matrix();
            long i0[3], i1[3];
            if (!range(tlo, thi, i0, i1)) return;
            for (long k = i0[2]; k <= i1[2]; ++k)
                for (long j = i0[1]; j <= i1[1]; ++j)
                    for (long i = i0[0]; i <= i1[0]; ++i) fn(cell(i, j, k));
        };
        for (const auto& t : tris) forCells(t, [&](size_t c) { ++count[c + 1]; });
        for (size_t c = 0; c < cells; ++c) count[c + 1] += count[c];
        start = count;
        items.resize(start[cells]);
        for (uint32_t id = 0; id < uint32_t(tris.size()); ++id)
            forCells(tris[id], [&](size_t c) { items[count[c]++] = id; });
    }
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

/// Removes points closer than `radius` to an earlier point (hash grid of cell `radius`).
class PointDeduper {
public:
    explicit PointDeduper(double radius) : r_(radius) {}

    void add(const Vec3d& p) {
        const long ci = long(std::floor(p.x() / r_)), cj = long(std::floor(p.y() / r_)),
                   ck = long(std::floor(p.z() / r_));
        for (long k = ck - 1; k <= ck + 1; ++k)
            for (long j = cj - 1; j <= cj + 1; ++j)
                for (long i = ci - 1; i <= ci + 1; ++i) {
                    auto it = cells_.find(key(i, j, k));
                    if (it == cells_.end()) continue;
                    for (uint32_t id : it->second)
                        if ((points_[id] - p).squaredNorm() < r_ * r_) return;
                }
        cells_[key(ci, cj, ck)].push_back(uint32_t(points_.size()));
        points_.push_back(p);
    }

    const std::vector<Vec3d>& points() const { return points_; }

private:
    static uint64_t key(long i, long j, long k) {
        const uint64_t mask = (1u << 21) - 1;
        return (uint64_t(i) & mask) << 42 | (uint64_t(j) & mask) << 21 | (uint64_t(k) & mask);
    }
    double r_;
    std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
    std::vector<Vec3d> points_;
};

class MeshContainer final : public Container {
public:
    MeshContainer(const LoadedMesh& mesh, const ContainerParams& params)
        : fluidInside_(params.fluidInside) {
        Vec3d lo = mesh.verts[0], hi = mesh.verts[0];
        for (const Vec3d& v : mesh.verts) {
            lo = lo.cwiseMin(v);
            hi = hi.cwiseMax(v);
        }
        if (params.hasBounds) {
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
        const double maxAbs = boxLo_.cwiseAbs().cwiseMax(boxHi_.cwiseAbs()).maxCoeff();
        delta_ = std::max(1e-4 * grid_.h, 8.0 * maxAbs * double(std::numeric_limits<float>::epsilon()));
        planeTol_ = 0.25 * delta_;
    }

    std::vector<Vec3> sampleWalls(double spacing, double /*offset: walls may be thin*/) const override {
        checkSpacing(spacing);
        PointDeduper dedup(0.3 * spacing);
        // Vertices, then edges, then interiors: points on shared features come first and
        // win the de-duplication, so edges are sampled evenly from either side.
        for (const auto& t : verts_)
            for (const Vec3d& p : t) dedup.add(p);
        for (const auto& t : verts_)
            for (int k = 0; k < 3; ++k) {
                const Vec3d &a = t[k], &b = t[(k + 1) % 3];
                const long n = long(std::ceil((b - a).norm() / spacing));
                for (long i = 1; i < n; ++i) dedup.add(a + (b - a) * (double(i) / double(n)));
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
                    dedup.add(a + u * (double(i) / double(nu)) + v * (double(j) / double(nv)));
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
    Vec3d boxLo_, boxHi_;
    float boxLoF_[3], boxHiF_[3];
    Vec3d origin_;
    double lineTol_ = 0, gridPad_ = 0, delta_ = 0, planeTol_ = 0;
    std::vector<TriTest> tris_;
    std::vector<std::array<Vec3d, 3>> verts_; ///< corners of tris_[i], local frame
    TriangleGrid grid_;
};

} // namespace

std::unique_ptr<Container> makeContainer(const ContainerParams& params, const std::string& where) {
    auto ordered = [](const Vec3d& lo, const Vec3d& hi) {
        return lo.allFinite() && hi.allFinite() && (lo.array() < hi.array()).all();
    };
    switch (params.type) {
    case ContainerParams::Type::None:
        return std::make_unique<NoneContainer>();
    case ContainerParams::Type::Box:
        if (!ordered(params.min, params.max))
            throw SceneError(where + ": container: max must exceed min on every axis");
        return std::make_unique<BoxContainer>(params.min, params.max, params.closedTop);
    case ContainerParams::Type::Dish:
        if (!(params.radius > 0 && std::isfinite(params.radius)))
            throw SceneError(where + ": container.radius: must be > 0");
        if (!(params.height > 0 && std::isfinite(params.height)))
            throw SceneError(where + ": container.height: must be > 0");
        if (!params.center.allFinite()) throw SceneError(where + ": container.center: must be finite");
        return std::make_unique<DishContainer>(params.center, params.radius, params.height);
    case ContainerParams::Type::Mesh: {
        if (!(params.meshScale > 0 && std::isfinite(params.meshScale)))
            throw SceneError(where + ": container.scale: must be > 0");
        if (params.hasBounds && !ordered(params.boundsMin, params.boundsMax))
            throw SceneError(where + ": container.bounds: max must exceed min on every axis");
        return std::make_unique<MeshContainer>(loadMesh(params, where), params);
    }
    }
    throw SceneError(where + ": container: unknown type");
}

} // namespace ferro

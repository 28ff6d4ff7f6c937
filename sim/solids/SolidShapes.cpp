#include "sim/solids/SolidShapes.hpp"

#include "sim/core/Constants.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

namespace ferro {

namespace {

uint64_t edgeKey(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }

// Points of a ring of `n` at radius r and height z, starting at angle phase * 2 pi / n.
void addRing(ShapeMesh& m, int n, double r, double z, double phase) {
    for (int k = 0; k < n; ++k) {
        const double a = 2.0 * kPi * (k + phase) / n;
        m.vertices.emplace_back(r * std::cos(a), r * std::sin(a), z);
    }
}

// A flat disc cap of radius r at height z: rings `rings` deep from the rim (its first vertex
// `rim`, n points, n even) inward to a centre point, facing +z (up) or -z. Mirror-symmetric
// about every plane through the axis and a rim vertex of even index: rings keep the rim's
// count or halve it (each inner point at the angle of every other outer one), quads between
// equal rings split by alternating diagonals, and a fan closes the centre. A triangulation
// that leans one way round the axis has a handedness, and so does its charge's field: a
// pool over a cored coil whose caps were stitched by angle turned at a few mm/s in 0.25 s.
void addCap(ShapeMesh& m, uint32_t rim, int n, double r, double z, int rings, bool up) {
    auto push = [&](uint32_t a, uint32_t b, uint32_t c) {
        // (a, b, c) counter-clockwise seen from +z; a lower cap faces -z.
        m.triangles.push_back(up ? std::array<uint32_t, 3>{a, b, c} : std::array<uint32_t, 3>{a, c, b});
    };
    uint32_t outer = rim;
    int outerN = n;
    for (int ring = rings - 1; ring >= 0; --ring) {
        const uint32_t inner = uint32_t(m.vertices.size());
        if (ring == 0) {
            m.vertices.emplace_back(0, 0, z);
            for (int i = 0; i < outerN; ++i) push(outer + uint32_t(i), outer + uint32_t((i + 1) % outerN), inner);
            return;
        }
        const double target = double(n) * ring / rings;
        const bool halve = outerN % 2 == 0 && outerN / 2 >= 4 && double(outerN / 2) >= target;
        const int innerN = halve ? outerN / 2 : outerN;
        addRing(m, innerN, r * ring / rings, z, 0.0);
        auto o = [&](int i) { return outer + uint32_t(i % outerN); };
        auto in = [&](int j) { return inner + uint32_t(j % innerN); };
        for (int j = 0; j < innerN; ++j) {
            if (halve) {
                // Outer 2j, 2j+1, 2j+2 over inner j, j+1: symmetric about outer 2j+1.
                push(o(2 * j), o(2 * j + 1), in(j));
                push(o(2 * j + 1), o(2 * j + 2), in(j + 1));
                push(in(j), o(2 * j + 1), in(j + 1));
            } else if (j % 2 == 0) {
                push(o(j), o(j + 1), in(j + 1));
                push(o(j), in(j + 1), in(j));
            } else {
                push(o(j), o(j + 1), in(j));
                push(o(j + 1), in(j + 1), in(j));
            }
        }
        outer = inner;
        outerN = innerN;
    }
}

// A surface of revolution about z through the profile points (r_k, z_k) from bottom to top,
// closed by flat caps where r > 0 at the ends. `n` points a ring.
ShapeMesh revolve(const std::vector<std::pair<double, double>>& profile, int n, double edge) {
    ShapeMesh m;
    std::vector<uint32_t> ringStart;
    for (const auto& [r, z] : profile) {
        ringStart.push_back(uint32_t(m.vertices.size()));
        if (r > 0)
            addRing(m, n, r, z, 0.0);
        else
            m.vertices.emplace_back(0, 0, z);
    }
    for (size_t k = 0; k + 1 < profile.size(); ++k) {
        const uint32_t lo = ringStart[k], hi = ringStart[k + 1];
        const bool loPoint = profile[k].first <= 0, hiPoint = profile[k + 1].first <= 0;
        for (int s = 0; s < n; ++s) {
            const uint32_t s1 = uint32_t((s + 1) % n);
            // Side quads, outward: (lo s, lo s+1, hi s+1) and (lo s, hi s+1, hi s).
            if (!loPoint && !hiPoint) {
                // Alternating diagonals (n even): no handedness (see addCap).
                if ((s + int(k)) % 2 == 0) {
                    m.triangles.push_back({lo + uint32_t(s), lo + s1, hi + s1});
                    m.triangles.push_back({lo + uint32_t(s), hi + s1, hi + uint32_t(s)});
                } else {
                    m.triangles.push_back({lo + uint32_t(s), lo + s1, hi + uint32_t(s)});
                    m.triangles.push_back({lo + s1, hi + s1, hi + uint32_t(s)});
                }
            } else if (hiPoint && !loPoint) {
                m.triangles.push_back({lo + uint32_t(s), lo + s1, hi});
            } else if (loPoint && !hiPoint) {
                m.triangles.push_back({lo, hi + s1, hi + uint32_t(s)});
            }
        }
    }
    auto capRings = [&](double r) { return std::max(1, int(std::ceil(r / edge))); };
    if (profile.front().first > 0) addCap(m, ringStart.front(), n, profile.front().first, profile.front().second, capRings(profile.front().first), false);
    if (profile.back().first > 0) addCap(m, ringStart.back(), n, profile.back().first, profile.back().second, capRings(profile.back().first), true);
    return m;
}

// Even, for the mirror symmetry of the alternating diagonals.
int ringCount(double radius, double edge) {
    const int n = std::max(8, int(std::ceil(2.0 * kPi * radius / edge)));
    return n + n % 2;
}

} // namespace

ShapeMesh makeSphere(double radius, double edge) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    ShapeMesh m;
    m.vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                  {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                   {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                   {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (Vec3d& v : m.vertices) v = radius * v.normalized();
    auto longest = [&] {
        double e = 0;
        for (const auto& tr : m.triangles)
            for (int k = 0; k < 3; ++k) e = std::max(e, (m.vertices[tr[k]] - m.vertices[tr[(k + 1) % 3]]).norm());
        return e;
    };
    while (longest() > edge && m.triangles.size() < 20u * (1u << 20)) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            const uint32_t idx = uint32_t(m.vertices.size());
            m.vertices.push_back(radius * (m.vertices[a] + m.vertices[b]).normalized());
            mid.emplace(key, idx);
            return idx;
        };
        std::vector<std::array<uint32_t, 3>> next;
        next.reserve(4 * m.triangles.size());
        for (const auto& tr : m.triangles) {
            const uint32_t a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]), c = midpoint(tr[2], tr[0]);
            next.push_back({tr[0], a, c});
            next.push_back({tr[1], b, a});
            next.push_back({tr[2], c, b});
            next.push_back({a, b, c});
        }
        m.triangles = std::move(next);
    }
    return m;
}

ShapeMesh makeCylinder(double radius, double height, double edge) {
    const int n = ringCount(radius, edge);
    const int rows = std::max(1, int(std::ceil(height / edge)));
    std::vector<std::pair<double, double>> profile;
    for (int k = 0; k <= rows; ++k) profile.emplace_back(radius, height * k / rows);
    return revolve(profile, n, edge);
}

ShapeMesh makeCone(double radius, double tipRadius, double height, double edge) {
    const int n = ringCount(radius, edge);
    const double slant = std::hypot(radius - tipRadius, height);
    const int rows = std::max(1, int(std::ceil(slant / edge)));
    std::vector<std::pair<double, double>> profile;
    for (int k = 0; k <= rows; ++k) {
        const double f = double(k) / rows;
        profile.emplace_back(radius + (tipRadius - radius) * f, height * f);
    }
    if (tipRadius <= 0) profile.back().first = 0;
    return revolve(profile, n, edge);
}

ClosedCheck checkClosed(const ShapeMesh& mesh) {
    std::unordered_map<uint64_t, int> directed;
    for (const auto& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) ++directed[edgeKey(t[k], t[(k + 1) % 3])];
    ClosedCheck c;
    for (const auto& [key, count] : directed) {
        const uint32_t a = uint32_t(key >> 32), b = uint32_t(key & 0xffffffffu);
        if (count > 1) ++c.flippedEdges;
        const auto back = directed.find(edgeKey(b, a));
        const int other = back == directed.end() ? 0 : back->second;
        if (a < b || other == 0) {
            const int total = count + other;
            if (total == 1) ++c.openEdges;
            else if (total > 2) ++c.crowdedEdges;
        }
    }
    return c;
}

void weldVertices(ShapeMesh& mesh) {
    std::map<std::array<double, 3>, uint32_t> index;
    std::vector<Vec3d> verts;
    std::vector<uint32_t> merged(mesh.vertices.size());
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        Vec3d q = mesh.vertices[i];
        q.array() += 0.0; // -0.0 -> +0.0
        auto [it, added] = index.emplace(std::array<double, 3>{q.x(), q.y(), q.z()}, uint32_t(verts.size()));
        if (added) verts.push_back(q);
        merged[i] = it->second;
    }
    std::vector<std::array<uint32_t, 3>> tris;
    for (const auto& t : mesh.triangles) {
        const std::array<uint32_t, 3> m{merged[t[0]], merged[t[1]], merged[t[2]]};
        if (m[0] != m[1] && m[1] != m[2] && m[0] != m[2]) tris.push_back(m);
    }
    mesh.vertices = std::move(verts);
    mesh.triangles = std::move(tris);
}

double signedVolume(const ShapeMesh& mesh) {
    double v = 0;
    for (const auto& t : mesh.triangles)
        v += mesh.vertices[t[0]].dot(mesh.vertices[t[1]].cross(mesh.vertices[t[2]]));
    return v / 6.0;
}

} // namespace ferro

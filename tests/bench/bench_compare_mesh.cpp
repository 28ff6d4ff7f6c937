// bench-compare-mesh: how far mesh A lies from a reference mesh B, for the accuracy columns of
// scripts/bench/ (surface voxel size, spike refinement): distances from every vertex of one mesh
// to the nearest point of the other's triangles (CGAL AABB tree, exact point-triangle
// distances), both ways, plus each mesh's enclosed volume, highest point and triangle count.
//
//   bench-compare-mesh A.ply B.ply [--above Z]
//
// Prints one line of key=value pairs (SI units):
//   mean_m max_m            symmetric: mean over the vertices of both meshes, max of both ways
//   mean_a_to_b_m max_a_to_b_m mean_b_to_a_m max_b_to_a_m
//   volume_a_m3 volume_b_m3 top_a_m top_b_m triangles_a triangles_b
// With --above Z, also mean_above_m and max_above_m: the same symmetric distances over only the
// vertices higher than Z (the spike tips), and vertices_above_a/_b.
// Exit codes: 4 a mesh file is missing, 2 a mesh is unreadable or empty or the options are wrong.
#include "sim/core/ExitCodes.hpp"
#include "sim/core/TriangleMesh.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using namespace ferro;

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

struct Distances {
    double sum = 0, max = 0, sumAbove = 0, maxAbove = 0;
    size_t count = 0, countAbove = 0;
};

// Distances from every vertex of `from` to the triangles of `to`.
Distances distancesTo(const TriangleMesh& from, const TriangleMesh& to, double above) {
    std::vector<Triangle> triangles;
    triangles.reserve(to.triangles.size());
    for (const auto& t : to.triangles) {
        auto p = [&](uint32_t i) { return Point(to.vertices[i].x(), to.vertices[i].y(), to.vertices[i].z()); };
        const Triangle tri(p(t[0]), p(t[1]), p(t[2]));
        if (!tri.is_degenerate()) triangles.push_back(tri);
    }
    Tree tree(triangles.begin(), triangles.end());
    tree.accelerate_distance_queries();
    Distances d;
    for (const Vec3& v : from.vertices) {
        const double dist = std::sqrt(tree.squared_distance(Point(v.x(), v.y(), v.z())));
        d.sum += dist;
        d.max = std::max(d.max, dist);
        ++d.count;
        if (v.z() > above) {
            d.sumAbove += dist;
            d.maxAbove = std::max(d.maxAbove, dist);
            ++d.countAbove;
        }
    }
    return d;
}

double top(const TriangleMesh& m) {
    double z = -std::numeric_limits<double>::infinity();
    for (const Vec3& v : m.vertices) z = std::max(z, double(v.z()));
    return z;
}

} // namespace

int main(int argc, char** argv) {
    std::vector<std::string> files;
    double above = std::numeric_limits<double>::infinity();
    bool haveAbove = false;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--above") && i + 1 < argc) {
            char* end = nullptr;
            above = std::strtod(argv[++i], &end);
            if (*end || !std::isfinite(above)) {
                std::fprintf(stderr, "bench-compare-mesh: error: --above needs a height in metres (got '%s')\n", argv[i]);
                return kExitBadInput;
            }
            haveAbove = true;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            std::fprintf(stderr, "bench-compare-mesh: error: unknown option %s (usage: bench-compare-mesh A.ply B.ply [--above Z])\n", argv[i]);
            return kExitBadInput;
        } else {
            files.push_back(argv[i]);
        }
    }
    if (files.size() != 2) {
        std::fprintf(stderr, "bench-compare-mesh: error: usage: bench-compare-mesh A.ply B.ply [--above Z]\n");
        return kExitBadInput;
    }
    try {
        const TriangleMesh a = readMesh(files[0]);
        const TriangleMesh b = readMesh(files[1]);
        for (size_t k = 0; k < 2; ++k)
            if ((k ? b : a).empty()) {
                std::fprintf(stderr, "bench-compare-mesh: error: %s: no triangles\n", files[k].c_str());
                return kExitBadInput;
            }
        const Distances ab = distancesTo(a, b, above);
        const Distances ba = distancesTo(b, a, above);
        std::printf("mean_m=%.6g max_m=%.6g mean_a_to_b_m=%.6g max_a_to_b_m=%.6g mean_b_to_a_m=%.6g max_b_to_a_m=%.6g "
                    "volume_a_m3=%.6g volume_b_m3=%.6g top_a_m=%.6g top_b_m=%.6g triangles_a=%zu triangles_b=%zu",
                    (ab.sum + ba.sum) / double(ab.count + ba.count), std::max(ab.max, ba.max), ab.sum / ab.count, ab.max,
                    ba.sum / ba.count, ba.max, enclosedVolume(a), enclosedVolume(b), top(a), top(b), a.triangles.size(),
                    b.triangles.size());
        if (haveAbove) {
            const size_t n = ab.countAbove + ba.countAbove;
            std::printf(" mean_above_m=%.6g max_above_m=%.6g vertices_above_a=%zu vertices_above_b=%zu",
                        n ? (ab.sumAbove + ba.sumAbove) / double(n) : 0.0, std::max(ab.maxAbove, ba.maxAbove),
                        ab.countAbove, ba.countAbove);
        }
        std::printf("\n");
    } catch (const StageError& e) {
        std::fprintf(stderr, "bench-compare-mesh: error: %s\n", e.what());
        return e.code();
    }
    return kExitOk;
}

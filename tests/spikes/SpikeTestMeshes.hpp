#pragma once
// Test and benchmark inputs for ferro-spikes: closed fluid bodies built directly, so the spike
// tests do not depend on ferro-surface.
#include "sim/core/TriangleMesh.hpp"
#include "sim/core/Constants.hpp"
#include "spikes/SpikeFrames.hpp"

#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace ferro::spiketest {

/// The scene text of the spike tests' dish: radius R [m], 3 cm deep, a 1 cm layer of oil-based
/// ferrofluid (rest density 1200, chi0 1.5, Ms 35 kA/m, sigma 0.025 N/m), then `extra` TOML
/// (the magnets, [spikes], ...).
inline std::string dishScene(double R, const std::string& extra)
{
    std::ostringstream s;
    s << "[fluid]\nrest_density = 1200.0\nviscosity = 5e-6\nsurface_tension = 0.025\n"
      << "[[fluid.block]]\nshape = \"cylinder\"\ncenter = [0.0, 0.0, 0.0]\nradius = " << 0.99 * R
      << "\nheight = 0.01\ncount = 2000\n"
      << "[container]\ntype = \"dish\"\ncenter = [0.0, 0.0, 0.0]\nradius = " << R << "\nheight = 0.03\n"
      << "[magnetization]\nsusceptibility = 1.5\nsaturation = 35000.0\n"
      << extra;
    return s.str();
}

/// The scene text of one uniform vertical field H [A/m].
inline std::string uniformField(double H)
{
    std::ostringstream s;
    s << "[[magnets]]\nkind = \"uniform\"\ndirection = [0.0, 0.0, 1.0]\nfield = " << H << "\n";
    return s.str();
}

/// ferro-spikes' input for `mesh` in scene `sc` at time t [s] (the magnets there), no particles.
inline SpikeInput frameInput(const SpikeScene& sc, const TriangleMesh& mesh, double time = 0.0)
{
    SpikeInput in;
    in.surface = mesh;
    in.fluid = sc.fluid;
    for (const MagnetTrack& t : sc.magnets) in.magnets.push_back(t.at(time));
    return in;
}

/// A closed cylinder of fluid ("a dish's pool"): floor at z = 0, axis +z through `center`,
/// radius R, top at z = height(r, angle). Top and floor are concentric rings ring_k of 6k
/// vertices (k = 0..rings; a near-uniform triangulation with 6-fold symmetry), the side one
/// band of quads. Triangles are counter-clockwise seen from outside.
inline TriangleMesh makePool(double R, int rings, const std::function<double(double, double)>& height,
                             const Vec3d& center = Vec3d::Zero())
{
    const double pi = kPi;
    TriangleMesh mesh;
    auto ringStart = [](int k) { return k == 0 ? 0 : 1 + 3 * k * (k - 1); }; // first vertex of ring k
    const int perDisc = 1 + 3 * rings * (rings + 1);
    for (int disc = 0; disc < 2; ++disc)
        for (int k = 0; k <= rings; ++k) {
            const int n = k == 0 ? 1 : 6 * k;
            const double r = R * k / rings;
            for (int i = 0; i < n; ++i) {
                const double a = 2 * pi * i / n;
                const double z = disc == 0 ? height(r, a) : 0.0;
                mesh.vertices.emplace_back(float(center.x() + r * std::cos(a)), float(center.y() + r * std::sin(a)),
                                           float(center.z() + z));
            }
        }
    auto add = [&](int disc, uint32_t a, uint32_t b, uint32_t c) {
        const uint32_t o = uint32_t(disc * perDisc);
        if (disc == 0)
            mesh.triangles.push_back({o + a, o + b, o + c});
        else
            mesh.triangles.push_back({o + a, o + c, o + b});
    };
    for (int disc = 0; disc < 2; ++disc)
        for (int k = 0; k < rings; ++k) {
            const int na = k == 0 ? 1 : 6 * k, nb = 6 * (k + 1);
            const uint32_t sa = uint32_t(ringStart(k)), sb = uint32_t(ringStart(k + 1));
            int i = 0, j = 0;
            while (i < (k == 0 ? 0 : na) || j < nb) {
                const double nextA = k == 0 ? 1e9 : double(i + 1) / na, nextB = double(j + 1) / nb;
                const uint32_t ai = sa + uint32_t(i % na), bj = sb + uint32_t(j % nb);
                if (nextB <= nextA && j < nb) {
                    add(disc, ai, bj, sb + uint32_t((j + 1) % nb));
                    ++j;
                } else {
                    add(disc, ai, bj, sa + uint32_t((i + 1) % na));
                    ++i;
                }
            }
        }
    const int n = 6 * rings;
    const uint32_t top = uint32_t(ringStart(rings)), bottom = uint32_t(perDisc + ringStart(rings));
    for (int i = 0; i < n; ++i) {
        const uint32_t t0 = top + uint32_t(i), t1 = top + uint32_t((i + 1) % n);
        const uint32_t b0 = bottom + uint32_t(i), b1 = bottom + uint32_t((i + 1) % n);
        mesh.triangles.push_back({t0, b0, b1});
        mesh.triangles.push_back({t0, b1, t1});
    }
    computeVertexNormals(mesh);
    return mesh;
}

/// A coat of fluid on an upright cylinder (a solid standing on z = 0, axis +z through the
/// origin): the closed tube between radii Ri and Ro from z = 0 to z = height, its outer wall
/// nTheta x nZ quads, its inner wall the same, the top and bottom annuli `rings` bands each.
/// `bump(theta, z)` [m] is added to the outer radius (0: a smooth coat). Triangles are
/// counter-clockwise seen from outside the fluid.
inline TriangleMesh makeCoat(double Ri, double Ro, double height, int nTheta, int nZ, int rings,
                             const std::function<double(double, double)>& bump = {})
{
    TriangleMesh mesh;
    // A grid of (nTheta) x (rows) vertices round a closed loop of rows: up the outer wall, in
    // across the top, down the inner wall, out across the bottom.
    std::vector<std::pair<double, double>> rows; // (radius, z) of each row; outer radius rows flagged by r == Ro
    for (int k = 0; k < nZ; ++k) rows.push_back({Ro, height * k / nZ});
    for (int k = 0; k < rings; ++k) rows.push_back({Ro - (Ro - Ri) * k / rings, height});
    for (int k = 0; k < nZ; ++k) rows.push_back({Ri, height - height * k / nZ});
    for (int k = 0; k < rings; ++k) rows.push_back({Ri + (Ro - Ri) * k / rings, 0.0});
    const int nRows = int(rows.size());
    for (int r = 0; r < nRows; ++r)
        for (int i = 0; i < nTheta; ++i) {
            const double a = 2 * kPi * i / nTheta;
            double radius = rows[size_t(r)].first;
            const double z = rows[size_t(r)].second;
            if (bump && r < nZ && r > 0) radius += bump(a, z);
            mesh.vertices.emplace_back(float(radius * std::cos(a)), float(radius * std::sin(a)), float(z));
        }
    auto at = [&](int r, int i) { return uint32_t(((r + nRows) % nRows) * nTheta + (i + nTheta) % nTheta); };
    for (int r = 0; r < nRows; ++r)
        for (int i = 0; i < nTheta; ++i) {
            // Up the outer wall with theta growing: (r, i) -> (r, i + 1) -> (r + 1, i + 1) is
            // counter-clockwise seen from outside.
            mesh.triangles.push_back({at(r, i), at(r, i + 1), at(r + 1, i + 1)});
            mesh.triangles.push_back({at(r, i), at(r + 1, i + 1), at(r + 1, i)});
        }
    computeVertexNormals(mesh);
    return mesh;
}

/// A flat pool of depth h.
inline TriangleMesh makeFlatPool(double R, double h, int rings)
{
    return makePool(R, rings, [h](double, double) { return h; });
}

} // namespace ferro::spiketest

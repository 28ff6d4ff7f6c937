#pragma once
// Checks shared by the spike tests: a spike's axis measured on the output mesh, angles, and
// the spiky mesh's health (closed, no self-intersection, the volume kept).
#include "sim/core/Constants.hpp"
#include "spikes/SpikeMapper.hpp"
#include "spikes/SurfaceGeometry.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace ferro::spiketest {

// The spike's axis measured on the output mesh: from the area-weighted centroid of its flank
// (vertices raised 15-60 % of the apex's rise along the tip direction; troughs sink and are
// left out; weighted by their undisplaced area, as a leaning spike stretches one side) to its
// apex vertex. Vertices belong to the spike if their undisplaced position is
// within 0.45 l of the tip's base (the troughs' centres are 0.577 l away).
inline Vec3d measuredAxis(const SpikeResult& res, const SpikeTip& tip, double l)
{
    std::vector<double> area(res.refined.vertices.size(), 0.0);
    for (const auto& t : res.refined.triangles) { // undisplaced areas: the same weight either side
        const Vec3d a = res.refined.vertices[t[0]].cast<double>(), b = res.refined.vertices[t[1]].cast<double>(),
                    c = res.refined.vertices[t[2]].cast<double>();
        for (uint32_t v : t) area[v] += (b - a).cross(c - a).norm() / 6;
    }
    auto rise = [&](size_t v) {
        return (res.mesh.vertices[v] - res.refined.vertices[v]).cast<double>().dot(tip.direction);
    };
    double best = -1;
    size_t apex = 0;
    std::vector<size_t> near;
    for (size_t v = 0; v < res.refined.vertices.size(); ++v) {
        if ((res.refined.vertices[v].cast<double>() - tip.base).norm() > 0.45 * l) continue;
        near.push_back(v);
        if (rise(v) > best) best = rise(v), apex = v;
    }
    Vec3d sum = Vec3d::Zero();
    double weight = 0;
    int count = 0;
    for (size_t v : near)
        if (rise(v) >= 0.15 * best && rise(v) <= 0.6 * best)
            sum += area[v] * res.mesh.vertices[v].cast<double>(), weight += area[v], ++count;
    REQUIRE(count >= 12);
    return (res.mesh.vertices[apex].cast<double>() - sum / weight).normalized();
}

inline double angleDegrees(const Vec3d& a, const Vec3d& b)
{
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / kPi;
}

inline void requireHealthy(const SpikeResult& res)
{
    const MeshHealth health = checkMeshHealth(res.mesh);
    REQUIRE(health.loadable);
    REQUIRE(health.closed);
    REQUIRE_FALSE(health.selfIntersecting);
    REQUIRE(std::abs(res.volumeOut - res.volumeIn) <= 0.005 * res.volumeIn);
    REQUIRE(std::abs(enclosedVolume(res.mesh) - res.volumeIn) <= 0.005 * res.volumeIn);
}

} // namespace ferro::spiketest

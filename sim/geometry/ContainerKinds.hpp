#pragma once
// Internal to sim/geometry: the container kinds' factories (one file each) and the float
// clamps they share. Container.cpp's makeContainer checks the parameters and picks one.
#include "sim/geometry/Container.hpp"

#include <algorithm>
#include <array>
#include <vector>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace ferro {
namespace container_detail {

std::unique_ptr<Container> makeNoneContainer();
std::unique_ptr<Container> makeBoxContainer(const Vec3d& lo, const Vec3d& hi, bool closedTop,
                                            bool periodicSides = false);
std::unique_ptr<Container> makeDishContainer(const Vec3d& center, double radius, double height);
/// Throws SceneError (prefixed with `where`) for an unreadable, open or empty mesh.
std::unique_ptr<Container> makeMeshContainer(const ContainerParams& params, const std::string& where);
/// A closed, outward mesh the fluid stays outside of (makeContainerWithSolids).
std::unique_ptr<Container> makeMeshObstacle(const std::vector<Vec3d>& vertices,
                                            const std::vector<std::array<uint32_t, 3>>& triangles);

/// Bounds of a container without walls [m].
constexpr double kHuge = 1e30;

/// The float closest to `lo` that is not below it. Clamping float coordinates to these
/// (and to inwardHi) keeps them inside the double-precision bounds, so a clamped point
/// passes contains(p, 0) exactly.
inline float inwardLo(double lo) {
    float f = static_cast<float>(lo);
    if (static_cast<double>(f) < lo) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

inline float inwardHi(double hi) {
    float f = static_cast<float>(hi);
    if (static_cast<double>(f) > hi) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
}

/// Clamps one coordinate into [lo, hi] and stops the velocity that pushed it out.
inline bool clampAxis(float& x, float& v, float lo, float hi) {
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
inline bool parkIfNonFinite(const Vec3& xOld, Vec3& x, Vec3& v) {
    if (x.allFinite()) return false;
    x = xOld;
    v.setZero();
    return true;
}

inline void checkSpacing(double spacing) {
    if (!(spacing > 0) || !std::isfinite(spacing))
        throw std::invalid_argument("Container::sampleWalls: spacing must be > 0");
}

inline long intervals(double length, double spacing) {
    return std::max(1L, std::lround(length / spacing));
}

inline Vec3 toVec3(const Vec3d& p) { return p.cast<Real>(); }

/// Rounds to float through a volatile, so that code re-testing a corrected position sees
/// exactly the float that is stored. A plain cast is not enough: GCC 12.2's SLP vectorizer
/// (-O2 and up) was seen to drop a double -> float -> double round trip entirely.
inline Vec3 toStoredVec3(const Vec3d& p) {
    volatile Real f[3] = {Real(p.x()), Real(p.y()), Real(p.z())};
    const Real x = f[0], y = f[1], z = f[2];
    return Vec3(x, y, z);
}

} // namespace container_detail
} // namespace ferro

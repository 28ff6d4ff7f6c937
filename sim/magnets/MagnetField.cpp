#include "sim/magnets/MagnetField.hpp"
#include "sim/magnets/MagnetKinds.hpp"

#include "sim/core/Constants.hpp"
#include "sim/core/Keyframes.hpp"

#include <Eigen/Geometry> // cross, unitOrthogonal

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

namespace {

// Unit axis of a magnet; false for a zero (or non-finite) direction, which has no axis.
bool unitAxis(const Vec3d& direction, Vec3d& n) {
    const double len = direction.norm();
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    n = direction / len;
    return true;
}

} // namespace

Vec3d magnetField(const Magnet& mag, const Vec3d& x) {
    Vec3d n;
    if (!unitAxis(mag.direction, n)) return Vec3d::Zero();
    return magnetKindInfo(mag.kind).field(mag, n, x);
}

Vec3d magnetField(const std::vector<Magnet>& magnets, const Vec3d& x) {
    Vec3d H = Vec3d::Zero();
    for (const Magnet& m : magnets) H += magnetField(m, x);
    return H;
}

Mat3d fieldGradient(const Magnet& mag, const Vec3d& x) {
    Vec3d n;
    if (!unitAxis(mag.direction, n)) return Mat3d::Zero();
    return magnetKindInfo(mag.kind).gradient(mag, n, x);
}

Mat3d fieldGradient(const std::vector<Magnet>& magnets, const Vec3d& x) {
    Mat3d J = Mat3d::Zero();
    for (const Magnet& m : magnets) J += fieldGradient(m, x);
    return J;
}

// ---------------------------------------------------------------------------------------
// Keyframe interpolation

namespace {

// Catmull-Rom tangent at key j for uneven spacing: central difference over the two
// neighbours, one-sided at the ends. Coincident key times degrade to a zero tangent.
Vec3d positionTangent(const std::vector<MagnetKeyframe>& k, size_t j) {
    const size_t lo = j == 0 ? 0 : j - 1;
    const size_t hi = std::min(j + 1, k.size() - 1);
    const double dt = k[hi].time - k[lo].time;
    if (!(dt > 0.0)) return Vec3d::Zero();
    return (k[hi].position - k[lo].position) / dt;
}

// The strength channel's monotone tangent (sim/core/Keyframes.hpp): a strength keyed up and
// down never overshoots its keys.
double strengthTangent(const std::vector<MagnetKeyframe>& k, size_t j) {
    return monotoneTangent(k, j, [](const MagnetKeyframe& key) { return key.strength; });
}

// Slerp between unit vectors a and b. Antiparallel keys have no unique great circle; any
// perpendicular axis gives a valid (unit, continuous in u) rotation.
Vec3d slerp(const Vec3d& a, const Vec3d& b, double u) {
    const double c = std::clamp(a.dot(b), -1.0, 1.0);
    const double theta = std::acos(c);
    if (theta < 1e-9) return ((1 - u) * a + u * b).normalized();
    Vec3d perp = b - c * a;
    if (perp.norm() < 1e-12) perp = a.unitOrthogonal();
    perp.normalize();
    return std::cos(theta * u) * a + std::sin(theta * u) * perp;
}

Vec3d keyDirection(const MagnetKeyframe& k, const Vec3d& fallback) {
    Vec3d n;
    return unitAxis(k.direction, n) ? n : fallback;
}

} // namespace

Magnet MagnetTrack::at(double t) const {
    Magnet m = base;
    if (keys.empty()) return m;
    Vec3d baseDir;
    if (!unitAxis(base.direction, baseDir)) baseDir = Vec3d::UnitZ();

    auto apply = [&](const MagnetKeyframe& k) {
        m.position = k.position;
        m.direction = keyDirection(k, baseDir);
        m.strength = k.strength;
        return m;
    };
    if (keys.size() == 1 || !(t > keys.front().time)) return apply(keys.front());
    if (t >= keys.back().time) return apply(keys.back());

    // Segment i with keys[i].time <= t < keys[i+1].time.
    const size_t i = keySegment(keys, t);
    const MagnetKeyframe& k0 = keys[i];
    const MagnetKeyframe& k1 = keys[i + 1];
    const double dt = k1.time - k0.time;
    if (!(dt > 0.0)) return apply(k1);
    const double u = (t - k0.time) / dt;

    m.position = hermite<Vec3d>(k0.position, k1.position, positionTangent(keys, i),
                                positionTangent(keys, i + 1), dt, u);
    m.strength = hermite<double>(k0.strength, k1.strength, strengthTangent(keys, i),
                                 strengthTangent(keys, i + 1), dt, u);
    m.direction = slerp(keyDirection(k0, baseDir), keyDirection(k1, baseDir), u);
    return m;
}

} // namespace ferro

#include "sim/sph/MagnetObstacles.hpp"

#include "sim/magnets/MagnetKinds.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace ferro {

namespace {

Vec3d unitOr(const Vec3d& d, const Vec3d& fallback) {
    const double n = d.norm();
    return n > 0 ? Vec3d(d / n) : fallback;
}

/// A unit vector perpendicular to n.
Vec3d perpendicular(const Vec3d& n) {
    return unitOr(std::abs(n.x()) < 0.9 ? n.cross(Vec3d::UnitX()) : n.cross(Vec3d::UnitY()), Vec3d::UnitX());
}

} // namespace

std::vector<MagnetObstacle> magnetObstacles(const std::vector<MagnetTrack>& tracks, double t1, double dt,
                                            double clearance, double maxSpeed) {
    std::vector<MagnetObstacle> out;
    for (const MagnetTrack& track : tracks) {
        const Magnet m = track.at(t1);
        const MagnetKindInfo& kind = magnetKindInfo(m.kind);
        if (kind.core == MagnetCore::None) continue;
        const double body = kind.bodyRadius(m.strength);
        // A coil's winding stands whatever its current; the other bodies carry their strength.
        if (!(body > 0) && kind.core != MagnetCore::Tube) continue;
        MagnetObstacle o;
        o.axis = unitOr(m.direction, Vec3d::UnitZ());
        o.radius = body + clearance;
        o.a = o.b = m.position;
        double reach = o.radius;
        if (kind.core == MagnetCore::Segment) {
            o.a = m.position - 0.5 * m.length * o.axis;
            o.b = m.position + 0.5 * m.length * o.axis;
            reach += 0.5 * m.length;
        } else if (kind.core == MagnetCore::Ring) {
            o.ringRadius = m.radius;
            reach += m.radius;
        } else if (kind.core == MagnetCore::Tube) {
            o.ringRadius = m.radius;
            o.halfLength = 0.5 * m.length;
            reach += m.radius + 0.5 * m.length;
        }
        if (dt > 0 && !track.keys.empty()) {
            const double h = 1e-3 * dt;
            const Vec3d u = (m.position - track.at(t1 - h).position) / h;
            const double s = u.norm();
            o.velocity = s > maxSpeed ? Vec3d(u * (maxSpeed / s)) : u;
        }
        o.lo = (m.position - Vec3d::Constant(reach)).cast<Real>();
        o.hi = (m.position + Vec3d::Constant(reach)).cast<Real>();
        out.push_back(o);
    }
    return out;
}

namespace {

/// The closest point of the body's core (segment, circle or cylinder) to p.
Vec3d closestCore(const MagnetObstacle& body, const Vec3d& p) {
    if (body.ringRadius > 0) {
        const Vec3d d = p - body.a;
        const double z = d.dot(body.axis);
        const Vec3d inPlane = d - z * body.axis;
        return body.a + std::clamp(z, -body.halfLength, body.halfLength) * body.axis +
               body.ringRadius * unitOr(inPlane, perpendicular(body.axis));
    }
    const Vec3d s = body.b - body.a;
    const double len2 = s.squaredNorm();
    const double f = len2 > 0 ? std::clamp((p - body.a).dot(s) / len2, 0.0, 1.0) : 0.0;
    return body.a + f * s;
}

} // namespace

bool isInside(const MagnetObstacle& body, const Vec3d& p) {
    return (p - closestCore(body, p)).norm() < body.radius;
}

bool keepOutside(const MagnetObstacle& body, Vec3& x, Vec3& v) {
    if ((x.array() < body.lo.array()).any() || (x.array() > body.hi.array()).any()) return false;
    const Vec3d p = x.cast<double>();
    const Vec3d core = closestCore(body, p);
    const Vec3d r = p - core;
    const double dist = r.norm();
    if (dist >= body.radius) return false;
    // At the core itself any direction is out: take the axis (a loop's axis is
    // perpendicular to its wire).
    const Vec3d n = dist > 0 ? Vec3d(r / dist) : body.axis;
    x = (core + body.radius * n).cast<Real>();
    // Float rounding may leave the rounded point a hair inside; nudge it out.
    if ((x.cast<double>() - core).norm() < body.radius) x = (core + body.radius * (1 + 1e-6) * n).cast<Real>();
    const Vec3d vd = v.cast<double>();
    const double into = (vd - body.velocity).dot(n);
    if (into < 0) v = (vd - into * n).cast<Real>();
    return true;
}

bool stopMotionInto(const MagnetObstacle& body, const Vec3& x, Vec3& v, double dt) {
    const Vec3 next = x + Real(dt) * v;
    const Vec3 lo = x.cwiseMin(next), hi = x.cwiseMax(next);
    if ((hi.array() < body.lo.array()).any() || (lo.array() > body.hi.array()).any()) return false;
    const Vec3d pn = next.cast<double>();
    if ((pn - closestCore(body, pn)).norm() >= body.radius) return false;
    const Vec3d p = x.cast<double>();
    const Vec3d r = p - closestCore(body, p);
    const double dist = r.norm();
    const Vec3d n = dist > 0 ? Vec3d(r / dist) : body.axis;
    const Vec3d vd = v.cast<double>();
    const double into = (vd - body.velocity).dot(n);
    if (!(into < 0)) return false;
    v = (vd - into * n).cast<Real>();
    return true;
}

} // namespace ferro

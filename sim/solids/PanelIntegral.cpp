#include "sim/solids/PanelIntegral.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace ferro {

namespace {

// integral over the segment p -> q of dl / |x - y|, for the edge line's distance from x of
// sqrt(d2): ln((R_q + s_q) / (R_p + s_p)), written as ln((R_p - s_p) / (R_q - s_q)) where the
// foot lies beyond q, and as the product over d^2 where it lies within the edge (R + s -> 0
// on the far side would lose every digit). d2 is floored at (1e-9 |q - p|)^2.
double edgeLogIntegral(const Vec3d& x, const Vec3d& p, const Vec3d& q, Vec3d& t, double& len) {
    t = q - p;
    len = t.norm();
    if (!(len > 0)) return 0.0;
    t /= len;
    const Vec3d dp = p - x, dq = q - x;
    const double sp = dp.dot(t), sq = dq.dot(t);
    const double Rp = dp.norm(), Rq = dq.norm();
    if (sp >= 0) return std::log((Rq + sq) / (Rp + sp));
    if (sq <= 0) return std::log((Rp - sp) / (Rq - sq));
    const double d2 = std::max((dp - sp * t).squaredNorm(), 1e-18 * len * len);
    return std::log((Rq + sq) * (Rp - sp) / d2);
}

} // namespace

Vec3d uniformTriangleField(const Vec3d& x, const Vec3d& a, const Vec3d& b, const Vec3d& c, bool onPanel) {
    const Vec3d nRaw = (b - a).cross(c - a);
    const double n2 = nRaw.norm();
    if (!(n2 > 0)) return Vec3d::Zero();
    const Vec3d n = nRaw / n2;
    Vec3d I = Vec3d::Zero();
    const Vec3d* v[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
        Vec3d t;
        double len;
        const double L = edgeLogIntegral(x, *v[k], *v[(k + 1) % 3], t, len);
        if (len > 0) I += L * t.cross(n); // t x n: the in-plane outward normal (counter-clockwise)
    }
    if (!onPanel) {
        const Vec3d r0 = a - x, r1 = b - x, r2 = c - x;
        const double l0 = r0.norm(), l1 = r1.norm(), l2 = r2.norm();
        const double triple = r0.dot(r1.cross(r2));
        const double denom = l0 * l1 * l2 + r0.dot(r1) * l2 + r0.dot(r2) * l1 + r1.dot(r2) * l0;
        // 2 atan2 is the solid angle with the sign of the triple product, which is negative on
        // the side n points to; the field there points along +n.
        I -= 2.0 * std::atan2(triple, denom) * n;
    }
    return I;
}

namespace {

// The gradient of edgeLogIntegral's value in x, in the same three forms (each the derivative
// of its own expression: R' = (x - p) / R, s' = -t, (d^2)' = -2 w with w = p - x - s_p t).
Vec3d edgeLogGradient(const Vec3d& x, const Vec3d& p, const Vec3d& q) {
    Vec3d t = q - p;
    const double len = t.norm();
    if (!(len > 0)) return Vec3d::Zero();
    t /= len;
    const Vec3d dp = p - x, dq = q - x;
    const double sp = dp.dot(t), sq = dq.dot(t);
    const double Rp = dp.norm(), Rq = dq.norm();
    const Vec3d up = -dp / Rp, uq = -dq / Rq; // (x - p) / R_p, (x - q) / R_q
    if (sp >= 0) return (uq - t) / (Rq + sq) - (up - t) / (Rp + sp);
    if (sq <= 0) return (up + t) / (Rp - sp) - (uq + t) / (Rq - sq);
    const Vec3d w = dp - sp * t;
    const double d2 = w.squaredNorm();
    const Vec3d dlog = d2 > 1e-18 * len * len ? Vec3d(-2.0 * w / d2) : Vec3d::Zero();
    return (uq - t) / (Rq + sq) + (up + t) / (Rp - sp) - dlog;
}

} // namespace

Mat3d uniformTriangleGradient(const Vec3d& x, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    // dI/dx of uniformTriangleField, term by term: the edge logarithms' gradients (above) and
    // the solid angle's, which is the field of the rim as a unit current loop (the segment
    // Biot-Savart law: for a = p - x, b = q - x, (a x b)(|a| + |b|) / (|a||b|(|a||b| + a.b))).
    const Vec3d nRaw = (b - a).cross(c - a);
    const double n2 = nRaw.norm();
    Mat3d J = Mat3d::Zero();
    if (!(n2 > 0)) return J;
    const Vec3d n = nRaw / n2;
    const Vec3d* v[3] = {&a, &b, &c};
    Vec3d gradOmega = Vec3d::Zero();
    for (int k = 0; k < 3; ++k) {
        const Vec3d& p = *v[k];
        const Vec3d& q = *v[(k + 1) % 3];
        const Vec3d t = q - p;
        if (!(t.squaredNorm() > 0)) continue;
        J += t.normalized().cross(n) * edgeLogGradient(x, p, q).transpose();
        const Vec3d ra = p - x, rb = q - x;
        const double la = ra.norm(), lb = rb.norm();
        const double den = la * lb * (la * lb + ra.dot(rb));
        if (den > 0) gradOmega += ra.cross(rb) * ((la + lb) / den);
    }
    // I carries -Omega n with Omega = 2 atan2(triple, denom) (uniformTriangleField).
    J -= n * gradOmega.transpose();
    return J;
}

Vec3d closestPointOnTriangle(const Vec3d& x, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d ab = b - a, ac = c - a, ax = x - a;
    const double d1 = ab.dot(ax), d2 = ac.dot(ax);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3d bx = x - b;
    const double d3 = ab.dot(bx), d4 = ac.dot(bx);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const Vec3d cx = x - c;
    const double d5 = ab.dot(cx), d6 = ac.dot(cx);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

} // namespace ferro

// Uniform field (kind "uniform"): H = strength * axis [A/m] everywhere, the field between
// Helmholtz coils; no position, no gradient.
#include "sim/magnets/MagnetKinds.hpp"

#include "sim/magnets/MagnetField.hpp"

namespace ferro {

/// A uniform field has no source body.
double uniformBodyRadius(double) { return 0.0; }

Vec3d uniformMagnetField(const Magnet& mag, const Vec3d& n, const Vec3d&) {
    return mag.strength * n;
}

Mat3d uniformMagnetGradient(const Magnet&, const Vec3d&, const Vec3d&) {
    return Mat3d::Zero();
}

} // namespace ferro

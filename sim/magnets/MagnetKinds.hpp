#pragma once
// The magnet kinds, one table: everything a scene file, a particle file, the field
// evaluation and a render need to know of a kind is its row in kMagnetKinds.
//
// Adding a kind touches two files:
//   1. this header: its MagnetKind value, the declarations of its field and gradient, and
//      its row in kMagnetKinds (name, strength key, which keys it reads, what is drawn);
//   2. sim/magnets/<Name>Magnet.cpp: the field H [A/m], its Jacobian [A/m^2] and the radius
//      of the smallest body that carries the strength.
// The scene parser (MagnetScene.cpp), the particle-file header (MagnetState.cpp), the
// field sum (MagnetField.cpp), the fluid's seeding and obstacles (sim/sph) and ferro-pov's
// magnet bodies all read the table.
#include "sim/core/Types.hpp"

#include <string>
#include <vector>

namespace ferro {

struct Magnet;
using Mat3d = Eigen::Matrix3d;

enum class MagnetKind {
    Dipole,  ///< point dipole at `position`, moment `strength` * direction
    Bar,     ///< two magnetic charges +-q_m, `length` apart along direction (Gilbert model)
    Uniform, ///< homogeneous field `strength` * direction everywhere (Helmholtz coils)
    Loop,    ///< circular current loop of `radius`, axis = direction, centred at `position`
    Coil     ///< solenoid: `turns` turns over `length` on a cylinder of `radius` (an electromagnet)
};

/// The strongest magnetization of any permanent magnet material [A/m]: sintered NdFeB of
/// the highest grade (N52, remanence ~1.45 T) has M = Br / mu0 ~ 1.15e6 A/m. A point source
/// stands for a real magnet, which is at least as big as this magnetization allows, so its
/// field near the source is bounded by that body (see magnetBodyRadius): the field of a
/// point dipole softened over one particle spacing reaches 100 T beside a 1 A m^2 source
/// and throws the fluid out of the dish.
constexpr double kStrongestMagnetization = 1.2e6;
/// Largest current density of a magnet's winding [A/m^2] (superconducting tape in its
/// field, pulsed copper); a loop's wire is at least sqrt(I / (pi J)) thick.
constexpr double kStrongestCurrentDensity = 1e9;

/// The radius [m] of the smallest body that can carry a source of this kind and strength:
/// dipole, a sphere of magnetization kStrongestMagnetization, (3 |m| / (4 pi M))^(1/3);
/// bar, a pole face of that magnetization, sqrt(|q| / (pi M)); loop and coil, the wire's
/// radius sqrt(|I| / (pi J)); 0 for a uniform field. Dipole and bar fields are exact outside about
/// twice this radius and bounded within it (DipoleMagnet.cpp), the loop is clamped at it.
double magnetBodyRadius(MagnetKind kind, double strength);

/// The solid the fluid keeps out of (sim/sph/MagnetObstacles): the points within the body
/// radius (plus a clearance) of the magnet's core.
enum class MagnetCore {
    None,    ///< no solid (a uniform field)
    Point,   ///< a sphere around `position`
    Segment, ///< a capsule around the segment of `length` along the axis through `position`
    Ring,    ///< a torus around the circle of `radius` about the axis through `position`
    Tube     ///< the cylinder of `radius` and `length` about the axis (a coil's winding), thickened
};

/// The body ferro-pov draws for a magnet.
enum class MagnetBody {
    None, ///< nothing (a uniform field has no body)
    Rod,  ///< a cylinder along the axis, split into north and south halves
    Ring, ///< a torus around the axis (a current loop's wire)
    Tube  ///< a hollow cylinder around the axis (a coil's winding)
};

/// Field and Jacobian of one magnet at x [m]; `axis` is its unit direction.
using MagnetFieldFn = Vec3d (*)(const Magnet& magnet, const Vec3d& axis, const Vec3d& x);
using MagnetGradientFn = Mat3d (*)(const Magnet& magnet, const Vec3d& axis, const Vec3d& x);
/// Radius [m] of the smallest body that carries `strength` (see magnetBodyRadius).
using MagnetBodyRadiusFn = double (*)(double strength);

struct MagnetKindInfo {
    MagnetKind kind;
    const char* name;         ///< scene `kind` and particle-file header word
    const char* strengthKey;  ///< scene key of Magnet::strength
    const char* strengthUnit; ///< its SI unit, for documentation and messages
    /// Largest |strength| a scene may set (MagnetScene.cpp refuses more, naming the key).
    /// Each is beyond any real magnet, yet keeps H, M and H^2 well inside a float where
    /// particles can be (float overflowed from field = 1e20 A/m: H^2 = 1e40 made H NaN):
    ///   dipole  1e6 A m^2: a cubic metre of NdFeB (M ~ 1e6 A/m); H = 1.6e14 A/m at 1 mm;
    ///   bar     1e6 A m:   a pole face of 1 m^2 of NdFeB;
    ///   uniform 1e9 A/m:   1257 T, beyond the strongest field ever made (~1000 T, pulsed);
    ///   loop    1e9 A:     several times the ampere-turns of a fusion reactor's central
    ///                      solenoid (~1.5e8); H = 5e11 A/m at the centre of a 1 mm loop;
    ///   coil    1e6 A a turn, with at most kMostTurns turns: 1e11 ampere-turns, H = 1e14 A/m
    ///                      inside a 1 mm long coil.
    double maxStrength;
    bool positioned;          ///< reads `position` and `softening` (false: same everywhere)
    bool usesLength;          ///< `length` required: the distance between the poles
    bool usesRadius;          ///< `radius` required: the loop's radius
    bool usesTurns;           ///< `turns` required: the coil's number of turns (Magnet::turns)
    MagnetBody body;          ///< what ferro-pov draws
    MagnetCore core;          ///< the solid the fluid keeps out of
    MagnetFieldFn field;
    MagnetGradientFn gradient;
    MagnetBodyRadiusFn bodyRadius;
};

Vec3d dipoleMagnetField(const Magnet&, const Vec3d&, const Vec3d&);    // DipoleMagnet.cpp
Mat3d dipoleMagnetGradient(const Magnet&, const Vec3d&, const Vec3d&);
double dipoleBodyRadius(double strength);
Vec3d barMagnetField(const Magnet&, const Vec3d&, const Vec3d&);       // BarMagnet.cpp
Mat3d barMagnetGradient(const Magnet&, const Vec3d&, const Vec3d&);
double barBodyRadius(double strength);
Vec3d uniformMagnetField(const Magnet&, const Vec3d&, const Vec3d&);   // UniformMagnet.cpp
Mat3d uniformMagnetGradient(const Magnet&, const Vec3d&, const Vec3d&);
double uniformBodyRadius(double strength);
Vec3d loopMagnetField(const Magnet&, const Vec3d&, const Vec3d&);      // LoopMagnet.cpp
Mat3d loopMagnetGradient(const Magnet&, const Vec3d&, const Vec3d&);
double loopBodyRadius(double strength);
Vec3d coilMagnetField(const Magnet&, const Vec3d&, const Vec3d&);      // CoilMagnet.cpp
Mat3d coilMagnetGradient(const Magnet&, const Vec3d&, const Vec3d&);
double coilBodyRadius(double strength);

/// Most turns a coil may have (with maxStrength, 1e11 ampere-turns).
constexpr double kMostTurns = 1e5;

/// One row per kind, in MagnetKind order.
inline const MagnetKindInfo kMagnetKinds[] = {
    // kind, name, strength key, unit, max strength, positioned, length, radius, turns, drawn body, solid core,
    // field, gradient, body radius
    {MagnetKind::Dipole, "dipole", "moment", "A m^2", 1e6, true, false, false, false, MagnetBody::Rod, MagnetCore::Point,
     &dipoleMagnetField, &dipoleMagnetGradient, &dipoleBodyRadius},
    {MagnetKind::Bar, "bar", "pole_strength", "A m", 1e6, true, true, false, false, MagnetBody::Rod, MagnetCore::Segment,
     &barMagnetField, &barMagnetGradient, &barBodyRadius},
    {MagnetKind::Uniform, "uniform", "field", "A/m", 1e9, false, false, false, false, MagnetBody::None, MagnetCore::None,
     &uniformMagnetField, &uniformMagnetGradient, &uniformBodyRadius},
    {MagnetKind::Loop, "loop", "current", "A", 1e9, true, false, true, false, MagnetBody::Ring, MagnetCore::Ring,
     &loopMagnetField, &loopMagnetGradient, &loopBodyRadius},
    {MagnetKind::Coil, "coil", "current", "A", 1e6, true, true, true, true, MagnetBody::Tube, MagnetCore::Tube,
     &coilMagnetField, &coilMagnetGradient, &coilBodyRadius},
};

/// The row of `kind`.
const MagnetKindInfo& magnetKindInfo(MagnetKind kind);
/// The row called `name`, or nullptr.
const MagnetKindInfo* findMagnetKind(const std::string& name);
/// Every kind's name, in table order.
std::vector<std::string> magnetKindNames();

} // namespace ferro

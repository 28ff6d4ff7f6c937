// The climb (issue 51): fluid standing on a soft-iron frustum over a cored coil, at rest,
// against the ferrohydrostatic Bernoulli law along its free surface, the same law the heap
// keeps (test_FluidMagnetics.cpp): rho g z_s - mu0 (F(H) + M_n^2 / 2) is one constant over
// the whole free surface, pool and coat. Reference: that law (Rosensweig, ch. 5), with H and
// M just inside the surface from an evaluation of our own (the magnets' and the solids' field
// at the surface point, the fluid's own as the particle reports it, M by the Langevin law).
//
// NOT YET PASSING, hence hidden (ferro_sph_tests "[.climb]"; 4,000 particles ~4 CPU minutes,
// 13,500 ~11): the harness of issue 51's climb must-show, kept for the next step. Measured
// 2026-12-07, 0.45 A, with the solids' standoff (a particle reads their field half a spacing
// off the wall; before it the pool moved at 7 mm/s after 1.5 s):
//   - 4,000 particles (0.8 mm): the 4 mm pool is five particles deep and holds no coat; a few
//     particles on the frustum's top, 55 % off the law; 2.0 mm/s.
//   - 8,000 (0.66 mm): the pool rises 1.35 mm up the flank; 14 surface cells, worst +4.5 Pa
//     (at the flank) of a 16.8 Pa rise (27 %), the rest within 2.1 Pa (13 %); 0.89 mm/s.
//   - 13,500 (0.55 mm): a 0.6 mm rise at the flank; 18 cells, worst +1.8 Pa (the contact
//     line) of 7.0 Pa (26 %), the rest within 1.1 Pa (15 %); 0.51 mm/s.
// At rest (< 1 mm/s) at both finer spacings; the law within 10 % not yet: the cells at the
// contact line sit 2-4 Pa above it. What it is not (8,000 particles, 2026-12-07 session 4):
//   - the normal traction alone: at the contact-line cells mu0 Mn^2/2 is 0.08-0.26 Pa (the
//     field along the steel's normal lies along the fluid's surface there), against 3.0-3.3
//     Pa at r = 6.2-6.5 mm where |H| is alike; a potential body force mu0 M_f(|H|) grad |H|
//     cannot give both, but `force = "surface"`, which applies mu0 (F + Mn^2/2) itself, is
//     worse: +6.5 Pa at the flank (35 % of 18.4 Pa) and not at rest (4.6 mm/s);
//   - capillarity alone: with no tension the fluid creeps up onto the frustum's top (10.6 mm)
//     and the pool's own cells spread over 6.8 Pa (48 %).
//   - the wall's meniscus (session 6, 8,000 particles): with the coil at 0.005 A (no climb;
//     the law is then rho g z = const) the akinci2013 fluid dips 0.38 mm at the steel (the
//     contact-line cell 3.9 Pa below the pool's), a non-wetting meniscus: capillarity pulls
//     the contact line down, so the excess with the field is, if anything, larger than 4.5 Pa;
//   - the tension model: with "csf" (FERRO_CLIMB_TENSION_MODEL=csf) the fluid creeps up the
//     flank onto the frustum's top (10.6 mm) as with no tension at all, and the pool is not
//     at rest (3.0 mm/s): csf holds no coat on a wall.
// Suspects left: the field the law reads half a spacing out where the particles read it at
// a standoff from the steel.
// Environment: FERRO_CLIMB_CURRENT [A], FERRO_CLIMB_COUNT (particles), FERRO_CLIMB_CHI
// (susceptibility), FERRO_CLIMB_FORCE (magnetization.force), FERRO_CLIMB_TENSION [N/m],
// FERRO_CLIMB_TENSION_MODEL (fluid.surface_tension_model);
// FERRO_CLIMB_CSV writes the cells (r, z, rho g z, mu0 (F + Mn^2/2), residual, mu0 Mn^2/2),
// FERRO_CLIMB_DUMP every particle's (r, z, speed) at the end.
#include "sim/core/Constants.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnetics/SolidCoupling.hpp"
#include "sim/magnets/LangevinLaw.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/scene/SimSceneFile.hpp"
#include "sim/spatial/HashGrid.hpp"
#include "sim/sph/FluidMagnetics.hpp"
#include "sim/sph/FluidSimulation.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

using namespace ferro;

namespace {

// A 15 mm dish with a 4 mm layer, a steel frustum (6 mm base radius, 2 mm top, 10 mm tall) on
// its floor over a soft-iron core in a coil of 500 turns under the floor, the current ramped
// to I over 0.4 s and held.
std::string climbScene(long count, double current) {
    const char* chiEnv = std::getenv("FERRO_CLIMB_CHI");
    const std::string chi = chiEnv ? chiEnv : "1.5";
    const char* forceEnv = std::getenv("FERRO_CLIMB_FORCE");
    const std::string force = forceEnv ? forceEnv : "body";
    const char* tensionEnv = std::getenv("FERRO_CLIMB_TENSION");
    const std::string tension = tensionEnv ? tensionEnv : "0.025";
    const char* modelEnv = std::getenv("FERRO_CLIMB_TENSION_MODEL");
    const std::string model = modelEnv ? modelEnv : "akinci2013";
    return R"([shot]
fps = 10
duration = 3.0
preroll = 0.0
[fluid]
rest_density = 1200.0
viscosity = 5e-6
surface_tension = )" + tension + R"(
surface_tension_model = ")" + model + R"("
[[fluid.block]]
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.015
height = 0.004
count = )" + std::to_string(count) + R"(
[container]
type = "dish"
center = [0.0, 0.0, 0.0]
radius = 0.015
height = 0.03
[[magnets]]
kind = "coil"
position = [0.0, 0.0, -0.012]
direction = [0.0, 0.0, 1.0]
radius = 0.008
length = 0.02
turns = 500
current = 0.0
[[magnets.keys]]
time = 0.0
current = 0.0
[[magnets.keys]]
time = 0.4
current = )" + std::to_string(current) + R"(
[magnetization]
susceptibility = )" + chi + R"(
saturation = 35000.0
force = ")" + force + R"("
[[solids]]
shape = "cone"
radius = 0.006
tip_radius = 0.002
height = 0.010
position = [0.0, 0.0, 0.0]
permeability = 1000
saturation = 1.6e6
[[solids]]
shape = "cylinder"
radius = 0.006
height = 0.02
position = [0.0, 0.0, -0.0225]
permeability = 1000
saturation = 1.6e6
)";
}

constexpr double kBase = 0.006, kTop = 0.002, kHeight = 0.010, kDish = 0.015;

// Distance from (r, z) to the frustum's surface (outside it; negative inside), in the half plane.
double frustumDistance(double r, double z) {
    const double slope = (kBase - kTop) / kHeight; // dr/dz of the flank
    const double c = 1.0 / std::sqrt(1 + slope * slope);
    const double flank = (r - (kBase - slope * std::clamp(z, 0.0, kHeight))) * c;
    if (z > kHeight) return r < kTop ? z - kHeight : std::hypot(r - kTop, z - kHeight);
    return flank;
}

// One look at the free surface: per surface particle, its surface point (r, z) and the two
// sides of the law there [Pa].
struct SurfaceSample {
    double r, z, gravity, magnetic;
    double normalShare; ///< mu0 Mn^2 / 2 of `magnetic` [Pa]
};

std::vector<SurfaceSample> surfaceSamples(const FluidSimulation& sim) {
    const double s = sim.spacing(), rho0 = sim.restDensity(), g = sim.scene().solver.gravity.norm();
    const double chi0 = sim.scene().magnetization.susceptibility, Ms = sim.scene().magnetization.saturation;
    const std::vector<Magnet> magnets = sim.magnetsNow();
    const FluidMagnetics& mag = *sim.magnetics();
    const SurfaceChargeSolver& solids = mag.solids()->solver();
    const std::vector<Vec3>& xf = sim.positions();
    std::vector<Vec3d> x(xf.size());
    for (size_t i = 0; i < x.size(); ++i) x[i] = xf[i].cast<double>();
    const HashGrid grid(x, 3 * s);
    std::vector<SurfaceSample> out;
    for (size_t i = 0; i < x.size(); ++i) {
        // The outward direction: away from the neighbours within two spacings.
        Vec3d inward = Vec3d::Zero();
        grid.forEachWithin(x[i], 2 * s, [&](uint32_t j, double d2) {
            if (j == i || d2 <= 0) return;
            const double d = std::sqrt(d2), w = (1 - d / (2 * s)) * (1 - d / (2 * s));
            inward += w * (x[j] - x[i]) / d;
        });
        if (!(inward.norm() > 0)) continue;
        const Vec3d n = -inward.normalized();
        // A surface particle has no neighbour within 3 spacings in its outward cone (40 deg):
        // with 1.5, particles of a layer under a gap between the pool's layers passed for
        // surface (FERRO_CLIMB_DUMP's picture at 0.55 mm).
        bool covered = false;
        grid.forEachWithin(x[i], 3 * s, [&](uint32_t j, double d2) {
            if (j != i && d2 > 0 && (x[j] - x[i]).dot(n) > std::cos(40 * kPi / 180) * std::sqrt(d2)) covered = true;
        });
        if (covered) continue;
        // Not a wetted wall: a spacing out along n is clear of the steel, the floor and the dish.
        const Vec3d out1 = x[i] + s * n;
        const double r1 = std::hypot(out1.x(), out1.y());
        if (frustumDistance(r1, out1.z()) < 0.5 * s || out1.z() < 0.5 * s || r1 > kDish - 3 * s) continue;
        // The surface point half a spacing out, its field: the magnets' and the solids' there,
        // the fluid's own as at the particle.
        const Vec3d xs = x[i] + 0.5 * s * n;
        Vec3d hs, hi;
        Mat3d J;
        solids.fieldAndGradient(xs, hs, J, 0.5 * s); // the standoff the simulation's particles read with
        solids.fieldAndGradient(x[i], hi, J, 0.5 * s);
        const Vec3d own = mag.field()[i].cast<double>() - magnetField(magnets, x[i]) - hi;
        const Vec3d H = magnetField(magnets, xs) + hs + own;
        const double h = H.norm();
        const double mn = h > 0 ? langevinMagnetization(h, chi0, Ms) * H.dot(n) / h : 0.0;
        out.push_back({std::hypot(xs.x(), xs.y()), xs.z(), rho0 * g * xs.z(),
                       kMu0 * (langevinEnergy(h, chi0, Ms) + 0.5 * mn * mn), kMu0 * 0.5 * mn * mn});
    }
    return out;
}

struct ClimbCheck {
    double rise = 0;    // rho g (highest cell - lowest cell) [Pa]
    double worst = 0;   // largest |residual - mean| over the cells [Pa]
    double coatTop = 0; // the highest surface point on the frustum's flank [m]
    double pool = 0;    // the pool's level 10 mm and more from the axis [m]
    size_t cells = 0;
};

// The law on cells one spacing square in (r, z), each the mean over every look's samples in
// it (cells with at least `looks` samples).
ClimbCheck climbCheck(const std::vector<std::vector<SurfaceSample>>& looks, double s, const char* csv) {
    std::map<std::pair<int, int>, std::vector<const SurfaceSample*>> cells;
    for (const auto& look : looks)
        for (const SurfaceSample& p : look) cells[{int(p.r / s), int(p.z / s)}].push_back(&p);
    struct Cell {
        double r, z, gravity, magnetic, normalShare;
    };
    std::vector<Cell> kept;
    for (const auto& [key, samples] : cells) {
        if (samples.size() < looks.size()) continue;
        Cell c{0, 0, 0, 0, 0};
        for (const SurfaceSample* p : samples) {
            c.r += p->r / samples.size();
            c.z += p->z / samples.size();
            c.gravity += p->gravity / samples.size();
            c.magnetic += p->magnetic / samples.size();
            c.normalShare += p->normalShare / samples.size();
        }
        kept.push_back(c);
    }
    ClimbCheck out;
    out.cells = kept.size();
    if (kept.empty()) return out;
    double mean = 0, lo = 1e300, hi = -1e300, poolCells = 0;
    for (const Cell& c : kept) {
        if (c.r > 0.010) out.pool += c.z, ++poolCells;
        mean += (c.gravity - c.magnetic) / kept.size();
        lo = std::min(lo, c.gravity);
        hi = std::max(hi, c.gravity);
        if (frustumDistance(c.r, c.z) < 3 * s) out.coatTop = std::max(out.coatTop, c.z);
    }
    for (const Cell& c : kept) out.worst = std::max(out.worst, std::abs(c.gravity - c.magnetic - mean));
    out.rise = hi - lo;
    out.pool /= std::max(poolCells, 1.0);
    if (csv) {
        std::ofstream f(csv);
        f << "# r [mm], z [mm], rho g z [Pa], mu0 (F + Mn^2/2) [Pa], residual - mean [Pa], mu0 Mn^2/2 [Pa]\n";
        for (const Cell& c : kept)
            f << 1e3 * c.r << ' ' << 1e3 * c.z << ' ' << c.gravity << ' ' << c.magnetic << ' '
              << c.gravity - c.magnetic - mean << ' ' << c.normalShare << '\n';
    }
    return out;
}

double rmsSpeed(const FluidSimulation& sim) {
    double sum = 0;
    for (const Vec3& v : sim.velocities()) sum += double(v.squaredNorm());
    return std::sqrt(sum / double(std::max<size_t>(sim.size(), 1)));
}

ClimbCheck settledClimb(long count, double current, double& rms, double& spacing) {
    FluidSimulation sim(parseSimScene(SceneDocument::parse(climbScene(count, current), "climb.toml")));
    spacing = sim.spacing();
    for (int frame = 1; frame <= 15; ++frame) sim.advanceTo(0.1 * frame);
    rms = rmsSpeed(sim);
    std::vector<std::vector<SurfaceSample>> looks{surfaceSamples(sim)};
    for (int k = 1; k <= 10; ++k) {
        sim.advanceTo(1.5 + 0.05 * k);
        looks.push_back(surfaceSamples(sim));
    }
    if (const char* dump = std::getenv("FERRO_CLIMB_DUMP")) {
        // Every particle's (r, z) [mm] and speed [mm/s] at the end, for a look at the state.
        std::ofstream out(dump);
        for (size_t i = 0; i < sim.size(); ++i) {
            const Vec3 x = sim.positions()[i];
            out << 1e3 * std::hypot(double(x.x()), double(x.y())) << " " << 1e3 * double(x.z()) << " "
                << 1e3 * double(sim.velocities()[i].norm()) << "\n";
        }
    }
    return climbCheck(looks, sim.spacing(), std::getenv("FERRO_CLIMB_CSV"));
}

} // namespace

TEST_CASE("fluid climbing a steel frustum over a cored coil rests on the ferrohydrostatic law", "[magnetics][solids][.climb]") {
    double rms = 0, s = 0;
    const double current = std::getenv("FERRO_CLIMB_CURRENT") ? std::atof(std::getenv("FERRO_CLIMB_CURRENT")) : 0.45;
    const long count = std::getenv("FERRO_CLIMB_COUNT") ? std::atol(std::getenv("FERRO_CLIMB_COUNT")) : 4000;
    const ClimbCheck c = settledClimb(count, current, rms, s);
    WARN("climb, " << count << " particles (" << 1e3 * s << " mm): rise " << c.rise << " Pa over " << c.cells
                                  << " cells, worst deviation from the law " << c.worst << " Pa ("
                                  << 100 * c.worst / c.rise << " %), coat top " << 1e3 * c.coatTop
                                  << " mm over the pool at " << 1e3 * c.pool << " mm, RMS speed " << 1e3 * rms
                                  << " mm/s");
    CHECK(rms < 0.001);
    CHECK(c.coatTop > c.pool + 2 * s); // the fluid climbs the flank above the pool
    CHECK(c.worst < 0.10 * c.rise);
}

// The magnetic part of ferro-sim in a running simulation: the Kelvin force against its
// closed form and its physical direction, the paper's examples (heaping over a magnet,
// flattening once the field is gone, two magnets), fluid staying attached in a strong
// field, the re-solve policy, H / M / magnets in the particle files, and resume.
#include "sim/sph/FluidMagnetics.hpp"
#include "sim/sph/FluidSimulation.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "sim/magnetics/MagnetizationSolver.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimSceneFile.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace ferro;

namespace {


std::string example(const std::string& name) { return std::string(FERRO_SOURCE_DIR) + "/examples/" + name; }

SimScene loadExample(const std::string& name, std::vector<std::string> overrides) {
    return parseSimScene(SceneDocument::load(example(name), overrides));
}

/// Height of the free surface (98th percentile of z) of the particles whose horizontal
/// distance from (cx, cy) is in [r0, r1).
double surfaceHeight(const std::vector<Vec3>& x, double cx, double cy, double r0, double r1) {
    std::vector<double> z;
    for (const Vec3& p : x) {
        const double r = std::hypot(p.x() - cx, p.y() - cy);
        if (r >= r0 && r < r1) z.push_back(p.z());
    }
    REQUIRE(z.size() > 20);
    std::sort(z.begin(), z.end());
    return z[size_t(0.98 * double(z.size() - 1))];
}

/// The field just inside the free surface a particle at xi stands for, at xs (half a spacing
/// out from its centre): the magnets' field there, analytic, plus the particle's own induced
/// field Hi - H_magnets(xi) as the simulation reports it (it changes little over half a
/// spacing; ringProfile says how little). Both surface rulers below read the field here.
Vec3d fieldAtSurface(const std::vector<Magnet>& magnets, const Vec3d& xi, const Vec3d& Hi, const Vec3d& xs) {
    return magnetField(magnets, xs) + (Hi - magnetField(magnets, xi));
}

/// The ferrohydrostatic balance along the free surface of a fluid at rest. With pressure
/// zero on the surface, the tangential part of rho g + f must vanish there, so between two
/// surface points g (z_a - z_b) = integral_b^a f / rho0 . dl. The surface is sampled in bins
/// of one spacing along the horizontal line from `from` to `to` (particles within 1.5
/// spacings of the line): in each bin the top 10 % of the particles by height. f is
/// evaluated independently of FluidMagnetics: mu0 (J_magnets M) / rho0 (the body force
/// model, magnetization.force = "body") half a spacing above each particle, with the
/// magnets' analytic field and Jacobian there plus the particle's induced field as the
/// simulation reports it, and M from the Langevin law (for the `external` solver this is
/// exactly mu0 grad F(H_magnets), so the balance reads rho g dz = mu0 dF). Returns the rise z(to) - z(from) [m] and the rise
/// the balance predicts, g^-1 times the line integral.
using Vec2d = Eigen::Vector2d;
struct SurfaceBalance {
    double rise = 0, predicted = 0;
};
SurfaceBalance surfaceBalance(const FluidSimulation& sim, const Vec2d& from, const Vec2d& to) {
    const double s = sim.spacing(), rho0 = sim.restDensity(), g = sim.scene().solver.gravity.norm();
    const std::vector<Magnet> magnets = sim.magnetsNow();
    const std::vector<Vec3>& x = sim.positions();
    const std::vector<Vec3>& H = sim.magnetics()->field();
    const double chi0 = sim.scene().magnetization.susceptibility, Msat = sim.scene().magnetization.saturation;
    const Vec2d axis = (to - from).normalized();
    const double length = (to - from).norm();
    const int bins = int(length / s) + 1;
    std::vector<std::vector<size_t>> inBin(static_cast<size_t>(bins));
    for (size_t i = 0; i < x.size(); ++i) {
        const Vec2d d = Vec2d(x[i].x(), x[i].y()) - from;
        const double along = d.dot(axis), across = std::abs(d.x() * axis.y() - d.y() * axis.x());
        const int b = int(std::floor(along / s + 0.5));
        if (across < 1.5 * s && b >= 0 && b < bins) inBin[size_t(b)].push_back(i);
    }
    std::vector<Vec3d> point, force;
    for (std::vector<size_t>& bin : inBin) {
        REQUIRE(bin.size() >= 10);
        std::sort(bin.begin(), bin.end(), [&](size_t a, size_t b) { return x[a].z() > x[b].z(); });
        const size_t top = std::max<size_t>(1, bin.size() / 10);
        Vec3d p = Vec3d::Zero(), f = Vec3d::Zero();
        for (size_t k = 0; k < top; ++k) {
            // The fluid a particle stands for ends half a spacing above its centre: the
            // balance holds on that surface (pressure zero), not along the centres, where
            // the pressure grows with the pull (5-10 g over a strong magnet).
            const Vec3d xi = x[bin[k]].cast<double>();
            const Vec3d xs = xi + Vec3d(0, 0, 0.5 * s);
            const Vec3d Hs = fieldAtSurface(magnets, xi, H[bin[k]].cast<double>(), xs);
            const Vec3d Ms = langevinMagnetization(Hs.norm(), chi0, Msat) * Hs.normalized();
            p += xs / double(top);
            f += kMu0 / rho0 * (fieldGradient(magnets, xs) * Ms) / double(top);
        }
        point.push_back(p);
        force.push_back(f);
    }
    SurfaceBalance out;
    out.rise = point.back().z() - point.front().z();
    double work = 0;   // trapezoid rule along the sampled surface
    for (size_t k = 1; k < point.size(); ++k) work += 0.5 * (force[k] + force[k - 1]).dot(point[k] - point[k - 1]);
    out.predicted = work / g;
    return out;
}

/// The ferrohydrostatic Bernoulli law along a pool's free surface (Rosensweig,
/// Ferrohydrodynamics, ch. 5): rho g z_s - mu0 (F(H) + M_n^2 / 2) is the same everywhere on
/// it, H and M the field and magnetization just inside the surface, M_n = M . n. Both sides
/// from the simulation's own particles: the surface is located by column tops (rings one
/// spacing wide around the dish axis, each cut into sectors about one spacing long; a
/// sector's highest particle is its top; the surface is half a spacing out from the tops,
/// see ringProfile), z_s, H and M_n are ring means over the surface points, the normal n
/// comes from the ring profile's slope. Rings from the axis to 2.5 spacings inside the wall
/// (`wallRadius`, clear of the meniscus).
struct BernoulliCheck {
    double rise = 0;         ///< rho g (z_s(axis) - z_s(outermost ring)) [Pa]
    double worst = 0;        ///< largest |residual - mean residual| over the rings [Pa]
    double traction = 0;     ///< mu0 M_n^2 / 2 on the axis [Pa]
    double pressure = 0;     ///< mu0 F(H) on the axis [Pa]
    /// The same law with the capillary pressure of the surface, sigma div n, added to the left
    /// side (rho g z_s + sigma div n = mu0 (F + M_n^2 / 2) + C): its worst deviation [Pa] and
    /// sigma div n on the axis [Pa]. div n from a smooth fit of the ring profile,
    /// z(r) = a0 + a1 r^2 + a2 r^4 + a3 r^6 (ring tops are too noisy to differentiate twice).
    double worstCapillary = 0;
    double capillary = 0;
};

/// Solves the small normal equations of a least-squares fit (Gaussian elimination).
std::vector<double> leastSquares(const std::vector<std::vector<double>>& rows, const std::vector<double>& rhs) {
    const size_t m = rows.front().size();
    std::vector<std::vector<double>> a(m, std::vector<double>(m + 1, 0.0));
    for (size_t r = 0; r < rows.size(); ++r)
        for (size_t i = 0; i < m; ++i) {
            for (size_t j = 0; j < m; ++j) a[i][j] += rows[r][i] * rows[r][j];
            a[i][m] += rows[r][i] * rhs[r];
        }
    for (size_t c = 0; c < m; ++c) {
        size_t pivot = c;
        for (size_t r = c + 1; r < m; ++r)
            if (std::abs(a[r][c]) > std::abs(a[pivot][c])) pivot = r;
        std::swap(a[c], a[pivot]);
        for (size_t r = 0; r < m; ++r) {
            if (r == c) continue;
            const double f = a[r][c] / a[c][c];
            for (size_t k = c; k <= m; ++k) a[r][k] -= f * a[c][k];
        }
    }
    std::vector<double> out(m);
    for (size_t i = 0; i < m; ++i) out[i] = a[i][m] / a[i][i];
    return out;
}
/// One look at the surface: per ring, the mean radius and height z_s of the surface over the
/// column tops, and the magnetic side's two terms mu0 F(H) and mu0 M_n^2 / 2 [Pa] there (see
/// BernoulliCheck).
struct RingProfile {
    std::vector<double> r, z, pressure, traction;
};

RingProfile ringProfile(const FluidSimulation& sim, double wallRadius) {
    const double s = sim.spacing();
    const double chi0 = sim.scene().magnetization.susceptibility, Msat = sim.scene().magnetization.saturation;
    const std::vector<Magnet> magnets = sim.magnetsNow();
    const std::vector<Vec3>& x = sim.positions();
    const std::vector<Vec3>& H = sim.magnetics()->field();
    const int rings = int((wallRadius - 2.5 * s) / s);
    REQUIRE(rings >= 4);
    std::map<std::pair<int, int>, size_t> top;   // (ring, sector) -> highest particle
    for (size_t i = 0; i < x.size(); ++i) {
        const double r = std::hypot(double(x[i].x()), double(x[i].y()));
        const int ring = int(r / s);
        if (ring >= rings) continue;
        const int sectors = std::max(1, int(2 * kPi * (ring + 0.5)));
        const double angle = std::atan2(double(x[i].y()), double(x[i].x())) + kPi;
        const std::pair<int, int> key(ring, std::min(sectors - 1, int(angle / (2 * kPi) * sectors)));
        const auto it = top.find(key);
        if (it == top.end() || x[i].z() > x[it->second].z()) top[key] = i;
    }
    std::vector<std::vector<size_t>> tops(static_cast<size_t>(rings));
    for (const auto& [key, i] : top) tops[size_t(key.first)].push_back(i);
    std::vector<double> centreZ(size_t(rings), 0.0);
    for (int k = 0; k < rings; ++k) {
        REQUIRE(!tops[size_t(k)].empty());
        for (size_t i : tops[size_t(k)]) centreZ[size_t(k)] += double(x[i].z()) / double(tops[size_t(k)].size());
    }
    // The surface is half a spacing out from the top particles' centres along the profile's
    // normal: the fluid a particle stands for ends there, and there its pressure is zero
    // (measured on this pool: 0.49-0.56 spacings above the centres, from the top particles'
    // pressure and the pressure gradient; surfaceBalance uses the same surface, and the
    // external solver's heap meets its balance on it within 2 %). The law needs H and M there,
    // just inside the surface, not at the centres: F + M_n^2 / 2 grows with depth by ~100 Pa
    // per spacing on the axis and ~30 at the outermost ring (chi0 1.5; the applied field's
    // gradient, 2e6 A/m^2 on the axis), against a rise of ~40 Pa, so a ruler at the centres
    // can be off by as much as the rise. The field there is fieldAtSurface's, and M is the
    // Langevin law of it, as the file's M is of the file's H. The induced field changes
    // little near the top (a flat layer over this dipole solved at 1 and 2 mm spacing: 2-5 %
    // per spacing, against 20 % for the applied field); taking it constant over the half spacing puts F on the axis
    // at most ~3 Pa low on this pool, ~10 % of its rise, in the direction that makes the
    // heap look too tall.
    RingProfile out;
    out.r.assign(size_t(rings), 0.0);
    out.z.assign(size_t(rings), 0.0);
    out.pressure.assign(size_t(rings), 0.0);
    out.traction.assign(size_t(rings), 0.0);
    for (int k = 0; k < rings; ++k) {
        const int lo = std::max(k - 1, 0), hi = std::min(k + 1, rings - 1);
        const double slope = (centreZ[size_t(hi)] - centreZ[size_t(lo)]) / (double(hi - lo) * s);
        const double count = double(tops[size_t(k)].size());
        for (size_t i : tops[size_t(k)]) {
            const Vec2d radial = Vec2d(x[i].x(), x[i].y()).normalized();
            const Vec3d n = Vec3d(-slope * radial.x(), -slope * radial.y(), 1).normalized();
            const Vec3d xi = x[i].cast<double>(), xs = xi + 0.5 * s * n;
            const Vec3d Hs = fieldAtSurface(magnets, xi, H[i].cast<double>(), xs);
            const double h = Hs.norm(), mn = h > 0 ? langevinMagnetization(h, chi0, Msat) * Hs.dot(n) / h : 0.0;
            out.r[size_t(k)] += std::hypot(xs.x(), xs.y()) / count;
            out.z[size_t(k)] += xs.z() / count;
            out.pressure[size_t(k)] += kMu0 * langevinEnergy(h, chi0, Msat) / count;
            out.traction[size_t(k)] += kMu0 * 0.5 * mn * mn / count;
        }
    }
    return out;
}

/// The law on the mean of several looks at a resting surface (each ring's values averaged
/// over the looks): a ring's column tops are a handful of particles, and in a pool at rest
/// (0.5 mm/s RMS) which particle tops a column changes from look to look, by up to a
/// quarter spacing (on the 2,560-particle pool the worst deviation of single looks 0.25 s
/// apart ranged over 9-34 % of the rise while the rise held at 32-33 Pa).
BernoulliCheck bernoulliCheck(const std::vector<RingProfile>& looks, const FluidSimulation& sim) {
    REQUIRE(!looks.empty());
    const double s = sim.spacing(), rho0 = sim.restDensity(), g = sim.scene().solver.gravity.norm();
    const size_t rings = looks.front().z.size();
    RingProfile mean;
    for (std::vector<double>* v : {&mean.r, &mean.z, &mean.pressure, &mean.traction}) v->assign(rings, 0.0);
    for (const RingProfile& look : looks) {
        REQUIRE(look.z.size() == rings);
        for (size_t k = 0; k < rings; ++k) {
            mean.r[k] += look.r[k] / double(looks.size());
            mean.z[k] += look.z[k] / double(looks.size());
            mean.pressure[k] += look.pressure[k] / double(looks.size());
            mean.traction[k] += look.traction[k] / double(looks.size());
        }
    }
    // Capillary pressure sigma div n of the axisymmetric profile z(r), n = (-z' e_r, 1) / sqrt(1 + z'^2):
    // div n = -(1/r) d/dr (r z' / sqrt(1 + z'^2)), by central differences of the fitted profile.
    std::vector<std::vector<double>> basis;
    for (size_t k = 0; k < rings; ++k) {
        const double u = mean.r[k] * mean.r[k];
        basis.push_back({1.0, u, u * u, u * u * u});
    }
    const std::vector<double> a = leastSquares(basis, mean.z);
    const auto slopeAt = [&](double r) {
        const double u = r * r;
        return 2 * r * (a[1] + 2 * a[2] * u + 3 * a[3] * u * u);
    };
    const auto divNormal = [&](double r) {
        const double dr = 0.25 * s;
        r = std::max(r, dr);
        const auto flux = [&](double q) {
            const double zp = slopeAt(q);
            return q * zp / std::sqrt(1 + zp * zp);
        };
        return -(flux(r + dr) - flux(r - dr)) / (2 * dr * r);
    };
    const double sigma = sim.scene().fluid.surfaceTension;
    std::vector<double> withCapillary;
    std::vector<double> residual;
    BernoulliCheck out;
    out.pressure = mean.pressure.front();
    out.traction = mean.traction.front();
    out.capillary = sigma * divNormal(mean.r.front());
    for (size_t k = 0; k < rings; ++k) {
        residual.push_back(rho0 * g * mean.z[k] - mean.pressure[k] - mean.traction[k]);
        withCapillary.push_back(residual.back() + sigma * divNormal(mean.r[k]));
    }
    const auto worstDeviation = [](const std::vector<double>& v) {
        double avg = 0, worst = 0;
        for (double r : v) avg += r / double(v.size());
        for (double r : v) worst = std::max(worst, std::abs(r - avg));
        return worst;
    };
    out.worst = worstDeviation(residual);
    out.worstCapillary = worstDeviation(withCapillary);
    out.rise = rho0 * g * (mean.z.front() - mean.z.back());
    return out;
}

/// Advances a resting pool by `span` [s], looking at its surface every `every` [s] (the
/// first look now): the law on the mean of the looks.
BernoulliCheck bernoulliCheckOverTime(FluidSimulation& sim, double wallRadius, double span = 0.5, double every = 0.05) {
    std::vector<RingProfile> looks{ringProfile(sim, wallRadius)};
    const double start = sim.time();
    for (int k = 1; k * every <= span + 1e-9; ++k) {
        sim.advanceTo(start + k * every);
        looks.push_back(ringProfile(sim, wallRadius));
    }
    return bernoulliCheck(looks, sim);
}

/// RMS particle speed [m/s].
double rmsSpeedOf(const FluidSimulation& sim) {
    double sum = 0;
    for (const Vec3& v : sim.velocities()) sum += double(v.squaredNorm());
    return std::sqrt(sum / double(std::max<size_t>(sim.size(), 1)));
}

/// Runs the pool to t = 1.5 s in quarter-second frames, as ferro-sim steps
/// examples/ferrohydrostatic_pool.toml; the RMS particle speed at the end [m/s]. Issue 29's
/// rest criterion: under 1 mm/s after 1.5 s.
double settleForOneAndAHalfSeconds(FluidSimulation& sim) {
    for (int frame = 1; frame <= 6; ++frame) sim.advanceTo(0.25 * frame);
    return rmsSpeedOf(sim);
}

bool allFinite(const FluidSimulation& sim) {
    for (size_t i = 0; i < sim.size(); ++i)
        if (!sim.positions()[i].allFinite() || !sim.velocities()[i].allFinite()) return false;
    if (const FluidMagnetics* m = sim.magnetics())
        for (size_t i = 0; i < m->field().size(); ++i)
            if (!m->field()[i].allFinite() || !m->magnetization()[i].allFinite()) return false;
    return true;
}

SimScene blobScene(const std::string& magnets, const std::string& law) {
    const std::string text = R"(
[shot]
fps = 30
duration = 0.1
[fluid]
rest_density = 1200
spacing = 0.002
[[fluid.block]]
min = [-0.006, -0.006, 0.01]
max = [0.006, 0.006, 0.02]
[sim]
gravity = [0, 0, 0]
)" + magnets + law;
    return parseSimScene(SceneDocument::parse(text, "blob.toml"));
}

} // namespace

TEST_CASE("the body force model with the external solver is mu0 chi grad(H^2 / 2) and points up the field", "[magnetics]") {
    const double chi = 0.8, rho0 = 1200;
    const SimScene scene = blobScene(R"(
[[magnets]]
kind = "dipole"
position = [0.003, -0.002, -0.01]
direction = [0.3, 0.1, 1.0]
moment = 2.0
)", "[magnetization]\nsusceptibility = 0.8\nsolver = \"external\"\nforce = \"body\"\n");
    FluidMagnetics mag(scene, 8e-9, 0.002);
    REQUIRE(mag.active());
    REQUIRE(mag.magnetic());
    std::vector<Vec3> x = {Vec3(0, 0, 0.01f), Vec3(0.01f, 0.004f, 0.012f), Vec3(-0.02f, 0.01f, 0.03f)};
    mag.update(0.0, x, {}, true);
    std::vector<Vec3> a(x.size(), Vec3::Zero());
    mag.addKelvinAcceleration(a);
    const std::vector<Magnet> magnets = mag.softenedMagnetsAt(0.0);
    for (size_t i = 0; i < x.size(); ++i) {
        // Linear law, curl-free field: mu0 (M . grad) H = mu0 chi grad(|H|^2 / 2).
        const Vec3d p = x[i].cast<double>();
        Vec3d grad;
        const double d = 1e-6;
        for (int k = 0; k < 3; ++k) {
            Vec3d e = Vec3d::Zero();
            e[k] = d;
            grad[k] = (magnetField(magnets, p + e).squaredNorm() - magnetField(magnets, p - e).squaredNorm()) / (4 * d);
        }
        const Vec3d expected = kMu0 * chi * grad / rho0;
        CAPTURE(i, a[i].transpose(), expected.transpose());
        REQUIRE((a[i].cast<double>() - expected).norm() < 1e-4 * expected.norm());
        // A paramagnetic fluid is pulled toward stronger field: here, toward the magnet.
        REQUIRE(a[i].cast<double>().dot(magnets[0].position - p) > 0);
        REQUIRE(mag.field()[i].cast<double>().isApprox(magnetField(magnets, p), 1e-5));
        REQUIRE(mag.magnetization()[i].cast<double>().isApprox(chi * magnetField(magnets, p), 1e-5));
    }
    REQUIRE(mag.maxAcceleration() > 0);
}

TEST_CASE("a uniform applied field exerts no body force, and a non-magnetic fluid feels none", "[magnetics]") {
    const SimScene uniform = blobScene("[[magnets]]\nkind = \"uniform\"\ndirection = [0, 0, 1]\nfield = 20000\n",
                                       "[magnetization]\nsusceptibility = 2\nsaturation = 30000\nsolver = \"external\"\n"
                                       "force = \"body\"\n");
    FluidSimulation sim(uniform);
    REQUIRE(sim.magnetics() != nullptr);
    sim.advanceTo(0.01);
    for (const Vec3& k : sim.magnetics()->kelvinAcceleration()) REQUIRE(k.norm() == 0);
    // Saturating law: |M| = L(H0) < Ms, along the field.
    const double expectedM = langevinMagnetization(20000, 2, 30000);
    for (const Vec3& M : sim.magnetics()->magnetization()) REQUIRE(M.z() == Approx(expectedM).epsilon(1e-5));

    const SimScene inert = blobScene("[[magnets]]\nkind = \"dipole\"\nposition = [0, 0, 0]\nmoment = 5\n", "");
    FluidSimulation still(inert);
    still.advanceTo(0.02);
    REQUIRE_FALSE(still.magnetics()->magnetic());
    double speed = 0;
    for (const Vec3& v : still.velocities()) speed = std::max(speed, double(v.norm()));
    REQUIRE(speed < 1e-6); // no gravity, no field force: the block stays at rest
    // The field is still reported.
    REQUIRE(still.magnetics()->field()[0].norm() > 0);
}

namespace {

/// Phi(H) = integral_0^H M(H') dH' of the Langevin law M = Ms L(3 chi0 H / Ms):
/// (Ms^2 / (3 chi0)) ln(sinh(xi) / xi), xi = 3 chi0 H / Ms. With the external solver the
/// Kelvin force per volume, mu0 (M . grad) H = mu0 grad Phi(|H|) (M parallel to a curl-free
/// H), is the gradient of the potential energy -mu0 Phi(|H|) per volume.
double energyReference(double H, double chi0, double Ms) {
    const double xi = 3 * chi0 * H / Ms;
    const double lnSinhOverXi = xi < 1e-4 ? xi * xi / 6 : xi < 30 ? std::log(std::sinh(xi) / xi)
                                                                  : xi - std::log(2 * xi);
    return Ms * Ms / (3 * chi0) * lnSinhOverXi;
}

} // namespace

TEST_CASE("a blob falling onto a bare magnet pole: finite, pulled toward it, kinetic energy within the magnetic energy released", "[magnetics]") {
    // No container, no gravity: the fluid is pulled onto the dipole itself, whose field
    // is singular there. The simulation regularizes it over one particle spacing.
    const double chi0 = 2, Ms = 30000, rho0 = 1200;
    const Vec3d pole(0, 0, -0.005);
    // The simulation's magnetic pressure F(H) against this file's own formula.
    for (double H : {0.0, 1.0, 300.0, 2500.0, 3e4, 1e6, 1e9})
        REQUIRE(langevinEnergy(H, chi0, Ms) == Approx(energyReference(H, chi0, Ms)).epsilon(1e-7).margin(1e-12));
    const std::string force = GENERATE(std::string("surface"), std::string("body"));
    FluidSimulation sim(blobScene("[[magnets]]\nkind = \"dipole\"\nposition = [0, 0, -0.005]\nmoment = 0.5\n",
                                  "[magnetization]\nsusceptibility = 2\nsaturation = 30000\nsolver = \"external\"\n"
                                  "force = \"" + force + "\"\n"));
    const size_t n = sim.size();
    const double V = sim.particleVolume();
    const std::vector<Magnet> magnets = sim.magnetsNow(); // softened as the particles feel them
    auto state = [&](Vec3d& com, double& potential, double& farthest) {
        com.setZero();
        potential = 0;
        farthest = 0;
        for (size_t i = 0; i < n; ++i) {
            const Vec3d x = sim.positions()[i].cast<double>();
            com += x / double(n);
            farthest = std::max(farthest, (x - pole).norm());
            potential -= kMu0 * V * langevinEnergy(magnetField(magnets, x).norm(), chi0, Ms);
        }
    };
    Vec3d com0, com1;
    double u0, u1, far0, far1;
    state(com0, u0, far0);
    // Internal forces cancel: the centre of mass accelerates with the mean Kelvin
    // acceleration (mu0 / rho0) grad Phi(|H|), which only grows as the blob (all of it above
    // the pole) comes closer; so after t it has fallen at least a0 t^2 / 2.
    double a0 = 0;
    for (size_t i = 0; i < n; ++i) {
        const Vec3d x = sim.positions()[i].cast<double>(), e(0, 0, 1e-7);
        a0 += kMu0 / rho0 * (langevinEnergy(magnetField(magnets, x + e).norm(), chi0, Ms) -
                             langevinEnergy(magnetField(magnets, x - e).norm(), chi0, Ms)) / 2e-7 / double(n);
    }
    REQUIRE(a0 < 0); // down, toward the pole
    const double tFall = std::sqrt(2 * (com0.z() - pole.z()) / -a0); // 40 ms
    double lastZ = com0.z();
    double kinetic = 0, vmax = 0, released = 0;
    for (int k = 1; k <= 10; ++k) {
        sim.advanceTo(0.01 * k);
        REQUIRE(allFinite(sim));
        state(com1, u1, far1);
        kinetic = 0;
        vmax = 0;
        for (const Vec3& v : sim.velocities()) {
            kinetic += 0.5 * rho0 * V * v.squaredNorm();
            vmax = std::max(vmax, double(v.norm()));
        }
        released = u0 - u1;
        CAPTURE(k, kinetic, released, vmax, com1.transpose(), far1);
        // Energy: the Kelvin force is conservative, pressure and viscosity only store or
        // dissipate: the kinetic energy never exceeds the magnetic energy released.
        REQUIRE(released > 0);
        // The experimental surface model breaks this with DFSPH at its 0.02 % density
        // tolerance: at 20 ms, 0.0055 J kinetic against 0.0020 J released, the fastest
        // particle at 6.2 m/s (at 0.1 % it stayed within): its push on a blob that is mostly
        // surface is not a potential force. The body model keeps it throughout.
        if (force == "body") {
            REQUIRE(kinetic <= released);
            // No particle is faster than one that took all the released energy for itself ...
            REQUIRE(0.5 * rho0 * V * vmax * vmax <= released);
            // ... so none gets farther from the pole than it started plus that speed times t.
            REQUIRE(far1 <= far0 + std::sqrt(2 * released / (rho0 * V)) * sim.time());
        }
        if (k == 1) {
            CAPTURE(a0, com0.z() - com1.z(), -0.5 * a0 * sim.time() * sim.time());
            REQUIRE(com0.z() - com1.z() >= -0.5 * a0 * sim.time() * sim.time());
        }
        // It keeps falling at least until it could have reached the pole with a0 alone.
        if (sim.time() <= tFall) REQUIRE(com1.z() < lastZ);
        lastZ = com1.z();
    }
    // The magnet is a solid (sim/sph/MagnetObstacles.hpp): the blob lands on the dipole's
    // body, a sphere of NdFeB of radius magnetBodyRadius (4.6 mm here), and stays on it. No
    // fluid centre comes closer than half a spacing to the body ...
    const double body = magnetBodyRadius(MagnetKind::Dipole, 0.5) + 0.5 * sim.spacing();
    double nearest = 1e30;
    for (const Vec3& p : sim.positions()) nearest = std::min(nearest, (p.cast<double>() - pole).norm());
    CAPTURE(body, nearest, far0, far1);
    REQUIRE(nearest >= body * (1 - 1e-6));
    // ... and with the body model (conservative) the blob gathers on it instead of splashing
    // apart: every particle ends nearer the pole than the farthest started (before the body
    // was solid, the blob fell through the pole and at 0.1 s 112 of its 180 particles were
    // farther than any at the start). The surface model's push is not a potential force
    // and throws a few particles off the body; not asserted.
    if (force == "body") REQUIRE(far1 < far0);
}

// The magnets' fall speed behind WCSPH's sound-speed advice (FluidSimulation::magneticFallSpeed):
// sqrt(2 mu0 dF / rho0), dF the largest difference of the Langevin energy F(H) = int M dH
// across the places the fluid can be at one time of the shot. Reference: the energy F
// evaluated here in closed form, Ms^2 / (3 chi0) ln(sinh(x) / x) with x = 3 chi0 H / Ms (not
// the library's langevinEnergy), over every particle of the fill, with no container (so the
// fill is all the places); for a magnet that approaches, at its last position, where the
// difference is largest.
TEST_CASE("the magnets' fall speed is the fall through the largest energy difference over the fill and the shot", "[magnetics]") {
    SimScene scene = loadExample("ferrohydrostatic_pool.toml", {"shot.duration=1", "shot.fps=4"});
    scene.container.type = ContainerParams::Type::None;
    const double chi0 = scene.magnetization.susceptibility, Ms = scene.magnetization.saturation;
    REQUIRE(Ms > 0);
    const auto energy = [&](double H) {
        const double x = 3 * chi0 * H / Ms;
        return x < 1e-4 ? chi0 * H * H / 2 : Ms * Ms / (3 * chi0) * (x + std::log1p(-std::exp(-2 * x)) - std::log(2 * x));
    };
    const auto expected = [&](const FluidSimulation& sim, Magnet m) {
        m.softening = std::max(m.softening, sim.spacing());
        double lo = 1e300, hi = 0;
        for (const Vec3& p : sim.positions()) {
            const double F = energy(magnetField(m, p.cast<double>()).norm());
            lo = std::min(lo, F);
            hi = std::max(hi, F);
        }
        return std::sqrt(2 * 4e-7 * M_PI * (hi - lo) / sim.restDensity());
    };
    SECTION("a still magnet") {
        const FluidSimulation sim(scene);
        const double v = expected(sim, scene.magnets[0].at(0));
        CAPTURE(v, sim.magneticFallSpeed());
        REQUIRE(v > 1.0);   // the 3 A m^2 dipole 2 cm under the fill: a 1.4 m/s fall (1.8 with the walls)
        REQUIRE(sim.magneticFallSpeed() == Approx(v).epsilon(1e-6));
    }
    SECTION("a magnet that approaches: the head at its closest") {
        MagnetTrack& track = scene.magnets[0];
        MagnetKeyframe far, near;
        far.time = 0;
        far.position = Vec3d(0, 0, -0.06);
        near.time = 1;
        near.position = Vec3d(0, 0, -0.02);
        far.strength = near.strength = track.base.strength;
        track.keys = {far, near};
        const FluidSimulation sim(scene);
        const double vNear = expected(sim, track.at(1)), vFar = expected(sim, track.at(0));
        CAPTURE(vNear, vFar, sim.magneticFallSpeed());
        REQUIRE(vNear > 3 * vFar);
        REQUIRE(sim.magneticFallSpeed() == Approx(vNear).epsilon(1e-6));
    }
    SECTION("in the dish: the walls' fluid side counts, the solid under the floor does not") {
        SimScene dish = loadExample("ferrohydrostatic_pool.toml", {"shot.duration=1", "shot.fps=4"});
        const FluidSimulation sim(dish);
        const FluidSimulation fillOnly(scene);
        // The nearest place fluid can reach is the floor over the magnet, its first layer's
        // centres half a spacing up: F there (0 at best elsewhere) bounds the head from above.
        // The boundary particles half a spacing inside the floor give 21 % more (1.81 against 1.50 m/s).
        Magnet m = dish.magnets[0].at(0);
        m.softening = std::max(m.softening, sim.spacing());
        const double floorZ = dish.container.center.z();
        const double bound = std::sqrt(2 * 4e-7 * M_PI * energy(magnetField(m, Vec3d(0, 0, floorZ + 0.5 * sim.spacing())).norm()) / sim.restDensity());
        const double below = std::sqrt(2 * 4e-7 * M_PI * energy(magnetField(m, Vec3d(0, 0, floorZ - 0.5 * sim.spacing())).norm()) / sim.restDensity());
        CAPTURE(sim.magneticFallSpeed(), fillOnly.magneticFallSpeed(), bound, below);
        REQUIRE(below > 1.1 * bound);   // the two differ enough for the check to tell them apart
        REQUIRE(sim.magneticFallSpeed() > fillOnly.magneticFallSpeed());
        REQUIRE(sim.magneticFallSpeed() <= bound * (1 + 1e-9));
    }
    SECTION("a uniform field holds no head, and no magnet none") {
        scene.magnets[0].base.kind = MagnetKind::Uniform;
        scene.magnets[0].base.strength = 2e4;
        REQUIRE(FluidSimulation(scene).magneticFallSpeed() == 0);
        scene.magnets.clear();
        REQUIRE(FluidSimulation(scene).magneticFallSpeed() == 0);
    }
}

TEST_CASE("a scene without magnets builds no magnetics at all", "[magnetics]") {
    FluidSimulation sim(loadExample("dish.toml", {"fluid.block.0.count=2000"}));
    REQUIRE(sim.magnetics() == nullptr);
    const auto H = sim.fieldById();
    const auto M = sim.magnetizationById();
    REQUIRE(H.size() == sim.size());
    for (size_t i = 0; i < H.size(); ++i) REQUIRE((H[i].norm() == 0 && M[i].norm() == 0));
}

TEST_CASE("paper Fig. 9: the fluid heaps up over the approaching magnet", "[magnetics][slow]") {
    FluidSimulation sim(loadExample("paper_fig9_approach.toml", {"fluid.block.0.count=6000"}));
    const double s = sim.spacing();
    sim.advanceTo(0.3); // settled, the magnet still far
    const double centre0 = surfaceHeight(sim.positionsById(), 0, 0, 0, 0.012);
    const double ring0 = surfaceHeight(sim.positionsById(), 0, 0, 0.03, 0.045);
    REQUIRE(std::abs(centre0 - ring0) < 0.5 * s); // flat to start with
    sim.advanceTo(sim.scene().shot.duration);
    REQUIRE(allFinite(sim));
    const double centre = surfaceHeight(sim.positionsById(), 0, 0, 0, 0.012);
    const double ring = surfaceHeight(sim.positionsById(), 0, 0, 0.03, 0.045);
    CAPTURE(s, centre0, ring0, centre, ring);
    // A heap of millimetres over the magnet: 3.2 mm (1.44 s) with the free-surface curve fit,
    // which keeps a resting pool to the Bernoulli law (the pool tests below); the boundary fit,
    // 40 % too tall at chi0 1.5, made it over 1.5 s.
    REQUIRE(centre > ring + 1.0 * s);
    REQUIRE(centre > centre0 + 0.5 * s);
    // (The rim is not checked: by the end the heap sloshes and the rim's level with it.)
}

// Figs. 10 and 11 are shots, not equilibria (the fluid still moves 10 mm/s when they are
// measured): they check the picture, the ferrohydrostatic balance is checked on a pool at
// rest below ("a pool over a magnet held still ...").
TEST_CASE("paper Fig. 10: the heap flattens again once the field is gone", "[magnetics][slow]") {
    FluidSimulation sim(loadExample("paper_fig10_release.toml", {"fluid.block.0.count=6000"}));
    const double s = sim.spacing();
    sim.advanceTo(1.0);
    const double heap = surfaceHeight(sim.positionsById(), 0, 0, 0, 0.012) -
                        surfaceHeight(sim.positionsById(), 0, 0, 0.03, 0.045);
    REQUIRE(heap > 0.5 * s);   // 2.4 mm at 2.2 mm spacing
    sim.advanceTo(sim.scene().shot.duration);
    REQUIRE(allFinite(sim));
    const double flat = surfaceHeight(sim.positionsById(), 0, 0, 0, 0.012) -
                        surfaceHeight(sim.positionsById(), 0, 0, 0.03, 0.045);
    CAPTURE(s, heap, flat);
    REQUIRE(std::abs(flat) < 0.5 * s);
    for (const Vec3& M : sim.magnetizationById()) REQUIRE(M.norm() < 1e-3);
}

TEST_CASE("paper Fig. 11: two magnets, two heaps, no NaN", "[magnetics][slow]") {
    FluidSimulation sim(loadExample("paper_fig11_two_magnets.toml", {"fluid.block.0.count=6000"}));
    const double s = sim.spacing();
    sim.advanceTo(sim.scene().shot.duration);
    REQUIRE(allFinite(sim));
    const auto x = sim.positionsById();
    const double left = surfaceHeight(x, -0.025, 0, 0, 0.008);
    const double right = surfaceHeight(x, 0.025, 0, 0, 0.008);
    const double rim = surfaceHeight(x, 0, 0, 0.042, 0.05);
    CAPTURE(s, left, right, rim);
    // With the free-surface curve fit (the heaps of the Bernoulli law, see Fig. 9) 1.5 A m^2
    // heaps 0.8 mm at 2.2 mm spacing, 1.0 A m^2 0.4 mm (the boundary fit: 1.7 and 0.6 mm).
    REQUIRE(left > rim + 0.25 * s);
    REQUIRE(right > rim + 0.1 * s);
    REQUIRE(left > right);             // the stronger magnet makes the taller heap
}

TEST_CASE("in a strong field the fluid stays attached: fewer than 0.1% particles leave", "[magnetics][slow]") {
    // A magnet four times the Fig. 9 one, 1 cm under the floor: |H| reaches ~1e5 A/m in
    // the fluid, far past saturation.
    FluidSimulation sim(loadExample("paper_fig9_approach.toml",
                                    {"fluid.block.0.count=6000", "magnets.0.moment=6.0", "magnets.0.keys.0.position=[0,0,-0.01]",
                                     "magnets.0.keys.1.position=[0,0,-0.01]"}));
    sim.advanceTo(1.0);
    REQUIRE(allFinite(sim));
    const auto x = sim.positionsById();
    const double reach = 2 * sim.spacing();
    size_t detached = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        bool attached = false;
        for (size_t j = 0; j < x.size() && !attached; ++j)
            attached = j != i && (x[i] - x[j]).norm() < reach;
        if (!attached) ++detached;
    }
    CAPTURE(detached, x.size());
    REQUIRE(double(detached) < 1e-3 * double(x.size()));
    double Hmax = 0;
    for (const Vec3& H : sim.fieldById()) Hmax = std::max(Hmax, double(H.norm()));
    REQUIRE(Hmax > 5e4);
}

TEST_CASE("the induced field is re-solved by the tolerance rule or every K steps", "[magnetics]") {
    const std::string magnet = "[[magnets]]\nkind = \"dipole\"\nposition = [0, 0, -0.03]\nmoment = 0.2\n";
    SECTION("every K steps") {
        FluidSimulation sim(blobScene(magnet, "[magnetization]\nsusceptibility = 1\nsolver = \"direct\"\nresolve_every = 4\n"));
        sim.resetMagneticsCounters();
        const size_t before = sim.stepCount();
        sim.advanceTo(1.0 / 30);
        const size_t steps = sim.stepCount() - before;
        const MagneticsStats& st = sim.magnetics()->stats();
        CAPTURE(steps, st.solves);
        REQUIRE(st.steps == steps);
        // One solve at the frame start, then one every 4 steps.
        REQUIRE(st.solves == 1 + (steps - 1) / 4);
    }
    SECTION("tolerance: a static magnet and slow fluid need few solves") {
        FluidSimulation sim(blobScene(magnet, "[magnetization]\nsusceptibility = 1\nsolver = \"direct\"\ntolerance = 0.05\n"));
        sim.resetMagneticsCounters();
        sim.advanceTo(1.0 / 30);
        const MagneticsStats& st = sim.magnetics()->stats();
        CAPTURE(st.steps, st.solves);
        REQUIRE(st.solves >= 1);
        REQUIRE(st.solves < st.steps);
    }
}

TEST_CASE("particle files carry H, M and the magnets at the frame's time, and resume is exact", "[magnetics][cli][slow]") {
    // The free-surface curve remembers its last fits (FluidMagnetics::kCurveMemory), so the
    // files carry the curve (magnetization_curve) for the resume.
    const std::string fit = "free_surface";
    const std::string sim = std::string(FERRO_BINARY_DIR) + "/bin/ferro-sim";
    const fs::path dir = fs::temp_directory_path() / ("ferro_test_mag_" + std::to_string(getpid()));
    fs::remove_all(dir);
    const std::string common = sim + " " + example("paper_fig9_approach.toml") +
                               " --set fluid.block.0.count=3000 --set shot.preroll=0 --set magnetization.curve_fit=\\\"" + fit +
                               "\\\" --quiet --out ";
    REQUIRE(std::system((common + (dir / "full").string() + " --max-frames 4").c_str()) == 0);
    REQUIRE(std::system((common + (dir / "part").string() + " --max-frames 2").c_str()) == 0);
    REQUIRE(std::system((common + (dir / "part").string() + " --max-frames 4 --resume").c_str()) == 0);

    const SimScene scene = loadExample("paper_fig9_approach.toml", {"fluid.block.0.count=3000"});
    const ParticleTable t = readParticleFile((dir / "full" / "particles_0003.ply").string());
    for (const char* col : {"hx", "hy", "hz", "mx", "my", "mz"}) REQUIRE(t.column(col) >= 0);
    const std::vector<Magnet> magnets = readMagnetComments(t);
    REQUIRE(magnets.size() == 1);
    const Magnet expected = scene.magnets[0].at(3.0 / 30);
    REQUIRE(magnets[0].position.isApprox(expected.position, 1e-7));
    REQUIRE(magnets[0].strength == Approx(expected.strength));
    REQUIRE(t.commentNumber("susceptibility", 0) == Approx(1.5));
    REQUIRE(t.commentNumber("saturation", 0) == Approx(35000));
    REQUIRE(t.comment("magnetization_curve").empty() == (fit == "boundary"));
    const auto x = t.vec3("x", "y", "z");
    const auto H = t.vec3("hx", "hy", "hz");
    const auto M = t.vec3("mx", "my", "mz");
    for (size_t i = 0; i < x.size(); ++i) {
        REQUIRE(M[i].norm() <= 35000);
        REQUIRE(H[i].norm() > 0);
        // M along H, with |M| = L(|H|).
        REQUIRE(M[i].dot(H[i]) >= 0.999f * M[i].norm() * H[i].norm());
        REQUIRE(M[i].norm() == Approx(langevinMagnetization(H[i].norm(), 1.5, 35000)).epsilon(1e-3));
    }

    const ParticleTable a = readParticleFile((dir / "full" / "particles_0004.ply").string());
    const ParticleTable b = readParticleFile((dir / "part" / "particles_0004.ply").string());
    REQUIRE(a.values.size() == b.values.size());
    double worst = 0;
    for (size_t k = 0; k < a.values.size(); ++k)
        worst = std::max(worst, double(std::abs(a.values[k] - b.values[k])) / (std::abs(double(a.values[k])) + 1e-3));
    REQUIRE(worst < 1e-5);
    if (fit == "free_surface") {
        // A curve comment that is no curve: a one-line error, and the frames stay as they were.
        ParticleTable bad = readParticleFile((dir / "part" / "particles_0004.ply").string());
        bad.setComment("magnetization_curve", "4356 14074 0.3 nan 0.5 -11 1.03");
        writeParticleFile((dir / "part" / "particles_0004.ply").string(), bad);
        const test::CommandResult r = test::runCommand(common + (dir / "part").string() + " --max-frames 5 --resume");
        CAPTURE(r.output);
        REQUIRE(r.code != 0);
        REQUIRE(r.output.find("magnetization_curve") != std::string::npos);
        REQUIRE(std::count(r.output.begin(), r.output.end(), '\n') <= 1);
        REQUIRE_FALSE(fs::exists(dir / "part" / "particles_0005.ply"));
        // After a pre-roll, frame 0 carries the pre-roll's curve, its fit time on the shot's
        // clock (the pre-roll ends at t = 0): the first frame's fit leans on it.
        const std::string pre = common + (dir / "pre").string() + " --max-frames 0";
        REQUIRE(std::system((pre.substr(0, pre.find(" --quiet")) + " --set shot.preroll=0.1" + pre.substr(pre.find(" --quiet"))).c_str()) == 0);
        const ParticleTable f0 = readParticleFile((dir / "pre" / "particles_0000.ply").string());
        const ParticleTable cache = readParticleFile((dir / "pre" / "preroll.ply").string());
        auto numbers = [](const std::string& line) {
            std::istringstream in(line);
            std::vector<double> v(7);
            for (double& d : v) REQUIRE(in >> d);
            return v;
        };
        CAPTURE(f0.comment("magnetization_curve"), cache.comment("magnetization_curve"));
        const std::vector<double> frame0 = numbers(f0.comment("magnetization_curve"));
        const std::vector<double> settled = numbers(cache.comment("magnetization_curve"));
        const double preroll = cache.commentNumber("preroll_time", 0);
        REQUIRE(preroll > 0.05);
        for (int k = 0; k < 6; ++k) REQUIRE(frame0[size_t(k)] == settled[size_t(k)]);
        REQUIRE(frame0[6] == Approx(settled[6] - preroll).margin(1e-12));
        REQUIRE(settled[6] > 0);
        // A pre-roll cache without the curve (written before 2026-12-02): frame 0 carries none
        // (the first fit starts afresh), and a run resumed from frame 0 goes on.
        ParticleTable old = cache;
        old.setComment("magnetization_curve", "");
        writeParticleFile((dir / "old.ply").string(), old);
        const std::string fromOld = pre.substr(0, pre.find(" --quiet")) + " --set shot.preroll=0.1 --preroll-cache " +
                                    (dir / "old.ply").string() + " --quiet --out " + (dir / "old").string();
        REQUIRE(std::system((fromOld + " --max-frames 0").c_str()) == 0);
        REQUIRE(readParticleFile((dir / "old" / "particles_0000.ply").string()).comment("magnetization_curve").empty());
        REQUIRE(std::system((fromOld + " --max-frames 1 --resume").c_str()) == 0);
        REQUIRE_FALSE(readParticleFile((dir / "old" / "particles_0001.ply").string()).comment("magnetization_curve").empty());
    }
    fs::remove_all(dir);
}


// Issue 13: a 3 A m^2 dipole held 2 cm under the floor pulls the fluid with 20-30 g.
// DFSPH's density solve used to clamp its source at rest density, which asked the pressure
// to leave expanded particles' density unchanged instead of leaving them without pressure:
// pressure built up in expanding fluid and pumped it (this half-size dish at the paper's
// spacing: 90-100 mm/s RMS for good; the full dish 30-40 mm/s). WCSPH settled all along.
// At rest the heap must then stand in ferrohydrostatic balance along its surface.
namespace {

struct RestingPoolCase {
    std::string solver, magnetization;
    double susceptibility;
    std::string curveFit = "free_surface";   // the default
};

void checkRestingPool(const RestingPoolCase& c)
{
    // examples/ferrohydrostatic_pool.toml: 2,560 particles, a 3 A m^2 dipole 2 cm under the floor.
    FluidSimulation sim(loadExample("ferrohydrostatic_pool.toml",
                                    {"sim.solver=\"" + c.solver + "\"", "magnetization.solver=\"" + c.magnetization + "\"",
                                     "magnetization.susceptibility=" + std::to_string(c.susceptibility),
                                     "magnetization.curve_fit=\"" + c.curveFit + "\""}));
    REQUIRE(sim.magnetics() != nullptr);
    double rms = 0;
    for (int frame = 1; frame <= 8; ++frame) {   // 4 frames a second, as ferro-sim would step them
        sim.advanceTo(0.25 * frame);
        rms = rmsSpeedOf(sim);
        if (frame == 1) REQUIRE(sim.magnetics()->maxAcceleration() > 30);   // over 3 g (40-50 with the free-surface fit): a strong pull
    }
    REQUIRE(allFinite(sim));
    // From 4 mm inside the wall (clear of the meniscus) to the centre.
    const SurfaceBalance heap = surfaceBalance(sim, Vec2d(0.021, 0), Vec2d(0, 0));
    CAPTURE(c.solver, c.magnetization, c.susceptibility, c.curveFit, rms, sim.spacing(), heap.rise, heap.predicted);
    // Measured 2026-12-04, RMS speed as the mean of the frames from 1.25 to 2 s: DFSPH 0.96
    // (external), 0.73 / 0.80 (auto, chi0 0.5 / 1.5), WCSPH 0.75 / 0.75 mm/s; DFSPH auto chi0 1.5
    // frame by frame 0.96, 0.80, 0.74, 0.71. Close to the bound, and chaotic in the last bits: with fused
    // multiply-adds in the pressure sweeps (tried for sim/sph/sweeps, not kept) DFSPH auto chi0
    // 1.5 read 1.29 at 2 s and 0.9-1.2 in the frames before; the self-consistent force changes
    // in steps at each re-solve of the particles' field, and the coarse pool answers with kicks
    // (single frames to 10 mm/s; with magnetization.tolerance 0.002, 0.74-1.04 mm/s from 1.25 s).
    // An open lead (issue 29's note); the sweeps keep these bits on every processor
    // (test_PressureSweeps.cpp).
    REQUIRE(rms < 0.001);
    if (c.magnetization == "external") {
        // Reference: rho g dz = mu0 dF, the analytic force's line integral along the surface
        // (surfaceBalance; measured within 2 %).
        REQUIRE(heap.predicted > sim.spacing());
        REQUIRE(std::abs(heap.rise - heap.predicted) < 0.1 * heap.predicted);
    } else {
        // The self-consistent solve: the heap against the ferrohydrostatic Bernoulli law
        // (Rosensweig ch. 5) with the particles' own H and M at the surface, traction included.
        // Reference: that law. Bound: 20 % / 40 % of the rise on this coarse pool (measured
        // 9.5 %, 32 % DFSPH, 5.6 % WCSPH, looks scattering +-10 %): the resolution's, not an
        // accuracy claim; the claim is the 10,240-particle pool's 10 % below. Measurements:
        // docs/physics/magnetization.md, "Tested accuracy".
        const BernoulliCheck law = bernoulliCheckOverTime(sim, 0.025);
        WARN("Bernoulli along the surface (" << c.solver << ", chi0 " << c.susceptibility << ", curve fit " << c.curveFit << "): centre rise "
             << law.rise << " Pa, worst deviation " << law.worst << " Pa, with the capillary term "
             << law.worstCapillary << " Pa; on the axis mu0 F = " << law.pressure << " Pa, mu0 Mn^2/2 = "
             << law.traction << " Pa, sigma div n = " << law.capillary << " Pa; RMS speed " << 1e3 * rms << " mm/s");
        REQUIRE(law.traction > 0.2 * law.pressure);   // the traction term matters here
        REQUIRE(law.worst < (c.susceptibility < 1 ? 0.20 : 0.40) * law.rise);
    }
}

} // namespace

// Since 2026-12-05 the suite runs four of the five cases, to buy back suite time: WCSPH with
// the analytic (external) field stays a hidden case, ferro_sph_tests "[.wcsph-external]";
// WCSPH is held by its self-consistent case, the analytic force by DFSPH's.
TEST_CASE("a pool over a magnet held still comes to rest in ferrohydrostatic balance (DFSPH and WCSPH)", "[magnetics][slow]") {
    checkRestingPool(GENERATE(RestingPoolCase{"dfsph", "external", 1.5}, RestingPoolCase{"dfsph", "auto", 0.5},
                              RestingPoolCase{"dfsph", "auto", 1.5}, RestingPoolCase{"wcsph", "auto", 1.5}));
}

TEST_CASE("a pool over a magnet held still comes to rest in ferrohydrostatic balance (WCSPH, analytic field)",
          "[magnetics][slow][.wcsph-external]") {
    checkRestingPool(RestingPoolCase{"wcsph", "external", 1.5});
}

// Issue 29: at fine spacing a pool over the same magnet never came to rest (a 12.5 mm dish at
// 0.75 mm: 29-36 mm/s RMS for 1.5 s, floor particles at 0.4-0.75 m/s, the same pool without
// the magnet at 0.2 mm/s). The cause was the step: the force criterion took the kernel's
// support for Monaghan's smoothing length, so the magnet's 31 g pull at the floor moved a
// particle 1/8 spacing a step before pressure answered, past what the DFSPH step takes
// (sim/sph/FluidSimulation.cpp, chooseTimeStep). The same fluid and dipole in a 6 mm dish at
// 0.75 mm (2,236 particles), `external` (a conservative force: what moves is the solver's).
TEST_CASE("a pool at fine spacing over a strong magnet comes to rest (DFSPH and WCSPH)", "[magnetics][slow]") {
    constexpr int kFinePoolFrames = 10;   // 1 s: the old step had it at 44-59 mm/s RMS by then
    struct Case {
        std::string solver, iteration;
        double tolerance;   // sim.max_density_error
    };
    // DFSPH's Jacobi at its default tolerance, DFSPH's conjugate gradients at a tenth of it
    // (sim.pressure_iteration = "cg"), WCSPH.
    const Case c = GENERATE(Case{"dfsph", "jacobi", 0.0002}, Case{"dfsph", "cg", 0.00002}, Case{"wcsph", "jacobi", 0.0002});
    FluidSimulation sim(loadExample("ferrohydrostatic_pool.toml",
                                    {"sim.solver=\"" + c.solver + "\"", "magnetization.solver=\"external\"",
                                     "sim.pressure_iteration=\"" + c.iteration + "\"",
                                     "sim.max_density_error=" + std::to_string(c.tolerance),
                                     "fluid.block.0.radius=0.006", "container.radius=0.006", "fluid.block.0.count=0",
                                     "fluid.spacing=0.00075"}));
    REQUIRE(sim.spacing() == Approx(0.00075).epsilon(0.02));
    size_t lateCaps = 0;
    for (int frame = 1; frame <= kFinePoolFrames; ++frame) {
        sim.advanceTo(0.1 * frame);
        if (frame == 1) REQUIRE(sim.magnetics()->maxAcceleration() > 200);   // over 20 g at the floor
        if (frame > kFinePoolFrames / 2) lateCaps += sim.frameSolverCaps().densityAtCap;
    }
    const double rms = rmsSpeedOf(sim);
    double fastest = 0, compression = 0;
    for (const Vec3& v : sim.velocities()) fastest = std::max(fastest, double(v.norm()));
    for (Real rho : sim.densities()) compression += std::max(0.0, double(rho) / sim.restDensity() - 1);
    compression /= double(sim.size());
    CAPTURE(c.solver, c.iteration, rms, fastest, compression, lateCaps, sim.runSolverCaps().steps);
    REQUIRE(allFinite(sim));
    REQUIRE(rms < 0.001);       // under 1 mm/s RMS
    REQUIRE(fastest < 0.01);    // and no particle faster than 10 mm/s
    if (c.iteration == "cg") {
        // Conjugate gradients reach their tolerance at every step of the settled pool (relaxed
        // Jacobi stops at its cap of 100 sweeps in nearly all of them here, 2,351 of 2,421 steps,
        // short of its ten times looser tolerance), and the particles' own SPH densities carry
        // a mean compression within twice the tolerance (measured 0.0011 %).
        REQUIRE(lateCaps == 0);
        REQUIRE(compression < 2 * c.tolerance);
    }
}

// The same pool and law at four times the particles (10,240, spacing 1.6x finer): settled for
// 1.5 s, then the Bernoulli law on the mean of 11 looks over 1.5-2.0 s, the surface half a
// spacing out from the column tops (ringProfile). 
static BernoulliCheck finePoolBernoulli(double chi0, const std::string& fit, double& rms) {
    FluidSimulation sim(loadExample("ferrohydrostatic_pool.toml",
                                    {"fluid.block.0.count=10240", "magnetization.susceptibility=" + std::to_string(chi0),
                                     "magnetization.curve_fit=\"" + fit + "\""}));
    rms = settleForOneAndAHalfSeconds(sim);
    REQUIRE(allFinite(sim));
    const BernoulliCheck law = bernoulliCheckOverTime(sim, 0.025);
    WARN("Bernoulli, 10,240 particles, chi0 " << chi0 << ", curve fit " << fit << ": centre rise " << law.rise << " Pa, worst deviation "
         << law.worst << " Pa (" << 100 * law.worst / law.rise << " %), with the capillary term " << law.worstCapillary
         << " Pa (" << 100 * law.worstCapillary / law.rise << " %); on the axis mu0 F = " << law.pressure
         << " Pa, mu0 Mn^2/2 = " << law.traction << " Pa, sigma div n = " << law.capillary << " Pa; RMS speed "
         << 1e3 * rms << " mm/s");
    return law;
}

// Issue 13's must-show on the pool at 10,240 particles with the default (free-surface) curve
// fit, ~2 CPU minutes a case. Reference: the ferrohydrostatic Bernoulli law; bound: the
// issue's 10 % of the rise (measured 3.0 % and 5.8 % at chi0 0.5 and 1.5 after 1.5 s of
// settling, RMS speed 0.62 and 0.72 mm/s; 4.4 % and 4.5 % after 2 s: docs/physics/
// magnetization.md, "Tested accuracy"). Since 2026-12-05 the suite runs chi0 1.5 only, the
// case where the traction matters most and the law is met by the narrower margin, to buy
// back suite time; chi0 0.5 stays held on the 2,560-particle pool above and runs here with
// the hidden tag: ferro_sph_tests "[.chi0-0.5]".
TEST_CASE("a finer pool over a still magnet keeps to the Bernoulli law within 10 % of its rise (chi0 1.5)",
          "[magnetics][slow]") {
    const double chi0 = 1.5;
    double rms = 0;
    const BernoulliCheck law = finePoolBernoulli(chi0, "free_surface", rms);
    REQUIRE(rms < 0.001);
    REQUIRE(law.traction > 0.2 * law.pressure);   // the traction term matters here
    REQUIRE(law.worst < 0.10 * law.rise);
}

TEST_CASE("a finer pool over a still magnet keeps to the Bernoulli law within 10 % of its rise (chi0 0.5)",
          "[magnetics][slow][.chi0-0.5]") {
    double rms = 0;
    const BernoulliCheck law = finePoolBernoulli(0.5, "free_surface", rms);
    REQUIRE(rms < 0.001);
    REQUIRE(law.traction > 0.2 * law.pressure);
    REQUIRE(law.worst < 0.10 * law.rise);
}

namespace {

/// Particles with no other particle within the SPH support radius: nothing holds them to
/// the fluid (no density, pressure or tension neighbour), they have left it.
size_t detachedCount(const std::vector<Vec3>& x, double support) {
    size_t lonely = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        bool attached = false;
        for (size_t j = 0; j < x.size() && !attached; ++j) attached = j != i && (x[i] - x[j]).norm() < support;
        if (!attached) ++lonely;
    }
    return lonely;
}

/// The free surface as a height field: in each column (square cells one spacing wide,
/// centred on the seed lattice's columns, which sit on multiples of the spacing) the highest
/// particle centre, averaged over blocks of 3 x 3 columns. Single column tops jitter by
/// ~0.45 spacing RMS on a disordered SPH surface at rest with no force at all (the top
/// particle of a column changes as particles shuffle); a 3.6 mm block still resolves a
/// pattern of peaks at lambda_c = 9.2 mm. Blocks whose centre lies within `radius` of the
/// axis, with at least 8 of their 9 columns present.
std::map<std::pair<int, int>, double> surfaceBlocks(const std::vector<Vec3>& x, double s, double radius) {
    std::map<std::pair<int, int>, double> top;
    for (const Vec3& p : x) {
        const std::pair<int, int> key(int(std::floor(p.x() / s + 0.5)), int(std::floor(p.y() / s + 0.5)));
        const auto it = top.find(key);
        if (it == top.end() || p.z() > it->second) top[key] = double(p.z());
    }
    std::map<std::pair<int, int>, std::pair<double, int>> sum;
    for (const auto& [key, z] : top) {
        const std::pair<int, int> block(int(std::floor(key.first / 3.0 + 0.5)), int(std::floor(key.second / 3.0 + 0.5)));
        sum[block].first += z;
        ++sum[block].second;
    }
    std::map<std::pair<int, int>, double> out;
    for (const auto& [block, zn] : sum)
        if (zn.second >= 8 && std::hypot(3 * block.first * s, 3 * block.second * s) <= radius) out[block] = zn.first / zn.second;
    return out;
}

} // namespace

// Issue 13: below the critical field (Rosensweig's M_c; examples/rosensweig_uniform.toml's
// header: 10.42 kA/m applied) a flat layer in a uniform normal field stays flat and
// attached, with the force model the code runs by default (force = "body" with the
// self-consistent solve: mu0 M_f(|H_magnets|) grad|H_magnets| / rho0). In a uniform field
// grad|H_magnets| = 0, so that force is exactly zero: what this holds is that nothing else
// in a magnetic step (the self-consistent solve of the layer's own field, the demagnetization
// curve's fit, the re-solve rule) disturbs a layer that has no reason to move. The
// experimental force = "surface" model, which does carry the layer's own traction, is not
// held here: in a finite dish it drives the layer to the rim even below the critical field
// (measured: docs/physics/magnetics.md section).
// The example's depth, fluid and field direction, its dish cut to a 1.77 cm radius and
// 2,560 particles (spacing 1.46 mm instead of 1.24 mm: 6.8 layers in the 1 cm depth) to keep
// the case under a minute of CPU (26 s measured); 0.8 x the critical field; 2 s, the
// example's duration. Reference: below M_c a flat layer is stable (Rosensweig's linear
// stability) and the body force is exactly zero; bound: flat to a quarter spacing, as the
// resting dish (measured 0.009 spacing RMS, the layer 1.1 spacings lower on average from the
// lattice settling, no particle detached).
TEST_CASE("below the critical field a flat layer in a uniform field stays flat and attached", "[magnetics][slow]") {
    const double radius = 0.0177;
    FluidSimulation sim(loadExample("rosensweig_uniform.toml",
                                    {"fluid.block.0.radius=" + std::to_string(radius), "container.radius=" + std::to_string(radius),
                                     "fluid.block.0.count=2560", "magnets.0.field=8340"}));
    REQUIRE(sim.magnetics() != nullptr);
    const double s = sim.spacing();
    // Blocks from the axis to 4 spacings inside the wall: the meniscus at the wall is
    // surface tension's, not the field's.
    const auto before = surfaceBlocks(sim.positionsById(), s, radius - 4 * s);
    REQUIRE(before.size() > 15);
    sim.advanceTo(2.0);
    REQUIRE(allFinite(sim));
    const auto x = sim.positionsById();
    const auto after = surfaceBlocks(x, s, radius - 4 * s);
    // The change of the surface's shape: the RMS of the height change about its mean. The
    // mean change is the seed lattice's top layer settling into the packing, ~0.75 spacing
    // down within 0.1 s whatever the field (measured with no magnetic force at all); a layer
    // that sinks evenly is still flat.
    std::vector<double> change;
    for (const auto& [key, z] : after)
        if (const auto it = before.find(key); it != before.end()) change.push_back(z - it->second);
    REQUIRE(change.size() > 0.9 * double(before.size()));
    double mean = 0, sum2 = 0;
    for (double d : change) mean += d / double(change.size());
    for (double d : change) sum2 += (d - mean) * (d - mean);
    const double rmsChange = std::sqrt(sum2 / double(change.size()));
    const size_t detached = detachedCount(x, sim.supportRadius());
    double Hmax = 0;
    for (const Vec3& H : sim.fieldById()) Hmax = std::max(Hmax, double(H.norm()));
    CAPTURE(s, rmsChange / s, mean / s, detached, Hmax, rmsSpeedOf(sim));
    REQUIRE(Hmax > 3000);   // the field is on: inside a wide flat layer H0 / (1 + chi0) = 3.3 kA/m, more at the edge
    REQUIRE(detached == 0);
    REQUIRE(rmsChange < 0.25 * s);
}

// Tips carried by the flow (spikes.response_time, SurfaceFlow.hpp): the offset from the lattice
// site against the closed-form solutions of dd/dt = u - dL/dt - d / tau, and ferro-spikes
// reading the flow from earlier frames' particle files.
#include "SpikeTestMeshes.hpp"
#include "sim/core/Constants.hpp"

#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "spikes/SpikeFrames.hpp"
#include "spikes/SurfaceFlow.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

using namespace ferro;

namespace {

// Particles on a 2 mm grid over a 4 cm square, 1 cm deep (the history's own particles).
std::vector<Vec3d> gridParticles()
{
    std::vector<Vec3d> x;
    for (int i = -10; i <= 10; ++i)
        for (int j = -10; j <= 10; ++j)
            for (int k = 0; k <= 5; ++k) x.emplace_back(0.002 * i, 0.002 * j, 0.002 * k);
    return x;
}

// A history sampled every dt from 0 to tEnd [s], every particle moving at u(t); the magnets
// (in the samples' headers) at magnets(t); every particle's |M| M(t) [A/m] (none without it).
SurfaceFlowHistory syntheticHistory(double dt, double tEnd, const std::function<Vec3d(double)>& u,
                                    const std::function<std::vector<Magnet>(double)>& magnets = {},
                                    const std::function<double(double)>& M = {})
{
    const std::vector<Vec3d> x = gridParticles();
    std::vector<FlowSample> samples;
    for (int k = 0; k * dt <= tEnd + 1e-12; ++k) {
        FlowSample s;
        s.time = k * dt;
        s.velocity.assign(x.size(), u(s.time));
        s.radius = 0.004;
        s.grid = std::make_unique<HashGrid>(x, s.radius);
        if (magnets) s.magnets = magnets(s.time);
        if (M) s.magnetization.assign(x.size(), M(s.time));
        samples.push_back(std::move(s));
    }
    return SurfaceFlowHistory(std::move(samples));
}

} // namespace

TEST_CASE("response_time: the carried offset solves dd/dt = u - dL/dt - d/tau (constant and oscillating flow, a sliding site)",
          "[spikes][flow]")
{
    const Vec3d n(0, 0, 1), site(0.001, -0.002, 0.01);
    const double tau = 0.2;
    SECTION("a steady flow: d = u tau (1 - e^(-t/tau)), its normal part dropped")
    {
        const Vec3d u(0.01, -0.004, 0.003);
        const SurfaceFlowHistory h = syntheticHistory(0.05, 1.0, [&](double) { return u; });
        const Vec3d along(0.01, -0.004, 0);
        for (double t : {0.1, 0.4, 1.0}) {
            const Vec3d expected = along * tau * (1 - std::exp(-t / tau));
            INFO("t = " << t);
            REQUIRE((h.carriedOffset(site, n, -1, tau, t) - expected).norm() < 1e-12);
        }
        // Past the last sample the flow holds: t = 1.3 continues the same curve.
        REQUIRE((h.carriedOffset(site, n, -1, tau, 1.3) - along * tau * (1 - std::exp(-1.3 / tau))).norm() < 1e-12);
    }
    SECTION("a sloshing flow u = U sin(w t): the driven, damped response, transient included")
    {
        const double U = 0.02, w = 2 * kPi / 0.5;   // a 0.5 s slosh
        const SurfaceFlowHistory h =
            syntheticHistory(1.0 / 120, 2.0, [&](double t) { return Vec3d(U * std::sin(w * t), 0, 0); });
        const double a = U * tau / (1 + w * w * tau * tau);
        const double amplitude = U * tau / std::sqrt(1 + w * w * tau * tau);
        for (double t = 0.1; t <= 2.0; t += 0.1) {
            const double exact = a * (std::sin(w * t) - w * tau * std::cos(w * t) + w * tau * std::exp(-t / tau));
            INFO("t = " << t);
            // Linear interpolation between samples 1/120 s apart: (w dt)^2 / 8 = 0.14 %.
            REQUIRE(std::abs(h.carriedOffset(site, n, -1, tau, t).x() - exact) < 0.005 * amplitude);
        }
        // The tips lag the flow by atan(w tau) and move with a fraction 1 / sqrt(1 + (w tau)^2)
        // of its amplitude: a response time long against the slosh lets them ride it.
    }
    SECTION("a magnet sliding at V with the fluid still: the tips trail by V tau (1 - e^(-t/tau))")
    {
        const Vec3d V(0.05, 0.02, 0);
        auto magnets = [&](double t) {
            Magnet m;
            m.kind = MagnetKind::Dipole;
            m.position = Vec3d(-0.02, 0, -0.01) + V * t;
            m.strength = 1;
            return std::vector<Magnet>{m};
        };
        const SurfaceFlowHistory h = syntheticHistory(0.05, 1.0, [](double) { return Vec3d::Zero(); }, magnets);
        for (double t : {0.2, 0.6, 1.0})
            REQUIRE((h.carriedOffset(site, n, 0, tau, t) + V * tau * (1 - std::exp(-t / tau))).norm() < 1e-12);
        // A uniform field's pattern does not move with its "position".
        auto uniform = [&](double t) {
            std::vector<Magnet> m = magnets(t);
            m[0].kind = MagnetKind::Uniform;
            return m;
        };
        const SurfaceFlowHistory still = syntheticHistory(0.05, 1.0, [](double) { return Vec3d::Zero(); }, uniform);
        REQUIRE(still.carriedOffset(site, n, 0, tau, 1.0).norm() == 0);
    }
    SECTION("the field's hold: none lets the flow carry the tip freely, a partial one pulls at hold / tau, and it lets go when the field falls")
    {
        const Vec3d u(0.01, -0.004, 0);
        const SurfaceFlowHistory h = syntheticHistory(0.05, 1.0, [&](double) { return u; }, {},
                                                      [](double t) { return t < 0.375 ? 10000.0 : 1000.0; });
        // The hold as the spikes' height curve gives it: here 1 above 5 kA/m, else `low`.
        for (double low : {0.0, 0.5}) {
            auto hold = [low](double M) { return M > 5000 ? 1.0 : low; };
            // Held fully up to the sample at 0.35 s: d = u tau (1 - e^(-t/tau)), and so on to
            // the next sample (past the last sample taken the flow and the hold hold). Over
            // the sample interval [0.35, 0.4] the rate is the mean of its ends' holds,
            // (1 + low) / (2 tau); from 0.4 s on it is low / tau (the exact solutions of
            // dd/dt = u - kappa d).
            auto relax = [&](double d, double kappa, double dt) {
                return kappa > 0 ? d * std::exp(-kappa * dt) + (1 - std::exp(-kappa * dt)) / kappa : d + dt;
            };
            const double d035 = tau * (1 - std::exp(-0.35 / tau));
            const double d04 = relax(d035, (1 + low) / (2 * tau), 0.05);
            for (double t : {0.2, 0.375, 0.4, 0.7, 1.0}) {
                const double expected = t < 0.399 ? tau * (1 - std::exp(-t / tau)) : relax(d04, low / tau, t - 0.4);
                INFO("hold " << low << " after the fall, t = " << t);
                REQUIRE((h.carriedOffset(site, n, -1, tau, t, hold) - u * expected).norm() < 1e-12);
            }
        }
        // Without a hold, or at samples without magnetization, the pull is the full 1 / tau.
        const SurfaceFlowHistory bare = syntheticHistory(0.05, 1.0, [&](double) { return u; });
        REQUIRE((bare.carriedOffset(site, n, -1, tau, 1.0, [](double) { return 0.0; }) -
                 u * tau * (1 - std::exp(-1.0 / tau))).norm() < 1e-12);
        REQUIRE((h.carriedOffset(site, n, -1, tau, 1.0) - u * tau * (1 - std::exp(-1.0 / tau))).norm() < 1e-12);
        // A flow growing linearly, u = a t, under a constant partial hold s: kappa = s / tau,
        // d = (a / kappa) (t - (1 - e^(-kappa t)) / kappa); a hold of 1e-7 takes the series
        // (kappa dt < 1e-4): d = a t^2 / 2 - kappa a t^3 / 6 + ...
        const Vec3d a(0.02, 0.01, 0);
        const SurfaceFlowHistory ramp = syntheticHistory(0.05, 1.0, [&](double t) { return a * t; }, {},
                                                         [](double) { return 1000.0; });
        for (double s : {0.5, 1e-7})
            for (double t : {0.3, 1.0}) {
                const double kappa = s / tau;
                const double expected = s > 1e-3 ? (t - (1 - std::exp(-kappa * t)) / kappa) / kappa
                                                 : t * t / 2 - kappa * t * t * t / 6;
                INFO("hold " << s << ", t = " << t);
                REQUIRE((ramp.carriedOffset(site, n, -1, tau, t, [s](double) { return s; }) - a * expected).norm() <
                        1e-12);
            }
        // Before the field first holds a tip there is no spike to carry: a field that holds
        // only from the sample at 0.5 s on starts the offset at 0 at the sample before it
        // (the interval [0.45, 0.5] at the mean rate 1 / (2 tau), then 1 / tau).
        const SurfaceFlowHistory late = syntheticHistory(0.05, 1.0, [&](double) { return u; }, {},
                                                         [](double t) { return t < 0.475 ? 1000.0 : 10000.0; });
        auto full = [](double M) { return M > 5000 ? 1.0 : 0.0; };
        REQUIRE(late.carriedOffset(site, n, -1, tau, 0.4, full).norm() == 0);
        const double k1 = 0.5 / tau, d05 = (1 - std::exp(-k1 * 0.05)) / k1;
        for (double t : {0.7, 1.0}) {
            const double expected = d05 * std::exp(-(t - 0.5) / tau) + tau * (1 - std::exp(-(t - 0.5) / tau));
            INFO("t = " << t);
            REQUIRE((late.carriedOffset(site, n, -1, tau, t, full) - u * expected).norm() < 1e-12);
        }
        // Sloshing once the field has let go (it held only at the first sample): the tip
        // rides the flow, d = integral of u (a sine's integral; sampled at 120 Hz, linear
        // interpolation misses by t dt^2 U w^2 / 12, about 0.2 % of U / w by 0.3 s).
        const double U = 0.02, w = 2 * kPi / 0.5;
        const SurfaceFlowHistory slosh = syntheticHistory(1.0 / 120, 1.0, [&](double t) { return Vec3d(U * std::sin(w * t), 0, 0); },
                                                          {}, [](double t) { return t < 1e-9 ? 10000.0 : 1000.0; });
        for (double t : {0.3, 0.55, 0.9}) {
            const double exact = U / w * (1 - std::cos(w * t));
            INFO("t = " << t);
            REQUIRE(std::abs(slosh.carriedOffset(site, n, -1, tau, t, full).x() - exact) < 0.005 * U / w);
        }
    }
    SECTION("samples after t do not count")
    {
        const SurfaceFlowHistory full = syntheticHistory(0.05, 1.0, [](double t) { return Vec3d(0.01 * t, 0, 0); });
        const SurfaceFlowHistory cut = syntheticHistory(0.05, 0.5, [](double t) { return Vec3d(0.01 * t, 0, 0); });
        REQUIRE((full.carriedOffset(site, n, -1, tau, 0.5) - cut.carriedOffset(site, n, -1, tau, 0.5)).norm() < 1e-15);
    }
}

namespace {

constexpr double kR = 0.03, kDepth = 0.01;

// A flat dish of ferrofluid in a uniform 15 kA/m field (alpha 100 A: tips 6.7 mm apart).
SpikeScene flowScene(double responseTime)
{
    std::ostringstream s;
    s << "[[magnets]]\nkind = \"uniform\"\ndirection = [0.0, 0.0, 1.0]\nfield = 15000.0\n"
      << "[spikes]\nalpha = 100.0\nresponse_time = " << responseTime << "\n";
    return parseSpikeScene(SceneDocument::parse(spiketest::dishScene(kR, s.str()), "flow.toml"));
}

// Particle files frames 0..last at 30 fps: the dish's particles (2 mm grid), from frame
// `onset` on all moving at u, before it still.
void writeFlowFrames(const ferro::test::TempDir& dir, int last, int onset, const Vec3& u)
{
    for (int f = 0; f <= last; ++f) {
        ParticleTable t;
        t.names = {"x", "y", "z", "vx", "vy", "vz"};
        for (int i = -14; i <= 14; ++i)
            for (int j = -14; j <= 14; ++j)
                for (int k = 0; k <= 4; ++k) {
                    if (std::hypot(i, j) > 14) continue;
                    const Vec3 v = f >= onset ? u : Vec3(0, 0, 0);
                    t.values.insert(t.values.end(), {0.002f * i, 0.002f * j, 0.002f * k + 0.001f, v.x(), v.y(), v.z()});
                }
        t.setComment("time", std::to_string(f / 30.0));
        t.setComment("frame", std::to_string(f));
        t.setComment("spacing", "0.002");
        writeParticleFile(dir.file("particles_" + std::string(4 - std::to_string(f).size(), '0') + std::to_string(f) + ".ply"), t);
    }
}

std::map<std::pair<int, int>, SpikeTip> byIndex(const SpikeResult& r)
{
    std::map<std::pair<int, int>, SpikeTip> m;
    for (const SpikeTip& t : r.tips) m[{t.i, t.j}] = t;
    return m;
}

} // namespace

TEST_CASE("ferro-spikes with response_time: a flow switched on carries every tip by u tau (1 - e^(-t/tau)), and the tips move as that offset grows",
          "[spikes][flow]")
{
    // Two flows: one that carries the tips a third of a spacing, one that carries them most
    // of a spacing, so the pattern is traced from an anchor a whole cell over and its tips
    // keep their own lattice coordinates (the one the flow took from site (i, j) is (i, j)).
    const Vec3 fast = GENERATE(Vec3(0.02f, 0.01f, 0.0f), Vec3(0.06f, 0.02f, 0.0f));
    ferro::test::TempDir dir("spike-flow");
    const Vec3 u = fast;
    const int last = 15, onset = 6; // the flow starts at 0.2 s; the frame is at 0.5 s
    writeFlowFrames(dir, last, onset, u);
    TriangleMesh pool = spiketest::makeFlatPool(kR, kDepth, 20);
    pool.velocities.assign(pool.vertices.size(), u);
    setComment(pool, "time", std::to_string(last / 30.0));
    writeMesh(dir.file("pool.ply"), pool);
    const std::string pattern = dir.file("particles_{:04}.ply"), particles = framePath(pattern, last);
    const double tau = 0.1;
    const SpikeResult laid = spikeFrame(flowScene(0), dir.file("pool.ply"), particles, dir.file("a.ply"), last, pattern);
    const SpikeResult carried =
        spikeFrame(flowScene(tau), dir.file("pool.ply"), particles, dir.file("b.ply"), last, pattern);
    // The history reaches 4 tau = 12 frames back, to frame 3; its samples are every frame
    // from 3 to 15 (0.05 s is 1.5 frames: at most 0.05 s apart is every frame). The flow at
    // frame 5 (0.167 s) is 0, from frame 6 (0.2 s) on it is u; between them it ramps
    // linearly. With the ramp's exact response, from t0 = 0.167 s (dt = 1/30 s):
    //     d(t) = u tau [(t - t0) / tau - (1 - e^(-(t - t0)/tau))] / (dt / tau) up to t0 + dt,
    //     then  d(t) = d1 e^(-(t - t1)/tau) + u tau (1 - e^(-(t - t1)/tau)).
    auto offset = [&](double t) {
        const double t0 = 5.0 / 30, dt = 1.0 / 30, t1 = t0 + dt;
        const double d1 = tau * ((dt / tau) - (1 - std::exp(-dt / tau))) / (dt / tau);
        return d1 * std::exp(-(t - t1) / tau) + tau * (1 - std::exp(-(t - t1) / tau));
    };
    const double t = last / 30.0;
    const Vec3d along = u.cast<double>();
    const double l = laid.patterns.at(0).spacing;
    const auto a = byIndex(laid), b = byIndex(carried);
    int matched = 0;
    for (const auto& [ij, tip] : a) {
        if (!b.count(ij) || tip.height < 0.9 * laid.maxHeight) continue;
        const Vec3d moved = b.at(ij).base - tip.base;
        INFO("tip " << ij.first << "," << ij.second << " moved " << moved.transpose() * 1e3 << " mm, expected "
                    << (along * offset(t)).transpose() * 1e3);
        REQUIRE((moved - along * offset(t)).norm() < 1e-3 * l);
        ++matched;
    }
    REQUIRE(matched > 20);
    if (u.x() > 0.05f) return; // the velocities below: the slower flow
    // Their velocity along the surface (the spiky mesh's at each apex) is the offset's growth
    // over the frame before: u (offset(t) - offset(t - 1/30)) * 30.
    const Vec3d expectedVelocity = along * (offset(t) - offset(t - 1.0 / 30)) * 30.0;
    REQUIRE(expectedVelocity.norm() > 0.03 * along.norm());
    int apexes = 0;
    for (const SpikeTip& tip : carried.tips) {
        if (tip.height < 0.9 * carried.maxHeight || !a.count({tip.i, tip.j})) continue;
        size_t apex = 0;
        for (size_t v = 1; v < carried.refined.vertices.size(); ++v)
            if ((carried.refined.vertices[v].cast<double>() - tip.base).norm() <
                (carried.refined.vertices[apex].cast<double>() - tip.base).norm())
                apex = v;
        if ((carried.refined.vertices[apex].cast<double>() - tip.base).norm() > 1e-6) continue;
        Vec3d v = carried.mesh.velocities[apex].cast<double>();
        v.z() = 0;
        // Only where the spikes stand at full weight: there the laid-out apex (same lattice
        // coordinates) keeps none of the fluid's velocity along the surface. Near the wall's
        // fade the surface's own velocity shows through, with or without the carry.
        size_t laidApex = 0;
        const Vec3d laidBase = a.at({tip.i, tip.j}).base;
        for (size_t w = 1; w < laid.refined.vertices.size(); ++w)
            if ((laid.refined.vertices[w].cast<double>() - laidBase).norm() <
                (laid.refined.vertices[laidApex].cast<double>() - laidBase).norm())
                laidApex = w;
        Vec3d vLaid = laid.mesh.velocities[laidApex].cast<double>();
        vLaid.z() = 0;
        if (vLaid.norm() > 1e-6 * along.norm()) continue;
        INFO("apex velocity " << v.transpose() << " expected " << expectedVelocity.transpose());
        REQUIRE((v - expectedVelocity).norm() < 0.02 * along.norm());
        ++apexes;
    }
    REQUIRE(apexes > 5);
}

TEST_CASE("ferro-spikes with response_time: an unusable earlier particle file is a one-line error naming it",
          "[spikes][flow]")
{
    ferro::test::TempDir dir("spike-flow-bad");
    writeFlowFrames(dir, 3, 0, Vec3(0.01f, 0.0f, 0.0f));
    // Frame 2's time is not a number: the history cannot be ordered.
    ParticleTable t = readParticleFile(dir.file("particles_0002.ply"));
    t.setComment("time", "nan");
    writeParticleFile(dir.file("particles_0002.ply"), t);
    TriangleMesh pool = spiketest::makeFlatPool(kR, kDepth, 12);
    setComment(pool, "time", std::to_string(3 / 30.0));
    writeMesh(dir.file("pool.ply"), pool);
    const std::string pattern = dir.file("particles_{:04}.ply");
    try {
        spikeFrame(flowScene(0.1), dir.file("pool.ply"), framePath(pattern, 3), dir.file("out.ply"), 3, pattern);
        FAIL("no error");
    } catch (const SpikeInputError& e) {
        const std::string what = e.what();
        INFO(what);
        REQUIRE(what.find("particles_0002.ply") != std::string::npos);
        REQUIRE(what.find("not a finite number") != std::string::npos);
        REQUIRE(what.find('\n') == std::string::npos);
    }
    REQUIRE_FALSE(std::ifstream(dir.file("out.ply")).good());
}

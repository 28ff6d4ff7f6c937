// The pressure sweeps' two compiled copies (sim/sph/sweeps/PressureSweeps.hpp) against the
// formulas they implement, evaluated here in double precision pair by pair from the same
// lists (the pressure accelerations and the density change of Bender & Koschier 2017), and
// against each other, bit for bit.
#include "sim/sph/FluidSimulation.hpp"
#include "sim/sph/sweeps/PressureSweeps.hpp"
#include "sim/scene/SimSceneFile.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

using namespace ferro;

namespace {

struct Reference {
    std::vector<double> a;    // three a particle
    std::vector<double> div;
};

// Periodic sides: the offset to the nearest image (pairs are far closer than half a period).
void nearestImage(const PressureSweepInput& in, double d[3]) {
    for (int c = 0; c < 2; ++c)
        if (in.period[c] > 0) d[c] -= double(in.period[c]) * std::round(d[c] / double(in.period[c]));
}

Reference referenceSweeps(const PressureSweepInput& in, size_t n, const std::vector<float>& kappa, const std::vector<float>& u) {
    Reference r;
    r.a.assign(3 * n, 0.0);
    r.div.assign(n, 0.0);
    for (size_t i = 0; i < n; ++i) {
        const double x[3] = {in.p4[4 * i], in.p4[4 * i + 1], in.p4[4 * i + 2]};
        double div = 0;
        for (uint32_t k = in.offset[i]; k < in.offset[i] + in.count[i]; ++k) {
            const uint32_t j = in.index[k];
            double d[3] = {x[0] - in.p4[4 * j], x[1] - in.p4[4 * j + 1], x[2] - in.p4[4 * j + 2]};
            nearestImage(in, d);
            const double s = double(in.gradFactor[k]);
            for (int c = 0; c < 3; ++c) {
                r.a[3 * i + c] -= double(in.volume) * (double(kappa[i]) + double(kappa[j])) * s * d[c];
                div += double(in.volume) * s * (double(u[3 * i + c]) - double(u[3 * j + c])) * d[c];
            }
        }
        for (uint32_t w = in.wallOffset[i]; w < in.wallOffset[i] + in.wallCount[i]; ++w) {
            const uint32_t b = in.wallIndex[w];
            const double s = double(in.wallGradFactor[w]) * double(in.wallVolume[b]);
            double d[3];
            for (int c = 0; c < 3; ++c) d[c] = x[c] - double(in.wallX[3 * b + c]);
            nearestImage(in, d);
            for (int c = 0; c < 3; ++c) {
                r.a[3 * i + c] -= double(in.wallMirror) * double(kappa[i]) * s * d[c];
                div += s * double(u[3 * i + c]) * d[c];
            }
        }
        r.div[i] = div;
    }
    return r;
}

} // namespace

// Reference: the sums of the formulas in double precision. Bound: float arithmetic over ~40
// pairs that largely cancel (a tank at rest): 1e-5 of the largest value in the field.
TEST_CASE("each compiled copy of the pressure sweeps computes the formulas on a real tank's lists", "[sph]") {
    // The tank, and a layer whose sides are periodic (pairs across the glued faces).
    const bool periodic = GENERATE(false, true);
    const std::string tank = std::string(FERRO_SOURCE_DIR) + "/examples/hydrostatic.toml";
    FluidSimulation sim(loadSimScene(tank, periodic ? std::vector<std::string>{
        "container.periodic_sides=true", "container.max=[0.02, 0.02, 0.05]", "fluid.block.0.max=[0.02, 0.02, 0.004]",
        "fluid.spacing=0.001"} : std::vector<std::string>{}));
    REQUIRE(sim.periodic().active() == periodic);
    sim.advanceTo(0.02);
    const size_t n = sim.size();
    REQUIRE(n > 1000);
    const PressureSweepInput in = sim.sweepInput();
    REQUIRE(in.gradFactor != nullptr);
    // The padded positions the sweeps read are the simulation's positions.
    size_t stale = 0;
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) stale += in.p4[4 * i + size_t(c)] != sim.positions()[i][c];
    CHECK(stale == 0);
    // A pressure field like a tank's (growing with depth, zero at the top) with a ripple, and
    // a velocity field with compression and shear.
    std::vector<float> kappa(n), u(3 * n);
    for (size_t i = 0; i < n; ++i) {
        const float x = in.p4[4 * i], y = in.p4[4 * i + 1], z = in.p4[4 * i + 2];
        kappa[i] = std::max(0.0f, 0.05f - z) * (1.0f + 0.1f * std::sin(400.0f * x));
        u[3 * i] = 0.01f * std::sin(300.0f * y);
        u[3 * i + 1] = 0.02f * z;
        u[3 * i + 2] = -0.5f * z + 0.003f * std::cos(250.0f * x);
    }
    // The same field padded to four floats a particle, 16-byte aligned (the sweeps' fast form).
    struct alignas(16) Float4 {
        float v[4];
    };
    std::vector<Float4> u4(n);
    for (size_t i = 0; i < n; ++i) u4[i] = Float4{{u[3 * i], u[3 * i + 1], u[3 * i + 2], 0.0f}};
    const Reference ref = referenceSweeps(in, n, kappa, u);
    double aMax = 0, divMax = 0;
    for (double v : ref.a) aMax = std::max(aMax, std::abs(v));
    for (double v : ref.div) divMax = std::max(divMax, std::abs(v));
    REQUIRE(aMax > 0);
    REQUIRE(divMax > 0);

    std::vector<float> firstA, firstDiv;   // the baseline copy's results
    std::vector<const PressureSweeps*> copies{&baselinePressureSweeps()};
    if (const PressureSweeps* fast = x86v3PressureSweeps()) copies.push_back(fast);
    for (const PressureSweeps* sweeps : copies) {
        std::vector<float> a(3 * n), div(n), div4(n);
        std::vector<Float4> a4(n);
        // In blocks of uneven size, as the parallel loops hand them out.
        for (size_t begin = 0; begin < n; begin += 97) {
            const size_t end = std::min(n, begin + 97);
            sweeps->accelerations(in, kappa.data(), a.data(), a4[0].v, begin, end);
            sweeps->divergence(in, u.data(), 3, div.data(), begin, end);
            sweeps->divergence(in, u4[0].v, 4, div4.data(), begin, end);
        }
        double aErr = 0, divErr = 0;
        for (size_t k = 0; k < 3 * n; ++k) aErr = std::max(aErr, std::abs(double(a[k]) - ref.a[k]));
        for (size_t i = 0; i < n; ++i) divErr = std::max(divErr, std::abs(double(div[i]) - ref.div[i]));
        // The padded copies hold the same numbers: the accelerations as written, the
        // divergence of the padded field as that of the plain one (the same sums, other loads).
        size_t paddedDiffer = 0;
        for (size_t i = 0; i < n; ++i) {
            for (int c = 0; c < 3; ++c) paddedDiffer += a4[i].v[c] != a[3 * i + size_t(c)];
            paddedDiffer += a4[i].v[3] != 0.0f;
            paddedDiffer += div4[i] != div[i];
        }
        CHECK(paddedDiffer == 0);
        // Every copy gives the baseline's bits (the same operations in the same order, no
        // fused multiply-adds: -ffp-contract=off), so frames do not depend on the processor
        // that made them: a farm of mixed machines, or a resume on another node, stays exact.
        if (firstA.empty()) {
            firstA = a;
            firstDiv = div;
        } else {
            CHECK(a == firstA);
            CHECK(div == firstDiv);
        }
        CAPTURE(sweeps->instructionSet, aMax, aErr, divMax, divErr);
        CHECK(aErr < 1e-5 * aMax);
        CHECK(divErr < 1e-5 * divMax);
    }
    if (copies.size() == 1) WARN("only the baseline copy runs on this processor or build: nothing to compare it with");
    // The simulation runs the copy for this processor (the baseline when FERRO_SWEEPS says so).
    const char* forced = std::getenv("FERRO_SWEEPS");
    const bool baselineForced = forced && std::string(forced) == "baseline";
    CHECK(&pressureSweeps() == (x86v3PressureSweeps() && !baselineForced ? x86v3PressureSweeps() : &baselinePressureSweeps()));
    // Through the simulation: the divergence of the pressure accelerations from their padded
    // copy (the iterations' path) is the divergence of the plain ones.
    std::vector<Real> kappaSim(kappa.begin(), kappa.end()), viaPadded, viaPlain;
    sim.pressureAccelerations(kappaSim);
    sim.pressureDivergence(viaPadded);
    sim.divergence(sim.accelerations(), viaPlain);
    CHECK(viaPadded == viaPlain);
    double simErr = 0;
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
            simErr = std::max(simErr, std::abs(double(sim.accelerations()[i][c]) - ref.a[3 * i + size_t(c)]));
    CHECK(simErr < 1e-5 * aMax);
}

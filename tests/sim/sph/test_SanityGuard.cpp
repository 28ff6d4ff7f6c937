// The sanity guard's counters (sim/sph/SanityGuard.hpp) on made-up step histories: when a
// run that crawls at sim.min_dt, or whose magnetization solve never converges, must stop.
// tests/sim/app/test_ferro_sim_cli.cpp trips both through scenes.
#include "sim/sph/SanityGuard.hpp"

#include <catch2/catch.hpp>

using namespace ferro;

TEST_CASE("a time step near sim.min_dt stops the run after kMaxStuckSteps steps in a row", "[guard]") {
    const double minDt = 1e-6, stuck = 3e-6, fine = 4e-6; // below and at kNearMinDt x min_dt
    REQUIRE(SanityLimits::kNearMinDt == 4);
    StallGuard guard(minDt);
    for (int i = 0; i < 10; ++i) REQUIRE_FALSE(guard.recordStep(1e-4));
    CHECK(guard.stuckSteps() == 0);
    // One step short of the limit, then a step at 4 x min_dt (not stuck): the count restarts.
    for (size_t i = 1; i < SanityLimits::kMaxStuckSteps; ++i) REQUIRE_FALSE(guard.recordStep(stuck));
    CHECK(guard.stuckSteps() == SanityLimits::kMaxStuckSteps - 1);
    REQUIRE_FALSE(guard.recordStep(fine));
    CHECK(guard.stuckSteps() == 0);
    // kMaxStuckSteps in a row: the last one stops the run, not one before.
    for (size_t i = 1; i < SanityLimits::kMaxStuckSteps; ++i) REQUIRE_FALSE(guard.recordStep(stuck));
    CHECK(guard.recordStep(stuck));
    CHECK(guard.stuckSteps() == SanityLimits::kMaxStuckSteps);
}

TEST_CASE("magnetization solves at their cap stop the run after kMaxUnconvergedSolves in a row", "[guard]") {
    REQUIRE(SanityLimits::kMaxUnconvergedSolves == 50);
    CHECK_FALSE(StallGuard::solverStalled(0));
    CHECK_FALSE(StallGuard::solverStalled(49));
    CHECK(StallGuard::solverStalled(50));
    CHECK(StallGuard::solverStalled(1000));
}

TEST_CASE("the speed bound: the override, else 5 x the energy speed, at least 0.1 m/s", "[guard]") {
    SpeedBound b;
    CHECK(b.value() == SanityLimits::kMinSpeed);
    b.gravity2 = 2 * 9.81 * 0.05; // a 5 cm fall: 0.990 m/s
    b.magnetic2 = 3.0;
    CHECK(b.energySpeed() == Approx(std::sqrt(0.981 + 3.0)));
    CHECK(b.value() == Approx(5 * std::sqrt(3.981)));
    b.override = 0.5;
    CHECK(b.value() == 0.5);
}

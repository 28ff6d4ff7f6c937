// sim/core/FrameRunner: one frame-range runner and one failure policy for every stage.
#include "sim/core/FrameRunner.hpp"
#include "sim/core/StageErrors.hpp"

#include <catch2/catch.hpp>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <mutex>
#include <set>

using namespace ferro;

TEST_CASE("runFrames runs every frame of the range once", "[core]") {
    std::mutex m;
    std::multiset<int> seen;
    runFrames({3, 41}, {{"--out", "s/x_{:04}.ply"}}, [&](int f) {
        std::lock_guard<std::mutex> lock(m);
        seen.insert(f);
    });
    REQUIRE(seen.size() == 39);
    for (int f = 3; f <= 41; ++f) CHECK(seen.count(f) == 1);
}

TEST_CASE("runFrames stops at the first failing frame and rethrows the lowest failure", "[core]") {
    // 10 million frames of which 3 exist: the run stops after a handful, not 10 million
    // error lines later, and names frame 3 whatever the thread count. The existing frames
    // take a while (as real frames do), so a runner that splits the range across threads
    // would see a frame near 5,000,000 fail first and report that one (CI saw it once).
    for (int threads : {1, 2}) {
        INFO("threads " << threads);
        std::atomic<long> calls{0};
        tbb::task_arena arena(threads);
        arena.execute([&] {
            try {
                runFrames({0, kMaxFrame}, {{"input", "p_{:04}.ply"}}, [&](int f) {
                    ++calls;
                    if (f < 3) std::this_thread::sleep_for(std::chrono::milliseconds(20));
                    if (f >= 3) throw InputMissingError("frame " + std::to_string(f) + " missing");
                });
                FAIL("no error");
            } catch (const InputMissingError& e) {
                CHECK(std::string(e.what()) == "frame 3 missing");
            }
        });
        CHECK(calls.load() < 100000);
    }
}

TEST_CASE("a frame range needs a placeholder in every pattern", "[core]") {
    CHECK_NOTHROW(checkFramePatterns({5, 5}, {{"--out", "single.ply"}}));
    CHECK_NOTHROW(checkFramePatterns({5, 9}, {{"--out", "m_%04d.ply"}, {"--vdb", ""}}));
    try {
        checkFramePatterns({0, 2}, {{"input", "p_{:04}.ply"}, {"--out", "single.ply"}});
        FAIL("a pattern without a placeholder was accepted");
    } catch (const BadInputError& e) {
        CHECK(std::string(e.what()) == "--out: a frame range needs a {:04} or %04d placeholder (got 'single.ply')");
    }
    bool ran = false;
    CHECK_THROWS_AS(runFrames({0, 2}, {{"--out", "single.ply"}}, [&](int) { ran = true; }), BadInputError);
    CHECK_FALSE(ran);
}

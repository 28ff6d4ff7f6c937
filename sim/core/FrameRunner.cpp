#include "sim/core/FrameRunner.hpp"

#include "sim/core/StageErrors.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <mutex>

namespace ferro {

void checkFramePatterns(const FrameRange& range, const std::vector<FramePattern>& patterns)
{
    if (range.first == range.last) return;
    for (const FramePattern& p : patterns)
        if (!p.pattern.empty() && framePath(p.pattern, range.first) == framePath(p.pattern, range.first + 1))
            throw BadInputError(p.option + ": a frame range needs a {:04} or %04d placeholder (got '" + p.pattern +
                                "')");
}

void runFrames(const FrameRange& range, const std::vector<FramePattern>& patterns,
               const std::function<void(int frame)>& work)
{
    checkFramePatterns(range, patterns);
    std::mutex mutex;
    std::exception_ptr failure;
    int failedFrame = 0;
    std::atomic<bool> stop{false};
    // Frames start in ascending order (workers pull the next frame from one counter), so
    // when frame F fails every frame below F has already started: the lowest failure is the
    // lowest failing frame of the range, whatever the thread count. A split range
    // (tbb::parallel_for over frames) could start near the end first and report frame
    // 5,000,000 missing when frame 3 is.
    std::atomic<int64_t> next{range.first};
    const int workers = std::max(1, tbb::this_task_arena::max_concurrency());
    tbb::parallel_for(0, workers, [&](int) {
        while (!stop) {
            const int64_t frame64 = next++;
            if (frame64 > int64_t(range.last)) return;
            const int frame = int(frame64);
            try {
                work(frame);
            } catch (...) {
                std::lock_guard<std::mutex> lock(mutex);
                if (!failure || frame < failedFrame) {
                    failure = std::current_exception();
                    failedFrame = frame;
                }
                stop = true;
            }
        }
    });
    if (failure) std::rethrow_exception(failure);
}

} // namespace ferro

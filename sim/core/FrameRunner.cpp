#include "sim/core/FrameRunner.hpp"

#include "sim/core/StageErrors.hpp"

#include <tbb/parallel_for.h>

#include <atomic>
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
    tbb::parallel_for(int64_t(range.first), int64_t(range.last) + 1, int64_t(1), [&](int64_t frame64) {
        if (stop) return;
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
    });
    if (failure) std::rethrow_exception(failure);
}

} // namespace ferro

// The baseline copy of the pressure sweeps and the run-time choice between the copies
// (PressureSweeps.hpp).
#include "sim/sph/sweeps/PressureSweeps.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <cstdlib>
#include <cstring>

namespace ferro {
namespace sweeps_baseline {
#include "sim/sph/sweeps/PressureSweepKernels.inc"
} // namespace sweeps_baseline

#if defined(FERRO_SWEEPS_X86V3)
namespace sweeps_x86v3 {
PressureSweeps table();
}
#endif

const PressureSweeps& baselinePressureSweeps() {
    static const PressureSweeps sweeps{sweeps_baseline::accelerationSweep, sweeps_baseline::divergenceSweep, "baseline"};
    return sweeps;
}

const PressureSweeps* x86v3PressureSweeps() {
#if defined(FERRO_SWEEPS_X86V3)
    // table() is x86-64-v3 code itself: called only once the processor is known to run it.
    static const PressureSweeps* sweeps = []() -> const PressureSweeps* {
#if defined(__clang__)
        const bool v3 = __builtin_cpu_supports("avx") && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                        __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2") && __builtin_cpu_supports("f16c");
#else
        const bool v3 = __builtin_cpu_supports("x86-64-v3");   // GCC 12: the whole level
#endif
        if (!v3) return nullptr;
        static const PressureSweeps table = sweeps_x86v3::table();
        return &table;
    }();
    return sweeps;
#else
    return nullptr;
#endif
}

const PressureSweeps& pressureSweeps() {
    static const PressureSweeps& chosen = []() -> const PressureSweeps& {
        const char* wanted = std::getenv("FERRO_SWEEPS");
        const PressureSweeps* fast = x86v3PressureSweeps();
        if (fast && !(wanted && std::strcmp(wanted, "baseline") == 0)) return *fast;
        return baselinePressureSweeps();
    }();
    return chosen;
}

} // namespace ferro

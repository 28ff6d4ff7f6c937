// The pressure sweeps compiled for x86-64-v3 (AVX2, FMA): sim/CMakeLists.txt gives this file
// -march=x86-64-v3 on x86-64, and PressureSweeps.cpp calls it only where the processor has
// both. It includes nothing but PressureSweeps.hpp and the kernels (that header's contract).
#include "sim/sph/sweeps/PressureSweeps.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#if defined(FERRO_SWEEPS_X86V3)
namespace ferro::sweeps_x86v3 {
#include "sim/sph/sweeps/PressureSweepKernels.inc"

PressureSweeps table() { return {accelerationSweep, divergenceSweep, "x86-64-v3"}; }
} // namespace ferro::sweeps_x86v3
#endif

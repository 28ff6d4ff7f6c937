#pragma once
// The two sweeps every pressure iteration runs (DFSPH's Jacobi and CG sweeps): the pressure
// accelerations of a pressure field, and the density change of a velocity or acceleration
// field. They are most of a DFSPH step's time (bench-sim's cost line: sweep_ms), so they are
// compiled twice, for the baseline x86-64 (SSE2) and for x86-64-v3 (AVX2, FMA), and the
// processor picks one at run time (pressureSweeps()): a generic build runs them as fast as a
// -march=native one. Measurements: docs/physics/sph-solver.md, "The models in brief".
//
// Contract: plain arrays only, so that the x86-64-v3 copy shares no inline code with the rest
// of the program (an inline function compiled for AVX2 in one file could otherwise be the
// copy the linker keeps for every file). The two copies give the same bits (the x86-64-v3 one
// is compiled with -ffp-contract=off: no fused multiply-adds): a frame does not depend on the
// processor that made it (tested: tests/sim/sph/test_PressureSweeps.cpp).
#include <cstddef>
#include <cstdint>

namespace ferro {

/// The particles' positions and neighbour lists as the sweeps read them (sorted order).
/// Vectors are three floats a particle (Vec3's layout).
struct PressureSweepInput {
    const float* p4 = nullptr;  ///< fluid positions, four floats a particle (x, y, z, 0), 16-byte aligned [m]
    const uint32_t* offset = nullptr;      ///< fluid pairs: first slot of particle i
    const uint32_t* count = nullptr;       ///< fluid pairs: neighbours of particle i
    const uint32_t* index = nullptr;       ///< fluid pairs: the neighbour j
    const float* gradFactor = nullptr;     ///< s_ij: grad W_ij = s_ij (x_i - x_j)
    const uint32_t* wallOffset = nullptr;  ///< wall pairs, likewise
    const uint32_t* wallCount = nullptr;
    const uint32_t* wallIndex = nullptr;
    const float* wallGradFactor = nullptr;
    const float* wallX = nullptr;          ///< wall particle positions, three floats each [m]
    const float* wallVolume = nullptr;     ///< Akinci volumes V_b [m^3]
    float volume = 0;                      ///< fluid particle volume V [m^3]
    float wallMirror = 1;                  ///< a wall pushes with kWallMirror kappa_i
    /// Periodic sides (sim/spatial/PeriodicDomain.hpp): x and y periods [m] and their
    /// inverses, 0 on a closed axis; pair offsets then go to the nearest image.
    float period[2] = {0, 0}, inverse[2] = {0, 0};
};

/// a_i = -sum_j V (kappa_i + kappa_j) grad W_ij - sum_b V_b mirror kappa_i grad W_ib for i in
/// [begin, end), written to a[3 i .. 3 i + 2] and, unless a4 is null, to a4[4 i .. 4 i + 3]
/// padded with 0 (Bender & Koschier 2017, kappa = p / rho^2 over rho0).
using PressureAccelerationSweep = void (*)(const PressureSweepInput&, const float* kappa, float* a, float* a4,
                                          size_t begin, size_t end);
/// out[i] = sum_j V (u_i - u_j) . grad W_ij + sum_b V_b u_i . grad W_ib for i in [begin, end):
/// D(rho / rho0)/Dt [1/s] for u = velocities (walls at rest). u holds `stride` floats a
/// particle: 3 (Vec3) or 4 (padded as a4 above, 16-byte aligned: the faster loads).
using DivergenceSweep = void (*)(const PressureSweepInput&, const float* u, int stride, float* out, size_t begin,
                                 size_t end);

struct PressureSweeps {
    PressureAccelerationSweep accelerations;
    DivergenceSweep divergence;
    const char* instructionSet;  ///< "x86-64-v3" or "baseline"
};

/// The copy for this processor, chosen once: x86-64-v3 where the processor has that level,
/// unless the environment sets FERRO_SWEEPS=baseline (for comparisons).
const PressureSweeps& pressureSweeps();
/// Each copy compiled into this build (the baseline always; x86-64-v3 on x86-64 where the
/// processor can run it), for tests that hold them to each other.
const PressureSweeps& baselinePressureSweeps();
const PressureSweeps* x86v3PressureSweeps();

} // namespace ferro

#pragma once
// Particle layouts with known surfaces for the surface tests and the benchmark.
#include "sim/core/Types.hpp"

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

namespace ferro::test {

/// Deterministic uniform numbers in [-1, 1) (a 64-bit LCG: same on every platform).
struct Jitter {
    uint64_t state;
    explicit Jitter(uint64_t seed) : state(seed * 6364136223846793005ull + 1442695040888963407ull) {}
    float next() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return float(double(state >> 11) / double(1ull << 52) - 1.0);
    }
};

/// Simple cubic lattice points (i + 1/2) * spacing inside [lo, lo + n * spacing) for which
/// `inside` holds at the point, each moved by up to `jitter` spacings per axis.
inline std::vector<Vec3> latticeFill(const Vec3& lo, const int n[3], double spacing, double jitter,
                                     const std::function<bool(const Vec3&)>& inside, uint64_t seed = 1) {
    std::vector<Vec3> x;
    Jitter rng(seed);
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
                const Vec3 p = lo + Vec3(Real((i + 0.5) * spacing), Real((j + 0.5) * spacing), Real((k + 0.5) * spacing));
                if (!inside(p)) continue;
                const float a = rng.next(), b = rng.next(), c = rng.next();
                x.push_back(p + Real(jitter * spacing) * Vec3(a, b, c));
            }
    return x;
}

/// A slab [0, nx s] x [0, ny s] x [0, nz s] of jittered lattice particles.
inline std::vector<Vec3> jitteredSlab(int nx, int ny, int nz, double spacing, double jitter, uint64_t seed = 1) {
    const int n[3] = {nx, ny, nz};
    return latticeFill(Vec3::Zero(), n, spacing, jitter, [](const Vec3&) { return true; }, seed);
}

/// Lattice particles whose cells' centres lie inside the sphere of `radius` at the origin.
inline std::vector<Vec3> sphereFill(double radius, double spacing, double jitter, uint64_t seed = 2) {
    const int m = int(std::ceil(radius / spacing)) + 1;
    const int n[3] = {2 * m, 2 * m, 2 * m};
    const Vec3 lo = Vec3::Constant(Real(-m * spacing));
    return latticeFill(lo, n, spacing, jitter, [&](const Vec3& p) { return p.norm() < radius; }, seed);
}

} // namespace ferro::test

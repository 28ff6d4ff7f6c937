#pragma once
// Parallel loops over particles shared by the simulator's parts (FluidSimulation,
// FluidMagnetics). Sums run in fixed blocks combined in a fixed order, so their results
// do not depend on the thread count: steps stay repeatable and resume bit for bit.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ferro {

/// Calls f(i) for i in [0, n) in parallel.
template <class F>
void forEachParticle(size_t n, F&& f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
}

/// Calls f(begin, end) on blocks of [0, n) in parallel: for loops that hand a whole block to
/// one function (the pressure sweeps, sim/sph/sweeps).
template <class F>
void forEachParticleBlock(size_t n, F&& f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256),
                      [&](const tbb::blocked_range<size_t>& r) { f(r.begin(), r.end()); });
}

/// Sum of f(i) over [0, n) whose result does not depend on the thread count or
/// scheduling: fixed blocks, each summed in order, blocks combined in order.
template <class F>
double deterministicSum(size_t n, F&& f) {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<size_t>(0, n, 1024), 0.0,
        [&](const tbb::blocked_range<size_t>& r, double acc) {
            for (size_t i = r.begin(); i != r.end(); ++i) acc += f(i);
            return acc;
        },
        [](double a, double b) { return a + b; });
}

/// Largest f(i) over [0, n) as a T, `none` when n = 0. A maximum is exact in any order, so
/// the result does not depend on the thread count either.
template <class T, class F>
T largestOf(size_t n, T none, F&& f) {
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 4096), none,
        [&](const tbb::blocked_range<size_t>& r, T m) {
            for (size_t i = r.begin(); i != r.end(); ++i) m = std::max(m, T(f(i)));
            return m;
        },
        [](T a, T b) { return std::max(a, b); });
}

/// Smallest f(i) over [0, n) as a T, `none` when n = 0 (exact in any order, as largestOf).
template <class T, class F>
T smallestOf(size_t n, T none, F&& f) {
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 4096), none,
        [&](const tbb::blocked_range<size_t>& r, T m) {
            for (size_t i = r.begin(); i != r.end(); ++i) m = std::min(m, T(f(i)));
            return m;
        },
        [](T a, T b) { return std::min(a, b); });
}

/// Reorders `data` so that data[k] = old data[order[k]]; leaves data of another size alone.
template <class T>
void permute(std::vector<T>& data, const std::vector<uint32_t>& order) {
    if (data.size() != order.size()) return;
    std::vector<T> tmp(data.size());
    forEachParticle(order.size(), [&](size_t k) { tmp[k] = data[order[k]]; });
    data.swap(tmp);
}

} // namespace ferro

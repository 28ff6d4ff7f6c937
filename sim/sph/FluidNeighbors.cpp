// FluidSimulation's neighbour lists: the search (particles re-sorted by cell, candidate slots
// within the support plus a Verlet skin) and the per-step update of current neighbours,
// densities and stored kernel gradients.
#include "sim/sph/FluidSimulation.hpp"

#include "sim/core/Constants.hpp"
#include "sim/core/ParticleLoops.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnetics/MagnetizationSolver.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ferro {

namespace {

constexpr size_t kGrain = 256;

} // namespace

void FluidSimulation::refreshNeighbors(bool forceSearch) {
    // A new search only when some pair may have closed the skin: two particles that each
    // moved less than half the skin since the search are still in each other's slots.
    bool search = forceSearch || skin_ <= 0 || xSearch_.size() != x_.size();
    if (!search) {
        const Real moved2 = largestOf(x_.size(), Real(0), [&](size_t i) { return (x_[i] - xSearch_[i]).squaredNorm(); });
        // (A non-finite position never gets here: integratePositions stops the run.)
        search = !(4 * double(moved2) < skin_ * skin_);
    }
    if (search) searchCandidates();
    updateNeighbors();
}

void FluidSimulation::searchCandidates() {
    const size_t n = x_.size();
    // Cells as wide as the search radius, so that the 3 x 3 x 3 stencil holds every
    // candidate within the support plus the skin.
    const Real radius = Real(h_ + skin_);
    // Periodic sides: back into the box (pair offsets take the nearest image anyway; the
    // grid and the image queries below need the box).
    if (periodic_.active()) forEachParticle(n, [&](size_t i) { periodic_.wrap(x_[i]); });
    grid_.sort(x_, id_, radius, order_);
    permute(x_, order_);
    permute(v_, order_);
    permute(id_, order_);
    solver_->permute(order_);
    if (implicitViscosity_) implicitViscosity_->permute(order_);
    if (magnetics_) magnetics_->permute(order_);
    grid_.index(x_, grid_.geometry());
    splitCoordinates(x_, px_, py_, pz_);
    p4_.resize(n);
    forEachParticle(n, [&](size_t i) { setPadded(i); });
    xSearch_ = x_;
    searchStep_ = steps_;
    ++stats_.searches;

    const bool haveBoundary = !bx_.empty();

    // Candidates within the support plus the skin, into fixed-capacity scratch lists. The
    // candidate buffer is generous (every candidate is written before it is tested); only
    // the hits are kept, and the capacity grows if one overflows.
    std::vector<uint32_t> fluidCount(n), boundaryCount(n);
    constexpr uint32_t kRoom = 4096;
    for (;;) {
        scratch_.resize(n * capacity_);
        bScratch_.resize(n * bCapacity_);
        std::atomic<bool> overflow{false};
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kGrain), [&](const tbb::blocked_range<size_t>& r) {
            std::vector<uint32_t> buffer(kRoom + 1);
            for (size_t i = r.begin(); i != r.end(); ++i) {
                // With periodic sides, a particle near a face also queries its images there
                // (each pair is found once: the box is wider than two search radii).
                uint32_t cnt = 0;
                forEachImageQuery(x_[i], radius, [&](const Vec3& q) {
                    if (cnt > kRoom) return;
                    const uint32_t found = gatherNeighbors(grid_, px_.data(), py_.data(), pz_.data(), q, radius,
                                                           q == x_[i] ? uint32_t(i) : uint32_t(-1), buffer.data() + cnt,
                                                           kRoom - cnt);
                    cnt = found > kRoom - cnt ? kRoom + 1 : cnt + found;
                });
                if (cnt > capacity_) overflow = true;
                std::copy_n(buffer.data(), std::min<uint32_t>(cnt, uint32_t(capacity_)), &scratch_[i * capacity_]);
                fluidCount[i] = cnt;
                cnt = 0;
                if (haveBoundary) {
                    forEachImageQuery(x_[i], radius, [&](const Vec3& q) {
                        if (cnt > kRoom) return;
                        const uint32_t found = gatherNeighbors(bGrid_, bpx_.data(), bpy_.data(), bpz_.data(), q, radius,
                                                               uint32_t(-1), buffer.data() + cnt, kRoom - cnt);
                        cnt = found > kRoom - cnt ? kRoom + 1 : cnt + found;
                    });
                    if (cnt > bCapacity_) overflow = true;
                    std::copy_n(buffer.data(), std::min<uint32_t>(cnt, uint32_t(bCapacity_)), &bScratch_[i * bCapacity_]);
                }
                boundaryCount[i] = cnt;
            }
        });
        if (!overflow) break;
        // Grow to the largest count seen (a few extra for the next steps). More than kRoom
        // candidates means particles piled up far beyond any SPH density: stop, do not loop.
        for (size_t i = 0; i < n; ++i) {
            if (fluidCount[i] > kRoom || boundaryCount[i] > kRoom) {
                std::ostringstream msg;
                msg << "particle " << id_[i] << " has more than " << kRoom << " neighbour candidates at t = " << time_
                    << " s: the fluid collapsed (time step too large or forces too strong)";
                throw SimulationError(msg.str());
            }
            if (fluidCount[i] > capacity_) capacity_ = std::min<size_t>(fluidCount[i] + 16, kRoom);
            if (boundaryCount[i] > bCapacity_) bCapacity_ = std::min<size_t>(boundaryCount[i] + 16, kRoom);
        }
    }
    // One slot per candidate; the candidates themselves are kept for the steps until the
    // next search.
    auto slots = [&](const std::vector<uint32_t>& count, const std::vector<uint32_t>& scratch, size_t capacity,
                     NeighborLists& lists, std::vector<uint32_t>& candidates) {
        lists.offset.resize(n + 1);
        lists.offset[0] = 0;
        for (size_t i = 0; i < n; ++i) lists.offset[i + 1] = lists.offset[i] + count[i];
        const size_t total = lists.offset[n];
        candidates.resize(total);
        lists.index.resize(total);
        lists.count.resize(n);
        if (storeGradients_) lists.gradFactor.resize(total);
        else lists.gradFactor.clear();
        forEachParticle(n, [&](size_t i) { std::copy_n(&scratch[i * capacity], count[i], &candidates[lists.offset[i]]); });
    };
    slots(fluidCount, scratch_, capacity_, fluidNbr_, fluidCandidates_);
    slots(boundaryCount, bScratch_, bCapacity_, boundaryNbr_, boundaryCandidates_);
    stats_.candidatePairs = fluidCandidates_.size();
}

void FluidSimulation::updateNeighbors() {
    // The neighbours of this step among the candidates (closer than the support), with
    // each pair's kernel gradient when the solver keeps them, and the density.
    const size_t n = x_.size();
    rho_.resize(n);
    const Real V = Real(volume_);
    const Real h2 = Real(h_ * h_);
    const bool storeGradients = storeGradients_;
#if defined(__SSE2__)
    const CubicSplineKernel4 kernel4(kernel_);
#endif
    const PeriodicDomain periodic = periodic_; // a copy: the loop's float stores could alias the member
    // Compacts particle i's candidates in `lists` (points at qx, qy, qz) to its neighbours;
    // returns sum_j V_j W_ij with V_j = volume[j], or V when volume is null. Branch-free:
    // every candidate is written to the next free slot, which advances only for a
    // neighbour (about 55 % are), and a candidate beyond the support adds W = 0.
    auto compact = [&](size_t i, NeighborLists& lists, const std::vector<uint32_t>& candidates, const Real* qx,
                       const Real* qy, const Real* qz, const Real* volume) {
        const Vec3 xi = x_[i];
        const uint32_t o = lists.offset[i], slots = lists.offset[i + 1] - o;
        const uint32_t* cand = candidates.data() + o;
        uint32_t* out = lists.index.data() + o;
        Real* grad = storeGradients ? lists.gradFactor.data() + o : nullptr;
        uint32_t cnt = 0, k = 0;
        Real sum = 0;
#if defined(__SSE2__)
        const __m128 h24 = _mm_set1_ps(h2);
        __m128 sum4 = _mm_setzero_ps();
        for (; k + 4 <= slots; k += 4) {
            const uint32_t* c = cand + k;
            const PairOffsets4 d(xi, qx, qy, qz, c, periodic);
            const __m128 r = _mm_sqrt_ps(d.r2);
            const __m128 vol = volume ? gather4(volume, c) : _mm_set1_ps(V);
            sum4 = _mm_add_ps(sum4, _mm_mul_ps(vol, kernel4.W(r)));
            const int hit = _mm_movemask_ps(_mm_cmplt_ps(d.r2, h24));
            if (grad) {
                alignas(16) float sc[4];
                _mm_store_ps(sc, kernel4.gradFactor(r));
                for (int l = 0; l < 4; ++l) {
                    out[cnt] = c[l];
                    grad[cnt] = sc[l];
                    cnt += uint32_t(hit >> l) & 1u;
                }
            } else {
                for (int l = 0; l < 4; ++l) {
                    out[cnt] = c[l];
                    cnt += uint32_t(hit >> l) & 1u;
                }
            }
        }
        sum = horizontalSum(sum4);
#endif
        for (; k < slots; ++k) {
            const uint32_t j = cand[k];
            const Vec3 d = periodic.offset(Vec3(xi.x() - qx[j], xi.y() - qy[j], xi.z() - qz[j]));
            const Real r2 = d.squaredNorm();
            out[cnt] = j;
            const Real r = std::sqrt(r2);
            const Real w = kernel_.W(r);
            if (grad) grad[cnt] = kernel_.gradWFactor(r);
            sum += (volume ? volume[j] : V) * w;
            cnt += uint32_t(r2 < h2);
        }
        lists.count[i] = cnt;
        return sum;
    };
    forEachParticle(n, [&](size_t i) {
        const Real density = V * kernel_.W0() +
                             compact(i, fluidNbr_, fluidCandidates_, px_.data(), py_.data(), pz_.data(), nullptr) +
                             compact(i, boundaryNbr_, boundaryCandidates_, bpx_.data(), bpy_.data(), bpz_.data(),
                                     bVolume_.data());
        rho_[i] = Real(rho0_) * density;
    });
    size_t pairs = 0;
    for (uint32_t c : fluidNbr_.count) pairs += c;
    stats_.neighborPairs = pairs;
}

} // namespace ferro

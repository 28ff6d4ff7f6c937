#pragma once
// The magnetic field of magnetized fluid particles: exact all-pairs sums and a Barnes-Hut
// octree, over the same particles in the same (Morton) order.
//
// Discretization. Particle j is a uniformly magnetized sphere of its volume V_j (radius
// a_j = (3 V_j / 4 pi)^(1/3)) with magnetization M_j, moment m_j = V_j M_j. Its field is
//   outside (r >= a_j):  H = (3 r (r . m_j) / r^5 - m_j / r^3) / (4 pi)   (exact point dipole)
//   inside  (r <  a_j):  H = -M_j / 3 = -m_j / (4 pi a_j^3)               (uniform)
// so it is finite everywhere, including at the particle's own centre (its self field
// -M_j / 3) and at coincident particles. The field at particle i sums every particle,
// itself included: on a cubic lattice the other particles' dipoles give the Lorentz local
// field H_macro + M / 3 and the own sphere's -M / 3 cancels the cavity term, so the
// particle field is the macroscopic field H of continuum magnetostatics (Clausius-Mossotti
// done right; tests/sim/magnetics/test_MagnetizationSolver.cpp checks a lattice sphere against 3 H0 / (3 + chi)).
//
// Tree. Particles are sorted along a Morton curve (cubic root cell); octree cells are
// contiguous index ranges. Each cell carries the multipole expansion of its dipoles about
// its volume centroid: total moment, quadrupole and octupole (the first and second moments
// of the dipoles, symmetric trace-free parts). The centroid is fixed by the positions, so
// the operator stays linear in M, as the self-consistent solver needs. Opening criterion
// (classic Barnes-Hut, "cell size / distance"): a cell whose particles' bounding box has
// largest side L is used as one expansion for targets at distance d > L / theta from its
// centroid (and outside all of its particles' spheres); nearer cells are opened down to
// leaves, whose particles are summed exactly. Targets are grouped by leaf (d is measured to
// the leaf's box): one interaction list per leaf (cells + particle ranges), built once per
// set of positions and re-used by every field evaluation of a solve. Measured on a 40,960
// particle layer: theta 0.5 -> ~0.1-0.4 % RMS error of the particle field, ~200 cells and
// ~400 particles per target (see tests/bench/bench_magnetization.cpp).
//
// Numbers. Positions and moments are float inside (SoA, SSE kernels), scaled by the mean
// particle radius so that float ranges do not depend on the scene's units. All-pairs sums
// are float within blocks of 4,096 sources and double across blocks; a tree sum (a few
// hundred terms) is float; point evaluations (fieldAt, gradientAt) are double throughout.
// Evaluation is deterministic: every target sums its sources in a fixed order.
#include "sim/core/Types.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace ferro {

using Mat3f = Eigen::Matrix3f;
using Mat3d = Eigen::Matrix3d;

class DipoleTree {
public:
    /// The default particle model: Wendland C2 support radius over the particle spacing
    /// V^(1/3) (MagnetizationParams::smoothing; see the file comment for the choice).
    static constexpr double kDefaultSmoothing = 2.5;
    /// Particle model of the next build(): smoothing > 0 spreads each moment over a Wendland
    /// C2 kernel of support smoothing * V^(1/3); 0 (or negative) makes every particle a
    /// uniformly magnetized sphere of its volume (the model before smoothed dipoles).
    void setSmoothing(double smoothing) { smoothing_ = smoothing > 0 ? smoothing : 0.0; }
    double smoothing() const { return smoothing_; }

    /// Sorts the particles at x [m] with volumes [m^3] (negative or non-finite volumes count
    /// as 0, i.e. a particle without moment) and builds the octree. With openingAngle > 0
    /// the per-leaf interaction lists are built too (needed by the tree evaluations);
    /// openingAngle is clamped to [0.05, 1]. leafSize: most particles per leaf.
    /// Non-finite positions are placed at the origin (the caller should not pass them).
    void build(const std::vector<Vec3>& x, const std::vector<Real>& volume, double openingAngle,
               int leafSize = 32);

    size_t size() const { return order_.size(); }
    /// order()[k] = index (in the build() input) of the particle in sorted place k.
    const std::vector<uint32_t>& order() const { return order_; }
    double openingAngle() const { return theta_; }
    /// Mean far-field (cells) and near-field (particles) interactions per target: the cost
    /// of one tree evaluation is about size() * (far + near) kernel calls.
    void interactionCounts(double& farPerTarget, double& nearPerTarget) const;

    /// Sets the magnetization, M[3k..3k+2] = M of sorted particle k [A/m], and sums the
    /// cell moments. Must be called after build() and before the evaluations below.
    void setMagnetization(const Eigen::VectorXd& M);
    /// Same from float vectors in build() input order (original indices).
    void setMagnetizationUnsorted(const std::vector<Vec3>& M);

    /// Field of all particles at every particle (self term -M/3 included), sorted order,
    /// H[3k..3k+2] [A/m]. useTree = false sums all pairs exactly (O(N^2)), true uses the
    /// interaction lists (requires openingAngle > 0 at build()).
    void fieldAtParticles(Eigen::VectorXd& H, bool useTree) const;
    /// Exact all-pairs field (float kernels, as fieldAtParticles(H, false)) at the sorted
    /// particles `targets` only: H[3q..3q+2] for targets[q]. For sampled error estimates
    /// and for timing the all-pairs sum on a subset.
    void fieldAtParticlesDirect(const std::vector<uint32_t>& targets, Eigen::VectorXd& H) const;
    /// Jacobian dH_a/dx_b [A/m^2] of the field of all OTHER particles at every particle
    /// (the own sphere's field is uniform; other spheres containing the particle add zero
    /// gradient), sorted order.
    void gradientAtParticles(std::vector<Mat3f>& J, bool useTree) const;

    /// Field at sorted particle k alone: exact sum over all particles, or the tree's value
    /// (the same number fieldAtParticles(H, true) gives for k). For error estimates.
    Eigen::Vector3d fieldAtParticleDirect(size_t k) const;
    Eigen::Vector3d fieldAtParticleTree(size_t k) const;

    /// Field [A/m] and its Jacobian [A/m^2] at an arbitrary point p [m], double precision:
    /// tree traversal with the opening angle of build() (exact sum if it was 0). A point
    /// inside a particle's sphere gets that sphere's uniform -M/3 and no gradient from it.
    Eigen::Vector3d fieldAt(const Eigen::Vector3d& p) const;
    Mat3d gradientAt(const Eigen::Vector3d& p) const;
    /// Exact all-particle sum at p (O(N)), double.
    Eigen::Vector3d fieldAtDirect(const Eigen::Vector3d& p) const;

    /// Volume-weighted centroid [m] and total moment sum V M [A m^2] of all particles.
    Eigen::Vector3d centroid() const;
    Eigen::Vector3d totalMoment() const;

private:
    struct Node {
        uint32_t begin = 0, end = 0;   // sorted particle range
        uint32_t firstChild = 0;       // children are consecutive nodes
        uint32_t childCount = 0;       // 0 = leaf
        float c[3] = {0, 0, 0};        // expansion centre (volume centroid), scaled units
        float radius = 0;              // max |x_j - c|, scaled
        float maxA = 0;                // largest particle radius in the cell, scaled
        float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}; // box of the particle centres, scaled
    };
    void fillNode(uint32_t index, uint32_t begin, uint32_t end, int level, const std::vector<uint64_t>& codes);
    void finishNode(Node& n) const;
    void buildInteractionLists();
    void sumCellMoments();
    bool accept(const Node& cell, double d) const;
    void gatherFar(size_t leaf, std::vector<float>& buf, size_t& count) const;
    // Adds Term (FieldTerm or GradientTerm in the .cpp, without 1/4pi, scaled units) at sorted
    // particle k of `leaf`: its far cells (gathered in buf by gatherFar) plus its near particles.
    template <class Term>
    void treeSum(size_t leaf, size_t k, const std::vector<float>& buf, size_t farCount, float* out) const;
    // Calls visit(leaf, k, buf, farCount) for every sorted particle k, leaves in parallel, each
    // leaf's far cells gathered once.
    template <class Visit>
    void forEachTreeTarget(Visit&& visit) const;
    void treeFieldAt(size_t leaf, size_t k, const std::vector<float>& buf, size_t farCount, double h[3]) const;
    // Surface sampling term (smoothed model only): h -= w_k (n_k . M_k) n_k, see the file comment.
    void computeSurfaceTerms();
    void addSurfaceTerm(size_t k, double h[3]) const;
    template <class Leaf, class Cell>
    void traverse(const Eigen::Vector3d& q, Leaf&& leaf, Cell&& cell) const;
    size_t leafOf(size_t k) const;

    double scale_ = 1;      // length unit of the internal coordinates [m]
    Eigen::Vector3d origin_{0, 0, 0}; // origin of the internal coordinates [m]
    uint32_t leafSize_ = 16;
    double theta_ = 0;
    std::vector<uint32_t> order_;
    // sorted particles, scaled units, SoA
    double smoothing_ = kDefaultSmoothing; // kernel support / particle spacing; 0 = spheres
    std::vector<float> px_, py_, pz_, a2_, ainv_, vol_; // a2_, ainv_: core radius^2, 1 / core radius
    std::vector<float> mx_, my_, mz_;  // moments V M (scaled volume), set by setMagnetization
    std::vector<float> surfaceWeight_, surfaceNormal_; // per particle w = max(0, 1 - n), outward normal (3)
    std::vector<Node> nodes_;
    std::vector<float> cell_;            // per cell: moment, quadrupole, octupole (see .cpp)
    std::vector<uint32_t> leaves_;       // node index of each leaf, increasing begin
    std::vector<uint32_t> leafBegin_;    // first particle of each leaf (for leafOf)
    // per-leaf interaction lists (CSR)
    std::vector<uint32_t> farStart_, farCells_;
    std::vector<uint32_t> nearStart_, nearRanges_; // pairs (begin, end)
};

} // namespace ferro

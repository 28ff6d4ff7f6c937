#pragma once
// The magnetic field of magnetized fluid particles: exact all-pairs sums and a Barnes-Hut
// octree, over the same particles in the same (Morton) order. Particle j's moment V_j M_j is
// spread over a Wendland C2 kernel of support smoothing * V_j^(1/3) (a point dipole outside
// it, bounded inside; smoothing = 0: a uniformly magnetized sphere); the field at a particle
// centre also drops the outside part of the normal jump near the free surface (surface term)
// and, optionally, the particle-scale noise of the operator (local correction). Far cells
// enter as dipole, quadrupole and octupole expansions (opening angle theta). Float SoA with
// SSE inside, scaled by the mean particle radius; point evaluations in double; every target
// sums its sources in a fixed order. The derivation, why this kernel, and the measurements:
// docs/physics/particle-field.md.
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
    /// Surface term onset between deficits 0.05 and 0.15 (true) or from any deficit (false,
    /// the model before the local correction); takes effect at the next build().
    void setSurfaceOnset(bool on) { surfaceOnset_ = on; }
    double smoothing() const { return smoothing_; }
    /// Periodic side walls (container.periodic_sides) for the next build(): the particles
    /// repeat with periods Lx, Ly [m] in x and y (0 = that axis is not periodic). build()
    /// then adds the eight neighbouring copies of the particles to the tree, and the field at
    /// the particles sums those exactly (tree or all pairs) plus every farther copy as the
    /// copy's total moment at its centre, out to 200 periods, and the continuum beyond (the
    /// 2D lattice sum of dipoles converges absolutely: the far copies shift the field by
    /// about thickness / (3 L) of M). Evaluations then cover the copies as well: size() is
    /// 9 n (3 n with one periodic axis), sorted place k holds input particle order()[k] % n,
    /// the copies' values are their particle's (setMagnetization must give a copy its
    /// particle's M, as a field-driven M does); only the n particles are evaluated.
    void setPeriodic(double Lx, double Ly) {
        period_[0] = Lx > 0 ? Lx : 0.0;
        period_[1] = Ly > 0 ? Ly : 0.0;
    }
    bool periodic() const { return period_[0] > 0 || period_[1] > 0; }
    /// The input particles of the last build() (size() without the periodic copies).
    size_t targetCount() const { return targetCount_; }
    /// Sorted place k is an input particle, not a periodic copy.
    bool isTarget(size_t k) const { return order_[k] < targetCount_; }

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

    /// Field of all particles at every particle (self term and surface term included), sorted order,
    /// H[3k..3k+2] [A/m]. useTree = false sums all pairs exactly (O(N^2)), true uses the
    /// interaction lists (requires openingAngle > 0 at build()).
    void fieldAtParticles(Eigen::VectorXd& H, bool useTree) const;
    /// Exact all-pairs field (float kernels, as fieldAtParticles(H, false)) at the sorted
    /// particles `targets` only: H[3q..3q+2] for targets[q]. For sampled error estimates
    /// and for timing the all-pairs sum on a subset.
    void fieldAtParticlesDirect(const std::vector<uint32_t>& targets, Eigen::VectorXd& H) const;
    /// Jacobian dH_a/dx_b [A/m^2] of the particle field at every particle, sorted order: the
    /// smoothed kernels' closed-form Jacobian (the own kernel's is zero at its centre; the
    /// surface term and the local correction are not differentiated). Sphere model: other spheres containing the
    /// particle, and its own, add zero gradient (uniform field inside).
    void gradientAtParticles(std::vector<Mat3f>& J, bool useTree) const;

    /// Field at sorted particle k alone: exact sum over all particles, or the tree's value
    /// (the same number fieldAtParticles(H, true) gives for k). For error estimates.
    Eigen::Vector3d fieldAtParticleDirect(size_t k) const;
    Eigen::Vector3d fieldAtParticleTree(size_t k) const;

    /// Local consistency correction (smoothed model only; see the file comment): measures
    /// the field operator's particle-scale noise for a uniform magnetization (three field
    /// evaluations, tree if useTree and the build has lists, else exact) and from then on
    /// every particle-centre field (fieldAtParticles, fieldAtParticle*) subtracts it.
    /// build() clears it. Keeps the magnetization set before the call.
    void computeLocalCorrection(bool useTree);
    bool hasLocalCorrection() const { return !localCorrection_.empty(); }
    /// Support of the neighbour mean in computeLocalCorrection, in particle supports.
    static constexpr double kCorrectionReach = 2.0;

    /// Field [A/m] and its Jacobian [A/m^2] at an arbitrary point p [m], double precision:
    /// tree traversal with the opening angle of build() (exact sum if it was 0): the smoothed
    /// field, without the surface term. Sphere model: a point inside a particle's sphere gets
    /// that sphere's uniform -M/3 and no gradient from it.
    Eigen::Vector3d fieldAt(const Eigen::Vector3d& p) const;
    Mat3d gradientAt(const Eigen::Vector3d& p) const;
    /// Exact all-particle sum at p (O(N)), double.
    Eigen::Vector3d fieldAtDirect(const Eigen::Vector3d& p) const;

    /// Volume-weighted centroid [m] and total moment sum V M [A m^2] of the input particles
    /// (one period's, without the periodic copies).
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
    void buildFrom(const std::vector<Vec3>& x, const std::vector<Real>& volume, double openingAngle, int leafSize);
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
    /// Particle ranges [begin, end) of the leaves whose boxes lie closer than reach [m] to
    /// target's box, as pairs in ranges (stack: scratch); used by the local passes.
    void leavesWithin(const Node& target, double reach, std::vector<uint32_t>& stack,
                      std::vector<uint32_t>& ranges) const;
    void addSurfaceTerm(size_t k, double h[3]) const;
    template <class Leaf, class Cell>
    void traverse(const Eigen::Vector3d& q, Leaf&& leaf, Cell&& cell) const;
    size_t leafOf(size_t k) const;
    // Periodic copies: every non-target place takes its particle's value (stride floats or
    // doubles a place); the far copies' uniform field.
    template <class T>
    void copyToImages(T* values, int stride) const;
    void addFarImages(double* H) const;
    bool leafHasTarget(size_t l) const { return leafHasTarget_.empty() || leafHasTarget_[l]; }
    double period_[2] = {0, 0};
    size_t targetCount_ = 0;
    std::vector<uint32_t> sourceSlot_;   // periodic: sorted place of each place's particle
    std::vector<char> leafHasTarget_;    // periodic: leaf holds an input particle
    Eigen::Matrix3d farImages_ = Eigen::Matrix3d::Zero(); // H = farImages_ * (sum over one period of V M) [1/m^3]
    Eigen::Vector3d farField_ = Eigen::Vector3d::Zero();  // the far copies' field of the set magnetization [A/m]

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
    std::vector<float> localCorrection_; // per particle D_k (9, row-major), see computeLocalCorrection
    bool surfaceOnset_ = true;           // see setSurfaceOnset
    std::vector<Node> nodes_;
    std::vector<float> cell_;            // per cell: moment, quadrupole, octupole (see .cpp)
    std::vector<uint32_t> leaves_;       // node index of each leaf, increasing begin
    std::vector<uint32_t> leafBegin_;    // first particle of each leaf (for leafOf)
    // per-leaf interaction lists (CSR)
    std::vector<uint32_t> farStart_, farCells_;
    std::vector<uint32_t> nearStart_, nearRanges_; // pairs (begin, end)
};

} // namespace ferro

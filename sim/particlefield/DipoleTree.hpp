#pragma once
// The magnetic field of magnetized fluid particles: exact all-pairs sums and a Barnes-Hut
// octree, over the same particles in the same (Morton) order.
//
// Discretization (default: smoothed dipoles). Particle j carries the moment m_j = V_j M_j
// spread over a Wendland C2 kernel of support radius a_j = smoothing * V_j^(1/3)
// (MagnetizationParams::smoothing, default 2.5 particle spacings):
//   W(r) = 21 / (2 pi a^3) (1 - q)^4 (1 + 4 q),  q = r / a < 1   (integral 1).
// The field of that smoothed magnetization is H = grad (m . grad psi) with psi the Newton
// potential of W (magnetic charge -m . grad W): the smoothed-dipole idea of Huang, Haedrich
// and Michels, "On the accurate large-scale simulation of ferrofluids", SIGGRAPH 2019; the
// kernel choice and closed form here are derived for this code. With the enclosed kernel
// mass Q(r) = int_{|s|<r} W (H = (d^2 psi/dr^2) r^ r^ + (dpsi/dr / r)(I - r^ r^) applied
// to m, dpsi/dr = -Q / (4 pi r^2)):
//   4 pi H = (3 Q / r^5 - 4 pi W / r^2) r (r . m) - (Q / r^3) m
//   Q = 14 q^3 - 84 q^5 + 140 q^6 - 90 q^7 + 21 q^8   (q < 1),  Q = 1 outside,
// so outside the support (r >= a) it is exactly the point dipole
//   4 pi H = 3 r (r . m) / r^5 - m / r^3,
// and inside it is a bounded polynomial (the coefficients in DipoleTree.cpp). At the centre
// H = -W(0) m / 3 = -(7 / (2 pi a^3)) m: the particle's self field, which for a lone particle
// is -7 / (2 pi smoothing^3) M (-0.071 M at 2.5) instead of a sphere's -M / 3; in a filled
// region the overlapping kernels of the neighbours make up the rest. The Jacobian (the Kelvin
// force's dH/dx) is the derivative of the same closed form, bounded everywhere. Why this
// kernel: W has a positive Fourier transform (Wendland functions are positive definite in
// 3D), so the particle field operator A is negative semidefinite for ANY particle positions,
// and I - chi A has its spectrum in [1, 1 + chi]: the self-consistent solve converges for
// every chi, where the sphere model's indefinite near field stalls at chi >~ 3 on disordered
// sets. Inside a uniformly magnetized region at least one support from its surface the
// smoothed field is exactly the continuum one (a radially symmetric kernel does not change
// a uniform interior field), so the macroscopic field is right without any lattice symmetry.
//
// Surface term. A particle within one support of the fluid's surface samples, through its
// neighbours' kernels, the smoothed field on both sides of the surface, where the continuum
// field jumps by the normal component (M . n) n. That biases the magnetization of the
// surface layer (a sphere's poles pick up extra moment, i.e. the ball acts prolate: +5 % on
// the interior field of a 10-spacing ball at chi = 10). The field at particle k therefore
// gets the outside part removed:
//   H_k -= max(0, 1 - n_k) (n_k_hat . M_k) n_k_hat,   n_k = sum_j V_j W_j(x_k - x_j),
//   n_k_hat = -grad n_k / |grad n_k|
// (n_k is the filled fraction of k's kernel, 1 inside the fluid; the term is zero there).
// It is local and positive semidefinite, so the operator keeps its spectrum bound. It acts
// at particle centres only: fieldAt() and gradientAt() at arbitrary points give the smoothed
// field itself, fieldAtParticle*() and fieldAtParticles() include the term. It sets in
// smoothly between deficits 1 - n_k of 0.05 and 0.15: inside a disordered fluid n scatters by
// a few percent, and those interior particles would get a one-sided term along a random
// normal (a bias of ~1 % of the interior field at chi = 10 on a 0.2-jittered ball).
//
// Local correction (computeLocalCorrection; MagnetizationParams::localCorrection, off by
// default in the simulation: MagnetizationParams.hpp says why; with it on, the surface term's
// onset above applies, off the term acts from any deficit as before). The smoothed field of a uniform M is exact in the continuum, but the discrete
// sum at particle k sees its near neighbours' directions through the bounded near field
// (3 Q / r^3 - 4 pi W) r^ r^: on a disordered set that is a random, traceless-dominated
// error of a few percent of M per particle, amplified by the self-consistent solve (on a
// ball jittered by 0.2 spacings: 5.6 % RMS field error at chi = 3, 11.5 % at 10, single
// particles 41 % off). It is not a density error: volumes from the SPH density
// (V = 1 / sum_j W_ij, paper eq. 7's m_j / rho_j: 4.8 % against 5.0 % at chi = 3, tests'
// "[.figures]") or volumes iterated until this kernel's sum is 1 within 0.3 % at every
// particle (5.9 %, measured once) leave it where it is. The correction
// measures it: K_k = the field at k of a uniform unit M along each axis (three field
// evaluations of the operator itself, surface term included) is the body's demagnetization
// tensor N(x_k), smooth on the body's scale, plus the particle-scale noise. Minus the
// smooth part of K at x_k (a kernel-weighted linear least-squares fit to the neighbours' K
// over twice the support, k itself excluded: a plain mean would be biased where the
// neighbourhood is one-sided, near a surface or a floor, and N varies there) it
// is the noise D_k, and the field at particle k becomes H_k - D_k M_k. Like SPH's kernel
// gradient correction it makes the discrete operator reproduce the uniform case; it acts
// in the interior only (weight rising from fill n_k = 0.7 to 0.8), where the surface term
// does not. Measured: jittered ball RMS 1.2 % (chi 3) and 2.2 % (chi 10), worst 7.6 %; a
// ball from a settled SPH tank 0.86 % (was 0.93 %) at chi 10. The operator is no longer
// exactly semidefinite, but D is a few percent: Newton-GMRES takes the same number of
// evaluations (tests up to chi 10). Cost: three field evaluations and one neighbour pass
// per build.
//
// smoothing = 0 selects the older model: particle j a uniformly magnetized sphere of its
// volume (radius a_j = (3 V_j / 4 pi)^(1/3)), point dipole outside, -M_j / 3 inside. On a
// cubic lattice the other particles' dipoles give the Lorentz local field H_macro + M / 3
// and the own sphere's -M / 3 cancels the cavity term (Clausius-Mossotti); on any other
// arrangement (a settled SPH state is disordered and slightly compressed) the near sums do
// not cancel: 6-12 % field error at chi = 0.5-1 and no convergence at chi >= 3 (tests in
// tests/sim/magnetics/test_MagnetizationSolver.cpp).
//
// Tree. Particles are sorted along a Morton curve (cubic root cell); octree cells are
// contiguous index ranges. Each cell carries the multipole expansion of its dipoles about
// its volume centroid: total moment, quadrupole and octupole (the first and second moments
// of the dipoles, symmetric trace-free parts). The centroid is fixed by the positions, so
// the operator stays linear in M, as the self-consistent solver needs. Opening criterion
// (classic Barnes-Hut, "cell size / distance"): a cell whose particles' bounding box has
// largest side L is used as one expansion for targets at distance d > L / theta from its
// centroid and outside the support (or sphere) of every one of its particles, where each
// is exactly a point dipole; nearer cells are opened down to leaves, whose particles are
// summed exactly with the smoothed near field. Targets are grouped by leaf (d is measured to
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
    /// Surface term onset between deficits 0.05 and 0.15 (true) or from any deficit (false,
    /// the model before the local correction); takes effect at the next build().
    void setSurfaceOnset(bool on) { surfaceOnset_ = on; }
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
    /// Surface sampling term's weight w = max(0, 1 - n_k) of sorted particle k (0 inside the
    /// fluid, about 1/2 in the top layer of a flat surface; 0 for the sphere model) and its
    /// outward normal (zero where w = 0).
    float surfaceWeight(size_t k) const { return surfaceWeight_.empty() ? 0.0f : surfaceWeight_[k]; }
    Eigen::Vector3f surfaceNormal(size_t k) const {
        return surfaceNormal_.empty() ? Eigen::Vector3f::Zero()
                                      : Eigen::Vector3f(surfaceNormal_[3 * k], surfaceNormal_[3 * k + 1], surfaceNormal_[3 * k + 2]);
    }
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
    /// Particle ranges [begin, end) of the leaves whose boxes lie closer than reach [m] to
    /// target's box, as pairs in ranges (stack: scratch); used by the local passes.
    void leavesWithin(const Node& target, double reach, std::vector<uint32_t>& stack,
                      std::vector<uint32_t>& ranges) const;
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

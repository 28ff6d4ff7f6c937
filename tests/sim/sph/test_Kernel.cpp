// Kernel properties: normalization, gradient antisymmetry and consistency, compact support;
// the scalar kernels against their formulas, and the SSE kernels against the scalar ones.
#include "sim/sph/Kernel.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace ferro;

TEST_CASE("cubic spline integrates to one over its support", "[kernel]") {
    for (double h : {0.5, 1.0, 0.0025}) {
        const CubicSplineKernel k{Real(h)};
        // Radial integral 4 pi r^2 W(r) dr with the midpoint rule.
        const int n = 20000;
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            const double r = (i + 0.5) * h / n;
            sum += 4 * kPi * r * r * k.W(Real(r)) * h / n;
        }
        REQUIRE(sum == Approx(1.0).epsilon(1e-4));
    }
}

TEST_CASE("cubic spline lattice sum approximates 1/volume", "[kernel]") {
    // On a cubic lattice of spacing s with h = 2 s the kernel sum is close to 1/s^3: the
    // SPH density of a lattice is within a few percent of the continuum value.
    const double s = 0.001;
    const CubicSplineKernel k(Real(2 * s));
    double sum = 0;
    for (int i = -2; i <= 2; ++i)
        for (int j = -2; j <= 2; ++j)
            for (int l = -2; l <= 2; ++l) sum += k.W(Real(s * std::sqrt(double(i * i + j * j + l * l))));
    REQUIRE(sum * s * s * s == Approx(1.0).epsilon(0.05));
}

TEST_CASE("cubic spline has compact support and a continuous profile", "[kernel]") {
    const CubicSplineKernel k(2);
    REQUIRE(k.W(2) == 0);
    REQUIRE(k.W(2.5f) == 0);
    REQUIRE(k.gradW(Vec3(2.2f, 0, 0), 2.2f).norm() == 0);
    REQUIRE(k.W(1.999f) > 0);
    REQUIRE(k.W(0) == Approx(k.W0()));
    // Continuity at the branch point q = 1/2 and monotone decrease.
    REQUIRE(k.W(0.99999f) == Approx(k.W(1.00001f)).epsilon(1e-4));
    for (float r = 0.01f; r < 2; r += 0.01f) REQUIRE(k.W(r) < k.W(r - 0.01f));
}

TEST_CASE("kernel gradient is antisymmetric and matches finite differences", "[kernel]") {
    const CubicSplineKernel k(0.004f);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-0.0025f, 0.0025f);
    for (int t = 0; t < 1000; ++t) {
        const Vec3 rij(u(rng), u(rng), u(rng));
        const float r = rij.norm();
        const Vec3 g = k.gradW(rij, r);
        const Vec3 gBack = k.gradW(Vec3(-rij), r);
        // Exact (bitwise) antisymmetry: pairwise forces cancel to the last bit.
        REQUIRE(g.x() == -gBack.x());
        REQUIRE(g.y() == -gBack.y());
        REQUIRE(g.z() == -gBack.z());
        if (r < 0.0039f && r > 1e-4f) {
            // Central difference of W along each axis, in double.
            for (int a = 0; a < 3; ++a) {
                const double eps = 1e-6;
                Eigen::Vector3d p = rij.cast<double>(), m = p;
                p[a] += eps;
                m[a] -= eps;
                const double fd = (double(k.W(float(p.norm()))) - double(k.W(float(m.norm())))) / (2 * eps);
                REQUIRE(g[a] == Approx(fd).margin(2e-3 * k.W0() / 0.004));
            }
        }
        // The gradient points toward the centre (W decreases outward).
        if (r > 1e-6f && r < 0.004f) REQUIRE(g.dot(rij) < 0);
    }
}

TEST_CASE("Akinci cohesion kernel: support, repulsion core, attraction", "[kernel]") {
    const CohesionKernel c(1);
    REQUIRE(c.C(1) == 0);
    REQUIRE(c.C(1.2f) == 0);
    REQUIRE(c.C(0.05f) < 0);  // repulsive near the centre
    REQUIRE(c.C(0.75f) > 0);  // attractive in the outer half
    REQUIRE(c.C(0.4999f) == Approx(c.C(0.5001f)).epsilon(1e-2));
}

namespace {

// Monaghan's cubic spline with support h, written out from the formula (Monaghan 1992 with
// smoothing length h / 2; normalisation 8 / (pi h^3)), in double: q = r / h,
//   W = 8 / (pi h^3) (6 q^3 - 6 q^2 + 1)   for q <= 1/2,
//   W = 8 / (pi h^3) 2 (1 - q)^3          for 1/2 < q <= 1, 0 beyond;
// dW/dr = 48 / (pi h^4) (3 q^2 - 2 q) and -48 / (pi h^4) (1 - q)^2 on the two pieces.
double splineW(double r, double h) {
    const double q = r / h, k = 8 / (kPi * h * h * h);
    if (q <= 0.5) return k * (6 * q * q * q - 6 * q * q + 1);
    if (q <= 1) return k * 2 * (1 - q) * (1 - q) * (1 - q);
    return 0;
}
/// s(r) = (dW/dr) / r, the factor of grad W = s (x_i - x_j); 0 at r = 0 by convention.
double splineGradFactor(double r, double h) {
    const double q = r / h, l = 48 / (kPi * h * h * h * h);
    if (r <= 0 || q >= 1) return 0;
    return (q <= 0.5 ? l * (3 * q * q - 2 * q) : -l * (1 - q) * (1 - q)) / r;
}
/// Akinci et al. 2013, eq. (2): C(r) = 32 / (pi h^9) of (h - r)^3 r^3 for h/2 < r <= h and
/// 2 (h - r)^3 r^3 - h^6 / 64 for 0 < r <= h/2, 0 otherwise.
double akinciC(double r, double h) {
    if (r <= 0 || r >= h) return 0;
    const double c = 32 / (kPi * std::pow(h, 9)), v = std::pow(h - r, 3) * std::pow(r, 3);
    return 2 * r > h ? c * v : c * (2 * v - std::pow(h, 6) / 64);
}

} // namespace

TEST_CASE("scalar kernels match the cubic spline and Akinci's cohesion written out", "[kernel]") {
    for (float h : {1.0f, 0.004f, 0.0025f}) {
        const CubicSplineKernel k(h);
        const CohesionKernel c(h);
        const double w0 = 8 / (kPi * double(h) * h * h), s0 = 48 / (kPi * std::pow(double(h), 5));
        const double c0 = 32 / (kPi * std::pow(double(h), 9)) * std::pow(double(h), 6) / 64; // |C(0+)|
        REQUIRE(k.W0() == Approx(w0).epsilon(1e-6));
        for (int i = 0; i <= 1200; ++i) {
            const float r = h * float(i) / 1000;   // [0, 1.2 h], including 0, h/2 and h
            CAPTURE(h, i, r);
            // Float rounding of q = r / h moves W by ~1e-7 of its scale: compare relatively,
            // with a floor of 1e-6 of the scale where the value itself goes to zero.
            REQUIRE(k.W(r) == Approx(splineW(r, h)).epsilon(1e-5).margin(1e-6 * w0));
            REQUIRE(k.gradWFactor(r) == Approx(splineGradFactor(r, h)).epsilon(1e-5).margin(1e-6 * s0));
            REQUIRE(c.C(r) == Approx(akinciC(r, h)).epsilon(1e-5).margin(1e-6 * c0));
        }
        REQUIRE(k.W(h) == 0);
        REQUIRE(k.gradWFactor(h) == 0);
        REQUIRE(k.gradWFactor(0) == 0);
        REQUIRE(c.C(0) == 0);
        REQUIRE(c.C(h) == 0);
        REQUIRE(k.W(h / 2) == Approx(w0 / 4).epsilon(1e-6));    // both pieces give 1/4 there
        REQUIRE(c.C(h / 2) == Approx(c0).epsilon(1e-5));        // 2 (h/2)^6 - h^6/64 = h^6/64
    }
}

#if defined(__SSE2__)
TEST_CASE("SSE kernels (four pairs at a time) equal the scalar kernels lane by lane", "[kernel]") {
    // The production force sweep (FluidSimulation::computeAccelerations) evaluates W's
    // gradient and the cohesion through CubicSplineKernel4 and CohesionKernel4; the scalar
    // tail and every other loop through the scalar kernels. They must agree to float rounding.
    std::mt19937 rng(5);
    for (float h : {1.0f, 0.004f, 0.0025f}) {
        const CubicSplineKernel k(h);
        const CohesionKernel c(h);
        const CubicSplineKernel4 k4(k);
        const CohesionKernel4 c4(c);
        std::vector<float> rs = {0.0f, h / 2, h, std::nextafter(h, 0.0f), std::nextafter(h / 2, 0.0f),
                                 std::nextafter(h / 2, 2 * h), 1.2f * h, 1e-12f * h};
        for (int i = 0; i <= 1200; ++i) rs.push_back(h * float(i) / 1000);
        std::uniform_real_distribution<float> u(0, 1.2f * h);
        for (int i = 0; i < 4000; ++i) rs.push_back(u(rng));
        while (rs.size() % 4) rs.push_back(0.5f * h);
        std::shuffle(rs.begin(), rs.end(), rng); // every kind of r in every lane
        const float wScale = k.W0(), sScale = k.gradientScale() * k.invRadius() * k.invRadius();
        const float cScale = c.scale() * c.innerOffset();
        for (size_t i = 0; i < rs.size(); i += 4) {
            const __m128 r4 = _mm_setr_ps(rs[i], rs[i + 1], rs[i + 2], rs[i + 3]);
            alignas(16) float w[4], g[4], co[4];
            _mm_store_ps(w, k4.W(r4));
            _mm_store_ps(g, k4.gradFactor(r4));
            _mm_store_ps(co, c4.C(r4));
            for (int lane = 0; lane < 4; ++lane) {
                const float r = rs[i + lane];
                CAPTURE(h, r, lane);
                REQUIRE(std::isfinite(w[lane]));
                REQUIRE(std::isfinite(g[lane]));
                REQUIRE(std::isfinite(co[lane]));
                REQUIRE(w[lane] == Approx(k.W(r)).epsilon(1e-6).margin(1e-7 * wScale));
                REQUIRE(g[lane] == Approx(k.gradWFactor(r)).epsilon(1e-6).margin(1e-7 * sScale));
                REQUIRE(co[lane] == Approx(c.C(r)).epsilon(1e-6).margin(1e-7 * cScale));
                if (r >= h) {
                    REQUIRE(w[lane] == 0);
                    REQUIRE(g[lane] == 0);
                    REQUIRE(co[lane] == 0);
                }
                if (r == 0) {
                    REQUIRE(w[lane] == wScale);
                    REQUIRE(g[lane] == 0);
                    REQUIRE(co[lane] == 0);
                }
            }
        }
    }
}
#endif

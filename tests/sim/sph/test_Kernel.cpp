// Kernel properties: normalization, gradient antisymmetry and consistency, compact support.
#include "sim/sph/Kernel.hpp"

#include <catch2/catch.hpp>

#include <random>

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

TEST_CASE("fused kernel evaluation matches W and grad W", "[kernel]") {
    const CubicSplineKernel k(0.003f);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-0.0018f, 0.0018f);
    for (int t = 0; t < 2000; ++t) {
        const Vec3 rij(u(rng), u(rng), u(rng));
        const float r2 = rij.squaredNorm();
        if (r2 >= 0.003f * 0.003f) continue;
        float w;
        Vec3 g;
        k.evaluate(rij, r2, w, g);
        REQUIRE(w == Approx(k.W(std::sqrt(r2))).epsilon(1e-5));
        REQUIRE((g - k.gradW(rij, std::sqrt(r2))).norm() <= 1e-5f * k.gradW(rij, std::sqrt(r2)).norm() + 1e-3f);
    }
}

// Restarted GMRES (sim/core/Gmres.hpp) against Eigen's dense LU solve: a nonsymmetric
// well-conditioned system, a diagonal one (converges in as many steps as distinct
// eigenvalues), the maxApply budget, and restarts.
#include "sim/core/Gmres.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <random>

using namespace ferro;

namespace {

/// I + 0.3 R / sqrt(n) with R uniform in [-1, 1]: nonsymmetric, eigenvalues in a disc of
/// radius ~0.3 * 0.58 about 1, so well conditioned.
Eigen::MatrixXd nonsymmetric(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) A(i, j) += 0.3 * u(rng) / std::sqrt(double(n));
    return A;
}

Eigen::VectorXd randomVector(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) b[i] = u(rng);
    return b;
}

} // namespace

TEST_CASE("GMRES solves a nonsymmetric system to its tolerance", "[gmres]") {
    const int n = 60;
    const Eigen::MatrixXd A = nonsymmetric(n, 3);
    REQUIRE((A - A.transpose()).norm() > 1);
    const Eigen::VectorXd b = randomVector(n, 4);
    const Eigen::VectorXd exact = A.partialPivLu().solve(b);
    int applied = 0;
    auto op = [&](const Eigen::VectorXd& v) { ++applied; return Eigen::VectorXd(A * v); };
    Eigen::VectorXd x;
    double res = -1;
    const double tol = 1e-10 * b.norm();
    const int used = gmres(op, b, x, tol, 200, 100, res);
    CAPTURE(used, res);
    REQUIRE(used == applied);
    REQUIRE(used < n);                       // converged before the Krylov space is full
    REQUIRE(res <= tol);
    REQUIRE((b - A * x).norm() <= 2 * tol);  // the reported residual is the true one
    REQUIRE((b - A * x).norm() == Approx(res).margin(1e-12 * b.norm()));
    // Error <= |A^-1| * residual.
    const double invNorm = A.inverse().operatorNorm();
    REQUIRE((x - exact).norm() <= invNorm * 2 * tol);
}

TEST_CASE("GMRES on a diagonal system with k distinct values converges in k applications", "[gmres]") {
    const int n = 40;
    Eigen::VectorXd d(n);
    for (int i = 0; i < n; ++i) d[i] = 1.0 + (i % 4);   // 4 distinct eigenvalues 1..4
    const Eigen::VectorXd b = randomVector(n, 9);
    auto op = [&](const Eigen::VectorXd& v) { return Eigen::VectorXd(d.asDiagonal() * v); };
    Eigen::VectorXd x;
    double res = -1;
    const int used = gmres(op, b, x, 1e-12, 100, 30, res);
    CAPTURE(used, res);
    REQUIRE(used == 4);   // minimal polynomial of degree 4
    REQUIRE(res <= 1e-12);
    const Eigen::VectorXd exact = b.cwiseQuotient(d);
    REQUIRE((x - exact).norm() <= 1e-11);
}

TEST_CASE("GMRES spends at most maxApply applications, and restarts converge", "[gmres]") {
    const int n = 80;
    // A harder nonsymmetric system: GMRES needs many iterations.
    Eigen::MatrixXd A = nonsymmetric(n, 21) * 1.0;
    for (int i = 0; i < n; ++i) A(i, i) += 0.5 * std::sin(double(i));   // spread the spectrum
    const Eigen::VectorXd b = randomVector(n, 22);
    const Eigen::VectorXd exact = A.partialPivLu().solve(b);
    auto solve = [&](double tol, int maxApply, int restart, Eigen::VectorXd& x, double& res) {
        int applied = 0;
        auto op = [&](const Eigen::VectorXd& v) { ++applied; return Eigen::VectorXd(A * v); };
        const int used = gmres(op, b, x, tol, maxApply, restart, res);
        REQUIRE(used == applied);
        return used;
    };
    Eigen::VectorXd x;
    double res = 0;
    // Unrestarted, to tolerance.
    const int full = solve(1e-10, 1000, 1000, x, res);
    CAPTURE(full);
    REQUIRE(res <= 1e-10);
    REQUIRE((x - exact).norm() <= 1e-8);
    // The budget: stops after exactly maxApply applications, residual reduced but not done.
    const int budget = full / 2;
    REQUIRE(solve(1e-10, budget, 1000, x, res) == budget);
    REQUIRE(res > 1e-10);
    REQUIRE(res < b.norm());
    REQUIRE((b - A * x).norm() == Approx(res).epsilon(1e-6));
    // Restarted every 5 vectors (many restarts): still converges to the tolerance, with
    // more applications than the unrestarted solve and a true residual matching the
    // Arnoldi one carried across the restarts.
    const int restarted = solve(1e-10, 5000, 5, x, res);
    CAPTURE(restarted);
    REQUIRE(res <= 1e-10);
    REQUIRE(restarted > full);
    REQUIRE((b - A * x).norm() <= 1e-9);
    REQUIRE((x - exact).norm() <= 1e-7);
    // A zero right-hand side: x = 0 without a single application.
    double r0 = -1;
    int applied = 0;
    auto op0 = [&](const Eigen::VectorXd& v) { ++applied; return Eigen::VectorXd(A * v); };
    REQUIRE(gmres(op0, Eigen::VectorXd::Zero(n).eval(), x, 1e-12, 10, 5, r0) == 0);
    REQUIRE(applied == 0);
    REQUIRE(x.norm() == 0);
    REQUIRE(r0 == 0);
}

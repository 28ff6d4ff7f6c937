// Self-consistent magnetization (sim/magnetics/MagnetizationSolver, sim/particlefield/DipoleTree): the Langevin
// law, the analytic magnetizable sphere, the solvers against each other, field gradients,
// far fields and regularization.
#include "sim/magnetics/MagnetizationSolver.hpp"
#include "sim/core/Constants.hpp"
#include "sim/core/ParticleFile.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <string>

using namespace ferro;

namespace {

using Solver = MagnetizationParams::Solver;

// Cubic lattice ball of spacing s [m] and radius R [m] centred at c: positions and volumes s^3.
void latticeBall(double s, double R, const Vec3d& c, std::vector<Vec3>& x, std::vector<Real>& V) {
    const int n = int(std::ceil(R / s));
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int k = -n; k <= n; ++k) {
                const Vec3d p(i * s, j * s, k * s);
                if (p.norm() <= R) {
                    x.push_back((c + p).cast<Real>());
                    V.push_back(Real(s * s * s));
                }
            }
}

// Fluid layer on a cubic lattice: a cylinder of radius R and `layers` layers of spacing s,
// bottom at z = s/2, with a slight jitter so the lattice is not perfect.
void layer(double s, double R, int layers, std::vector<Vec3>& x, std::vector<Real>& V) {
    const int n = int(std::ceil(R / s));
    uint32_t state = 12345;
    auto jitter = [&]() {
        state = state * 1664525u + 1013904223u;
        return 0.1 * s * (double(state >> 8) / double(1u << 24) - 0.5);
    };
    for (int k = 0; k < layers; ++k)
        for (int i = -n; i <= n; ++i)
            for (int j = -n; j <= n; ++j) {
                const Vec3d p(i * s, j * s, (k + 0.5) * s);
                if (p.head<2>().norm() <= R) {
                    x.push_back((p + Vec3d(jitter(), jitter(), jitter())).cast<Real>());
                    V.push_back(Real(s * s * s));
                }
            }
}

Magnet uniformField(const Vec3d& dir, double H0) {
    Magnet m;
    m.kind = Magnet::Kind::Uniform;
    m.direction = dir;
    m.strength = H0;
    return m;
}

Magnet dipoleBelow(double z, double moment) {
    Magnet m;
    m.kind = Magnet::Kind::Dipole;
    m.position = Vec3d(0, 0, z);
    m.direction = Vec3d(0, 0, 1);
    m.strength = moment;
    return m;
}

MagnetizationParams params(Solver solver, double chi, double Ms = 0, double tol = 1e-3) {
    MagnetizationParams p;
    p.solver = solver;
    p.susceptibility = chi;
    p.saturation = Ms;
    p.tolerance = tol;
    p.maxIterations = 100;
    return p;
}

bool allFinite(const std::vector<Vec3>& v) {
    for (const Vec3& a : v)
        if (!a.allFinite()) return false;
    return true;
}

} // namespace

TEST_CASE("Langevin law: bounded by Ms, slope chi0 at zero, series and closed form agree", "[magnetization]") {
    const double chi0 = 1.5, Ms = 3e4;
    double prev = 0;
    for (double H = 1e-12; H < 1e15; H *= 1.3) {
        const double M = langevinMagnetization(H, chi0, Ms);
        REQUIRE(M <= Ms);
        REQUIRE(M > 0);
        REQUIRE(M >= prev); // monotone
        REQUIRE(M <= chi0 * H * (1 + 1e-12)); // concave: below the initial slope
        REQUIRE(langevinMagnetization(-H, chi0, Ms) == -M);
        prev = M;
    }
    REQUIRE(langevinMagnetization(1e300, chi0, Ms) == Ms);
    REQUIRE(langevinMagnetization(0, chi0, Ms) == 0);
    // slope chi0 at H -> 0
    for (double H : {1e-9, 1e-3, 1.0}) REQUIRE(langevinMagnetization(H, chi0, Ms) / H == Approx(chi0).epsilon(1e-6));
    REQUIRE(langevinSlope(0, chi0, Ms) == Approx(chi0).epsilon(1e-15));
    REQUIRE(langevinSecant(0, chi0, Ms) == Approx(chi0).epsilon(1e-15));
    // large field: M -> Ms (1 - 1/xi)
    const double Hbig = 1e7, xi = 3 * chi0 * Hbig / Ms;
    REQUIRE(langevinMagnetization(Hbig, chi0, Ms) == Approx(Ms * (1 - 1 / xi)).epsilon(1e-12));
    // linear law when Ms = 0
    REQUIRE(langevinMagnetization(1234.0, chi0, 0) == chi0 * 1234.0);
    // series (below xi = 0.2) and closed form (above) meet continuously
    const double below = std::nextafter(0.2, 0.0);
    REQUIRE(langevin(below) == Approx(langevin(0.2)).epsilon(1e-14));
    REQUIRE(langevinDerivative(below) == Approx(langevinDerivative(0.2)).epsilon(1e-13));
    // closed form in long double far enough from the cancellation
    for (double x : {0.05, 0.1, 0.15, 0.199, 0.25, 0.5, 1.0, 3.0, 30.0}) {
        const long double X = x;
        const long double ref = std::cosh(X) / std::sinh(X) - 1.0L / X;
        REQUIRE(langevin(x) == Approx(double(ref)).epsilon(1e-13));
    }
    // derivative against central differences
    for (double x : {0.01, 0.19, 0.21, 0.7, 2.0, 9.0}) {
        const double h = 1e-5;
        REQUIRE(langevinDerivative(x) == Approx((langevin(x + h) - langevin(x - h)) / (2 * h)).epsilon(1e-8));
    }
    REQUIRE(langevinDerivative(800.0) == Approx(1.0 / (800.0 * 800.0)).epsilon(1e-12));
}

TEST_CASE("Lattice sphere in a uniform field has the interior field 3 H0 / (3 + chi)", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    // 12.5 spacings: the staircase surface biases the interior field by ~18 spacings / R
    // percent for chi = 3 (a discretization effect that vanishes as the ball grows).
    const double s = 1e-3, R = 12.5e-3;
    latticeBall(s, R, Vec3d(0.01, -0.02, 0.03), x, V);
    const double H0 = 1000;
    const std::vector<Magnet> magnets{uniformField(Vec3d(0, 0, 1), H0)};
    for (double chi : {0.5, 1.0, 3.0}) {
        MagnetizationSolver solver(params(Solver::Direct, chi));
        std::vector<Vec3> H, M;
        const auto stats = solver.solve(x, V, magnets, H, M);
        INFO("chi " << chi << ": " << stats.iterations << " evaluations, residual " << stats.residual);
        REQUIRE(stats.solver == Solver::Direct);
        REQUIRE(stats.residual < 1e-3);
        const double Hin = 3 * H0 / (3 + chi);
        double maxErr = 0, sumErr2 = 0;
        int inner = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            if ((x[i].cast<double>() - Vec3d(0.01, -0.02, 0.03)).norm() > 0.7 * R) continue;
            ++inner;
            const double e = (H[i].cast<double>() - Vec3d(0, 0, Hin)).norm() / Hin;
            maxErr = std::max(maxErr, e);
            sumErr2 += e * e;
            REQUIRE((M[i].cast<double>() - chi * H[i].cast<double>()).norm() < 1e-4 * chi * Hin);
        }
        const double rmsErr = std::sqrt(sumErr2 / inner);
        INFO("relative interior error: max " << maxErr << ", rms " << rmsErr << " over " << inner << " particles");
        REQUIRE(inner > 2500);
        REQUIRE(maxErr < 0.03);
        REQUIRE(rmsErr < 0.02);
        // Without the particles' own field (external solver) the interior would be H0.
        CHECK(std::abs(Hin - H0) / Hin > 0.1);
    }
}

TEST_CASE("Saturating sphere: interior field solves H = H0 - M(H) / 3", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    const double s = 1e-3, R = 8.5e-3;
    latticeBall(s, R, Vec3d::Zero(), x, V);
    const double chi0 = 2.0, Ms = 2e4, H0 = 2e4;
    // scalar reference by bisection
    double lo = 0, hi = H0;
    for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        (mid + langevinMagnetization(mid, chi0, Ms) / 3 > H0 ? hi : lo) = mid;
    }
    const double Hin = 0.5 * (lo + hi);
    REQUIRE(Hin > 3 * H0 / (3 + chi0) * 1.05); // saturation matters here
    for (Solver kind : {Solver::Direct, Solver::Tree}) {
        MagnetizationSolver solver(params(kind, chi0, Ms));
        std::vector<Vec3> H, M;
        const auto stats = solver.solve(x, V, {uniformField(Vec3d(1, 0, 0), H0)}, H, M);
        INFO("newton " << stats.newtonSteps << " evaluations " << stats.iterations << " residual " << stats.residual);
        REQUIRE(stats.residual < 1e-3);
        REQUIRE(stats.newtonSteps >= 2);
        double maxErr = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            if (x[i].norm() > 0.7 * R) continue;
            maxErr = std::max(maxErr, (H[i].cast<double>() - Vec3d(Hin, 0, 0)).norm() / Hin);
            REQUIRE(M[i].norm() < Ms);
        }
        REQUIRE(maxErr < 0.03);
    }
}

TEST_CASE("Tree agrees with direct on a 10k-particle layer over a dipole", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    layer(1.24e-3, 0.025, 8, x, V);
    REQUIRE(x.size() > 10000);
    const std::vector<Magnet> magnets{dipoleBelow(-0.015, 1.0)};
    for (double Ms : {0.0, 3e4}) {
        std::vector<Vec3> Hd, Md, Ht, Mt;
        MagnetizationSolver direct(params(Solver::Direct, 2.0, Ms, 1e-3));
        MagnetizationSolver tree(params(Solver::Tree, 2.0, Ms, 1e-3));
        const auto sd = direct.solve(x, V, magnets, Hd, Md);
        const auto st = tree.solve(x, V, magnets, Ht, Mt);
        REQUIRE(sd.residual < 1e-4);
        REQUIRE(st.residual < 1e-4);
        REQUIRE(st.openingAngle == Approx(0.5));
        // the particle field matters here: the external field alone is far off
        std::vector<Vec3> Hext(x.size());
        for (size_t i = 0; i < x.size(); ++i) Hext[i] = magnetField(magnets, x[i].cast<double>()).cast<Real>();
        const double extErr = ferro::test::relativeRms(Hext, Hd);
        const double err = ferro::test::relativeRms(Ht, Hd), errM = ferro::test::relativeRms(Mt, Md);
        std::vector<Vec3> indT(x.size()), indD(x.size());
        for (size_t i = 0; i < x.size(); ++i) {
            indT[i] = Ht[i] - Hext[i];
            indD[i] = Hd[i] - Hext[i];
        }
        const double errInduced = ferro::test::relativeRms(indT, indD);
        INFO("Ms " << Ms << ": tree error " << err << " (M " << errM << ", particle field alone " << errInduced
                   << "), estimate " << st.fieldError << ", external error " << extErr);
        REQUIRE(extErr > 0.1);
        REQUIRE(err < 0.01);
        REQUIRE(errM < 0.01);
        REQUIRE(errInduced < 0.02);
        REQUIRE(st.fieldError < 0.01);
        REQUIRE(st.fieldError > 0.1 * err); // the estimate is of the right size
    }
}

TEST_CASE("External and direct coincide as chi -> 0", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    layer(1.24e-3, 0.008, 4, x, V);
    const std::vector<Magnet> magnets{dipoleBelow(-0.01, 0.5)};
    double prevDiff = 0;
    for (double chi : {1e-2, 1e-3, 1e-4}) {
        std::vector<Vec3> He, Me, Hd, Md;
        MagnetizationSolver ext(params(Solver::External, chi, 0, 1e-4));
        MagnetizationSolver dir(params(Solver::Direct, chi, 0, 1e-4));
        const auto se = ext.solve(x, V, magnets, He, Me);
        dir.solve(x, V, magnets, Hd, Md);
        REQUIRE(se.iterations == 0);
        const double diff = ferro::test::relativeRms(He, Hd);
        INFO("chi " << chi << ": relative difference " << diff << ", estimate " << se.fieldError);
        REQUIRE(diff < chi);        // first order in chi
        REQUIRE(diff > 0.01 * chi); // and not zero: the particle field is there
        REQUIRE(se.fieldError == Approx(diff).epsilon(0.5)); // the sampled estimate is right
        if (prevDiff > 0) REQUIRE(diff == Approx(prevDiff / 10).epsilon(0.1));
        prevDiff = diff;
    }
}

TEST_CASE("Linear magnetization superposes and scales", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    layer(1.24e-3, 0.01, 4, x, V);
    const Magnet a = dipoleBelow(-0.01, 0.5);
    Magnet b = uniformField(Vec3d(1, 0, 1), 3000);
    for (Solver kind : {Solver::Direct, Solver::Tree}) {
        MagnetizationSolver solver(params(kind, 1.5, 0, 1e-5));
        std::vector<Vec3> Ha, Ma, Hb, Mb, Hab, Mab, H2, M2;
        solver.solve(x, V, {a}, Ha, Ma);
        solver.solve(x, V, {b}, Hb, Mb);
        solver.solve(x, V, {a, b}, Hab, Mab);
        // Reversed, not scaled: a magnet's body radius grows with its strength
        // (magnetBodyRadius), which changes the near field, so only the sign is exactly linear.
        Magnet a2 = a;
        a2.strength *= -1;
        solver.solve(x, V, {a2}, H2, M2);
        std::vector<Vec3> sum(x.size()), scaled(x.size());
        for (size_t i = 0; i < x.size(); ++i) {
            sum[i] = Ma[i] + Mb[i];
            scaled[i] = -Ma[i];
        }
        REQUIRE(ferro::test::relativeRms(sum, Mab) < 1e-4);
        REQUIRE(ferro::test::relativeRms(scaled, M2) < 1e-4);
    }
}

TEST_CASE("Field gradients match finite differences of the field", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    layer(1.24e-3, 0.012, 4, x, V);
    const std::vector<Magnet> magnets{dipoleBelow(-0.008, 0.5)};
    MagnetizationSolver solver(params(Solver::Direct, 1.5, 3e4, 1e-4));
    std::vector<Vec3> H, M;
    solver.solve(x, V, magnets, H, M);

    ParticleFieldEvaluator exact;
    exact.build(x, V, M, 0.0);
    // Point gradient of the particle field vs central differences: within the kernels'
    // support (the first point) and outside all of them.
    const double h = 1e-6;
    const double support = MagnetizationParams{}.smoothing * 1.24e-3;
    for (const Vec3d& p : {Vec3d(0.001, 0.002, 0.0065), Vec3d(0.02, 0, 0.003), Vec3d(0, 0, 0.01)}) {
        const Mat3d G = exact.inducedGradient(p);
        Mat3d F;
        for (int j = 0; j < 3; ++j) {
            Vec3d d = Vec3d::Zero();
            d[j] = h;
            F.col(j) = (exact.inducedField(p + d) - exact.inducedField(p - d)) / (2 * h);
        }
        INFO("p " << p.transpose() << "\nG\n" << G << "\nF\n" << F);
        REQUIRE((G - F).norm() < 1e-5 * F.norm());
        double nearest = std::numeric_limits<double>::infinity();
        for (const Vec3& xi : x) nearest = std::min(nearest, (xi.cast<double>() - p).norm());
        if (nearest > support) REQUIRE(std::abs(G.trace()) < 1e-9 * G.norm()); // div H = 0 outside sources
        else REQUIRE(std::abs(G.trace()) > 1e-3 * G.norm()); // inside: div H = -div M, the smoothed moments
    }
    // Per-particle Jacobian of the total field vs differences of the total field at the
    // particle (the own kernel's field is even about its centre and drops out), direct and tree.
    MagnetizationSolver treeSolver(params(Solver::Tree, 1.5, 3e4, 1e-4));
    std::vector<Eigen::Matrix3f> J, Jt;
    solver.fieldGradient(x, V, magnets, M, J);
    treeSolver.fieldGradient(x, V, magnets, M, Jt);
    double num = 0, den = 0, numT = 0;
    for (size_t i = 0; i < x.size(); i += 97) {
        const Vec3d p = x[i].cast<double>();
        Mat3d F;
        for (int j = 0; j < 3; ++j) {
            Vec3d d = Vec3d::Zero();
            d[j] = 1e-6;
            F.col(j) = (totalField(magnets, exact, p + d) - totalField(magnets, exact, p - d)) / 2e-6;
        }
        num += (J[i].cast<double>() - F).squaredNorm();
        numT += (Jt[i].cast<double>() - F).squaredNorm();
        den += F.squaredNorm();
    }
    INFO("direct " << std::sqrt(num / den) << " tree " << std::sqrt(numT / den));
    REQUIRE(std::sqrt(num / den) < 1e-4);
    REQUIRE(std::sqrt(numT / den) < 0.02);

    // solve() can return the Jacobians at its solution: the same as fieldGradient() after it.
    std::vector<Vec3> Ht, Mt;
    std::vector<Eigen::Matrix3f> Jsolve, Jafter;
    treeSolver.solve(x, V, magnets, Ht, Mt, &Jsolve);
    treeSolver.fieldGradient(x, V, magnets, Mt, Jafter);
    REQUIRE(Jsolve.size() == x.size());
    double d = 0, r = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        d += (Jsolve[i] - Jafter[i]).cast<double>().squaredNorm();
        r += Jafter[i].cast<double>().squaredNorm();
    }
    REQUIRE(std::sqrt(d / r) < 1e-5);
    // External neglects the particle field, and with it the particle part of the gradient.
    MagnetizationSolver external(params(Solver::External, 1.5, 3e4));
    std::vector<Eigen::Matrix3f> Je;
    external.fieldGradient(x, V, magnets, M, Je);
    for (size_t i = 0; i < x.size(); i += 211)
        REQUIRE((Je[i].cast<double>() - fieldGradient(magnets, x[i].cast<double>())).norm() <
                1e-5 * Je[i].norm());
}

TEST_CASE("Far from the fluid its field is the dipole of its total moment", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    layer(1.24e-3, 0.01, 4, x, V);
    const std::vector<Magnet> magnets{uniformField(Vec3d(0.3, 0, 1), 5000)};
    MagnetizationSolver solver(params(Solver::Tree, 1.0, 3e4));
    std::vector<Vec3> H, M;
    solver.solve(x, V, magnets, H, M);
    ParticleFieldEvaluator tree;
    tree.build(x, V, M);
    const Vec3d m = tree.totalMoment(), c = tree.centroid();
    REQUIRE(m.norm() > 0);
    for (const Vec3d& dir : {Vec3d(1, 0, 0), Vec3d(0, 0, 1), Vec3d(1, 2, -1).normalized()}) {
        const Vec3d r = 2.0 * dir; // 2 m: 100 times the fluid's size
        const Vec3d dip = (3 * r * r.dot(m) / std::pow(r.norm(), 5) - m / std::pow(r.norm(), 3)) / (4 * kPi);
        REQUIRE((tree.inducedField(c + r) - dip).norm() < 1e-3 * dip.norm());
        REQUIRE((tree.inducedFieldExact(c + r) - dip).norm() < 1e-3 * dip.norm());
    }
    // At a particle centre the evaluator gives back the solver's field; the smoothed field at
    // the same point differs by the surface sampling term only (the layer is 4 particles
    // deep, all within a support of its surface: check that the term is bounded by M).
    ParticleFieldEvaluator exact;
    exact.build(x, V, M, 0.0);
    for (size_t i = 0; i < x.size(); i += 131) {
        const Vec3d Hi = magnetField(magnets, x[i].cast<double>()) + exact.inducedFieldAtParticle(i);
        REQUIRE((Hi - H[i].cast<double>()).norm() < 0.01 * H[i].norm());
        const Vec3d smooth = totalField(magnets, exact, x[i].cast<double>());
        REQUIRE((smooth - Hi).norm() <= M[i].norm() * 1.001);
    }
}

TEST_CASE("Coincident particles and a magnet pole inside the fluid stay finite", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    layer(1.24e-3, 0.01, 3, x, V);
    const size_t n0 = x.size();
    for (size_t i = 0; i < 50; ++i) { // duplicates of existing particles, some exactly coincident
        x.push_back(x[i * 7]);
        V.push_back(V[i * 7]);
    }
    x.push_back(Vec3(0, 0, 0.002)); // and a particle of zero volume
    V.push_back(0);
    REQUIRE(x.size() == n0 + 51);
    Magnet bar;
    bar.kind = Magnet::Kind::Bar;
    bar.position = Vec3d(0, 0, 0.002); // its north pole sits inside the fluid
    bar.direction = Vec3d(0, 0, 1);
    bar.length = 0.004;
    bar.strength = 5.0;
    for (Solver kind : {Solver::Direct, Solver::Tree, Solver::External, Solver::Auto}) {
        MagnetizationSolver solver(params(kind, 3.0, 3e4));
        std::vector<Vec3> H, M;
        const auto stats = solver.solve(x, V, {bar}, H, M);
        REQUIRE(allFinite(H));
        REQUIRE(allFinite(M));
        REQUIRE(std::isfinite(stats.residual));
        REQUIRE(std::isfinite(stats.fieldError));
        for (const Vec3& m : M) REQUIRE(m.norm() <= 3e4f * 1.0001f);
        std::vector<Eigen::Matrix3f> J;
        solver.fieldGradient(x, V, {bar}, M, J);
        for (const auto& j : J) REQUIRE(j.allFinite());
        // exactly coincident particles feel the same field
        REQUIRE((H[n0] - H[0]).norm() <= 1e-3f * H[0].norm());
    }
}

TEST_CASE("Warm start cuts the work of the next solve", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    layer(1.24e-3, 0.015, 5, x, V);
    for (Solver kind : {Solver::Direct, Solver::Tree}) {
        MagnetizationSolver solver(params(kind, 2.0, 3e4, 1e-3));
        std::vector<Vec3> H, M;
        const auto cold = solver.solve(x, V, {dipoleBelow(-0.012, 1.0)}, H, M);
        // the magnet moves up by 0.1 mm; positions jiggle a little
        std::vector<Vec3> x2 = x;
        for (size_t i = 0; i < x2.size(); ++i) x2[i].z() += 1e-5f * float(i % 3);
        std::vector<Vec3> Hc, Mc;
        const auto again = solver.solve(x2, V, {dipoleBelow(-0.0119, 1.0)}, Hc, Mc);
        const auto warm = solver.solve(x2, V, {dipoleBelow(-0.0119, 1.0)}, H, M);
        INFO("cold " << cold.iterations << " cold again " << again.iterations << " warm " << warm.iterations);
        REQUIRE(warm.iterations < again.iterations);
        REQUIRE(ferro::test::relativeRms(H, Hc) < 2e-3);
        // an already converged state costs one evaluation
        const auto done = solver.solve(x2, V, {dipoleBelow(-0.0119, 1.0)}, H, M);
        REQUIRE(done.iterations == 1);
    }
}

TEST_CASE("Auto picks the cheapest accurate solver, and nothing runs without magnets", "[magnetization]") {
    std::vector<Vec3> small, big;
    std::vector<Real> Vs, Vb;
    layer(1.24e-3, 0.01, 3, small, Vs);
    layer(1.24e-3, 0.018, 6, big, Vb);
    REQUIRE(small.size() <= MagnetizationSolver::directLimit());
    REQUIRE(big.size() > MagnetizationSolver::directLimit());
    const std::vector<Magnet> magnets{dipoleBelow(-0.01, 0.5)};
    std::vector<Vec3> H, M;
    {
        MagnetizationSolver s(params(Solver::Auto, 1e-4, 0, 0.01));
        REQUIRE(s.solve(big, Vb, magnets, H, M).solver == Solver::External);
    }
    {
        MagnetizationSolver s(params(Solver::Auto, 1.5, 3e4, 0.01));
        const auto st = s.solve(small, Vs, magnets, H, M);
        REQUIRE(st.solver == Solver::Direct);
        REQUIRE(st.fieldError < 0.01);
    }
    {
        MagnetizationSolver s(params(Solver::Auto, 1.5, 3e4, 0.01));
        const auto st = s.solve(big, Vb, magnets, H, M);
        REQUIRE(st.solver == Solver::Tree);
        REQUIRE(st.fieldError < 0.01);
    }
    {
        MagnetizationSolver s(params(Solver::Direct, 1.5, 3e4));
        H.assign(big.size(), Vec3(1, 2, 3));
        const auto st = s.solve(big, Vb, {}, H, M);
        REQUIRE(st.skipped);
        REQUIRE(st.iterations == 0);
        for (size_t i = 0; i < big.size(); ++i) REQUIRE((H[i].isZero() && M[i].isZero()));
        std::vector<Eigen::Matrix3f> J;
        s.fieldGradient(big, Vb, {}, M, J);
        REQUIRE(J.size() == big.size());
    }
    {
        MagnetizationSolver s(params(Solver::Tree, 1.5, 3e4));
        std::vector<Vec3> none, Hn, Mn;
        const auto st = s.solve(none, {}, magnets, Hn, Mn);
        REQUIRE(st.skipped);
        REQUIRE((Hn.empty() && Mn.empty()));
        // a single particle: its own field only. Smoothed dipole: the kernel's centre value
        // -W(0) V M / 3 = -7 M / (2 pi eta^3) with eta = support / V^(1/3), so
        // H = H0 / (1 + 7 chi / (2 pi eta^3)) (no surface term: a lone kernel has no gradient).
        std::vector<Vec3> one{Vec3(0, 0, 0)}, H1, M1;
        s.solve(one, {1e-9f}, {uniformField(Vec3d(0, 1, 0), 100)}, H1, M1);
        const double eta = s.params().smoothing;
        REQUIRE(H1[0].y() == Approx(100 / (1 + 7 * 1.5 / (2 * kPi * eta * eta * eta))).epsilon(1e-3));
        // uniformly magnetized sphere (smoothing 0): H = 3 H0 / (3 + chi) as a lone sphere
        MagnetizationParams ps = s.params();
        ps.smoothing = 0;
        MagnetizationSolver(ps).solve(one, {1e-9f}, {uniformField(Vec3d(0, 1, 0), 100)}, H1, M1);
        REQUIRE(H1[0].y() == Approx(300 / 4.5).epsilon(1e-3));
    }
    {
        MagnetizationSolver s(params(Solver::Direct, 0.0, 0)); // not magnetic: H is the magnets' own
        const auto st = s.solve(big, Vb, magnets, H, M);
        REQUIRE(st.skipped);
        REQUIRE((H[5].cast<double>() - magnetField(magnets, big[5].cast<double>())).norm() < 1e-3 * H[5].norm());
        REQUIRE(M[5].isZero());
    }
}

// ---- Disordered balls: the particle model must be accurate per particle, not only on a lattice.

namespace {

// Ball of a cubic lattice of spacing s and radius R [m] about the origin, every coordinate
// then displaced uniformly in +-jitter * s (RMS displacement jitter * s), fixed seed.
void jitteredBall(double s, double R, double jitter, uint32_t seed, std::vector<Vec3>& x, std::vector<Real>& V) {
    std::vector<Vec3> lattice;
    latticeBall(s, R, Vec3d::Zero(), lattice, V);
    uint64_t state = seed;
    auto uniform = [&]() { // in [-1, 1)
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return 2.0 * double(state >> 11) / double(1ULL << 53) - 1.0;
    };
    x.clear();
    for (const Vec3& p : lattice)
        x.push_back((p.cast<double>() + jitter * s * Vec3d(uniform(), uniform(), uniform())).cast<Real>());
}

// Interior field of a magnetizable sphere in the uniform field H0: H_in + M(H_in) / 3 = H0,
// by bisection (linear: 3 H0 / (3 + chi0)).
double sphereInteriorField(double H0, double chi0, double Ms) {
    double lo = 0, hi = H0;
    for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        (mid + langevinMagnetization(mid, chi0, Ms) / 3 > H0 ? hi : lo) = mid;
    }
    return 0.5 * (lo + hi);
}

struct BallErrors {
    double mean = 0, rms = 0, worst = 0; // relative to H_in
    size_t interior = 0;
    MagnetizationSolver::Stats stats;
};

// The ball cases' targets against the analytic interior field (issue's accuracy): a converged
// solve, the interior field within 2 % mean, 3 % RMS and 10 % worst.
void requireBallTargets(const BallErrors& e, const char* what)
{
    INFO(what << ": interior " << e.interior << ", mean " << e.mean << ", rms " << e.rms << ", worst " << e.worst
              << ", " << e.stats.iterations << " evaluations, residual " << e.stats.residual);
    REQUIRE(e.stats.converged);
    REQUIRE(e.mean < 0.02);
    REQUIRE(e.rms < 0.03);
    REQUIRE(e.worst < 0.10);
}

// Solves the ball (any particle set of one spacing) in H0 along z and compares the field of
// its interior particles with the analytic H_in. The ball's radius is its volume's,
// R = (3 sum V / 4 pi)^(1/3), about the volume centroid; interior = at least `margin` [m]
// inside that radius.
BallErrors ballErrors(const std::vector<Vec3>& x, const std::vector<Real>& V, const MagnetizationParams& p,
                      double H0, double margin) {
    double vol = 0;
    Vec3d c = Vec3d::Zero();
    for (size_t i = 0; i < x.size(); ++i) {
        vol += V[i];
        c += double(V[i]) * x[i].cast<double>();
    }
    c /= vol;
    const double R = std::cbrt(3 * vol / (4 * kPi));
    MagnetizationSolver solver(p);
    std::vector<Vec3> H, M;
    BallErrors e;
    e.stats = solver.solve(x, V, {uniformField(Vec3d(0, 0, 1), H0)}, H, M);
    const double Hin = sphereInteriorField(H0, p.susceptibility, p.saturation);
    Vec3d sum = Vec3d::Zero();
    double sum2 = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        if ((x[i].cast<double>() - c).norm() > R - margin) continue;
        ++e.interior;
        const Vec3d h = H[i].cast<double>();
        sum += h;
        const double err = (h - Vec3d(0, 0, Hin)).norm() / Hin;
        sum2 += err * err;
        e.worst = std::max(e.worst, err);
    }
    e.mean = (sum / double(std::max<size_t>(e.interior, 1)) - Vec3d(0, 0, Hin)).norm() / Hin;
    e.rms = std::sqrt(sum2 / double(std::max<size_t>(e.interior, 1)));
    return e;
}

} // namespace

namespace {

// tests/data/settled_ball.ply (scripts/make_settled_ball.py says how it was made): 3,615
// particles of 2.5 mm spacing cut from a resting SPH tank, volumes the rest volume h^3 as
// sim/sph/FluidMagnetics passes them.
void settledBall(std::vector<Vec3>& x, std::vector<Real>& V, double& spacing) {
    const ParticleTable t = readParticleFile(std::string(FERRO_SOURCE_DIR) + "/tests/data/settled_ball.ply");
    x = t.vec3("x", "y", "z");
    spacing = 0;
    for (const auto& c : t.comments)
        if (c.first == "spacing") spacing = std::stod(c.second);
    V.assign(x.size(), Real(spacing * spacing * spacing));
}

struct BallCase {
    double chi0, Ms; // Ms = 0: linear
};
// chi0 = 0.5, 1, 3, 10 linear, and chi0 = 3 and 10 saturating (Ms = H0 = 20 kA/m: the
// interior field solves H + M(H) / 3 = H0 with M at 45-60 % of Ms).
const BallCase kBallCases[] = {{0.5, 0}, {1, 0}, {3, 0}, {10, 0}, {3, 2e4}, {10, 2e4}};
constexpr double kBallH0 = 2e4;

// Interior margin: one kernel support (2.5 spacings, two SPH smoothing lengths h = support / 2)
// inside the volume radius, where the smoothed magnetization of a uniform ball is uniform.
double interiorMargin(double spacing) { return MagnetizationParams{}.smoothing * spacing; }

} // namespace

TEST_CASE("Settled SPH ball in a uniform field: every interior particle has the sphere's field", "[magnetization]") {
    std::vector<Vec3> x;
    std::vector<Real> V;
    double s = 0;
    settledBall(x, V, s);
    REQUIRE(x.size() == 3615);
    for (const BallCase& c : kBallCases) {
        const BallErrors e = ballErrors(x, V, params(Solver::Direct, c.chi0, c.Ms, 1e-3), kBallH0, interiorMargin(s));
        INFO("chi0 " << c.chi0 << " Ms " << c.Ms);
        REQUIRE(e.interior > 1000);
        REQUIRE(e.stats.residual <= 1e-4);
        requireBallTargets(e, "direct");
    }
    // The tree converges to the same accuracy (chi0 = 10, the hardest case).
    const BallErrors t = ballErrors(x, V, params(Solver::Tree, 10, 0, 1e-3), kBallH0, interiorMargin(s));
    REQUIRE(t.stats.solver == Solver::Tree);
    requireBallTargets(t, "tree");
    // The uniformly-magnetized-sphere model (smoothing = 0) is far off on the same ball: its
    // near-neighbour sums cancel only on a cubic lattice, and a settled SPH state is a
    // disordered, slightly compressed one (11-12 % RMS at chi0 = 1).
    MagnetizationParams old = params(Solver::Direct, 1, 0, 1e-3);
    old.smoothing = 0;
    const BallErrors o = ballErrors(x, V, old, kBallH0, interiorMargin(s));
    INFO("spheres: mean " << o.mean << ", rms " << o.rms << ", worst " << o.worst);
    REQUIRE(o.rms > 0.05);
}

TEST_CASE("Jittered ball in a uniform field: interior field per particle, converged up to chi0 = 10", "[magnetization]") {
    // Cubic lattice ball of radius 10 spacings, every coordinate displaced by up to +-0.2
    // spacings (RMS displacement 0.2 spacings), fixed seed: 4,169 particles, 1,772 interior.
    const double s = 1e-3;
    std::vector<Vec3> x;
    std::vector<Real> V;
    jitteredBall(s, 10 * s, 0.2, 7, x, V);
    REQUIRE(x.size() == 4169);
    for (const BallCase& c : kBallCases) {
        MagnetizationParams p = params(Solver::Direct, c.chi0, c.Ms, 1e-3);
        p.localCorrection = true;
        const BallErrors e = ballErrors(x, V, p, kBallH0, interiorMargin(s));
        INFO("chi0 " << c.chi0 << " Ms " << c.Ms);
        REQUIRE(e.interior > 1500);
        // Reference: the analytic interior field of a uniformly magnetized sphere (ballErrors).
        // Bounds: the targets, met with the local correction (off by default in the
        // simulation); measured with and without it: docs/physics/magnetization.md, "Tested
        // accuracy".
        REQUIRE(e.stats.residual <= 1e-4);
        requireBallTargets(e, "direct, local correction");
    }
    // Tree (chi0 = 10, the hardest case): the correction measured with the tree's own sums.
    MagnetizationParams pt = params(Solver::Tree, 10, 0, 1e-3);
    pt.localCorrection = true;
    const BallErrors t = ballErrors(x, V, pt, kBallH0, interiorMargin(s));
    REQUIRE(t.stats.solver == Solver::Tree);
    requireBallTargets(t, "tree, local correction");
}

namespace {
// SPH volumes V_i = 1 / sum_j W(x_i - x_j) with the simulation's kernel (cubic spline of
// support 2 spacings), scaled so that a full cubic lattice has V = s^3 (as FluidSimulation
// sets its particle volume): what a simulation passing m / rho_i would pass.
std::vector<Real> sphVolumes(const std::vector<Vec3>& x, double s) {
    auto W = [h = 2 * s](double r) {
        const double q = r / h;
        if (q >= 1) return 0.0;
        return 8.0 / (kPi * h * h * h) * (q <= 0.5 ? 6 * q * q * (q - 1) + 1 : 2 * (1 - q) * (1 - q) * (1 - q));
    };
    double lattice = 0;
    for (int k = -2; k <= 2; ++k)
        for (int j = -2; j <= 2; ++j)
            for (int i = -2; i <= 2; ++i) lattice += W(s * std::sqrt(double(i * i + j * j + k * k)));
    std::vector<Real> V(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
        double sum = 0;
        for (const Vec3& y : x) sum += W((x[i] - y).cast<double>().norm());
        V[i] = Real(s * s * s * lattice / sum);
    }
    return V;
}
} // namespace

TEST_CASE("Disordered balls: figures of the particle models", "[.figures]") {
    // Not run by default (build/bin/ferro_magnetics_tests "[.figures]"): the table of the
    // closing report, direct solver. Models: smoothed dipoles with the local correction (an
    // option, off by default), without it (the default), without it on SPH volumes, and the old sphere model.
    std::vector<Vec3> xs, xj;
    std::vector<Real> Vs, Vj;
    double s = 0;
    settledBall(xs, Vs, s);
    jitteredBall(1e-3, 10e-3, 0.2, 7, xj, Vj);
    const std::vector<Real> Vsph[2] = {sphVolumes(xs, s), sphVolumes(xj, 1e-3)};
    for (int set = 0; set < 2; ++set)
        for (int model = 0; model < 4; ++model)
            for (const BallCase& c : kBallCases) {
                MagnetizationParams p = params(Solver::Direct, c.chi0, c.Ms, 1e-3);
                p.localCorrection = model == 0;
                if (model == 3) p.smoothing = 0;
                const double spacing = set == 0 ? s : 1e-3;
                const std::vector<Real>& V = model == 2 ? Vsph[set] : set == 0 ? Vs : Vj;
                const BallErrors e = ballErrors(set == 0 ? xs : xj, V, p, kBallH0, interiorMargin(spacing));
                const char* names[] = {"corrected", "smoothed", "sph-vol", "spheres"};
                std::printf("%-8s %-9s chi0 %4.1f Ms %5.0f  interior %4zu  mean %6.2f%%  rms %7.2f%%  worst %8.2f%%  "
                            "evals %3d  residual %.1e  converged %s\n",
                            set == 0 ? "settled" : "jittered", names[model], c.chi0, c.Ms, e.interior, 100 * e.mean,
                            100 * e.rms, 100 * e.worst, e.stats.iterations, e.stats.residual,
                            e.stats.converged ? "yes" : "NO");
                std::fflush(stdout);
            }
}

TEST_CASE("a periodic flat layer has the infinite layer's field: H0 / (1 + chi) normal, H0 along it",
          "[magnetization][periodic]") {
    // A slab of 16 x 16 x 6 lattice particles repeating every 16 spacings in x and y is an
    // infinite layer: B_n continuous gives H = H0 / (1 + chi) inside for a normal field,
    // H_t continuous gives H = H0 for a field along it (no demagnetization). The same slab
    // alone (no periodic copies) is a finite plate, whose centre field is far from either.
    const double s = 1e-3;
    const int nx = 16, layers = 6;
    std::vector<Vec3> x;
    std::vector<Real> V;
    uint32_t state = 777;
    auto jitter = [&]() {
        state = state * 1664525u + 1013904223u;
        return 0.1 * s * (double(state >> 8) / double(1u << 24) - 0.5);
    };
    for (int k = 0; k < layers; ++k)
        for (int j = 0; j < nx; ++j)
            for (int i = 0; i < nx; ++i) {
                x.push_back(Vec3d((i + 0.5) * s + jitter(), (j + 0.5) * s + jitter(), (k + 0.5) * s + jitter()).cast<Real>());
                V.push_back(Real(s * s * s));
            }
    const double L = nx * s, H0 = 1000, chi = 2.0;
    // Interior: the middle two layers (the surface term and the staircase act within a
    // support of the top and bottom).
    auto interiorMean = [&](const std::vector<Vec3>& H, int axis) {
        double sum = 0;
        int count = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            if (std::abs(x[i].z() - 0.5 * layers * s) > 0.75 * s) continue;
            sum += H[i][axis];
            ++count;
        }
        return sum / count;
    };
    for (Solver kind : {Solver::Direct, Solver::Tree}) {
        for (int axis : {2, 0}) {
            Vec3d dir = Vec3d::Zero();
            dir[axis] = 1;
            const std::vector<Magnet> magnets{uniformField(dir, H0)};
            const double expected = axis == 2 ? H0 / (1 + chi) : H0;
            MagnetizationSolver solver(params(kind, chi));
            solver.setPeriodic(L, L);
            std::vector<Vec3> H, M;
            const auto stats = solver.solve(x, V, magnets, H, M);
            const double periodic = interiorMean(H, axis);
            // Every particle sees the same surroundings: the field may not depend on x, y.
            double spread = 0;
            for (size_t i = 0; i < x.size(); ++i)
                if (std::abs(x[i].z() - 0.5 * layers * s) <= 0.75 * s)
                    spread = std::max(spread, std::abs(H[i][axis] - periodic) / expected);
            MagnetizationSolver alone(params(kind, chi));
            std::vector<Vec3> Ha, Ma;
            alone.solve(x, V, magnets, Ha, Ma);
            const double finite = interiorMean(Ha, axis);
            CAPTURE(int(kind), axis, stats.iterations, stats.residual, periodic, finite, expected, spread);
            REQUIRE(stats.residual < 1e-3);
            REQUIRE(periodic == Approx(expected).epsilon(0.025));
            REQUIRE(spread < 0.03);
            // The copies matter: the plate alone is off by more than 5 %.
            REQUIRE(std::abs(finite / expected - 1) > 0.05);
        }
    }
}

// The solids' surface-charge solve (sim/solids/SurfaceChargeSolver) against the analytic
// magnetized sphere, and its panel integral against quadrature.
#include "sim/solids/PanelIntegral.hpp"
#include "sim/solids/SolidShapes.hpp"
#include "sim/solids/SurfaceChargeSolver.hpp"

#include "sim/core/Constants.hpp"
#include "sim/magnets/MagnetField.hpp"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

using namespace ferro;

namespace {

// integral_T (x - y)/|x - y|^3 dA by the midpoint rule on a 2^k-fold subdivision (x off T).
Vec3d bruteTriangle(const Vec3d& x, const Vec3d& a, const Vec3d& b, const Vec3d& c, int n) {
    Vec3d sum = Vec3d::Zero();
    const double area = 0.5 * (b - a).cross(c - a).norm() / (double(n) * n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n - i; ++j) {
            // The upright sub-triangle (i, j) and, where it exists, the inverted one beside it.
            const Vec3d p = a + (b - a) * ((i + 1.0 / 3) / n) + (c - a) * ((j + 1.0 / 3) / n);
            sum += area * (x - p) / std::pow((x - p).norm(), 3);
            if (i + j < n - 1) {
                const Vec3d q = a + (b - a) * ((i + 2.0 / 3) / n) + (c - a) * ((j + 2.0 / 3) / n);
                sum += area * (x - q) / std::pow((x - q).norm(), 3);
            }
        }
    return sum;
}

struct SphereErrors {
    size_t panels = 0;
    double outside = 0; // worst relative error of the field outside, 1.2 - 3 radii
    double inside = 0;  // worst relative error of the field inside, within 0.6 radii
    double fast = 0;    // worst relative error outside of fieldAndGradient (the particles' path)
    double gradient = 0; // worst relative difference of its Jacobian from the analytic dipole's
    int iterations = 0;
};

// A sphere of radius a and relative permeability mu in the uniform field H0 z, meshed with
// edges at most `edge`: the worst errors against the exact solution (outside: the dipole
// 4 pi a^3 (mu - 1)/(mu + 2) H0; inside: 3 H0 / (mu + 2)) over points on 8 directions.
SphereErrors sphereErrors(double mu, double edge) {
    const double a = 0.01, H0 = 1e4;
    const ShapeMesh mesh = makeSphere(a, edge);
    SolidSurface s;
    s.vertices = mesh.vertices;
    s.triangles = mesh.triangles;
    s.permeability = mu;
    SurfaceChargeSolver solver;
    solver.setSurfaces({s});
    const SurfaceChargeSolver::Stats st = solver.solve([&](const Vec3d&) { return Vec3d(0, 0, H0); });
    SphereErrors e;
    e.panels = solver.panelCount();
    e.iterations = st.iterations;
    const Vec3d m(0, 0, 4 * kPi * a * a * a * (mu - 1) / (mu + 2) * H0);
    const Vec3d dirs[] = {Vec3d(0, 0, 1),  Vec3d(1, 0, 0),   Vec3d(0.3, -0.5, 0.8), Vec3d(-0.7, 0.2, -0.4),
                          Vec3d(0, 1, -1), Vec3d(0.9, 0.9, 0.2), Vec3d(-0.1, -0.3, -1), Vec3d(0.5, -0.8, 0)};
    for (const Vec3d& d0 : dirs) {
        const Vec3d d = d0.normalized();
        for (double r : {1.2, 1.5, 2.0, 3.0}) {
            const Vec3d x = r * a * d;
            const double R = x.norm();
            const Vec3d ref = (3 * x * m.dot(x) / (R * R) - m) / (4 * kPi * R * R * R);
            e.outside = std::max(e.outside, (solver.field(x) - ref).norm() / ref.norm());
            Vec3d h;
            Mat3d J;
            solver.fieldAndGradient(x, h, J);
            e.fast = std::max(e.fast, (h - ref).norm() / ref.norm());
            // The dipole's Jacobian: (3 (m.r) I + 3 r m^T + 3 m r^T - 15 (m.r) r r^T / R^2) / (4 pi R^5).
            const double mr = m.dot(x);
            const Mat3d Jref = (3 * mr * Mat3d::Identity() + 3 * x * m.transpose() + 3 * m * x.transpose() -
                                15 * mr * x * x.transpose() / (R * R)) / (4 * kPi * std::pow(R, 5));
            e.gradient = std::max(e.gradient, (J - Jref).norm() / Jref.norm());
        }
        for (double r : {0.0, 0.3, 0.6}) {
            const Vec3d ref(0, 0, 3 * H0 / (mu + 2));
            e.inside = std::max(e.inside, (solver.interiorField(r * a * d) - ref).norm() / ref.norm());
        }
    }
    return e;
}

// A coil of 500 turns, 2 cm long, on the z axis at height z [m], of radius [m] and current [A].
Magnet upwardCoil(double z, double radius, double current) {
    Magnet coil;
    coil.kind = MagnetKind::Coil;
    coil.position = Vec3d(0, 0, z);
    coil.radius = radius;
    coil.length = 0.02;
    coil.turns = 500;
    coil.strength = current;
    return coil;
}

// The climb's electromagnet core: a soft-iron cylinder (mu_r 1000) 6 mm in radius and 20 mm
// tall, its top 2.5 mm under the dish floor (z = 0), panels about `edge` [m] across.
SolidSurface coreUnderFloor(double edge) {
    const ShapeMesh core = makeCylinder(0.006, 0.02, edge);
    SolidSurface s;
    for (const Vec3d& v : core.vertices) s.vertices.push_back(v + Vec3d(0, 0, -0.0225));
    s.triangles = core.triangles;
    s.permeability = 1000;
    return s;
}

// The total field H (the coil's plus the solids') at x, and grad|H| = J H / |H| (J v, the
// convention of the callers of fieldAndGradient, which a standoff's Jacobian keeps).
Vec3d totalGradH(const SurfaceChargeSolver& solver, const Magnet& coil, const Vec3d& x, double standoff, Vec3d& H) {
    Vec3d h;
    Mat3d J;
    solver.fieldAndGradient(x, h, J, standoff);
    H = h + magnetField(coil, x);
    return (J + fieldGradient(coil, x)) * H / H.norm();
}

} // namespace

TEST_CASE("a flat panel's field Jacobian in closed form matches central differences of its field", "[solids]") {
    // Reference: central differences of uniformTriangleField (step 1e-6 of the distance),
    // accurate to ~1e-7 away from the rim; random triangles, points anywhere and points within
    // 1e-3 of the triangle's plane across its edges (the logarithms' three forms).
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    double worst = 0;
    for (int k = 0; k < 2000; ++k) {
        const Vec3d a(u(rng), u(rng), 0.1 * u(rng)), b(u(rng), u(rng), 0.1 * u(rng)), c(u(rng), u(rng), 0.1 * u(rng));
        Vec3d x(1.5 * u(rng), 1.5 * u(rng), 0.5 * u(rng));
        if (k % 2) x = a + (b - a) * (0.5 + 0.6 * u(rng)) + (c - a) * (0.3 * u(rng)) + (b - a).cross(c - a).normalized() * 1e-3 * u(rng);
        const double h = 1e-6 * (x - (a + b + c) / 3.0).norm();
        Mat3d numeric;
        for (int j = 0; j < 3; ++j) {
            Vec3d s = Vec3d::Zero();
            s[j] = h;
            numeric.col(j) = (uniformTriangleField(x + s, a, b, c) - uniformTriangleField(x - s, a, b, c)) / (2 * h);
        }
        worst = std::max(worst, (uniformTriangleGradient(x, a, b, c) - numeric).norm() / numeric.norm());
    }
    WARN("closed-form panel Jacobian against central differences: worst " << worst);
    CHECK(worst < 1e-5);
}

TEST_CASE("a uniformly charged triangle's closed-form field matches quadrature", "[solids]") {
    const Vec3d a(0.0, 0.0, 0.0), b(1.0, 0.1, 0.0), c(0.2, 0.9, 0.3);
    for (const Vec3d& x : {Vec3d(0.4, 0.3, 0.5), Vec3d(0.4, 0.3, -0.2), Vec3d(2, -1, 0.5), Vec3d(-0.3, 0.2, 0.0),
                           Vec3d(1.5, 0.5, 0.1), Vec3d(0.0, 0.0, 0.2)}) {
        const Vec3d I = uniformTriangleField(x, a, b, c);
        const Vec3d ref = bruteTriangle(x, a, b, c, 400);
        INFO("x = " << x.transpose() << ": " << I.transpose() << " against " << ref.transpose());
        CHECK((I - ref).norm() < 2e-3 * ref.norm());
    }
    // The normal part jumps by 2 pi across the panel (the charge's sigma / 2 either side), and
    // the principal value at the centroid has none.
    const Vec3d n = (b - a).cross(c - a).normalized();
    const Vec3d g = (a + b + c) / 3;
    const double up = uniformTriangleField(g + 1e-9 * n, a, b, c).dot(n);
    const double down = uniformTriangleField(g - 1e-9 * n, a, b, c).dot(n);
    CHECK(up - down == Approx(4 * kPi).epsilon(1e-6));
    CHECK(std::abs(uniformTriangleField(g, a, b, c, true).dot(n)) < 1e-12);
}

TEST_CASE("generated shapes are closed and outward", "[solids]") {
    for (const ShapeMesh& m : {makeSphere(0.01, 0.004), makeCylinder(0.01, 0.03, 0.003), makeCone(0.02, 0.0, 0.05, 0.004),
                               makeCone(0.02, 0.005, 0.05, 0.004)}) {
        CHECK(checkClosed(m).closed());
        CHECK(signedVolume(m) > 0);
    }
    const double r = 0.01, h = 0.03;
    CHECK(signedVolume(makeCylinder(r, h, 0.001)) == Approx(kPi * r * r * h).epsilon(0.01));
    CHECK(signedVolume(makeCone(r, 0.0, h, 0.001)) == Approx(kPi * r * r * h / 3).epsilon(0.01));
}

// The table of the sphere's errors against the panel count (icosphere levels 3-5).
void sphereTable(const std::vector<double>& edges, bool check) {
    std::printf("mu_r    panels  outside err  inside err  point eval  gradient  iterations\n");
    for (double mu : {10.0, 1000.0}) {
        SphereErrors prev;
        for (double edge : edges) {
            const SphereErrors e = sphereErrors(mu, edge);
            std::printf("%-7g %6zu  %10.3e  %10.3e  %10.3e  %8.3e  %d\n", mu, e.panels, e.outside, e.inside, e.fast,
                        e.gradient, e.iterations);
            if (check && prev.panels > 0) {
                // The interior field converges as the panel size (halves from level to level);
                // the exterior one is at a floor of 0.1-0.3 % from 1,280 panels on (the table).
                CHECK(e.inside < 0.6 * prev.inside);
                CHECK(e.outside < 0.005);
                CHECK(e.fast < 0.01);      // the particles' faster path: the must-show's 1 %
                CHECK(e.gradient < 0.02);
                CHECK(e.inside < 0.02);
            }
            prev = e;
        }
    }
}

TEST_CASE("a magnetized sphere matches the analytic field at mu_r 10 and 1000, converging with panels", "[solids]") {
    // Icosphere levels 3 and 4 (1,280 and 5,120 panels). The must-show: outside within 1 %
    // of the dipole at 1.2 - 3 radii, inside within 2 % of 3 H0 / (mu_r + 2).
    sphereTable({0.0025, 0.0012}, true);
}

TEST_CASE("the sphere's convergence table to 20,480 panels", "[.figures][solids]") {
    sphereTable({0.005, 0.0025, 0.0012, 0.0006}, false);
}

TEST_CASE("a saturating sphere: M bounded by Ms, the uniform solution of H = H0 - M/3 with Froehlich-Kennelly M(H)", "[solids]") {
    // Soft iron (mu_r 2000, Ms 1.6e6 A/m) in fields from well below to far beyond saturation.
    // A uniformly magnetized sphere has no volume charge, so the surface-charge model is exact:
    // H_in = H0 - M / 3, M = chi H_in / (1 + chi H_in / Ms), solved here by bisection on M.
    const double a = 0.01, mu = 2000, Ms = 1.6e6, chi = mu - 1;
    const ShapeMesh mesh = makeSphere(a, 0.0025);
    SolidSurface s;
    s.vertices = mesh.vertices;
    s.triangles = mesh.triangles;
    s.permeability = mu;
    s.saturation = Ms;
    for (double H0 : {1e4, 1e6, 1e7}) {
        double lo = 0, hi = Ms;
        for (int it = 0; it < 200; ++it) {
            const double M = 0.5 * (lo + hi), H = H0 - M / 3;
            (chi * H / (1 + chi * std::abs(H) / Ms) > M ? lo : hi) = M;
        }
        const double Mref = 0.5 * (lo + hi);
        SurfaceChargeSolver solver;
        solver.setSurfaces({s});
        const SurfaceChargeSolver::Stats st = solver.solve([&](const Vec3d&) { return Vec3d(0, 0, H0); });
        // The moment from the field far away: m = 4 pi a^3 M / 3 along z.
        const Vec3d x(0, 0, 5 * a);
        const double m = solver.field(x).z() * 2 * kPi * std::pow(5 * a, 3);
        const double Mfar = m / (4.0 / 3.0 * kPi * a * a * a);
        double Mmax = 0;
        for (double v : solver.magnetizationMagnitude()) Mmax = std::max(Mmax, v);
        INFO("H0 " << H0 << ": M " << Mfar << " from the far field, panels' largest |M| " << Mmax << ", exact " << Mref
                   << ", secant steps " << st.secantSteps);
        CHECK(Mfar == Approx(Mref).epsilon(0.02));
        CHECK(Mmax < 1.03 * Ms); // bounded: the secants' fixed point is under Ms, their last step within 3 %
        CHECK(st.secantSteps < 30);
    }
}

TEST_CASE("the solve stays well conditioned up to mu_r 1e5: a cone in a coil's field takes as many GMRES steps", "[solids]") {
    // The deflated conductor mode keeps the spectrum away from 0 as lambda -> 1: measured
    // 12, 14 and 14 steps to 1e-6 at mu_r 10, 1e3 and 1e5 (1,462 panels).
    const Magnet coil = upwardCoil(-0.015, 0.012, 2.0);
    const ShapeMesh cone = makeCone(0.008, 0.0005, 0.025, 0.0015);
    std::vector<int> iterations;
    for (double mu : {10.0, 1e3, 1e5}) {
        SolidSurface s;
        s.vertices = cone.vertices;
        s.triangles = cone.triangles;
        s.permeability = mu;
        SurfaceChargeSolver solver;
        solver.setSurfaces({s});
        const SurfaceChargeSolver::Stats st = solver.solve([&](const Vec3d& p) { return magnetField(coil, p); });
        INFO("mu_r " << mu << ": " << st.iterations << " steps, residual " << st.residual);
        CHECK(st.converged);
        CHECK(st.iterations <= 20);
        iterations.push_back(st.iterations);
        // No net charge: a body's charge sums to zero (div B = 0).
        double q = 0, qabs = 0;
        for (size_t i = 0; i < solver.panelCount(); ++i) {
            q += solver.charge()[i] * solver.areas()[i];
            qabs += std::abs(solver.charge()[i]) * solver.areas()[i];
        }
        CHECK(std::abs(q) < 1e-4 * qabs);
    }
    CHECK(iterations[2] <= iterations[0] + 4);
}

TEST_CASE("the solids' field at points is a gradient: no circulation of grad|H| round closed loops", "[solids]") {
    // A soft-iron core in a coil under a dish (the climb's electromagnet), panels of 2.5 mm:
    // the force on the fluid, mu0 M grad|H|, is a gradient only if the field is one, and then
    // the circulation of grad|H| round any closed loop vanishes. The field is assembled from
    // pieces (panels near and far by different rules, the tree's expansions) that jump where
    // a piece changes rule; a jump adds to the circulation. Loops: circles of 1.5 mm about
    // points off the axis (so that no symmetry of the mesh cancels it), level and upright,
    // 0.3 to 4.5 mm above the floor; and circles about the axis (where the mesh's own
    // handedness showed: a triangulation leaning one way round the axis made 3.1e-4 here and
    // turned a pool, SolidShapes.cpp). Reference: 0; bound 1e-3 of the mean |grad|H||.
    const Magnet coil = upwardCoil(-0.012, 0.008, 4.0);
    const SolidSurface s = coreUnderFloor(0.00247);
    // Both paths: the sum over every panel, and the tree (forced on at this panel count).
    SurfaceChargeSolver::Params treeParams;
    treeParams.treeMinPanels = 0;
    SurfaceChargeSolver direct, tree(treeParams);
    for (SurfaceChargeSolver* solver : {&direct, &tree}) {
        solver->setSurfaces({s});
        REQUIRE(solver->solve([&](const Vec3d& p) { return magnetField(coil, p); }).converged);
    }
    struct Loop { Vec3d centre, u, v; double radius; };
    std::vector<Loop> loops;
    for (const auto& [r, z] : {std::make_pair(0.0036, 0.001), std::make_pair(0.0044, 0.002), std::make_pair(0.006, 0.0005),
                               std::make_pair(0.008, 0.001), std::make_pair(0.005, 0.0003)})
        loops.push_back({Vec3d(0, 0, z), Vec3d::UnitX(), Vec3d::UnitY(), r}); // about the axis
    for (const auto& [r, z] : {std::make_pair(0.004, 0.0018), std::make_pair(0.0055, 0.002), std::make_pair(0.0075, 0.003)}) {
        loops.push_back({Vec3d(r, 0.001, z), Vec3d::UnitX(), Vec3d::UnitY(), 0.0015});  // level
        loops.push_back({Vec3d(r, 0.001, z + 0.0003), Vec3d::UnitX(), Vec3d::UnitZ(), 0.0015}); // upright
    }
    for (const SurfaceChargeSolver* solver : {&direct, &tree})
    for (const Loop& l : loops) {
        const int n = 720;
        double circulation = 0, size = 0;
        for (int k = 0; k < n; ++k) {
            const double a = 2 * kPi * (k + 0.5) / n;
            const Vec3d x = l.centre + l.radius * (std::cos(a) * l.u + std::sin(a) * l.v);
            const Vec3d tangent = -std::sin(a) * l.u + std::cos(a) * l.v;
            Vec3d H;
            const Vec3d grad = totalGradH(*solver, coil, x, 0.0, H);
            circulation += grad.dot(tangent) / n;
            size += grad.norm() / n;
        }
        WARN((solver == &tree ? "tree" : "direct") << ": loop about " << l.centre.transpose() << " radius " << l.radius << ": mean tangential grad|H| "
                           << circulation / size << " of the mean |grad|H||");
        CHECK(std::abs(circulation) < 1e-3 * size);
    }
}

TEST_CASE("a point at a solid's wall sees the field a standoff off it: no spike at the panels' edges", "[solids]") {
    // A soft-iron core (panels of 2.5 mm) in a coil. A fluid particle slides along the wall,
    // touching it: the flat, piecewise-constant panels' field has a logarithmic spike at
    // every panel edge there (grad |H| ~ the charge jump over the distance), which flung
    // particles off a Morpho Tower at 1,000 g. With the standoff (0.5 mm) the field along
    // lines 20 um off the top face, across the rim, and down the side varies on no scale
    // finer than the standoff: |grad |H|| <= |H| / standoff everywhere, and |H| changes by
    // under 2 % between samples 10 um apart. Without it the same lines break both bounds
    // (checked too, so the test can tell the difference).
    const Magnet coil = upwardCoil(-0.012, 0.008, 4.0);
    SurfaceChargeSolver solver;
    solver.setSurfaces({coreUnderFloor(0.0025)});
    REQUIRE(solver.solve([&](const Vec3d& p) { return magnetField(coil, p); }).converged);
    const double top = -0.0025, standoff = 0.0005;
    struct Line { Vec3d a, b; };
    const std::vector<Line> lines = {
        {Vec3d(0.0005, 0.0003, top + 2e-5), Vec3d(0.0059, 0.0011, top + 2e-5)},   // over the top face
        {Vec3d(0.00602, 0.0002, top - 0.004), Vec3d(0.00602, 0.0002, top - 0.0001)}, // down the side
        {Vec3d(0.0058, 0.0013, top + 2e-5), Vec3d(0.0066, 0.0013, top + 2e-5)},   // across the rim
    };
    for (const double so : {standoff, 0.0}) {
        double worstGrad = 0, worstJump = 0;
        for (const Line& l : lines) {
            const int n = int((l.b - l.a).norm() / 1e-5);
            double last = -1;
            for (int k = 0; k <= n; ++k) {
                const Vec3d x = l.a + (l.b - l.a) * (double(k) / n);
                Vec3d H;
                const Vec3d grad = totalGradH(solver, coil, x, so, H);
                worstGrad = std::max(worstGrad, grad.norm() * standoff / H.norm());
                if (last > 0) worstJump = std::max(worstJump, std::abs(H.norm() - last) / last);
                last = H.norm();
            }
        }
        WARN("standoff " << so << " m: largest |grad|H|| standoff / |H| " << worstGrad << ", largest jump " << worstJump);
        if (so > 0) {
            CHECK(worstGrad < 1.0);
            CHECK(worstJump < 0.02);
        } else {
            CHECK((worstGrad > 1.0 || worstJump > 0.02));
        }
    }
}

TEST_CASE("the panel tree's field at points matches the sum over every panel", "[solids]") {
    // A cored coil's core and a cone standing 2.5 mm above it (the Morpho Tower's
    // arrangement), panels of 1.2 mm (2,992), solved once; the field and Jacobian at points
    // from 0.3 mm to 40 mm off the surfaces by the tree (PanelTree, the particles' path)
    // against the sum of every panel (openingAngle 0, the path the analytic sphere tests above
    // hold). Bound: 1e-3 of the total |H| and |J| (coil plus solids) within 4 mm of a surface,
    // where the fluid is, or of their mean 1 mm off the surfaces where that is larger (near a
    // null of the field); farther, 1e-3 of that mean (the fluid's field tolerance is 1e-2).
    const Magnet coil = upwardCoil(-0.012, 0.008, 2.0);
    const ShapeMesh cone = makeCone(0.006, 0.001, 0.02, 0.0012);
    std::vector<SolidSurface> bodies{coreUnderFloor(0.0012), SolidSurface{}};
    bodies[1].vertices = cone.vertices;
    bodies[1].triangles = cone.triangles;
    SurfaceChargeSolver::Params directParams;
    directParams.openingAngle = 0;
    SurfaceChargeSolver tree, direct(directParams);
    tree.setSurfaces(bodies);
    direct.setSurfaces(bodies);
    auto applied = [&](const Vec3d& p) { return magnetField(coil, p); };
    REQUIRE(tree.solve(applied).converged);
    REQUIRE(direct.solve(applied).converged);
    const size_t n = direct.panelCount();
    std::vector<Vec3d> near1mm, points;
    std::vector<bool> close;
    for (size_t i = 0; i < n; ++i) near1mm.push_back(direct.centroids()[i] + 0.001 * direct.normals()[i]);
    for (size_t i = 0; i < n; i += 7)
        for (double d : {0.0003, 0.001, 0.004, 0.015, 0.04}) {
            const Vec3d x = direct.centroids()[i] + d * direct.normals()[i];
            // Outside both bodies (the core from z = -22.5 to -2.5 mm, the cone from 0 to 20 mm).
            const double rho = std::hypot(x.x(), x.y());
            if (x.z() > -0.0225 && x.z() < -0.0025 && rho < 0.006) continue;
            if (x.z() > 0 && x.z() < 0.02 && rho < 0.006 - 0.25 * x.z()) continue;
            points.push_back(x);
            close.push_back(d <= 0.004);
        }
    double hRef = 0, jRef = 0;
    for (const Vec3d& x : near1mm) {
        Vec3d h;
        Mat3d j;
        direct.fieldAndGradient(x, h, j);
        hRef += (h + magnetField(coil, x)).norm() / double(n);
        jRef += (j + fieldGradient(coil, x)).norm() / double(n);
    }
    double nearH = 0, nearJ = 0, farH = 0, farJ = 0;
    for (size_t k = 0; k < points.size(); ++k) {
        const Vec3d& x = points[k];
        Vec3d ht, hd;
        Mat3d jt, jd;
        tree.fieldAndGradient(x, ht, jt);
        direct.fieldAndGradient(x, hd, jd);
        if (close[k]) {
            nearH = std::max(nearH, (ht - hd).norm() / std::max((hd + magnetField(coil, x)).norm(), hRef));
            nearJ = std::max(nearJ, (jt - jd).norm() / std::max((jd + fieldGradient(coil, x)).norm(), jRef));
        } else {
            farH = std::max(farH, (ht - hd).norm() / hRef);
            farJ = std::max(farJ, (jt - jd).norm() / jRef);
        }
    }
    WARN(n << " panels, " << points.size() << " points: tree against direct, worst within 4 mm |dH|/|H| " << nearH
           << ", |dJ|/|J| " << nearJ << "; farther, of the surface's scale, " << farH << ", " << farJ);
    CHECK(nearH < 1e-3);
    CHECK(nearJ < 1e-3);
    CHECK(farH < 1e-3);
    CHECK(farJ < 1e-3);
    // The standoff's path through the tree (the nearest surface point found among the
    // panels it lists): a standoff wider than two panel radii (2 mm against ~0.7 mm), points
    // 0.3 mm off the surfaces, against the sum over every panel.
    double standoffH = 0;
    for (size_t k = 0; k < points.size(); ++k) {
        if (!close[k]) continue;
        const Vec3d& x = points[k];
        Vec3d ht, hd;
        Mat3d jt, jd;
        tree.fieldAndGradient(x, ht, jt, 0.002);
        direct.fieldAndGradient(x, hd, jd, 0.002);
        standoffH = std::max(standoffH, (ht - hd).norm() / std::max((hd + magnetField(coil, x)).norm(), hRef));
    }
    WARN("with a 2 mm standoff, within 4 mm: tree against direct |dH|/|H| " << standoffH);
    CHECK(standoffH < 1e-3);
}

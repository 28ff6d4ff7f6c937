#pragma once
// Restarted GMRES(m) (Saad & Schultz 1986), header-only; used by the solids' surface-charge
// solve (sim/solids/SurfaceChargeSolver.cpp) and the magnetization solver
// (MagnetizationSolver.cpp) for the matrix-free linear system of each Newton step,
// (I - G chi_local) dH = -R (G the dipole field of the particles, chi_local the Jacobian of
// M(H)).
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <vector>

namespace ferro {

/// Solves op(x) = b by restarted GMRES(restart), starting from x = 0.
///  - op: any callable taking a const Eigen::VectorXd& of b's size and returning the
///    operator applied to it (an Eigen::VectorXd of the same size); it is the only access to
///    the operator (matrix-free).
///  - Stops when the residual norm |b - op(x)| <= absTol (absolute, not relative), or when
///    maxApply applications of op have been spent, or on a breakdown with nothing to add.
///  - Restarts after `restart` Krylov vectors; a restart takes its residual from the Arnoldi
///    relation (op V_m = V_{m+1} Hbar) instead of applying op again, so every application of
///    op goes to a new Krylov vector. resNorm receives that residual norm (exact in exact
///    arithmetic; it can differ from |b - op(x)| by rounding).
///  - x is resized to b's size; returns the number of applications of op (<= maxApply).
/// Memory: restart + 1 vectors of b's size.
template <class Op>
int gmres(Op&& op, const Eigen::VectorXd& b, Eigen::VectorXd& x, double absTol, int maxApply, int restart, double& resNorm) {
    const Eigen::Index n = b.size();
    x.setZero(n);
    Eigen::VectorXd r = b;
    double beta = r.norm();
    resNorm = beta;
    int applied = 0;
    std::vector<Eigen::VectorXd> V;
    while (beta > absTol && applied < maxApply) {
        const int m = std::min(restart, maxApply - applied);
        V.assign(1, r / beta);
        Eigen::MatrixXd Hh = Eigen::MatrixXd::Zero(m + 1, m);
        Eigen::VectorXd cs = Eigen::VectorXd::Zero(m), sn = Eigen::VectorXd::Zero(m), g = Eigen::VectorXd::Zero(m + 1);
        g[0] = beta;
        int k = 0;
        double est = beta;
        for (; k < m && est > absTol; ++k) {
            Eigen::VectorXd w = op(V[k]);
            ++applied;
            for (int i = 0; i <= k; ++i) { // modified Gram-Schmidt
                Hh(i, k) = w.dot(V[i]);
                w -= Hh(i, k) * V[i];
            }
            Hh(k + 1, k) = w.norm();
            const bool breakdown = !(Hh(k + 1, k) > 1e-300);
            V.push_back(breakdown ? Eigen::VectorXd(Eigen::VectorXd::Zero(n)) : Eigen::VectorXd(w / Hh(k + 1, k)));
            // apply the previous rotations to the new column, then a new one
            Eigen::VectorXd col = Hh.col(k);
            for (int i = 0; i < k; ++i) {
                const double t = cs[i] * col[i] + sn[i] * col[i + 1];
                col[i + 1] = -sn[i] * col[i] + cs[i] * col[i + 1];
                col[i] = t;
            }
            const double den = std::hypot(col[k], col[k + 1]);
            cs[k] = den > 0 ? col[k] / den : 1.0;
            sn[k] = den > 0 ? col[k + 1] / den : 0.0;
            col[k] = den;
            col[k + 1] = 0;
            for (int i = 0; i <= k + 1; ++i) Hh(i, k) = col[i]; // rotated (upper-triangular) storage
            g[k + 1] = -sn[k] * g[k];
            g[k] = cs[k] * g[k];
            est = std::abs(g[k + 1]);
            if (breakdown) {
                ++k;
                break;
            }
        }
        // y = R^-1 g (R = rotated Hh, upper triangular k x k)
        Eigen::VectorXd y = Eigen::VectorXd::Zero(k);
        for (int i = k - 1; i >= 0; --i) {
            double s = g[i];
            for (int j = i + 1; j < k; ++j) s -= Hh(i, j) * y[j];
            y[i] = Hh(i, i) != 0 ? s / Hh(i, i) : 0.0;
        }
        for (int i = 0; i < k; ++i) x += y[i] * V[i];
        // Residual of the rotated least-squares problem: Q^T (0,...,0,g_k) in the V basis.
        Eigen::VectorXd e = Eigen::VectorXd::Zero(k + 1);
        e[k] = g[k];
        for (int i = k - 1; i >= 0; --i) { // undo the rotations
            const double t = cs[i] * e[i] - sn[i] * e[i + 1];
            e[i + 1] = sn[i] * e[i] + cs[i] * e[i + 1];
            e[i] = t;
        }
        r.setZero(n);
        for (int i = 0; i <= k; ++i) r += e[i] * V[i];
        beta = r.norm();
        resNorm = beta;
        if (k == 0) break;
    }
    return applied;
}

} // namespace ferro

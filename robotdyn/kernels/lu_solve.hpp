// robotdyn/kernels/lu_solve.hpp: solves with the LU factors P A = L U of Eigen's PartialPivLU, written out as
// vector substitutions (for the small blocks of a projection they cost a fraction of Eigen's generic triangular
// solvers), and LAPACK's estimate of ||A^-1||_1 from them (Hager and Higham, as LAPACK's gecon and Eigen's rcond
// estimate), the test robotdyn/reduction/projection.py makes with numpy's exact 1-norm condition number
// (projection.MAX_CONDITION) and robotdyn/contact/sliding.py with numpy.linalg.cond. Used by the projection (A_d),
// the slipping wheels' system (K), the constraint forces and the rigid limit (A_d^T).
#pragma once

#include "common.hpp"

#include <algorithm>

namespace robotdyn {
namespace kernels {

// The work buffers of the solves (a member of the Evaluator, so the solves allocate nothing once sized).
struct LuSolver {
  VectorXd perm, est_v, est_s, est_old;

  // A^-1 x in place
  void solve(const Eigen::PartialPivLU<MatrixXd>& lu, Eigen::Ref<VectorXd> x) {
    const MatrixXd& LU = lu.matrixLU();
    const auto& p = lu.permutationP().indices();  // (P x)[p[i]] = x[i]
    const Eigen::Index n = x.size();
    perm.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) perm[p[i]] = x[i];
    for (Eigen::Index i = 1; i < n; ++i) {  // L (unit lower)
      double s = perm[i];
      for (Eigen::Index j = 0; j < i; ++j) s -= LU(i, j) * perm[j];
      perm[i] = s;
    }
    for (Eigen::Index i = n - 1; i >= 0; --i) {  // U
      double s = perm[i];
      for (Eigen::Index j = i + 1; j < n; ++j) s -= LU(i, j) * perm[j];
      perm[i] = s / LU(i, i);
    }
    x = perm;
  }

  // A^-T x in place (A = P^T L U, so A^T = U^T L^T P)
  void solve_transposed(const Eigen::PartialPivLU<MatrixXd>& lu, Eigen::Ref<VectorXd> x) {
    const MatrixXd& LU = lu.matrixLU();
    const Eigen::Index n = x.size();
    for (Eigen::Index i = 0; i < n; ++i) {  // U^T (lower)
      double s = x[i];
      for (Eigen::Index j = 0; j < i; ++j) s -= LU(j, i) * x[j];
      x[i] = s / LU(i, i);
    }
    for (Eigen::Index i = n - 2; i >= 0; --i) {  // L^T (unit upper)
      double s = x[i];
      for (Eigen::Index j = i + 1; j < n; ++j) s -= LU(j, i) * x[j];
      x[i] = s;
    }
    const auto& p = lu.permutationP().indices();  // (P^T x)[i] = x[p[i]]
    perm.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) perm[i] = x[p[i]];
    x = perm;
  }

  // LAPACK's estimate of ||A^-1||_1 with the solves above: a lower bound of the exact norm (in exact arithmetic),
  // in practice within a small factor of it
  double inverse_norm_estimate(const Eigen::PartialPivLU<MatrixXd>& lu) {
    const Eigen::Index n = lu.rows();
    est_v.setConstant(n, 1.0 / static_cast<double>(n));
    solve(lu, est_v);
    double lower = est_v.lpNorm<1>();
    if (n == 1) return lower;
    auto signs = [](const VectorXd& v, VectorXd& out) {
      out.resize(v.size());
      for (Eigen::Index i = 0; i < v.size(); ++i) out[i] = v[i] >= 0.0 ? 1.0 : -1.0;
    };
    signs(est_v, est_old);
    est_v = est_old;
    solve_transposed(lu, est_v);
    Eigen::Index index, old_index;
    est_v.cwiseAbs().maxCoeff(&index);
    double old_lower = lower;
    for (int k = 0; k < 4; ++k) {
      est_v.setZero(n);
      est_v[index] = 1.0;
      solve(lu, est_v);
      lower = est_v.lpNorm<1>();
      if (lower <= old_lower) break;
      signs(est_v, est_s);
      if (est_s == est_old) break;
      est_v = est_s;
      solve_transposed(lu, est_v);
      old_index = index;
      est_v.cwiseAbs().maxCoeff(&index);
      if (index == old_index) break;
      old_lower = lower;
      est_old = est_s;
    }
    double alternate = 1.0;
    est_v.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      est_v[i] = alternate * (1.0 + static_cast<double>(i) / static_cast<double>(n - 1));
      alternate = -alternate;
    }
    solve(lu, est_v);
    return std::max(lower, 2.0 * est_v.lpNorm<1>() / (3.0 * static_cast<double>(n)));
  }
};

}  // namespace kernels
}  // namespace robotdyn

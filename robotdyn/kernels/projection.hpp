// robotdyn/kernels/projection.hpp: the projection onto independent velocities that are a selection of v, twin of
// robotdyn/reduction/projection.py (Projection._build) with the Python path's row choice (rows, independent,
// dependent velocities):
//
//   S = P [I; -A_d^-1 A_i]  (A_d, A_i: the chosen rows on the dependent and independent columns), so A S = 0
//   w = Sdot nu solves A w = -Adot v on the chosen rows: w_d = -A_d^-1 drift_rows, w_i = 0
//   the block's 1-norm condition number above 1e10 is singular (projection.MAX_CONDITION), decided by LAPACK's
//   estimate far from the bound and by the exact number from an estimate of 1e8 on; the chosen rows must still span
//   the others (|A S| <= 1e-10 max(1, |A|)), else the Python path re-chooses (Fallback).
// The operational variant (independent velocities that are a frame's twist) is operational_space.hpp.
#pragma once

#include "common.hpp"
#include "lu_solve.hpp"

#include <cmath>
#include <limits>
#include <vector>

namespace robotdyn {
namespace kernels {

// The work buffers of the selection projection.
struct SelectionBuffers {
  MatrixXd Ad, Ai, Adinv, Sd;
};

// The selection's blocks: S (nv, k) set to the identity on the independent velocities (zero elsewhere), and, where
// some velocity is dependent, A_d and A_i of the chosen rows (in b) with A_d's LU factors in lu. Returns false where
// no velocity is dependent (S is then complete).
inline bool selection_blocks(const MatrixXd& A, const std::vector<int>& rows, const std::vector<int>& independent,
                             const std::vector<int>& dependent, int nv, Eigen::PartialPivLU<MatrixXd>& lu,
                             SelectionBuffers& b, MatrixXd& S) {
  const int nd = static_cast<int>(dependent.size());
  const int k = static_cast<int>(independent.size());
  S.setZero(nv, k);
  for (int j = 0; j < k; ++j) S(independent[j], j) = 1.0;
  if (nd == 0) return false;
  b.Ad.resize(nd, nd);
  b.Ai.resize(nd, k);
  for (int r = 0; r < nd; ++r) {
    for (int c = 0; c < nd; ++c) b.Ad(r, c) = A(rows[r], dependent[c]);
    for (int c = 0; c < k; ++c) b.Ai(r, c) = A(rows[r], independent[c]);
  }
  lu.compute(b.Ad);
  return true;
}

// S's dependent rows, -A_d^-1 A_i, from the LU factors selection_blocks left; false (S unchanged there) where the
// solve is not finite (an exactly singular block: a zero pivot).
inline bool selection_solve(const std::vector<int>& dependent, LuSolver& lus, const Eigen::PartialPivLU<MatrixXd>& lu,
                            SelectionBuffers& b, MatrixXd& S) {
  b.Sd = b.Ai;
  for (Eigen::Index c = 0; c < b.Sd.cols(); ++c) lus.solve(lu, b.Sd.col(c));
  if (!b.Sd.allFinite()) return false;
  for (size_t r = 0; r < dependent.size(); ++r) S.row(dependent[r]) = -b.Sd.row(static_cast<Eigen::Index>(r));
  return true;
}

// S (nv, k) from the constraint rows A with the chosen rows and velocities; leaves A_d's LU factors in lu and its
// 1-norm condition number (estimated below 1e8, exact above) in cond. Returns false where no velocity is dependent
// (S a selection, nothing to check), true where check_span should follow.
inline bool project_selection(const MatrixXd& A, const std::vector<int>& rows, const std::vector<int>& independent,
                              const std::vector<int>& dependent, int nv, LuSolver& lus,
                              Eigen::PartialPivLU<MatrixXd>& lu, SelectionBuffers& b, double& cond, MatrixXd& S) {
  if (!selection_blocks(A, rows, independent, dependent, nv, lu, b, S)) {
    cond = 1.0;
    return false;
  }
  // The Python path refuses a block whose 1-norm condition number exceeds 1e10 (projection.MAX_CONDITION).
  // LAPACK's estimate (O(n^2), LuSolver::inverse_norm_estimate) decides far from that bound; from an estimate of 1e8
  // on, the exact number (an O(n^3) inverse) decides, as in Python. The exact number is reported by the Python side
  // (robotdyn.fast.compiled.LazyProjection), from A.
  cond = b.Ad.cwiseAbs().colwise().sum().maxCoeff() * lus.inverse_norm_estimate(lu);
  if (std::isnan(cond)) cond = std::numeric_limits<double>::infinity();
  if (!(cond < 1e8)) {
    b.Adinv = lu.inverse();
    cond = b.Ad.cwiseAbs().colwise().sum().maxCoeff() * b.Adinv.cwiseAbs().colwise().sum().maxCoeff();
    if (!(std::isfinite(cond) && cond <= 1e10)) throw Fallback("singular");
  }
  if (!selection_solve(dependent, lus, lu, b, S)) throw Fallback("singular");
  return true;
}

// The chosen rows still span all rows: |A S| <= 1e-10 max(1, |A|) (AS a work buffer), else Fallback. A and S are
// read only (non-const: see reduced_dynamics.hpp's reduce).
inline void check_span(MatrixXd& A, MatrixXd& S, MatrixXd& AS) {
  const double scale = std::max(1.0, A.size() ? A.cwiseAbs().maxCoeff() : 0.0);
  if (A.size() && S.cols()) {  // (no independent velocity: nothing to check, and no maximum to take)
    AS.noalias() = A.lazyProduct(S);
    if (!(AS.cwiseAbs().maxCoeff() <= 1e-10 * scale)) throw Fallback("row choice no longer spans");  // NaN too
  }
}

// w = Sdot nu (nv) from the rows' drift Adot v: w_d = -A_d^-1 drift_rows with A_d's LU factors, zero elsewhere
// (rhs, wd work buffers).
inline void drift_acceleration_selection(const VectorXd& drift, const std::vector<int>& rows,
                                         const std::vector<int>& dependent, const Eigen::PartialPivLU<MatrixXd>& lu,
                                         LuSolver& lus, VectorXd& rhs, VectorXd& wd, VectorXd& w) {
  const int nr = static_cast<int>(rows.size());
  if (!nr) return;
  rhs.resize(nr);
  for (int r = 0; r < nr; ++r) rhs[r] = drift[rows[r]];
  lus.solve(lu, rhs);
  wd = -rhs;
  for (int r = 0; r < nr; ++r) w[dependent[r]] = wd[r];
}

}  // namespace kernels
}  // namespace robotdyn

// robotdyn/kernels/rigid_limit.hpp: the loads rigid-body dynamics leave open, fixed by the rigid limit of the
// wheels' normal compliance, twin of robotdyn/contact/rigid_limit.py (the same formulas; notes:
// indeterminate-loads-and-compliance.md). With lambda a solution of A^T lambda = e and N a basis of null(A^T):
//
//   lambda + N z,  z along the directions V_n that move normal loads (an SVD of P = C N, C picking each wheel's
//   normal load) minimising sum_i n_i^2 / k_i (Menabrea, Castigliano: the compatible loads), n = n0 + P z;
//   minimum norm along the directions that move no normal load; the rows rigid-body dynamics determine keep their
//   values. Where the compatible loads would pull on a wheel the no-pull split (a least-distance program) is the
//   Python path's (Fallback).
#pragma once

#include "common.hpp"
#include "lu_solve.hpp"
#include "rolling_contact.hpp"

#include <algorithm>
#include <limits>
#include <vector>

namespace robotdyn {
namespace kernels {

struct RigidLimit {
  bool on = true;  // set_rigid_limit(false): the basic solution (zero on redundant rows)
  VectorXd kstiff, rk;  // normal stiffnesses k [N/m] and 1 / sqrt(k) (equal weights without them)
  VectorXd n0, saved, cc, y, n, z, t, wrow;
  MatrixXd Q, N, P, G, O, W, H;
  Eigen::LLT<MatrixXd> llt;
  std::vector<bool> in;
  Eigen::ColPivHouseholderQR<MatrixXd> qr;
  Eigen::JacobiSVD<MatrixXd> svd;

  void set_stiffness(const Eigen::Ref<const VectorXd>& k) {
    kstiff = k;
    rk = k.cwiseSqrt().cwiseInverse();
  }

  // lambda (m) in place. A the stacked rows, rows/dependent the projection's choice with A_d's LU factors in lu (or,
  // operational, a column-pivoting QR of A here). Nothing happens without redundant rows, where a row acts on no
  // coordinate (a planar root's normal rows), or when off.
  void split(const MatrixXd& A, const std::vector<int>& rows, const std::vector<int>& dependent, bool operational,
             const Eigen::PartialPivLU<MatrixXd>& lu, LuSolver& lus, const std::vector<Wheel>& wheels,
             const std::vector<WheelGeometry>& geo, int nv, VectorXd& lambda) {
    const int m = static_cast<int>(A.rows());
    const int nw = static_cast<int>(wheels.size());
    if (!on || static_cast<int>(rows.size()) >= m || nw == 0 || m == 0) return;
    const double scale = std::max(1.0, A.cwiseAbs().maxCoeff());
    for (int r = 0; r < m; ++r)
      if (A.row(r).cwiseAbs().maxCoeff() <= 1e-12 * scale) return;
    const int nr = static_cast<int>(rows.size());
    int d;
    if (!operational) {
      // a basis of null(A^T) from the projection's own LU of A_d: each row j outside the projection's choice is
      // A_j = c^T A_R with A_d^T c = (A_j on the dependent columns), so e_j - sum_r c_r e_{rows_r} is in null(A^T)
      d = m - nr;
      N.setZero(m, d);
      in.assign(m, false);
      for (int r = 0; r < nr; ++r) in[rows[r]] = true;
      int col = 0;
      for (int j = 0; j < m; ++j) {
        if (in[j]) continue;
        cc.resize(nr);
        for (int r = 0; r < nr; ++r) cc[r] = A(j, dependent[r]);
        lus.solve_transposed(lu, cc);
        N(j, col) = 1.0;
        for (int r = 0; r < nr; ++r) N(rows[r], col) = -cc[r];
        ++col;
      }
    } else {
      qr.setThreshold(std::max(m, nv) * std::numeric_limits<double>::epsilon());
      qr.compute(A);
      d = m - static_cast<int>(qr.rank());
      if (d <= 0) return;
      Q = qr.householderQ();
      N = Q.rightCols(d);
    }
    P.setZero(nw, d);
    n0.setZero(nw);
    for (int i = 0; i < nw; ++i) {
      const Wheel& wh = wheels[i];
      const int row = geo[i].row;
      for (int r = 0; r < wh.D.rows(); ++r) {
        const double c = wh.D(r, 2);
        if (c == 0.0) continue;
        P.row(i) += c * N.row(row + r);
        n0[i] += c * lambda[row + r];
      }
    }
    svd.compute(P, Eigen::ComputeFullV);
    const VectorXd& sv = svd.singularValues();
    int p = 0;
    while (p < sv.size() && sv[p] > 1e-9) ++p;
    if (p == 0) return;
    const MatrixXd& V = svd.matrixV();
    if (rk.size() != nw) rk.setOnes(nw);  // 1 / sqrt(k) (set_stiffness; equal without it)
    G.noalias() = P * V.leftCols(p);
    W.noalias() = rk.asDiagonal() * G;
    H.noalias() = W.transpose() * W;
    y.noalias() = W.transpose() * rk.cwiseProduct(n0);
    llt.compute(H);
    llt.solveInPlace(y);
    y = -y;
    n = n0;
    n.noalias() += G * y;
    const double big = std::max(n0.cwiseAbs().maxCoeff(), n.cwiseAbs().maxCoeff());
    if (!y.allFinite()) throw Fallback("the rigid limit's split is not finite here");
    if (n.minCoeff() < -1e-9 * big)
      throw Fallback("a wheel would pull: the rigid limit's no-pull split is solved on the Python path");
    saved = lambda;
    z.noalias() = V.leftCols(p) * y;
    lambda.noalias() += N * z;
    if (d > p) {  // minimum norm along the open directions N V_o (Gram-Schmidt: N need not be orthonormal)
      O.noalias() = N * V.rightCols(d - p);
      for (int c = 0; c < d - p; ++c) {
        for (int b = 0; b < c; ++b) O.col(c) -= O.col(b).dot(O.col(c)) * O.col(b);
        O.col(c) /= O.col(c).norm();
      }
      t.noalias() = O.transpose() * lambda;
      lambda.noalias() -= O * t;
    }
    wrow = N.rowwise().squaredNorm();  // (a row's weight in null(A^T) is zero in every basis)
    for (int r = 0; r < m; ++r)
      if (wrow[r] <= 1e-16) lambda[r] = saved[r];
  }
};

}  // namespace kernels
}  // namespace robotdyn

// robotdyn/kernels/pull_back.hpp: the pull-back of holonomic residuals onto the constraint manifold during a
// simulation, twin of robotdyn/reduction/pull_back.py: qdot -= alpha dq with dq the minimum-norm least-squares
// solution of A_h dq = phi (A_h the holonomic rows, phi their residuals), directions of no rank left out, so that
// rows with no rank (a wheel's normal row under a planar root) keep their residual as a constant offset. The Python
// path takes dq from a truncated SVD (singular values below 1e-9 max(s_max, 1) count as zero); here the same dq comes
// from a complete orthogonal decomposition (a column-pivoting QR, then RZ) with pivots below 1e-9 max(p_max, 1)
// counting as zero, p_max the largest pivot (the largest column norm of A_h): a few microseconds where the SVD of the
// linkage rover's A_h (16 x 25) took ~80, three quarters of its whole right-hand side.
#pragma once

#include "common.hpp"

#include <algorithm>
#include <vector>

namespace robotdyn {
namespace kernels {

struct PullBack {
  MatrixXd Ah;
  VectorXd phi, dq, y;
  std::vector<int> rows, cols;  // A's holonomic rows; its columns taking part (not exactly zero on those rows)
  Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod;

  // x <- (I - tau u u^T) x on the entries (x0, xt) for u = (1, e) (Eigen's applyHouseholderOnTheLeft on one column,
  // written out: its products made a heap temporary per reflector).
  template <class E, class T>
  static void reflect(double& x0, T&& xt, const E& e, double tau) {
    if (xt.size() == 0) {
      x0 *= 1.0 - tau;
      return;
    }
    if (tau == 0.0) return;
    const double t = e.dot(xt) + x0;
    x0 -= tau * t;
    for (Eigen::Index i = 0; i < xt.size(); ++i) xt[i] -= (tau * e[i]) * t;
  }

  // dq = cod's minimum-norm solution of Ah dq = phi (CompleteOrthogonalDecomposition::solve's steps: c = Q^T phi,
  // T z = c on the rank's rows, y = Z^T (z, 0), dq = P y) in the buffers above, allocating nothing once sized
  // (phi is overwritten with c).
  void solve() {
    const Eigen::Index m = Ah.rows(), n = Ah.cols(), rank = cod.rank();
    const MatrixXd& QR = cod.matrixQTZ();  // Q's reflectors below the diagonal (ColPivHouseholderQR's storage)
    for (Eigen::Index k = 0; k < rank; ++k)  // c = Q^T phi = H_{rank-1} ... H_0 phi
      reflect(phi[k], phi.tail(m - k - 1), QR.col(k).tail(m - k - 1), cod.hCoeffs()[k]);
    y.setZero(n);
    y.head(rank) = phi.head(rank);
    cod.matrixT().topLeftCorner(rank, rank).template triangularView<Eigen::Upper>().solveInPlace(y.head(rank));
    if (rank < n)  // y = Z^T (z, 0): reflector k acts on entry k and the last n - rank entries
      for (Eigen::Index k = 0; k < rank; ++k)
        reflect(y[k], y.tail(n - rank), QR.row(k).tail(n - rank).transpose(), cod.zCoeffs()[k]);
    dq.resize(n);
    const auto& p = cod.colsPermutation().indices();
    for (Eigen::Index i = 0; i < n; ++i) dq[p[i]] = y[i];
  }

  // out.head(nv) -= alpha dq (nothing where every holonomic residual is exactly zero).
  void apply(const std::vector<bool>& holonomic, const VectorXd& residual, const MatrixXd& A, int nv, double alpha,
             Eigen::Ref<VectorXd> out) {
    bool any = false;
    rows.clear();
    for (size_t r = 0; r < holonomic.size(); ++r)
      if (holonomic[r]) {
        rows.push_back(static_cast<int>(r));
        any = any || residual[r] != 0.0;
      }
    if (!any) return;
    const int nh = static_cast<int>(rows.size());
    // A_h on its columns that are not exactly zero (coordinates that no holonomic row moves: 7 of the linkage
    // rover's 25): dq is exactly zero on the others (the minimum-norm solution has no component along them, and
    // the decomposition of the whole A_h kept them exactly zero), and the decomposition of the rest takes the same
    // steps, up to the grouping of Eigen's vectorised sums over the dropped zeros (measured: the same bits as the
    // whole A_h on 96 right-hand sides of four robots, residuals up to 1e-6; the linkage rover's pull-back
    // 9.9 -> 8.5 us, its column-pivoting QR on 18 columns instead of 25)
    cols.clear();
    for (int c = 0; c < nv; ++c)
      for (int r : rows)
        if (A(r, c) != 0.0) {  // (NaN too: kept, and then no pull-back, as before: the step fails as non-finite)
          cols.push_back(c);
          break;
        }
    const int nc = static_cast<int>(cols.size());
    if (nc == 0) return;  // no rank at all
    Ah.resize(nh, nc);
    phi.resize(nh);
    for (int j = 0; j < nh; ++j) {
      for (int c = 0; c < nc; ++c) Ah(j, c) = A(rows[j], cols[c]);
      phi[j] = residual[rows[j]];
    }
    const double pmax = Ah.colwise().norm().maxCoeff();  // the first pivot of the column-pivoting QR
    if (!(pmax > 0.0)) return;                            // no rank at all (or not finite: the step fails elsewhere)
    cod.setThreshold(1e-9 * std::max(pmax, 1.0) / pmax);  // pivots <= 1e-9 max(p_max, 1) count as zero
    cod.compute(Ah);
    if (cod.rank() == 0) return;
    solve();
    for (int c = 0; c < nc; ++c) out[cols[c]] -= alpha * dq[c];
  }
};

}  // namespace kernels
}  // namespace robotdyn

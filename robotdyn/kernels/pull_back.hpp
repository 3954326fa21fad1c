// robotdyn/kernels/pull_back.hpp: the pull-back of holonomic residuals onto the constraint manifold during a
// simulation, twin of robotdyn/reduction/pull_back.py: qdot -= alpha dq with dq the minimum-norm solution of
// A_h dq = phi (A_h the holonomic rows, phi their residuals), by a truncated SVD: singular values below
// 1e-9 max(s_max, 1) count as zero, so rows with no rank (a wheel's normal row under a planar root) keep their
// residual as a constant offset.
#pragma once

#include "common.hpp"

#include <algorithm>
#include <vector>

namespace robotdyn {
namespace kernels {

// out.head(nv) -= alpha dq (nothing where every holonomic residual is exactly zero).
inline void pull_back(const std::vector<bool>& holonomic, const VectorXd& residual, const MatrixXd& A, int nv,
                      double alpha, Eigen::JacobiSVD<MatrixXd>& svd, Eigen::Ref<VectorXd> out) {
  int nh = 0;
  bool any = false;
  for (size_t r = 0; r < holonomic.size(); ++r)
    if (holonomic[r]) {
      ++nh;
      any = any || residual[r] != 0.0;
    }
  if (!any) return;
  MatrixXd Ah(nh, nv);
  VectorXd phi(nh);
  int j = 0;
  for (size_t r = 0; r < holonomic.size(); ++r)
    if (holonomic[r]) {
      Ah.row(j) = A.row(r);
      phi[j++] = residual[r];
    }
  svd.compute(Ah, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const VectorXd& s = svd.singularValues();
  const double cut = 1e-9 * std::max(s.size() ? s[0] : 0.0, 1.0);
  int rank = 0;
  while (rank < s.size() && s[rank] > cut) ++rank;
  if (rank == 0) return;
  VectorXd c = svd.matrixU().leftCols(rank).transpose() * phi;
  c.array() /= s.head(rank).array();
  out.head(nv).noalias() -= alpha * (svd.matrixV().leftCols(rank) * c);
}

}  // namespace kernels
}  // namespace robotdyn

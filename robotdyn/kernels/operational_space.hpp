// robotdyn/kernels/operational_space.hpp: independent velocities that are a frame's twist, twin of
// robotdyn/reduction/operational_space.py (OperationalVelocities, project_operational): nu = J_o v with J_o the
// selected components of a frame's twist (LOCAL: body axes; else LOCAL_WORLD_ALIGNED), and with the chosen rows A_r
//
//   K = [A_r; J_o],  K S = [0; I]  so  S = (K^-1)[:, -k:],  A S = 0,  J_o S = I
//   w = -K^-1 [drift_rows; Jdot_o v], Jdot_o v the frame's (spatial, or classical in world axes) acceleration at
//   zero joint acceleration
//   K's exact 1-norm condition number above 1e10 is singular (Fallback: the Python path decides)
#pragma once

#include "common.hpp"

#include <cmath>
#include <vector>

namespace robotdyn {
namespace kernels {

// K = [A_r; J_o] from the rows A, the chosen rows and the operational frame fid's selected components, its LU
// factors (in lu) and K^-1, and S (nv, k), K^-1's last k columns: project_operational without its condition number
// (a run's sample, after evaluations that all passed it: Evaluator::sample). Returns false where K^-1 is not finite
// (S is then not set). Jc is a work buffer.
inline bool operational_inverse(const MatrixXd& A, const std::vector<int>& rows, const std::vector<int>& select,
                                const pin::Model& model, pin::Data& data, int fid, bool local, int nv, MatrixXd& K,
                                Matrix6x& Jc, Eigen::PartialPivLU<MatrixXd>& lu, MatrixXd& Kinv, MatrixXd& S) {
  const int k = static_cast<int>(select.size());
  const int nr = static_cast<int>(rows.size());
  if (nr + k != nv) throw Fallback("operational rows do not match");
  K.resize(nv, nv);
  for (int r = 0; r < nr; ++r) K.row(r) = A.row(rows[r]);
  Jc.setZero(6, nv);
  pin::getFrameJacobian(model, data, fid, local ? pin::LOCAL : pin::LOCAL_WORLD_ALIGNED, Jc);
  for (int r = 0; r < k; ++r) K.row(nr + r) = Jc.row(select[r]);
  lu.compute(K);
  // K^-1 as lu.inverse() computes it (Eigen's Inverse<PartialPivLU> assigns lu.solve(I): the same bits), without the
  // copy of the factors that the Inverse expression holds (three heap allocations per call)
  Kinv = lu.solve(MatrixXd::Identity(nv, nv));
  if (!Kinv.allFinite()) return false;
  S = Kinv.rightCols(k);
  return true;
}

// S (nv, k) and K^-1 as operational_inverse; leaves K's LU factors in lu and its exact 1-norm condition number in
// cond; above 1e10, or K^-1 not finite: Fallback (K, Jc work buffers).
inline void project_operational(const MatrixXd& A, const std::vector<int>& rows, const std::vector<int>& select,
                                const pin::Model& model, pin::Data& data, int fid, bool local, int nv, MatrixXd& K,
                                Matrix6x& Jc, Eigen::PartialPivLU<MatrixXd>& lu, MatrixXd& Kinv, double& cond,
                                MatrixXd& S) {
  const bool finite = operational_inverse(A, rows, select, model, data, fid, local, nv, K, Jc, lu, Kinv, S);
  cond = K.cwiseAbs().colwise().sum().maxCoeff() * Kinv.cwiseAbs().colwise().sum().maxCoeff();
  if (!(std::isfinite(cond) && cond <= 1e10) || !finite) throw Fallback("singular");
}

// The last k entries of out from entry `base` on: d/dt J_o at zero joint acceleration, times v (after an RNEA pass at
// (q, v, 0)).
inline void operational_drift(const pin::Model& model, const pin::Data& data, int fid, bool local,
                              const std::vector<int>& select, int base, VectorXd& out) {
  const pin::Motion a = local ? pin::getFrameAcceleration(model, data, fid, pin::LOCAL)
                              : pin::getFrameClassicalAcceleration(model, data, fid, pin::LOCAL_WORLD_ALIGNED);
  for (size_t r = 0; r < select.size(); ++r) {
    const int s = select[r];
    out[base + r] = s < 3 ? a.linear()[s] : a.angular()[s - 3];
  }
}

// w = -K^-1 [drift_rows; Jdot_o v] (rhs a work buffer of nv entries; Kinv read only).
inline void drift_acceleration_operational(const VectorXd& drift, const std::vector<int>& rows,
                                           const std::vector<int>& select, const pin::Model& model,
                                           const pin::Data& data, int fid, bool local, int nv, MatrixXd& Kinv,
                                           VectorXd& rhs, VectorXd& w) {
  const int nr = static_cast<int>(rows.size());
  rhs.resize(nv);
  for (int r = 0; r < nr; ++r) rhs[r] = drift[rows[r]];
  operational_drift(model, data, fid, local, select, nr, rhs);
  w.noalias() = -Kinv * rhs;
}

}  // namespace kernels
}  // namespace robotdyn

// robotdyn/kernels/contact_forces.hpp: constraint forces at a state, twin of robotdyn/contact/contact_forces.py:
//
//   A^T lambda = e,  e = M a + C v + g - B tau  (M a + h = B tau + A^T lambda, a = S nudot + w)
//
// solved on the rows the projection uses: A_d^T lambda_r = e_d with the projection's own LU factors of A_d; with
// operational velocities lambda_r = (K^-T e)_head (K = [A_r; J_o], K S = [0; I]). Rows outside the projection's choice
// (redundant ones) get zero: the basic solution, equal to every other solution on the rows rigid-body dynamics
// determine (the rigid limit, rigid_limit.hpp, fixes the others). A wheel's multipliers are the force the ground
// exerts on it at the contact point, along (t1, t2, n) [N].
#pragma once

#include "common.hpp"
#include "lu_solve.hpp"
#include "rolling_contact.hpp"

#include <vector>

namespace robotdyn {
namespace kernels {

// lambda (m) from e = M a + C v + g (made e - B tau here, in place); Bt a work buffer, lr the rows' multipliers (B,
// Kinv read only).
inline void constraint_multipliers(MatrixXd& B, const Eigen::Ref<const VectorXd>& tau, VectorXd& Bt,
                                   VectorXd& e, const std::vector<int>& rows, const std::vector<int>& dependent,
                                   bool operational, MatrixXd& Kinv, const Eigen::PartialPivLU<MatrixXd>& lu,
                                   LuSolver& lus, int m, VectorXd& lr, VectorXd& lambda) {
  Bt.noalias() = B * tau;
  e -= Bt;
  lambda.setZero(m);
  const int nr = static_cast<int>(rows.size());
  if (!nr) return;
  if (operational) {  // K = [A_r; J_o] with K S = [0; I]: K^T (lambda_r, 0) = e, so lambda_r = (K^-T e)_head
    lr.noalias() = Kinv.transpose() * e;
    lr.conservativeResize(nr);
  } else {
    lr.resize(nr);
    for (int r = 0; r < nr; ++r) lr[r] = e[dependent[r]];
    lus.solve_transposed(lu, lr);
  }
  for (int r = 0; r < nr; ++r) lambda[rows[r]] = lr[r];
}

// Per wheel: the force along (t1, t2, n), the same in world axes, the contact frame (rows t1, t2, n: (nw, 9),
// row-major) and the contact point (nw, 3).
inline void wheel_force_table(const std::vector<Wheel>& wheels, const std::vector<WheelGeometry>& geo,
                              const VectorXd& lambda, RowMat& local, RowMat& world, RowMat& frames, RowMat& points) {
  const int nw = static_cast<int>(wheels.size());
  local.resize(nw, 3);
  world.resize(nw, 3);
  frames.resize(nw, 9);
  points.resize(nw, 3);
  for (int i = 0; i < nw; ++i) {
    const WheelGeometry& g = geo[i];
    const Vector3d f = wheel_force(wheels[i], g, lambda);
    local.row(i) = f.transpose();
    world.row(i) = (f[0] * g.t1 + f[1] * g.t2 + f[2] * g.n).transpose();
    frames.row(i) << g.t1.transpose(), g.t2.transpose(), g.n.transpose();
    points.row(i) = g.p.transpose();
  }
}

}  // namespace kernels
}  // namespace robotdyn

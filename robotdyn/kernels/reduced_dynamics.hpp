// robotdyn/kernels/reduced_dynamics.hpp: the equations of motion in the independent velocities, twin of
// robotdyn/reduction/reduced_dynamics.py (D'Alembert with v = S nu, a = S nudot + w):
//
//   M_r = S^T M S,  h = C_r nu + g_r = S^T RNEA(q, S nu, w) = S^T (C v + g + M w),  g_r = S^T g,  B_r = S^T B
//
// here from two Pinocchio passes per state: CRBA in the WORLD convention (M, the joint Jacobians, and from its
// composite inertias g_k = -J_k^T (Y_subtree(k) a_g), the torque that holds the subtree's weight) and RNEA without
// gravity at zero joint acceleration (C v).
#pragma once

#include "common.hpp"

namespace robotdyn {
namespace kernels {

// g (nv) from CRBA's composite inertias (data.oYcrb) and world joint Jacobians (data.J), gravity the model's
// (a Pinocchio model whose own gravity is zero).
inline void gravity_torques(const pin::Model& model, const pin::Data& data, const pin::Motion& gravity, int nv,
                            VectorXd& g) {
  g.resize(nv);
  for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model.njoints); ++i) {
    const int col = model.joints[i].idx_v();
    const pin::Force weight = data.oYcrb[i] * gravity;
    g[col] = -(data.J.col(col).head<3>().dot(weight.linear()) + data.J.col(col).tail<3>().dot(weight.angular()));
  }
}

// M_r, h, g_r, B_r from M (CRBA's upper triangle: its lower one is filled here), S, g, Cv (RNEA's C v: g is added to
// it in place, so it holds C v + g after), w and B; SM = M S is kept (the slipping wheels' system and the constraint
// forces use it). S, g, w and B are read only (non-const references: Eigen's products of non-const operands, which
// GCC inlines where it does not inline those of const ones; measured 10 -> 16 us per evaluation on MMR12-EOD).
inline void reduce(MatrixXd& M, MatrixXd& S, VectorXd& g, VectorXd& Cv, VectorXd& w, MatrixXd& B, MatrixXd& SM,
                   MatrixXd& Mr, VectorXd& hr, VectorXd& gr, MatrixXd& Br) {
  M.triangularView<Eigen::StrictlyLower>() = M.transpose().triangularView<Eigen::StrictlyLower>();
  SM.noalias() = M.lazyProduct(S);
  Mr.noalias() = S.transpose().lazyProduct(SM);
  gr.noalias() = S.transpose() * g;
  Cv += g;
  hr.noalias() = S.transpose() * Cv;
  hr.noalias() += SM.transpose() * w;
  Br.noalias() = S.transpose().lazyProduct(B);
}

}  // namespace kernels
}  // namespace robotdyn

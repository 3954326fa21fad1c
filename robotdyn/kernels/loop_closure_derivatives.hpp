// robotdyn/kernels/loop_closure_derivatives.hpp: configuration derivatives of a loop closure's rows, twin of
// robotdyn/constraints/row_derivatives.py (closure_velocity_dq, closure_drift_dq) beside the closure's values in
// loop_closure.hpp (robotdyn/constraints/loop_closure.py, whose LoopClosure.rows gives Adot): d(A x)/dq at fixed x,
// the drift's dgamma/dq at fixed v, and Adot.
#pragma once

#include <vector>

#include "frame_derivatives.hpp"

namespace robotdyn {
namespace derivs {

// The closure's two frames at q: placements (R1, p1, p2) and world Jacobians J1, J2 (6 x n).
struct ClosureFrames {
  Matrix3d R1;
  Vector3d p1, p2;
  const Matrix6x* J1;
  const Matrix6x* J2;
};

// copy the selected components (0..5: x y z rx ry rz in frame 1's axes) of a 6 x n block into out
template <class Out>
void select_rows(const Matrix6xB& full, const std::vector<int>& select, Out&& out) {
  for (size_t r = 0; r < select.size(); ++r) out.row(static_cast<Eigen::Index>(r)) = full.row(select[r]);
}

// closure_velocity_dq: V1/dV1, V2/dV2 the frames' world velocities at x and their q-derivatives
template <class Out>
void closure_velocity_dq(const ClosureFrames& f, const std::vector<int>& select, const Vector6d& V1,
                         const Matrix6x& dV1, const Vector6d& V2, const Matrix6x& dV2, Out&& out) {
  const Matrix6x &J1 = *f.J1, &J2 = *f.J2;
  const Matrix3d R1T = f.R1.transpose();
  const Vector3d d = f.p2 - f.p1;
  const Matrix3x dd = J2.topRows<3>() - J1.topRows<3>();
  const Vector3d yt = V2.head<3>() - V1.head<3>() + d.cross(V1.tail<3>());
  const Vector3d yr = V2.tail<3>() - V1.tail<3>();
  const Matrix3x dyt = dV2.topRows<3>() - dV1.topRows<3>() + cross_d(d, dd, V1.tail<3>(), dV1.bottomRows<3>());
  const Matrix3x dyr = dV2.bottomRows<3>() - dV1.bottomRows<3>();
  Matrix6xB full(6, J1.cols());
  rotate_skew_add(R1T, yt, J1.bottomRows<3>(), dyt, full.topRows<3>());
  rotate_skew_add(R1T, yr, J1.bottomRows<3>(), dyr, full.bottomRows<3>());
  select_rows(full, select, out);
}

// closure_drift_dq into drift_out, and Adot (LoopClosure.rows) into adot_out; A1/dA1, A2/dA2 the frames' world
// classical accelerations at v with q-derivatives, dJ1, dJ2 their Jacobians' time variations along v
template <class Out1, class Out2>
void closure_drift_dq(const ClosureFrames& f, const std::vector<int>& select, const Vector6d& V1,
                      const Matrix6x& dV1, const Vector6d& V2, const Matrix6x& dV2, const Vector6d& A1,
                      const Matrix6x& dA1, const Vector6d& A2, const Matrix6x& dA2, const Matrix6x& dJ1,
                      const Matrix6x& dJ2, Out1&& drift_out, Out2&& adot_out) {
  const Matrix6x &J1 = *f.J1, &J2 = *f.J2;
  const Matrix3d R1T = f.R1.transpose();
  const Vector3d d = f.p2 - f.p1;
  const Matrix3x dd = J2.topRows<3>() - J1.topRows<3>();
  const Vector3d w1 = V1.tail<3>();
  const Matrix3x dw1 = dV1.bottomRows<3>();
  const Vector3d ddot = V2.head<3>() - V1.head<3>();
  const Matrix3x dddot = dV2.topRows<3>() - dV1.topRows<3>();
  const Vector3d kt = ddot + d.cross(w1);
  const Matrix3x dkt_q = dddot + cross_d(d, dd, w1, dw1);
  const Vector3d jt = A2.head<3>() - A1.head<3>() + ddot.cross(w1) + d.cross(A1.tail<3>());
  const Matrix3x djt = dA2.topRows<3>() - dA1.topRows<3>() + cross_d(ddot, dddot, w1, dw1) +
                       cross_d(d, dd, A1.tail<3>(), dA1.bottomRows<3>());
  const Vector3d kr = V2.tail<3>() - V1.tail<3>();
  const Matrix3x dkr = dV2.bottomRows<3>() - dV1.bottomRows<3>();
  const Vector3d jr = A2.tail<3>() - A1.tail<3>();
  const Matrix3x djr = dA2.bottomRows<3>() - dA1.bottomRows<3>();
  const Vector3d yt = jt - w1.cross(kt), yr = jr - w1.cross(kr);
  const Matrix3x dyt = djt - cross_d(w1, dw1, kt, dkt_q);
  const Matrix3x dyr = djr - cross_d(w1, dw1, kr, dkr);
  Matrix6xB full(6, J1.cols());
  rotate_skew_add(R1T, yt, J1.bottomRows<3>(), dyt, full.topRows<3>());
  rotate_skew_add(R1T, yr, J1.bottomRows<3>(), dyr, full.bottomRows<3>());
  select_rows(full, select, drift_out);
  // Adot: R1^T (dK - [w1]x K) with K = [J2_c - J1_c + [d]x J1_w; J2_w - J1_w]
  const Matrix3d W = skew3(w1);
  Matrix3x Kt = dd;  // (the sums below in the same order, the products written in place)
  Kt.noalias() += skew3(d) * J1.bottomRows<3>();
  Matrix3x dKt = dJ2.topRows<3>() - dJ1.topRows<3>();
  dKt.noalias() += skew3(ddot) * J1.bottomRows<3>();
  dKt.noalias() += skew3(d) * dJ1.bottomRows<3>();
  const Matrix3x Kr = J2.bottomRows<3>() - J1.bottomRows<3>();
  Matrix3x dKr = dJ2.bottomRows<3>() - dJ1.bottomRows<3>();
  dKt.noalias() -= W * Kt;
  dKr.noalias() -= W * Kr;
  full.topRows<3>().noalias() = R1T * dKt;
  full.bottomRows<3>().noalias() = R1T * dKr;
  select_rows(full, select, adot_out);
}

// d(A_c^T mu_c)/dq at fixed mu_c, added into T (n x n). With g = R1 mu (mu scattered on the selected components:
// g_t its translation half, g_r its rotation half, world axes) the rows' generalized force is
// (J2_O - J1_O)^T Phi, Phi = (g_t, p2 x g_t + g_r) (g_t acts at p2; J_i the frames' joints' world Jacobians at the
// origin). Its derivative: (dJ2_O - dJ1_O)^T at fixed Phi [force_jacobian_dq] + (J2_O - J1_O)^T dPhi, with
// dg = -[g]x J1_w (R1's rotation) and d(p2 x g_t) = -[g_t]x J2_v + [p2]x dg_t. f's J1, J2: the frames'
// LOCAL_WORLD_ALIGNED Jacobians gathered on `cols` (the closure's columns); Jworld: CRBA's data.J.
template <class JM>
void closure_force_dq(const pin::Model& model, const JM& Jworld, pin::JointIndex jid1, pin::JointIndex jid2,
                      const ClosureFrames& f, const std::vector<int>& select, const Eigen::Ref<const VectorXd>& mu,
                      const std::vector<int>& cols, MatrixXd& block, MatrixXd& T) {
  const Matrix6x &J1 = *f.J1, &J2 = *f.J2;
  Vector6d m6 = Vector6d::Zero();
  for (size_t r = 0; r < select.size(); ++r) m6[select[r]] += mu[static_cast<Eigen::Index>(r)];
  const Vector3d gt = f.R1 * m6.head<3>(), gr = f.R1 * m6.tail<3>();
  Vector6d phi;
  phi << gt, f.p2.cross(gt) + gr;
  const size_t common = common_support(model, jid1, jid2);  // (their pairs there cancel)
  force_jacobian_dq(model, Jworld, jid2, phi, 1.0, T, common);
  force_jacobian_dq(model, Jworld, jid1, phi, -1.0, T, common);
  const Eigen::Index nc = J1.cols();
  Matrix6xB dJ(6, nc), dphi(6, nc);  // J2_O - J1_O (v_O = v_p + p x w) and dPhi
  dJ.topRows<3>() = J2.topRows<3>() - J1.topRows<3>();
  dJ.topRows<3>().noalias() += skew3(f.p2) * J2.bottomRows<3>();
  dJ.topRows<3>().noalias() -= skew3(f.p1) * J1.bottomRows<3>();
  dJ.bottomRows<3>() = J2.bottomRows<3>() - J1.bottomRows<3>();
  dphi.topRows<3>().noalias() = -skew3(gt) * J1.bottomRows<3>();
  dphi.bottomRows<3>().noalias() = -skew3(gr) * J1.bottomRows<3>();
  dphi.bottomRows<3>().noalias() -= skew3(gt) * J2.topRows<3>();
  dphi.bottomRows<3>().noalias() += skew3(f.p2) * dphi.topRows<3>();
  block.noalias() = dJ.transpose().lazyProduct(dphi);  // (6-deep: coefficient-wise)
  for (size_t a = 0; a < cols.size(); ++a)
    for (size_t b = 0; b < cols.size(); ++b) T(cols[a], cols[b]) += block(a, b);
}

}  // namespace derivs
}  // namespace robotdyn

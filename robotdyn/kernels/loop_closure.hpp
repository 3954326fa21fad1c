// robotdyn/kernels/loop_closure.hpp: a loop closure between two frames on different branches, twin of
// robotdyn/constraints/loop_closure.py (LoopClosure). With d = p2 - p1 (world), frame 1's rotation R1 and
// LOCAL_WORLD_ALIGNED Jacobians J_i, the selected components (x y z rx ry rz, in frame 1's axes) of
//
//   translation rows  R1^T (J2_v - J1_v + [d]_x J1_w) v        residual R1^T d
//   rotation rows     R1^T (J2_w - J1_w) v                     residual log(R1^T R2)
//   drift             R1^T (kdot - w1 x k) for k = (ddot + d x w1) and (w2 - w1), the classical accelerations
//                     at zero joint acceleration standing for kdot (LoopClosure.drift: d/dt R1^T x =
//                     R1^T (xdot - w1 x x))
// All rows are holonomic.
#pragma once

#include "common.hpp"

#include <vector>

namespace robotdyn {
namespace kernels {

struct Closure {
  int f1, f2;               // indices into the Evaluator's frames
  std::vector<int> select;  // components 0..5 (x y z rx ry rz) in frame 1's axes
};

// The closure's rows into A and residual from `row` on (LoopClosure.jacobian, .residual): M1, M2 the frames'
// placements, J1, J2 their LOCAL_WORLD_ALIGNED Jacobians; Jrel (6, nv) and K3 (3, nv) are work buffers. Returns the
// next row.
inline int closure_rows(const Closure& c, const pin::SE3& M1, const pin::SE3& M2, const Matrix6x& J1,
                        const Matrix6x& J2, int nv, int row, MatrixXd& Jrel, Eigen::Matrix<double, 3, Eigen::Dynamic>& K3,
                        MatrixXd& A, VectorXd& residual) {
  const Matrix3d R1T = M1.rotation().transpose();
  const Vector3d dp = M2.translation() - M1.translation();
  // only the halves (translation, rotation) that some selected component reads: a ball joint's closure (x y z)
  // computes no rotation rows and no log3 (each entry of the others the same operations as before: the same bits)
  bool translation = false, rotation = false;
  for (int s : c.select) (s < 3 ? translation : rotation) = true;
  Jrel.resize(6, nv);  // relative velocity in frame 1's axes (LoopClosure.jacobian)
  Vector3d e_pos = Vector3d::Zero(), e_rot = Vector3d::Zero();
  if (translation) {
    K3 = J2.topRows<3>() - J1.topRows<3>();
    K3.noalias() += skew(dp).lazyProduct(J1.bottomRows<3>());
    Jrel.topRows<3>().noalias() = R1T.lazyProduct(K3);
    e_pos = R1T * dp;
  }
  if (rotation) {
    K3 = J2.bottomRows<3>() - J1.bottomRows<3>();
    Jrel.bottomRows<3>().noalias() = R1T.lazyProduct(K3);
    e_rot = pin::log3(Matrix3d(R1T * M2.rotation()));
  }
  for (size_t r = 0; r < c.select.size(); ++r) {
    const int s = c.select[r];
    A.row(row + r) = Jrel.row(s);
    residual[row + r] = s < 3 ? e_pos[s] : e_rot[s - 3];
  }
  return row + static_cast<int>(c.select.size());
}

// The closure's drift into drift from `row` on (LoopClosure.drift), after an RNEA pass at (q, v, 0); fid1, fid2 the
// Pinocchio frames. Returns the next row.
inline int closure_drift(const Closure& c, const pin::Model& model, const pin::Data& data, int fid1, int fid2, int row,
                         VectorXd& drift) {
  const pin::Motion V1 = pin::getFrameVelocity(model, data, fid1, pin::LOCAL_WORLD_ALIGNED);
  const pin::Motion V2 = pin::getFrameVelocity(model, data, fid2, pin::LOCAL_WORLD_ALIGNED);
  const pin::Motion a1 = classical_acceleration(model, data, fid1, V1);
  const pin::Motion a2 = classical_acceleration(model, data, fid2, V2);
  const Vector3d d = data.oMf[fid2].translation() - data.oMf[fid1].translation();
  const Vector3d w1 = V1.angular();
  const Vector3d ddot = V2.linear() - V1.linear();
  const Vector3d kt = ddot + d.cross(w1);
  const Vector3d dkt = a2.linear() - a1.linear() + ddot.cross(w1) + d.cross(a1.angular());
  const Vector3d kr = V2.angular() - w1;
  const Vector3d dkr = a2.angular() - a1.angular();
  const Matrix3d R1T = data.oMf[fid1].rotation().transpose();
  const Vector3d et = R1T * (dkt - w1.cross(kt)), er = R1T * (dkr - w1.cross(kr));
  for (size_t r = 0; r < c.select.size(); ++r) {
    const int s = c.select[r];
    drift[row + r] = s < 3 ? et[s] : er[s - 3];
  }
  return row + static_cast<int>(c.select.size());
}

}  // namespace kernels
}  // namespace robotdyn

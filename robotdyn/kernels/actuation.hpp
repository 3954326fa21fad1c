// robotdyn/kernels/actuation.hpp: how motor torques enter the equations of motion, twin of
// robotdyn/reduction/actuation.py (Motor, actuation_matrix). A motor on a one-dof joint with world axis a acts on
// the joint's child and reacts on a body (by default the joint's parent); by virtual power its column is
//
//   B_j = (J_w,child - J_w,reaction)^T a      (revolute; a prismatic joint's column is its axis likewise)
//
// and the default reaction (the parent) gives the unit column e_index.
#pragma once

#include "common.hpp"

#include <vector>

namespace robotdyn {
namespace kernels {

struct Motor {
  int index;     // velocity index of the driven joint
  int joint;     // joint id
  int reaction;  // index into the Evaluator's frames, -1: the joint's parent (a unit column)
};

// B (nv, motors) after CRBA in the WORLD convention (data.J: the world joint Jacobians), Jf the frames'
// LOCAL_WORLD_ALIGNED Jacobians.
inline void motor_columns(const std::vector<Motor>& motors, const pin::Model& model, const pin::Data& data,
                          const std::vector<Matrix6x>& Jf, int nv, MatrixXd& B) {
  B.setZero(nv, motors.size());
  for (size_t j = 0; j < motors.size(); ++j) {
    const Motor& mo = motors[j];
    if (mo.reaction < 0) {
      B(mo.index, j) = 1.0;
      continue;
    }
    // the joint's angular Jacobian is CRBA's world one (data.J) on its supporting joints' columns (an angular
    // velocity does not depend on the reference point), so no Jacobian of the joint is assembled; a prismatic
    // joint's column is its axis in either convention
    const Vector3d ang = data.J.col(mo.index).tail<3>();
    const Vector3d axis = ang.squaredNorm() > 0.25 ? ang : Vector3d(data.J.col(mo.index).head<3>());
    B.col(j).noalias() = Jf[mo.reaction].bottomRows<3>().transpose() * axis;  // then negated in place: the same
    B.col(j) = -B.col(j);  // numbers as -(J^T axis), without the temporary (a heap allocation) that expression made
    for (const pin::JointIndex s : model.supports[mo.joint]) {
      if (s == 0) continue;
      const int c0 = model.joints[s].idx_v();
      for (int c = c0; c < c0 + model.joints[s].nv(); ++c) B(c, j) += data.J.col(c).tail<3>().dot(axis);
    }
  }
}

}  // namespace kernels
}  // namespace robotdyn

// robotdyn/kernels/joint_springs.hpp: springs and dampers on joints, twin of robotdyn/reduction/joint_springs.py
// (SpringForce; summed as robotdyn/contact/applied_forces.py does), in its order of operations. A spring on the
// one-coordinate joint j (velocity index j, natural coordinates: q and v share it) applies the generalised force
//   Q_j = -k (q_j - q_j0) - c qdot_j                      [N or N m]
// stores 1/2 k (q_j - q_j0)^2 [J] and its damper does the power -c qdot_j^2 [W] (<= 0).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace robotdyn {
namespace kernels {

struct JointSpring {
  int index;         // the joint's coordinate in q and v
  double stiffness;  // k [N/m or N m/rad], >= 0
  double damping;    // c [N s/m or N m s/rad], >= 0
  double rest;       // q_j0 [m or rad]
};

// One spring's force Q_j = -k (q_j - q_j0) - c qdot_j (SpringForce.force) [N or N m].
inline double joint_spring_force(const JointSpring& s, const Eigen::Ref<const Eigen::VectorXd>& q,
                                 const Eigen::Ref<const Eigen::VectorXd>& v) {
  return -s.stiffness * (q[s.index] - s.rest) - s.damping * v[s.index];
}

// Q += each spring's force (SpringForce.force); returns the dampers' power (sum of SpringForce.damper_power) [W].
inline double add_joint_springs(const std::vector<JointSpring>& springs, const Eigen::Ref<const Eigen::VectorXd>& q,
                                const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> Q) {
  double power = 0.0;
  for (const JointSpring& s : springs) {
    Q[s.index] += joint_spring_force(s, q, v);
    power += -s.damping * (v[s.index] * v[s.index]);
  }
  return power;
}

// The springs' stored energy (sum of SpringForce.potential) [J].
inline double joint_springs_potential(const std::vector<JointSpring>& springs,
                                      const Eigen::Ref<const Eigen::VectorXd>& q) {
  double out = 0.0;
  for (const JointSpring& s : springs) {
    const double d = q[s.index] - s.rest;
    out += 0.5 * s.stiffness * d * d;
  }
  return out;
}

}  // namespace kernels
}  // namespace robotdyn

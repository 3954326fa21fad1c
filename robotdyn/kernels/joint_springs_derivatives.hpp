// robotdyn/kernels/joint_springs_derivatives.hpp: the joint springs' and dampers' terms of the compiled derivative
// set and of the compiled constraint forces, twin of robotdyn/reduction/joint_springs.py (spring_terms) as
// robotdyn/reduction/dynamics_derivatives.py uses it. A spring on coordinate j applies Q_j = -k (q_j - q_j0) - c qdot_j
// (kernels/joint_springs.hpp), so Q is joint-diagonal: dQ/dq = -k and dQ/dv = -c at (j, j), zero elsewhere. The
// derivatives' residual is rho = RNEA(q, v, a) - B tau - Q with the reduced solve M_r nudot = B_r tau - h_r + S^T Q;
// the constraint forces solve A^T lambda = e = RNEA(q, v, a) - B tau - Q (robotdyn/contact/contact_forces.py).
#pragma once

#include <Eigen/Core>

#include <vector>

#include "joint_springs.hpp"

namespace robotdyn {
namespace kernels {

// The tree's inverse dynamics and its derivatives less the springs' (dynamics_derivatives: rho's RNEA - Q,
// dtau_dq -= dQ/dq, dtau_dv -= dQ/dv): tau -= Q(q, v), dtau_dq(j, j) += k, dtau_dv(j, j) += c.
inline void subtract_joint_springs_derivatives(const std::vector<JointSpring>& springs,
                                               const Eigen::Ref<const Eigen::VectorXd>& q,
                                               const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> tau,
                                               Eigen::Ref<Eigen::MatrixXd> dtau_dq, Eigen::Ref<Eigen::MatrixXd> dtau_dv) {
  for (const JointSpring& s : springs) {
    tau[s.index] -= joint_spring_force(s, q, v);
    dtau_dq(s.index, s.index) += s.stiffness;
    dtau_dv(s.index, s.index) += s.damping;
  }
}

// f += S^T Q(q, v) (the reduced equations' applied term; S (n, k), f (k)).
inline void add_reduced_joint_springs(const std::vector<JointSpring>& springs,
                                      const Eigen::Ref<const Eigen::VectorXd>& q,
                                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::MatrixXd& S,
                                      Eigen::Ref<Eigen::VectorXd> f) {
  for (const JointSpring& s : springs)
    f.noalias() += joint_spring_force(s, q, v) * S.row(s.index).transpose();
}

// e -= Q(q, v) (the constraint forces' right-hand side).
inline void subtract_joint_springs(const std::vector<JointSpring>& springs, const Eigen::Ref<const Eigen::VectorXd>& q,
                                   const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> e) {
  for (const JointSpring& s : springs) e[s.index] -= joint_spring_force(s, q, v);
}

}  // namespace kernels
}  // namespace robotdyn

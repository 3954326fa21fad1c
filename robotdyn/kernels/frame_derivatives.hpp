// Frame velocities and accelerations with their configuration derivatives at one state (q, x).
// Python twin: robotdyn/constraints/row_derivatives.py (FramePass, _rot_dq, _cross_d).
//
// One computeForwardKinematicsDerivatives(q, x, 0) on a Pinocchio data of its own; per frame, Pinocchio's
// getFrameVelocityDerivatives / getFrameAccelerationDerivatives in LOCAL axes, rotated to world axes here (as in
// Python: Pinocchio's LOCAL_WORLD_ALIGNED velocity derivative is not the derivative of the LOCAL_WORLD_ALIGNED
// Jacobian times a fixed velocity, which is what the constraint rows need). Rotations and world Jacobians come
// from the evaluator's configuration pass (its data and frame Jacobians at q).
#pragma once

#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/kinematics-derivatives.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/frames-derivatives.hpp>

#include <vector>

namespace robotdyn {
namespace derivs {

namespace pin = pinocchio;
using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;
using Matrix6x = Eigen::Matrix<double, 6, Eigen::Dynamic>;
using Matrix3x = Eigen::Matrix<double, 3, Eigen::Dynamic>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

inline Matrix3d skew3(const Vector3d& x) {
  Matrix3d m;
  m << 0.0, -x[2], x[1], x[2], 0.0, -x[0], -x[1], x[0], 0.0;
  return m;
}

// d(R(q) y)/dq at fixed y for a frame rotation R with world angular Jacobian Jw: -[R y]x Jw (_rot_dq)
inline Matrix3x rot_dq(const Vector3d& Ry, const Matrix3x& Jw) { return -skew3(Ry) * Jw; }

// derivative of x cross y from those of x and y (3 x n each) (_cross_d)
inline Matrix3x cross_d(const Vector3d& x, const Matrix3x& dx, const Vector3d& y, const Matrix3x& dy) {
  return -skew3(y) * dx + skew3(x) * dy;
}

// One pass (FramePass): the kinematics derivatives at (q, x, 0) and, per frame, cached world-axes results.
struct FramePass {
  pin::Data data;
  VectorXd x;
  std::vector<char> has_vel, has_acc;
  std::vector<Vector6d> V, Acc;
  std::vector<Matrix6x> dV, dAcc;
  Matrix6x t1_, t2_, t3_, t4_;  // work

  void run(const pin::Model& model, const VectorXd& q, const VectorXd& x_, size_t nframes) {
    if (data.oMi.size() != static_cast<size_t>(model.njoints) || data.oMf.size() != model.frames.size())
      data = pin::Data(model);
    x = x_;
    pin::computeForwardKinematicsDerivatives(model, data, q, x, VectorXd::Zero(model.nv));
    has_vel.assign(model.frames.size(), 0);
    has_acc.assign(model.frames.size(), 0);
    if (V.size() != model.frames.size()) {
      V.resize(model.frames.size());
      Acc.resize(model.frames.size());
      dV.resize(model.frames.size());
      dAcc.resize(model.frames.size());
    }
    (void)nframes;
  }

  // world-axes (LOCAL_WORLD_ALIGNED) frame velocity V = J x and dV/dq at fixed x (FramePass.velocity);
  // R: the frame's rotation at q, Jw: its world angular Jacobian (3 x n)
  void velocity(const pin::Model& model, pin::FrameIndex fid, const Matrix3d& R, const Matrix3x& Jw) {
    if (has_vel[fid]) return;
    const int n = model.nv;
    t1_.setZero(6, n);
    t2_.setZero(6, n);
    pin::getFrameVelocityDerivatives(model, data, fid, pin::LOCAL, t1_, t2_);
    const pin::Motion local = pin::getFrameVelocity(model, data, fid, pin::LOCAL);
    const Vector3d lin = R * local.linear(), ang = R * local.angular();
    V[fid] << lin, ang;
    dV[fid].resize(6, n);
    dV[fid].topRows<3>() = R * t1_.topRows<3>() + rot_dq(lin, Jw);
    dV[fid].bottomRows<3>() = R * t1_.bottomRows<3>() + rot_dq(ang, Jw);
    has_vel[fid] = 1;
  }

  // world-axes classical acceleration at vdot = 0 and its q-derivative at fixed x (FramePass.acceleration)
  void acceleration(const pin::Model& model, pin::FrameIndex fid, const Matrix3d& R, const Matrix3x& Jw) {
    if (has_acc[fid]) return;
    const int n = model.nv;
    t1_.setZero(6, n);  // v_partial_dq (LOCAL)
    t2_.setZero(6, n);  // a_partial_dq
    t3_.setZero(6, n);  // a_partial_dv
    t4_.setZero(6, n);  // a_partial_da
    pin::getFrameAccelerationDerivatives(model, data, fid, pin::LOCAL, t1_, t2_, t3_, t4_);
    const pin::Motion vl = pin::getFrameVelocity(model, data, fid, pin::LOCAL);
    const pin::Motion al = pin::getFrameAcceleration(model, data, fid, pin::LOCAL);
    const Vector3d v = vl.linear(), w = vl.angular();
    const Vector3d lin = al.linear() + w.cross(v);
    const Matrix3x lin_dq = t2_.topRows<3>() + cross_d(w, t1_.bottomRows<3>(), v, t1_.topRows<3>());
    const Vector3d Rlin = R * lin, Rang = R * al.angular();
    Acc[fid] << Rlin, Rang;
    dAcc[fid].resize(6, n);
    dAcc[fid].topRows<3>() = R * lin_dq + rot_dq(Rlin, Jw);
    dAcc[fid].bottomRows<3>() = R * t2_.bottomRows<3>() + rot_dq(Rang, Jw);
    has_acc[fid] = 1;
  }

  // the frame Jacobian's time variation along x in LOCAL_WORLD_ALIGNED (KinematicState.frame's dJ): the forward
  // kinematics derivatives leave data.dJ as computeJointJacobiansTimeVariation does
  void jacobian_dot(const pin::Model& model, pin::FrameIndex fid, Matrix6x& dJ) {
    dJ.setZero(6, model.nv);
    pin::getFrameJacobianTimeVariation(model, data, fid, pin::LOCAL_WORLD_ALIGNED, dJ);
  }

  // world angular velocity of a joint's body and its q-derivative at fixed x (the motors' reaction terms)
  void joint_angular(const pin::Model& model, pin::JointIndex jid, const Matrix3d& R, const Matrix3x& Jw,
                     Vector3d& w, Matrix3x& dw) {
    const int n = model.nv;
    t1_.setZero(6, n);
    t2_.setZero(6, n);
    pin::getJointVelocityDerivatives(model, data, jid, pin::LOCAL, t1_, t2_);
    w = R * data.v[jid].angular();
    dw = R * t1_.bottomRows<3>() + rot_dq(w, Jw);
  }
};

}  // namespace derivs
}  // namespace robotdyn

// robotdyn/kernels/frame_derivatives.hpp: frame velocities and accelerations with their configuration derivatives
// at one state (q, x), twin of robotdyn/constraints/row_derivatives.py (FramePass, _rot_dq, _cross_d).
//
// A pass with accelerations runs computeForwardKinematicsDerivatives on a Pinocchio data of its own, or (run_on, the
// derivative set's pass at v) takes that algorithm's forward-step fields from the evaluator's bias pass at v, and
// takes, per joint, the WORLD configuration derivatives of the joint's velocity and acceleration that Pinocchio's
// getJointVelocityDerivatives / getJointAccelerationDerivatives assemble, by their own steps (motionSet::motionAction
// over the joint's support) without the outputs those functions also fill and the pass does not read, carried to
// each frame's origin (FramePass below; the compiled derivatives equal the Python twin's, which calls Pinocchio's
// functions themselves, to 1e-10 in tests/test_compiled_derivatives*.py). A velocity-only pass (run_velocities) reuses the evaluator's configuration pass instead
// of recomputing the placements: the world joint velocities ov_i = ov_parent + J_i x_i from the world Jacobian
// columns J (CRBA's data.J) and, per column c of a joint on the support of j, the same WORLD derivative that
// getJointVelocityDerivatives assembles from computeForwardKinematicsDerivatives' dVdq:
// d ov_j / dq_c = J_c x (ov_j - ov_parent(c)) (motion cross product; Pinocchio's right-perturbation tangent). The Python twin rotates the LOCAL frame derivatives to
// world axes instead; both are the derivatives of the LOCAL_WORLD_ALIGNED J(q) x at fixed x and of its classical
// acceleration, which is what the constraint rows need. Placements and world Jacobians come from the evaluator's
// configuration pass (its data and frame Jacobians at q).
#pragma once

#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/kinematics-derivatives.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/frames-derivatives.hpp>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace robotdyn {
namespace derivs {

namespace pin = pinocchio;
using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;
using Matrix6x = Eigen::Matrix<double, 6, Eigen::Dynamic>;
// 3 x n blocks of the derivative formulas, on the stack (no allocation per temporary) up to kMaxNv coordinates;
// a larger model takes the Python path (ReducedDerivatives::run refuses it)
constexpr int kMaxNv = 128;
using Matrix3x = Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxNv>;
using RowX = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxNv>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6xB = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxNv>;  // 6 x n work block on the stack

inline Matrix3d skew3(const Vector3d& x) {
  Matrix3d m;
  m << 0.0, -x[2], x[1], x[2], 0.0, -x[0], -x[1], x[0], 0.0;
  return m;
}

// out = the columns `cols` of a block (rows x cols.size()), and back: the columns of a block into `cols` of out
// (the rows' zero blocks: ReducedDerivatives' compact columns)
template <class M, class O>
void gather_cols(const M& full, const std::vector<int>& cols, O& out) {
  out.resize(full.rows(), static_cast<Eigen::Index>(cols.size()));
  for (size_t j = 0; j < cols.size(); ++j) out.col(static_cast<Eigen::Index>(j)) = full.col(cols[j]);
}
template <class Out>
void scatter_cols(const MatrixXd& part, const std::vector<int>& cols, Out&& out) {
  for (size_t j = 0; j < cols.size(); ++j) out.col(cols[j]) = part.col(static_cast<Eigen::Index>(j));
}

// R^T ([y]x Jw + dy) into out (3 x n), the products written in place (the closure rows' last step)
template <class JW, class Out>
void rotate_skew_add(const Matrix3d& RT, const Vector3d& y, const JW& Jw, const Matrix3x& dy, Out&& out) {
  Matrix3x t = dy;
  t.noalias() += skew3(y) * Jw;
  out.noalias() = RT * t;
}

// d(R(q) y)/dq at fixed y for a frame rotation R with world angular Jacobian Jw: -[R y]x Jw (_rot_dq)
inline Matrix3x rot_dq(const Vector3d& Ry, const Matrix3x& Jw) { return -skew3(Ry) * Jw; }

// derivative of x cross y from those of x and y (3 x n each) (_cross_d): -[y]x dx + [x]x dy, column by column as
// the two cross products dx_c x y + x x dy_c (the skew-matrix products' own sums in their order, their zero terms
// left out: the same numbers, without building the 3 x 3 matrices or a product kernel's set-up)
inline Matrix3x cross_d(const Vector3d& x, const Matrix3x& dx, const Vector3d& y, const Matrix3x& dy) {
  Matrix3x out(3, dx.cols());
  for (Eigen::Index c = 0; c < dx.cols(); ++c) {
    const double a0 = dx(0, c), a1 = dx(1, c), a2 = dx(2, c), b0 = dy(0, c), b1 = dy(1, c), b2 = dy(2, c);
    out(0, c) = (y[2] * a1 - y[1] * a2) + (x[1] * b2 - x[2] * b1);
    out(1, c) = (y[0] * a2 - y[2] * a0) + (x[2] * b0 - x[0] * b2);
    out(2, c) = (y[1] * a0 - y[0] * a1) + (x[0] * b1 - x[1] * b0);
  }
  return out;
}

// T += sign d(J^T phi)/dq at fixed phi: the generalized force of a spatial force phi = (f, m) fixed in the world
// (force f, moment m about the world origin, world axes) on the body of joint jid, J its world Jacobian columns at
// the origin (CRBA's data.J, on jid's support). Pinocchio's tangent: d J_j / dq_c = J_c x J_j (motion cross product)
// where c's joint supports j's (itself included), else zero (getKinematicHessian's WORLD rule, the one
// getJointVelocityDerivatives sums); so dQ_j/dq_c = (J_c x J_j) . phi = J_j . (f x w_c, f x v_c + m x w_c) with
// J_c = (v_c, w_c). The constraint forces' derivative at fixed multipliers (ReducedDerivatives::force_dq), one pass
// over the support's column pairs instead of one frame velocity pass per column of S. `from` > 0: only the pairs
// whose later joint is at position >= from in jid's support. The same phi with opposite signs on two joints gives
// the same terms on the pairs of their common support (common_support), which cancel: a closure's two frames and a
// motor's body and reaction frame take both passes from there.
template <class JM, class Out>
void force_jacobian_dq(const pin::Model& model, const JM& J, pin::JointIndex jid, const Vector6d& phi, double sign,
                       Out&& T, size_t from = 0) {
  const Vector3d f = phi.head<3>(), m = phi.tail<3>();
  const auto& sup = model.supports[jid];
  for (size_t a = 0; a < sup.size(); ++a) {
    const pin::JointIndex s1 = sup[a];
    if (s1 == 0) continue;
    const int c0 = model.idx_vs[s1], c1 = c0 + model.nvs[s1];
    for (int c = c0; c < c1; ++c) {
      const Vector3d vc = J.col(c).template head<3>(), wc = J.col(c).template tail<3>();
      Vector6d psi;
      psi << sign * f.cross(wc), sign * (f.cross(vc) + m.cross(wc));
      for (size_t b = std::max(a, from); b < sup.size(); ++b) {
        const pin::JointIndex s2 = sup[b];
        const int j0 = model.idx_vs[s2], j1 = j0 + model.nvs[s2];
        for (int j = j0; j < j1; ++j) T(j, c) += J.col(j).dot(psi);
      }
    }
  }
}

// the number of leading entries two joints' supports share (their common ancestors, the universe first)
inline size_t common_support(const pin::Model& model, pin::JointIndex j1, pin::JointIndex j2) {
  const auto &s1 = model.supports[j1], &s2 = model.supports[j2];
  size_t m = 0;
  while (m < s1.size() && m < s2.size() && s1[m] == s2[m]) ++m;
  return m;
}

// One pass (FramePass): the kinematics derivatives at (q, x) (with accelerations: at (q, x, 0)) and, per frame,
// cached world-axes results. Pinocchio's joint derivatives are taken in WORLD (the spatial velocity and
// acceleration at the world origin, whose q-derivatives at fixed x are exact there) and carried to the frame
// origin p: v_p = v_O + w x p, a_p = a_O + alpha x p + w x v_p (classical acceleration), differentiated with
// dp/dq = J_p (the frame's LOCAL_WORLD_ALIGNED Jacobian's linear rows). The Python twin rotates the LOCAL
// derivatives instead; both give the derivative of the LOCAL_WORLD_ALIGNED J(q) x at fixed x (and of its
// classical acceleration), and the tests hold them equal to 1e-10.
struct FramePass {
  pin::Data data;
  VectorXd x;
  bool accelerations = false;
  const pin::Data* base = nullptr;  // velocity-only pass: the evaluator's data at q (oMi, world columns J)
  std::vector<pin::Motion> ov;      // velocity-only pass: world joint velocities at x
  std::vector<char> has_vel, has_acc, has_jv, has_ja;
  std::vector<Vector6d> V, Acc;
  std::vector<Matrix6x> dV, dAcc, jdV, jdA;
  VectorXd zero_;  // the acceleration of a pass with accelerations (zero)

  void run(const pin::Model& model, const VectorXd& q, const VectorXd& x_, bool with_accelerations) {
    if (data.oMi.size() != static_cast<size_t>(model.njoints) || data.oMf.size() != model.frames.size())
      data = pin::Data(model);
    x = x_;
    accelerations = with_accelerations;
    base = nullptr;
    if (accelerations) {
      zero_.setZero(model.nv);
      pin::computeForwardKinematicsDerivatives(model, data, q, x, zero_);
    } else
      pin::computeForwardKinematicsDerivatives(model, data, q, x);  // velocities only (first order)
    reset(model);
  }

  // a velocity-only pass at x on the evaluator's configuration pass `at_q` (placements and CRBA's world Jacobian
  // columns at q, which must outlive the pass's use): no Pinocchio pass of its own
  template <class X>
  void run_velocities(const pin::Model& model, const pin::Data& at_q, const Eigen::MatrixBase<X>& x_) {
    x = x_;
    accelerations = false;
    base = &at_q;
    ov.resize(static_cast<size_t>(model.njoints));
    ov[0].setZero();
    for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model.njoints); ++i) {
      const int c0 = model.idx_vs[i], nvi = model.nvs[i];
      ov[i] = ov[model.parents[i]];
      ov[i].toVector().noalias() += at_q.J.middleCols(c0, nvi) * x.segment(c0, nvi);
    }
    reset(model);
  }

  // a pass with accelerations at x = v on the evaluator's state `at_q` after its bias pass at v (configure(q),
  // dynamics(nu): placements oMi and world Jacobian columns J at q, the joints' local velocities v and accelerations
  // a at zero joint acceleration, RNEA's forward sweep, operation for operation computeForwardKinematicsDerivatives'
  // own at (q, v, 0)): the fields of that algorithm's forward step the pass reads (oMi, J, v, a, ov = oMi v, oa =
  // oMi a, dJ = ov x J, the same operations) without recomputing the placements, nor its second-order outputs (dVdq,
  // dAdq, dAdv), which nothing here reads (the frames' derivatives are assembled from ov, oa, J and dJ below)
  template <class X>
  void run_on(const pin::Model& model, const pin::Data& at_q, const Eigen::MatrixBase<X>& x_) {
    if (data.oMi.size() != static_cast<size_t>(model.njoints) || data.oMf.size() != model.frames.size())
      data = pin::Data(model);
    x = x_;
    accelerations = true;
    base = nullptr;
    data.J = at_q.J;
    data.v[0].setZero();
    data.a[0].setZero();
    data.ov[0].setZero();
    data.oa[0].setZero();
    for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model.njoints); ++i) {
      data.oMi[i] = at_q.oMi[i];
      data.v[i] = at_q.v[i];
      data.a[i] = at_q.a[i];
      data.ov[i] = data.oMi[i].act(data.v[i]);
      data.oa[i] = data.oMi[i].act(data.a[i]);
      const int c0 = model.idx_vs[i], nvi = model.nvs[i];
      auto dJcols = data.dJ.middleCols(c0, nvi);
      pin::motionSet::motionAction(data.ov[i], data.J.middleCols(c0, nvi), dJcols);
    }
    reset(model);
  }

  // a joint's world velocity at x (spatial, at the world origin)
  const pin::Motion& joint_velocity(pin::JointIndex jid) const { return base ? ov[jid] : data.ov[jid]; }

  void reset(const pin::Model& model) {
    const size_t nf = model.frames.size(), nj = static_cast<size_t>(model.njoints);
    has_vel.assign(nf, 0);
    has_acc.assign(nf, 0);
    has_jv.assign(nj, 0);
    has_ja.assign(nj, 0);
    if (V.size() != nf) {
      V.resize(nf);
      Acc.resize(nf);
      dV.resize(nf);
      dAcc.resize(nf);
    }
    if (jdV.size() != nj) {
      jdV.resize(nj);
      jdA.resize(nj);
    }
  }

  // a per-joint or per-frame 6 x n result zeroed only when first sized: each is written on its joint's supporting
  // columns only (the same columns at every state: the model's supports are fixed), so its other columns stay the
  // zeros of that first call (no 6 x n clearing per frame and pass)
  static void zero_once(Matrix6x& m, int nv) {
    if (m.cols() != nv) m.setZero(6, nv);
  }

  // d(ov)/dq of a joint at fixed x, WORLD (6 x n)
  const Matrix6x& joint_velocity_dq(const pin::Model& model, pin::JointIndex jid) {
    if (!has_jv[jid]) {
      zero_once(jdV[jid], model.nv);
      if (base) {  // d ov_j / dq_c = J_c x (ov_j - ov_parent(c)) on the support of j (header)
        for (const pin::JointIndex s : model.supports[jid]) {
          if (s == 0) continue;
          const pin::Motion rel = ov[jid] - ov[model.parents[s]];
          const int c0 = model.idx_vs[s];
          for (int c = c0; c < c0 + model.nvs[s]; ++c) {
            const auto Jc = base->J.col(c);
            const Vector3d lin = Jc.template head<3>(), ang = Jc.template tail<3>();
            jdV[jid].col(c).template head<3>() = ang.cross(rel.linear()) + lin.cross(rel.angular());
            jdV[jid].col(c).template tail<3>() = ang.cross(rel.angular());
          }
        }
      } else {  // getJointVelocityDerivatives(WORLD)'s v_partial_dq, its own steps (not its v_partial_dv = J)
        const pin::Motion& vlast = data.ov[jid];
        for (const pin::JointIndex s : model.supports[jid]) {
          if (s == 0) continue;
          const pin::JointIndex parent = model.parents[s];
          const int c0 = model.idx_vs[s], nvs = model.nvs[s];
          const pin::Motion vtmp = parent > 0 ? pin::Motion(data.ov[parent] - vlast) : pin::Motion(-vlast);
          auto cols = jdV[jid].middleCols(c0, nvs);
          pin::motionSet::motionAction(vtmp, data.J.middleCols(c0, nvs), cols);
        }
      }
      has_jv[jid] = 1;
    }
    return jdV[jid];
  }

  // d(oa)/dq of a joint at fixed (x, vdot = 0), WORLD (6 x n): the a_partial_dq of Pinocchio's
  // getJointAccelerationDerivatives(WORLD) on this pass's computeForwardKinematicsDerivatives, its own steps on the
  // support of jid (motionSet::motionAction of (oa_parent - oa_j) on the joint's columns J, plus that of
  // (ov_parent - ov_j) on dJ), without the three outputs it also fills and the pass does not read. `out` is written
  // on jid's supporting columns only: its other columns must be zero (zero_once on a buffer kept for jid)
  void joint_acceleration_dq(const pin::Model& model, pin::JointIndex jid, Matrix6x& out) {
    zero_once(out, model.nv);
    const pin::Motion& vlast = data.ov[jid];
    const pin::Motion& alast = data.oa[jid];
    for (const pin::JointIndex s : model.supports[jid]) {
      if (s == 0) continue;
      const pin::JointIndex parent = model.parents[s];
      const int c0 = model.idx_vs[s], nvs = model.nvs[s];
      auto cols = out.middleCols(c0, nvs);
      const pin::Motion atmp = parent > 0 ? pin::Motion(data.oa[parent] - alast) : pin::Motion(-alast);
      pin::motionSet::motionAction(atmp, data.J.middleCols(c0, nvs), cols);
      if (parent > 0) {
        const pin::Motion vtmp = data.ov[parent] - vlast;
        pin::motionSet::motionAction<pin::ADDTO>(vtmp, data.dJ.middleCols(c0, nvs), cols);
      }
    }
  }

  // f(c) for each column c of a joint's supporting joints (in order): the only columns its world Jacobian and its
  // derivatives can be nonzero in
  template <class F>
  static void for_support_cols(const pin::Model& model, pin::JointIndex jid, F&& f) {
    for (const pin::JointIndex s : model.supports[jid]) {
      if (s == 0) continue;
      const int c0 = model.idx_vs[s], c1 = c0 + model.nvs[s];
      for (int c = c0; c < c1; ++c) f(c);
    }
  }

  // world-axes (LOCAL_WORLD_ALIGNED) frame velocity V = J x and dV/dq at fixed x (FramePass.velocity);
  // oMf: the frame's placement at q, J: its LOCAL_WORLD_ALIGNED Jacobian at q (6 x n)
  void velocity(const pin::Model& model, pin::FrameIndex fid, const pin::SE3& oMf, const Matrix6x& J) {
    if (has_vel[fid]) return;
    const pin::JointIndex jid = model.frames[fid].parentJoint;
    const Matrix6x& jd = joint_velocity_dq(model, jid);
    const pin::Motion& vj = joint_velocity(jid);
    const Vector3d p = oMf.translation(), w = vj.angular();
    const Vector3d vp = vj.linear() + w.cross(p);
    V[fid] << vp, w;
    // jd_lin - [p]x jd_ang + [w]x J_lin, the products written in place, on the supporting joints' columns (jd and J
    // are zero on the others: on a branched tree most of the columns up to the joint's last)
    zero_once(dV[fid], model.nv);
    // ([p]x y = p x y: the skew products' own sums, their zero terms left out)
    for_support_cols(model, jid, [&](int c) {
      Vector3d t = jd.col(c).head<3>();
      t -= p.cross(jd.col(c).tail<3>());
      t += w.cross(J.col(c).head<3>());
      dV[fid].col(c).head<3>() = t;
      dV[fid].col(c).tail<3>() = jd.col(c).tail<3>();
    });
    has_vel[fid] = 1;
  }

  // world-axes classical acceleration at vdot = 0 and its q-derivative at fixed x (FramePass.acceleration)
  void acceleration(const pin::Model& model, pin::FrameIndex fid, const pin::SE3& oMf, const Matrix6x& J) {
    if (has_acc[fid]) return;
    if (!accelerations) throw std::logic_error("frame pass without accelerations");
    velocity(model, fid, oMf, J);
    const pin::JointIndex jid = model.frames[fid].parentJoint;
    if (!has_ja[jid]) {
      joint_acceleration_dq(model, jid, jdA[jid]);
      has_ja[jid] = 1;
    }
    const Matrix6x& ja = jdA[jid];
    const pin::Motion& oa = data.oa[jid];
    const Vector3d p = oMf.translation(), w = data.ov[jid].angular(), al = oa.angular();
    const Vector3d vp = V[fid].head<3>();
    Acc[fid] << oa.linear() + al.cross(p) + w.cross(vp), al;
    // the same sum, products in place, on the supporting joints' columns (the only ones that can be nonzero)
    zero_once(dAcc[fid], model.nv);
    const Matrix6x& dv = dV[fid];
    for_support_cols(model, jid, [&](int c) {  // (cross products for the skew products, as in velocity)
      Vector3d t = ja.col(c).head<3>();
      t -= p.cross(ja.col(c).tail<3>());
      t += al.cross(J.col(c).head<3>());
      t += w.cross(dv.col(c).head<3>());
      t -= vp.cross(dv.col(c).tail<3>());
      dAcc[fid].col(c).head<3>() = t;
      dAcc[fid].col(c).tail<3>() = ja.col(c).tail<3>();
    });
    has_acc[fid] = 1;
  }

  // the frame Jacobian's time variation along x in LOCAL_WORLD_ALIGNED (KinematicState.frame's dJ) on the columns
  // `cols` (sorted; they hold the frame's supporting columns): out = its columns cols (6 x cols.size()), zero off the
  // support. Pinocchio's getFrameJacobianTimeVariation(LOCAL_WORLD_ALIGNED) on the forward kinematics derivatives'
  // data.dJ (as computeJointJacobiansTimeVariation leaves it), its own steps column for column (translateJointJacobian
  // then the frame velocity's term; no mimic joints here), written into the gathered block directly instead of a
  // 6 x n block cleared and gathered
  void jacobian_dot(const pin::Model& model, pin::FrameIndex fid, const std::vector<int>& cols, Matrix6x& out) {
    const pin::Frame& frame = model.frames[fid];
    const pin::JointIndex jid = frame.parentJoint;
    const pin::SE3 oMframe = data.oMi[jid] * frame.placement;
    const Vector3d& p = oMframe.translation();
    const pin::Motion& ov = data.ov[jid];
    out.setZero(6, static_cast<Eigen::Index>(cols.size()));
    size_t at = cols.size();  // the support's columns, last first (the order of Pinocchio's loop), found in cols
    for (int j = model.idx_vs[jid] + model.nvs[jid] - 1; j >= 0; j = data.parents_fromRow[static_cast<size_t>(j)]) {
      while (at > 0 && cols[at - 1] > j) --at;
      if (at == 0 || cols[at - 1] != j) throw std::logic_error("jacobian_dot: a supporting column not in cols");
      const auto v_in = data.dJ.col(j);
      auto v_out = out.col(static_cast<Eigen::Index>(at - 1));
      v_out = v_in;
      v_out.head<3>().noalias() -= p.cross(v_in.tail<3>());
      v_out.head<3>() -= Vector3d(ov.linear() + ov.angular().cross(p)).cross(data.J.col(j).tail<3>());
    }
  }
};

}  // namespace derivs
}  // namespace robotdyn

// robotdyn/kernels/operational_space_derivatives.hpp: derivatives of the reduced forward dynamics with operational-
// space velocities nu = J_o v (operational_space.hpp), twin of robotdyn/reduction/dynamics_derivatives.py (the twist
// parts of _Projection: solve_neg, multiplier, twist_velocity_dq, twist_drift_dq; pieces, Pieces.Aq and
// dynamics_derivatives) for the projection of robotdyn/reduction/operational_space.py, the same formulas in the
// same order. With K = [A_r; J_o] (K S = [0; I], K w = -[gamma_r; Jdot_o v]):
//
//   dS = -K^-1 dK S,  dw = -K^-1 (dK w + d[gamma_r; Jdot_o v]),  dS^T rho = -S^T dK^T mu,  mu = K^-T rho,
//
// where dK enters only as d(K x)/dq at fixed x: the constraint rows' (the <kind>_derivatives.hpp, through
// ReducedDerivatives) and the twist rows' d(J_o x)/dq = the frame velocity's q-derivative at fixed x (LOCAL: Pinocchio's
// getFrameVelocityDerivatives, or FramePass.velocity rotated into the frame's axes; world axes: FramePass.velocity);
// d(Jdot_o v)/dq likewise from the frame's LOCAL spatial acceleration (FramePass.acceleration rotated, the Python
// twin's getFrameAccelerationDerivatives) or its world classical acceleration (FramePass), and
// d(Jdot_o v)/dv = Jdot_o + d(J_o v)/dq.
//
// ProjectedPieces below are the Python `pieces` for either projection (a selection of v through ReducedDerivatives'
// LU of A_d, or K^-1 here): the operational derivatives and the slipping wheels' (sliding_derivatives.hpp) finish
// from them. A selection of v without slipping wheels keeps ReducedDerivatives::run. OperationalDerivatives::run
// takes its multiplier term as one derivative of the constraint and twist forces at fixed mu (force_dq,
// twist_force_dq; twin dynamics_derivatives.twist_force_dq) on two frame passes (at a = S nudot + w, velocity-only,
// and at v: ProjectedPieces::build_at); the slipping wheels' kernel keeps the passes at the columns of S (build).
#pragma once

#include "reduced_dynamics_derivatives.hpp"

#include <pinocchio/algorithm/frames-derivatives.hpp>

namespace robotdyn {
namespace derivs {

// The operational frame: Pinocchio frame id, its placement and LOCAL_WORLD_ALIGNED Jacobian at q, the axes and
// the selected twist components (0..5: vx vy vz wx wy wz).
struct TwistFrame {
  int fid;
  const pin::SE3* oMf;
  const Matrix6x* J;
  bool local;
  const std::vector<int>* select;
};

// d(J_o x)/dq at fixed x = fp.x (k x n) (_Projection.twist_velocity_dq); w1, w2 work. LOCAL on a velocity-only pass
// (FramePass::run_velocities, no Pinocchio data): the frame's world-axes velocity V = (v, w) and dV (FramePass.velocity)
// rotated into its axes, d(R^T y)/dq = R^T ([y]x J_w + dy) (the Python twin's FramePass.velocity inverted); else
// Pinocchio's getFrameVelocityDerivatives(LOCAL) on the pass's data
inline void twist_velocity_dq(const pin::Model& model, FramePass& fp, const TwistFrame& tf, MatrixXd& out,
                              Matrix6x& w1, Matrix6x& w2) {
  const Matrix6x* dV;
  if (tf.local && fp.base) {
    fp.velocity(model, tf.fid, *tf.oMf, *tf.J);
    const Vector6d& V = fp.V[tf.fid];
    const Matrix6x& dVw = fp.dV[tf.fid];
    const Matrix3d RT = tf.oMf->rotation().transpose();
    const auto Jw = tf.J->bottomRows<3>();
    w1.resize(6, model.nv);
    rotate_skew_add(RT, V.head<3>(), Jw, Matrix3x(dVw.topRows<3>()), w1.topRows<3>());
    rotate_skew_add(RT, V.tail<3>(), Jw, Matrix3x(dVw.bottomRows<3>()), w1.bottomRows<3>());
    dV = &w1;
  } else if (tf.local) {
    w1.setZero(6, model.nv);
    w2.setZero(6, model.nv);
    pin::getFrameVelocityDerivatives(model, fp.data, static_cast<pin::FrameIndex>(tf.fid), pin::LOCAL, w1, w2);
    dV = &w1;
  } else {
    fp.velocity(model, tf.fid, *tf.oMf, *tf.J);
    dV = &fp.dV[tf.fid];
  }
  const std::vector<int>& sel = *tf.select;
  out.resize(static_cast<int>(sel.size()), model.nv);
  for (size_t r = 0; r < sel.size(); ++r) out.row(static_cast<int>(r)) = dV->row(sel[r]);
}

// d(Jdot_o v)/dq at fixed v = fp.x (a pass with accelerations) and Jdot_o (k x n each) (_Projection.twist_drift_dq,
// FrameTwist.rows): LOCAL, the body-axes spatial acceleration (Pinocchio's getFrameAccelerationDerivatives(LOCAL)
// a_partial_dq in the Python twin); world axes, the classical acceleration. LOCAL here from the frame's world-axes
// velocity (v_p, w) and classical acceleration (a_p, alpha) with their q-derivatives (FramePass.velocity,
// FramePass.acceleration), like twist_velocity_dq: the body-axes spatial acceleration at zero joint acceleration is
// d/dt (R^T v_p, R^T w) = (R^T (a_p - w x v_p), R^T alpha), and d(R^T y)/dq = R^T ([y]x J_w + dy) (into w2; w3 and
// w4 unused)
inline void twist_drift_dq(const pin::Model& model, FramePass& fp, const TwistFrame& tf, MatrixXd& drift,
                           MatrixXd& Jdot, Matrix6x& w1, Matrix6x& w2, Matrix6x& w3, Matrix6x& w4) {
  const Matrix6x* dA;
  fp.acceleration(model, tf.fid, *tf.oMf, *tf.J);
  if (tf.local) {
    const Vector6d& V = fp.V[tf.fid];
    const Vector6d& Acc = fp.Acc[tf.fid];
    const Matrix6x& dV = fp.dV[tf.fid];
    const Matrix6x& dAw = fp.dAcc[tf.fid];
    const Vector3d vp = V.head<3>(), w = V.tail<3>();
    const Vector3d y = Acc.head<3>() - w.cross(vp);
    Matrix3x dy = dAw.topRows<3>();  // d(a_p - w x v_p) = da_p + [v_p]x dw - [w]x dv_p
    dy.noalias() += skew3(vp) * dV.bottomRows<3>();
    dy.noalias() -= skew3(w) * dV.topRows<3>();
    const Matrix3d RT = tf.oMf->rotation().transpose();
    const auto Jw = tf.J->bottomRows<3>();
    w2.resize(6, model.nv);
    rotate_skew_add(RT, y, Jw, dy, w2.topRows<3>());
    rotate_skew_add(RT, Vector3d(Acc.tail<3>()), Jw, Matrix3x(dAw.bottomRows<3>()), w2.bottomRows<3>());
    dA = &w2;
  } else {
    dA = &fp.dAcc[tf.fid];
  }
  const std::vector<int>& sel = *tf.select;
  const int k = static_cast<int>(sel.size());
  drift.resize(k, model.nv);
  for (int r = 0; r < k; ++r) drift.row(r) = dA->row(sel[r]);
  w1.setZero(6, model.nv);
  pin::getFrameJacobianTimeVariation(model, fp.data, static_cast<pin::FrameIndex>(tf.fid),
                                     tf.local ? pin::LOCAL : pin::LOCAL_WORLD_ALIGNED, w1);
  Jdot.resize(k, model.nv);
  for (int r = 0; r < k; ++r) Jdot.row(r) = w1.row(sel[r]);
}

// d(J_o^T mu_o)/dq at fixed mu_o (n x n), added into T: the twist rows' generalized force, a wrench at the frame's
// origin p (mu_o on the selected components: force then moment, in the frame's own axes if LOCAL, else world axes),
// Phi = (f, p x f + m) at the world origin with f, m in world axes (LOCAL: f = R f_L, m = R m_L). Its derivative:
// the Jacobian's at fixed Phi (force_jacobian_dq) plus J_O^T dPhi, dPhi = (df, -[f]x J_v + [p]x df + dm), df = -[f]x J_w
// and dm = -[m]x J_w if LOCAL (else zero); J_O = (J_v + [p]x J_w; J_w) from the frame's LOCAL_WORLD_ALIGNED J.
// S^T T is the twist part of the multiplier term, sum_r mu_o,r d(J_o S_l)/dq, without a pass per column of S.
template <class JM>
void twist_force_dq(const pin::Model& model, const JM& Jworld, const TwistFrame& tf,
                    const Eigen::Ref<const VectorXd>& mu, MatrixXd& T) {
  const std::vector<int>& sel = *tf.select;
  Vector6d w6 = Vector6d::Zero();
  for (size_t r = 0; r < sel.size(); ++r) w6[sel[r]] += mu[static_cast<Eigen::Index>(r)];
  const Matrix3d R = tf.oMf->rotation();
  const Vector3d p = tf.oMf->translation();
  const Vector3d f = tf.local ? Vector3d(R * w6.head<3>()) : Vector3d(w6.head<3>());
  const Vector3d m = tf.local ? Vector3d(R * w6.tail<3>()) : Vector3d(w6.tail<3>());
  Vector6d phi;
  phi << f, p.cross(f) + m;
  force_jacobian_dq(model, Jworld, model.frames[static_cast<pin::FrameIndex>(tf.fid)].parentJoint, phi, 1.0, T);
  const Matrix6x& J = *tf.J;
  const Eigen::Index n = J.cols();
  Matrix6xB JO(6, n), dphi(6, n);
  JO.topRows<3>() = J.topRows<3>();
  JO.topRows<3>().noalias() += skew3(p) * J.bottomRows<3>();
  JO.bottomRows<3>() = J.bottomRows<3>();
  dphi.bottomRows<3>().noalias() = -skew3(f) * J.topRows<3>();
  if (tf.local) {
    dphi.topRows<3>().noalias() = -skew3(f) * J.bottomRows<3>();
    dphi.bottomRows<3>().noalias() += skew3(p) * dphi.topRows<3>();
    dphi.bottomRows<3>().noalias() -= skew3(m) * J.bottomRows<3>();
  } else {
    dphi.topRows<3>().setZero();
  }
  T.noalias() += JO.transpose() * dphi;
}

}  // namespace derivs

// The derivative pieces at (q, nu) for either projection (Python `pieces`); the passes, the rows' derivatives, the
// geometry and the tree data are the evaluator's derivative workspace (ev.deriv_: columns of S, then w, then v).
template <class Ev>
struct ProjectedPieces {
  using RD = ReducedDerivatives<Ev>;
  using MatrixXd = Eigen::MatrixXd;
  using VectorXd = Eigen::VectorXd;

  bool op = false;
  int n = 0, k = 0;
  derivs::TwistFrame tf{};
  std::vector<MatrixXd> dJ;  // d(J_o x)/dq per pass (k x n; operational only)
  MatrixXd Jodot, dJd_q, dJd_v, dgam_v, Vq, dgA, dgJ, Wnu;
  bool lean = false;  // build_at: passes at a and v only (ws.dAa, ws.dAv; the twist's dJa, dJ[1])
  MatrixXd dJa;
  derivs::Matrix6x w1, w2, w3, w4;

  // -K^-1 [XA_rows; XJ] (n x cols); XA holds all constraint rows (Projection.solve_neg)
  MatrixXd solve_neg(Ev& ev, const MatrixXd& XA, const MatrixXd& XJ) const {
    if (!op) return RD::solve_neg(ev, XA);
    const int nr = static_cast<int>(ev.rows_.size());
    MatrixXd X(nr + k, XA.cols());
    for (int r = 0; r < nr; ++r) X.row(r) = XA.row(ev.rows_[r]);
    X.bottomRows(k) = XJ;
    return -ev.Kinv_ * X;
  }

  // configure(q), dynamics(nu), and the projection's frame (build and build_at begin with it)
  void start(Ev& ev, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
    if (ev.nv_ > derivs::kMaxNv) throw std::domain_error("more coordinates than the derivative kernels' blocks hold");
    ev.configure(q);
    ev.dynamics(nu);
    n = ev.nv_;
    k = static_cast<int>(ev.S_.cols());
    op = ev.operational_;
    if (op) {
      const int f = ev.op_frame_;
      tf = derivs::TwistFrame{ev.frames_[f], &ev.data_.oMf[ev.frames_[f]], &ev.Jf_[f], ev.op_local_, &ev.op_select_};
    }
  }

  // configure(q), dynamics(nu), then every piece (pieces), on the passes at the columns of S, at w and at v
  void build(Ev& ev, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
    start(ev, q, nu);
    const pinocchio::Model& model = ev.model_;
    auto& ws = ev.deriv_;
    lean = false;
    dJ.resize(op ? k + 2 : 0);
    RD::frame_passes(ev, [&](int l, derivs::FramePass& fp) {
      if (op) derivs::twist_velocity_dq(model, fp, tf, dJ[l], w1, w2);
    });
    finish(ev, ws.dA[k + 1], ws.passes[k + 1], op ? k + 1 : 0);
  }

  // after start(): every piece on two passes only, at a = S nudot + w (velocity-only) and at v
  // (ReducedDerivatives::run_passes); Aq(nudot) then holds for this a's nudot only, and the multiplier term is
  // force_dq's (OperationalDerivatives::run)
  void build_at(Ev& ev, const VectorXd& a) {
    const pinocchio::Model& model = ev.model_;
    auto& ws = ev.deriv_;
    lean = true;
    RD::run_passes(ev, a);  // velocity-only at a (a LOCAL twist: twist_velocity_dq's rotation of the world velocity)
    dJ.resize(op ? 1 : 0);
    if (op) {
      derivs::twist_velocity_dq(model, ws.pass_a, tf, dJa, w1, w2);
      derivs::twist_velocity_dq(model, ws.pass_v, tf, dJ[0], w1, w2);
    }
    finish(ev, ws.dAv, ws.pass_v, 0);
  }

  // the pieces from d(A v)/dq, the pass at v (with accelerations) and d(J_o v)/dq (dJ[jv])
  void finish(Ev& ev, const MatrixXd& dA_v, derivs::FramePass& fv, int jv) {
    const pinocchio::Model& model = ev.model_;
    auto& ws = ev.deriv_;
    const MatrixXd& S = ev.S_;
    dgam_v = ws.Adot + dA_v;  // d gamma / dv = Adot + d(A v)/dq
    MatrixXd none(0, n);
    if (op) {
      derivs::twist_drift_dq(model, fv, tf, dJd_q, Jodot, w1, w2, w3, w4);
      dJd_v = Jodot + dJ[jv];
    }
    Vq = solve_neg(ev, dA_v, op ? dJ[jv] : none);  // v = S(q) nu: dv/dq = -K^-1 d(K v)/dq
    dgA = ws.dgam_q + dgam_v * Vq;
    if (op) dgJ = dJd_q + dJd_v * Vq;
    Wnu = op ? solve_neg(ev, dgam_v * S, dJd_v * S) : solve_neg(ev, dgam_v * S, none);
  }

  // da/dq at fixed nudot, a = S nudot + w: -K^-1 (d(K a)/dq + dg) (Pieces.Aq)
  MatrixXd Aq(Ev& ev, const VectorXd& nudot) const {
    const auto& ws = ev.deriv_;
    if (lean) {  // build_at's passes: at a = S nudot + w for this nudot
      if (!op) return solve_neg(ev, ws.dAa + dgA, MatrixXd(0, n));
      return solve_neg(ev, ws.dAa + dgA, dJa + dgJ);
    }
    MatrixXd dKa = ws.dA[k];
    for (int l = 0; l < k; ++l) dKa += nudot[l] * ws.dA[l];
    if (!op) return solve_neg(ev, dKa + dgA, MatrixXd(0, n));
    MatrixXd dKaJ = dJ[k];
    for (int l = 0; l < k; ++l) dKaJ += nudot[l] * dJ[l];
    return solve_neg(ev, dKa + dgA, dKaJ + dgJ);
  }
};

// The reduced forward dynamics' derivatives with operational-space velocities (dynamics_derivatives with a twist).
template <class Ev>
struct OperationalDerivatives {
  using MatrixXd = Eigen::MatrixXd;
  using VectorXd = Eigen::VectorXd;

  static bool serves(const Ev& ev) { return ev.operational_; }

  static derivs::Result run(Ev& ev, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                            const Eigen::Ref<const VectorXd>& tau) {
    if (!ev.slips_.empty()) throw std::domain_error("slipping wheels: sliding_derivatives.hpp");
    ProjectedPieces<Ev> pc;
    pc.start(ev, q, nu);
    if (tau.size() != ev.Br_.cols()) throw std::invalid_argument("tau has the wrong length");
    const int n = pc.n, k = pc.k;
    auto& ws = ev.deriv_;
    const MatrixXd& S = ev.S_;
    const MatrixXd& M = ev.data_.M;  // symmetric (dynamics)
    derivs::Result out;
    const Eigen::LLT<MatrixXd> llt = ReducedDerivatives<Ev>::reduced_mass(ev, tau, out);
    VectorXd& a = ws.a;  // (the workspace's vectors and matrices, as in ReducedDerivatives::run: no allocation)
    a.noalias() = S * out.nudot;
    a += ev.w_;
    pc.build_at(ev, a);  // two passes (at a and v), not one per column of S
    MatrixXd& dtau_dq = ws.dtau_dq;
    MatrixXd& dtau_dv = ws.dtau_dv;
    ReducedDerivatives<Ev>::tree(ev, a, dtau_dq, dtau_dv);
    VectorXd& rho = ws.rho;
    rho.noalias() = ev.B_ * tau;
    rho = ws.tree.tau - rho;
    // dS^T rho = -S^T dK^T mu, mu = K^-T rho split into the rows' and the twist's parts: the multiplier term
    // S^T d(K^T mu)/dq at fixed mu as one derivative of the constraint and twist forces (with the motors' d(B tau)/dq)
    const int nr = static_cast<int>(ev.rows_.size());
    const VectorXd mu = ev.Kinv_.transpose() * rho;
    VectorXd& muf = ws.muf;  // (the workspace's: no allocation once sized)
    muf.setZero(ev.nrows());
    for (int r = 0; r < nr; ++r) muf[ev.rows_[r]] = mu[r];
    MatrixXd& Tf = ws.Tf;
    ReducedDerivatives<Ev>::force_dq(ev, muf, tau, Tf);
    derivs::twist_force_dq(ev.model_, ev.data_.J, pc.tf, mu.tail(k), Tf);
    const MatrixXd Aq = pc.Aq(ev, out.nudot);
    MatrixXd& ST = ws.ST;
    ST = S.transpose();
    MatrixXd& G = ws.G;  // S^T (dtau_dq - Tf) + (S^T dtau_dv) Vq + (S^T M) Aq
    dtau_dq -= Tf;
    G.noalias() = ST * dtau_dq;
    MatrixXd& STM = ws.STM;
    STM.noalias() = ST * dtau_dv;
    G.noalias() += STM * pc.Vq;
    STM.noalias() = ST * M;
    G.noalias() += STM * Aq;
    ReducedDerivatives<Ev>::solve_reduced(ev, llt, G, dtau_dv, pc.Wnu, out);
    out.Vq = pc.Vq;
    return out;
  }
};

}  // namespace robotdyn

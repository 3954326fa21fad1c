// robotdyn/kernels/sliding_derivatives.hpp: derivatives of the forward dynamics with slipping wheels (sliding.hpp),
// twin of robotdyn/contact/sliding_derivatives.py (law_jacobian, sliding_derivatives), the same formulas in the
// same order. The accelerations and the kept rows' forces solve together (SlipSystem):
//
//   Phi = RNEA(q, v, a) - B tau - G lambda = 0,  G = A_R^T - sum_i J_t,i^T c_i(s_i) e_i^T,  a = S nudot + w,
//   s_i = J_t,i v,  so with K_s = [M S, -G]:  K_s d(nudot, lambda) = -dPhi,
//
//   dPhi = dRNEA/dq dq + dRNEA/dv dv + M da|nudot - d(B tau) - d(A_R^T lambda)/dq dq
//          + sum_i lambda_i (d(J_t,i^T c_i)/dq dq + J_t,i^T c_i'(s_i) ds_i),  ds_i = d(J_t,i v)/dq dq + J_t,i dv.
//
// The transposed-row terms need every column of dA/dq: one frame pass per velocity (at each unit vector). The
// laws' c'(s) (law_jacobian): regularised Coulomb mu (I/rho - s s^T/rho^3), rho = sqrt(|s|^2 + v_s^2); the linear
// tyre k I in its linear range (k |s| <= mu, the kink included: the linear side, as the Python path) and, where it
// slides at Coulomb's limit, mu (I/|s| - s s^T/|s|^3), defined for every |s| > mu/k > 0. Exact (set-valued) Coulomb
// friction and stick-slip wheels are not compiled (the Python path refuses them in one line before this is called).
// The projection's pieces (either projection) are ProjectedPieces (operational_space_derivatives.hpp).
#pragma once

#include "operational_space_derivatives.hpp"
#include "sliding.hpp"

#include <cmath>

namespace robotdyn {
namespace derivs {

// dc/ds (2 x 2) of a slipping wheel's law at slip s (free directions only) (law_jacobian)
inline Eigen::Matrix2d law_jacobian(const kernels::Slip& sl, const Eigen::Vector2d& slip) {
  const Eigen::Vector2d x = slip.cwiseProduct(sl.free);
  Eigen::Matrix2d J;
  if (sl.law == 0) {
    const double rho = std::sqrt(x.dot(x) + sl.p1 * sl.p1);
    J = sl.p0 * (Eigen::Matrix2d::Identity() / rho - x * x.transpose() / (rho * rho * rho));
  } else {
    const double speed = std::sqrt(x.dot(x));
    if (speed * sl.p0 <= sl.p1)
      J = sl.p0 * Eigen::Matrix2d::Identity();
    else
      J = sl.p1 * (Eigen::Matrix2d::Identity() / speed - x * x.transpose() / (speed * speed * speed));
  }
  return sl.free.asDiagonal() * J * sl.free.asDiagonal();
}

}  // namespace derivs

template <class Ev>
struct SlidingDerivatives {
  using RD = ReducedDerivatives<Ev>;
  using MatrixXd = Eigen::MatrixXd;
  using VectorXd = Eigen::VectorXd;

  // the tangential rows (t1, t2) of a slipping wheel's contact frame (TANGENT)
  static const MatrixXd& tangent() {
    static const MatrixXd D = (MatrixXd(2, 3) << 1.0, 0.0, 0.0, 0.0, 1.0, 0.0).finished();
    return D;
  }

  // d(J_t x)/dq at fixed x of wheel `w`'s tangential rows on a pass (wheel_velocity_dq with directions TANGENT)
  static MatrixXd tangential_dq(Ev& ev, derivs::FramePass& fp, int w) {
    const auto& wh = ev.wheels_[w];
    const int fid = ev.frames_[wh.frame];
    fp.velocity(ev.model_, fid, ev.data_.oMf[fid], ev.Jf_[wh.frame]);
    const double xR = wh.radius_index >= 0 ? fp.x[wh.radius_index] : 0.0;
    MatrixXd out(2, ev.nv_);
    derivs::wheel_velocity_dq(ev.geo_[w], ev.deriv_.geo[w], tangent(), fp.V[fid], fp.dV[fid], xR, out);
    return out;
  }

  static derivs::Result run(Ev& ev, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                            const Eigen::Ref<const VectorXd>& tau) {
    if (ev.slips_.empty()) throw std::invalid_argument("no slipping wheels");
    ProjectedPieces<Ev> pc;
    pc.build(ev, q, nu);
    if (tau.size() != ev.Br_.cols()) throw std::invalid_argument("tau has the wrong length");
    const int n = pc.n, k = pc.k;
    const int nr = static_cast<int>(ev.rows_.size());
    if (k + nr != n) throw std::domain_error("rows and independent velocities do not make a square system");
    auto& sys = ev.slip_;
    try {  // the coupled solve and its Painleve test, as the simulation's (a singular one: the Python path's error)
      sys.solve(ev.slips_, ev.rows_, ev.A_, ev.SM_, ev.geo_, ev.Aw_, ev.v_, ev.B_, tau, ev.data_.tau, ev.data_.M,
                ev.w_, n, k, ev.lus_);
    } catch (const kernels::SlipError& e) {
      throw std::domain_error(e.what());
    }
    const VectorXd nudot = sys.x.head(k), lam = sys.x.tail(nr);
    const MatrixXd& S = ev.S_;
    const MatrixXd& M = ev.data_.M;
    const VectorXd a = S * nudot + ev.w_;
    MatrixXd dtau_dq, dtau_dv;
    RD::tree(ev, a, dtau_dq, dtau_dv);
    // every column of dA/dq: passes at the unit vectors, T_j = d(A e_j)/dq (m x n)
    auto& ws = ev.deriv_;
    std::vector<derivs::FramePass>& units = ws.units;
    units.resize(n);
    MatrixXd Tj, dGlam_q = MatrixXd::Zero(n, n), dGlam_nu = MatrixXd::Zero(n, k);
    const int nw = static_cast<int>(ev.slips_.size());
    std::vector<MatrixXd> Tt(static_cast<size_t>(nw) * n);  // d(J_t,i e_j)/dq (2 x n) per wheel i, unit j
    for (int j = 0; j < n; ++j) {
      derivs::FramePass& fp = units[j];
      fp.run(ev.model_, ev.q_, VectorXd::Unit(n, j), false);
      RD::prepare(ev, fp, false);
      RD::velocity_dq(ev, fp, Tj);
      for (int r = 0; r < nr; ++r) dGlam_q.row(j) += lam[r] * Tj.row(ev.rows_[r]);
      for (int i = 0; i < nw; ++i) Tt[i * n + j] = tangential_dq(ev, fp, ev.slips_[i].wheel);
    }
    for (int i = 0; i < nw; ++i) {
      const kernels::Slip& sl = ev.slips_[i];
      const auto& g = ev.geo_[sl.wheel];
      MatrixXd Jt(2, n);
      Jt.row(0) = g.t1.transpose() * ev.Aw_[sl.wheel];
      Jt.row(1) = g.t2.transpose() * ev.Aw_[sl.wheel];
      const Eigen::Vector2d s = sys.s.row(i).transpose(), c = sys.c.row(i).transpose();
      const Eigen::Matrix2d C = derivs::law_jacobian(sl, s);
      const double li = lam[sys.pos[i]];
      const MatrixXd ds_q = tangential_dq(ev, ws.passes[k + 1], sl.wheel) + Jt * pc.Vq;  // at fixed v, then v(q)
      for (int j = 0; j < n; ++j) {
        const MatrixXd& T = Tt[i * n + j];
        dGlam_q.row(j) -= li * (c[0] * T.row(0) + c[1] * T.row(1));
      }
      const MatrixXd JtC = Jt.transpose() * C;
      dGlam_q -= li * (JtC * ds_q);
      dGlam_nu -= li * (JtC * (Jt * S));
    }
    // -d(B tau)/dq of the motors reacting on a body (motor_force_dq: the same terms as the unit passes' would give)
    MatrixXd Bq = MatrixXd::Zero(n, n);
    RD::motor_force_dq(ev, tau, Bq);
    Bq = -Bq;
    MatrixXd R(n, n + k + ev.B_.cols());
    R.leftCols(n) = dtau_dq + dtau_dv * pc.Vq + M * pc.Aq(ev, nudot) + Bq - dGlam_q;  // (Bq holds -d(B tau)/dq)
    R.middleCols(n, k) = dtau_dv * S + M * pc.Wnu - dGlam_nu;
    R.rightCols(ev.B_.cols()) = -ev.B_;
    const MatrixXd X = sys.lu.solve(-R).topRows(k);
    derivs::Result out;
    out.nudot = nudot;
    out.dq = X.leftCols(n);
    out.dnu = X.middleCols(n, k);
    out.dtau = X.rightCols(ev.B_.cols());
    out.v = ev.v_;
    out.Vq = pc.Vq;
    out.S = S;
    out.A = ev.A_;
    return out;
  }
};

}  // namespace robotdyn

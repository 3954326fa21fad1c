// robotdyn/kernels/sliding.hpp: wheels that slip under a friction law, twin of robotdyn/contact/sliding.py (forward,
// SlippingWheel) and of the laws of robotdyn/contact/friction.py (the concepts page docs/concepts.md, "Slipping
// wheels"; notes: contact-forces-and-friction.md). A slipping wheel keeps its normal row; on its free directions
// (t1, t2) the tangential force is F_t = -f_n c(s), s = J_t v its slip velocity, with the law
//
//   0 RegularisedCoulomb   c = mu s / sqrt(|s|^2 + v_s^2)            (p0 = mu, p1 = slip velocity v_s [m/s])
//   1 LinearTyre           c = k s if k |s| <= mu, else mu s / |s|   (p0 = stiffness k [s/m], p1 = mu, inf allowed)
//
// The accelerations and the normal loads solve one linear system (the friction direction fixed by the current slip)
//
//   [M S,  -(A_R^T - sum_i J_t,i^T c_i e_i^T)] [nudot; lambda] = B tau - RNEA(q, v, w) + Q(q, v),
//
// Q the joint springs' and dampers' generalised force (joint_springs.hpp; the caller passes C v + g - Q as Cvg),
// A_R the projection's rows, J_t,i = (t1, t2)^T A_w,i the tangential rows of slipping wheel i, e_i selecting its
// normal load; the friction power W-dot = sum_i F_i . s_i. The system's 2-norm condition number above 1e12 is the
// Painleve case (sliding.PAINLEVE_CONDITION).
#pragma once

#include "common.hpp"
#include "lu_solve.hpp"
#include "painleve.hpp"
#include "rolling_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace robotdyn {
namespace kernels {

// A wheel whose tangential force follows a friction law (the header's table).
struct Slip {
  int wheel;       // index into the Evaluator's wheels
  int normal_row;  // its normal row (index into the stacked rows)
  int law;
  double p0, p1;
  Eigen::Vector2d free;  // 1: the direction follows the law, 0: it rolls (its no-slip row stays a constraint)
};

// The slipping wheels' contact problem cannot be solved here: kind 0 singular (Painleve; value: its 2-norm
// condition number), kind 1 a slipping wheel's normal row is not among the projection's rows (value: the slip's
// index), kind 2 the effective normal matrix is no P-matrix (Painleve, painleve.hpp; value: the threshold mu_P or
// NaN, wheels: the bit mask of the first minor that is not positive). The Python side raises the reference path's
// error from it (robotdyn/simulation/compiled_engine.py).
struct SlipError : std::runtime_error {
  SlipError(int kind_, double value_, int wheels_ = 0)
      : std::runtime_error(kind_ == 0   ? "singular slipping contact problem"
                           : kind_ == 1 ? "slipping wheel's normal row redundant"
                                        : "Painleve: the sliding wheels' effective normal matrix is no P-matrix"),
        kind(kind_), value(value_), wheels(wheels_) {}
  int kind;
  double value;
  int wheels;
};

// c(s) of a slipping wheel's law on its free directions (FrictionLaw.coefficient, SlippingWheel.
// friction_coefficient), in the Python formulas' order of operations.
inline Eigen::Vector2d friction_coefficient(const Slip& sl, const Eigen::Vector2d& slip) {
  const Eigen::Vector2d s = slip.cwiseProduct(sl.free);
  Eigen::Vector2d c;
  if (sl.law == 0) {
    c = sl.p0 * s / std::sqrt(s.dot(s) + sl.p1 * sl.p1);
  } else {
    const double speed = std::sqrt(s.dot(s));
    c = speed * sl.p0 <= sl.p1 ? Eigen::Vector2d(sl.p0 * s) : Eigen::Vector2d(sl.p1 * s / speed);
  }
  return c.cwiseProduct(sl.free);
}

// The coupled system of the header, its solution and the Painleve test; the results stay in the members.
struct SlipSystem {
  MatrixXd K, Jt, U;  // U: each slipping wheel's friction column J_t^T c (nv, W)
  PainleveCheck painleve;
  VectorXd b, x, normal;
  Eigen::Matrix<double, Eigen::Dynamic, 2> s, c;  // per slipping wheel: slip velocity, c(s)
  std::vector<int> pos;                           // per slipping wheel: its normal row's place among the rows
  Eigen::PartialPivLU<MatrixXd> lu;
  Eigen::JacobiSVD<MatrixXd> svd;
  double kappa1 = 0.0, kappa2 = 0.0;  // the last Painleve test (Evaluator.slip_condition)
  double min_normal = HUGE_VAL;       // the smallest normal load (the lift-off event's value) [N]
  double power = 0.0;                 // the friction power sum_i F_i . s_i [W]

  // Each slipping wheel's tangential rows J_t = (t1, t2)^T A_w, slip velocity s = J_t v, law c(s) and friction
  // column U_i = J_t^T c (the system's K takes U_i on the wheel's normal-load column).
  void friction_columns(const std::vector<Slip>& slips, const std::vector<WheelGeometry>& geo,
                        std::vector<MatrixXd>& Aw, VectorXd& v, int nv) {
    const int nw = static_cast<int>(slips.size());
    s.resize(nw, 2);
    c.resize(nw, 2);
    Jt.resize(2, nv);
    U.resize(nv, nw);
    for (int i = 0; i < nw; ++i) {
      const Slip& sl = slips[i];
      const WheelGeometry& g = geo[sl.wheel];
      Jt.row(0).noalias() = g.t1.transpose() * Aw[sl.wheel];
      Jt.row(1).noalias() = g.t2.transpose() * Aw[sl.wheel];
      const Eigen::Vector2d si = Jt * v;
      const Eigen::Vector2d ci = friction_coefficient(sl, si);
      s.row(i) = si.transpose();
      c.row(i) = ci.transpose();
      U.col(i).noalias() = Jt.transpose() * ci;
    }
  }

  // b = B tau - (C v + g - Q) - M w: the system's right-hand side above the rows (the header's).
  void right_hand_side(MatrixXd& B, const Eigen::Ref<const VectorXd>& tau, VectorXd& Cvg, MatrixXd& M, VectorXd& w) {
    b.noalias() = B * tau;
    b -= Cvg;
    b.noalias() -= M * w;
  }

  // The LU factors of a square system K into lu, and the Painleve test on its condition: the decision of the Python
  // path's np.linalg.cond(K) > 1e12 (2-norm) without an O(n^3) inverse or SVD at regular states. From the LU factors
  // just computed, LAPACK's O(n^2) estimate e of ||K^-1||_1 (the projection's estimator,
  // LuSolver::inverse_norm_estimate) gives kappa_1 ~ ||K||_1 e. For n x n matrices kappa_2 <= n kappa_1, and
  // e <= ||K^-1||_1 underestimates by a small factor in practice (the projection counts on 100: its estimate decides
  // below 1e8 against its bound 1e10). So:
  //   n ||K||_1 e <= 1e12 / 100  ->  regular, no further work (kappa_2 <= 1e12 unless e underestimates by > 100);
  //   otherwise (near the threshold, beyond it, or NaN / inf from a zero pivot) the singular values decide,
  //   exactly as numpy.linalg.cond does (kappa_2 = s_max / s_min, singular above 1e12 or not finite), and give
  //   the value the Python path reports.
  // The band [1e10 / n, 1e12] of estimates that pay for the SVD is a factor 100 n wide: only a state near
  // Painleve pays there. Both systems use it: this one's K and sliding_rigid_limit.hpp's coupled K.
  void factor_checked(const MatrixXd& Ks, Eigen::PartialPivLU<MatrixXd>& factors, LuSolver& lus) {
    factors.compute(Ks);
    const int n = static_cast<int>(Ks.rows());
    kappa1 = Ks.cwiseAbs().colwise().sum().maxCoeff() * lus.inverse_norm_estimate(factors);
    kappa2 = std::numeric_limits<double>::quiet_NaN();  // (not computed)
    if (!(n * kappa1 <= 1e12 / 100)) {  // NaN too
      svd.compute(Ks);
      const VectorXd& sv = svd.singularValues();
      const double cond = sv[0] / sv[sv.size() - 1];
      kappa2 = std::isnan(cond) ? HUGE_VAL : cond;
      if (!(std::isfinite(cond) && cond <= 1e12)) throw SlipError(0, kappa2);
    }
  }

  // Solves for x = (nudot (k), lambda_R) at a state: SM = M S, A the stacked rows (the projection's `rows`), geo and
  // Aw the wheels' geometry and A_w, v the velocities, B tau the motors' forces, Cvg = C v + g (- Q), M w the
  // drift's force (Aw, v, B, Cvg, M, w read only).
  void solve(const std::vector<Slip>& slips, const std::vector<int>& rows, const MatrixXd& A, const MatrixXd& SM,
             const std::vector<WheelGeometry>& geo, std::vector<MatrixXd>& Aw, VectorXd& v, MatrixXd& B,
             const Eigen::Ref<const VectorXd>& tau, VectorXd& Cvg, MatrixXd& M, VectorXd& w, int nv, int k,
             LuSolver& lus) {
    const int nr = static_cast<int>(rows.size());
    const int nw = static_cast<int>(slips.size());
    K.resize(nv, nv);
    K.leftCols(k) = SM;  // M S
    for (int r = 0; r < nr; ++r) K.col(k + r) = -A.row(rows[r]).transpose();
    pos.resize(nw);
    for (int i = 0; i < nw; ++i) {
      const auto hit = std::find(rows.begin(), rows.end(), slips[i].normal_row);
      if (hit == rows.end()) throw SlipError(1, i);
      pos[i] = static_cast<int>(hit - rows.begin());
    }
    friction_columns(slips, geo, Aw, v, nv);
    for (int i = 0; i < nw; ++i) K.col(k + pos[i]) += U.col(i);
    right_hand_side(B, tau, Cvg, M, w);
    factor_checked(K, lu, lus);
    x = lu.solve(b);
    if (nw > 0) check_painleve(slips, rows, A, M, nv, k, nr);
    normal.resize(nw);
    power = 0.0;
    min_normal = HUGE_VAL;
    for (int i = 0; i < nw; ++i) {
      const double fn = x[k + pos[i]];
      normal[i] = fn;
      min_normal = std::min(min_normal, fn);
      power += -fn * c(i, 0) * s(i, 0) + -fn * c(i, 1) * s(i, 1);
    }
  }

  // The Painleve check (painleve.hpp) on the factorised K: throws SlipError kind 2 where the effective normal
  // matrix is no P-matrix.
  void check_painleve(const std::vector<Slip>& slips, const std::vector<int>& rows, const MatrixXd& A,
                      const MatrixXd& M, int nv, int k, int nr) {
    const int nw = static_cast<int>(slips.size());
    PainleveCheck& pc = painleve;
    pc.AR.resize(nr, nv);
    for (int r = 0; r < nr; ++r) pc.AR.row(r) = A.row(rows[r]);
    pc.gram.noalias() = pc.AR * pc.AR.transpose();
    pc.sel.setZero(nr, nw);
    for (int i = 0; i < nw; ++i) pc.sel(pos[i], i) = 1.0;
    pc.gram_lu.compute(pc.gram);
    pc.Yg = pc.gram_lu.solve(pc.sel);
    pc.Z.noalias() = pc.AR.transpose() * pc.Yg;
    pc.MZ.noalias() = M * pc.Z;
    pc.Y = lu.solve(pc.MZ);
    pc.E.resize(nw, nw);
    for (int i = 0; i < nw; ++i) pc.E.row(i) = -pc.Y.row(k + pos[i]);  // D^-1
    pc.D = pc.E.inverse();
    const int mask = pc.first_violation();
    if (!mask) return;
    double mu_p = std::numeric_limits<double>::quiet_NaN();
    if ((mask & (mask - 1)) == 0) {  // one wheel: its threshold where its law is proportional to mu
      int j = 0;
      while (!((mask >> j) & 1)) ++j;
      const Slip& sl = slips[j];
      const Eigen::Vector2d sj = s.row(j).transpose().cwiseProduct(sl.free);
      const double mu = sl.law == 0 ? sl.p0 : sl.p1;
      const bool proportional = sl.law == 0 || std::sqrt(sj.dot(sj)) * sl.p0 > sl.p1;
      pc.Y = lu.solve(U);
      pc.Q.resize(nw, nw);
      for (int i = 0; i < nw; ++i) pc.Q.row(i) = pc.Y.row(k + pos[i]);
      const double f = -pc.D.row(j).dot(pc.Q.col(j));  // F = -D Q, the friction's part of D
      const double t = (pc.D(j, j) + f) / f;           // D0_jj / F_jj
      if (proportional && std::isfinite(mu) && f != 0.0 && std::isfinite(t) && t > 0.0 && t < 1.0) mu_p = mu * t;
    }
    throw SlipError(2, mu_p, mask);
  }
};

}  // namespace kernels
}  // namespace robotdyn

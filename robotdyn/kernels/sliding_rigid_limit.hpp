// robotdyn/kernels/sliding_rigid_limit.hpp: slipping wheels whose normal loads rigid-body dynamics leave open (a rigid
// chassis on four wheels), twin of robotdyn/contact/sliding_rigid_limit.py (coupled; the same steps in the same
// order, its docstring derives them; notes: indeterminate-loads-and-compliance.md, contact-forces-and-friction.md),
// called by robotdyn/contact/sliding.py's forward where the projection drops rows. Unknowns
// (nudot (k), lambda on every row (m), the no-pull multipliers mu_U of the wheels held at zero load (u)):
//
//   M S nudot - (A^T - sum_i J_t,i^T c_i e_i^T) lambda = B tau - RNEA(q, v, w) + Q    (n rows; Q: joint springs)
//   (C N V_n)^T (K^-1 C lambda - mu) = 0                                              (p rows: compatibility)
//   (N V_o)^T lambda = 0                                                              (d - p rows: minimum norm)
//   C_U lambda = 0                                                                    (u rows: held at zero)
//
// N an orthonormal basis of null(A^T) (m x d), C each wheel's normal load from the multipliers (W x m), V_n / V_o
// the directions of N that move / move no normal load (an SVD of P = C N, p above 1e-9), K the wheels' normal
// stiffnesses (only their ratios matter: K^-1 = mean(k) / k). The set U comes from an active-set loop (a loaded
// wheel whose load comes out negative is held at zero, a held one whose mu comes out negative is loaded again, at
// most 2W + 2 solves); where a wheel to hold cannot be held by the load-moving directions left (its row of C N V_n
// depends on those of U: a whole axle would pull), the compatible loads (U empty, some negative) are returned for
// the lift-off event. A condition number above 1e12 is the Painleve case (sliding.hpp), as is an effective normal
// matrix that is no P-matrix on the separations the rigid rows allow (painleve.hpp). p = 0 (the redundant rows move
// no load): not served here, the determinate system of sliding.hpp decides (as coupled returns None).
#pragma once

#include "common.hpp"
#include "lu_solve.hpp"
#include "painleve.hpp"
#include "rolling_contact.hpp"
#include "sliding.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace robotdyn {
namespace kernels {

struct SlipRigidLimit {
  static constexpr double RANK_TOL = 1e-9;  // contact/rigid_limit.py RANK_TOL
  static constexpr double PULL_TOL = 1e-9;  // contact/rigid_limit.py PULL_TOL

  VectorXd lam, mu, loads, kinv, b, x, sol_c, sv;
  MatrixXd N, C, P, PV, compat, opened, G, K, Kc, Ab, E, Z, MZ, Y, basis, Ut, tmp;
  std::vector<int> unloaded, where, free_;
  Eigen::JacobiSVD<MatrixXd> svd_a, svd_p, svd_k;
  Eigen::PartialPivLU<MatrixXd> lu;
  int m = 0, d = 0, p = 0, rank = 0;

  // One evaluation: true with the results in sys (x's head the accelerations, s, c, U, normal, power, min_normal)
  // and lam, unloaded here; false where p = 0 (sys untouched: the determinate system decides). A the stacked rows
  // (m x nv), SM = M S, geo/Aw the wheels' geometry and A_w, Cvg = C v + g (- Q, sliding.hpp), M w the drift's
  // force, kstiff the wheels' normal stiffnesses (empty: equal). Throws SlipError kind 0 (singular, or no active set found: value
  // inf) and kind 2 (no P-matrix; wheels: the bit mask of the slipping wheels involved, value NaN).
  bool solve(SlipSystem& sys, const std::vector<Slip>& slips, const std::vector<Wheel>& wheels, const MatrixXd& A,
             const MatrixXd& SM, const std::vector<WheelGeometry>& geo, std::vector<MatrixXd>& Aw, VectorXd& v,
             MatrixXd& B, const Eigen::Ref<const VectorXd>& tau, VectorXd& Cvg, MatrixXd& M, VectorXd& w,
             const VectorXd& kstiff, int nv, int k, LuSolver& lus) {
    m = static_cast<int>(A.rows());
    const int n = nv;
    const int nwh = static_cast<int>(wheels.size());
    const int nw = static_cast<int>(slips.size());
    // N: the null space of A^T from its SVD (numpy's rank rule: s > s_max max(shape) eps)
    svd_a.compute(A.transpose(), Eigen::ComputeThinU | Eigen::ComputeFullV);
    const VectorXd& sa = svd_a.singularValues();
    const double smax = sa.size() ? sa.maxCoeff() : 0.0;
    const double tol = smax * std::max(m, n) * std::numeric_limits<double>::epsilon();
    rank = 0;
    for (Eigen::Index i = 0; i < sa.size(); ++i) rank += sa[i] > tol;
    d = m - rank;
    N = svd_a.matrixV().rightCols(d);
    // C (normal_map) and P = C N, its load-moving directions V_n
    C.setZero(nwh, m);
    for (int i = 0; i < nwh; ++i)
      for (int r = 0; r < wheels[i].D.rows(); ++r) C(i, geo[i].row + r) = wheels[i].D(r, 2);
    P.noalias() = C * N;
    svd_p.compute(P, Eigen::ComputeFullV);
    const VectorXd& sp = svd_p.singularValues();
    p = 0;
    for (Eigen::Index i = 0; i < sp.size(); ++i) p += sp[i] > RANK_TOL;
    if (p == 0) return false;
    // kinv = mean(k) / k (only the ratios matter)
    if (kstiff.size() == nwh) kinv = VectorXd::Constant(nwh, kstiff.mean()).cwiseQuotient(kstiff);
    else kinv.setOnes(nwh);
    // G = A^T with each slipping wheel's friction column J_t^T c taken from its normal row's column
    G = A.transpose();
    sys.friction_columns(slips, geo, Aw, v, n);
    where.resize(nw);
    for (int i = 0; i < nw; ++i) {
      G.col(slips[i].normal_row) -= sys.U.col(i);
      where[i] = slips[i].wheel;
    }
    sys.right_hand_side(B, tau, Cvg, M, w);
    const MatrixXd& V = svd_p.matrixV();
    PV.noalias() = P * V.leftCols(p);                                    // (W, p)
    compat.noalias() = PV.transpose() * (kinv.asDiagonal() * C);           // (p, m)
    opened.noalias() = (N * V.rightCols(d - p)).transpose();             // (d - p, m)
    const int nrow = n + d, ncol = k + m;
    if (nrow != ncol) throw Fallback("rows and independent velocities do not make a square system");
    unloaded.clear();
    bool done = false;
    for (int iter = 0; iter < 2 * nwh + 2; ++iter) {
      const int u = static_cast<int>(unloaded.size());
      K.setZero(nrow + u, ncol + u);
      K.topLeftCorner(n, k) = SM;
      K.block(0, k, n, m) = -G;
      K.block(n, k, p, m) = compat;
      for (int j = 0; j < u; ++j) K.block(n, ncol + j, p, 1) = -PV.row(unloaded[j]).transpose();
      K.block(n + p, k, d - p, m) = opened;
      for (int j = 0; j < u; ++j) K.block(nrow + j, k, 1, m) = C.row(unloaded[j]);
      b.setZero(nrow + u);
      b.head(n) = sys.b;
      sys.factor_checked(K, lu, lus);
      x = lu.solve(b);
      lam = x.segment(k, m);
      mu = x.tail(u);
      loads.noalias() = C * lam;
      const double scale = std::max(loads.size() ? loads.cwiseAbs().maxCoeff() : 0.0, 1e-300);
      int worst = -1;
      for (int j = 0; j < nwh; ++j) {
        if (std::find(unloaded.begin(), unloaded.end(), j) != unloaded.end()) continue;
        if (worst < 0 || loads[j] < loads[worst]) worst = j;
      }
      if (u == 0) {
        sol_c = x;
        Kc = K;
      }
      if (worst >= 0 && loads[worst] < -PULL_TOL * scale) {
        tmp.resize(u + 1, p);
        for (int j = 0; j < u; ++j) tmp.row(j) = PV.row(unloaded[j]);
        tmp.row(u) = PV.row(worst);
        svd_k.compute(tmp);
        int r = 0;
        for (Eigen::Index i = 0; i < svd_k.singularValues().size(); ++i) r += svd_k.singularValues()[i] > RANK_TOL;
        if (r <= u) {  // a whole axle would pull: the compatible loads, some negative (the lift-off event finds zero)
          x = sol_c;
          K = Kc;
          lu.compute(K);
          lam = x.segment(k, m);
          loads.noalias() = C * lam;
          unloaded.clear();
          done = true;
          break;
        }
        unloaded.push_back(worst);
        continue;
      }
      if (u) {
        Eigen::Index jmin;
        const double mmin = mu.minCoeff(&jmin);
        if (mmin < -PULL_TOL * mu.cwiseAbs().maxCoeff()) {
          unloaded.erase(unloaded.begin() + jmin);
          continue;
        }
      }
      done = true;
      break;
    }
    if (!done) throw SlipError(0, HUGE_VAL);
    check_painleve(sys, slips, A, M, n, k);
    sys.x = x;
    sys.normal.resize(nw);
    sys.power = 0.0;
    sys.min_normal = HUGE_VAL;
    double any_min = HUGE_VAL;
    for (int i = 0; i < nw; ++i) {
      const double fn = loads[where[i]];
      sys.normal[i] = fn;
      sys.power += -fn * sys.c(i, 0) * sys.s(i, 0) + -fn * sys.c(i, 1) * sys.s(i, 1);
      any_min = std::min(any_min, fn);
      if (std::find(unloaded.begin(), unloaded.end(), where[i]) == unloaded.end())
        sys.min_normal = std::min(sys.min_normal, fn);  // contact_load: the loaded wheels only
    }
    if (sys.min_normal == HUGE_VAL) sys.min_normal = any_min;  // (every slipping wheel unloaded)
    return true;
  }

  // coupled's Painleve check on the separations the rigid rows allow (painleve.check with its basis).
  void check_painleve(SlipSystem& sys, const std::vector<Slip>& slips, const MatrixXd& A, const MatrixXd& M, int n,
                      int k) {
    const int nw = static_cast<int>(slips.size());
    std::vector<int> live;
    for (int i = 0; i < nw; ++i)
      if (std::find(unloaded.begin(), unloaded.end(), where[i]) == unloaded.end()) live.push_back(i);
    const int L = static_cast<int>(live.size());
    if (!L) return;
    E.setZero(m, L);
    for (int j = 0; j < L; ++j) E(slips[live[j]].normal_row, j) = 1.0;
    tmp.noalias() = N.transpose() * E;  // (d, L)
    svd_k.compute(tmp, Eigen::ComputeFullV);
    int r = 0;
    for (Eigen::Index i = 0; i < svd_k.singularValues().size(); ++i) r += svd_k.singularValues()[i] > RANK_TOL;
    const bool sub = r > 0;
    if (sub) {
      if (L - r == 0) return;
      basis = svd_k.matrixV().rightCols(L - r);
    }
    // Z = lstsq(A, E): the minimum-norm solution, A^+ = U_r S_r^-1 V_r^T from A^T = V S U^T (svd_a)
    const MatrixXd& Ua = svd_a.matrixU();  // (n, min(n, m)): A^T's left vectors
    const MatrixXd& Va = svd_a.matrixV();  // (m, m)
    Z.noalias() = Ua.leftCols(rank) *
                  (svd_a.singularValues().head(rank).cwiseInverse().asDiagonal() * (Va.leftCols(rank).transpose() * E));
    MZ.setZero(K.rows(), L);
    MZ.topRows(n).noalias() = M * Z;
    Y = lu.solve(MZ);
    PainleveCheck& pc = sys.painleve;
    pc.E.resize(L, L);
    for (int j = 0; j < L; ++j) pc.E.row(j) = -Y.row(k + slips[live[j]].normal_row);
    if (sub) pc.E = (basis.transpose() * pc.E * basis).eval();
    pc.D = pc.E.inverse();
    const int mask = pc.first_violation();
    if (!mask) return;
    // the slipping wheels involved (in slip order): the minor's wheels, or those its basis directions touch
    int wheels_mask = 0;
    for (int j = 0; j < static_cast<int>(pc.D.rows()); ++j) {
      if (!((mask >> j) & 1)) continue;
      if (!sub) wheels_mask |= 1 << live[j];
      else
        for (int i = 0; i < L; ++i)
          if (std::fabs(basis(i, j)) > 1e-9) wheels_mask |= 1 << live[i];
    }
    throw SlipError(2, std::numeric_limits<double>::quiet_NaN(), wheels_mask);
  }
};

}  // namespace kernels
}  // namespace robotdyn

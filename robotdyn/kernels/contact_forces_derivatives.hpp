// robotdyn/kernels/contact_forces_derivatives.hpp: derivatives of the constraint forces, twin of
// robotdyn/contact/force_derivatives.py (layer: the multipliers at known motion and their partial derivatives; the
// chain along the motion's pieces), beside contact_forces.hpp and rigid_limit.hpp (the forces themselves), the same
// formulas in the same order:
//
//   H d(lambda, u, mu) = (-dP_o lambda - dA u, de - dA^T lambda, 0),
//   H = [[W + P_o, A, C_U^T], [A^T, 0, 0], [C_U, 0, 0]],  e = RNEA(q, v, a) - B(q) tau,
//   dP_o = -Z^+ dZ P_o - (Z^+ dZ P_o)^T,  Z = [A^T; C] (with a split) or A^T,
//
// with W = C^T K^-1 C the rigid limit's complementary energy (C picks the wheels' normal loads, K their
// stiffnesses: only the ratios matter), C_U the wheels it holds unloaded (its active set, from the forces), P_o the
// orthogonal projector onto what stays open (null(A^T), and null(C) with a split). dA/dq comes from the rows'
// velocity derivatives at the unit velocities (one frame pass per coordinate, ReducedDerivatives::velocity_dq on
// Pinocchio's computeForwardKinematicsDerivatives), de/dq, de/dv and M from Pinocchio's computeRNEADerivatives at
// (q, v, a) less the motors' d(B tau)/dq (ReducedDerivatives::motor_force_dq). The
// pseudo-inverses are truncated at the ranks the Python path uses (SVDs), so both give the same numbers.
//
// Served: rolling wheels, loop closures, couplings (what ReducedDerivatives serves); operational-space velocities
// and slipping wheels throw std::domain_error (the Python path answers). ForceChain adds, after
// ReducedDerivatives::run, the two pieces of the projection the chain needs: da/dq at fixed nudot (Pieces.Aq) and
// dw/dnu (Pieces.Wnu), from the run's own workspace.
#pragma once

#include <Eigen/SVD>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <vector>

#include "reduced_dynamics_derivatives.hpp"

namespace robotdyn {
namespace derivs {

// Layer 1 at (q, v, a, tau): the multipliers and their partial derivatives (m x n, m x n, m x n, m x motors).
struct ForceLayer {
  VectorXd lam;
  MatrixXd dq, dv, da, dtau;
  double residual = 0.0;  // |H X - rhs| / max(|e|, 1)
};

// The chain's pieces after ReducedDerivatives::run: a = S nudot + w, da/dq at fixed nudot (n x n), dw/dnu (n x k).
struct ForceChain {
  VectorXd a;
  MatrixXd Aq, Wnu;
};

// Moore-Penrose pseudo-inverse of X truncated at rank r (numpy's SVD truncated as the Python path does)
inline MatrixXd truncated_pinv(const MatrixXd& X, int r) {
  if (X.rows() == 0 || X.cols() == 0 || r <= 0) return MatrixXd::Zero(X.cols(), X.rows());
  Eigen::BDCSVD<MatrixXd> svd(X, Eigen::ComputeThinU | Eigen::ComputeThinV);
  r = std::min<int>(r, static_cast<int>(svd.singularValues().size()));
  return svd.matrixV().leftCols(r) * svd.singularValues().head(r).cwiseInverse().asDiagonal() *
         svd.matrixU().leftCols(r).transpose();
}

}  // namespace derivs

template <class Ev>
struct ContactForcesDerivatives {
  using RD = ReducedDerivatives<Ev>;
  using Model = pinocchio::Model;
  using MatrixXd = Eigen::MatrixXd;
  using VectorXd = Eigen::VectorXd;

  // Pieces.Aq(nudot) and Pieces.Wnu from the workspace the last ReducedDerivatives::run(ev, q, nu, tau) left (its
  // passes at a = S nudot + w and at v: d(A a)/dq, d(A v)/dq): -K^-1 (d(K a)/dq + dgamma) and -K^-1 dgamma/dv S.
  static derivs::ForceChain chain(Ev& ev, const derivs::Result& r) {
    auto& ws = ev.deriv_;
    if (ws.dAa.rows() != ev.nrows() || ws.dAa.cols() != ev.nv_ || ws.dAv.rows() != ev.nrows())
      throw std::logic_error("the chain needs the derivatives' run first");
    derivs::ForceChain out;
    out.a = r.S * r.nudot + ev.w_;
    const MatrixXd dgam_v = ws.Adot + ws.dAv;
    MatrixXd dKa = ws.dAa + ws.dgam_q + dgam_v * r.Vq;
    out.Aq = RD::solve_neg(ev, dKa);
    out.Wnu = RD::solve_neg(ev, dgam_v * r.S);
    return out;
  }

  // Layer 1 (force_derivatives.layer) at (q, v, a, tau): kstiff the wheels' normal stiffnesses (wheel order),
  // unloaded the wheels the rigid limit holds at zero load (wheel indices), split whether open loads are split.
  static derivs::ForceLayer layer(Ev& ev, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& v,
                                  const Eigen::Ref<const VectorXd>& a, const Eigen::Ref<const VectorXd>& tau,
                                  const Eigen::Ref<const VectorXd>& kstiff, const std::vector<int>& unloaded,
                                  bool split) {
    if (ev.operational_) throw std::domain_error("operational-space velocities: force derivatives on the Python path");
    if (!ev.slips_.empty()) throw std::domain_error("slipping wheels: force derivatives on the Python path");
    if (ev.nv_ > derivs::kMaxNv) throw std::domain_error("more coordinates than the derivative kernels' blocks hold");
    const int n = ev.nv_;
    if (v.size() != n || a.size() != n || tau.size() != static_cast<Eigen::Index>(ev.motors_.size()))
      throw std::invalid_argument("v, a or tau has the wrong length");
    const int nw = static_cast<int>(ev.wheels_.size());
    if (kstiff.size() != nw || !(kstiff.array() > 0.0).all())
      throw std::invalid_argument("one positive normal stiffness per wheel");
    ev.configure(q);
    const Model& model = ev.model_;
    auto& ws = ev.deriv_;
    const int m = ev.nrows();
    const MatrixXd& A = ev.A_;
    const MatrixXd& B = ev.B_;
    derivs::ForceLayer out;
    // the contact geometry's derivatives (configuration level), read by velocity_dq
    ws.geo.resize(ev.wheels_.size());
    for (size_t i = 0; i < ev.wheels_.size(); ++i)
      derivs::wheel_geometry_dq(ev.geo_[i], ev.Jf_[ev.wheels_[i].frame], ev.wheels_[i].radius_index,
                                ev.terrain_.flat(), ws.geo[i]);
    // one frame pass per unit velocity e_j: d(A e_j)/dq (column j of A differentiated, m x n); the motors'
    // d(B tau)/dq (ReducedDerivatives::motor_force_dq)
    std::vector<MatrixXd> dAj(n);
    MatrixXd dBt = MatrixXd::Zero(n, n);
    RD::motor_force_dq(ev, tau, dBt);
    derivs::FramePass fp;
    for (int j = 0; j < n; ++j) {
      fp.run(model, ev.q_, VectorXd::Unit(n, j), false);
      RD::prepare(ev, fp, false);
      RD::velocity_dq(ev, fp, dAj[j]);
    }
    // the tree at (q, v, a) with gravity: e, de/dq, de/dv and M
    if (!ws.has_tree) {
      ws.tree = pinocchio::Data(model);
      ws.has_tree = true;
    }
    MatrixXd dR_q = MatrixXd::Zero(n, n), dR_v = MatrixXd::Zero(n, n), M = MatrixXd::Zero(n, n);
    ev.model_.gravity = ev.gravity_;
    try {
      pinocchio::computeRNEADerivatives(model, ws.tree, ev.q_, VectorXd(v), VectorXd(a), dR_q, dR_v, M);
    } catch (...) {
      ev.model_.gravity.setZero();
      throw;
    }
    ev.model_.gravity.setZero();
    kernels::subtract_joint_springs_derivatives(ev.springs_, ev.q_, v, ws.tree.tau, dR_q, dR_v);  // e and its
    // derivatives less the joint springs' Q (joint_springs_derivatives.hpp; contact/force_derivatives.py's twin)
    M.triangularView<Eigen::StrictlyLower>() = M.transpose().triangularView<Eigen::StrictlyLower>();
    const VectorXd e = ws.tree.tau - B * tau;
    const MatrixXd de_q = dR_q - dBt;
    if (m == 0) {
      out.lam.resize(0);
      out.dq.resize(0, n);
      out.dv.resize(0, n);
      out.da.resize(0, n);
      out.dtau.resize(0, B.cols());
      return out;
    }
    // the structure: null space of A^T, open directions, the split's W and C_U
    Eigen::JacobiSVD<MatrixXd> svdA(A.transpose(), Eigen::ComputeFullV);
    const VectorXd& sA = svdA.singularValues();
    const double tolA = (sA.size() ? sA.maxCoeff() : 0.0) * std::max(m, n) * std::numeric_limits<double>::epsilon();
    int rank = 0;
    for (int i = 0; i < sA.size(); ++i) rank += sA[i] > tolA;
    const int d = m - rank;
    const MatrixXd N = svdA.matrixV().rightCols(d);
    MatrixXd C = MatrixXd::Zero(nw, m);
    for (int i = 0; i < nw; ++i)
      for (int r = 0; r < ev.wheels_[i].D.rows(); ++r) C(i, ev.geo_[i].row + r) = ev.wheels_[i].D(r, 2);
    MatrixXd W = MatrixXd::Zero(m, m);
    MatrixXd CU = MatrixXd::Zero(0, m);
    MatrixXd opened = N;
    bool split_on = false;
    if (d && nw && split) {
      const MatrixXd P = C * N;
      bool any_open = false;
      for (int i = 0; i < nw; ++i) any_open = any_open || P.row(i).norm() > 1e-8;  // DETERMINED_TOL
      const double scale = std::max(A.cwiseAbs().maxCoeff(), 1.0);
      bool inert = false;
      for (int r = 0; r < m; ++r) inert = inert || A.row(r).cwiseAbs().maxCoeff() <= 1e-12 * scale;
      if (any_open && !inert) {
        Eigen::JacobiSVD<MatrixXd> svdP(P, Eigen::ComputeFullV);
        const VectorXd& sp = svdP.singularValues();
        int p = 0;
        for (int i = 0; i < sp.size(); ++i) p += sp[i] > 1e-9;  // rigid_limit.RANK_TOL
        if (p) {
          opened = N * svdP.matrixV().rightCols(d - p);
          const VectorXd kinv = kstiff.mean() * kstiff.cwiseInverse();
          W = C.transpose() * kinv.asDiagonal() * C;
          CU.resize(static_cast<int>(unloaded.size()), m);
          for (size_t u = 0; u < unloaded.size(); ++u) {
            if (unloaded[u] < 0 || unloaded[u] >= nw) throw std::invalid_argument("unloaded wheel index out of range");
            CU.row(u) = C.row(unloaded[u]);
          }
          split_on = true;
        }
      }
    }
    const MatrixXd Po = opened * opened.transpose();
    const int un = static_cast<int>(CU.rows());
    const bool withC = split_on && W.cwiseAbs().maxCoeff() > 0.0;
    MatrixXd Z(n + (withC ? nw : 0), m);
    Z.topRows(n) = A.transpose();
    if (withC) Z.bottomRows(nw) = C;
    const int zr = m - static_cast<int>(opened.cols());
    const MatrixXd Zp = derivs::truncated_pinv(Z, zr);  // (m, rows of Z)
    const int s = m + n + un;
    MatrixXd H = MatrixXd::Zero(s, s);
    H.topLeftCorner(m, m) = W + Po;
    H.block(0, m, m, n) = A;
    H.block(m, 0, n, m) = A.transpose();
    if (un) {
      H.block(0, m + n, m, un) = CU.transpose();
      H.block(m + n, 0, un, m) = CU;
    }
    const MatrixXd Hp = derivs::truncated_pinv(H, m + rank + un);  // u is determined up to null(A)
    const auto Hl = Hp.topRows(m);
    out.lam = Hl.middleCols(m, n) * e;
    const VectorXd u = Hp.middleRows(m, n).middleCols(m, n) * e;
    {
      VectorXd X(s), rhs = VectorXd::Zero(s);
      X << out.lam, u, Hp.bottomRows(un).middleCols(m, n) * e;
      rhs.segment(m, n) = e;
      out.residual = (H * X - rhs).norm() / std::max(e.norm(), 1.0);
    }
    // q: -dP_o lambda - dA u (r1), de - dA^T lambda (r2), dA = dA/dq_p (column j from dAj[j].col(p))
    const MatrixXd Zpn = Zp.leftCols(n);  // Z^+ dZ = Zpn dA^T (the rows of C do not move)
    const VectorXd Pl = Po * out.lam, zl = Zpn.transpose() * out.lam;
    MatrixXd r1(m, n), r2 = de_q, dA(m, n);
    for (int p = 0; p < n; ++p) {
      for (int j = 0; j < n; ++j) dA.col(j) = dAj[j].col(p);
      r1.col(p) = Zpn * (dA.transpose() * Pl) + Po * (dA * zl) - dA * u;
    }
    for (int j = 0; j < n; ++j) r2.row(j) -= out.lam.transpose() * dAj[j];
    const MatrixXd H1 = Hl.leftCols(m), H2 = Hl.middleCols(m, n);
    out.dq = H1 * r1 + H2 * r2;
    out.dv = H2 * dR_v;
    out.da = H2 * M;
    out.dtau = -(H2 * B);
    return out;
  }
};

}  // namespace robotdyn

// robotdyn/kernels/reduced_dynamics_derivatives.hpp: derivatives of the reduced forward dynamics nudot(q, nu, tau),
// twin of robotdyn/reduction/dynamics_derivatives.py (pieces, Pieces.Aq, motor_rows, dynamics_derivatives), the same
// formulas: the projection's chain rule (dS = -K^-1 dK S, dw = -K^-1 (dK w + d gamma)), the multiplier
// mu = K^-T rho, Pinocchio's computeRNEADerivatives for the tree, the motors' reaction terms and the reduced solve;
// the per-constraint pieces are the <kind>_derivatives.hpp beside this file. Three differ from the Python path's in
// form, not in value: the multiplier term S^T d(A^T mu)/dq is one derivative of the constraint forces at fixed mu
// (force_dq: each kind's <kind>_force_dq, twins in constraints/row_derivatives.py, and the motors' d(B tau)/dq,
// motor_force_dq), where the Python path sums mu_r d(A S_l)/dq over one frame pass per column of S; and d(A a)/dq at
// a = S nudot + w is one velocity pass at a, where the Python path adds its passes at w and at S's columns (A x is
// linear in x). So run() takes two frame passes (at a, velocity-only, and at v with accelerations) whatever k; and
// the projection's pieces Aq and W_nu enter only through S^T M Aq and S^T M W_nu, taken by one adjoint solve of k
// columns, Z = K^-T (S^T M_d)^T, rather than formed (a solve of n + k columns, the Python path's Pieces.Aq, .Wnu).
// tests/test_compiled_derivatives*.py hold it to the Python path (1e-10), tests/test_force_dq.py the force
// derivatives to the rows' derivatives at the unit velocities (1e-12).
//
// Served here: independent velocities that are a selection of v (operational-space velocities and slipping wheels
// throw, and the Python side takes its reference path). The evaluator hands over its state after configure(q)
// and dynamics(nu) (S, v, w, A, M, B, M_r, h_r, B_r, the LU factors of A_d) through the friend ReducedDerivatives.
#pragma once

#include <pinocchio/algorithm/rnea-derivatives.hpp>

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "frame_derivatives.hpp"
#include "joint_coupling_derivatives.hpp"
#include "joint_springs_derivatives.hpp"
#include "loop_closure_derivatives.hpp"
#include "rolling_contact_derivatives.hpp"

namespace robotdyn {
namespace derivs {

// Work buffers kept by the evaluator between calls (Pinocchio data of the passes and of the tree derivatives).
struct Workspace {
  std::vector<FramePass> passes;  // columns of S, then w, then v (frame_passes: the operational-space kernels)
  FramePass pass_a, pass_v;       // run(): velocity-only at a = S nudot + w, and at v with accelerations
  std::vector<FramePass> units;   // at the unit vectors (sliding_derivatives.hpp: every column of dA/dq)
  pinocchio::Data tree;
  bool has_tree = false;
  std::vector<MatrixXd> dA;  // d(A x)/dq per pass (m x n)
  std::vector<WheelGeometryDq> geo;
  MatrixXd dgam_q, Adot;
  // the rows' nonzero columns (zero blocks: a wheel's rows depend on q only through its frame's supporting joints and
  // its radius coordinate, a closure's through its two frames' supporting joints): per wheel and per closure the
  // sorted columns, the wheels' geometry derivatives and the closures' frame Jacobians on them (frame_passes), and
  // gather buffers (velocity_dq with `compact`), one set per wheel and per closure: each keeps its size between
  // calls (shared buffers resized from one row's column count to the next reallocated on every derivative set)
  std::vector<std::vector<int>> wheel_cols, closure_cols;
  std::vector<int> radius_col;  // a wheel's radius column among its columns, or -1
  std::vector<WheelGeometryDq> geoc;
  std::vector<Matrix6x> cJ1, cJ2;
  struct Gathered {
    Matrix6x J, dV1, dV2, dA1, dA2, dJ1, dJ2;
    MatrixXd out, out2, Aw, F;  // F: the force derivative's block on the columns (force_dq)
  };
  std::vector<Gathered> wheel_gather, closure_gather;
  // run()'s work matrices, kept between calls (sized on first use: no allocation per derivative set)
  MatrixXd dtau_dq, dtau_dv, dtau_da, X, Y, Vd, Xg, Xgd, X2, G, ST, STM, Minv, T, T2;
  MatrixXd Z, XgS, STT;  // run()'s adjoint: K^-T (S^T M_d)^T, d(K gamma)/dv S, S^T (dtau/dv S + M W_nu)
  MatrixXd dAa, dAv, Tf, Cd;  // run(): d(A a)/dq, d(A v)/dq, d(A^T mu + B tau)/dq at fixed (mu, tau), C_d
  VectorXd a, rho, rd, mu, muf;
};

// The outputs (DynamicsDerivatives' analytic contents, SI units).
struct Result {
  VectorXd nudot;  // (k)
  MatrixXd dq;     // (k, n) natural coordinates
  MatrixXd dnu;    // (k, k)
  MatrixXd dtau;   // (k, motors)
  VectorXd v;      // qdot = S nu (n)
  MatrixXd Vq;     // d(S nu)/dq (n, n)
  MatrixXd S;      // (n, k)
  MatrixXd A;      // all constraint rows at q (m, n)
};

}  // namespace derivs

template <class Ev>
struct ReducedDerivatives {
  using Model = pinocchio::Model;
  using MatrixXd = Eigen::MatrixXd;
  using VectorXd = Eigen::VectorXd;
  using Matrix3d = Eigen::Matrix3d;

  // an m x n matrix of the rows' derivatives (ws.dAa, ws.dAv, ws.dgam_q, ws.Adot) zeroed only when first sized: on
  // the compact columns every row is written on the same columns at every state (a wheel's and a closure's own
  // columns, compact_columns; a coupling's whole row), so its other entries stay the zeros of that first call
  static void zero_once(MatrixXd& m, int rows, int cols) {
    if (m.rows() != rows || m.cols() != cols) m.setZero(rows, cols);
  }

  // d(A x)/dq of every row at the pass's x (velocity_dq), stacked in constraint order. With `compact` (after
  // frame_passes' column lists) each wheel's and closure's formulas run on their nonzero columns only, gathered, and
  // are scattered back: the same formulas, column by column, on fewer columns
  static void velocity_dq(Ev& ev, derivs::FramePass& fp, MatrixXd& out, bool compact = false) {
    const Model& model = ev.model_;
    auto& ws = ev.deriv_;
    if (compact)
      zero_once(out, ev.nrows(), ev.nv_);
    else
      out.setZero(ev.nrows(), ev.nv_);
    for (const auto& [kind, i] : ev.order_) {
      if (kind == 0) {
        const auto& wh = ev.wheels_[i];
        const auto& g = ev.geo_[i];
        const int fid = ev.frames_[wh.frame];
        const auto& J = ev.Jf_[wh.frame];
        fp.velocity(model, fid, ev.data_.oMf[fid], J);
        const double xR = wh.radius_index >= 0 ? fp.x[wh.radius_index] : 0.0;
        const int nd = static_cast<int>(wh.D.rows());
        if (compact) {
          const std::vector<int>& cols = ws.wheel_cols[i];
          auto& gb = ws.wheel_gather[i];
          derivs::gather_cols(fp.dV[fid], cols, gb.dV1);
          gb.out.resize(nd, static_cast<int>(cols.size()));
          derivs::wheel_velocity_dq(g, ws.geoc[i], wh.D, fp.V[fid], gb.dV1, xR, gb.out);
          derivs::scatter_cols(gb.out, cols, out.middleRows(g.row, nd));
        } else {
          derivs::wheel_velocity_dq(g, ws.geo[i], wh.D, fp.V[fid], fp.dV[fid], xR, out.middleRows(g.row, nd));
        }
      } else if (kind == 1) {
        const auto& c = ev.closures_[i];
        const int row = closure_row(ev, i), nr = static_cast<int>(c.select.size());
        const int f1 = ev.frames_[c.f1], f2 = ev.frames_[c.f2];
        auto fr = frames_of(ev, c);
        prepare_closure(ev, fp, c);
        if (compact) {
          const std::vector<int>& cols = ws.closure_cols[i];
          auto& gb = ws.closure_gather[i];
          fr.J1 = &ws.cJ1[i];
          fr.J2 = &ws.cJ2[i];
          derivs::gather_cols(fp.dV[f1], cols, gb.dV1);
          derivs::gather_cols(fp.dV[f2], cols, gb.dV2);
          gb.out.resize(nr, static_cast<int>(cols.size()));
          derivs::closure_velocity_dq(fr, c.select, fp.V[f1], gb.dV1, fp.V[f2], gb.dV2, gb.out);
          derivs::scatter_cols(gb.out, cols, out.middleRows(row, nr));
        } else {
          derivs::closure_velocity_dq(fr, c.select, fp.V[f1], fp.dV[f1], fp.V[f2], fp.dV[f2], out.middleRows(row, nr));
        }
      } else {
        const auto& c = ev.couplings_[i];
        const derivs::CosineCoupling cc{c.i, c.j, c.amplitude, c.rate, c.phase};
        derivs::coupling_velocity_dq(cc, ev.q_[c.j], fp.x[c.j], out.middleRows(coupling_row(ev, i), 1));
      }
    }
  }

  // first row of closure i / coupling i (rows follow order_; wheels record theirs in their geometry)
  static int closure_row(const Ev& ev, size_t which) { return row_of(ev, 1, which); }
  static int coupling_row(const Ev& ev, size_t which) { return row_of(ev, 2, which); }
  static int row_of(const Ev& ev, int kind_, size_t which) {
    int row = 0;
    for (const auto& [kind, i] : ev.order_) {
      if (kind == kind_ && static_cast<size_t>(i) == which) return row;
      row += kind == 0 ? static_cast<int>(ev.wheels_[i].D.rows())
                       : kind == 1 ? static_cast<int>(ev.closures_[i].select.size()) : 1;
    }
    return row;
  }

  template <class C>
  static derivs::ClosureFrames frames_of(Ev& ev, const C& c) {
    const int f1 = ev.frames_[c.f1], f2 = ev.frames_[c.f2];
    derivs::ClosureFrames fr;
    fr.R1 = ev.data_.oMf[f1].rotation();
    fr.p1 = ev.data_.oMf[f1].translation();
    fr.p2 = ev.data_.oMf[f2].translation();
    fr.J1 = &ev.Jf_[c.f1];
    fr.J2 = &ev.Jf_[c.f2];
    return fr;
  }

  // the frames' velocities in a pass (the closures' velocity_dq reads them from the cache)
  static void prepare(Ev& ev, derivs::FramePass& fp, bool accelerations) {
    const Model& model = ev.model_;
    for (const auto& c : ev.closures_) {
      prepare_closure(ev, fp, c);
      if (accelerations)
        for (int f : {c.f1, c.f2}) fp.acceleration(model, ev.frames_[f], ev.data_.oMf[ev.frames_[f]], ev.Jf_[f]);
    }
  }
  template <class C>
  static void prepare_closure(Ev& ev, derivs::FramePass& fp, const C& c) {
    for (int f : {c.f1, c.f2}) fp.velocity(ev.model_, ev.frames_[f], ev.data_.oMf[ev.frames_[f]], ev.Jf_[f]);
  }

  // the columns a joint's world Jacobian and velocity derivatives can be nonzero in: its supporting joints' (sorted)
  static void support_cols(const Model& model, pinocchio::JointIndex jid, std::vector<int>& cols) {
    for (const pinocchio::JointIndex s : model.supports[jid]) {
      if (s == 0) continue;
      for (int c = model.idx_vs[s]; c < model.idx_vs[s] + model.nvs[s]; ++c)
        cols.push_back(c);
    }
  }

  // frame_passes' column lists and the quantities gathered on them once per state (the workspace's, above)
  static void compact_columns(Ev& ev) {
    const Model& model = ev.model_;
    auto& ws = ev.deriv_;
    const size_t nw = ev.wheels_.size(), nc = ev.closures_.size();
    ws.wheel_cols.resize(nw);
    ws.radius_col.assign(nw, -1);
    ws.geoc.resize(nw);
    ws.wheel_gather.resize(nw);
    for (size_t i = 0; i < nw; ++i) {
      const auto& wh = ev.wheels_[i];
      std::vector<int>& cols = ws.wheel_cols[i];
      cols.clear();
      support_cols(model, model.frames[ev.frames_[wh.frame]].parentJoint, cols);
      if (wh.radius_index >= 0 && std::find(cols.begin(), cols.end(), wh.radius_index) == cols.end()) {
        cols.push_back(wh.radius_index);
        std::sort(cols.begin(), cols.end());
      }
      if (wh.radius_index >= 0)
        ws.radius_col[i] = static_cast<int>(std::find(cols.begin(), cols.end(), wh.radius_index) - cols.begin());
      derivs::gather_cols(ev.Jf_[wh.frame], cols, ws.wheel_gather[i].J);  // (J and Aw at q: drift_dq's, force_dq's)
      derivs::gather_cols(ev.Aw_[i], cols, ws.wheel_gather[i].Aw);
      derivs::wheel_geometry_dq(ev.geo_[i], ws.wheel_gather[i].J, ws.radius_col[i], ev.terrain_.flat(), ws.geoc[i]);
    }
    ws.closure_cols.resize(nc);
    ws.cJ1.resize(nc);
    ws.cJ2.resize(nc);
    ws.closure_gather.resize(nc);
    for (size_t i = 0; i < nc; ++i) {
      const auto& c = ev.closures_[i];
      std::vector<int>& cols = ws.closure_cols[i];
      cols.clear();
      support_cols(model, model.frames[ev.frames_[c.f1]].parentJoint, cols);
      support_cols(model, model.frames[ev.frames_[c.f2]].parentJoint, cols);
      std::sort(cols.begin(), cols.end());
      cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
      derivs::gather_cols(ev.Jf_[c.f1], cols, ws.cJ1[i]);
      derivs::gather_cols(ev.Jf_[c.f2], cols, ws.cJ2[i]);
    }
  }

  // drift_dq and Adot of every row on the pass at v
  static void drift_dq(Ev& ev, derivs::FramePass& fp, MatrixXd& dgam, MatrixXd& Adot) {
    const Model& model = ev.model_;
    auto& ws = ev.deriv_;
    zero_once(dgam, ev.nrows(), ev.nv_);
    zero_once(Adot, ev.nrows(), ev.nv_);
    for (const auto& [kind, i] : ev.order_) {
      if (kind == 0) {
        const auto& wh = ev.wheels_[i];
        const auto& g = ev.geo_[i];
        const int fid = ev.frames_[wh.frame];
        const auto& J = ev.Jf_[wh.frame];
        fp.acceleration(model, fid, ev.data_.oMf[fid], J);
        const int nd = static_cast<int>(wh.D.rows());
        // on the wheel's nonzero columns (compact_columns), scattered back
        const std::vector<int>& cols = ws.wheel_cols[i];
        const int nc = static_cast<int>(cols.size());
        auto& gb = ws.wheel_gather[i];
        derivs::gather_cols(fp.dV[fid], cols, gb.dV1);  // (gb.J, gb.Aw: compact_columns')
        derivs::gather_cols(fp.dAcc[fid], cols, gb.dA1);
        fp.jacobian_dot(model, fid, cols, gb.dJ1);
        gb.out.resize(nd, nc);
        gb.out2.resize(nd, nc);
        derivs::wheel_drift_dq(g, ws.geoc[i], wh.D, ev.terrain_, ev.terrain_.flat(), gb.J, wh.radius_index,
                               ws.radius_col[i], fp.x, fp.V[fid], gb.dV1, fp.Acc[fid], gb.dA1, gb.dJ1, gb.Aw,
                               gb.out, gb.out2);
        derivs::scatter_cols(gb.out, cols, dgam.middleRows(g.row, nd));
        derivs::scatter_cols(gb.out2, cols, Adot.middleRows(g.row, nd));
      } else if (kind == 1) {
        const auto& c = ev.closures_[i];
        const int row = closure_row(ev, i), nr = static_cast<int>(c.select.size());
        const int f1 = ev.frames_[c.f1], f2 = ev.frames_[c.f2];
        // on the closure's nonzero columns (compact_columns), scattered back
        const std::vector<int>& cols = ws.closure_cols[i];
        const int nc = static_cast<int>(cols.size());
        auto& gb = ws.closure_gather[i];
        auto fr = frames_of(ev, c);
        fr.J1 = &ws.cJ1[i];
        fr.J2 = &ws.cJ2[i];
        derivs::gather_cols(fp.dV[f1], cols, gb.dV1);
        derivs::gather_cols(fp.dV[f2], cols, gb.dV2);
        derivs::gather_cols(fp.dAcc[f1], cols, gb.dA1);
        derivs::gather_cols(fp.dAcc[f2], cols, gb.dA2);
        fp.jacobian_dot(model, f1, cols, gb.dJ1);
        fp.jacobian_dot(model, f2, cols, gb.dJ2);
        gb.out.resize(nr, nc);
        gb.out2.resize(nr, nc);
        derivs::closure_drift_dq(fr, c.select, fp.V[f1], gb.dV1, fp.V[f2], gb.dV2, fp.Acc[f1], gb.dA1, fp.Acc[f2],
                                 gb.dA2, gb.dJ1, gb.dJ2, gb.out, gb.out2);
        derivs::scatter_cols(gb.out, cols, dgam.middleRows(row, nr));
        derivs::scatter_cols(gb.out2, cols, Adot.middleRows(row, nr));
      } else {
        const auto& c = ev.couplings_[i];
        const derivs::CosineCoupling cc{c.i, c.j, c.amplitude, c.rate, c.phase};
        const int row = coupling_row(ev, i);
        derivs::coupling_drift_dq(cc, ev.q_[c.j], fp.x[c.j], dgam.middleRows(row, 1), Adot.middleRows(row, 1));
      }
    }
  }

  // -K^-1 [X_rows] for the selection projection (Projection.solve_neg): zero except the dependent rows (the
  // operational-space, sliding and contact-force derivative kernels use it; run() makes its own two solves)
  static MatrixXd solve_neg(Ev& ev, const MatrixXd& X) {
    const int nd = static_cast<int>(ev.dependent_.size());
    MatrixXd out = MatrixXd::Zero(ev.nv_, X.cols());
    if (nd == 0) return out;
    MatrixXd Xr(nd, X.cols());
    for (int r = 0; r < nd; ++r) Xr.row(r) = X.row(ev.rows_[r]);
    const MatrixXd Y = ev.lu_.solve(Xr);
    for (int r = 0; r < nd; ++r) out.row(ev.dependent_[r]) = -Y.row(r);
    return out;
  }

  static derivs::Result run(Ev& ev, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                            const Eigen::Ref<const VectorXd>& tau) {
    if (ev.operational_) throw std::domain_error("operational-space velocities: derivatives on the Python path");
    if (!ev.slips_.empty()) throw std::domain_error("slipping wheels: derivatives on the Python path");
    if (ev.nv_ > derivs::kMaxNv) throw std::domain_error("more coordinates than the derivative kernels' blocks hold");
    ev.configure(q);
    ev.dynamics(nu);
    if (tau.size() != ev.Br_.cols()) throw std::invalid_argument("tau has the wrong length");
    auto& ws = ev.deriv_;
    const int n = ev.nv_;
    const MatrixXd& S = ev.S_;
    const VectorXd& w = ev.w_;
    const MatrixXd& M = ev.data_.M;  // symmetric (dynamics)
    derivs::Result out;
    const Eigen::LLT<MatrixXd> llt = reduced_mass(ev, tau, out);
    VectorXd& a = ws.a;  // (the work matrices are the workspace's: no allocation once sized)
    a.noalias() = S * out.nudot;
    a += w;
    run_passes(ev, a);
    const MatrixXd& dA_v = ws.dAv;
    // the projection's solves. With K^-1 on the dependent rows (K = A_d, the rows rows_ and columns dependent_):
    // dv/dq = -K^-1 d(K v)/dq (v = S(q) nu), an output (Vq), one solve of n columns. The two other pieces of the
    // Python path (Pieces.Aq, Pieces.Wnu), Aq = -K^-1 (d(K a)/dq + dgamma/dq at fixed v + d(K gamma)/dv dv/dq) and
    // W_nu = -K^-1 d(K gamma)/dv S, enter the reduced dynamics only through (S^T M) Aq and (S^T M) W_nu, which are
    // zero off the dependent rows: (S^T M_d) K^-1 X = Z^T X with Z = K^-T (S^T M_d)^T, one transposed solve of k
    // columns (the adjoint) instead of a solve of n + k (the contact forces' chain forms Aq and W_nu itself,
    // ContactForcesDerivatives::chain)
    const int nd = static_cast<int>(ev.dependent_.size());
    out.Vq = MatrixXd::Zero(n, n);
    MatrixXd& ST = ws.ST;
    ST = S.transpose();
    MatrixXd& STM = ws.STM;  // S^T C_d for a matrix C's dependent columns C_d (ws.Cd)
    MatrixXd& Cd = ws.Cd;
    MatrixXd& Xa = ws.X2;  // d(K a)/dq + dgamma/dq at fixed v
    MatrixXd& Xg = ws.Xg;  // d(K gamma)/dv
    MatrixXd& Z = ws.Z;
    if (nd) {
      MatrixXd& X = ws.X;  // d(K v)/dq
      X.resize(nd, n);
      Xg.resize(nd, n);
      Xa.resize(nd, n);
      for (int r = 0; r < nd; ++r) {
        const int row = ev.rows_[r];
        X.row(r) = dA_v.row(row);
        Xg.row(r) = ws.Adot.row(row) + dA_v.row(row);  // d gamma / dv = Adot + d(A v)/dq
        Xa.row(r) = ws.dAa.row(row) + ws.dgam_q.row(row);  // d(A a)/dq = d(A w)/dq + sum_l nudot_l d(A S_l)/dq
      }
      MatrixXd& Y = ws.Y;
      Y = ev.lu_.solve(X);
      MatrixXd& Vd = ws.Vd;  // dependent rows of dv/dq
      Vd = -Y;
      for (int r = 0; r < nd; ++r) out.Vq.row(ev.dependent_[r]) = Vd.row(r);
      Cd.resize(n, nd);
      for (int r = 0; r < nd; ++r) Cd.col(r) = M.col(ev.dependent_[r]);
      STM.noalias() = ST * Cd;  // S^T M_d (k x nd)
      Z = ev.lu_.transpose().solve(STM.transpose());
    }
    // the tree: RNEA(q, v, a) and its derivatives, with gravity
    MatrixXd& dtau_dq = ws.dtau_dq;
    MatrixXd& dtau_dv = ws.dtau_dv;
    tree(ev, a, dtau_dq, dtau_dv);
    VectorXd& rho = ws.rho;
    rho.noalias() = ev.B_ * tau;
    rho = ws.tree.tau - rho;
    // dS^T rho = -S^T dK^T mu, mu = A_d^-T rho_d: the multiplier term L = S^T d(A^T mu)/dq at fixed mu (sum_r mu_r
    // d(A S_l)/dq row by row, the Python path's) as ONE derivative of the constraint force, with the motors'
    // d(B tau)/dq (motor_rows' terms) in the same matrix: Tf = d(A^T mu + B tau)/dq (force_dq)
    VectorXd& muf = ws.muf;  // mu on the constraint rows
    muf.setZero(ev.nrows());
    if (nd) {
      VectorXd& rd = ws.rd;
      rd.resize(nd);
      for (int r = 0; r < nd; ++r) rd[r] = rho[ev.dependent_[r]];
      VectorXd& mu = ws.mu;
      mu = ev.lu_.transpose().solve(rd);
      for (int r = 0; r < nd; ++r) muf[ev.rows_[r]] = mu[r];
    }
    force_dq(ev, muf, tau, ws.Tf);
    MatrixXd& G = ws.G;  // S^T (dtau_dq - Tf) + (S^T dtau_dv) Vq + (S^T M) Aq
    dtau_dq -= ws.Tf;
    G.noalias() = ST * dtau_dq;
    MatrixXd& STT = ws.STT;  // S^T (dtau_dv S + M W_nu)
    ws.T.noalias() = dtau_dv * S;
    STT.noalias() = ST * ws.T;
    if (nd) {
      // Vq and Aq are zero off the dependent rows: (S^T C) Vq = (S^T C_d) V_d, and (S^T M) Aq = -Z^T (Xa + Xg_d V_d)
      // with Xg_d = d(K gamma)/dv's dependent columns: G += (S^T C_d - Z^T Xg_d) V_d - Z^T Xa
      for (int r = 0; r < nd; ++r) Cd.col(r) = dtau_dv.col(ev.dependent_[r]);
      STM.noalias() = ST * Cd;
      MatrixXd& Xgd = ws.Xgd;
      Xgd.resize(nd, nd);
      for (int r = 0; r < nd; ++r) Xgd.col(r) = Xg.col(ev.dependent_[r]);
      STM.noalias() -= Z.transpose() * Xgd;
      G.noalias() += STM * ws.Vd;
      G.noalias() -= Z.transpose() * Xa;
      // (S^T M) W_nu = -Z^T (Xg S)
      ws.XgS.noalias() = Xg * S;
      STT.noalias() -= Z.transpose() * ws.XgS;
    }
    solve_reduced(ev, llt, G, STT, out);
    return out;
  }

  // run()'s passes at the evaluator's state (configure(q), dynamics(nu) done): the rows' d(A a)/dq at a = S nudot +
  // w on a velocity-only pass (FramePass::run_velocities on the evaluator's configuration pass; A x is linear in x,
  // so this is d(A w)/dq + sum_l nudot_l d(A S_l)/dq in one pass), and d(A v)/dq, the drift's dgamma/dq and Adot on
  // the pass at v with accelerations (ws.dAa, ws.dAv, ws.dgam_q, ws.Adot; FramePass::run_on, on the evaluator's
  // bias pass at v), every row on its own columns; `full`:
  // the pass at a is a Pinocchio pass of its own (the LOCAL operational twist reads its data)
  static void run_passes(Ev& ev, const VectorXd& a, bool full = false) {
    const Model& model = ev.model_;
    auto& ws = ev.deriv_;
    compact_columns(ev);
    if (full)
      ws.pass_a.run(model, ev.q_, a, false);
    else
      ws.pass_a.run_velocities(model, ev.data_, a);
    velocity_dq(ev, ws.pass_a, ws.dAa, true);
    ws.pass_v.run_on(model, ev.data_, ev.v_);  // (the evaluator's bias pass at v: no forward kinematics of its own)
    prepare(ev, ws.pass_v, true);
    velocity_dq(ev, ws.pass_v, ws.dAv, true);
    drift_dq(ev, ws.pass_v, ws.dgam_q, ws.Adot);
  }

  // Tf = d(A(q)^T mu)/dq + d(B(q) tau)/dq at fixed (mu, tau) (n x n; mu on every constraint row, m): each
  // constraint's force derivative (wheel_force_dq, closure_force_dq, coupling_force_dq, beside its velocity_dq) on
  // its own columns (compact_columns first), and the motors reacting on a body (motor_force_dq). S^T Tf is the sum
  // over rows r of mu_r d(A_r S_l)/dq (the Python path's, one frame pass per column S_l) plus S^T d(B tau)/dq
  static void force_dq(Ev& ev, const VectorXd& mu, const Eigen::Ref<const VectorXd>& tau, MatrixXd& Tf) {
    const Model& model = ev.model_;
    auto& ws = ev.deriv_;
    Tf.setZero(ev.nv_, ev.nv_);
    for (const auto& [kind, i] : ev.order_) {
      if (kind == 0) {
        const auto& wh = ev.wheels_[i];
        const auto& g = ev.geo_[i];
        const int nd = static_cast<int>(wh.D.rows());
        if (mu.segment(g.row, nd).isZero(0.0)) continue;
        const int fid = ev.frames_[wh.frame];
        auto& gb = ws.wheel_gather[i];  // (gb.J, gb.Aw: compact_columns')
        derivs::wheel_force_dq(model, ev.data_.J, model.frames[fid].parentJoint, g, ws.geoc[i], wh.D,
                               mu.segment(g.row, nd), gb.J, gb.Aw, ws.wheel_cols[i], ws.radius_col[i], gb.F, Tf);
      } else if (kind == 1) {
        const auto& c = ev.closures_[i];
        const int row = closure_row(ev, i), nr = static_cast<int>(c.select.size());
        if (mu.segment(row, nr).isZero(0.0)) continue;
        auto fr = frames_of(ev, c);
        fr.J1 = &ws.cJ1[i];
        fr.J2 = &ws.cJ2[i];
        derivs::closure_force_dq(model, ev.data_.J, model.frames[ev.frames_[c.f1]].parentJoint,
                                 model.frames[ev.frames_[c.f2]].parentJoint, fr, c.select, mu.segment(row, nr),
                                 ws.closure_cols[i], ws.closure_gather[i].F, Tf);
      } else {
        const auto& c = ev.couplings_[i];
        const derivs::CosineCoupling cc{c.i, c.j, c.amplitude, c.rate, c.phase};
        derivs::coupling_force_dq(cc, ev.q_[c.j], mu[coupling_row(ev, i)], Tf);
      }
    }
    motor_force_dq(ev, tau, Tf);
  }

  // Tf += d(B(q) tau)/dq of the motors reacting on a body: B tau = sum_j tau_j (Jw_child - Jw_reaction)^T axis, a
  // pure moment tau_j axis on the joint's body and its opposite on the reaction frame's: force_jacobian_dq at fixed
  // (0, tau_j axis) on both supports plus (Jw_child - Jw_reaction)^T tau_j daxis (motor_axis); motor_rows' terms
  // x^T d(B tau)/dq for all x at once
  static void motor_force_dq(Ev& ev, const Eigen::Ref<const VectorXd>& tau, MatrixXd& Tf) {
    const Model& model = ev.model_;
    for (size_t j = 0; j < ev.motors_.size(); ++j) {
      const auto& mo = ev.motors_[j];
      if (mo.reaction < 0 || tau[j] == 0.0) continue;
      const pinocchio::JointIndex jid = static_cast<pinocchio::JointIndex>(mo.joint);
      Eigen::Vector3d axis;
      derivs::Matrix3x daxis;
      motor_axis(ev, mo, axis, daxis);
      const int rf = ev.frames_[mo.reaction];
      derivs::Vector6d phi;
      phi << Eigen::Vector3d::Zero(), tau[j] * axis;
      // the moment on the joint's body and its opposite on the reaction frame's, their pairs on the common support
      // left out (they cancel; the reaction's body an ancestor of the joint's, its pass is empty)
      const pinocchio::JointIndex rj = model.frames[rf].parentJoint;
      const size_t common = derivs::common_support(model, jid, rj);
      derivs::force_jacobian_dq(model, ev.data_.J, jid, phi, 1.0, Tf, common);
      derivs::force_jacobian_dq(model, ev.data_.J, rj, phi, -1.0, Tf, common);
      derivs::Matrix3x Jd = -ev.Jf_[mo.reaction].template bottomRows<3>();  // Jw_child - Jw_reaction
      for (const pinocchio::JointIndex s : model.supports[jid]) {
        if (s == 0) continue;
        const int c0 = model.idx_vs[s];
        for (int c = c0; c < c0 + model.nvs[s]; ++c) Jd.col(c) += ev.data_.J.col(c).template tail<3>();
      }
      Tf.noalias() += tau[j] * (Jd.transpose() * daxis);
    }
  }

  // the shared set-up of the operational-space derivative kernels at the evaluator's state (configure(q),
  // dynamics(nu) done): the contact geometry's derivatives (ws.geo), the frame passes at the columns of S, at w and
  // at v (ws.passes, the last with accelerations) with every row's d(A x)/dq there (ws.dA), then per_pass(l, pass)
  // (the operational-space rows' own), and the drift's derivatives on the pass at v (ws.dgam_q, ws.Adot)
  template <class PerPass>
  static void frame_passes(Ev& ev, PerPass&& per_pass) {
    const Model& model = ev.model_;
    auto& ws = ev.deriv_;
    const int k = static_cast<int>(ev.S_.cols());
    ws.geo.resize(ev.wheels_.size());
    for (size_t i = 0; i < ev.wheels_.size(); ++i)
      derivs::wheel_geometry_dq(ev.geo_[i], ev.Jf_[ev.wheels_[i].frame], ev.wheels_[i].radius_index,
                                ev.terrain_.flat(), ws.geo[i]);
    compact_columns(ev);
    ws.passes.resize(k + 2);
    ws.dA.resize(k + 2);
    for (int l = 0; l < k + 2; ++l) {
      derivs::FramePass& fp = ws.passes[l];
      fp.run(model, ev.q_, l < k ? VectorXd(ev.S_.col(l)) : l == k ? ev.w_ : ev.v_, l == k + 1);
      prepare(ev, fp, l == k + 1);
      velocity_dq(ev, fp, ws.dA[l], true);
      per_pass(l, fp);
    }
    drift_dq(ev, ws.passes[k + 1], ws.dgam_q, ws.Adot);
  }

  // the reduced mass matrix's factors and nudot = M_r^-1 (B_r tau - h_r + S^T Q) into out.nudot (Q: joint springs)
  static Eigen::LLT<MatrixXd> reduced_mass(Ev& ev, const Eigen::Ref<const VectorXd>& tau, derivs::Result& out) {
    Eigen::LLT<MatrixXd> llt(ev.Mr_);
    if (llt.info() != Eigen::Success) throw std::domain_error("reduced mass matrix not positive definite");
    VectorXd f = ev.Br_ * tau - ev.hr_;
    kernels::add_reduced_joint_springs(ev.springs_, ev.q_, ev.v_, ev.S_, f);  // joint springs and dampers: + S^T Q
    out.nudot = llt.solve(f);
    return llt;
  }

  // the reduced solve (dynamics_derivatives' last step): dq = -M_r^-1 G, dnu = -M_r^-1 S^T (dtau/dv S + M W_nu),
  // dtau = M_r^-1 B_r, with v, S and A (out.Vq is the caller's)
  static void solve_reduced(Ev& ev, const Eigen::LLT<MatrixXd>& llt, const MatrixXd& G, const MatrixXd& dtau_dv,
                            const MatrixXd& Wnu, derivs::Result& out) {
    const MatrixXd& S = ev.S_;
    const MatrixXd& M = ev.data_.M;
    auto& ws = ev.deriv_;  // (its work matrices: the same products, without temporaries)
    MatrixXd& T = ws.T;  // dtau_dv S + M W_nu
    T.noalias() = dtau_dv * S;
    ws.T2.noalias() = M * Wnu;
    T += ws.T2;
    ws.ST = S.transpose();
    ws.T2.noalias() = ws.ST * T;
    solve_reduced(ev, llt, G, ws.T2, out);
  }
  // the same from STT = S^T (dtau/dv S + M W_nu) (k x k)
  static void solve_reduced(Ev& ev, const Eigen::LLT<MatrixXd>& llt, const MatrixXd& G, const MatrixXd& STT,
                            derivs::Result& out) {
    const int k = static_cast<int>(ev.S_.cols());
    MatrixXd& Minv = ev.deriv_.Minv;
    Minv.setIdentity(k, k);
    llt.solveInPlace(Minv);
    out.dq.noalias() = -Minv * G;
    out.dnu.noalias() = -Minv * STT;
    out.dtau.noalias() = Minv * ev.Br_;
    out.v = ev.v_;
    out.S = ev.S_;
    out.A = ev.A_;
  }

  // RNEA(q, v, a) with gravity, less the joint springs' Q, and its q-, v-derivatives on the workspace's tree data
  // (ws.tree.tau: RNEA - Q)
  static void tree(Ev& ev, const VectorXd& a, MatrixXd& dtau_dq, MatrixXd& dtau_dv) {
    auto& ws = ev.deriv_;
    const int n = ev.nv_;
    if (!ws.has_tree) {
      ws.tree = pinocchio::Data(ev.model_);
      ws.has_tree = true;
    }
    dtau_dq.setZero(n, n);
    dtau_dv.setZero(n, n);
    MatrixXd& dtau_da = ws.dtau_da;  // (M, which the evaluation's CRBA already holds: Pinocchio fills it anyway)
    dtau_da.setZero(n, n);
    ev.model_.gravity = ev.gravity_;
    try {
      pinocchio::computeRNEADerivatives(ev.model_, ws.tree, ev.q_, ev.v_, a, dtau_dq, dtau_dv, dtau_da);
    } catch (...) {
      ev.model_.gravity.setZero();
      throw;
    }
    ev.model_.gravity.setZero();
    // joint springs and dampers (joint_springs_derivatives.hpp): tau - Q, dtau_dq - dQ/dq, dtau_dv - dQ/dv
    kernels::subtract_joint_springs_derivatives(ev.springs_, ev.q_, ev.v_, ws.tree.tau, dtau_dq, dtau_dv);
  }

  // a motor's joint axis in world axes and its q-derivative at fixed S: the joint body's world angular Jacobian
  // from CRBA's world columns (data_.J) on its supporting joints, axis = its column `index`, daxis = -[axis]x Jw
  template <class Motor>
  static void motor_axis(const Ev& ev, const Motor& mo, Eigen::Vector3d& axis, derivs::Matrix3x& daxis) {
    const Model& model = ev.model_;
    const pinocchio::JointIndex jid = static_cast<pinocchio::JointIndex>(mo.joint);
    derivs::Matrix3x Jw = derivs::Matrix3x::Zero(3, ev.nv_);
    for (const pinocchio::JointIndex s : model.supports[jid]) {
      if (s == 0) continue;
      const int c0 = model.idx_vs[s];
      for (int c = c0; c < c0 + model.nvs[s]; ++c) Jw.col(c) = ev.data_.J.col(c).template tail<3>();
    }
    axis = Jw.col(mo.index);
    daxis = -derivs::skew3(axis) * Jw;
  }
};

}  // namespace robotdyn

// robotdyn._compiled: the reduced model evaluated in one compiled call (see robotdyn/fast/compiled.py).
//
// This file is the Evaluator's orchestration and its Python bindings. The formulas are the kernels under
// robotdyn/kernels/, one header per constraint kind or reduction step, each named like its Python reference and
// opening with its formulas (the same formulas in the same order of operations as the Python path):
//   kernels/terrain.hpp            constraints/terrain.py (plane/ramp, sine, bump)
//   kernels/rolling_contact.hpp    constraints/rolling_contact.py (a wheel's geometry, rows, residual, drift)
//   kernels/loop_closure.hpp       constraints/loop_closure.py
//   kernels/joint_coupling.hpp     constraints/joint_coupling.py (cosine laws)
//   kernels/actuation.hpp          reduction/actuation.py (the motors' B)
//   kernels/projection.hpp         reduction/projection.py (_build: S = P [I; -Ad^-1 Ai], w = -Ad^-1 drift)
//   kernels/operational_space.hpp  reduction/operational_space.py (K = [A_r; J_o], K S = [0; I])
//   kernels/reduced_dynamics.hpp   reduction/reduced_dynamics.py (M_r = S^T M S, h = S^T RNEA(q, S nu, w), here
//                                  S^T (C v + g + M w): two Pinocchio passes per state, CRBA (M, g from its
//                                  composite inertias) and RNEA without gravity (C v, and the drift's accelerations))
//   kernels/pull_back.hpp          reduction/pull_back.py
//   kernels/contact_forces.hpp     contact/contact_forces.py (lambda on the projection's rows, wheel forces)
//   kernels/rigid_limit.hpp        contact/rigid_limit.py (the loads rigid-body dynamics leave open)
//   kernels/sliding.hpp            contact/sliding.py and contact/friction.py (slipping wheels, friction laws)
//   kernels/painleve.hpp           contact/painleve.py (the sliding wheels' Painleve check: a P-matrix of loads)
//   kernels/sliding_rigid_limit.hpp contact/sliding.py coupled (slipping wheels whose loads rigid statics leave open)
//   kernels/joint_springs.hpp      reduction/joint_springs.py (springs and dampers on joints)
//   kernels/joint_springs_derivatives.hpp  their terms in the derivative set and in the constraint forces
//   kernels/compliant_contact.hpp  contact/compliant_contact.py (wheels that fly and land: normal force laws)
//   kernels/compliant_rolling.hpp  contact/compliant_rolling.py (compliant wheels rolling while in contact)
//   kernels/lu_solve.hpp           LU substitutions and LAPACK's 1-norm condition estimate (used by the above)
// The rigid-body algorithms are Pinocchio's (header-only use of the installed Pinocchio 4), on a copy of the
// robot's Pinocchio model rebuilt joint by joint; tests/test_compiled*.py check every output against the Python
// path on every robot.
#include "kernels/common.hpp"
#include "kernels/terrain.hpp"
#include "kernels/rolling_contact.hpp"
#include "kernels/loop_closure.hpp"
#include "kernels/joint_coupling.hpp"
#include "kernels/actuation.hpp"
#include "kernels/lu_solve.hpp"
#include "kernels/projection.hpp"
#include "kernels/operational_space.hpp"
#include "kernels/reduced_dynamics.hpp"
#include "kernels/pull_back.hpp"
#include "kernels/contact_forces.hpp"
#include "kernels/rigid_limit.hpp"
#include "kernels/sliding.hpp"
#include "kernels/sliding_rigid_limit.hpp"
#include "_integrator.hpp"
#include "_stiff_integrator.hpp"
#include "kernels/compliant_contact.hpp"
#include "kernels/joint_springs.hpp"
#include "kernels/joint_springs_derivatives.hpp"  // (and the constraint forces' e - Q)
#include "kernels/compliant_rolling.hpp"
#include "_torque_profile.hpp"
#include "_controller.hpp"
#include "kernels/reduced_dynamics_derivatives.hpp"  // the derivatives (robotdyn/fast/compiled_derivatives.py)
#include "kernels/contact_forces_derivatives.hpp"  // (robotdyn/contact/compiled_force_derivatives.py)
#include "kernels/operational_space_derivatives.hpp"  // ... with operational-space velocities
#include "kernels/sliding_derivatives.hpp"            // ... with slipping wheels

#include <pybind11/pybind11.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <cmath>
#include <thread>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace py = pybind11;
namespace kernels = robotdyn::kernels;
using namespace robotdyn::kernels;  // pin, the Eigen names, RowMat, Matrix6x and the kernels

namespace {

// Seconds per call of f() over `repeat` calls: this thread's CPU time (the machine may be shared; no Python in the
// loop), else wall time. Used by Evaluator::profile and derivatives_seconds.
template <class F>
double call_seconds(int repeat, F&& f) {
#ifdef CLOCK_THREAD_CPUTIME_ID
  timespec a, b;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a);
  for (int i = 0; i < repeat; ++i) f();
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &b);
  return ((b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec)) / repeat;
#else
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < repeat; ++i) f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / repeat;
#endif
}

class Evaluator {
  template <class> friend struct robotdyn::ReducedDerivatives;  // kernels/reduced_dynamics_derivatives.hpp
  template <class> friend struct robotdyn::ContactForcesDerivatives;  // kernels/contact_forces_derivatives.hpp
  template <class> friend struct robotdyn::ProjectedPieces;         // kernels/operational_space_derivatives.hpp
  template <class> friend struct robotdyn::OperationalDerivatives;  // (the same)
  template <class> friend struct robotdyn::SlidingDerivatives;      // kernels/sliding_derivatives.hpp

 public:
  Evaluator(const std::vector<std::string>& kinds, const std::vector<int>& parents,
            const std::vector<MatrixXd>& placements, const std::vector<Vector3d>& axes,
            const std::vector<VectorXd>& inertias, const Vector3d& gravity)
      : nv_(0) {
    for (size_t i = 0; i < kinds.size(); ++i) {
      const MatrixXd& P = placements[i];  // (3, 4): [R | p]
      pin::SE3 placement(Matrix3d(P.leftCols<3>()), Vector3d(P.col(3)));
      const std::string& k = kinds[i];
      pin::JointIndex parent = static_cast<pin::JointIndex>(parents[i]);
      std::string name = "j" + std::to_string(i + 1);
      pin::JointIndex id;
      if (k == "RX") id = model_.addJoint(parent, pin::JointModelRX(), placement, name);
      else if (k == "RY") id = model_.addJoint(parent, pin::JointModelRY(), placement, name);
      else if (k == "RZ") id = model_.addJoint(parent, pin::JointModelRZ(), placement, name);
      else if (k == "PX") id = model_.addJoint(parent, pin::JointModelPX(), placement, name);
      else if (k == "PY") id = model_.addJoint(parent, pin::JointModelPY(), placement, name);
      else if (k == "PZ") id = model_.addJoint(parent, pin::JointModelPZ(), placement, name);
      else if (k == "RU") id = model_.addJoint(parent, pin::JointModelRevoluteUnaligned(axes[i]), placement, name);
      else if (k == "PU") id = model_.addJoint(parent, pin::JointModelPrismaticUnaligned(axes[i]), placement, name);
      else throw std::invalid_argument("unsupported joint kind " + k);
      const VectorXd& in = inertias[i];  // mass, lever (3), inertia about the COM (xx, xy, xz, yy, yz, zz)
      Matrix3d I;
      I << in[4], in[5], in[6], in[5], in[7], in[8], in[6], in[8], in[9];
      model_.appendBodyToJoint(id, pin::Inertia(in[0], Vector3d(in[1], in[2], in[3]), I), pin::SE3::Identity());
      model_.inertias[id] = pin::Inertia(in[0], Vector3d(in[1], in[2], in[3]), I);  // exactly (set_model_vector)
    }
    gravity_ = pin::Motion(gravity, Vector3d::Zero());
    model_.gravity.setZero();  // gravity enters through g_ (see configure), so RNEA gives C v alone
    nv_ = model_.nv;
    data_ = pin::Data(model_);
    zero_.setZero(nv_);
    bias_fast_ = kernels::bias_forces_apply(model_);
  }

  // ----------------------------------------------------------------------------------------------- set-up
  int add_frame(int joint, const MatrixXd& P) {
    pin::SE3 placement(Matrix3d(P.leftCols<3>()), Vector3d(P.col(3)));
    std::string name = "f" + std::to_string(frames_.size());
    frames_.push_back(static_cast<int>(model_.addFrame(
        pin::Frame(name, static_cast<pin::JointIndex>(joint), 0, placement, pin::OP_FRAME))));
    data_ = pin::Data(model_);
    crba_at_q_ = false;
    return static_cast<int>(frames_.size()) - 1;
  }
  void set_terrain(int kind, const std::vector<double>& c) {
    if (kind < 0 || kind > 2 || c.size() > 5) throw std::invalid_argument("unknown terrain");
    terrain_.kind = kind;
    for (size_t i = 0; i < c.size(); ++i) terrain_.c[i] = c[i];
  }
  void add_wheel(int frame, const Vector3d& axis, double radius, int radius_index, const MatrixXd& D) {
    if (D.cols() != 3 || D.rows() < 1 || D.rows() > 3) throw std::invalid_argument("wheel rows must be (1..3, 3)");
    order_.emplace_back(0, static_cast<int>(wheels_.size()));
    wheels_.push_back(Wheel{frame, axis, radius, radius_index, D});
    for (int r = 0; r < D.rows(); ++r) holonomic_.push_back(D(r, 2) != 0.0);
  }
  void add_closure(int f1, int f2, const std::vector<int>& select) {
    order_.emplace_back(1, static_cast<int>(closures_.size()));
    closures_.push_back(Closure{f1, f2, select});
    for (size_t r = 0; r < select.size(); ++r) holonomic_.push_back(true);
  }
  void add_coupling(int i, int j, double amplitude, double rate, double phase, double offset) {
    order_.emplace_back(2, static_cast<int>(couplings_.size()));
    couplings_.push_back(Coupling{i, j, amplitude, rate, phase, offset});
    holonomic_.push_back(true);
  }
  void add_motor(int index, int joint, int reaction) { motors_.push_back(Motor{index, joint, reaction}); }
  // A slipping wheel: wheel index, its normal row, law code and parameters (see Slip), free directions (t1, t2).
  void add_slipping(int wheel, int normal_row, int law, double p0, double p1, const Eigen::Vector2d& free) {
    if (wheel < 0 || wheel >= static_cast<int>(wheels_.size())) throw std::invalid_argument("no such wheel");
    if (normal_row < 0 || normal_row >= nrows()) throw std::invalid_argument("no such row");
    if (law < 0 || law > 1) throw std::invalid_argument("unknown friction law code");
    slips_.push_back(Slip{wheel, normal_row, law, p0, p1, free});
  }
  int slipping() const { return static_cast<int>(slips_.size()); }
  // Whether the slipping wheels' loads may be left open by the rows (a rigid chassis on four wheels): then, where
  // the projection drops rows, slip_rhs_into solves coupled's system (kernels/sliding_rigid_limit.hpp).
  void set_slip_open(bool on) { slip_open_ = on; }
  // The last slipping evaluation's multipliers on every row and the wheels held at zero load (indices among the
  // wheels), where coupled's system served it; None otherwise.
  py::object slip_multipliers() const {
    if (!slip_coupled_) return py::none();
    return py::make_tuple(slip_rl_.lam, slip_rl_.unloaded);
  }
  // The rows used and the independent velocity indices (a selection of v).
  void set_selection(const std::vector<int>& rows, const std::vector<int>& independent,
                     const std::vector<int>& dependent) {
    rows_ = rows;
    independent_ = independent;
    dependent_ = dependent;
    operational_ = false;
    selected_ = true;
    configured_ = false;
  }
  // Operational velocities: nu = J_o v with J_o the selected components of a frame's twist (local or world axes).
  void set_operational(const std::vector<int>& rows, int frame, const std::vector<int>& select, bool local) {
    rows_ = rows;
    op_frame_ = frame;
    op_select_ = select;
    op_local_ = local;
    operational_ = true;
    selected_ = true;
    configured_ = false;
  }

  int nv() const { return nv_; }
  double condition() const { return cond_; }
  py::tuple slip_condition() const { return py::make_tuple(slip_.kappa1, slip_.kappa2); }
  int nrows() const { return static_cast<int>(holonomic_.size()); }
  int mobility() const {
    return operational_ ? static_cast<int>(op_select_.size()) : static_cast<int>(independent_.size());
  }

  // The full-coordinate model at q (for the self-check against the Python model): M, g and RNEA(q, v, a).
  py::tuple full(const VectorXd& q, const VectorXd& v, const VectorXd& a) {
    model_.gravity = gravity_;
    crba_at_q_ = false, configured_ = false;  // data_ at another q: the next right-hand side configures again
    MatrixXd M = pin::crba(model_, data_, q);
    M.triangularView<Eigen::StrictlyLower>() = M.transpose().triangularView<Eigen::StrictlyLower>();
    VectorXd g = pin::computeGeneralizedGravity(model_, data_, q);
    VectorXd tau = pin::rnea(model_, data_, q, v, a);
    model_.gravity.setZero();
    return py::make_tuple(M, g, tau);
  }

  // ------------------------------------------------------------------------------------------ evaluation
  // Configuration level: kinematics, the constraint rows A, residuals, the motors' B and the projection S.
  void configure(const Eigen::Ref<const VectorXd>& q) {
    if (!selected_) throw Fallback("no projection chosen yet");
    if (q.size() != nv_) throw std::invalid_argument("q has the wrong length");
    configured_ = false;  // (until this configuration is complete)
    q_ = q;
    // one pass: placements, world joint Jacobians, M (upper triangle) and the subtrees' composite inertias, from
    // which g_k = -J_k^T (Y_subtree(k) * gravity): the torque that holds the subtree's weight
    pin::crba(model_, data_, q_, pin::Convention::WORLD);
    crba_at_q_ = true;  // (bias_pass reuses its joint placements)
    gravity_torques(model_, data_, gravity_, nv_, g_);
    rows_pass(true);
    project();
    configured_ = true;
  }

  // After CRBA's kinematics at q_: the frames' placements and Jacobians, then every constraint's rows (A, residual)
  // and, with `motors`, the motors' columns B.
  void rows_pass(bool motors) {
    for (int f : frames_) pin::updateFramePlacement(model_, data_, static_cast<pin::FrameIndex>(f));  // those used
    const int m = nrows();
    A_.setZero(m, nv_);
    residual_.setZero(m);
    geo_.resize(wheels_.size());
    Jf_.resize(frames_.size());
    for (size_t f = 0; f < frames_.size(); ++f) {
      Jf_[f].setZero(6, nv_);
      pin::getFrameJacobian(model_, data_, frames_[f], pin::LOCAL_WORLD_ALIGNED, Jf_[f]);
    }
    Aw_.resize(wheels_.size());
    constraint_rows(motors);
  }

  // Every constraint's rows (A, residual: kernels/rolling_contact, loop_closure, joint_coupling) in the rows'
  // order, and with `motors` the motors' columns B (kernels/actuation), at the configured placements and frame
  // Jacobians.
  void constraint_rows(bool motors = true) {
    int row = 0;
    for (const auto& [kind, i] : order_)
      row = kind == 0 ? wheel_rows(i, row) : kind == 1 ? closure_rows(i, row) : coupling_rows(i, row);
    if (motors) motor_columns(motors_, model_, data_, Jf_, nv_, B_);
  }

  // Every constraint's drift at v (the joint accelerations at zero joint acceleration in data_.a), then w, the
  // drift's acceleration (kernels/projection, kernels/operational_space).
  void drift_pass() {
    drift_.setZero(nrows());
    int row = 0;
    for (const auto& [kind, i] : order_)
      row = kind == 0 ? wheel_drift(i, row) : kind == 1 ? closure_drift(i, row) : coupling_drift(i, row);
    w_.setZero(nv_);
    if (operational_)
      drift_acceleration_operational(drift_, rows_, op_select_, model_, data_, frames_[op_frame_], op_local_, nv_,
                                     Kinv_, rhs_, w_);
    else
      drift_acceleration_selection(drift_, rows_, dependent_, lu_, lus_, rhs_, wd_, w_);
  }

  // State level: v = S nu, the drift, w and the dynamics.
  void dynamics(const Eigen::Ref<const VectorXd>& nu) {
    if (nu.size() != S_.cols()) throw std::invalid_argument("nu has the wrong length");
    v_.noalias() = S_ * nu;
    // one pass: RNEA(q, v, 0) without gravity = C v, whose forward sweep leaves the joint velocities and their
    // accelerations at zero joint acceleration (for the drift terms); RNEA(q, v, w) = C v + g + M w
    bias_pass();
    for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model_.njoints); ++i) data_.a[i] = data_.a_gf[i];
    drift_pass();
    reduce(data_.M, S_, g_, data_.tau, w_, B_, SM_, Mr_, hr_, gr_, Br_);
  }

  // RNEA(q_, v_, 0) into data_ (tau = C v): on CRBA's joint placements where configure left them at q_
  // (kernels/reduced_dynamics.hpp, bias_forces: the same bits), else Pinocchio's own pass.
  void bias_pass() {
    if (bias_fast_ && crba_at_q_) kernels::bias_forces(model_, data_, v_, zero_);
    else pin::rnea(model_, data_, q_, v_, zero_);
  }

  py::tuple evaluate(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
    configure(q);
    dynamics(nu);
    if (operational_) return py::make_tuple(Mr_, hr_, gr_, Br_, S_, w_, v_, A_, residual_, cond_, Kinv_);
    return py::make_tuple(Mr_, hr_, gr_, Br_, S_, w_, v_, A_, residual_, py::none(), py::none());
  }

  // The same without copies: the results stay in buffers read through the views M, h, g, B, S, w, v. Returns a
  // counter that changes whenever a buffer moved (then views taken before are stale).
  long compute(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
    configure(q);
    dynamics(nu);
    const double* now[7] = {Mr_.data(), hr_.data(), gr_.data(), Br_.data(), S_.data(), w_.data(), v_.data()};
    for (int i = 0; i < 7; ++i)
      if (now[i] != buffers_[i]) {
        std::copy(now, now + 7, buffers_);
        ++generation_;
        break;
      }
    return generation_;
  }
  const MatrixXd& Mr() const { return Mr_; }
  const VectorXd& hr() const { return hr_; }
  const VectorXd& gr() const { return gr_; }
  const MatrixXd& Br() const { return Br_; }
  const MatrixXd& S() const { return S_; }
  const VectorXd& w() const { return w_; }
  const VectorXd& v() const { return v_; }

  // d/dt of (q, nu): (S nu - alpha A_h^+ phi, M_r^-1 (B_r tau - h_r)).
  VectorXd rhs(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
               const Eigen::Ref<const VectorXd>& tau, double alpha) {
    VectorXd out(nv_ + nu.size());
    rhs_into(q, nu, tau, alpha, out);
    return out;
  }

  void rhs_into(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                const Eigen::Ref<const VectorXd>& tau, double alpha, Eigen::Ref<VectorXd> out) {
    // springs, compliant wheels: the stiff integrator's differences in nu keep q, whose configuration level is kept
    if (!(applied() && configured_ && q.size() == q_.size() && q == q_)) configure(q);
    dynamics(nu);
    const int k = static_cast<int>(S_.cols());
    if (tau.size() != Br_.cols()) throw std::invalid_argument("tau has the wrong length");
    if (out.size() != nv_ + k) throw std::invalid_argument("state has the wrong length");
    out.head(nv_) = v_;
    if (alpha != 0.0) pull_back(alpha, out);
    if (controller_) {  // a feedback law (robotdyn/_controller.hpp): the torques at this state, not the profile's
      control_tau_.resize(Br_.cols());
      controller_->eval(control_t_, q, nu, Mr_, hr_, Br_, S_, w_, v_, [this](int f) { return frame_kinematics(f); },
                        control_tau_);
      force_.noalias() = Br_ * control_tau_;
    } else {
      force_.noalias() = Br_ * tau;
    }
    force_ -= hr_;
    if (applied()) {  // joint springs, compliant wheels: + S^T Q(q, v)
      applied_forces();
      force_.noalias() += S_.transpose() * Qa_;
    }
    llt_.compute(Mr_);
    if (rolling_active()) rolling_solve(nu, alpha);  // the rows of the rolling wheels in the run's contact set
    else llt_.solveInPlace(force_);
    out.tail(k) = force_;
  }

  // ------------------------------------------------------------------------------------------ slipping wheels
  // d/dt of (q, nu, W[, W_d]) with slipping wheels (robotdyn/contact/sliding.py forward; kernels/sliding.hpp): the
  // accelerations and the normal loads from one linear system, W-dot the friction power. Joint springs and dampers
  // (kernels/joint_springs.hpp) add their Q(q, v) to the system's right-hand side (as forward adds app.Q), and
  // W_d-dot, their dampers' power, is the state's last component. Leaves the normal loads and their minimum (the
  // lift-off event's value) and the Painleve test's condition numbers in slip_.
  void slip_rhs_into(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                     const Eigen::Ref<const VectorXd>& tau, double alpha, Eigen::Ref<VectorXd> out) {
    configure(q);
    dynamics(nu);
    const int k = static_cast<int>(S_.cols());
    const int nr = static_cast<int>(rows_.size());
    if (tau.size() != Br_.cols()) throw std::invalid_argument("tau has the wrong length");
    if (out.size() != nv_ + k + works()) throw std::invalid_argument("state has the wrong length");
    if (k + nr != nv_) throw Fallback("rows and independent velocities do not make a square system");
    if (controller_) {  // a feedback law's torques at this state (as rhs_into)
      control_tau_.resize(Br_.cols());
      controller_->eval(control_t_, q, nu, Mr_, hr_, Br_, S_, w_, v_, [this](int f) { return frame_kinematics(f); },
                        control_tau_);
    }
    const Eigen::Ref<const VectorXd> torque = controller_ ? Eigen::Ref<const VectorXd>(control_tau_) : tau;
    VectorXd* bias = &data_.tau;  // C v + g (RNEA at zero acceleration), less Q where springs act
    if (applied()) {  // joint springs and dampers (compliant wheels too): b = B tau - (C v + g - Q) - M w
      applied_forces();
      slip_bias_ = data_.tau - Qa_;
      bias = &slip_bias_;
    }
    slip_coupled_ = slip_open_ && nr < A_.rows() &&
                    slip_rl_.solve(slip_, slips_, wheels_, A_, SM_, geo_, Aw_, v_, B_, torque, *bias, data_.M, w_,
                                   rigid_.kstiff, nv_, k, lus_);
    if (!slip_coupled_)
      slip_.solve(slips_, rows_, A_, SM_, geo_, Aw_, v_, B_, torque, *bias, data_.M, w_, nv_, k, lus_);
    out.head(nv_) = v_;
    if (alpha != 0.0) pull_back(alpha, out);
    out.segment(nv_, k) = slip_.x.head(k);
    out[nv_ + k] = slip_.power;
    if (applied()) {  // (+ compliant wheels' friction power, as forward adds app.friction_power)
      out[nv_ + k] += friction_power_;
      out[nv_ + k + 1] = damper_power_;
    }
  }
  // The extra states of a run after (q, nu): the friction work with slipping wheels or compliant wheels, and the
  // damper work with joint springs or compliant wheels (the friction work then stays in its place).
  int works() const { return applied() ? 2 : !slips_.empty() ? 1 : 0; }

  // (d/dt (q, nu, W[, W_d]), normal loads (W,), slip velocities (W, 2), friction forces (W, 2)) at one state: the
  // compiled sliding.forward (tests compare it with the Python path); W_d-dot (the dampers' power) with springs.
  py::tuple slip_rhs(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                     const Eigen::Ref<const VectorXd>& tau, double alpha) {
    if (slips_.empty()) throw std::invalid_argument("no slipping wheels");
    VectorXd out(nv_ + nu.size() + works());
    slip_rhs_into(q, nu, tau, alpha, out);
    RowMat force(slips_.size(), 2);
    for (size_t i = 0; i < slips_.size(); ++i) force.row(i) = -slip_.normal[i] * slip_.c.row(i);
    return py::make_tuple(out, slip_.normal, RowMat(slip_.s), force);
  }

  // ------------------------------------------------------------------------------------------ springs, compliant wheels
  // Applied forces that depend on the state (robotdyn/contact/applied_forces.py): joint springs and dampers
  // (kernels/joint_springs.hpp) and compliant wheels (kernels/compliant_contact.hpp). Their sum Q(q, v) enters
  // rhs_into as S^T Q; a simulation carries the friction and the damper work as two extra states; observe adds
  // their stored energy.
  void add_spring(int index, double stiffness, double damping, double rest) {
    if (index < 0 || index >= nv_) throw std::invalid_argument("no such coordinate");
    springs_.push_back(robotdyn::kernels::JointSpring{index, stiffness, damping, rest});
  }
  // A compliant wheel: its contact geometry as a wheel without rows (as add_wheel), its normal law (kind 0 linear,
  // 1 Hunt-Crossley; k, c, n) and its friction law (code -1 none, 0 regularised Coulomb, 1 linear tyre; p0, p1)
  // on the tangential directions D (0..2, 2), rows of coefficients of (t1, t2).
  void add_compliant_wheel(int frame, const Vector3d& axis, double radius, int radius_index, int kind, double k,
                           double c, double n, int code, double p0, double p1, const MatrixXd& D) {
    if (kind < 0 || kind > 1 || code < -1 || code > 1) throw std::invalid_argument("unknown contact or friction law");
    if (D.cols() != 2 || D.rows() > 2) throw std::invalid_argument("tangential directions must be (0..2, 2)");
    robotdyn::kernels::CompliantContact cc;
    cc.wheel = static_cast<int>(wheels_.size());
    cc.normal = robotdyn::kernels::NormalLaw{kind, k, c, n};
    cc.friction = robotdyn::kernels::FrictionLaw{code, p0, p1};
    cc.D = D;
    order_.emplace_back(0, static_cast<int>(wheels_.size()));
    wheels_.push_back(Wheel{frame, axis, radius, radius_index, Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 3, 3>(0, 3)});
    contacts_.push_back(cc);
  }
  bool applied() const { return !springs_.empty() || !contacts_.empty(); }
  // The compliant wheels' contact mode at the last applied_forces: bits 2i (wheel i pressed in), 2i + 1 (its normal
  // force positive); the stiff integrator's differences do not cross a switch of it.
  unsigned long long contact_mode() const {
    unsigned long long out = 0;
    for (size_t i = 0; i < contact_states_.size() && i < 32; ++i) {
      if (contact_states_[i].delta > 0.0) out |= 1ULL << (2 * i);
      if (contact_states_[i].force[2] > 0.0) out |= 1ULL << (2 * i + 1);
    }
    return out;
  }

  // Q (Qa_), the friction and damper powers and each contact's state, after configure(q) and v_ = S nu.
  void applied_forces() {
    Qa_.setZero(nv_);
    damper_power_ = robotdyn::kernels::add_joint_springs(springs_, q_, v_, Qa_);
    friction_power_ = 0.0;
    contact_states_.resize(contacts_.size());
    Ac_.resize(3, nv_);
    for (size_t i = 0; i < contacts_.size(); ++i) {
      const robotdyn::kernels::CompliantContact& cc = contacts_[i];
      const WheelGeometry& g = geo_[cc.wheel];
      Ac_.row(0).noalias() = g.t1.transpose() * Aw_[cc.wheel];
      Ac_.row(1).noalias() = g.t2.transpose() * Aw_[cc.wheel];
      robotdyn::kernels::penetration_gradient(wheels_[cc.wheel], g, terrain_, Jf_[wheels_[cc.wheel].frame],
                                              Aw_[cc.wheel], Ac_.row(2));  // d phi / dq (n^T A_w on a plane)
      const robotdyn::kernels::ContactState st = robotdyn::kernels::add_compliant_contact(cc, g.phi, Ac_, v_, Qa_);
      contact_states_[i] = st;
      friction_power_ += st.friction_power;
      damper_power_ += st.damper_power;
    }
  }
  // The springs' and contacts' stored energy at the configured q [J].
  double stored_energy() const {
    double out = robotdyn::kernels::joint_springs_potential(springs_, q_);
    for (const auto& cc : contacts_) out += cc.normal.potential(-geo_[cc.wheel].phi);
    return out;
  }
  // The compliant wheels' penetrations [m] at the state y (its q).
  // (An explicit step's last evaluation was at its end, dopri5's first-same-as-last: its configuration is reused.)
  void penetrations(const double* y, const py::object& rechoose, std::vector<double>& out) {
    if (!(configured_ && q_.size() == nv_ && Eigen::Map<const VectorXd>(y, nv_) == q_))
      with_rechoice(y, rechoose, [&] { configure(Eigen::Map<const VectorXd>(y, nv_)); });
    out.resize(contacts_.size());
    for (size_t i = 0; i < contacts_.size(); ++i) out[i] = -geo_[contacts_[i].wheel].phi;
  }
  // (Q (nv,), friction power [W], damper power [W], per compliant wheel (delta, rate, F_t1, F_t2, f_n)) at (q, nu):
  // the compiled robotdyn.contact.applied_forces.applied (tests compare them).
  py::tuple applied_state(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
    configure(q);
    dynamics(nu);
    applied_forces();
    RowMat states(contacts_.size(), 5);
    for (size_t i = 0; i < contacts_.size(); ++i) {
      const auto& st = contact_states_[i];
      states.row(i) << st.delta, st.rate, st.force[0], st.force[1], st.force[2];
    }
    return py::make_tuple(Qa_, friction_power_, damper_power_, states);
  }

  // ------------------------------------------------------------------------------------------ rolling compliant wheels
  // Compliant wheels that roll while in contact (robotdyn/contact/compliant_rolling.py, kernels/compliant_rolling.hpp):
  // the run's contact set (set_rolling_mode, data of the run) says whose tangential rows are constraints; the event
  // min_i s_i pressing_i (s_i = +1 in the set: lift-off, -1 out of it: touch-down) ends the run at a switch, where
  // robotdyn/simulation/compiled_rolling.py applies the touch-down impact and starts the next run.
  // The last compliant wheel added rolls on its directions D (1..2, 2), rows of coefficients of (t1, t2).
  void add_rolling_rows(const MatrixXd& D) {
    if (contacts_.empty() || D.cols() != 2 || D.rows() < 1 || D.rows() > 2)
      throw std::invalid_argument("rolling rows need a compliant wheel and directions (1..2, 2)");
    Wheel wh = wheels_[contacts_.back().wheel];
    wh.D.setZero(D.rows(), 3);
    wh.D.leftCols(2) = D;
    rolling_contact_.push_back(static_cast<int>(contacts_.size()) - 1);
    rolling_wheels_.push_back(wh);
    rolling_on_.push_back(0);
  }
  // The contact set: on[i] != 0 where rolling wheel i's rows hold.
  void set_rolling_mode(const std::vector<int>& on) {
    if (on.size() != rolling_on_.size()) throw std::invalid_argument("one flag per rolling compliant wheel expected");
    for (size_t i = 0; i < on.size(); ++i) rolling_on_[i] = on[i] != 0;
  }
  bool rolling_active() const {
    return std::any_of(rolling_on_.begin(), rolling_on_.end(), [](char c) { return c != 0; });
  }
  // Rows G (m, nv) and drift Gdot v (m,) of the rolling wheels with on[i] set, after configure and dynamics.
  void rolling_rows_into(const std::vector<char>& on, MatrixXd& G, VectorXd& drift) {
    int m = 0;
    for (size_t i = 0; i < on.size(); ++i)
      if (on[i]) m += static_cast<int>(rolling_wheels_[i].D.rows());
    G.resize(m, nv_);
    drift.resize(m);
    int row = 0;
    for (size_t i = 0; i < on.size(); ++i) {
      if (!on[i]) continue;
      const Wheel& wh = rolling_wheels_[i];
      const int w = contacts_[rolling_contact_[i]].wheel;
      const WheelGeometry& g = geo_[w];
      Matrix3d ET;
      ET.row(0) = g.t1.transpose();
      ET.row(1) = g.t2.transpose();
      ET.row(2) = g.n.transpose();
      const int nd = static_cast<int>(wh.D.rows());
      G.middleRows(row, nd).noalias() = (wh.D * ET) * Aw_[w];
      row = kernels::wheel_drift(wh, g, terrain_, model_, data_, frames_[wh.frame], Aw_[w], v_, row, drift);
    }
  }
  // nudot into force_ (M_r nudot = force_ + G_r^T lambda, G_r nudot = -(G w + Gdot v) - beta G_r nu), llt_ factored.
  void rolling_solve(const Eigen::Ref<const VectorXd>& nu, double beta) {
    rolling_rows_into(rolling_on_, rollG_, rollDrift_);
    rollGr_.noalias() = rollG_ * S_;
    rollTarget_ = -(rollG_ * w_ + rollDrift_);
    if (beta != 0.0) rollTarget_.noalias() -= beta * (rollGr_ * nu);
    kernels::rolling_accelerations(llt_, rollGr_, rollTarget_, force_, rollLambda_, rollMinvGT_);
  }
  // The event's value after applied_forces: min_i s_i pressing_i [m] (>= 0 until the contact set must change).
  double rolling_event() const {
    double g = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < rolling_contact_.size(); ++i) {
      const int c = rolling_contact_[i];
      const auto& st = contact_states_[c];
      const double p = kernels::pressing(contacts_[c].normal, st.delta, st.rate);
      g = std::min(g, rolling_on_[i] ? p : -p);
    }
    return g;
  }
  // (indicators (R,) [m], G (m, nv) of every rolling wheel in order, M_r, S, v) at (q, nu): the switch's data.
  py::tuple rolling_state(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
    configure(q);
    dynamics(nu);
    applied_forces();
    VectorXd p(rolling_contact_.size());
    for (size_t i = 0; i < rolling_contact_.size(); ++i) {
      const int c = rolling_contact_[i];
      p[i] = kernels::pressing(contacts_[c].normal, contact_states_[c].delta, contact_states_[c].rate);
    }
    MatrixXd G;
    VectorXd drift;
    rolling_rows_into(std::vector<char>(rolling_contact_.size(), 1), G, drift);
    return py::make_tuple(p, G, Mr_, S_, v_);
  }

  // ------------------------------------------------------------------------------------------ feedback laws
  // A feedback law (robotdyn/_controller.hpp) replacing the torque profile in rhs_into (simulate), or none.
  void set_controller(const robotdyn::Controller* c) {
    if (c == nullptr) {
      controller_.reset();
      return;
    }
    if (c->motors() != static_cast<int>(motors_.size()) || c->n() != nv_ || c->k() != mobility())
      throw std::invalid_argument("the feedback law is for another robot (motors, coordinates or velocities)");
    controller_ = *c;
  }

  // The law's torques at (t, q, nu) (robotdyn/simulation/feedback.py's reference checks them).
  VectorXd control_torque(const robotdyn::Controller& c, double t, const Eigen::Ref<const VectorXd>& q,
                          const Eigen::Ref<const VectorXd>& nu) {
    configure(q);
    dynamics(nu);
    robotdyn::Controller law = c;
    VectorXd out(Br_.cols());
    law.eval(t, q, nu, Mr_, hr_, Br_, S_, w_, v_, [this](int f) { return frame_kinematics(f); }, out);
    return out;
  }

  // Frame f (add_frame's index) at the evaluated state, for a linearising law's point tasks: its placement, its
  // LOCAL_WORLD_ALIGNED Jacobian and its classical acceleration at zero joint acceleration (dynamics' RNEA pass).
  robotdyn::FrameKinematics frame_kinematics(int f) {
    if (f < 0 || f >= static_cast<int>(frames_.size())) throw std::invalid_argument("no such frame");
    const auto fid = static_cast<pin::FrameIndex>(frames_[f]);
    robotdyn::FrameKinematics out;
    out.R = data_.oMf[fid].rotation();
    out.p = data_.oMf[fid].translation();
    out.J = &Jf_[f];
    const pin::Motion acc = pin::getFrameClassicalAcceleration(model_, data_, fid, pin::LOCAL_WORLD_ALIGNED);
    out.a = acc.linear();
    out.alpha = acc.angular();
    return out;
  }

  // ------------------------------------------------------------------------------------------ simulation
  // Where the row choice stops working (Fallback), `rechoose(q, nu)` (Python, with the GIL) returns the Python
  // path's new (rows, independent, dependent), or raises the Python path's error: as the scipy path, which
  // evaluates that state in Python.
  template <class Eval>
  void with_rechoice(const double* y, const py::object& rechoose, Eval&& eval) {
    try {
      eval();
    } catch (const Fallback&) {
      if (rechoose.is_none()) throw;
      {
        py::gil_scoped_acquire gil;
        const int k = mobility();
        VectorXd q(Eigen::Map<const VectorXd>(y, nv_)), nu(Eigen::Map<const VectorXd>(y + nv_, k));
        py::tuple sel = run_ < 0 ? rechoose(q, nu) : rechoose(run_, q, nu);
        ++rechoices_;
        configured_ = false;
        rows_ = sel[0].cast<std::vector<int>>();
        if (!operational_) {
          independent_ = sel[1].cast<std::vector<int>>();
          dependent_ = sel[2].cast<std::vector<int>>();
        }
      }
      eval();
    }
  }

  // The ODE of simulate() with the torques of a profile: y = (q, nu), dy = d/dt y.
  void deriv(double t, const std::vector<double>& y, std::vector<double>& dy, double alpha,
             const robotdyn::TorqueProfile& profile, const py::object& rechoose) {
    const int k = mobility();
    last_t_ = t;  // where an escaping Fallback happened (the Python side names the time)
    control_t_ = t;  // the time of a feedback law's references (rhs_into)
    tau_.resize(profile.motors());
    profile.eval(t, tau_);
    dy.resize(y.size());
    if (slips_.empty()) {
      with_rechoice(y.data(), rechoose, [&] {
        rhs_into(Eigen::Map<const VectorXd>(y.data(), nv_), Eigen::Map<const VectorXd>(y.data() + nv_, k), tau_,
                 alpha, Eigen::Map<VectorXd>(dy.data(), nv_ + k));
      });
      if (applied()) {  // y = (q, nu, friction work, damper work)
        dy[nv_ + k] = friction_power_;
        dy[nv_ + k + 1] = damper_power_;
      }
      if (!rolling_contact_.empty()) {  // the contact-switch event's value at this state (lift_off reuses it)
        event_t_ = t;
        event_y_ = y;
        event_g_ = rolling_event();
      }
      return;
    }
    try {  // y = (q, nu, friction work[, damper work])
      with_rechoice(y.data(), rechoose, [&] {
        slip_rhs_into(Eigen::Map<const VectorXd>(y.data(), nv_), Eigen::Map<const VectorXd>(y.data() + nv_, k),
                      tau_, alpha, Eigen::Map<VectorXd>(dy.data(), nv_ + k + works()));
      });
    } catch (const SlipError&) {
      slip_error_t_ = t;
      slip_error_y_ = y;
      throw;
    }
    event_t_ = t;  // the lift-off event's value at this state (lift_off reuses it)
    event_y_ = y;
    event_g_ = slip_.min_normal;
  }

  // The lift-off event: the smallest normal load of the slipping wheels at (t, y) [N] (from the last evaluation
  // when it was at this very state).
  double lift_off(double t, const std::vector<double>& y, double alpha, const robotdyn::TorqueProfile& profile,
                  const py::object& rechoose) {
    if (!(t == event_t_ && y == event_y_)) {
      event_dy_.resize(y.size());
      deriv(t, y, event_dy_, alpha, profile, rechoose);
    }
    return event_g_;
  }

  // ------------------------------------------------------------------------------------------ stepped from Python
  // One call per evaluation for an integrator driven from Python (robotdyn/simulation/cvode.py: SUNDIALS CVODE):
  // dy = d/dt y of simulate()'s ODE at (t, y), y = (q, nu[, works]) as in simulate, written into dy (no allocation);
  // the compliant wheels' penetrations [m] at y into `out`; the terminal event's value (lift_off) at (t, y).
  int state_size() const { return nv_ + mobility() + works(); }
  void deriv_into(double t, const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> dy, double alpha,
                  const robotdyn::TorqueProfile& profile, const py::object& rechoose) {
    if (y.size() != state_size() || dy.size() != state_size())
      throw std::invalid_argument("y, dy: expected arrays of the state's length " + std::to_string(state_size()));
    step_y_.assign(y.data(), y.data() + y.size());
    deriv(t, step_y_, step_dy_, alpha, profile, rechoose);
    dy = Eigen::Map<const VectorXd>(step_dy_.data(), static_cast<Eigen::Index>(step_dy_.size()));
  }
  void depths_into(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> out, const py::object& rechoose) {
    if (y.size() != state_size() || out.size() != static_cast<Eigen::Index>(contacts_.size()))
      throw std::invalid_argument("y, out: expected the state's length and one value per compliant wheel");
    penetrations(y.data(), rechoose, step_depths_);
    out = Eigen::Map<const VectorXd>(step_depths_.data(), static_cast<Eigen::Index>(step_depths_.size()));
  }
  // A Jacobian's differences are being taken (on: the projection skips its span check, as for rosenbrock4: a
  // difference leaves the constraint manifold by ~1e-8)
  void set_differencing(bool on) { differencing_ = on; }
  double event_value(double t, const Eigen::Ref<const VectorXd>& y, double alpha,
                     const robotdyn::TorqueProfile& profile, const py::object& rechoose) {
    if (y.size() != state_size()) throw std::invalid_argument("y: expected the state's length");
    step_y_.assign(y.data(), y.data() + y.size());
    return lift_off(t, step_y_, alpha, profile, rechoose);
  }

  // Total mechanical energy [J] (kinetic 1/2 v^T M v, potential -sum m_i g . c_i as Pinocchio's
  // computePotentialEnergy) and the largest holonomic residual at a state y = (q, nu).
  void observe(const double* y, double& energy, double& residual, const py::object& rechoose) {
    with_rechoice(y, rechoose, [&] { configure(Eigen::Map<const VectorXd>(y, nv_)); });
    v_.noalias() = S_ * Eigen::Map<const VectorXd>(y + nv_, mobility());  // (no dynamics needed)
    energy_residual(energy, residual);
  }

  // observe's energy and residual from the evaluator's M (CRBA's upper triangle), placements, v_ and residuals.
  void energy_residual(double& energy, double& residual) {
    double potential = 0.0;
    for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model_.njoints); ++i) {
      const pin::Inertia& Y = model_.inertias[i];
      potential -= Y.mass() * gravity_.linear().dot(data_.oMi[i].act(Y.lever()));
    }
    energy = 0.5 * v_.dot(data_.M.selfadjointView<Eigen::Upper>() * v_) + potential;  // CRBA fills the upper part
    if (applied()) energy += stored_energy();  // springs' and compliant contacts' elastic energy
    residual = 0.0;
    for (size_t r = 0; r < holonomic_.size(); ++r)
      if (holonomic_[r]) residual = std::max(residual, std::fabs(residual_[r]));
  }

  // A sample's energy and residual after a run that kept its row choice (no re-choice): observe's numbers, the same
  // bits, without what a sample does not use. The choice in force served, and passed its checks at, every
  // evaluation of the run, the evaluations on both sides of the sample included; so the configuration pass here
  // skips the gravity torques, the motors' columns B and the projection's condition and span checks
  // (projection.hpp's project_selection otherwise, step by step: S from A_d's LU factors; for operational
  // velocities operational_space.hpp's operational_inverse). Springs and compliant wheels (their stored energy) and
  // an S that is not finite (a zero pivot) go through observe.
  void sample(const double* y, double& energy, double& residual, const py::object& rechoose) {
    if (applied() || !selected_ || differencing_) return observe(y, energy, residual, rechoose);
    bool finite = true;
    with_rechoice(y, rechoose, [&] {
      configured_ = false;  // (this pass leaves g_ and B_ from another configuration)
      q_ = Eigen::Map<const VectorXd>(y, nv_);
      pin::crba(model_, data_, q_, pin::Convention::WORLD);
      rows_pass(false);
      if (operational_)
        finite = kernels::operational_inverse(A_, rows_, op_select_, model_, data_, frames_[op_frame_], op_local_, nv_,
                                              K_, Jc_, lu_, Kinv_, S_);
      else finite = sample_selection();
    });
    if (!finite) return observe(y, energy, residual, rechoose);
    v_.noalias() = S_ * Eigen::Map<const VectorXd>(y + nv_, mobility());
    energy_residual(energy, residual);
  }

  // S of project_selection (kernels/projection.hpp) without its condition number and span checks (sample); false
  // where it is not finite.
  bool sample_selection() {
    if (!kernels::selection_blocks(A_, rows_, independent_, dependent_, nv_, lu_, sel_, S_)) return true;
    return kernels::selection_solve(dependent_, lus_, lu_, sel_, S_);
  }

  // ------------------------------------------------------------------------------------------ constraint forces
  // lambda of A^T lambda = e, e = M a + C v + g - B tau (robotdyn/contact_forces.py), on the rows the projection
  // uses: with the LU factors of A_d (the projection's own factorisation), A_d^T lambda_r = e_d; with operational
  // velocities by the projection's K^-1 (K = [A_r; J_o]). Rows outside the projection's choice (redundant ones) get zero: lambda is the
  // basic solution, equal to every other solution on the rows that rigid-body dynamics determine (the Python side
  // reports the others with the null space of A^T). After dynamics() (forward: nudot from the torques) or with a
  // given full acceleration a (forces_at).
  void lambda_from(const Eigen::Ref<const VectorXd>& tau) {
    constraint_multipliers(B_, tau, force_, e_, rows_, dependent_, operational_, Kinv_, lu_, lus_, nrows(), lr_,
                           lambda_);
  }

  // Forward dynamics at (q, nu, tau) and the constraint forces, into buffers read through the views nudot, lam,
  // e, wheel_local (nw, 3) along (t1, t2, n), wheel_world, wheel_frames (nw, 9: t1, t2, n), contact_points; returns
  // a counter that changes whenever a buffer moved (as compute).
  long forces(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
              const Eigen::Ref<const VectorXd>& tau) {
    if (tau.size() != static_cast<Eigen::Index>(motors_.size())) throw std::invalid_argument("tau has the wrong length");
    configure(q);
    dynamics(nu);
    force_.noalias() = Br_ * tau;
    force_ -= hr_;
    kernels::add_reduced_joint_springs(springs_, q_, v_, S_, force_);  // joint springs and dampers: + S^T Q
    llt_.compute(Mr_);
    if (llt_.info() != Eigen::Success) throw Fallback("reduced mass matrix not positive definite");
    nudot_ = force_;
    llt_.solveInPlace(nudot_);
    a_ = w_;
    a_.noalias() += S_ * nudot_;
    e_ = data_.tau;  // C v + g (dynamics)
    e_.noalias() += data_.M * a_;
    kernels::subtract_joint_springs(springs_, q_, v_, e_);  // e = M a + C v + g - Q (joint springs and dampers)
    lambda_from(tau);
    rigid_limit_split();
    fill_wheel_forces();
    const double* now[7] = {nudot_.data(), lambda_.data(), e_.data(), wl_.data(), ww_.data(), wf_.data(), wp_.data()};
    for (int i = 0; i < 7; ++i)
      if (now[i] != fbuffers_[i]) {
        std::copy(now, now + 7, fbuffers_);
        ++fgeneration_;
        break;
      }
    return fgeneration_;
  }

  // The same for given full velocities v and accelerations a (inverse dynamics): (lambda, e, wheel forces, A).
  py::tuple forces_at(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& v,
                      const Eigen::Ref<const VectorXd>& a, const Eigen::Ref<const VectorXd>& tau) {
    if (v.size() != nv_ || a.size() != nv_ || tau.size() != static_cast<Eigen::Index>(motors_.size()))
      throw std::invalid_argument("v, a or tau has the wrong length");
    configure(q);
    pin::rnea(model_, data_, q_, v, a);  // without gravity: M a + C v
    e_ = data_.tau + g_;
    kernels::subtract_joint_springs(springs_, q_, v, e_);  // - Q (joint springs and dampers)
    lambda_from(tau);
    return py::make_tuple(lambda_, e_, wheel_forces(), A_);
  }

  // The loads rigid-body dynamics leave open, by the rigid limit of the wheels' normal compliance
  // (robotdyn/contact/rigid_limit.py, the same formulas): lambda + N z with N a basis of the null space of A^T (from
  // the projection's LU of A_d; with operational velocities a column-pivoting QR of A), z along the directions V_n that move normal loads (an SVD of C N) minimising
  // sum n_i^2 / k_i: the compatible loads; minimum norm along those that move none; the rows rigid-body dynamics
  // determine keep their values. Where the compatible loads would pull on a wheel the no-pull split (a
  // least-distance program) is the Python path's: Fallback. Nothing happens without redundant rows, where a row acts
  // on no coordinate (a planar root's normal rows), or with the split turned off (set_rigid_limit(false)).
  void rigid_limit_split() {
    rigid_.split(A_, rows_, dependent_, operational_, lu_, lus_, wheels_, geo_, nv_, lambda_);
  }
  void set_normal_stiffness(const Eigen::Ref<const VectorXd>& k) {
    if (k.size() != static_cast<Eigen::Index>(wheels_.size())) throw std::invalid_argument("one stiffness per wheel");
    if (!(k.array() > 0.0).all() || !k.allFinite()) throw std::invalid_argument("stiffnesses must be finite and > 0");
    rigid_.set_stiffness(k);
  }
  void set_rigid_limit(bool on) { rigid_.on = on; }

  // Per wheel: the force along (t1, t2, n), the same in world axes, the contact frame (rows t1, t2, n: (nw, 9),
  // row-major) and the contact point (nw, 3).
  void fill_wheel_forces() { wheel_force_table(wheels_, geo_, lambda_, wl_, ww_, wf_, wp_); }
  py::tuple wheel_forces() {
    fill_wheel_forces();
    return py::make_tuple(wl_, ww_, wf_, wp_);
  }
  const VectorXd& nudot() const { return nudot_; }
  const VectorXd& lam() const { return lambda_; }
  const VectorXd& e() const { return e_; }
  const RowMat& wheel_local() const { return wl_; }
  const RowMat& wheel_world() const { return ww_; }
  const RowMat& wheel_frames() const { return wf_; }
  const RowMat& contact_points() const { return wp_; }

  // ------------------------------------------------------------------------------------------ model vector
  // The numbers this model is built from, in one vector (robotdyn/model_variants.py reads and writes the same
  // layout): per joint its placement (R row-major, p: 12) and inertia (mass, lever, Ixx Ixy Ixz Iyy Iyz Izz about
  // the centre of mass: 10); per frame its placement (12); per wheel its radius and axle (4); per coupling its law
  // (amplitude, rate, phase, offset); the gravity (3).
  VectorXd model_vector() const {
    VectorXd x(model_vector_size());
    Eigen::Index i = 0;
    auto put_se3 = [&](const pin::SE3& M) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) x[i++] = M.rotation()(r, c);
      for (int r = 0; r < 3; ++r) x[i++] = M.translation()[r];
    };
    for (pin::JointIndex j = 1; j < static_cast<pin::JointIndex>(model_.njoints); ++j) {
      put_se3(model_.jointPlacements[j]);
      const pin::Inertia& Y = model_.inertias[j];
      x[i++] = Y.mass();
      for (int r = 0; r < 3; ++r) x[i++] = Y.lever()[r];
      const Matrix3d I = Y.inertia().matrix();
      for (auto [r, c] : {std::pair{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}}) x[i++] = I(r, c);
    }
    for (int f : frames_) put_se3(model_.frames[f].placement);
    for (const Wheel& w : wheels_) {
      x[i++] = w.radius;
      for (int r = 0; r < 3; ++r) x[i++] = w.axis[r];
    }
    for (const Coupling& c : couplings_) {
      x[i++] = c.amplitude;
      x[i++] = c.rate;
      x[i++] = c.phase;
      x[i++] = c.offset;
    }
    for (int r = 0; r < 3; ++r) x[i++] = gravity_.linear()[r];
    return x;
  }
  Eigen::Index model_vector_size() const {
    return 22 * (model_.njoints - 1) + 12 * static_cast<Eigen::Index>(frames_.size()) +
           4 * static_cast<Eigen::Index>(wheels_.size()) + 4 * static_cast<Eigen::Index>(couplings_.size()) + 3;
  }
  void set_model_vector(const double* x) {
    configured_ = false;
    crba_at_q_ = false;
    Eigen::Index i = 0;
    auto get_se3 = [&]() {
      Matrix3d R;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) R(r, c) = x[i++];
      Vector3d p(x[i], x[i + 1], x[i + 2]);
      i += 3;
      return pin::SE3(R, p);
    };
    for (pin::JointIndex j = 1; j < static_cast<pin::JointIndex>(model_.njoints); ++j) {
      model_.jointPlacements[j] = get_se3();
      const double mass = x[i];
      const Vector3d lever(x[i + 1], x[i + 2], x[i + 3]);
      Matrix3d I;
      I << x[i + 4], x[i + 5], x[i + 6], x[i + 5], x[i + 7], x[i + 8], x[i + 6], x[i + 8], x[i + 9];
      i += 10;
      model_.inertias[j] = pin::Inertia(mass, lever, I);
    }
    for (int f : frames_) model_.frames[f].placement = get_se3();
    for (Wheel& w : wheels_) {
      w.radius = x[i];
      w.axis = Vector3d(x[i + 1], x[i + 2], x[i + 3]);
      i += 4;
    }
    for (Coupling& c : couplings_) {
      c.amplitude = x[i];
      c.rate = x[i + 1];
      c.phase = x[i + 2];
      c.offset = x[i + 3];
      i += 4;
    }
    gravity_ = pin::Motion(Vector3d(x[i], x[i + 1], x[i + 2]), Vector3d::Zero());
  }
  void set_model_vector_py(const VectorXd& x) {
    if (x.size() != model_vector_size()) throw std::invalid_argument("model vector has the wrong length");
    set_model_vector(x.data());
  }

  // ------------------------------------------------------------------------------------------ many runs
  // N simulations on `threads` threads (robotdyn/batch.py: simulate_many), each thread with its own copy of this
  // evaluator, the runs handed out one at a time; every run starts from this evaluator's row choice and, where
  // `models` has rows, with its own model vector, so that its result does not depend on the thread or on the
  // runs before it (the same numbers as Evaluator.simulate alone). A run that fails (constraints violated at its
  // start, a non-finite state, a vanishing step, an error of the Python path where its rows had to be re-chosen)
  // is recorded with its message; the others go on. The main thread waits without the GIL and takes it every
  // 50 ms for signals (Ctrl-C: the runs under way stop, finished runs are kept) and progress(done).
  py::dict simulate_many(const Eigen::Ref<const RowMat>& Q0, const Eigen::Ref<const RowMat>& NU0,
                         const Eigen::Ref<const RowMat>& models, const std::vector<robotdyn::TorqueProfile*>& profiles,
                         const std::vector<std::vector<double>>& breaks, double t_end,
                         const std::vector<double>& samples, double rtol, double atol, double alpha,
                         const std::string& method, int threads, py::object progress, py::object rechoose,
                         double time_limit) {
    if (!slips_.empty()) throw std::invalid_argument("simulate_many does not run robots with slipping wheels");
    if (applied()) throw std::invalid_argument("simulate_many does not run robots with joint springs or compliant wheels");
    const long N = static_cast<long>(Q0.rows());
    const int k = mobility(), dim = nv_ + k;
    const long S = static_cast<long>(samples.size());
    if (Q0.cols() != nv_ || NU0.rows() != N || NU0.cols() != k) throw std::invalid_argument("q0 or nu0 shapes");
    if (static_cast<long>(profiles.size()) != N || static_cast<long>(breaks.size()) != N)
      throw std::invalid_argument("one torque profile and one breakpoint list per run expected");
    if (models.rows() != 0 && (models.rows() != N || models.cols() != model_vector_size()))
      throw std::invalid_argument("one model vector per run expected");
    for (const auto* p : profiles)
      if (p == nullptr || p->motors() != static_cast<int>(motors_.size()))
        throw std::invalid_argument("a torque profile for another number of motors");
    if (!selected_) throw Fallback("no projection chosen yet");
    py::array_t<double> Y({N, S, static_cast<long>(dim)}), E({N, S}), R({N, S});
    py::array_t<long> emitted(N), nfev(N), steps(N);
    py::array_t<int> status(N);
    py::array_t<double> walls(N);
    double* wall_out = walls.mutable_data();
    std::fill(wall_out, wall_out + N, 0.0);
    std::vector<std::string> messages(N);
    double* y_out = Y.mutable_data();
    double* e_out = E.mutable_data();
    double* r_out = R.mutable_data();
    long* emitted_out = emitted.mutable_data();
    long* nfev_out = nfev.mutable_data();
    long* steps_out = steps.mutable_data();
    int* status_out = status.mutable_data();
    std::fill(emitted_out, emitted_out + N, 0L);
    std::fill(nfev_out, nfev_out + N, 0L);
    std::fill(steps_out, steps_out + N, 0L);
    std::fill(status_out, status_out + N, -1);  // not run
    std::atomic<long> next_run{0}, done{0};
    std::atomic<bool> stop{false};
    const int nthreads = std::max(1, std::min<int>(threads, static_cast<int>(std::max<long>(N, 1))));
    auto worker = [&]() {
      Evaluator ev(*this);
      for (long i = next_run++; i < N && !stop.load(); i = next_run++) {
        ev.run_ = static_cast<int>(i);
        ev.rows_ = rows_;
        ev.independent_ = independent_;
        ev.dependent_ = dependent_;
        if (models.rows()) ev.set_model_vector(models.row(i).data());
        double* yi = y_out + i * S * dim;
        double* ei = e_out + i * S;
        double* ri = r_out + i * S;
        long count = 0, evals = 0;
        const auto started = std::chrono::steady_clock::now();
        bool timed_out = false;
        try {
          robotdyn::State y0(dim);
          Eigen::Map<VectorXd>(y0.data(), nv_) = Q0.row(i).transpose();
          Eigen::Map<VectorXd>(y0.data() + nv_, k) = NU0.row(i).transpose();
          ev.check_start(y0.data(), rechoose);
          auto system = [&](const robotdyn::State& x, robotdyn::State& dxdt, double t) {
            ++evals;
            ev.deriv(t, x, dxdt, alpha, *profiles[i], rechoose);
          };
          auto observer = [&](double, const robotdyn::State& x) {
            std::copy(x.begin(), x.end(), yi + count * dim);
            ++count;
          };
          auto poll = [&](double) {  // time_limit <= 0: none; past it the run stops as failed, named so
            if (time_limit > 0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() >
                                      time_limit)
              timed_out = true;
            return !stop.load() && !timed_out;
          };
          size_t next = 0;
          const long rechoices = ev.rechoices_;
          robotdyn::Outcome out = robotdyn::integrate(method, system, y0, 0.0, t_end, samples, next, breaks[i], rtol,
                                                      atol, observer, poll);
          const bool kept = ev.rechoices_ == rechoices;  // as simulate: the lean pass where the choice was kept
          for (long j = 0; j < count; ++j)
            if (kept) ev.sample(yi + j * dim, ei[j], ri[j], rechoose);
            else ev.observe(yi + j * dim, ei[j], ri[j], rechoose);
          status_out[i] = out.status;
          if (timed_out && out.status == robotdyn::INTERRUPTED) {
            status_out[i] = robotdyn::FAILED;
            std::ostringstream text;
            text << "the run exceeded its time limit of " << time_limit << " s at t = " << out.t << " s of " << t_end
                 << " s";
            messages[i] = text.str();
          } else if (out.status == robotdyn::FAILED)
            messages[i] = "integration failed at t = " + std::to_string(out.t) + " s: " + out.message;
          else if (out.status == robotdyn::INTERRUPTED)
            messages[i] = "interrupted at t = " + std::to_string(out.t) + " s";
          steps_out[i] = out.steps;
        } catch (py::error_already_set& e) {
          py::gil_scoped_acquire gil;
          status_out[i] = robotdyn::FAILED;
          messages[i] = e.what();
        } catch (const std::exception& e) {
          status_out[i] = robotdyn::FAILED;
          messages[i] = e.what();
        }
        emitted_out[i] = count;
        nfev_out[i] = evals;
        wall_out[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        ++done;
      }
    };
    bool interrupted = false;
    std::optional<py::error_already_set> pending;  // an exception of a signal handler or of progress
    {
      py::gil_scoped_release release;
      std::vector<std::thread> pool;
      for (int t = 0; t < nthreads; ++t) pool.emplace_back(worker);
      long reported = -1;
      while (done.load() < N && !stop.load()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) {
          if (PyErr_ExceptionMatches(PyExc_KeyboardInterrupt)) {
            PyErr_Clear();
            interrupted = true;
          } else {
            pending.emplace();  // fetches the error
          }
          stop = true;
        } else if (!progress.is_none() && done.load() != reported) {
          reported = done.load();
          try {
            progress(reported, N);
          } catch (py::error_already_set& e) {
            if (e.matches(PyExc_KeyboardInterrupt)) interrupted = true;
            else pending.emplace(e);
            stop = true;
          }
        }
      }
      for (auto& th : pool) th.join();  // without the GIL: a run may need it to re-choose its rows
    }
    if (pending) throw *pending;
    py::dict result;
    result["y"] = Y;
    result["energy"] = E;
    result["residual"] = R;
    result["emitted"] = emitted;
    result["nfev"] = nfev;
    result["steps"] = steps;
    result["status"] = status;
    result["messages"] = messages;
    result["walls"] = walls;
    result["interrupted"] = interrupted;
    return result;
  }

  // The start of a run: the holonomic residuals within 1e-6 (Robot.check_constraints' tolerance).
  void check_start(const double* y, const py::object& rechoose) {
    with_rechoice(y, rechoose, [&] { configure(Eigen::Map<const VectorXd>(y, nv_)); });
    for (size_t r = 0; r < holonomic_.size(); ++r)
      if (holonomic_[r] && !(std::fabs(residual_[r]) <= 1e-6))
        throw std::invalid_argument("q0 violates holonomic row #" + std::to_string(r) + " by " +
                                    std::to_string(residual_[r]) + "; expected |residual| <= 1e-06");
  }

  // A whole simulation (robotdyn/compiled_simulation.py) from (t0, q0, nu0) to t_end with samples at `samples`
  // (those >= t0). Runs without the GIL; every ~50 ms it takes the GIL to check for signals (Ctrl-C: status
  // INTERRUPTED, the samples so far kept) and to call progress(t) (None: no call).
  py::dict simulate(const VectorXd& q0, const VectorXd& nu0, double t0, double t_end,
                    const std::vector<double>& samples, double rtol, double atol, double alpha,
                    const robotdyn::TorqueProfile& profile, const std::vector<double>& breaks,
                    const std::string& method, py::object progress, py::object rechoose) {
    const int k = mobility();
    if (q0.size() != nv_ || nu0.size() != k) throw std::invalid_argument("q0 or nu0 has the wrong length");
    if (profile.motors() != static_cast<int>(motors_.size()))
      throw std::invalid_argument("the torque profile is for another number of motors");
    const bool slipping = !slips_.empty();
    if (slipping && !contacts_.empty()) throw std::invalid_argument("slipping wheels with compliant wheels");
    if (method == "rosenbrock4" && slipping) throw std::invalid_argument("rosenbrock4 does not run slipping wheels");
    // slipping wheels: the friction work; springs, compliant wheels: friction and damper work (works())
    const int dim = nv_ + k + works();
    robotdyn::State y0(dim, 0.0);
    Eigen::Map<VectorXd>(y0.data(), nv_) = q0;
    Eigen::Map<VectorXd>(y0.data() + nv_, k) = nu0;
    std::vector<double> ts, ys, energy, residual;
    ts.reserve(samples.size());
    ys.reserve(samples.size() * dim);
    long nfev = 0;
    const long rechoices = rechoices_;  // (the samples' pass is the lean one where the run makes no re-choice)
    auto system = [&](const robotdyn::State& x, robotdyn::State& dxdt, double t) {
      ++nfev;
      deriv(t, x, dxdt, alpha, profile, rechoose);
    };
    auto observer = [&](double t, const robotdyn::State& x) {
      ts.push_back(t);
      ys.insert(ys.end(), x.begin(), x.end());
    };
    bool interrupted = false;
    auto poll = [&](double t) -> bool {
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) {
        if (PyErr_ExceptionMatches(PyExc_KeyboardInterrupt)) {
          PyErr_Clear();
          interrupted = true;
          return false;
        }
        throw py::error_already_set();
      }
      if (!progress.is_none()) {
        try {
          progress(t);
        } catch (py::error_already_set& e) {
          if (!e.matches(PyExc_KeyboardInterrupt)) throw;
          interrupted = true;
          return false;
        }
      }
      return true;
    };
    size_t next = 0;
    while (next < samples.size() && samples[next] < t0) ++next;
    robotdyn::Outcome out;
    struct LiftOff {  // the terminal event of slipping wheels: their smallest normal load crossing zero downwards
      Evaluator* ev;
      double alpha;
      const robotdyn::TorqueProfile* profile;
      const py::object* rechoose;
      bool on;
      bool active() const { return on; }
      double operator()(double t, const robotdyn::State& y) { return ev->lift_off(t, y, alpha, *profile, *rechoose); }
    } lift_off{this, alpha, &profile, &rechoose, slipping || !rolling_contact_.empty()};
    int slip_error = -1;
    double slip_value = 0.0;
    int slip_wheels = 0;  // kind 2 (Painleve check): the bit mask of the wheels named
    std::vector<std::tuple<double, int, int>> crossings;  // flight phases: (t, compliant wheel, +1 touch-down / -1 lift-off)
    {
      py::gil_scoped_release release;
      try {
        if (method == "rosenbrock4") {  // stiff (_stiff_integrator.hpp), with the compliant wheels' flight phases
          auto depths = [this, &rechoose](double, const robotdyn::State& y, std::vector<double>& d) {
            penetrations(y.data(), rechoose, d);
          };
          robotdyn::Crossings<decltype(depths)> flights(depths);
          struct Mode {  // the right-hand side's mode, and the Jacobian's differences on or off
            Evaluator* ev;
            unsigned long long operator()() const { return ev->contact_mode(); }
            void differencing(bool on) { ev->differencing_ = on; }
          } mode{this};
          out = robotdyn::integrate_stiff(system, y0, t0, t_end, samples, next, breaks, rtol, atol, nv_ + k, observer,
                                          poll, flights, mode, lift_off);
          for (const auto& [te, i, direction] : flights.found)
            if (te <= out.t) crossings.emplace_back(te, i, direction);
        } else if (!contacts_.empty()) {  // explicit, with the flight phases on the dense output
          auto depths = [this, &rechoose](double, const robotdyn::State& y, std::vector<double>& d) {
            penetrations(y.data(), rechoose, d);
          };
          robotdyn::Crossings<decltype(depths)> flights(depths);
          out = robotdyn::integrate_crossings(method, system, y0, t0, t_end, samples, next, breaks, rtol, atol,
                                              observer, poll, flights, lift_off);
          for (const auto& [te, i, direction] : flights.found)
            if (te <= out.t) crossings.emplace_back(te, i, direction);
        } else {
          out = robotdyn::integrate(method, system, y0, t0, t_end, samples, next, breaks, rtol, atol, observer, poll,
                                    lift_off);
        }
      } catch (const SlipError& e) {
        slip_error = e.kind;
        slip_value = e.value;
        slip_wheels = e.wheels;
        out.status = robotdyn::FAILED;
        out.t = slip_error_t_;
        out.y = slip_error_y_;
        out.message = e.what();
      }
      energy.resize(ts.size());
      residual.resize(ts.size());
      const bool kept = rechoices_ == rechoices;  // the run kept its row choice: the lean pass (sample)
      for (size_t i = 0; i < ts.size(); ++i)
        if (kept) sample(ys.data() + i * dim, energy[i], residual[i], rechoose);
        else observe(ys.data() + i * dim, energy[i], residual[i], rechoose);
    }
    const long N = static_cast<long>(ts.size());
    py::dict result;
    result["t"] = py::array_t<double>(N, ts.data());
    py::array_t<double> y({N, static_cast<long>(dim)});
    std::copy(ys.begin(), ys.end(), y.mutable_data());
    result["y"] = y;
    result["energy"] = py::array_t<double>(N, energy.data());
    result["residual"] = py::array_t<double>(N, residual.data());
    result["status"] = interrupted ? static_cast<int>(robotdyn::INTERRUPTED) : out.status;
    result["t_stop"] = out.t;
    result["y_stop"] = py::array_t<double>(static_cast<long>(out.y.size()), out.y.data());
    result["message"] = out.message;
    result["nfev"] = nfev;
    result["steps"] = out.steps;
    result["event"] = out.event;
    result["slip_error"] = slip_error;
    result["slip_value"] = slip_value;
    result["slip_wheels"] = slip_wheels;
    result["flights"] = crossings;
    return result;
  }

  // Where an evaluation's time goes (make bench): CPU seconds per call, each part timed over `repeat` calls at (q, nu),
  // next to Pinocchio's own C++ algorithms on the same model: "evaluation" (configure + dynamics, as compute),
  // "pinocchio" (CRBA + RNEA + the frames' placements and Jacobians, the rigid-body work inside it), "crba", "rnea",
  // "frames", "rows" (constraint rows, residuals, B), "projection", "drift" (drift and w, after RNEA), "reduce"
  // (M_r, h, g_r, B_r), "rhs" (the simulation's right-hand side with the pull-back at gain `alpha`), "pull_back",
  // "gravity" (g from CRBA's composite inertias), "solve" (the right-hand side's LLT of M_r and its solve), "applied"
  // (springs and compliant wheels; 0 without), "controller" (the feedback law; 0 without), "observe" and "sample" (a
  // run's sample: its energy and residual by the whole configuration pass and by the lean one), and Pinocchio's own passes
  // as a user calls them: "kinematics" (forwardKinematics) and "pinocchio_jacobians" (CRBA + RNEA +
  // computeJointJacobians).
  // The evaluator is left evaluated at (q, nu).
  py::dict profile(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu, int repeat, double alpha) {
    if (repeat < 1) throw std::invalid_argument("repeat must be >= 1");
    configure(q);
    dynamics(nu);
    const VectorXd q0 = q, nu0 = nu;
    const VectorXd tau = VectorXd::Zero(Br_.cols());
    VectorXd out(nv_ + nu.size());
    auto seconds = [repeat](auto&& f) { return call_seconds(repeat, f); };
    auto frames = [&] {
      for (int f : frames_) pin::updateFramePlacement(model_, data_, static_cast<pin::FrameIndex>(f));
      for (size_t f = 0; f < frames_.size(); ++f) {
        Jf_[f].setZero(6, nv_);
        pin::getFrameJacobian(model_, data_, frames_[f], pin::LOCAL_WORLD_ALIGNED, Jf_[f]);
      }
    };
    auto rows = [&] {
      A_.setZero(nrows(), nv_);
      residual_.setZero(nrows());
      constraint_rows();
    };
    auto drift = [&] { drift_pass(); };
    py::dict t;
    t["evaluation"] = seconds([&] { configure(q0); dynamics(nu0); });
    t["pinocchio"] = seconds([&] {
      pin::crba(model_, data_, q_, pin::Convention::WORLD);
      bias_pass();
      frames();
    });
    t["crba"] = seconds([&] { pin::crba(model_, data_, q_, pin::Convention::WORLD); });
    t["frames"] = seconds(frames);
    t["rows"] = seconds(rows);
    t["projection"] = seconds([&] { project(); });
    t["rnea"] = seconds([&] {
      bias_pass();
      for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model_.njoints); ++i) data_.a[i] = data_.a_gf[i];
    });
    t["drift"] = seconds(drift);
    const VectorXd Cv = data_.tau;
    t["reduce"] = seconds([&] {
      data_.tau = Cv;
      reduce(data_.M, S_, g_, data_.tau, w_, B_, SM_, Mr_, hr_, gr_, Br_);
    });
    t["rhs"] = seconds([&] { rhs_into(q0, nu0, tau, alpha, out); });
    t["pull_back"] = seconds([&] { pull_back(alpha, out); });
    configure(q0);
    dynamics(nu0);
    t["gravity"] = seconds([&] { gravity_torques(model_, data_, gravity_, nv_, g_); });
    const VectorXd f0 = Br_ * tau - hr_;
    t["solve"] = seconds([&] {  // rhs_into's solve: LLT of M_r, then M_r^-1 (B_r tau - h)
      force_ = f0;
      llt_.compute(Mr_);
      llt_.solveInPlace(force_);
    });
    t["applied"] = applied() ? seconds([&] { applied_forces(); }) : 0.0;
    if (controller_) {
      control_tau_.resize(Br_.cols());
      t["controller"] = seconds([&] {
        controller_->eval(control_t_, q0, nu0, Mr_, hr_, Br_, S_, w_, v_,
                          [this](int f) { return frame_kinematics(f); }, control_tau_);
      });
    } else {
      t["controller"] = 0.0;
    }
    // a run's sample at (q, nu): its energy and residual by observe (the whole configuration pass) and by sample
    // (the lean pass after a run that kept its row choice)
    {
      std::vector<double> y(q0.data(), q0.data() + q0.size());
      y.insert(y.end(), nu0.data(), nu0.data() + nu0.size());
      const py::object none = py::none();
      double energy = 0.0, residual = 0.0;
      t["observe"] = seconds([&] { observe(y.data(), energy, residual, none); });
      t["sample"] = seconds([&] { sample(y.data(), energy, residual, none); });
    }
    // Pinocchio's own passes as a user calls them (the floor of issue 26): the joints' placements alone, and CRBA
    // (its default convention) + RNEA + computeJointJacobians, each redoing the kinematics
    t["kinematics"] = seconds([&] { pin::forwardKinematics(model_, data_, q_); });
    t["pinocchio_jacobians"] = seconds([&] {
      pin::crba(model_, data_, q_);
      pin::rnea(model_, data_, q_, v_, zero_);
      pin::computeJointJacobians(model_, data_, q_);
    });
    configure(q0);
    dynamics(nu0);
    return t;
  }

  // Many states: stacked M_r (N, k, k), h (N, k), g (N, k), S (N, n, k), w (N, n), B_r (N, k, motors).
  py::tuple evaluate_many(const Eigen::Ref<const RowMat>& Q, const Eigen::Ref<const RowMat>& NU) {
    const int N = static_cast<int>(Q.rows());
    const int k = mobility();
    const int nm = static_cast<int>(motors_.size());
    RowMat Mr(N, k * k), hr(N, k), gr(N, k), S(N, nv_ * k), w(N, nv_), B(N, k * nm);
    std::vector<int> failed;
    for (int i = 0; i < N; ++i) {
      try {
        configure(Q.row(i).transpose());
        dynamics(NU.row(i).transpose());
      } catch (const Fallback&) {
        failed.push_back(i);
        continue;
      }
      Eigen::Map<RowMat>(Mr.row(i).data(), k, k) = Mr_;
      hr.row(i) = hr_.transpose();
      gr.row(i) = gr_.transpose();
      Eigen::Map<RowMat>(S.row(i).data(), nv_, k) = S_;
      w.row(i) = w_.transpose();
      Eigen::Map<RowMat>(B.row(i).data(), k, nm) = Br_;
    }
    return py::make_tuple(Mr, hr, gr, S, w, B, failed);
  }

 private:
  // The kernels on this evaluator's state (robotdyn/kernels/), in row order: each returns the next row.
  int wheel_rows(size_t i, int row) {
    const Wheel& wh = wheels_[i];
    return kernels::wheel_rows(wh, terrain_, data_.oMf[frames_[wh.frame]], Jf_[wh.frame], q_, row, geo_[i], Aw_[i],
                               A_, residual_);
  }
  int wheel_drift(size_t i, int row) {
    const Wheel& wh = wheels_[i];
    if (wh.D.rows() == 0) return row;  // a compliant wheel: no rows
    return kernels::wheel_drift(wh, geo_[i], terrain_, model_, data_, frames_[wh.frame], Aw_[i], v_, row, drift_);
  }
  int closure_rows(size_t i, int row) {
    const Closure& c = closures_[i];
    return kernels::closure_rows(c, data_.oMf[frames_[c.f1]], data_.oMf[frames_[c.f2]], Jf_[c.f1], Jf_[c.f2], nv_, row,
                                 Jrel_, K3_, A_, residual_);
  }
  int closure_drift(size_t i, int row) {
    const Closure& c = closures_[i];
    return kernels::closure_drift(c, model_, data_, frames_[c.f1], frames_[c.f2], row, drift_);
  }
  int coupling_rows(size_t i, int row) { return kernels::coupling_rows(couplings_[i], q_, row, A_, residual_); }
  int coupling_drift(size_t i, int row) { return kernels::coupling_drift(couplings_[i], q_, v_, row, drift_); }

  void project() {  // projection.py _build / operational_space.py project_operational, with the given rows
    if (operational_)
      project_operational(A_, rows_, op_select_, model_, data_, frames_[op_frame_], op_local_, nv_, K_, Jc_, lu_,
                          Kinv_, cond_, S_);
    else if (!project_selection(A_, rows_, independent_, dependent_, nv_, lus_, lu_, sel_, cond_, S_))
      return;
    if (!differencing_) check_span(A_, S_, AS_);  // (a stiff Jacobian's difference leaves the manifold by ~1e-8)
  }

  void pull_back(double alpha, Eigen::Ref<VectorXd> out) { pull_back_.apply(holonomic_, residual_, A_, nv_, alpha, out); }

  pin::Model model_;
  pin::Data data_;
  int nv_;
  std::vector<int> frames_;
  std::vector<Wheel> wheels_;
  std::vector<Closure> closures_;
  std::vector<Coupling> couplings_;
  std::vector<std::pair<int, int>> order_;  // (0: wheel, 1: closure, 2: coupling; index), in row order
  std::vector<Motor> motors_;
  std::vector<Slip> slips_;
  std::vector<bool> holonomic_;
  Terrain terrain_;
  pin::Motion gravity_;  // the model's gravity (the Pinocchio model itself has none, see the constructor)
  std::vector<int> rows_, independent_, dependent_, op_select_;
  int op_frame_ = -1;
  bool op_local_ = true, operational_ = false, selected_ = false, configured_ = false;
  bool differencing_ = false;  // a stiff Jacobian's differences are being taken (project skips its span check)
  bool bias_fast_ = false;    // bias_pass may reuse CRBA's placements (kernels::bias_forces_apply)
  bool crba_at_q_ = false;    // data_ holds configure's CRBA at q_ for the current model
  // state and work buffers (sized on first use, then reused)
  VectorXd tau_, e_, lambda_, lr_, nudot_, a_;
  RowMat wl_, ww_, wf_, wp_;
  const double* fbuffers_[7] = {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
  long fgeneration_ = 0;
  std::optional<robotdyn::Controller> controller_;  // set_controller
  double control_t_ = 0.0;
  VectorXd control_tau_;
  VectorXd q_, v_, w_, zero_, g_, residual_, drift_, gr_, hr_, rhs_, wd_, force_;
  MatrixXd A_, S_, SM_, B_, Br_, Mr_, Kinv_, K_, AS_, Jrel_;
  SelectionBuffers sel_;  // the projection's A_d, A_i, A_d^-1, S_d
  LuSolver lus_;          // the LU substitutions' buffers
  Eigen::Matrix<double, 3, Eigen::Dynamic> K3_;
  Matrix6x Jc_;
  Eigen::PartialPivLU<MatrixXd> lu_;
  Eigen::LLT<MatrixXd> llt_;
  PullBack pull_back_;  // the pull-back's decomposition and buffers
  double cond_ = 1.0;
  RigidLimit rigid_;  // the rigid limit's split (forces) and its buffers
  SlipSystem slip_;   // the slipping wheels' system (slip_rhs_into), its results and buffers
  kernels::SlipRigidLimit slip_rl_;  // ... where the rows leave their loads open (coupled's system)
  bool slip_open_ = false, slip_coupled_ = false;
  VectorXd slip_bias_;  // C v + g - Q of the slipping wheels' system where joint springs act (slip_rhs_into)
  // joint springs and compliant wheels (applied_forces)
  std::vector<robotdyn::kernels::JointSpring> springs_;
  std::vector<robotdyn::kernels::CompliantContact> contacts_;
  std::vector<robotdyn::kernels::ContactState> contact_states_;
  VectorXd Qa_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> Ac_;
  double friction_power_ = 0.0, damper_power_ = 0.0;
  // rolling compliant wheels (add_rolling_rows): their contact index, their rows' wheel, the run's contact set, buffers
  std::vector<int> rolling_contact_;
  std::vector<Wheel> rolling_wheels_;
  std::vector<char> rolling_on_;
  MatrixXd rollG_, rollGr_, rollMinvGT_;
  VectorXd rollDrift_, rollTarget_, rollLambda_;
  // the lift-off event's cache and the state of a SlipError
  double event_t_ = std::numeric_limits<double>::quiet_NaN(), event_g_ = 0.0;

 public:
  double last_t_ = std::numeric_limits<double>::quiet_NaN();  // time of the last right-hand side evaluated

 private:
  double slip_error_t_ = 0.0;
  std::vector<double> event_y_, event_dy_, slip_error_y_;
  std::vector<double> step_y_, step_dy_, step_depths_;  // deriv_into, depths_into, event_value
  std::vector<WheelGeometry> geo_;
  std::vector<Matrix6x> Jf_;
  std::vector<MatrixXd> Aw_;
  robotdyn::derivs::Workspace deriv_;  // the derivatives' passes (kernels/reduced_dynamics_derivatives.hpp)
  const double* buffers_[7] = {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
  int run_ = -1;  // the run a batch thread is on (its rechoice callback gets it), -1 alone
  long rechoices_ = 0;  // the row choices made by the Python path so far (with_rechoice)
  long generation_ = 0;
};

// The derivative set at one state by the evaluator's kind (slipping wheels, operational velocities, else the reduced
// dynamics): for the "derivatives" binding and the batched and timed bindings below.
robotdyn::derivs::Result derivative_set(Evaluator& ev, const Eigen::Ref<const VectorXd>& q,
                                        const Eigen::Ref<const VectorXd>& nu, const Eigen::Ref<const VectorXd>& tau) {
  try {
    if (ev.slipping()) return robotdyn::SlidingDerivatives<Evaluator>::run(ev, q, nu, tau);
    if (robotdyn::OperationalDerivatives<Evaluator>::serves(ev))
      return robotdyn::OperationalDerivatives<Evaluator>::run(ev, q, nu, tau);
    return robotdyn::ReducedDerivatives<Evaluator>::run(ev, q, nu, tau);
  } catch (const std::domain_error& e) {
    throw Fallback(e.what());
  }
}

// The set's tuple (nudot, dnudot/dq, dnudot/dnu, dnudot/dtau, v, dv/dq, S, A), the matrices moved into the arrays (no
// copies), then with `check` the bits of its first six outputs that are not finite (bit i: output i), tested here
// where they were just written: robotdyn.fast.compiled_derivatives (a non-finite result is its NonFiniteError)
py::tuple derivative_tuple(robotdyn::derivs::Result&& r, bool check) {
  if (!check)
    return py::make_tuple(std::move(r.nudot), std::move(r.dq), std::move(r.dnu), std::move(r.dtau), std::move(r.v),
                          std::move(r.Vq), std::move(r.S), std::move(r.A));
  const int bad = (r.nudot.allFinite() ? 0 : 1) | (r.dq.allFinite() ? 0 : 2) | (r.dnu.allFinite() ? 0 : 4) |
                  (r.dtau.allFinite() ? 0 : 8) | (r.v.allFinite() ? 0 : 16) | (r.Vq.allFinite() ? 0 : 32);
  return py::make_tuple(std::move(r.nudot), std::move(r.dq), std::move(r.dnu), std::move(r.dtau), std::move(r.v),
                        std::move(r.Vq), std::move(r.S), std::move(r.A), bad);
}

// The state equation's Jacobians at many states, one per row of Q (N, n), NU (N, k), TAU (N, motors), in one call
// (a collocation's nodes, robotdyn.optimisation.node_batches): f_x (N, (n+k)^2), each row the row-major
// [[d(S nu)/dq, S], [dnudot/dq, dnudot/dnu]], and f_tau (N, (n+k) motors), each row [[0], [dnudot/dtau]].
// Fallback at the first state where the compiled derivatives do not serve.
py::tuple derivatives_many(Evaluator& ev, const Eigen::Ref<const RowMat>& Q, const Eigen::Ref<const RowMat>& NU,
                           const Eigen::Ref<const RowMat>& TAU) {
  const Eigen::Index N = Q.rows(), n = Q.cols(), k = NU.cols(), nm = TAU.cols(), nx = n + k;
  if (NU.rows() != N || TAU.rows() != N) throw std::invalid_argument("Q, NU and TAU need as many rows");
  RowMat Fx(N, nx * nx), Fu = RowMat::Zero(N, nx * nm);
  for (Eigen::Index i = 0; i < N; ++i) {
    const robotdyn::derivs::Result r =
        derivative_set(ev, Q.row(i).transpose(), NU.row(i).transpose(), TAU.row(i).transpose());
    if (r.Vq.rows() != n || r.dq.rows() != k || r.dtau.cols() != nm)
      throw std::invalid_argument("Q, NU, TAU: the wrong number of columns");
    Eigen::Map<RowMat> fx(Fx.row(i).data(), nx, nx), fu(Fu.row(i).data(), nx, nm);
    fx.topLeftCorner(n, n) = r.Vq;
    fx.topRightCorner(n, k) = r.S;
    fx.bottomLeftCorner(k, n) = r.dq;
    fx.bottomRightCorner(k, k) = r.dnu;
    fu.bottomRows(k) = r.dtau;
  }
  return py::make_tuple(Fx, Fu);
}

// The right-hand side (qdot, nudot) at many states, one per row of Q, NU, TAU, pull-back gain alpha: (N, nv + k)
// (a finite-difference Jacobian's evaluations in one call). Fallback as rhs.
RowMat rhs_many(Evaluator& ev, const Eigen::Ref<const RowMat>& Q, const Eigen::Ref<const RowMat>& NU,
                const Eigen::Ref<const RowMat>& TAU, double alpha) {
  const Eigen::Index N = Q.rows();
  if (NU.rows() != N || TAU.rows() != N) throw std::invalid_argument("Q, NU and TAU need as many rows");
  RowMat out(N, ev.nv() + NU.cols());
  VectorXd y(ev.nv() + NU.cols());
  for (Eigen::Index i = 0; i < N; ++i) {
    ev.rhs_into(Q.row(i).transpose(), NU.row(i).transpose(), TAU.row(i).transpose(), alpha, y);
    out.row(i) = y.transpose();
  }
  return out;
}

// CPU seconds per call (this thread's clock, no Python in the loop) of the derivative set ("derivatives") and of one
// evaluation, the right-hand side without pull-back ("rhs"), at (q, nu, tau): the ratio a finite-difference Jacobian
// of 2 (n + k + motors) evaluations is compared with (bench/bench.py trajectory_optimisation_bench).
py::dict derivatives_seconds(Evaluator& ev, const VectorXd& q, const VectorXd& nu, const VectorXd& tau, int repeat) {
  if (repeat < 1) throw std::invalid_argument("repeat must be >= 1");
  auto seconds = [repeat](auto&& f) { return call_seconds(repeat, f); };
  VectorXd out(ev.nv() + nu.size());
  double sink = 0.0;
  py::dict t;
  t["derivatives"] = seconds([&] { sink += derivative_set(ev, q, nu, tau).dq.sum(); });
  t["rhs"] = seconds([&] {
    ev.rhs_into(q, nu, tau, 0.0, out);
    sink += out[0];
  });
  t["check"] = sink;  // (kept, so that no call is optimised away)
  return t;
}

}  // namespace

PYBIND11_MODULE(_compiled, m) {
  m.doc() = "robotdyn's compiled reduced-model evaluator (see robotdyn.compiled)";
  py::register_exception<Fallback>(m, "Fallback", PyExc_RuntimeError);
  py::class_<robotdyn::Controller>(m, "Controller",
                                    "a feedback law as data (robotdyn.simulation.feedback.FeedbackLaw)")
      .def(py::init<int, int, int, const robotdyn::TorqueProfile*, const MatrixXd&, const robotdyn::TorqueProfile*,
                    const MatrixXd&, const robotdyn::TorqueProfile*, const robotdyn::TorqueProfile*>(),
           py::arg("motors"), py::arg("n"), py::arg("k"), py::arg("feedforward").none(true), py::arg("Kq"),
           py::arg("q_ref").none(true), py::arg("Knu"), py::arg("nu_ref").none(true),
           py::arg("acceleration").none(true))
      .def("set_linearising",
           [](robotdyn::Controller& c, double kp, double kd, double damping, const std::vector<int>& controlled,
              const py::list& tasks, const py::list& secondary) {
             auto read = [](const py::list& items) {
               std::vector<robotdyn::Task> out;
               for (const py::handle& item : items) {
                 const py::tuple tp = item.cast<py::tuple>();
                 robotdyn::Task task;
                 task.kind = tp[0].cast<int>();
                 task.frame = tp[1].cast<int>();
                 task.offset = tp[2].cast<Vector3d>();
                 task.select = tp[3].cast<std::vector<int>>();
                 task.y = std::make_shared<robotdyn::TorqueProfile>(tp[4].cast<const robotdyn::TorqueProfile&>());
                 task.yd = std::make_shared<robotdyn::TorqueProfile>(tp[5].cast<const robotdyn::TorqueProfile&>());
                 task.ydd = std::make_shared<robotdyn::TorqueProfile>(tp[6].cast<const robotdyn::TorqueProfile&>());
                 for (const auto& p : {task.y, task.yd, task.ydd})
                   if (p->motors() != task.dim()) throw std::invalid_argument("a task's reference has the wrong width");
                 out.push_back(std::move(task));
               }
               return out;
             };
             c.set_linearising(robotdyn::Linearising(kp, kd, damping, controlled, read(tasks), read(secondary)));
           },
           "add the input-output linearising law (robotdyn.simulation.control.LinearisingController)");
  py::class_<robotdyn::TorqueProfile>(m, "TorqueProfile",
                                      "motor torques as data (robotdyn.torque_profile): sum of constant, sine, table terms")
      .def(py::init<int, const std::vector<int>&, const std::vector<MatrixXd>&, const std::vector<std::vector<double>>&>())
      .def_property_readonly("motors", &robotdyn::TorqueProfile::motors)
      .def("__call__", [](const robotdyn::TorqueProfile& p, double t) {
        VectorXd out(p.motors());
        p.eval(t, out);
        return out;
      });
  py::class_<Evaluator>(m, "Evaluator")
      .def(py::init<const Evaluator&>(), "a copy (its own Pinocchio data and buffers)")
      .def(py::init<const std::vector<std::string>&, const std::vector<int>&, const std::vector<MatrixXd>&,
                    const std::vector<Vector3d>&, const std::vector<VectorXd>&, const Vector3d&>())
      .def("add_frame", &Evaluator::add_frame)
      .def("set_terrain", &Evaluator::set_terrain)
      .def("add_coupling", &Evaluator::add_coupling)
      .def("add_wheel", &Evaluator::add_wheel)
      .def("add_closure", &Evaluator::add_closure)
      .def("add_motor", &Evaluator::add_motor)
      .def("add_slipping", &Evaluator::add_slipping)
      .def("add_spring", &Evaluator::add_spring)
      .def("add_compliant_wheel", &Evaluator::add_compliant_wheel)
      .def("applied_state", &Evaluator::applied_state)
      .def("add_rolling_rows", &Evaluator::add_rolling_rows)
      .def("set_rolling_mode", &Evaluator::set_rolling_mode)
      .def("rolling_state", &Evaluator::rolling_state)
      .def_property_readonly("slipping", &Evaluator::slipping)
      .def_readonly("last_t", &Evaluator::last_t_, "Time [s] of the last right-hand side a simulation evaluated")
      .def_property_readonly("slip_condition", &Evaluator::slip_condition,
                             "The last slipping evaluation's Painleve test: (||K||_1 times LAPACK's estimate of "
                             "||K^-1||_1, the 2-norm condition number from the singular values or NaN where the "
                             "estimate cleared the state)")
      .def("slip_rhs", &Evaluator::slip_rhs)
      .def("set_slip_open", &Evaluator::set_slip_open)
      .def("slip_multipliers", &Evaluator::slip_multipliers)
      .def("set_selection", &Evaluator::set_selection)
      .def("set_operational", &Evaluator::set_operational)
      .def("full", &Evaluator::full)
      .def("evaluate", &Evaluator::evaluate)
      .def("compute", &Evaluator::compute)
      .def_property_readonly("M", &Evaluator::Mr, py::return_value_policy::reference_internal)
      .def_property_readonly("h", &Evaluator::hr, py::return_value_policy::reference_internal)
      .def_property_readonly("g", &Evaluator::gr, py::return_value_policy::reference_internal)
      .def_property_readonly("B", &Evaluator::Br, py::return_value_policy::reference_internal)
      .def_property_readonly("S", &Evaluator::S, py::return_value_policy::reference_internal)
      .def_property_readonly("w", &Evaluator::w, py::return_value_policy::reference_internal)
      .def_property_readonly("v", &Evaluator::v, py::return_value_policy::reference_internal)
      .def("rhs", &Evaluator::rhs)
      .def("simulate", &Evaluator::simulate)
      .def("deriv_into", &Evaluator::deriv_into, "dy = d/dt y at (t, y, alpha, profile, rechoose): one evaluation "
           "of simulate's ODE written into the float64 array dy (robotdyn.simulation.cvode)")
      .def("depths_into", &Evaluator::depths_into, "the compliant wheels' penetrations [m] at y into out (y, out, rechoose)")
      .def("event_value", &Evaluator::event_value, "the terminal event's value at (t, y, alpha, profile, rechoose): the "
           "slipping wheels' smallest load [N] or the rolling compliant wheels' switch value")
      .def_property_readonly("state_size", &Evaluator::state_size)
      .def_property_readonly("works", &Evaluator::works,
                             "The run's extra states after (q, nu): 1 (friction work) with slipping wheels, 2 (and "
                             "the damper work) with joint springs or compliant wheels, slipping wheels or not")
      .def("set_differencing", &Evaluator::set_differencing, "a Jacobian's differences are being taken (on/off)")
      .def("set_controller", &Evaluator::set_controller, py::arg("controller").none(true),
           "a feedback law replacing the torque profile in simulate (None: none)")
      .def("control_torque", &Evaluator::control_torque)
      .def("simulate_many", &Evaluator::simulate_many)
      .def("forces", &Evaluator::forces)
      .def("set_normal_stiffness", &Evaluator::set_normal_stiffness)
      .def("set_rigid_limit", &Evaluator::set_rigid_limit)
      .def_property_readonly("nudot", &Evaluator::nudot, py::return_value_policy::reference_internal)
      .def_property_readonly("lam", &Evaluator::lam, py::return_value_policy::reference_internal)
      .def_property_readonly("e", &Evaluator::e, py::return_value_policy::reference_internal)
      .def_property_readonly("wheel_local", &Evaluator::wheel_local, py::return_value_policy::reference_internal)
      .def_property_readonly("wheel_world", &Evaluator::wheel_world, py::return_value_policy::reference_internal)
      .def_property_readonly("wheel_frames", &Evaluator::wheel_frames, py::return_value_policy::reference_internal)
      .def_property_readonly("contact_points", &Evaluator::contact_points,
                             py::return_value_policy::reference_internal)
      .def("forces_at", &Evaluator::forces_at)
      .def("model_vector", &Evaluator::model_vector)
      .def("set_model_vector", &Evaluator::set_model_vector_py)
      .def("observe", [](Evaluator& ev, const VectorXd& y) {
        if (y.size() != ev.nv() + ev.mobility()) throw std::invalid_argument("y has the wrong length");
        double e, r;
        ev.observe(y.data(), e, r, py::none());
        return py::make_tuple(e, r);
      })
      .def("sample", [](Evaluator& ev, const VectorXd& y) {  // the lean pass of a run that kept its row choice
        if (y.size() != ev.nv() + ev.mobility()) throw std::invalid_argument("y has the wrong length");
        double e, r;
        ev.sample(y.data(), e, r, py::none());
        return py::make_tuple(e, r);
      })
      .def("evaluate_many", &Evaluator::evaluate_many)
      .def("derivatives",  // (q, nu, tau as Eigen::Ref: a float64 array is read in place, not copied)
           [](Evaluator& ev, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
              const Eigen::Ref<const VectorXd>& tau) { return derivative_tuple(derivative_set(ev, q, nu, tau), false); },
           "(nudot, dnudot/dq, dnudot/dnu, dnudot/dtau, v, dv/dq, S, A) at (q, nu, tau) "
           "(robotdyn.fast.compiled_derivatives)")
      .def("derivatives_checked",
           [](Evaluator& ev, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
              const Eigen::Ref<const VectorXd>& tau) { return derivative_tuple(derivative_set(ev, q, nu, tau), true); },
           "the derivatives' tuple and the bits of its first six outputs that are not finite (bit i: output i) "
           "(robotdyn.fast.compiled_derivatives)")
      .def("force_chain",
           [](Evaluator& ev, const VectorXd& q, const VectorXd& nu, const VectorXd& tau) {
             using CFD = robotdyn::ContactForcesDerivatives<Evaluator>;
             robotdyn::derivs::Result r;
             robotdyn::derivs::ForceChain c;
             try {
               r = robotdyn::ReducedDerivatives<Evaluator>::run(ev, q, nu, tau);
               c = CFD::chain(ev, r);
             } catch (const std::domain_error& e) {
               throw Fallback(e.what());
             }
             return py::make_tuple(r.nudot, r.dq, r.dnu, r.dtau, r.v, r.Vq, r.S, r.A, c.a, c.Aq, c.Wnu);
           },
           "the derivatives' tuple, then (a, da/dq at fixed nudot, dw/dnu) at (q, nu, tau) "
           "(robotdyn.contact.compiled_force_derivatives)")
      .def("force_layer",
           [](Evaluator& ev, const VectorXd& q, const VectorXd& v, const VectorXd& a, const VectorXd& tau,
              const VectorXd& k, const std::vector<int>& unloaded, bool split) {
             robotdyn::derivs::ForceLayer l;
             try {
               l = robotdyn::ContactForcesDerivatives<Evaluator>::layer(ev, q, v, a, tau, k, unloaded, split);
             } catch (const std::domain_error& e) {
               throw Fallback(e.what());
             }
             return py::make_tuple(l.lam, l.dq, l.dv, l.da, l.dtau, l.residual);
           },
           "(lambda, dlambda/dq, dlambda/dv, dlambda/da, dlambda/dtau, residual) at (q, v, a, tau) with the wheels' "
           "normal stiffnesses and the unloaded wheels' indices (robotdyn.contact.compiled_force_derivatives)")
      .def("profile", &Evaluator::profile, py::arg("q"), py::arg("nu"), py::arg("repeat"), py::arg("alpha") = 0.0,
           "seconds per call of each part of an evaluation, and of Pinocchio's CRBA + RNEA + frame Jacobians")
      .def("derivatives_many", &derivatives_many, "(f_x (N, (n+k)^2), f_tau (N, (n+k) motors)) at the rows of (Q, NU, "
           "TAU) (robotdyn.optimisation.node_batches)")
      .def("rhs_many", &rhs_many, "(qdot, nudot) at the rows of (Q, NU, TAU), gain alpha: (N, nv + k)")
      .def("derivatives_seconds", &derivatives_seconds, py::arg("q"), py::arg("nu"), py::arg("tau"), py::arg("repeat"),
           "CPU seconds per call of the derivative set and of one evaluation (rhs), timed in C++")
      .def_property_readonly("condition", &Evaluator::condition,
                             "1-norm condition number of the last projection's block: LAPACK's estimate below 1e8, "
                             "exact above (operational velocities: exact)")
      .def_property_readonly("nv", &Evaluator::nv)
      .def_property_readonly("nrows", &Evaluator::nrows);
}

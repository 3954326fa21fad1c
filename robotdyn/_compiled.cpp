// robotdyn._compiled: the reduced model evaluated in one compiled call (see robotdyn/compiled.py).
//
// Same formulas as the Python reference, in the same order:
//   rolling contact             robotdyn/rolling_contact.py (per wheel), robotdyn/wheel_group.py (fast path)
//   terrains                    robotdyn/terrain.py (plane/ramp, sine, bump)
//   loop closures               robotdyn/loop_closure.py
//   joint couplings             robotdyn/joint_coupling.py (cosine laws)
//   projection                  robotdyn/projection.py (_build: S = P [I; -Ad^-1 Ai], w = -Ad^-1 drift)
//   operational velocities      robotdyn/operational_space.py (K = [A_r; J_o], K S = [0; I])
//   motors                      robotdyn/actuation.py
//   dynamics                    robotdyn/reduced_dynamics.py (M_r = S^T M S, h = S^T RNEA(q, S nu, w), here
//                               S^T (C v + g + M w): two Pinocchio passes per state, CRBA (M, g from its
//                               composite inertias) and RNEA without gravity (C v, and the drift's accelerations))
// The rigid-body algorithms are Pinocchio's (header-only use of the installed Pinocchio 4), on a copy of the
// robot's Pinocchio model rebuilt joint by joint; tests/test_compiled.py checks every output against the Python
// path on every robot.
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/model.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/frames.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "_integrator.hpp"
#include "_torque_profile.hpp"
#include "_controller.hpp"
#include "kernels/reduced_dynamics_derivatives.hpp"  // the derivatives (robotdyn/fast/compiled_derivatives.py)

#include <pybind11/pybind11.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace py = pybind11;
namespace pin = pinocchio;
using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;
using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Matrix6x = Eigen::Matrix<double, 6, Eigen::Dynamic>;

namespace {

// A failure the Python side handles by falling back to the reference path (which raises the proper error).
struct Fallback : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Wheel {
  int frame;       // index into Evaluator::frames
  Vector3d axis;   // axle in the wheel frame (unit)
  double radius;   // m (plus q[radius_index] when radius_index >= 0)
  int radius_index;
  Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 3, 3> D;  // (nd, 3) rows as coefficients of (t1, t2, n)
};

// A wheel whose tangential force follows a friction law (robotdyn/sliding.py, robotdyn/friction.py): F_t = -f_n c(s)
// on its free directions (t1, t2), with the law
//   0 RegularisedCoulomb   c = p0 s / sqrt(|s|^2 + p1^2)          (p0 = mu, p1 = slip velocity [m/s])
//   1 LinearTyre           c = p0 s if p0 |s| <= p1, else p1 s/|s|  (p0 = stiffness [s/m], p1 = mu, inf allowed)
struct Slip {
  int wheel;       // index into Evaluator::wheels_
  int normal_row;  // its normal row (index into the stacked rows)
  int law;
  double p0, p1;
  Eigen::Vector2d free;  // 1: the direction follows the law, 0: it rolls (its no-slip row stays a constraint)
};

// The slipping wheels' contact problem cannot be solved here: kind 0 singular (Painleve; value: its 2-norm
// condition number), kind 1 a slipping wheel's normal row is not among the projection's rows (value: the slip's
// index). The Python side raises the reference path's error from it (robotdyn/compiled_simulation.py).
struct SlipError : std::runtime_error {
  SlipError(int kind_, double value_)
      : std::runtime_error(kind_ == 0 ? "singular slipping contact problem" : "slipping wheel's normal row redundant"),
        kind(kind_), value(value_) {}
  int kind;
  double value;
};

struct Coupling {  // q[i] = amplitude cos(rate q[j] + phase) + offset
  int i, j;
  double amplitude, rate, phase, offset;
};

// z = f(x, y): 0 plane h + gx x + gy y; 1 sine a sin(kx x + ky y + phase); 2 smooth step(s) (tanh), as terrain.py
struct Terrain {
  int kind = 0;
  double c[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
  bool flat() const { return kind == 0; }
  void step(double x, double x0, double& f, double& fx, double& fxx) const {
    const double h = c[0], w = c[2];
    const double t = std::tanh((x - x0) / w), s = 1.0 - t * t;
    f = 0.5 * h * (1 + t);
    fx = 0.5 * h * s / w;
    fxx = -h * t * s / (w * w);
  }
  // height, gradient and Hessian at (x, y)
  void eval(double x, double y, double& f, Eigen::Vector2d& g, Eigen::Matrix2d& H) const {
    if (kind == 0) {
      f = c[0] + c[1] * x + c[2] * y;
      g << c[1], c[2];
      H.setZero();
    } else if (kind == 1) {
      const double arg = c[1] * x + c[2] * y + c[3];
      f = c[0] * std::sin(arg);
      const double co = c[0] * std::cos(arg);
      g << co * c[1], co * c[2];
      const double si = -c[0] * std::sin(arg);
      H << si * c[1] * c[1], si * c[1] * c[2], si * c[2] * c[1], si * c[2] * c[2];
    } else {
      double fx, fxx;
      step(x, c[1], f, fx, fxx);
      if (!std::isnan(c[3])) {
        double f2, fx2, fxx2;
        step(x, c[1] + c[3], f2, fx2, fxx2);
        f -= f2;
        fx -= fx2;
        fxx -= fxx2;
      }
      g << fx, 0.0;
      H << fxx, 0.0, 0.0, 0.0;
    }
  }
  Vector3d normal(double x, double y) const {
    double f;
    Eigen::Vector2d g;
    Eigen::Matrix2d H;
    eval(x, y, f, g, H);
    Vector3d m(-g[0], -g[1], 1.0);
    return m / m.norm();
  }
};

struct Closure {
  int f1, f2;              // indices into Evaluator::frames
  std::vector<int> select; // components 0..5 (x y z rx ry rz) in frame 1's axes
};

struct Motor {
  int index;     // velocity index of the driven joint
  int joint;     // joint id
  int reaction;  // index into frames, -1: the joint's parent (a unit column)
};

struct Geometry {  // configuration-level quantities of one wheel
  Vector3d a, u, n, t1, t2;
  Matrix3d N;  // dn/dp on a curved terrain
  double na, nw, nc1, R;
  Vector3d p;  // contact point (world)
  int row;     // the wheel's first row
};

inline Matrix3d skew(const Vector3d& x) {
  Matrix3d m;
  m << 0.0, -x[2], x[1], x[2], 0.0, -x[0], -x[1], x[0], 0.0;
  return m;
}

class Evaluator {
  template <class> friend struct robotdyn::ReducedDerivatives;  // kernels/reduced_dynamics_derivatives.hpp

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
  }

  // ----------------------------------------------------------------------------------------------- set-up
  int add_frame(int joint, const MatrixXd& P) {
    pin::SE3 placement(Matrix3d(P.leftCols<3>()), Vector3d(P.col(3)));
    std::string name = "f" + std::to_string(frames_.size());
    frames_.push_back(static_cast<int>(model_.addFrame(
        pin::Frame(name, static_cast<pin::JointIndex>(joint), 0, placement, pin::OP_FRAME))));
    data_ = pin::Data(model_);
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
  // The rows used and the independent velocity indices (a selection of v).
  void set_selection(const std::vector<int>& rows, const std::vector<int>& independent,
                     const std::vector<int>& dependent) {
    rows_ = rows;
    independent_ = independent;
    dependent_ = dependent;
    operational_ = false;
    selected_ = true;
  }
  // Operational velocities: nu = J_o v with J_o the selected components of a frame's twist (local or world axes).
  void set_operational(const std::vector<int>& rows, int frame, const std::vector<int>& select, bool local) {
    rows_ = rows;
    op_frame_ = frame;
    op_select_ = select;
    op_local_ = local;
    operational_ = true;
    selected_ = true;
  }

  int nv() const { return nv_; }
  double condition() const { return cond_; }
  py::tuple slip_condition() const { return py::make_tuple(slip_kappa1_, slip_kappa2_); }
  int nrows() const { return static_cast<int>(holonomic_.size()); }
  int mobility() const {
    return operational_ ? static_cast<int>(op_select_.size()) : static_cast<int>(independent_.size());
  }

  // The full-coordinate model at q (for the self-check against the Python model): M, g and RNEA(q, v, a).
  py::tuple full(const VectorXd& q, const VectorXd& v, const VectorXd& a) {
    model_.gravity = gravity_;
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
    q_ = q;
    // one pass: placements, world joint Jacobians, M (upper triangle) and the subtrees' composite inertias, from
    // which g_k = -J_k^T (Y_subtree(k) * gravity): the torque that holds the subtree's weight
    pin::crba(model_, data_, q_, pin::Convention::WORLD);
    g_.resize(nv_);
    for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model_.njoints); ++i) {
      const int col = model_.joints[i].idx_v();
      const pin::Force weight = data_.oYcrb[i] * gravity_;
      g_[col] = -(data_.J.col(col).head<3>().dot(weight.linear()) + data_.J.col(col).tail<3>().dot(weight.angular()));
    }
    pin::updateFramePlacements(model_, data_);
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
    int row = 0;
    for (const auto& [kind, i] : order_)
      row = kind == 0 ? wheel_rows(i, row) : kind == 1 ? closure_rows(i, row) : coupling_rows(i, row);
    B_.setZero(nv_, motors_.size());
    for (size_t j = 0; j < motors_.size(); ++j) {
      const Motor& mo = motors_[j];
      if (mo.reaction < 0) {
        B_(mo.index, j) = 1.0;
        continue;
      }
      // the joint's angular Jacobian is CRBA's world one (data_.J) on its supporting joints' columns (an angular
      // velocity does not depend on the reference point), so no Jacobian of the joint is assembled; a prismatic
      // joint's column is its axis in either convention
      const Vector3d ang = data_.J.col(mo.index).tail<3>();
      const Vector3d axis = ang.squaredNorm() > 0.25 ? ang : Vector3d(data_.J.col(mo.index).head<3>());
      B_.col(j).noalias() = -(Jf_[mo.reaction].bottomRows<3>().transpose() * axis);
      for (const pin::JointIndex s : model_.supports[mo.joint]) {
        if (s == 0) continue;
        const int c0 = model_.joints[s].idx_v();
        for (int c = c0; c < c0 + model_.joints[s].nv(); ++c) B_(c, j) += data_.J.col(c).tail<3>().dot(axis);
      }
    }
    project();
  }

  // State level: v = S nu, the drift, w and the dynamics.
  void dynamics(const Eigen::Ref<const VectorXd>& nu) {
    if (nu.size() != S_.cols()) throw std::invalid_argument("nu has the wrong length");
    v_.noalias() = S_ * nu;
    // one pass: RNEA(q, v, 0) without gravity = C v, whose forward sweep leaves the joint velocities and their
    // accelerations at zero joint acceleration (for the drift terms); RNEA(q, v, w) = C v + g + M w
    pin::rnea(model_, data_, q_, v_, zero_);
    for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model_.njoints); ++i) data_.a[i] = data_.a_gf[i];
    drift_.setZero(nrows());
    int row = 0;
    for (const auto& [kind, i] : order_)
      row = kind == 0 ? wheel_drift(i, row) : kind == 1 ? closure_drift(i, row) : coupling_drift(i, row);
    w_.setZero(nv_);
    const int nr = static_cast<int>(rows_.size());
    if (operational_) {
      rhs_.resize(nv_);
      for (int r = 0; r < nr; ++r) rhs_[r] = drift_[rows_[r]];
      operational_drift(rhs_);
      w_.noalias() = -Kinv_ * rhs_;
    } else if (nr) {
      rhs_.resize(nr);
      for (int r = 0; r < nr; ++r) rhs_[r] = drift_[rows_[r]];
      lu_solve(lu_, rhs_);
      wd_ = -rhs_;
      for (int r = 0; r < nr; ++r) w_[dependent_[r]] = wd_[r];
    }
    data_.M.triangularView<Eigen::StrictlyLower>() = data_.M.transpose().triangularView<Eigen::StrictlyLower>();
    SM_.noalias() = data_.M.lazyProduct(S_);
    Mr_.noalias() = S_.transpose().lazyProduct(SM_);
    gr_.noalias() = S_.transpose() * g_;
    data_.tau += g_;
    hr_.noalias() = S_.transpose() * data_.tau;
    hr_.noalias() += SM_.transpose() * w_;
    Br_.noalias() = S_.transpose().lazyProduct(B_);
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
    configure(q);
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
    llt_.compute(Mr_);
    llt_.solveInPlace(force_);
    out.tail(k) = force_;
  }

  // ------------------------------------------------------------------------------------------ slipping wheels
  // c(s) of a slipping wheel's law on its free directions (FrictionLaw.coefficient, SlippingWheel.
  // friction_coefficient), in the Python formulas' order of operations.
  static Eigen::Vector2d coefficient(const Slip& sl, const Eigen::Vector2d& slip) {
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

  // d/dt of (q, nu, W) with slipping wheels (robotdyn/sliding.py forward): the accelerations and the normal loads
  // from one linear system
  //   [M S,  -(A_R^T - sum_i J_t,i^T c_i e_i^T)] [nudot; lambda] = B tau - RNEA(q, v, w),
  // A_R the projection's rows, J_t,i = (t1, t2)^T A_w,i the tangential rows of slipping wheel i, s_i = J_t,i v its
  // slip velocity, c_i = c(s_i), e_i selecting its normal load; W-dot = sum_i F_i . s_i, F_i = -f_n,i c_i (the
  // friction power). The system's 2-norm condition number above 1e12 is the Painleve case (SlipError 0), decided
  // as numpy.linalg.cond would: LAPACK's 1-norm estimate from the LU factors clears regular states, the singular
  // values decide near the threshold (the rule below). Leaves the normal loads in slip_normal_ and their minimum
  // (the lift-off event's value) in slip_min_, the condition numbers of the test in slip_kappa1_, slip_kappa2_.
  void slip_rhs_into(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                     const Eigen::Ref<const VectorXd>& tau, double alpha, Eigen::Ref<VectorXd> out) {
    configure(q);
    dynamics(nu);
    const int k = static_cast<int>(S_.cols());
    const int nr = static_cast<int>(rows_.size());
    const int nw = static_cast<int>(slips_.size());
    if (tau.size() != Br_.cols()) throw std::invalid_argument("tau has the wrong length");
    if (out.size() != nv_ + k + 1) throw std::invalid_argument("state has the wrong length");
    if (k + nr != nv_) throw Fallback("rows and independent velocities do not make a square system");
    Ks_.resize(nv_, nv_);
    Ks_.leftCols(k) = SM_;  // M S (dynamics)
    for (int r = 0; r < nr; ++r) Ks_.col(k + r) = -A_.row(rows_[r]).transpose();
    slip_pos_.resize(nw);
    slip_s_.resize(nw, 2);
    slip_c_.resize(nw, 2);
    Jt_.resize(2, nv_);
    for (int i = 0; i < nw; ++i) {
      const Slip& sl = slips_[i];
      const auto hit = std::find(rows_.begin(), rows_.end(), sl.normal_row);
      if (hit == rows_.end()) throw SlipError(1, i);
      slip_pos_[i] = static_cast<int>(hit - rows_.begin());
      const Geometry& g = geo_[sl.wheel];
      Jt_.row(0).noalias() = g.t1.transpose() * Aw_[sl.wheel];
      Jt_.row(1).noalias() = g.t2.transpose() * Aw_[sl.wheel];
      const Eigen::Vector2d s = Jt_ * v_;
      const Eigen::Vector2d c = coefficient(sl, s);
      slip_s_.row(i) = s.transpose();
      slip_c_.row(i) = c.transpose();
      Ks_.col(k + slip_pos_[i]).noalias() += Jt_.transpose() * c;
    }
    bs_.noalias() = B_ * tau;
    bs_ -= data_.tau;  // C v + g (dynamics)
    bs_.noalias() -= data_.M * w_;
    slip_lu_.compute(Ks_);
    // Painleve test, the decision of the Python path's np.linalg.cond(K) > 1e12 (2-norm) without an O(n^3) inverse
    // or SVD at regular states. From the LU factors just computed, LAPACK's O(n^2) estimate e of ||K^-1||_1 (the
    // projection's estimator, inverse_norm_estimate) gives kappa_1 ~ ||K||_1 e. For n x n matrices
    // kappa_2 <= n kappa_1, and e <= ||K^-1||_1 underestimates by a small factor in practice (the projection
    // counts on 100: its estimate decides below 1e8 against its bound 1e10). So:
    //   n ||K||_1 e <= 1e12 / 100  ->  regular, no further work (kappa_2 <= 1e12 unless e underestimates by > 100);
    //   otherwise (near the threshold, beyond it, or NaN / inf from a zero pivot) the singular values decide,
    //   exactly as numpy.linalg.cond does (kappa_2 = s_max / s_min, singular above 1e12 or not finite), and give
    //   the value the Python path reports.
    // The band [1e10 / n, 1e12] of estimates that pay for the SVD is a factor 100 n wide: only a state near
    // Painleve pays there.
    slip_kappa1_ = Ks_.cwiseAbs().colwise().sum().maxCoeff() * inverse_norm_estimate(slip_lu_);
    slip_kappa2_ = std::numeric_limits<double>::quiet_NaN();  // (not computed)
    if (!(nv_ * slip_kappa1_ <= 1e12 / 100)) {  // NaN too
      slip_svd_.compute(Ks_);
      const VectorXd& sv = slip_svd_.singularValues();
      const double cond = sv[0] / sv[sv.size() - 1];
      slip_kappa2_ = std::isnan(cond) ? HUGE_VAL : cond;
      if (!(std::isfinite(cond) && cond <= 1e12)) throw SlipError(0, slip_kappa2_);
    }
    xs_ = slip_lu_.solve(bs_);
    out.head(nv_) = v_;
    if (alpha != 0.0) pull_back(alpha, out);
    out.segment(nv_, k) = xs_.head(k);
    slip_normal_.resize(nw);
    double power = 0.0;
    slip_min_ = HUGE_VAL;
    for (int i = 0; i < nw; ++i) {
      const double fn = xs_[k + slip_pos_[i]];
      slip_normal_[i] = fn;
      slip_min_ = std::min(slip_min_, fn);
      power += -fn * slip_c_(i, 0) * slip_s_(i, 0) + -fn * slip_c_(i, 1) * slip_s_(i, 1);
    }
    out[nv_ + k] = power;
  }

  // (d/dt (q, nu, W), normal loads (W,), slip velocities (W, 2), friction forces (W, 2)) at one state: the compiled
  // sliding.forward (tests compare it with the Python path).
  py::tuple slip_rhs(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                     const Eigen::Ref<const VectorXd>& tau, double alpha) {
    if (slips_.empty()) throw std::invalid_argument("no slipping wheels");
    VectorXd out(nv_ + nu.size() + 1);
    slip_rhs_into(q, nu, tau, alpha, out);
    RowMat force(slips_.size(), 2);
    for (size_t i = 0; i < slips_.size(); ++i) force.row(i) = -slip_normal_[i] * slip_c_.row(i);
    return py::make_tuple(out, slip_normal_, RowMat(slip_s_), force);
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
    if (!slips_.empty()) throw std::invalid_argument("feedback laws do not run with slipping wheels");
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
      return;
    }
    try {  // y = (q, nu, friction work)
      with_rechoice(y.data(), rechoose, [&] {
        slip_rhs_into(Eigen::Map<const VectorXd>(y.data(), nv_), Eigen::Map<const VectorXd>(y.data() + nv_, k),
                      tau_, alpha, Eigen::Map<VectorXd>(dy.data(), nv_ + k + 1));
      });
    } catch (const SlipError&) {
      slip_error_t_ = t;
      slip_error_y_ = y;
      throw;
    }
    event_t_ = t;  // the lift-off event's value at this state (lift_off reuses it)
    event_y_ = y;
    event_g_ = slip_min_;
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

  // Total mechanical energy [J] (kinetic 1/2 v^T M v, potential -sum m_i g . c_i as Pinocchio's
  // computePotentialEnergy) and the largest holonomic residual at a state y = (q, nu).
  void observe(const double* y, double& energy, double& residual, const py::object& rechoose) {
    with_rechoice(y, rechoose, [&] { configure(Eigen::Map<const VectorXd>(y, nv_)); });
    v_.noalias() = S_ * Eigen::Map<const VectorXd>(y + nv_, mobility());  // (no dynamics needed)
    double potential = 0.0;
    for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model_.njoints); ++i) {
      const pin::Inertia& Y = model_.inertias[i];
      potential -= Y.mass() * gravity_.linear().dot(data_.oMi[i].act(Y.lever()));
    }
    energy = 0.5 * v_.dot(data_.M.selfadjointView<Eigen::Upper>() * v_) + potential;  // CRBA fills the upper part
    residual = 0.0;
    for (size_t r = 0; r < holonomic_.size(); ++r)
      if (holonomic_[r]) residual = std::max(residual, std::fabs(residual_[r]));
  }

  // ------------------------------------------------------------------------------------------ constraint forces
  // lambda of A^T lambda = e, e = M a + C v + g - B tau (robotdyn/contact_forces.py), on the rows the projection
  // uses: with the LU factors of A_d (the projection's own factorisation), A_d^T lambda_r = e_d; with operational
  // velocities by the projection's K^-1 (K = [A_r; J_o]). Rows outside the projection's choice (redundant ones) get zero: lambda is the
  // basic solution, equal to every other solution on the rows that rigid-body dynamics determine (the Python side
  // reports the others with the null space of A^T). After dynamics() (forward: nudot from the torques) or with a
  // given full acceleration a (forces_at).
  void lambda_from(const Eigen::Ref<const VectorXd>& tau) {
    force_.noalias() = B_ * tau;
    e_ -= force_;
    lambda_.setZero(nrows());
    const int nr = static_cast<int>(rows_.size());
    if (!nr) return;
    if (operational_) {  // K = [A_r; J_o] with K S = [0; I]: K^T (lambda_r, 0) = e, so lambda_r = (K^-T e)_head
      lr_.noalias() = Kinv_.transpose() * e_;
      lr_.conservativeResize(nr);
    } else {
      lr_.resize(nr);
      for (int r = 0; r < nr; ++r) lr_[r] = e_[dependent_[r]];
      lu_solve_transposed(lu_, lr_);
    }
    for (int r = 0; r < nr; ++r) lambda_[rows_[r]] = lr_[r];
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
    llt_.compute(Mr_);
    if (llt_.info() != Eigen::Success) throw Fallback("reduced mass matrix not positive definite");
    nudot_ = force_;
    llt_.solveInPlace(nudot_);
    a_ = w_;
    a_.noalias() += S_ * nudot_;
    e_ = data_.tau;  // C v + g (dynamics)
    e_.noalias() += data_.M * a_;
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
    const int m = nrows();
    const int nw = static_cast<int>(wheels_.size());
    if (!rigid_limit_ || static_cast<int>(rows_.size()) >= m || nw == 0 || m == 0) return;
    const double scale = std::max(1.0, A_.cwiseAbs().maxCoeff());
    for (int r = 0; r < m; ++r)
      if (A_.row(r).cwiseAbs().maxCoeff() <= 1e-12 * scale) return;
    const int nr = static_cast<int>(rows_.size());
    int d;
    if (!operational_) {
      // a basis of null(A^T) from the projection's own LU of A_d: each row j outside the projection's choice is
      // A_j = c^T A_R with A_d^T c = (A_j on the dependent columns), so e_j - sum_r c_r e_{rows_r} is in null(A^T)
      d = m - nr;
      rl_N_.setZero(m, d);
      rl_in_.assign(m, false);
      for (int r = 0; r < nr; ++r) rl_in_[rows_[r]] = true;
      int col = 0;
      for (int j = 0; j < m; ++j) {
        if (rl_in_[j]) continue;
        rl_c_.resize(nr);
        for (int r = 0; r < nr; ++r) rl_c_[r] = A_(j, dependent_[r]);
        lu_solve_transposed(lu_, rl_c_);
        rl_N_(j, col) = 1.0;
        for (int r = 0; r < nr; ++r) rl_N_(rows_[r], col) = -rl_c_[r];
        ++col;
      }
    } else {
      rl_qr_.setThreshold(std::max(m, nv_) * std::numeric_limits<double>::epsilon());
      rl_qr_.compute(A_);
      d = m - static_cast<int>(rl_qr_.rank());
      if (d <= 0) return;
      rl_Q_ = rl_qr_.householderQ();
      rl_N_ = rl_Q_.rightCols(d);
    }
    rl_P_.setZero(nw, d);
    rl_n0_.setZero(nw);
    for (int i = 0; i < nw; ++i) {
      const Wheel& wh = wheels_[i];
      const int row = geo_[i].row;
      for (int r = 0; r < wh.D.rows(); ++r) {
        const double c = wh.D(r, 2);
        if (c == 0.0) continue;
        rl_P_.row(i) += c * rl_N_.row(row + r);
        rl_n0_[i] += c * lambda_[row + r];
      }
    }
    rl_svd_.compute(rl_P_, Eigen::ComputeFullV);
    const VectorXd& sv = rl_svd_.singularValues();
    int p = 0;
    while (p < sv.size() && sv[p] > 1e-9) ++p;
    if (p == 0) return;
    const MatrixXd& V = rl_svd_.matrixV();
    if (rl_rk_.size() != nw) rl_rk_.setOnes(nw);  // 1 / sqrt(k) (set_normal_stiffness; equal without it)
    rl_G_.noalias() = rl_P_ * V.leftCols(p);
    rl_W_.noalias() = rl_rk_.asDiagonal() * rl_G_;
    rl_H_.noalias() = rl_W_.transpose() * rl_W_;
    rl_y_.noalias() = rl_W_.transpose() * rl_rk_.cwiseProduct(rl_n0_);
    rl_llt_.compute(rl_H_);
    rl_llt_.solveInPlace(rl_y_);
    rl_y_ = -rl_y_;
    rl_n_ = rl_n0_;
    rl_n_.noalias() += rl_G_ * rl_y_;
    const double big = std::max(rl_n0_.cwiseAbs().maxCoeff(), rl_n_.cwiseAbs().maxCoeff());
    if (!rl_y_.allFinite()) throw Fallback("the rigid limit's split is not finite here");
    if (rl_n_.minCoeff() < -1e-9 * big)
      throw Fallback("a wheel would pull: the rigid limit's no-pull split is solved on the Python path");
    rl_saved_ = lambda_;
    rl_z_.noalias() = V.leftCols(p) * rl_y_;
    lambda_.noalias() += rl_N_ * rl_z_;
    if (d > p) {  // minimum norm along the open directions N V_o (Gram-Schmidt: N need not be orthonormal)
      rl_O_.noalias() = rl_N_ * V.rightCols(d - p);
      for (int c = 0; c < d - p; ++c) {
        for (int b = 0; b < c; ++b) rl_O_.col(c) -= rl_O_.col(b).dot(rl_O_.col(c)) * rl_O_.col(b);
        rl_O_.col(c) /= rl_O_.col(c).norm();
      }
      rl_t_.noalias() = rl_O_.transpose() * lambda_;
      lambda_.noalias() -= rl_O_ * rl_t_;
    }
    rl_w_ = rl_N_.rowwise().squaredNorm();  // (a row's weight in null(A^T) is zero in every basis)
    for (int r = 0; r < m; ++r)
      if (rl_w_[r] <= 1e-16) lambda_[r] = rl_saved_[r];
  }
  void set_normal_stiffness(const Eigen::Ref<const VectorXd>& k) {
    if (k.size() != static_cast<Eigen::Index>(wheels_.size())) throw std::invalid_argument("one stiffness per wheel");
    if (!(k.array() > 0.0).all() || !k.allFinite()) throw std::invalid_argument("stiffnesses must be finite and > 0");
    kstiff_ = k;
    rl_rk_ = k.cwiseSqrt().cwiseInverse();
  }
  void set_rigid_limit(bool on) { rigid_limit_ = on; }

  // Per wheel: the force along (t1, t2, n), the same in world axes, the contact frame (rows t1, t2, n: (nw, 9),
  // row-major) and the contact point (nw, 3).
  void fill_wheel_forces() {
    const int nw = static_cast<int>(wheels_.size());
    wl_.resize(nw, 3);
    ww_.resize(nw, 3);
    wf_.resize(nw, 9);
    wp_.resize(nw, 3);
    for (int i = 0; i < nw; ++i) {
      const Geometry& g = geo_[i];
      const Wheel& wh = wheels_[i];
      const Vector3d f = wh.D.transpose() * lambda_.segment(g.row, wh.D.rows());
      wl_.row(i) = f.transpose();
      ww_.row(i) = (f[0] * g.t1 + f[1] * g.t2 + f[2] * g.n).transpose();
      wf_.row(i) << g.t1.transpose(), g.t2.transpose(), g.n.transpose();
      wp_.row(i) = g.p.transpose();
    }
  }
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
          robotdyn::Outcome out = robotdyn::integrate(method, system, y0, 0.0, t_end, samples, next, breaks[i], rtol,
                                                      atol, observer, poll);
          for (long j = 0; j < count; ++j) ev.observe(yi + j * dim, ei[j], ri[j], rechoose);
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
    const int dim = nv_ + k + (slipping ? 1 : 0);  // slipping wheels: the friction work as the last component
    robotdyn::State y0(dim, 0.0);
    Eigen::Map<VectorXd>(y0.data(), nv_) = q0;
    Eigen::Map<VectorXd>(y0.data() + nv_, k) = nu0;
    std::vector<double> ts, ys, energy, residual;
    ts.reserve(samples.size());
    ys.reserve(samples.size() * dim);
    long nfev = 0;
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
    } lift_off{this, alpha, &profile, &rechoose, slipping};
    int slip_error = -1;
    double slip_value = 0.0;
    {
      py::gil_scoped_release release;
      try {
        out = robotdyn::integrate(method, system, y0, t0, t_end, samples, next, breaks, rtol, atol, observer, poll,
                                  lift_off);
      } catch (const SlipError& e) {
        slip_error = e.kind;
        slip_value = e.value;
        out.status = robotdyn::FAILED;
        out.t = slip_error_t_;
        out.y = slip_error_y_;
        out.message = e.what();
      }
      energy.resize(ts.size());
      residual.resize(ts.size());
      for (size_t i = 0; i < ts.size(); ++i) observe(ys.data() + i * dim, energy[i], residual[i], rechoose);
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
    return result;
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
  // A^-1 x in place, with LU factors P A = L U (the projection's A_d in lu_, the slipping system's K in slip_lu_):
  // vector triangular solves, no temporaries
  void lu_solve(const Eigen::PartialPivLU<MatrixXd>& lu, Eigen::Ref<VectorXd> x) {
    // substitutions written out: for the small blocks of a projection they cost a fraction of Eigen's generic
    // triangular solvers
    const MatrixXd& LU = lu.matrixLU();
    const auto& perm = lu.permutationP().indices();  // (P x)[perm[i]] = x[i]
    const Eigen::Index n = x.size();
    perm_.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) perm_[perm[i]] = x[i];
    for (Eigen::Index i = 1; i < n; ++i) {  // L (unit lower)
      double s = perm_[i];
      for (Eigen::Index j = 0; j < i; ++j) s -= LU(i, j) * perm_[j];
      perm_[i] = s;
    }
    for (Eigen::Index i = n - 1; i >= 0; --i) {  // U
      double s = perm_[i];
      for (Eigen::Index j = i + 1; j < n; ++j) s -= LU(i, j) * perm_[j];
      perm_[i] = s / LU(i, i);
    }
    x = perm_;
  }
  // A^-T x in place (A = P^T L U, so A^T = U^T L^T P)
  void lu_solve_transposed(const Eigen::PartialPivLU<MatrixXd>& lu, Eigen::Ref<VectorXd> x) {
    const MatrixXd& LU = lu.matrixLU();
    const Eigen::Index n = x.size();
    for (Eigen::Index i = 0; i < n; ++i) {  // U^T (lower)
      double s = x[i];
      for (Eigen::Index j = 0; j < i; ++j) s -= LU(j, i) * x[j];
      x[i] = s / LU(i, i);
    }
    for (Eigen::Index i = n - 2; i >= 0; --i) {  // L^T (unit upper)
      double s = x[i];
      for (Eigen::Index j = i + 1; j < n; ++j) s -= LU(j, i) * x[j];
      x[i] = s;
    }
    const auto& perm = lu.permutationP().indices();  // (P^T x)[i] = x[perm[i]]
    perm_.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) perm_[i] = x[perm[i]];
    x = perm_;
  }
  // LAPACK's estimate of ||A^-1||_1 (Hager and Higham, as Eigen's rcond estimate) with the solves above: a lower
  // bound of the exact norm (in exact arithmetic), in practice within a small factor of it
  double inverse_norm_estimate(const Eigen::PartialPivLU<MatrixXd>& lu) {
    const Eigen::Index n = lu.rows();
    est_v_.setConstant(n, 1.0 / static_cast<double>(n));
    lu_solve(lu, est_v_);
    double lower = est_v_.lpNorm<1>();
    if (n == 1) return lower;
    auto signs = [](const VectorXd& v, VectorXd& out) {
      out.resize(v.size());
      for (Eigen::Index i = 0; i < v.size(); ++i) out[i] = v[i] >= 0.0 ? 1.0 : -1.0;
    };
    signs(est_v_, est_old_);
    est_v_ = est_old_;
    lu_solve_transposed(lu, est_v_);
    Eigen::Index index, old_index;
    est_v_.cwiseAbs().maxCoeff(&index);
    double old_lower = lower;
    for (int k = 0; k < 4; ++k) {
      est_v_.setZero(n);
      est_v_[index] = 1.0;
      lu_solve(lu, est_v_);
      lower = est_v_.lpNorm<1>();
      if (lower <= old_lower) break;
      signs(est_v_, est_s_);
      if (est_s_ == est_old_) break;
      est_v_ = est_s_;
      lu_solve_transposed(lu, est_v_);
      old_index = index;
      est_v_.cwiseAbs().maxCoeff(&index);
      if (index == old_index) break;
      old_lower = lower;
      est_old_ = est_s_;
    }
    double alternate = 1.0;
    est_v_.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      est_v_[i] = alternate * (1.0 + static_cast<double>(i) / static_cast<double>(n - 1));
      alternate = -alternate;
    }
    lu_solve(lu, est_v_);
    return std::max(lower, 2.0 * est_v_.lpNorm<1>() / (3.0 * static_cast<double>(n)));
  }

  // Contact point and frame of wheel i (RollingWheel._geometry), its rows D E^T A_w and residuals.
  int wheel_rows(size_t i, int row) {
    const Wheel& wh = wheels_[i];
    const pin::SE3& oMf = data_.oMf[frames_[wh.frame]];
    Geometry& g = geo_[i];
    g.row = row;
    g.R = wh.radius;
    if (wh.radius_index >= 0) {
      g.R += q_[wh.radius_index];
      if (g.R <= 0) throw Fallback("radius not positive");
    }
    g.a.noalias() = oMf.rotation() * wh.axis;
    const Vector3d c = oMf.translation();
    const bool flat = terrain_.flat();
    Vector3d n = terrain_.normal(c[0], c[1]), p;
    int it = 0;
    for (; it < 100; ++it) {
      g.na = n.dot(g.a);
      Vector3d wv = n - g.na * g.a;
      g.nw = wv.norm();
      if (g.nw < 1e-9) throw Fallback("wheel lying flat");
      g.u = wv / g.nw;
      p = c - g.R * g.u;
      if (flat) break;
      const Vector3d m = terrain_.normal(p[0], p[1]);
      const double d2 = (m - n).squaredNorm();
      n = m;
      if (d2 < 1e-30) {
        g.na = n.dot(g.a);
        wv = n - g.na * g.a;
        g.nw = wv.norm();
        g.u = wv / g.nw;
        p = c - g.R * g.u;
        break;
      }
    }
    if (it == 100) throw Fallback("contact point did not converge");
    g.n = n;
    g.p = p;
    double f;
    Eigen::Vector2d grad;
    Eigen::Matrix2d H;
    terrain_.eval(p[0], p[1], f, grad, H);
    const double norm = std::sqrt(1.0 + grad.squaredNorm());
    const double phi = (p[2] - f) / norm;
    if (!flat) {  // Terrain.normal_derivative
      Matrix3d dm = Matrix3d::Zero();
      dm.block<2, 2>(0, 0) = -H;
      g.N = (Matrix3d::Identity() - n * n.transpose()) * dm / norm;
    }
    const Vector3d c1 = g.a.cross(n);
    g.nc1 = c1.norm();
    g.t1 = c1 / g.nc1;
    g.t2 = n.cross(g.t1);
    const Matrix6x& J = Jf_[wh.frame];
    const Vector3d r = -g.R * g.u;
    MatrixXd& Aw = Aw_[i];
    Aw = J.topRows<3>();
    Aw.noalias() -= skew(r).lazyProduct(J.bottomRows<3>());
    if (wh.radius_index >= 0) Aw.col(wh.radius_index) -= g.u;
    Matrix3d ET;
    ET.row(0) = g.t1.transpose();
    ET.row(1) = g.t2.transpose();
    ET.row(2) = n.transpose();
    const int nd = static_cast<int>(wh.D.rows());
    const Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 3, 3> W = wh.D * ET;
    A_.middleRows(row, nd).noalias() = W.lazyProduct(Aw);
    for (int r2 = 0; r2 < nd; ++r2) residual_[row + r2] = wh.D(r2, 2) != 0.0 ? phi : 0.0;
    return row + nd;
  }

  // Drift D (Edot^T s + E^T acc) of wheel i (RollingWheel.drift, WheelGroup._drift).
  int wheel_drift(size_t i, int row) {
    const Wheel& wh = wheels_[i];
    const Geometry& g = geo_[i];
    const int fid = frames_[wh.frame];
    const pin::Motion vf = pin::getFrameVelocity(model_, data_, fid, pin::LOCAL_WORLD_ALIGNED);
    const pin::Motion af = pin::getFrameClassicalAcceleration(model_, data_, fid, pin::LOCAL_WORLD_ALIGNED);
    const Vector3d omega = vf.angular(), cdot = vf.linear();
    const double Rdot = wh.radius_index >= 0 ? v_[wh.radius_index] : 0.0;
    const Vector3d& n = g.n;
    const Vector3d adot = omega.cross(g.a);
    const Vector3d rhs_const = -(n.dot(adot)) * g.a - g.na * adot;
    Vector3d udot, ndot = Vector3d::Zero();
    if (terrain_.flat()) {
      udot = (rhs_const - g.u * g.u.dot(rhs_const)) / g.nw;
    } else {
      const Matrix3d P = (Matrix3d::Identity() - g.u * g.u.transpose()) / g.nw;
      const Matrix3d QaN = (Matrix3d::Identity() - g.a * g.a.transpose()) * g.N;
      const Matrix3d K = Matrix3d::Identity() + g.R * (P * QaN);
      const Vector3d rhs = P * (QaN * (cdot - Rdot * g.u) + rhs_const);
      udot = K.partialPivLu().solve(rhs);
      ndot = g.N * (cdot - g.R * udot - Rdot * g.u);
    }
    const Vector3d r = -g.R * g.u, rdot = -g.R * udot - Rdot * g.u;
    const Vector3d c1dot = adot.cross(n) + g.a.cross(ndot);
    const Vector3d t1dot = (c1dot - g.t1 * g.t1.dot(c1dot)) / g.nc1;
    const Vector3d t2dot = ndot.cross(g.t1) + n.cross(t1dot);
    Vector3d acc = af.linear() + af.angular().cross(r) + omega.cross(rdot);
    if (wh.radius_index >= 0) acc -= udot * Rdot;
    const Vector3d s = Aw_[i] * v_;
    const Vector3d d(t1dot.dot(s) + g.t1.dot(acc), t2dot.dot(s) + g.t2.dot(acc), ndot.dot(s) + n.dot(acc));
    const int nd = static_cast<int>(wh.D.rows());
    drift_.segment(row, nd).noalias() = wh.D * d;
    return row + nd;
  }

  int closure_rows(size_t i, int row) {
    const Closure& c = closures_[i];
    const pin::SE3& M1 = data_.oMf[frames_[c.f1]];
    const pin::SE3& M2 = data_.oMf[frames_[c.f2]];
    const Matrix3d R1T = M1.rotation().transpose();
    const Matrix6x& J1 = Jf_[c.f1];
    const Matrix6x& J2 = Jf_[c.f2];
    const Vector3d dp = M2.translation() - M1.translation();
    Jrel_.resize(6, nv_);  // relative velocity in frame 1's axes (LoopClosure.jacobian)
    K3_ = J2.topRows<3>() - J1.topRows<3>();
    K3_.noalias() += skew(dp).lazyProduct(J1.bottomRows<3>());
    Jrel_.topRows<3>().noalias() = R1T.lazyProduct(K3_);
    K3_ = J2.bottomRows<3>() - J1.bottomRows<3>();
    Jrel_.bottomRows<3>().noalias() = R1T.lazyProduct(K3_);
    const Vector3d e_pos = R1T * dp;
    const Vector3d e_rot = pin::log3(Matrix3d(R1T * M2.rotation()));
    for (size_t r = 0; r < c.select.size(); ++r) {
      const int s = c.select[r];
      A_.row(row + r) = Jrel_.row(s);
      residual_[row + r] = s < 3 ? e_pos[s] : e_rot[s - 3];
    }
    return row + static_cast<int>(c.select.size());
  }

  int closure_drift(size_t i, int row) {  // LoopClosure.drift
    const Closure& c = closures_[i];
    const int f1 = frames_[c.f1], f2 = frames_[c.f2];
    const pin::Motion V1 = pin::getFrameVelocity(model_, data_, f1, pin::LOCAL_WORLD_ALIGNED);
    const pin::Motion V2 = pin::getFrameVelocity(model_, data_, f2, pin::LOCAL_WORLD_ALIGNED);
    const pin::Motion a1 = pin::getFrameClassicalAcceleration(model_, data_, f1, pin::LOCAL_WORLD_ALIGNED);
    const pin::Motion a2 = pin::getFrameClassicalAcceleration(model_, data_, f2, pin::LOCAL_WORLD_ALIGNED);
    const Vector3d d = data_.oMf[f2].translation() - data_.oMf[f1].translation();
    const Vector3d w1 = V1.angular();
    const Vector3d ddot = V2.linear() - V1.linear();
    const Vector3d kt = ddot + d.cross(w1);
    const Vector3d dkt = a2.linear() - a1.linear() + ddot.cross(w1) + d.cross(a1.angular());
    const Vector3d kr = V2.angular() - w1;
    const Vector3d dkr = a2.angular() - a1.angular();
    const Matrix3d R1T = data_.oMf[f1].rotation().transpose();
    const Vector3d et = R1T * (dkt - w1.cross(kt)), er = R1T * (dkr - w1.cross(kr));
    for (size_t r = 0; r < c.select.size(); ++r) {
      const int s = c.select[r];
      drift_[row + r] = s < 3 ? et[s] : er[s - 3];
    }
    return row + static_cast<int>(c.select.size());
  }

  int coupling_rows(size_t i, int row) {  // JointCoupling.jacobian with a CosineLaw
    const Coupling& c = couplings_[i];
    const double arg = c.rate * q_[c.j] + c.phase;
    A_(row, c.i) = 1.0;
    A_(row, c.j) -= -c.amplitude * c.rate * std::sin(arg);
    residual_[row] = q_[c.i] - (c.amplitude * std::cos(arg) + c.offset);
    return row + 1;
  }

  int coupling_drift(size_t i, int row) {  // JointCoupling.drift: -f''(q_r) v_r^2
    const Coupling& c = couplings_[i];
    const double arg = c.rate * q_[c.j] + c.phase;
    const double vr = v_[c.j];
    drift_[row] = -(-c.amplitude * c.rate * c.rate * std::cos(arg)) * vr * vr;
    return row + 1;
  }

  void operational_drift(VectorXd& out) {  // the last k entries: d/dt J_o at zero joint acceleration, times v
    const int fid = frames_[op_frame_];
    const pin::Motion a = op_local_ ? pin::getFrameAcceleration(model_, data_, fid, pin::LOCAL)
                                    : pin::getFrameClassicalAcceleration(model_, data_, fid, pin::LOCAL_WORLD_ALIGNED);
    const int base = static_cast<int>(rows_.size());
    for (size_t r = 0; r < op_select_.size(); ++r) {
      const int s = op_select_[r];
      out[base + r] = s < 3 ? a.linear()[s] : a.angular()[s - 3];
    }
  }

  void project() {  // projection.py _build / operational_space.py project_operational, with the given rows
    const double scale = std::max(1.0, A_.size() ? A_.cwiseAbs().maxCoeff() : 0.0);
    if (operational_) {
      const int k = static_cast<int>(op_select_.size());
      const int nr = static_cast<int>(rows_.size());
      if (nr + k != nv_) throw Fallback("operational rows do not match");
      K_.resize(nv_, nv_);
      for (int r = 0; r < nr; ++r) K_.row(r) = A_.row(rows_[r]);
      Jc_.setZero(6, nv_);
      pin::getFrameJacobian(model_, data_, frames_[op_frame_], op_local_ ? pin::LOCAL : pin::LOCAL_WORLD_ALIGNED, Jc_);
      for (int r = 0; r < k; ++r) K_.row(nr + r) = Jc_.row(op_select_[r]);
      lu_.compute(K_);
      Kinv_ = lu_.inverse();
      cond_ = K_.cwiseAbs().colwise().sum().maxCoeff() * Kinv_.cwiseAbs().colwise().sum().maxCoeff();
      if (!(std::isfinite(cond_) && cond_ <= 1e10) || !Kinv_.allFinite()) throw Fallback("singular");
      S_ = Kinv_.rightCols(k);
    } else {
      const int nd = static_cast<int>(dependent_.size());
      const int k = static_cast<int>(independent_.size());
      S_.setZero(nv_, k);
      for (int j = 0; j < k; ++j) S_(independent_[j], j) = 1.0;
      if (nd == 0) {
        cond_ = 1.0;
        return;
      }
      Ad_.resize(nd, nd);
      Ai_.resize(nd, k);
      for (int r = 0; r < nd; ++r) {
        for (int c = 0; c < nd; ++c) Ad_(r, c) = A_(rows_[r], dependent_[c]);
        for (int c = 0; c < k; ++c) Ai_(r, c) = A_(rows_[r], independent_[c]);
      }
      lu_.compute(Ad_);
      // The Python path refuses a block whose 1-norm condition number exceeds 1e10 (projection.MAX_CONDITION).
      // LAPACK's estimate (O(n^2), inverse_norm_estimate) decides far from that bound; from an estimate of 1e8 on, the exact
      // number (an O(n^3) inverse) decides, as in Python. The exact number is reported by the Python side
      // (robotdyn.compiled.LazyProjection), from A.
      cond_ = Ad_.cwiseAbs().colwise().sum().maxCoeff() * inverse_norm_estimate(lu_);
      if (std::isnan(cond_)) cond_ = std::numeric_limits<double>::infinity();
      if (!(cond_ < 1e8)) {
        Adinv_ = lu_.inverse();
        cond_ = Ad_.cwiseAbs().colwise().sum().maxCoeff() * Adinv_.cwiseAbs().colwise().sum().maxCoeff();
        if (!(std::isfinite(cond_) && cond_ <= 1e10)) throw Fallback("singular");
      }
      Sd_ = Ai_;
      for (int c = 0; c < k; ++c) lu_solve(lu_, Sd_.col(c));
      if (!Sd_.allFinite()) throw Fallback("singular");  // an exactly singular block (a zero pivot)
      for (int r = 0; r < nd; ++r) S_.row(dependent_[r]) = -Sd_.row(r);
    }
    if (A_.size() && S_.cols()) {  // (no independent velocity: nothing to check, and no maximum to take)
      AS_.noalias() = A_.lazyProduct(S_);
      if (!(AS_.cwiseAbs().maxCoeff() <= 1e-10 * scale)) throw Fallback("row choice no longer spans");  // NaN too
    }
  }

  void pull_back(double alpha, Eigen::Ref<VectorXd> out) {
    int nh = 0;
    bool any = false;
    for (size_t r = 0; r < holonomic_.size(); ++r)
      if (holonomic_[r]) {
        ++nh;
        any = any || residual_[r] != 0.0;
      }
    if (!any) return;
    MatrixXd Ah(nh, nv_);
    VectorXd phi(nh);
    int j = 0;
    for (size_t r = 0; r < holonomic_.size(); ++r)
      if (holonomic_[r]) {
        Ah.row(j) = A_.row(r);
        phi[j++] = residual_[r];
      }
    // truncated SVD: singular values below 1e-9 max(s_max, 1) count as zero (robotdyn/pull_back.py): rows with
    // no rank, e.g. a wheel's normal row under a planar root, keep their residual as a constant offset
    svd_.compute(Ah, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const VectorXd& s = svd_.singularValues();
    const double cut = 1e-9 * std::max(s.size() ? s[0] : 0.0, 1.0);
    int rank = 0;
    while (rank < s.size() && s[rank] > cut) ++rank;
    if (rank == 0) return;
    VectorXd c = svd_.matrixU().leftCols(rank).transpose() * phi;
    c.array() /= s.head(rank).array();
    out.head(nv_).noalias() -= alpha * (svd_.matrixV().leftCols(rank) * c);
  }

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
  bool op_local_ = true, operational_ = false, selected_ = false;
  // state and work buffers (sized on first use, then reused)
  VectorXd tau_, perm_, e_, lambda_, lr_, nudot_, a_;
  RowMat wl_, ww_, wf_, wp_;
  const double* fbuffers_[7] = {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
  long fgeneration_ = 0;
  std::optional<robotdyn::Controller> controller_;  // set_controller
  double control_t_ = 0.0;
  VectorXd control_tau_;
  VectorXd q_, v_, w_, zero_, g_, residual_, drift_, gr_, hr_, rhs_, wd_, force_, est_v_, est_s_, est_old_;
  MatrixXd A_, S_, SM_, B_, Br_, Mr_, Adinv_, Kinv_, K_, Ad_, Ai_, Sd_, AS_, Jrel_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> K3_;
  Matrix6x Jc_;
  Eigen::PartialPivLU<MatrixXd> lu_;
  Eigen::LLT<MatrixXd> llt_;
  Eigen::JacobiSVD<MatrixXd> svd_;
  double cond_ = 1.0;
  // slipping wheels' work buffers (slip_rhs_into), the lift-off event's cache and the state of a SlipError
  MatrixXd Ks_, Jt_;
  bool rigid_limit_ = true;
  VectorXd kstiff_, rl_n0_, rl_saved_;
  MatrixXd rl_Q_, rl_N_, rl_P_, rl_G_, rl_O_, rl_W_, rl_H_;
  VectorXd rl_c_, rl_rk_, rl_y_, rl_n_, rl_z_, rl_t_, rl_w_;
  Eigen::LLT<MatrixXd> rl_llt_;
  std::vector<bool> rl_in_;
  Eigen::ColPivHouseholderQR<MatrixXd> rl_qr_;
  Eigen::JacobiSVD<MatrixXd> rl_svd_;
  VectorXd bs_, xs_, slip_normal_;
  Eigen::Matrix<double, Eigen::Dynamic, 2> slip_s_, slip_c_;
  std::vector<int> slip_pos_;
  Eigen::PartialPivLU<MatrixXd> slip_lu_;
  Eigen::JacobiSVD<MatrixXd> slip_svd_;
  double slip_kappa1_ = 0.0, slip_kappa2_ = 0.0;  // the last Painleve test (slip_condition)
  double slip_min_ = HUGE_VAL, event_t_ = std::numeric_limits<double>::quiet_NaN(), event_g_ = 0.0;

 public:
  double last_t_ = std::numeric_limits<double>::quiet_NaN();  // time of the last right-hand side evaluated

 private:
  double slip_error_t_ = 0.0;
  std::vector<double> event_y_, event_dy_, slip_error_y_;
  std::vector<Geometry> geo_;
  std::vector<Matrix6x> Jf_;
  std::vector<MatrixXd> Aw_;
  robotdyn::derivs::Workspace deriv_;  // the derivatives' passes (kernels/reduced_dynamics_derivatives.hpp)
  const double* buffers_[7] = {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
  int run_ = -1;  // the run a batch thread is on (its rechoice callback gets it), -1 alone
  long generation_ = 0;
};

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
      .def_property_readonly("slipping", &Evaluator::slipping)
      .def_readonly("last_t", &Evaluator::last_t_, "Time [s] of the last right-hand side a simulation evaluated")
      .def_property_readonly("slip_condition", &Evaluator::slip_condition,
                             "The last slipping evaluation's Painleve test: (||K||_1 times LAPACK's estimate of "
                             "||K^-1||_1, the 2-norm condition number from the singular values or NaN where the "
                             "estimate cleared the state)")
      .def("slip_rhs", &Evaluator::slip_rhs)
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
      .def("evaluate_many", &Evaluator::evaluate_many)
      .def("derivatives",
           [](Evaluator& ev, const VectorXd& q, const VectorXd& nu, const VectorXd& tau) {
             robotdyn::derivs::Result r;
             try {
               r = robotdyn::ReducedDerivatives<Evaluator>::run(ev, q, nu, tau);
             } catch (const std::domain_error& e) {
               throw Fallback(e.what());
             }
             return py::make_tuple(r.nudot, r.dq, r.dnu, r.dtau, r.v, r.Vq, r.S, r.A);
           },
           "(nudot, dnudot/dq, dnudot/dnu, dnudot/dtau, v, dv/dq, S, A) at (q, nu, tau) "
           "(robotdyn.fast.compiled_derivatives)")
      .def_property_readonly("condition", &Evaluator::condition,
                             "1-norm condition number of the last projection's block: LAPACK's estimate below 1e8, "
                             "exact above (operational velocities: exact)")
      .def_property_readonly("nv", &Evaluator::nv)
      .def_property_readonly("nrows", &Evaluator::nrows);
}

// robotdyn._compiled: the reduced model evaluated in one compiled call (see robotdyn/compiled.py).
//
// Same formulas as the Python reference, in the same order:
//   rolling contact on a plane  robotdyn/rolling_contact.py (per wheel), robotdyn/wheel_group.py (fast path)
//   loop closures               robotdyn/loop_closure.py
//   projection                  robotdyn/projection.py (_build: S = P [I; -Ad^-1 Ai], w = -Ad^-1 drift)
//   operational velocities      robotdyn/operational_space.py (K = [A_r; J_o], K S = [0; I])
//   motors                      robotdyn/actuation.py
//   dynamics                    robotdyn/reduced_dynamics.py (M_r = S^T M S, h = S^T RNEA(q, S nu, w))
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

#include <pybind11/pybind11.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>
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
  double radius;   // m
  MatrixXd D;      // (nd, 3) rows as coefficients of (t1, t2, n)
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

struct Geometry {  // configuration-level quantities of one wheel on the plane
  Vector3d a, u, t1, t2;
  double na, nw, nc1, R;
};

inline Matrix3d skew(const Vector3d& x) {
  Matrix3d m;
  m << 0.0, -x[2], x[1], x[2], 0.0, -x[0], -x[1], x[0], 0.0;
  return m;
}

class Evaluator {
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
    }
    model_.gravity.linear(gravity);
    nv_ = model_.nv;
    data_ = pin::Data(model_);
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
  void set_plane(const Vector3d& normal, const Vector3d& height_row, double h, double slope_norm) {
    n0_ = normal;
    height_row_ = height_row;
    h_ = h;
    slope_norm_ = slope_norm;
  }
  void add_wheel(int frame, const Vector3d& axis, double radius, const MatrixXd& D) {
    order_.emplace_back(0, static_cast<int>(wheels_.size()));
    wheels_.push_back(Wheel{frame, axis, radius, D});
    for (int r = 0; r < D.rows(); ++r) holonomic_.push_back(D(r, 2) != 0.0);
  }
  void add_closure(int f1, int f2, const std::vector<int>& select) {
    order_.emplace_back(1, static_cast<int>(closures_.size()));
    closures_.push_back(Closure{f1, f2, select});
    for (size_t r = 0; r < select.size(); ++r) holonomic_.push_back(true);
  }
  void add_motor(int index, int joint, int reaction) { motors_.push_back(Motor{index, joint, reaction}); }
  // The rows used and the independent velocity indices (a selection of v).
  void set_selection(const std::vector<int>& rows, const std::vector<int>& independent,
                     const std::vector<int>& dependent) {
    rows_ = rows;
    independent_ = independent;
    dependent_ = dependent;
    operational_ = false;
  }
  // Operational velocities: nu = J_o v with J_o the selected components of a frame's twist (local or world axes).
  void set_operational(const std::vector<int>& rows, int frame, const std::vector<int>& select, bool local) {
    rows_ = rows;
    op_frame_ = frame;
    op_select_ = select;
    op_local_ = local;
    operational_ = true;
  }

  int nv() const { return nv_; }
  int nrows() const { return static_cast<int>(holonomic_.size()); }
  int mobility() const {
    return operational_ ? static_cast<int>(op_select_.size()) : static_cast<int>(independent_.size());
  }

  // The full-coordinate model at q (for the self-check against the Python model): M, g and RNEA(q, v, a).
  py::tuple full(const VectorXd& q, const VectorXd& v, const VectorXd& a) {
    MatrixXd M = pin::crba(model_, data_, q);
    M.triangularView<Eigen::StrictlyLower>() = M.transpose().triangularView<Eigen::StrictlyLower>();
    VectorXd g = pin::computeGeneralizedGravity(model_, data_, q);
    VectorXd tau = pin::rnea(model_, data_, q, v, a);
    return py::make_tuple(M, g, tau);
  }

  // ------------------------------------------------------------------------------------------ evaluation
  // Configuration level: kinematics, the constraint rows A, residuals, the motors' B and the projection S.
  void configure(const Eigen::Ref<const VectorXd>& q) {
    if (q.size() != nv_) throw std::invalid_argument("q has the wrong length");
    q_ = q;
    pin::computeJointJacobians(model_, data_, q_);
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
    int row = 0;
    Aw_.resize(wheels_.size());
    for (const auto& [kind, i] : order_) row = kind == 0 ? wheel_rows(i, row) : closure_rows(i, row);
    // motors (configuration only)
    B_.setZero(nv_, motors_.size());
    for (size_t j = 0; j < motors_.size(); ++j) {
      const Motor& mo = motors_[j];
      if (mo.reaction < 0) {
        B_(mo.index, j) = 1.0;
        continue;
      }
      Matrix6x Jc = Matrix6x::Zero(6, nv_);
      pin::getJointJacobian(model_, data_, mo.joint, pin::LOCAL_WORLD_ALIGNED, Jc);
      Vector3d ang = Jc.block<3, 1>(3, mo.index);
      Vector3d axis = ang.squaredNorm() > 0.25 ? ang : Vector3d(Jc.block<3, 1>(0, mo.index));
      B_.col(j) = (Jc.bottomRows<3>() - Jf_[mo.reaction].bottomRows<3>()).transpose() * axis;
    }
    project();
  }

  // State level: v = S nu, the drift, w and the dynamics.
  void dynamics(const Eigen::Ref<const VectorXd>& nu) {
    if (nu.size() != S_.cols()) throw std::invalid_argument("nu has the wrong length");
    v_ = S_ * nu;
    VectorXd zero = VectorXd::Zero(nv_);
    pin::forwardKinematics(model_, data_, q_, v_, zero);
    drift_.setZero(nrows());
    int row = 0;
    for (const auto& [kind, i] : order_) row = kind == 0 ? wheel_drift(i, row) : closure_drift(i, row);
    w_.setZero(nv_);
    if (operational_) {
      VectorXd rhs(nv_);
      for (size_t r = 0; r < rows_.size(); ++r) rhs[r] = drift_[rows_[r]];
      rhs.tail(op_select_.size()) = operational_drift();
      w_ = -(Kinv_ * rhs);
    } else if (!rows_.empty()) {
      VectorXd d(rows_.size());
      for (size_t r = 0; r < rows_.size(); ++r) d[r] = drift_[rows_[r]];
      VectorXd wd = -(Adinv_ * d);
      for (size_t r = 0; r < dependent_.size(); ++r) w_[dependent_[r]] = wd[r];
    }
    M_ = pin::crba(model_, data_, q_);
    M_.triangularView<Eigen::StrictlyLower>() = M_.transpose().triangularView<Eigen::StrictlyLower>();
    Mr_.noalias() = S_.transpose() * M_ * S_;
    g_ = pin::computeGeneralizedGravity(model_, data_, q_);
    gr_.noalias() = S_.transpose() * g_;
    const VectorXd& tau = pin::rnea(model_, data_, q_, v_, w_);
    hr_.noalias() = S_.transpose() * tau;
    Br_.noalias() = S_.transpose() * B_;
  }

  py::tuple evaluate(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
    configure(q);
    dynamics(nu);
    return py::make_tuple(Mr_, hr_, gr_, Br_, S_, w_, v_, A_, residual_, cond_, Adinv_);
  }

  // The same without returning anything: the results are read through the views M, h, g, B, S, w, v (valid
  // until the next call).
  void compute(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
    configure(q);
    dynamics(nu);
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
    configure(q);
    dynamics(nu);
    const int k = static_cast<int>(S_.cols());
    VectorXd out(nv_ + k);
    out.head(nv_) = v_;
    if (alpha != 0.0) pull_back(alpha, out);
    out.tail(k) = Mr_.llt().solve(Br_ * tau - hr_);
    return out;
  }

  // Many states: stacked M_r (N, k, k), h (N, k), g (N, k), S (N, n, k), w (N, n).
  py::tuple evaluate_many(const Eigen::Ref<const RowMat>& Q, const Eigen::Ref<const RowMat>& NU) {
    const int N = static_cast<int>(Q.rows());
    const int k = mobility();
    RowMat Mr(N, k * k), hr(N, k), gr(N, k), S(N, nv_ * k), w(N, nv_), B(N, k * motors_.size());
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
      Eigen::Map<RowMat>(B.row(i).data(), k, motors_.size()) = Br_;
    }
    return py::make_tuple(Mr, hr, gr, S, w, B, failed);
  }

 private:
  int wheel_rows(size_t i, int row) {
    const Wheel& wh = wheels_[i];
    const pin::SE3& oMf = data_.oMf[frames_[wh.frame]];
    Geometry& g = geo_[i];
    g.R = wh.radius;
    g.a = oMf.rotation() * wh.axis;
    g.na = g.a.dot(n0_);
    Vector3d wv = n0_ - g.na * g.a;
    g.nw = wv.norm();
    if (g.nw < 1e-9) throw Fallback("wheel lying flat");
    g.u = wv / g.nw;
    Vector3d p = oMf.translation() - g.R * g.u;
    double phi = (p.dot(height_row_) - h_) / slope_norm_;
    Vector3d c1 = g.a.cross(n0_);
    g.nc1 = c1.norm();
    g.t1 = c1 / g.nc1;
    g.t2 = n0_.cross(g.t1);
    const Matrix6x& J = Jf_[wh.frame];
    Vector3d r = -g.R * g.u;
    Aw_[i] = J.topRows<3>() - skew(r) * J.bottomRows<3>();
    Matrix3d ET;
    ET.row(0) = g.t1.transpose();
    ET.row(1) = g.t2.transpose();
    ET.row(2) = n0_.transpose();
    const int nd = static_cast<int>(wh.D.rows());
    A_.middleRows(row, nd) = (wh.D * ET) * Aw_[i];
    for (int r2 = 0; r2 < nd; ++r2) residual_[row + r2] = wh.D(r2, 2) != 0.0 ? phi : 0.0;
    return row + nd;
  }

  int wheel_drift(size_t i, int row) {
    const Wheel& wh = wheels_[i];
    const Geometry& g = geo_[i];
    const int fid = frames_[wh.frame];
    const pin::Motion vf = pin::getFrameVelocity(model_, data_, fid, pin::LOCAL_WORLD_ALIGNED);
    const pin::Motion af = pin::getFrameClassicalAcceleration(model_, data_, fid, pin::LOCAL_WORLD_ALIGNED);
    const Vector3d omega = vf.angular();
    const Vector3d adot = omega.cross(g.a);
    const double nad = adot.dot(n0_);
    const Vector3d qv = -nad * g.a - g.na * adot;
    const Vector3d udot = (qv - g.u * g.u.dot(qv)) / g.nw;
    const Vector3d r = -g.R * g.u, rdot = -g.R * udot;
    const Vector3d k = adot.cross(n0_);
    const Vector3d t1dot = (k - g.t1 * g.t1.dot(k)) / g.nc1;
    const Vector3d t2dot = n0_.cross(t1dot);
    const Vector3d acc = af.linear() + af.angular().cross(r) + omega.cross(rdot);
    const Vector3d s = Aw_[i] * v_;
    Vector3d d(t1dot.dot(s) + g.t1.dot(acc), t2dot.dot(s) + g.t2.dot(acc), n0_.dot(acc));
    const int nd = static_cast<int>(wh.D.rows());
    drift_.segment(row, nd) = wh.D * d;
    return row + nd;
  }

  int closure_rows(size_t i, int row) {
    const Closure& c = closures_[i];
    const pin::SE3& M1 = data_.oMf[frames_[c.f1]];
    const pin::SE3& M2 = data_.oMf[frames_[c.f2]];
    const Matrix3d& R1 = M1.rotation();
    const Matrix6x& J1 = Jf_[c.f1];
    const Matrix6x& J2 = Jf_[c.f2];
    Vector3d dp = M2.translation() - M1.translation();
    // relative velocity in frame 1's axes: translation d/dt(R1^T dp), rotation R1^T (w2 - w1)
    Eigen::Matrix<double, 6, Eigen::Dynamic> Jrel(6, nv_);
    Jrel.topRows<3>() = R1.transpose() * (J2.topRows<3>() - J1.topRows<3>() + skew(dp) * J1.bottomRows<3>());
    Jrel.bottomRows<3>() = R1.transpose() * (J2.bottomRows<3>() - J1.bottomRows<3>());
    Vector3d e_pos = R1.transpose() * dp;
    Vector3d e_rot = pin::log3(Matrix3d(R1.transpose() * M2.rotation()));
    for (size_t r = 0; r < c.select.size(); ++r) {
      const int s = c.select[r];
      A_.row(row + r) = Jrel.row(s);
      residual_[row + r] = s < 3 ? e_pos[s] : e_rot[s - 3];
    }
    return row + static_cast<int>(c.select.size());
  }

  int closure_drift(size_t i, int row) {
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

  VectorXd operational_drift() {
    const int fid = frames_[op_frame_];
    Vector3d lin, ang;
    if (op_local_) {  // d/dt of the body-axes twist: the spatial acceleration at zero joint acceleration
      const pin::Motion a = pin::getFrameAcceleration(model_, data_, fid, pin::LOCAL);
      lin = a.linear();
      ang = a.angular();
    } else {
      const pin::Motion a = pin::getFrameClassicalAcceleration(model_, data_, fid, pin::LOCAL_WORLD_ALIGNED);
      lin = a.linear();
      ang = a.angular();
    }
    VectorXd out(op_select_.size());
    for (size_t r = 0; r < op_select_.size(); ++r) out[r] = op_select_[r] < 3 ? lin[op_select_[r]] : ang[op_select_[r] - 3];
    return out;
  }

  void project() {
    const double scale = std::max(1.0, A_.size() ? A_.cwiseAbs().maxCoeff() : 0.0);
    if (operational_) {
      const int k = static_cast<int>(op_select_.size());
      if (static_cast<int>(rows_.size()) + k != nv_) throw Fallback("operational rows do not match");
      MatrixXd K(nv_, nv_);
      for (size_t r = 0; r < rows_.size(); ++r) K.row(r) = A_.row(rows_[r]);
      Matrix6x Jo = Matrix6x::Zero(6, nv_);
      pin::getFrameJacobian(model_, data_, frames_[op_frame_], op_local_ ? pin::LOCAL : pin::LOCAL_WORLD_ALIGNED, Jo);
      for (int r = 0; r < k; ++r) K.row(rows_.size() + r) = Jo.row(op_select_[r]);
      Eigen::PartialPivLU<MatrixXd> lu(K);
      Kinv_ = lu.inverse();
      cond_ = K.cwiseAbs().colwise().sum().maxCoeff() * Kinv_.cwiseAbs().colwise().sum().maxCoeff();
      if (!std::isfinite(cond_) || cond_ > 1e10) throw Fallback("singular");
      S_ = Kinv_.rightCols(k);
      Adinv_ = Kinv_;
    } else {
      const int nd = static_cast<int>(dependent_.size());
      const int k = static_cast<int>(independent_.size());
      S_.setZero(nv_, k);
      for (int j = 0; j < k; ++j) S_(independent_[j], j) = 1.0;
      if (nd == 0) {
        cond_ = 1.0;
        Adinv_.resize(0, 0);
        return;
      }
      MatrixXd Ad(nd, nd), Ai(nd, k);
      for (int r = 0; r < nd; ++r) {
        for (int c = 0; c < nd; ++c) Ad(r, c) = A_(rows_[r], dependent_[c]);
        for (int c = 0; c < k; ++c) Ai(r, c) = A_(rows_[r], independent_[c]);
      }
      Eigen::PartialPivLU<MatrixXd> lu(Ad);
      Adinv_ = lu.inverse();
      cond_ = Ad.cwiseAbs().colwise().sum().maxCoeff() * Adinv_.cwiseAbs().colwise().sum().maxCoeff();
      if (!std::isfinite(cond_) || cond_ > 1e10) throw Fallback("singular");
      MatrixXd Sd = -(Adinv_ * Ai);
      for (int r = 0; r < nd; ++r) S_.row(dependent_[r]) = Sd.row(r);
    }
    if (A_.size() && (A_ * S_).cwiseAbs().maxCoeff() > 1e-10 * scale) throw Fallback("row choice no longer spans");
  }

  void pull_back(double alpha, VectorXd& out) {
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
    out.head(nv_) -= alpha * Ah.completeOrthogonalDecomposition().solve(phi);
  }

  pin::Model model_;
  pin::Data data_;
  int nv_;
  std::vector<int> frames_;
  std::vector<Wheel> wheels_;
  std::vector<Closure> closures_;
  std::vector<std::pair<int, int>> order_;  // (0: wheel, 1: closure; index), in row order
  std::vector<Motor> motors_;
  std::vector<bool> holonomic_;
  Vector3d n0_{0.0, 0.0, 1.0}, height_row_{0.0, 0.0, 1.0};
  double h_ = 0.0, slope_norm_ = 1.0;
  std::vector<int> rows_, independent_, dependent_, op_select_;
  int op_frame_ = -1;
  bool op_local_ = true, operational_ = false;
  // state
  VectorXd q_, v_, w_, residual_, drift_, g_, gr_, hr_;
  MatrixXd A_, S_, B_, Br_, M_, Mr_, Adinv_, Kinv_;
  double cond_ = 1.0;
  std::vector<Geometry> geo_;
  std::vector<Matrix6x> Jf_;
  std::vector<MatrixXd> Aw_;
};

}  // namespace

PYBIND11_MODULE(_compiled, m) {
  m.doc() = "robotdyn's compiled reduced-model evaluator (see robotdyn.compiled)";
  py::register_exception<Fallback>(m, "Fallback", PyExc_RuntimeError);
  py::class_<Evaluator>(m, "Evaluator")
      .def(py::init<const std::vector<std::string>&, const std::vector<int>&, const std::vector<MatrixXd>&,
                    const std::vector<Vector3d>&, const std::vector<VectorXd>&, const Vector3d&>())
      .def("add_frame", &Evaluator::add_frame)
      .def("set_plane", &Evaluator::set_plane)
      .def("add_wheel", &Evaluator::add_wheel)
      .def("add_closure", &Evaluator::add_closure)
      .def("add_motor", &Evaluator::add_motor)
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
      .def("evaluate_many", &Evaluator::evaluate_many)
      .def_property_readonly("nv", &Evaluator::nv)
      .def_property_readonly("nrows", &Evaluator::nrows);
}

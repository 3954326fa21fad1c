// robotdyn/_evaluator.cpp: the Evaluator's member functions (the class: robotdyn/_evaluator.hpp) in the order of
// their declarations, the simulation drivers last: simulate and simulate_many (robotdyn/simulation/
// compiled_simulation.py, many_runs.py) on the Boost.Odeint drivers of robotdyn/_integrator.hpp and
// robotdyn/_stiff_integrator.hpp.
#include "_evaluator.hpp"
#include "_integrator.hpp"
#include "_stiff_integrator.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace robotdyn {
namespace compiled {

Evaluator::Evaluator(const std::vector<std::string>& kinds, const std::vector<int>& parents,
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
int Evaluator::add_frame(int joint, const MatrixXd& P) {
  pin::SE3 placement(Matrix3d(P.leftCols<3>()), Vector3d(P.col(3)));
  std::string name = "f" + std::to_string(frames_.size());
  frames_.push_back(static_cast<int>(model_.addFrame(
      pin::Frame(name, static_cast<pin::JointIndex>(joint), 0, placement, pin::OP_FRAME))));
  data_ = pin::Data(model_);
  crba_at_q_ = false;
  return static_cast<int>(frames_.size()) - 1;
}

void Evaluator::set_terrain(int kind, const std::vector<double>& c) {
  if (kind < 0 || kind > 2 || c.size() > 5) throw std::invalid_argument("unknown terrain");
  terrain_.kind = kind;
  for (size_t i = 0; i < c.size(); ++i) terrain_.c[i] = c[i];
}

void Evaluator::add_wheel(int frame, const Vector3d& axis, double radius, int radius_index, const MatrixXd& D) {
  if (D.cols() != 3 || D.rows() < 1 || D.rows() > 3) throw std::invalid_argument("wheel rows must be (1..3, 3)");
  order_.emplace_back(0, static_cast<int>(wheels_.size()));
  wheels_.push_back(Wheel{frame, axis, radius, radius_index, D});
  for (int r = 0; r < D.rows(); ++r) holonomic_.push_back(D(r, 2) != 0.0);
}

void Evaluator::add_closure(int f1, int f2, const std::vector<int>& select) {
  order_.emplace_back(1, static_cast<int>(closures_.size()));
  closures_.push_back(Closure{f1, f2, select});
  for (size_t r = 0; r < select.size(); ++r) holonomic_.push_back(true);
}

void Evaluator::add_coupling(int i, int j, double amplitude, double rate, double phase, double offset) {
  order_.emplace_back(2, static_cast<int>(couplings_.size()));
  couplings_.push_back(Coupling{i, j, amplitude, rate, phase, offset});
  holonomic_.push_back(true);
}

void Evaluator::add_slipping(int wheel, int normal_row, int law, double p0, double p1, const Eigen::Vector2d& free) {
  if (wheel < 0 || wheel >= static_cast<int>(wheels_.size())) throw std::invalid_argument("no such wheel");
  if (normal_row < 0 || normal_row >= nrows()) throw std::invalid_argument("no such row");
  if (law < 0 || law > 1) throw std::invalid_argument("unknown friction law code");
  slips_.push_back(Slip{wheel, normal_row, law, p0, p1, free});
}

void Evaluator::set_selection(const std::vector<int>& rows, const std::vector<int>& independent,
                              const std::vector<int>& dependent) {
  rows_ = rows;
  independent_ = independent;
  dependent_ = dependent;
  operational_ = false;
  selected_ = true;
  configured_ = false;
}

void Evaluator::set_operational(const std::vector<int>& rows, int frame, const std::vector<int>& select, bool local) {
  rows_ = rows;
  op_frame_ = frame;
  op_select_ = select;
  op_local_ = local;
  operational_ = true;
  selected_ = true;
  configured_ = false;
}

py::tuple Evaluator::full(const VectorXd& q, const VectorXd& v, const VectorXd& a) {
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
void Evaluator::configure(const Eigen::Ref<const VectorXd>& q) {
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

void Evaluator::rows_pass(bool motors) {
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

void Evaluator::constraint_rows(bool motors) {
  int row = 0;
  for (const auto& [kind, i] : order_)
    row = kind == 0 ? wheel_rows(i, row) : kind == 1 ? closure_rows(i, row) : coupling_rows(i, row);
  if (motors) motor_columns(motors_, model_, data_, Jf_, nv_, B_);
}

void Evaluator::drift_pass() {
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

void Evaluator::dynamics(const Eigen::Ref<const VectorXd>& nu) {
  if (nu.size() != S_.cols()) throw std::invalid_argument("nu has the wrong length");
  v_.noalias() = S_ * nu;
  // one pass: RNEA(q, v, 0) without gravity = C v, whose forward sweep leaves the joint velocities and their
  // accelerations at zero joint acceleration (for the drift terms); RNEA(q, v, w) = C v + g + M w
  bias_pass();
  for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model_.njoints); ++i) data_.a[i] = data_.a_gf[i];
  drift_pass();
  reduce(data_.M, S_, g_, data_.tau, w_, B_, SM_, Mr_, hr_, gr_, Br_);
}

void Evaluator::bias_pass() {
  if (bias_fast_ && crba_at_q_) kernels::bias_forces(model_, data_, v_, zero_);
  else pin::rnea(model_, data_, q_, v_, zero_);
}

py::tuple Evaluator::evaluate(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
  configure(q);
  dynamics(nu);
  if (operational_) return py::make_tuple(Mr_, hr_, gr_, Br_, S_, w_, v_, A_, residual_, cond_, Kinv_);
  return py::make_tuple(Mr_, hr_, gr_, Br_, S_, w_, v_, A_, residual_, py::none(), py::none());
}

long Evaluator::compute(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
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

VectorXd Evaluator::rhs(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                        const Eigen::Ref<const VectorXd>& tau, double alpha) {
  VectorXd out(nv_ + nu.size());
  rhs_into(q, nu, tau, alpha, out);
  return out;
}

void Evaluator::rhs_into(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
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
void Evaluator::slip_rhs_into(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                              const Eigen::Ref<const VectorXd>& tau, double alpha, Eigen::Ref<VectorXd> out) {
  configure(q);
  dynamics(nu);
  const int k = static_cast<int>(S_.cols());
  const int nr = static_cast<int>(rows_.size());
  if (tau.size() != Br_.cols()) throw std::invalid_argument("tau has the wrong length");
  if (out.size() != nv_ + k + 1) throw std::invalid_argument("state has the wrong length");
  if (k + nr != nv_) throw Fallback("rows and independent velocities do not make a square system");
  slip_.solve(slips_, rows_, A_, SM_, geo_, Aw_, v_, B_, tau, data_.tau, data_.M, w_, nv_, k, lus_);
  out.head(nv_) = v_;
  if (alpha != 0.0) pull_back(alpha, out);
  out.segment(nv_, k) = slip_.x.head(k);
  out[nv_ + k] = slip_.power;
}

py::tuple Evaluator::slip_rhs(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                              const Eigen::Ref<const VectorXd>& tau, double alpha) {
  if (slips_.empty()) throw std::invalid_argument("no slipping wheels");
  VectorXd out(nv_ + nu.size() + 1);
  slip_rhs_into(q, nu, tau, alpha, out);
  RowMat force(slips_.size(), 2);
  for (size_t i = 0; i < slips_.size(); ++i) force.row(i) = -slip_.normal[i] * slip_.c.row(i);
  return py::make_tuple(out, slip_.normal, RowMat(slip_.s), force);
}

// ------------------------------------------------------------------------------------------ springs, compliant wheels
void Evaluator::add_spring(int index, double stiffness, double damping, double rest) {
  if (index < 0 || index >= nv_) throw std::invalid_argument("no such coordinate");
  springs_.push_back(robotdyn::kernels::JointSpring{index, stiffness, damping, rest});
}

void Evaluator::add_compliant_wheel(int frame, const Vector3d& axis, double radius, int radius_index, int kind,
                                    double k, double c, double n, int code, double p0, double p1, const MatrixXd& D) {
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

unsigned long long Evaluator::contact_mode() const {
  unsigned long long out = 0;
  for (size_t i = 0; i < contact_states_.size() && i < 32; ++i) {
    if (contact_states_[i].delta > 0.0) out |= 1ULL << (2 * i);
    if (contact_states_[i].force[2] > 0.0) out |= 1ULL << (2 * i + 1);
  }
  return out;
}

void Evaluator::applied_forces() {
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

double Evaluator::stored_energy() const {
  double out = robotdyn::kernels::joint_springs_potential(springs_, q_);
  for (const auto& cc : contacts_) out += cc.normal.potential(-geo_[cc.wheel].phi);
  return out;
}

void Evaluator::penetrations(const double* y, const py::object& rechoose, std::vector<double>& out) {
  if (!(configured_ && q_.size() == nv_ && Eigen::Map<const VectorXd>(y, nv_) == q_))
    with_rechoice(y, rechoose, [&] { configure(Eigen::Map<const VectorXd>(y, nv_)); });
  out.resize(contacts_.size());
  for (size_t i = 0; i < contacts_.size(); ++i) out[i] = -geo_[contacts_[i].wheel].phi;
}

py::tuple Evaluator::applied_state(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
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
void Evaluator::add_rolling_rows(const MatrixXd& D) {
  if (contacts_.empty() || D.cols() != 2 || D.rows() < 1 || D.rows() > 2)
    throw std::invalid_argument("rolling rows need a compliant wheel and directions (1..2, 2)");
  Wheel wh = wheels_[contacts_.back().wheel];
  wh.D.setZero(D.rows(), 3);
  wh.D.leftCols(2) = D;
  rolling_contact_.push_back(static_cast<int>(contacts_.size()) - 1);
  rolling_wheels_.push_back(wh);
  rolling_on_.push_back(0);
}

void Evaluator::set_rolling_mode(const std::vector<int>& on) {
  if (on.size() != rolling_on_.size()) throw std::invalid_argument("one flag per rolling compliant wheel expected");
  for (size_t i = 0; i < on.size(); ++i) rolling_on_[i] = on[i] != 0;
}

void Evaluator::rolling_rows_into(const std::vector<char>& on, MatrixXd& G, VectorXd& drift) {
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

void Evaluator::rolling_solve(const Eigen::Ref<const VectorXd>& nu, double beta) {
  rolling_rows_into(rolling_on_, rollG_, rollDrift_);
  rollGr_.noalias() = rollG_ * S_;
  rollTarget_ = -(rollG_ * w_ + rollDrift_);
  if (beta != 0.0) rollTarget_.noalias() -= beta * (rollGr_ * nu);
  kernels::rolling_accelerations(llt_, rollGr_, rollTarget_, force_, rollLambda_, rollMinvGT_);
}

double Evaluator::rolling_event() const {
  double g = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < rolling_contact_.size(); ++i) {
    const int c = rolling_contact_[i];
    const auto& st = contact_states_[c];
    const double p = kernels::pressing(contacts_[c].normal, st.delta, st.rate);
    g = std::min(g, rolling_on_[i] ? p : -p);
  }
  return g;
}

py::tuple Evaluator::rolling_state(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu) {
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
void Evaluator::set_controller(const robotdyn::Controller* c) {
  if (c == nullptr) {
    controller_.reset();
    return;
  }
  if (c->motors() != static_cast<int>(motors_.size()) || c->n() != nv_ || c->k() != mobility())
    throw std::invalid_argument("the feedback law is for another robot (motors, coordinates or velocities)");
  if (!slips_.empty()) throw std::invalid_argument("feedback laws do not run with slipping wheels");
  controller_ = *c;
}

VectorXd Evaluator::control_torque(const robotdyn::Controller& c, double t, const Eigen::Ref<const VectorXd>& q,
                                   const Eigen::Ref<const VectorXd>& nu) {
  configure(q);
  dynamics(nu);
  robotdyn::Controller law = c;
  VectorXd out(Br_.cols());
  law.eval(t, q, nu, Mr_, hr_, Br_, S_, w_, v_, [this](int f) { return frame_kinematics(f); }, out);
  return out;
}

robotdyn::FrameKinematics Evaluator::frame_kinematics(int f) {
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

void Evaluator::deriv(double t, const std::vector<double>& y, std::vector<double>& dy, double alpha,
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
  event_g_ = slip_.min_normal;
}

double Evaluator::lift_off(double t, const std::vector<double>& y, double alpha, const robotdyn::TorqueProfile& profile,
                           const py::object& rechoose) {
  if (!(t == event_t_ && y == event_y_)) {
    event_dy_.resize(y.size());
    deriv(t, y, event_dy_, alpha, profile, rechoose);
  }
  return event_g_;
}

void Evaluator::deriv_into(double t, const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> dy, double alpha,
                           const robotdyn::TorqueProfile& profile, const py::object& rechoose) {
  if (y.size() != state_size() || dy.size() != state_size())
    throw std::invalid_argument("y, dy: expected arrays of the state's length " + std::to_string(state_size()));
  step_y_.assign(y.data(), y.data() + y.size());
  deriv(t, step_y_, step_dy_, alpha, profile, rechoose);
  dy = Eigen::Map<const VectorXd>(step_dy_.data(), static_cast<Eigen::Index>(step_dy_.size()));
}

void Evaluator::depths_into(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> out, const py::object& rechoose) {
  if (y.size() != state_size() || out.size() != static_cast<Eigen::Index>(contacts_.size()))
    throw std::invalid_argument("y, out: expected the state's length and one value per compliant wheel");
  penetrations(y.data(), rechoose, step_depths_);
  out = Eigen::Map<const VectorXd>(step_depths_.data(), static_cast<Eigen::Index>(step_depths_.size()));
}

double Evaluator::event_value(double t, const Eigen::Ref<const VectorXd>& y, double alpha,
                              const robotdyn::TorqueProfile& profile, const py::object& rechoose) {
  if (y.size() != state_size()) throw std::invalid_argument("y: expected the state's length");
  step_y_.assign(y.data(), y.data() + y.size());
  return lift_off(t, step_y_, alpha, profile, rechoose);
}

void Evaluator::observe(const double* y, double& energy, double& residual, const py::object& rechoose) {
  with_rechoice(y, rechoose, [&] { configure(Eigen::Map<const VectorXd>(y, nv_)); });
  v_.noalias() = S_ * Eigen::Map<const VectorXd>(y + nv_, mobility());  // (no dynamics needed)
  energy_residual(energy, residual);
}

void Evaluator::energy_residual(double& energy, double& residual) {
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

void Evaluator::sample(const double* y, double& energy, double& residual, const py::object& rechoose) {
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

bool Evaluator::sample_selection() {
  if (!kernels::selection_blocks(A_, rows_, independent_, dependent_, nv_, lu_, sel_, S_)) return true;
  return kernels::selection_solve(dependent_, lus_, lu_, sel_, S_);
}

// ------------------------------------------------------------------------------------------ constraint forces
void Evaluator::lambda_from(const Eigen::Ref<const VectorXd>& tau) {
  constraint_multipliers(B_, tau, force_, e_, rows_, dependent_, operational_, Kinv_, lu_, lus_, nrows(), lr_,
                         lambda_);
}

long Evaluator::forces(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
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

py::tuple Evaluator::forces_at(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& v,
                               const Eigen::Ref<const VectorXd>& a, const Eigen::Ref<const VectorXd>& tau) {
  if (v.size() != nv_ || a.size() != nv_ || tau.size() != static_cast<Eigen::Index>(motors_.size()))
    throw std::invalid_argument("v, a or tau has the wrong length");
  configure(q);
  pin::rnea(model_, data_, q_, v, a);  // without gravity: M a + C v
  e_ = data_.tau + g_;
  lambda_from(tau);
  return py::make_tuple(lambda_, e_, wheel_forces(), A_);
}

void Evaluator::set_normal_stiffness(const Eigen::Ref<const VectorXd>& k) {
  if (k.size() != static_cast<Eigen::Index>(wheels_.size())) throw std::invalid_argument("one stiffness per wheel");
  if (!(k.array() > 0.0).all() || !k.allFinite()) throw std::invalid_argument("stiffnesses must be finite and > 0");
  rigid_.set_stiffness(k);
}

py::tuple Evaluator::wheel_forces() {
  fill_wheel_forces();
  return py::make_tuple(wl_, ww_, wf_, wp_);
}

// ------------------------------------------------------------------------------------------ model vector
VectorXd Evaluator::model_vector() const {
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

Eigen::Index Evaluator::model_vector_size() const {
  return 22 * (model_.njoints - 1) + 12 * static_cast<Eigen::Index>(frames_.size()) +
         4 * static_cast<Eigen::Index>(wheels_.size()) + 4 * static_cast<Eigen::Index>(couplings_.size()) + 3;
}

void Evaluator::set_model_vector(const double* x) {
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

void Evaluator::set_model_vector_py(const VectorXd& x) {
  if (x.size() != model_vector_size()) throw std::invalid_argument("model vector has the wrong length");
  set_model_vector(x.data());
}

py::dict Evaluator::profile(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu, int repeat,
                            double alpha) {
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

py::tuple Evaluator::evaluate_many(const Eigen::Ref<const RowMat>& Q, const Eigen::Ref<const RowMat>& NU) {
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

void Evaluator::project() {  // projection.py _build / operational_space.py project_operational, with the given rows
  if (operational_)
    project_operational(A_, rows_, op_select_, model_, data_, frames_[op_frame_], op_local_, nv_, K_, Jc_, lu_,
                        Kinv_, cond_, S_);
  else if (!project_selection(A_, rows_, independent_, dependent_, nv_, lus_, lu_, sel_, cond_, S_))
    return;
  if (!differencing_) check_span(A_, S_, AS_);  // (a stiff Jacobian's difference leaves the manifold by ~1e-8)
}

// ============================================================================================== simulation drivers
// ------------------------------------------------------------------------------------------ many runs
py::dict Evaluator::simulate_many(const Eigen::Ref<const RowMat>& Q0, const Eigen::Ref<const RowMat>& NU0,
                                  const Eigen::Ref<const RowMat>& models,
                                  const std::vector<robotdyn::TorqueProfile*>& profiles,
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

void Evaluator::check_start(const double* y, const py::object& rechoose) {
  with_rechoice(y, rechoose, [&] { configure(Eigen::Map<const VectorXd>(y, nv_)); });
  for (size_t r = 0; r < holonomic_.size(); ++r)
    if (holonomic_[r] && !(std::fabs(residual_[r]) <= 1e-6))
      throw std::invalid_argument("q0 violates holonomic row #" + std::to_string(r) + " by " +
                                  std::to_string(residual_[r]) + "; expected |residual| <= 1e-06");
}

py::dict Evaluator::simulate(const VectorXd& q0, const VectorXd& nu0, double t0, double t_end,
                             const std::vector<double>& samples, double rtol, double atol, double alpha,
                             const robotdyn::TorqueProfile& profile, const std::vector<double>& breaks,
                             const std::string& method, py::object progress, py::object rechoose) {
  const int k = mobility();
  if (q0.size() != nv_ || nu0.size() != k) throw std::invalid_argument("q0 or nu0 has the wrong length");
  if (profile.motors() != static_cast<int>(motors_.size()))
    throw std::invalid_argument("the torque profile is for another number of motors");
  const bool slipping = !slips_.empty();
  if (slipping && applied()) throw std::invalid_argument("slipping wheels with joint springs or compliant wheels");
  if (method == "rosenbrock4" && slipping) throw std::invalid_argument("rosenbrock4 does not run slipping wheels");
  // slipping wheels: the friction work as the last component; springs, compliant wheels: friction and damper work
  const int dim = nv_ + k + (slipping ? 1 : applied() ? 2 : 0);
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

}  // namespace compiled
}  // namespace robotdyn

// Feedback laws as data, evaluated without Python: the C++ side of robotdyn/simulation/feedback.py (FeedbackLaw,
// whose __call__ is the Python reference of eval below, term by term).
//
//   tau = f(t) + K_q (q_d(t) - q) + K_nu (nu_d(t) - nu) + B_r^+ (M_r a(t) + h_r)
//
// f (motors), q_d (n), nu_d (k) and a (k) are profiles of time (robotdyn::TorqueProfile, any width); K_q
// (motors, n) and K_nu (motors, k) constant gains; B_r^+ the minimum-norm least-squares inverse (numpy.linalg.lstsq)
// of the reduced input matrix, with M_r and h_r the reduced mass matrix and the reduced nonlinear forces the
// evaluator has just computed at (q, nu). Each term is optional. Covers PD tracking of coordinates and velocities,
// LQR (tau0 - K (x - x0)) and computed-torque (inverse dynamics) feed-forward of a reference acceleration.
#pragma once

#include <Eigen/Core>
#include <Eigen/QR>

#include <memory>
#include <optional>
#include <string>
#include <stdexcept>

#include "_torque_profile.hpp"

namespace robotdyn {

class Controller {
 public:
  Controller() = default;
  // Null profiles / empty gain matrices: the term is absent.
  Controller(int motors, int n, int k, const TorqueProfile* feedforward, const Eigen::MatrixXd& Kq,
             const TorqueProfile* q_ref, const Eigen::MatrixXd& Knu, const TorqueProfile* nu_ref,
             const TorqueProfile* acceleration)
      : motors_(motors), n_(n), k_(k), Kq_(Kq), Knu_(Knu) {
    auto keep = [](const TorqueProfile* p, int width, const char* what) -> std::shared_ptr<TorqueProfile> {
      if (p == nullptr) return nullptr;
      if (p->motors() != width)
        throw std::invalid_argument(std::string("feedback law: ") + what + " has the wrong width");
      return std::make_shared<TorqueProfile>(*p);
    };
    ff_ = keep(feedforward, motors, "the feed-forward torque");
    qd_ = keep(q_ref, n, "the coordinate reference");
    nud_ = keep(nu_ref, k, "the velocity reference");
    acc_ = keep(acceleration, k, "the reference acceleration");
    if (Kq_.size() && (Kq_.rows() != motors || Kq_.cols() != n))
      throw std::invalid_argument("feedback law: K_q must be (motors, n)");
    if (Knu_.size() && (Knu_.rows() != motors || Knu_.cols() != k))
      throw std::invalid_argument("feedback law: K_nu must be (motors, k)");
    if (qd_ && !Kq_.size()) throw std::invalid_argument("feedback law: a coordinate reference without K_q");
    if (nud_ && !Knu_.size()) throw std::invalid_argument("feedback law: a velocity reference without K_nu");
    qbuf_.resize(n);
    nubuf_.resize(k);
  }

  int motors() const { return motors_; }
  int n() const { return n_; }
  int k() const { return k_; }
  bool needs_dynamics() const { return static_cast<bool>(acc_); }

  // tau at (t, q, nu), with the reduced model (M_r, h_r, B_r) at that state, into out (motors).
  void eval(double t, const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& nu,
            const Eigen::MatrixXd& M, const Eigen::VectorXd& h, const Eigen::MatrixXd& B,
            Eigen::Ref<Eigen::VectorXd> out) {
    out.setZero();
    if (ff_) ff_->eval(t, out);
    if (Kq_.size()) {
      if (qd_) qd_->eval(t, qbuf_);
      else qbuf_.setZero();
      qbuf_ -= q;
      out.noalias() += Kq_ * qbuf_;
    }
    if (Knu_.size()) {
      if (nud_) nud_->eval(t, nubuf_);
      else nubuf_.setZero();
      nubuf_ -= nu;
      out.noalias() += Knu_ * nubuf_;
    }
    if (acc_) {
      acc_->eval(t, nubuf_);
      force_.noalias() = M * nubuf_;
      force_ += h;
      cod_.compute(B);
      out.noalias() += cod_.solve(force_);
    }
  }

 private:
  int motors_ = 0, n_ = 0, k_ = 0;
  std::shared_ptr<TorqueProfile> ff_, qd_, nud_, acc_;
  Eigen::MatrixXd Kq_, Knu_;
  Eigen::VectorXd qbuf_, nubuf_, force_;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod_;
};

}  // namespace robotdyn

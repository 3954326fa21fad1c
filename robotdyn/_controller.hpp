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
//
// Plus, optionally, the input-output linearising law of robotdyn/simulation/control.py (LinearisingController.
// command, its Python reference, step by step): tasks on coordinates and on points of frames, references as
// profiles (value, rate, acceleration), u = (JS)^+ (y_d'' + K_d (y_d' - y') + K_p (y_d - y) - J w - Jdot v), a
// secondary task in the null space, damping of the rest, and the computed torque on the reduced model
// (computed_torque: [B_r, -M_r[:, free]] solved in least squares).
#pragma once

#include <Eigen/Core>
#include <Eigen/QR>
#include <Eigen/SVD>

#include <memory>
#include <optional>
#include <string>
#include <stdexcept>

#include "_torque_profile.hpp"

namespace robotdyn {

// One output of the linearising law: a point of a frame (kind 0; `frame` the evaluator's frame index, `offset` in
// the frame's axes, `select` the world axes) or coordinates (kind 1; `select` their indices in q). Its reference:
// value, rate and acceleration profiles, each of the task's dimension.
struct Task {
  int kind = 1;
  int frame = -1;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::vector<int> select;
  std::shared_ptr<TorqueProfile> y, yd, ydd;
  int dim() const { return static_cast<int>(select.size()); }
};

// The kinematics of a frame at the evaluated state: placement, LOCAL_WORLD_ALIGNED Jacobian (6, n), and the
// classical acceleration of its origin and its angular acceleration at zero joint acceleration (world axes).
struct FrameKinematics {
  Eigen::Matrix3d R;
  Eigen::Vector3d p, a, alpha;
  const Eigen::Matrix<double, 6, Eigen::Dynamic>* J = nullptr;
};

// numpy.linalg.pinv(A, rcond): singular values below rcond * the largest dropped; into P, with the SVD's and the
// inverted singular values' buffers (kept by the caller: sized once, no allocation per call after the first).
inline void pinv_into(const Eigen::MatrixXd& A, double rcond, Eigen::JacobiSVD<Eigen::MatrixXd>& svd,
                      Eigen::VectorXd& inv, Eigen::MatrixXd& P) {
  if (A.size() == 0) {
    P.setZero(A.cols(), A.rows());
    return;
  }
  svd.compute(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  const double cut = rcond * (s.size() ? s[0] : 0.0);
  inv.setZero(s.size());
  for (Eigen::Index i = 0; i < s.size(); ++i)
    if (s[i] > cut) inv[i] = 1.0 / s[i];
  P.noalias() = svd.matrixV() * inv.asDiagonal() * svd.matrixU().transpose();
}

// The buffers of one evaluation of the linearising law (Linearising::eval): owned by each copy of a Controller (one
// per thread of simulate_many), sized on the first evaluation and reused, so that an evaluation allocates nothing
// afterwards. Every product is formed into its buffer as the allocating expressions formed it into a temporary,
// so the torques are the same bits.
struct LinearisingWork {
  struct TaskWork {  // one task's rows
    Eigen::VectorXd y, drift, yr, ydr, yddr, ydot, Jw;
    Eigen::MatrixXd J, Jp, JS;
    Eigen::Matrix<double, 3, Eigen::Dynamic> skJ;  // (the type of the temporary it replaces)
  };
  std::vector<TaskWork> tasks;  // the primary tasks, then the secondary ones
  Eigen::MatrixXd A, A2, A2N, P, P2, PA, N, N2, NN, lhs;
  Eigen::VectorXd b, b2, u, r2, A2u, P2r2, d, Nd, rhs, x, inv, inv2;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd, svd2;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
  std::vector<int> ctrl, free;
  std::vector<char> is_ctrl;
};

class Linearising {
 public:
  Linearising() = default;
  Linearising(double kp, double kd, double damping, const std::vector<int>& controlled, std::vector<Task> tasks,
              std::vector<Task> secondary)
      : kp_(kp), kd_(kd), damping_(damping), controlled_(controlled), tasks_(std::move(tasks)),
        secondary_(std::move(secondary)) {}

  // The motor torques (out) at (t, q, nu) from the reduced model (M, h, B, S, w, v) and frame(f) -> kinematics, with
  // the buffers in wk (no allocation once they are sized).
  template <class Frames>
  void eval(double t, const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& nu,
            const Eigen::MatrixXd& M, const Eigen::VectorXd& h, const Eigen::MatrixXd& B, const Eigen::MatrixXd& S,
            const Eigen::VectorXd& w, const Eigen::VectorXd& v, Frames&& frame, Eigen::Ref<Eigen::VectorXd> out,
            LinearisingWork& wk) {
    const Eigen::Index k = M.rows();
    wk.tasks.resize(tasks_.size() + secondary_.size());
    rows(tasks_, 0, t, q, S, w, v, frame, wk.A, wk.b, wk);
    pinv_into(wk.A, 1e-10, wk.svd, wk.inv, wk.P);
    wk.u.noalias() = wk.P * wk.b;
    wk.PA.noalias() = wk.P * wk.A;
    wk.N = Eigen::MatrixXd::Identity(k, k) - wk.PA;
    if (!secondary_.empty()) {
      rows(secondary_, tasks_.size(), t, q, S, w, v, frame, wk.A2, wk.b2, wk);
      wk.A2N.noalias() = wk.A2 * wk.N;
      pinv_into(wk.A2N, 1e-8, wk.svd2, wk.inv2, wk.P2);
      wk.A2u.noalias() = wk.A2 * wk.u;
      wk.r2 = wk.b2 - wk.A2u;
      wk.P2r2.noalias() = wk.P2 * wk.r2;
      wk.u = wk.u + wk.P2r2;
      wk.PA.noalias() = wk.P2 * wk.A2N;
      wk.N2 = Eigen::MatrixXd::Identity(k, k) - wk.PA;
      wk.NN.noalias() = wk.N * wk.N2;
      wk.N = wk.NN;
    }
    if (damping_ != 0.0) {
      wk.d = damping_ * nu;
      wk.Nd.noalias() = wk.N * wk.d;
      wk.u -= wk.Nd;
    }
    // computed_torque: M nudot + h = B tau with nudot[controlled] = u[controlled], the free ones unknown
    const Eigen::Index m = B.cols();
    wk.ctrl = controlled_;
    wk.free.clear();
    if (wk.ctrl.empty())
      for (int i = 0; i < k; ++i) wk.ctrl.push_back(i);
    wk.is_ctrl.assign(k, 0);
    for (int c : wk.ctrl) wk.is_ctrl[c] = 1;
    for (int i = 0; i < k; ++i)
      if (!wk.is_ctrl[i]) wk.free.push_back(i);
    wk.lhs.resize(k, m + static_cast<Eigen::Index>(wk.free.size()));
    wk.lhs.leftCols(m) = B;
    for (size_t j = 0; j < wk.free.size(); ++j) wk.lhs.col(m + j) = -M.col(wk.free[j]);
    wk.rhs.setZero(k);
    for (int c : wk.ctrl) wk.rhs += M.col(c) * wk.u[c];
    wk.rhs += h;
    wk.cod.compute(wk.lhs);
    wk.x = wk.cod.solve(wk.rhs);
    out += wk.x.head(m);
  }

 private:
  // The rows A (tasks' dimension, k) and right-hand sides b of `tasks`, whose buffers are wk.tasks[first + i].
  template <class Frames>
  void rows(const std::vector<Task>& tasks, size_t first, double t, const Eigen::Ref<const Eigen::VectorXd>& q,
            const Eigen::MatrixXd& S, const Eigen::VectorXd& w, const Eigen::VectorXd& v, Frames& frame,
            Eigen::MatrixXd& A, Eigen::VectorXd& b, LinearisingWork& wk) {
    int total = 0;
    for (const Task& task : tasks) total += task.dim();
    const Eigen::Index n = S.rows();
    A.resize(total, S.cols());
    b.resize(total);
    int row = 0;
    for (size_t ti = 0; ti < tasks.size(); ++ti) {
      const Task& task = tasks[ti];
      LinearisingWork::TaskWork& tw = wk.tasks[first + ti];
      const int d = task.dim();
      tw.y.resize(d), tw.drift.resize(d), tw.yr.resize(d), tw.ydr.resize(d), tw.yddr.resize(d);
      tw.J.resize(d, n);
      if (task.kind == 0) {
        const FrameKinematics f = frame(task.frame);
        const Eigen::Vector3d r = f.R * task.offset;
        const Eigen::Vector3d omega = f.J->bottomRows<3>() * v;
        Eigen::Matrix3d sk;
        sk << 0.0, -r[2], r[1], r[2], 0.0, -r[0], -r[1], r[0], 0.0;
        tw.skJ.noalias() = sk * f.J->bottomRows<3>();
        tw.Jp = f.J->topRows<3>() - tw.skJ;
        const Eigen::Vector3d dr = f.a + f.alpha.cross(r) + omega.cross(omega.cross(r));
        const Eigen::Vector3d pos = f.p + r;
        for (int i = 0; i < d; ++i) {
          tw.y[i] = pos[task.select[i]];
          tw.J.row(i) = tw.Jp.row(task.select[i]);
          tw.drift[i] = dr[task.select[i]];
        }
      } else {
        tw.J.setZero();
        for (int i = 0; i < d; ++i) {
          tw.y[i] = q[task.select[i]];
          tw.J(i, task.select[i]) = 1.0;
        }
        tw.drift.setZero();
      }
      task.y->eval(t, tw.yr);
      task.yd->eval(t, tw.ydr);
      task.ydd->eval(t, tw.yddr);
      tw.ydot.noalias() = tw.J * v;
      tw.JS.noalias() = tw.J * S;
      A.middleRows(row, d) = tw.JS;
      tw.Jw.noalias() = tw.J * w;
      b.segment(row, d) = tw.yddr + kd_ * (tw.ydr - tw.ydot) + kp_ * (tw.yr - tw.y) - tw.Jw - tw.drift;
      row += d;
    }
  }

  double kp_ = 0.0, kd_ = 0.0, damping_ = 0.0;
  std::vector<int> controlled_;
  std::vector<Task> tasks_, secondary_;
};

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

  // Adds the linearising law's torques to every evaluation.
  void set_linearising(const Linearising& law) { lin_ = std::make_shared<Linearising>(law); }
  bool needs_frames() const { return static_cast<bool>(lin_); }

  int motors() const { return motors_; }
  int n() const { return n_; }
  int k() const { return k_; }
  bool needs_dynamics() const { return static_cast<bool>(acc_); }

  // tau at (t, q, nu), with the reduced model (M_r, h_r, B_r, S, w, v) and the frames' kinematics at that state,
  // into out (motors).
  template <class Frames>
  void eval(double t, const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& nu,
            const Eigen::MatrixXd& M, const Eigen::VectorXd& h, const Eigen::MatrixXd& B, const Eigen::MatrixXd& S,
            const Eigen::VectorXd& w, const Eigen::VectorXd& v, Frames&& frame, Eigen::Ref<Eigen::VectorXd> out) {
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
      solved_ = cod_.solve(force_);  // (into its buffer: no temporary per evaluation)
      out += solved_;
    }
    if (lin_) lin_->eval(t, q, nu, M, h, B, S, w, v, frame, out, lin_work_);
  }

 private:
  int motors_ = 0, n_ = 0, k_ = 0;
  std::shared_ptr<TorqueProfile> ff_, qd_, nud_, acc_;
  std::shared_ptr<Linearising> lin_;  // shared by copies (its evaluation keeps no state: its buffers are lin_work_)
  LinearisingWork lin_work_;          // each copy's own (simulate_many's threads)
  Eigen::MatrixXd Kq_, Knu_;
  Eigen::VectorXd qbuf_, nubuf_, force_, solved_;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod_;
};

}  // namespace robotdyn

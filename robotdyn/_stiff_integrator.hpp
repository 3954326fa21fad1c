// A stiff integrator for compiled simulations: Boost.Odeint's Rosenbrock method of order 4 (rosenbrock4, L-stable,
// embedded order-3 error estimate; Shampine's coefficients) under its step-size controller (rosenbrock4_controller,
// error in the RMS norm of |err_i| / (atol + rtol max(|y_i|, |y_new,i|))) with its dense output
// (rosenbrock4_dense_output), driven by run_dense of _integrator.hpp like the explicit dense-output steppers:
// samples interpolated, restarts at breakpoints, poll every ~50 ms, FAILED on a vanishing step (below the spacing of
// doubles at t) or a non-finite state.
// (Used for compliant wheel contacts, whose stiffness makes explicit steppers take steps of ~0.1 / omega.)
//
// The Jacobian df/dy that a Rosenbrock step needs is taken by forward differences of the right-hand side, one
// evaluation per column (step sqrt(eps) max(1, |y_j|)) and one for df/dt; the right-hand side at the step's start,
// which rosenbrock4 evaluates just before, is reused, and a retried step (same start) reuses the whole Jacobian.
// Columns from `active` on are zero without evaluation (states nothing depends on: accumulated work). The right-hand
// side may switch between smooth modes (a compliant wheel touching down: its damper force jumps from zero to
// c deltadot): `mode()` names the mode of the last evaluation (a bit pattern), and a difference whose perturbed state
// left the mode of y is taken backwards instead (a difference across the jump would put jump / step ~ 1e10 into J);
// mode.differencing(true / false) brackets the differences (the evaluator then skips checks that a state ~1e-8 off
// the constraint manifold would fail, e.g. the projection's span check).
// (A Jacobian kept over several steps, as W-methods allow, is no option here: rosenbrock4's error estimate then
// collapses the steps: on the compliant linkage rover, 3 reuses took 11x more steps.) Why differences: the right-hand side is a projected multibody model
// (S(q), its drift, the contact geometry) without compiled derivatives; differences cost `active` + 1 evaluations
// per step, against the 6 evaluations of the step itself, and their error (~1e-8 relative) only perturbs the
// Rosenbrock matrix, which changes the error estimate, never the consistency of the accepted solution.
//
// Non-terminal crossing events (flight phases): after every accepted step, `on_step(stepper)` may locate sign
// changes of functions of the state on the dense output (Crossings below).
#pragma once

#include "_integrator.hpp"

#include <boost/numeric/odeint/stepper/rosenbrock4.hpp>
#include <boost/numeric/odeint/stepper/rosenbrock4_controller.hpp>
#include <boost/numeric/odeint/stepper/rosenbrock4_dense_output.hpp>

#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

namespace robotdyn {

// rosenbrock4_dense_output behind the std::vector State interface that run_dense drives.
template <class OnStep, class Mode>
class StiffStepper {
 public:
  using Vec = boost::numeric::ublas::vector<double>;
  using Mat = boost::numeric::ublas::matrix<double>;
  using Dense = odeint::rosenbrock4_dense_output<odeint::rosenbrock4_controller<odeint::rosenbrock4<double>>>;

  StiffStepper(double atol, double rtol, int active, OnStep& on_step, Mode& mode)
      : dense_(odeint::rosenbrock4_controller<odeint::rosenbrock4<double>>(atol, rtol)), active_(active),
        on_step_(on_step), mode_(mode) {}

  void initialize(const State& y0, double t0, double dt0) {
    to_vec(y0, u_);
    dense_.initialize(u_, t0, dt0);
    cur_ = y0;
    if (!started_) {
      started_ = true;
      on_step_.start(t0, cur_);
    }
  }

  template <class Sys>
  void do_step(Sys& sys) {
    auto f = [this, &sys](const Vec& x, Vec& dxdt, double t) { eval(sys, x, dxdt, t); };
    auto jac = [this, &sys](const Vec& x, Mat& J, double t, Vec& dfdt) { jacobian(sys, x, J, t, dfdt); };
    dense_.do_step(std::make_pair(f, jac));
    from_vec(dense_.current_state(), cur_);
    on_step_(*this);
  }

  void calc_state(double t, State& y) {
    tmp_.resize(cur_.size(), false);  // (rosenbrock4's calc_state writes into it without resizing)
    dense_.calc_state(t, tmp_);
    from_vec(tmp_, y);
  }
  const State& current_state() const { return cur_; }
  double current_time() const { return dense_.current_time(); }
  double previous_time() const { return dense_.previous_time(); }
  double current_time_step() const { return dense_.current_time_step(); }

 private:
  static void to_vec(const State& x, Vec& u) {
    u.resize(x.size(), false);
    std::copy(x.begin(), x.end(), u.begin());
  }
  static void from_vec(const Vec& u, State& x) { x.assign(u.begin(), u.end()); }

  template <class Sys>
  void eval(Sys& sys, const Vec& x, Vec& dxdt, double t) {
    from_vec(x, xs_);
    sys(xs_, ds_, t);
    to_vec(ds_, dxdt);
    last_t_ = t;  // (the Jacobian at this very state reuses it)
    last_x_ = xs_;
    last_f_ = ds_;
    last_mode_ = mode_();
  }

  template <class Sys>
  void jacobian(Sys& sys, const Vec& x, Mat& J, double t, Vec& dfdt) {
    const size_t n = x.size();
    from_vec(x, xs_);
    if (!(t == last_t_ && xs_ == last_x_)) {
      sys(xs_, last_f_, t);
      last_t_ = t;
      last_x_ = xs_;
      last_mode_ = mode_();
    }
    const unsigned long long mode0 = last_mode_;
    // (rosenbrock4 factorises J in place: the kept copy is handed out again)
    if (jac_.size1() == n && t == jac_t_ && xs_ == jac_x_) {  // a retried step: the same Jacobian
      J = jac_;
      dfdt = dfdt_;
      return;
    }
    jac_t_ = t;
    jac_x_ = xs_;
    f0_ = last_f_;
    struct Bracket {  // mode_.differencing(true) until the differences are taken (or one throws)
      Mode& m;
      explicit Bracket(Mode& m_) : m(m_) { m.differencing(true); }
      ~Bracket() { m.differencing(false); }
    } bracket(mode_);
    J.resize(n, n, false);
    J.clear();
    const double root = std::sqrt(std::numeric_limits<double>::epsilon());
    const size_t active = std::min(n, static_cast<size_t>(active_));
    for (size_t j = 0; j < active; ++j) {
      xp_ = xs_;
      xp_[j] += root * std::max(1.0, std::fabs(xs_[j]));
      double h = xp_[j] - xs_[j];  // (exactly representable)
      sys(xp_, fp_, t);
      if (mode_() != mode0) {  // across a switch of the right-hand side: the other side
        xp_[j] = xs_[j] - h;
        h = xp_[j] - xs_[j];
        sys(xp_, fp_, t);
      }
      for (size_t i = 0; i < n; ++i) J(i, j) = (fp_[i] - f0_[i]) / h;
    }
    volatile double tp = t + root * std::max(1.0, std::fabs(t));
    const double ht = tp - t;
    sys(xs_, fp_, tp);
    dfdt.resize(n, false);
    for (size_t i = 0; i < n; ++i) dfdt[i] = (fp_[i] - f0_[i]) / ht;
    jac_ = J;
    dfdt_ = dfdt;
    last_t_ = std::numeric_limits<double>::quiet_NaN();  // (sys's buffers were used at other states since)
  }

  Dense dense_;
  int active_;
  OnStep& on_step_;
  Mode& mode_;
  bool started_ = false;
  Vec u_, tmp_, dfdt_;
  Mat jac_;
  State cur_, xs_, ds_, xp_, fp_, f0_, last_x_, last_f_, jac_x_;
  double last_t_ = std::numeric_limits<double>::quiet_NaN(), jac_t_ = std::numeric_limits<double>::quiet_NaN();
  unsigned long long last_mode_ = 0;
};

// Non-terminal events: m functions g(y) of the state (`values(t, y, out)` fills them) whose crossings of zero are
// located on the stepper's dense output after each accepted step (Illinois regula falsi, locate_root), as
// scipy's solve_ivp does for its events: upward where g goes from <= 0 to >= 0 across a step, downward from >= 0
// to <= 0; one crossing per function and step. `found` lists (t, function index, +1 up / -1 down) in step order.
template <class Values>
struct Crossings {
  Values values;
  std::vector<double> prev, now;
  State y;
  std::vector<std::tuple<double, int, int>> found;

  explicit Crossings(Values v) : values(std::move(v)) {}
  void start(double t0, const State& y0) { values(t0, y0, prev); }
  template <class Stepper>
  void operator()(Stepper& stepper) {
    if (prev.empty()) return;
    const double t0 = stepper.previous_time(), t1 = stepper.current_time();
    values(t1, stepper.current_state(), now);
    for (size_t i = 0; i < now.size(); ++i) {
      const double a = prev[i], b = now[i];
      const int direction = (a <= 0.0 && b >= 0.0 && !(a == 0.0 && b == 0.0)) ? 1 : (a >= 0.0 && b <= 0.0 && !(a == 0.0 && b == 0.0)) ? -1 : 0;
      if (!direction) continue;
      std::vector<double> g;
      const double s = direction > 0 ? -1.0 : 1.0;  // locate_root wants g going from >= 0 to <= 0
      const double te = locate_root(
          [&](double tc) {
            stepper.calc_state(tc, y);
            values(tc, y, g);
            return s * g[i];
          },
          t0, s * a, t1, s * b);
      found.emplace_back(te, static_cast<int>(i), direction);
    }
    prev.swap(now);
  }
};

// No events.
struct NoCrossings {
  void start(double, const State&) {}
  template <class Stepper>
  void operator()(Stepper&) {}
};

// The stiff run from (t0, y0) to t_end (see the top of this file): rtol, atol on every component; columns of the
// Jacobian from `active` on are zero; on_step as Crossings (or NoCrossings); mode() the right-hand side's mode at
// its last evaluation.
template <class System, class Observer, class Poll, class OnStep, class Mode, class Event = NoEvent>
Outcome integrate_stiff(System& system, const State& y0, double t0, double t_end, const std::vector<double>& samples,
                        size_t& next, const std::vector<double>& breaks, double rtol, double atol, int active,
                        Observer&& observer, Poll&& poll, OnStep& on_step, Mode& mode, Event&& event = Event()) {
  const double dt0 = std::min(1e-4, 1e-3 * (t_end - t0));
  StiffStepper<OnStep, Mode> stepper(atol, rtol, active, on_step, mode);
  // a step across a compliant wheel's touch-down (its damper force jumps) is accepted only once it is about
  // tolerance / jump long: steps down to the spacing of doubles at t are allowed (unit 0), not only 8 eps
  return run_dense(stepper, system, y0, t0, t_end, samples, next, breaks, dt0, observer, poll, event, 0.0);
}

}  // namespace robotdyn

namespace robotdyn {

// An explicit dense-output stepper of _integrator.hpp (dopri5, bulirsch_stoer) with non-terminal crossing events
// (Crossings) located on its dense output after each accepted step, as StiffStepper does.
template <class Stepper, class OnStep>
class WithCrossings {
 public:
  WithCrossings(Stepper& stepper, OnStep& on_step) : stepper_(stepper), on_step_(on_step) {}
  void initialize(const State& y0, double t0, double dt0) {
    stepper_.initialize(y0, t0, dt0);
    if (!started_) {
      started_ = true;
      on_step_.start(t0, y0);
    }
  }
  template <class Sys>
  void do_step(Sys& sys) {
    stepper_.do_step(sys);
    on_step_(*this);
  }
  void calc_state(double t, State& y) {
    y.resize(stepper_.current_state().size());
    stepper_.calc_state(t, y);
  }
  const State& current_state() const { return stepper_.current_state(); }
  double current_time() const { return stepper_.current_time(); }
  double previous_time() const { return stepper_.previous_time(); }
  double current_time_step() const { return stepper_.current_time_step(); }

 private:
  Stepper& stepper_;
  OnStep& on_step_;
  bool started_ = false;
};

// dopri5 or bulirsch_stoer (as integrate of _integrator.hpp) with crossing events; steps down to the spacing of
// doubles at t, as integrate_stiff (a touch-down's damper force jumps).
template <class System, class Observer, class Poll, class OnStep, class Event = NoEvent>
Outcome integrate_crossings(const std::string& method, System& system, const State& y0, double t0, double t_end,
                            const std::vector<double>& samples, size_t& next, const std::vector<double>& breaks,
                            double rtol, double atol, Observer&& observer, Poll&& poll, OnStep& on_step,
                            Event&& event = Event()) {
  const double dt0 = std::min(1e-3, 1e-3 * (t_end - t0));
  if (method == "bulirsch_stoer") {
    odeint::bulirsch_stoer_dense_out<State> stepper(atol, rtol, 1.0, 0.0);
    WithCrossings<decltype(stepper), OnStep> with(stepper, on_step);
    return run_dense(with, system, y0, t0, t_end, samples, next, breaks, dt0, observer, poll, event, 0.0);
  }
  if (method == "dopri5") {
    auto stepper = odeint::make_dense_output(atol, rtol, odeint::runge_kutta_dopri5<State>());
    WithCrossings<decltype(stepper), OnStep> with(stepper, on_step);
    return run_dense(with, system, y0, t0, t_end, samples, next, breaks, dt0, observer, poll, event, 0.0);
  }
  throw std::invalid_argument("flight phases need a dense-output integrator (dopri5, bulirsch_stoer, rosenbrock4), not " +
                              method);
}

}  // namespace robotdyn

// A whole simulation in C++: Boost.Odeint's error-controlled steppers driven to the requested sample times
// (robotdyn/compiled_simulation.py is the Python side; robotdyn/simulation.py's scipy loop the reference).
//
// Two drivers:
//  - run_sampled, for odeint's variable-step, variable-order Adams-Bashforth-Moulton (controlled_adams_bashforth_
//    moulton, orders 1..10, PECE with a PI step-size controller; the default): it steps exactly onto every
//    breakpoint, where it restarts the multistep history (a kink of the torque profile must not lie inside the
//    interpolation that Adams formulas rest on), and takes the samples between its steps from the Hermite
//    interpolant of its last accepted points (states and derivatives: HermiteHistory), so that dense sampling
//    does not shorten its steps;
//  - run_dense, for dense-output steppers (bulirsch_stoer_dense_out: Bulirsch-Stoer extrapolation; dopri5:
//    Dormand-Prince 5(4)): the samples inside each accepted step are interpolated (the steps do not depend on the
//    sampling); the stepper is restarted at breakpoints too.
// Both call `poll` every ~50 ms of wall time (progress, Ctrl-C, a stop flag), refuse a vanishing step size and a
// non-finite state (FAILED), and let an exception of the right-hand side propagate.
//
// A terminal event (optional, as solve_ivp's with direction -1): a function g(t, y) checked at every accepted step;
// where it goes from >= 0 to <= 0 across a step, its root is located (Illinois regula falsi safeguarded by
// bisection, to 4 eps relative in t) on the dense output (run_dense) or, for Adams (no dense output), on a
// Dormand-Prince re-integration from the step's start at the run's tolerances; the run stops there, with the
// samples up to the root and Outcome::event set.
#pragma once

#include <boost/numeric/odeint/stepper/bulirsch_stoer_dense_out.hpp>
#include <boost/numeric/odeint/stepper/dense_output_runge_kutta.hpp>
#include <boost/numeric/odeint/stepper/generation.hpp>
#include <boost/numeric/odeint/stepper/runge_kutta_dopri5.hpp>
#include <boost/numeric/odeint/stepper/adaptive_adams_bashforth_moulton.hpp>
#include <boost/numeric/odeint/stepper/controlled_adams_bashforth_moulton.hpp>
#include <boost/numeric/odeint/util/odeint_error.hpp>
#include <boost/numeric/odeint/integrate/integrate_adaptive.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotdyn {

namespace odeint = boost::numeric::odeint;
using State = std::vector<double>;

enum Status { DONE = 0, INTERRUPTED = 1, FAILED = 3 };

// How a run ended: DONE (t_end reached), INTERRUPTED (poll said stop), FAILED (the step size vanished or the
// state became non-finite).
struct Outcome {
  int status = DONE;
  double t = 0.0;  // time of the last accepted step
  State y;         // state there
  std::string message;
  long steps = 0;
  bool event = false;  // stopped at a root of the terminal event (t, y: there)
};

// No event (the default of integrate).
struct NoEvent {
  bool active() const { return false; }
  double operator()(double, const State&) { return 0.0; }
};

// The root of g in [a, b] with g(a) = ga >= 0 >= gb = g(b): Illinois regula falsi, every third iterate a bisection,
// until the bracket is 4 eps (relative) wide; returns its right end (g <= 0 there: the crossing has happened).
template <class G>
double locate_root(G&& g, double a, double ga, double b, double gb) {
  if (ga == 0.0) return a;
  if (gb == 0.0) return b;
  const double eps = std::numeric_limits<double>::epsilon();
  int side = 0;
  for (int it = 0; it < 300; ++it) {
    if (b - a <= 4.0 * eps * std::max(std::fabs(a), std::fabs(b))) break;
    double c = it % 3 == 2 ? 0.5 * (a + b) : (a * gb - b * ga) / (gb - ga);
    if (!(c > a && c < b)) c = 0.5 * (a + b);
    if (!(c > a && c < b)) break;  // no double strictly inside
    const double gc = g(c);
    if (gc == 0.0) return c;
    if (gc > 0.0) {
      a = c;
      ga = gc;
      if (side == 1) gb *= 0.5;
      side = 1;
    } else {
      b = c;
      gb = gc;
      if (side == -1) ga *= 0.5;
      side = -1;
    }
  }
  return b;
}

// One error-controlled run from (t0, y0) to t_end. `samples` are the requested output times (sorted), `next`
// the index of the first one still to emit (updated); observer(t, y) receives them in order. `breaks`: sorted
// times never stepped across.
template <class Stepper, class System, class Observer, class Poll, class Event = NoEvent>
Outcome run_dense(Stepper& stepper, System& system, const State& y0, double t0, double t_end,
                  const std::vector<double>& samples, size_t& next, const std::vector<double>& breaks,
                  double dt0, Observer&& observer, Poll&& poll, Event&& event = Event(), double unit = 1.0) {
  // (a step below 8 eps max(unit, |t|) fails as vanishing: unit 1 by default, 0 for the true spacing of doubles)
  Outcome out;
  out.t = t0;
  out.y = y0;
  const double eps = std::numeric_limits<double>::epsilon();
  auto reached = [&](double t, double target) { return target - t <= 8.0 * eps * std::max(1.0, std::fabs(target)); };
  size_t b = 0;
  while (b < breaks.size() && breaks[b] <= t0 + 8.0 * eps * std::max(1.0, std::fabs(t0))) ++b;
  // samples at the start time itself
  while (next < samples.size() && samples[next] <= t0) observer(samples[next++], y0);
  auto sys = [&system](const State& x, State& dxdt, double t) { system(x, dxdt, t); };
  double limit = std::min(b < breaks.size() ? breaks[b] : t_end, t_end);
  stepper.initialize(y0, t0, std::min(dt0, limit - t0));
  State y(y0.size());
  double g_prev = event.active() ? event(t0, y0) : 0.0;
  auto clock = std::chrono::steady_clock::now();
  while (!reached(stepper.current_time(), t_end)) {
    const double tc = stepper.current_time();
    if (reached(tc, limit)) {  // a breakpoint: restart there (the stepper's memory spans a kink otherwise)
      // every breakpoint within rounding of tc at once: windows meeting one double apart give two, and restarting
      // at each in turn took the 1-ulp gap between them as the next step size, which then failed as vanishing
      while (b < breaks.size() && reached(tc, breaks[b])) ++b;
      limit = std::min(b < breaks.size() ? breaks[b] : t_end, t_end);
      stepper.initialize(State(stepper.current_state()), tc, std::min(stepper.current_time_step(), limit - tc));
      continue;
    }
    if (tc + stepper.current_time_step() > limit)
      stepper.initialize(State(stepper.current_state()), tc, limit - tc);
    const double h = stepper.current_time_step();
    if (!(h > 8.0 * eps * std::max(unit, std::fabs(tc)))) {
      out.status = FAILED;
      out.message = "Required step size is less than spacing between numbers.";
      return out;
    }
    try {
      stepper.do_step(sys);
    } catch (const odeint::step_adjustment_error& e) {  // odeint: too many failed steps in a row
      out.status = FAILED;
      out.message = e.what();
      return out;
    }
    const double t1 = stepper.current_time();
    const State& x1 = stepper.current_state();
    for (double v : x1)
      if (!std::isfinite(v)) {
        out.status = FAILED;
        out.message = "the state became non-finite";
        return out;
      }
    ++out.steps;
    if (event.active()) {
      const double g1 = event(t1, x1);
      if (g_prev >= 0.0 && g1 <= 0.0) {  // a root inside the step: on the dense output
        const double t0s = stepper.previous_time();
        const double te = locate_root(
            [&](double tc) {
              stepper.calc_state(tc, y);
              return event(tc, y);
            },
            t0s, g_prev, t1, g1);
        while (next < samples.size() && samples[next] <= te) {
          const double ts = samples[next++];
          stepper.calc_state(ts, y);
          observer(ts, y);
        }
        if (te >= t1) y = x1;
        else stepper.calc_state(te, y);
        out.t = te;
        out.y = y;
        out.event = true;
        return out;
      }
      g_prev = g1;
    }
    while (next < samples.size() && (samples[next] <= t1 || (samples[next] <= t_end && reached(t1, t_end)))) {
      const double ts = samples[next++];
      if (ts >= t1) {
        observer(ts, x1);
      } else {
        stepper.calc_state(ts, y);
        observer(ts, y);
      }
    }
    out.t = t1;
    out.y = x1;
    if ((out.steps & 15) == 0) {
      const auto now = std::chrono::steady_clock::now();
      if (now - clock > std::chrono::milliseconds(50)) {
        clock = now;
        if (!poll(t1)) {
          out.status = INTERRUPTED;
          return out;
        }
      }
    }
  }
  return out;
}

// The accepted points of a multistep run since its last restart (the newest `capacity`), each with its state and
// its derivative, and the Hermite interpolant through them: the polynomial of degree 2 m - 1 that takes the m
// states and derivatives at the m times (Newton's divided differences on the doubled nodes), evaluated at times
// inside the newest interval. With m = 4 (degree 7) its error is O(h^8). Measured at 1,001-1,801 samples against
// dopri5 at rtol 1e-12 (Quasimoro's 90 s manoeuvre and LQR, the linkage's straight line and bump): the largest
// errors in q and nu are of the same size with Adams orders up to 8 and up to 10 (at most 1.8x apart).
class HermiteHistory {
 public:
  explicit HermiteHistory(size_t capacity) : cap_(capacity) {}
  void clear() { t_.clear(), x_.clear(), f_.clear(), fresh_ = false; }
  size_t size() const { return t_.size(); }
  double back() const { return t_.back(); }
  void push(double t, const State& x, const State& f) {
    if (t_.size() == cap_) {  // the oldest point's storage takes the newest (no allocation per step)
      std::rotate(t_.begin(), t_.begin() + 1, t_.end());
      std::rotate(x_.begin(), x_.begin() + 1, x_.end());
      std::rotate(f_.begin(), f_.begin() + 1, f_.end());
      t_.back() = t, x_.back() = x, f_.back() = f;
    } else {
      t_.push_back(t), x_.push_back(x), f_.push_back(f);
    }
    fresh_ = false;
  }
  // The interpolant at s into out (size of a state). The divided differences are computed once per accepted point
  // (several samples often fall inside one step) and kept until the next push or clear.
  void at(double s, State& out) {
    const size_t m = t_.size(), N = 2 * m, d = x_.back().size();
    if (!fresh_) {
      c_.resize(N);
      for (size_t j = 0; j < N; ++j) c_[j] = x_[j / 2];
      for (size_t k = 1; k < N; ++k)
        for (size_t j = N - 1; j >= k; --j) {
          if (k == 1 && j % 2 == 1) {  // a doubled node: the derivative there
            c_[j] = f_[j / 2];
            continue;
          }
          const double dz = t_[j / 2] - t_[(j - k) / 2];
          for (size_t i = 0; i < d; ++i) c_[j][i] = (c_[j][i] - c_[j - 1][i]) / dz;
        }
      fresh_ = true;
    }
    out = c_[N - 1];
    for (size_t j = N - 1; j-- > 0;) {
      const double w = s - t_[j / 2];
      for (size_t i = 0; i < d; ++i) out[i] = c_[j][i] + w * out[i];
    }
  }

 private:
  size_t cap_;
  bool fresh_ = false;  // c_ holds the divided differences of the current points
  std::vector<double> t_;
  std::vector<State> x_, f_, c_;
};

// A controlled multistep stepper (Adams) restarted (reset) at breakpoints and stepping exactly onto each of them
// and onto t_end (a step that would end within 1 % of a target is stretched onto it). With `interpolate` the
// samples between steps come from the Hermite interpolant of the accepted points (HermiteHistory: states and the
// derivatives the stepper evaluated there), so the steps do not depend on the sampling; without, the stepper
// steps exactly onto every sample too.
template <class Stepper, class System, class Observer, class Poll, class Event = NoEvent>
Outcome run_sampled(Stepper& stepper, System& system, const State& y0, double t0, double t_end,
                    const std::vector<double>& samples, size_t& next, const std::vector<double>& breaks,
                    double dt0, Observer&& observer, Poll&& poll, Event&& event = Event(), double rtol = 0.0,
                    double atol = 0.0, bool interpolate = true) {
  Outcome out;
  const double eps = std::numeric_limits<double>::epsilon();
  auto reached = [&](double t, double target) { return target - t <= 8.0 * eps * std::max(1.0, std::fabs(target)); };
  size_t b = 0;
  while (b < breaks.size() && breaks[b] <= t0) ++b;
  while (next < samples.size() && samples[next] <= t0) observer(samples[next++], y0);
  // the last evaluation (the stepper ends every accepted step with one at the accepted state) and the first one of
  // each restarted segment (at its start state)
  double call_t = 0.0, seg_t = t0;
  State call_x, call_f, seg_x = y0, seg_f;
  bool seg_open = true;
  auto sys = [&](const State& x, State& dxdt, double t) {
    system(x, dxdt, t);
    if (!interpolate) return;
    call_t = t, call_x = x, call_f = dxdt;
    if (seg_open && t == seg_t && x == seg_x) seg_f = dxdt, seg_open = false;
  };
  HermiteHistory history(4);
  State x = y0, x_prev, y_s(y0.size());
  // the derivative at the accepted state (t, x): the stepper's last evaluation, else one more
  auto accepted = [&](double t) {
    if (history.size() == 0) {
      if (seg_open) {
        seg_f.resize(seg_x.size());
        system(seg_x, seg_f, seg_t);
        seg_open = false;
      }
      history.push(seg_t, seg_x, seg_f);
    }
    if (!(call_x == x && std::fabs(call_t - t) <= 8.0 * eps * std::max(1.0, std::fabs(t)))) {
      call_f.resize(x.size());
      system(x, call_f, t);
    }
    history.push(t, x, call_f);
  };
  auto emit_to = [&](double t_to, bool at_end) {  // the samples up to t_to, on the interpolant (t_to: accepted)
    while (next < samples.size() && (samples[next] <= t_to || reached(t_to, samples[next]))) {
      const double ts = samples[next++];
      if (reached(ts, history.back()) || ts >= history.back()) {
        observer(ts, x);
      } else {
        history.at(ts, y_s);
        observer(ts, y_s);
      }
    }
    (void)at_end;
  };
  double t = t0, dt_nat = dt0;
  double g_prev = event.active() ? event(t0, y0) : 0.0;
  int rejected = 0;
  auto clock = std::chrono::steady_clock::now();
  while (!reached(t, t_end)) {
    double target = t_end;
    if (!interpolate && next < samples.size()) target = std::min(target, samples[next]);
    if (b < breaks.size()) target = std::min(target, breaks[b]);
    const bool truncated = t + 1.01 * dt_nat >= target;
    double dt = truncated ? target - t : dt_nat;
    if (!(dt > 8.0 * eps * std::max(1.0, std::fabs(t)))) {
      out.status = FAILED;
      out.message = "Required step size is less than spacing between numbers.";
      break;
    }
    const double t_prev = t;
    if (event.active()) x_prev = x;
    if (stepper.try_step(sys, x, t, dt) != odeint::success) {
      dt_nat = dt;
      if (++rejected > 1000) {
        out.status = FAILED;
        out.message = "1000 rejected steps in a row";
        break;
      }
      continue;
    }
    rejected = 0;
    dt_nat = truncated ? std::max(dt, dt_nat) : dt;
    ++out.steps;
    if (truncated) t = target;  // land exactly
    if (interpolate) accepted(t);
    bool restart = false;
    if (b < breaks.size() && reached(t, breaks[b])) {  // a kink: the multistep history must not span it
      while (b < breaks.size() && reached(t, breaks[b])) ++b;
      stepper.reset();
      dt_nat = std::min(dt_nat, dt0);
      restart = true;
    }
    if (event.active()) {
      const double g1 = event(t, x);
      if (g_prev >= 0.0 && g1 <= 0.0) {  // a root inside the step: re-integrate from its start (Dormand-Prince)
        State y;
        auto state_at = [&](double tc) {
          y = x_prev;
          auto rk = odeint::make_controlled(atol, rtol, odeint::runge_kutta_dopri5<State>());
          odeint::integrate_adaptive(rk, sys, y, t_prev, tc, std::min(dt, tc - t_prev));
        };
        const double te = locate_root(
            [&](double tc) {
              state_at(tc);
              return event(tc, y);
            },
            t_prev, g_prev, t, g1);
        if (interpolate) emit_to(te, false);
        if (reached(te, t)) {  // the root is the step's end
          while (next < samples.size() && reached(t, samples[next])) observer(samples[next++], x);
          y = x;
        } else {
          state_at(te);
        }
        out.t = te;
        out.y = y;
        out.event = true;
        return out;
      }
      g_prev = g1;
    }
    if (interpolate) emit_to(t, false);
    else
      while (next < samples.size() && reached(t, samples[next])) observer(samples[next++], x);
    if (restart && interpolate) {  // a new segment starts here
      history.clear();
      seg_t = t, seg_x = x, seg_open = true;
    }
    if ((out.steps & 15) == 0) {
      const auto now = std::chrono::steady_clock::now();
      if (now - clock > std::chrono::milliseconds(50)) {
        clock = now;
        if (!poll(t)) {
          out.status = INTERRUPTED;
          break;
        }
      }
    }
  }
  out.t = t;
  out.y = x;
  return out;
}

// Adams (default), Bulirsch-Stoer or Dormand-Prince 5(4) at tolerances rtol, atol on every component (odeint's
// error checkers, max norm: |err_i| <= atol + rtol (|y_i| + dt |dy_i/dt|) for adams and dopri5,
// atol + rtol |y_i| for bulirsch_stoer).
template <class System, class Observer, class Poll, class Event = NoEvent>
Outcome integrate(const std::string& method, System& system, const State& y0, double t0, double t_end,
                  const std::vector<double>& samples, size_t& next, const std::vector<double>& breaks, double rtol,
                  double atol, Observer&& observer, Poll&& poll, Event&& event = Event()) {
  const double dt0 = std::min(1e-3, 1e-3 * (t_end - t0));
  if (method == "bulirsch_stoer") {
    odeint::bulirsch_stoer_dense_out<State> stepper(atol, rtol, 1.0, 0.0);
    return run_dense(stepper, system, y0, t0, t_end, samples, next, breaks, dt0, observer, poll, event);
  }
  if (method == "dopri5") {
    auto stepper = odeint::make_dense_output(atol, rtol, odeint::runge_kutta_dopri5<State>());
    return run_dense(stepper, system, y0, t0, t_end, samples, next, breaks, dt0, observer, poll, event);
  }
  if (method == "adams") {
    // orders up to 10: against 8, 28 % fewer evaluations on Quasimoro's 90 s manoeuvre (9,420 against 13,090) and 7 to
    // 19 % fewer on the linkage's and Quasimoro's controller scenarios, at the same errors against a tight
    // reference; 12 gained nothing more (bench/bench.py controllers)
    using Adams = odeint::controlled_adams_bashforth_moulton<odeint::adaptive_adams_bashforth_moulton<10, State>>;
    Adams stepper(typename Adams::step_adjuster_type(atol, rtol, 1.0));
    return run_sampled(stepper, system, y0, t0, t_end, samples, next, breaks, dt0, observer, poll, event, rtol,
                       atol);
  }
  throw std::invalid_argument("unknown compiled integrator " + method + "; expected adams, bulirsch_stoer or dopri5");
}

}  // namespace robotdyn

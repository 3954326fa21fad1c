// robotdyn/_evaluator.hpp: the compiled evaluator, robotdyn._compiled.Evaluator (see robotdyn/fast/compiled.py): the
// reduced model evaluated in one compiled call.
//
// The Evaluator orchestrates the kernels under robotdyn/kernels/, one header per constraint kind or reduction step,
// each named like its Python reference and opening with its formulas (the same formulas in the same order of
// operations as the Python path):
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
//   kernels/joint_springs.hpp      reduction/joint_springs.py (springs and dampers on joints)
//   kernels/compliant_contact.hpp  contact/compliant_contact.py (wheels that fly and land: normal force laws)
//   kernels/compliant_rolling.hpp  contact/compliant_rolling.py (compliant wheels rolling while in contact)
//   kernels/lu_solve.hpp           LU substitutions and LAPACK's 1-norm condition estimate (used by the above)
// The rigid-body algorithms are Pinocchio's (header-only use of the installed Pinocchio 4), on a copy of the
// robot's Pinocchio model rebuilt joint by joint; tests/test_compiled*.py check every output against the Python
// path on every robot.
//
// The extension is two translation units of about equal compile time, compiled in parallel (setup.py: pybind11's
// ParallelCompile), each of them including this header:
//   _evaluator.cpp  the Evaluator's member functions: set-up, evaluation, right-hand sides, forces, samples, profile,
//                   and the simulation drivers (simulate, simulate_many: _integrator.hpp, _stiff_integrator.hpp)
//   _compiled.cpp   the Python module robotdyn._compiled: the bindings, and the derivative set (the kernels
//                   kernels/*_derivatives.hpp on the Evaluator)
// Every unit that includes this header instantiates the templates the kernels' inline functions use (most of a
// unit's compile time): a unit more costs that much again.
#pragma once

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
#include "kernels/compliant_contact.hpp"
#include "kernels/joint_springs.hpp"
#include "kernels/compliant_rolling.hpp"
#include "_torque_profile.hpp"
#include "_controller.hpp"
#include "kernels/reduced_dynamics_derivatives.hpp"  // the derivatives' workspace (derivs::Workspace)

#include <pybind11/pybind11.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <chrono>
#include <ctime>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace robotdyn {

// the derivatives of the other kinds (their kernels: _compiled.cpp's includes), friends of the Evaluator
template <class Ev>
struct ContactForcesDerivatives;  // kernels/contact_forces_derivatives.hpp
template <class Ev>
struct ProjectedPieces;  // kernels/operational_space_derivatives.hpp
template <class Ev>
struct OperationalDerivatives;  // (the same)
template <class Ev>
struct SlidingDerivatives;  // kernels/sliding_derivatives.hpp

namespace compiled {

namespace py = pybind11;
using namespace robotdyn::kernels;  // pin, the Eigen names, RowMat, Matrix6x and the kernels

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
            const std::vector<VectorXd>& inertias, const Vector3d& gravity);

  // ----------------------------------------------------------------------------------------------- set-up
  int add_frame(int joint, const MatrixXd& P);
  void set_terrain(int kind, const std::vector<double>& c);
  void add_wheel(int frame, const Vector3d& axis, double radius, int radius_index, const MatrixXd& D);
  void add_closure(int f1, int f2, const std::vector<int>& select);
  void add_coupling(int i, int j, double amplitude, double rate, double phase, double offset);
  void add_motor(int index, int joint, int reaction) { motors_.push_back(Motor{index, joint, reaction}); }
  // A slipping wheel: wheel index, its normal row, law code and parameters (see Slip), free directions (t1, t2).
  void add_slipping(int wheel, int normal_row, int law, double p0, double p1, const Eigen::Vector2d& free);
  int slipping() const { return static_cast<int>(slips_.size()); }
  // The rows used and the independent velocity indices (a selection of v).
  void set_selection(const std::vector<int>& rows, const std::vector<int>& independent,
                     const std::vector<int>& dependent);
  // Operational velocities: nu = J_o v with J_o the selected components of a frame's twist (local or world axes).
  void set_operational(const std::vector<int>& rows, int frame, const std::vector<int>& select, bool local);

  int nv() const { return nv_; }
  double condition() const { return cond_; }
  py::tuple slip_condition() const { return py::make_tuple(slip_.kappa1, slip_.kappa2); }
  int nrows() const { return static_cast<int>(holonomic_.size()); }
  int mobility() const {
    return operational_ ? static_cast<int>(op_select_.size()) : static_cast<int>(independent_.size());
  }

  // The full-coordinate model at q (for the self-check against the Python model): M, g and RNEA(q, v, a).
  py::tuple full(const VectorXd& q, const VectorXd& v, const VectorXd& a);

  // ------------------------------------------------------------------------------------------ evaluation
  // Configuration level: kinematics, the constraint rows A, residuals, the motors' B and the projection S.
  void configure(const Eigen::Ref<const VectorXd>& q);

  // After CRBA's kinematics at q_: the frames' placements and Jacobians, then every constraint's rows (A, residual)
  // and, with `motors`, the motors' columns B.
  void rows_pass(bool motors);

  // Every constraint's rows (A, residual: kernels/rolling_contact, loop_closure, joint_coupling) in the rows'
  // order, and with `motors` the motors' columns B (kernels/actuation), at the configured placements and frame
  // Jacobians.
  void constraint_rows(bool motors = true);

  // Every constraint's drift at v (the joint accelerations at zero joint acceleration in data_.a), then w, the
  // drift's acceleration (kernels/projection, kernels/operational_space).
  void drift_pass();

  // State level: v = S nu, the drift, w and the dynamics.
  void dynamics(const Eigen::Ref<const VectorXd>& nu);

  // RNEA(q_, v_, 0) into data_ (tau = C v): on CRBA's joint placements where configure left them at q_
  // (kernels/reduced_dynamics.hpp, bias_forces: the same bits), else Pinocchio's own pass.
  void bias_pass();

  py::tuple evaluate(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu);

  // The same without copies: the results stay in buffers read through the views M, h, g, B, S, w, v. Returns a
  // counter that changes whenever a buffer moved (then views taken before are stale).
  long compute(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu);
  const MatrixXd& Mr() const { return Mr_; }
  const VectorXd& hr() const { return hr_; }
  const VectorXd& gr() const { return gr_; }
  const MatrixXd& Br() const { return Br_; }
  const MatrixXd& S() const { return S_; }
  const VectorXd& w() const { return w_; }
  const VectorXd& v() const { return v_; }

  // d/dt of (q, nu): (S nu - alpha A_h^+ phi, M_r^-1 (B_r tau - h_r)).
  VectorXd rhs(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
               const Eigen::Ref<const VectorXd>& tau, double alpha);

  void rhs_into(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                const Eigen::Ref<const VectorXd>& tau, double alpha, Eigen::Ref<VectorXd> out);

  // ------------------------------------------------------------------------------------------ slipping wheels
  // d/dt of (q, nu, W) with slipping wheels (robotdyn/contact/sliding.py forward; kernels/sliding.hpp): the
  // accelerations and the normal loads from one linear system, W-dot the friction power. Leaves the normal loads
  // and their minimum (the lift-off event's value) and the Painleve test's condition numbers in slip_.
  void slip_rhs_into(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                     const Eigen::Ref<const VectorXd>& tau, double alpha, Eigen::Ref<VectorXd> out);

  // (d/dt (q, nu, W), normal loads (W,), slip velocities (W, 2), friction forces (W, 2)) at one state: the compiled
  // sliding.forward (tests compare it with the Python path).
  py::tuple slip_rhs(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
                     const Eigen::Ref<const VectorXd>& tau, double alpha);

  // ------------------------------------------------------------------------------------------ springs, compliant wheels
  // Applied forces that depend on the state (robotdyn/contact/applied_forces.py): joint springs and dampers
  // (kernels/joint_springs.hpp) and compliant wheels (kernels/compliant_contact.hpp). Their sum Q(q, v) enters
  // rhs_into as S^T Q; a simulation carries the friction and the damper work as two extra states; observe adds
  // their stored energy.
  void add_spring(int index, double stiffness, double damping, double rest);
  // A compliant wheel: its contact geometry as a wheel without rows (as add_wheel), its normal law (kind 0 linear,
  // 1 Hunt-Crossley; k, c, n) and its friction law (code -1 none, 0 regularised Coulomb, 1 linear tyre; p0, p1)
  // on the tangential directions D (0..2, 2), rows of coefficients of (t1, t2).
  void add_compliant_wheel(int frame, const Vector3d& axis, double radius, int radius_index, int kind, double k,
                           double c, double n, int code, double p0, double p1, const MatrixXd& D);
  bool applied() const { return !springs_.empty() || !contacts_.empty(); }
  // The compliant wheels' contact mode at the last applied_forces: bits 2i (wheel i pressed in), 2i + 1 (its normal
  // force positive); the stiff integrator's differences do not cross a switch of it.
  unsigned long long contact_mode() const;

  // Q (Qa_), the friction and damper powers and each contact's state, after configure(q) and v_ = S nu.
  void applied_forces();
  // The springs' and contacts' stored energy at the configured q [J].
  double stored_energy() const;
  // The compliant wheels' penetrations [m] at the state y (its q).
  // (An explicit step's last evaluation was at its end, dopri5's first-same-as-last: its configuration is reused.)
  void penetrations(const double* y, const py::object& rechoose, std::vector<double>& out);
  // (Q (nv,), friction power [W], damper power [W], per compliant wheel (delta, rate, F_t1, F_t2, f_n)) at (q, nu):
  // the compiled robotdyn.contact.applied_forces.applied (tests compare them).
  py::tuple applied_state(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu);

  // ------------------------------------------------------------------------------------------ rolling compliant wheels
  // Compliant wheels that roll while in contact (robotdyn/contact/compliant_rolling.py, kernels/compliant_rolling.hpp):
  // the run's contact set (set_rolling_mode, data of the run) says whose tangential rows are constraints; the event
  // min_i s_i pressing_i (s_i = +1 in the set: lift-off, -1 out of it: touch-down) ends the run at a switch, where
  // robotdyn/simulation/compiled_rolling.py applies the touch-down impact and starts the next run.
  // The last compliant wheel added rolls on its directions D (1..2, 2), rows of coefficients of (t1, t2).
  void add_rolling_rows(const MatrixXd& D);
  // The contact set: on[i] != 0 where rolling wheel i's rows hold.
  void set_rolling_mode(const std::vector<int>& on);
  bool rolling_active() const {
    return std::any_of(rolling_on_.begin(), rolling_on_.end(), [](char c) { return c != 0; });
  }
  // Rows G (m, nv) and drift Gdot v (m,) of the rolling wheels with on[i] set, after configure and dynamics.
  void rolling_rows_into(const std::vector<char>& on, MatrixXd& G, VectorXd& drift);
  // nudot into force_ (M_r nudot = force_ + G_r^T lambda, G_r nudot = -(G w + Gdot v) - beta G_r nu), llt_ factored.
  void rolling_solve(const Eigen::Ref<const VectorXd>& nu, double beta);
  // The event's value after applied_forces: min_i s_i pressing_i [m] (>= 0 until the contact set must change).
  double rolling_event() const;
  // (indicators (R,) [m], G (m, nv) of every rolling wheel in order, M_r, S, v) at (q, nu): the switch's data.
  py::tuple rolling_state(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu);

  // ------------------------------------------------------------------------------------------ feedback laws
  // A feedback law (robotdyn/_controller.hpp) replacing the torque profile in rhs_into (simulate), or none.
  void set_controller(const robotdyn::Controller* c);

  // The law's torques at (t, q, nu) (robotdyn/simulation/feedback.py's reference checks them).
  VectorXd control_torque(const robotdyn::Controller& c, double t, const Eigen::Ref<const VectorXd>& q,
                          const Eigen::Ref<const VectorXd>& nu);

  // Frame f (add_frame's index) at the evaluated state, for a linearising law's point tasks: its placement, its
  // LOCAL_WORLD_ALIGNED Jacobian and its classical acceleration at zero joint acceleration (dynamics' RNEA pass).
  robotdyn::FrameKinematics frame_kinematics(int f);

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
             const robotdyn::TorqueProfile& profile, const py::object& rechoose);

  // The lift-off event: the smallest normal load of the slipping wheels at (t, y) [N] (from the last evaluation
  // when it was at this very state).
  double lift_off(double t, const std::vector<double>& y, double alpha, const robotdyn::TorqueProfile& profile,
                  const py::object& rechoose);

  // ------------------------------------------------------------------------------------------ stepped from Python
  // One call per evaluation for an integrator driven from Python (robotdyn/simulation/cvode.py: SUNDIALS CVODE):
  // dy = d/dt y of simulate()'s ODE at (t, y), y = (q, nu[, works]) as in simulate, written into dy (no allocation);
  // the compliant wheels' penetrations [m] at y into `out`; the terminal event's value (lift_off) at (t, y).
  int state_size() const { return nv_ + mobility() + (!slips_.empty() ? 1 : applied() ? 2 : 0); }
  void deriv_into(double t, const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> dy, double alpha,
                  const robotdyn::TorqueProfile& profile, const py::object& rechoose);
  void depths_into(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> out, const py::object& rechoose);
  // A Jacobian's differences are being taken (on: the projection skips its span check, as for rosenbrock4: a
  // difference leaves the constraint manifold by ~1e-8)
  void set_differencing(bool on) { differencing_ = on; }
  double event_value(double t, const Eigen::Ref<const VectorXd>& y, double alpha,
                     const robotdyn::TorqueProfile& profile, const py::object& rechoose);

  // Total mechanical energy [J] (kinetic 1/2 v^T M v, potential -sum m_i g . c_i as Pinocchio's
  // computePotentialEnergy) and the largest holonomic residual at a state y = (q, nu).
  void observe(const double* y, double& energy, double& residual, const py::object& rechoose);

  // observe's energy and residual from the evaluator's M (CRBA's upper triangle), placements, v_ and residuals.
  void energy_residual(double& energy, double& residual);

  // A sample's energy and residual after a run that kept its row choice (no re-choice): observe's numbers, the same
  // bits, without what a sample does not use. The choice in force served, and passed its checks at, every
  // evaluation of the run, the evaluations on both sides of the sample included; so the configuration pass here
  // skips the gravity torques, the motors' columns B and the projection's condition and span checks
  // (projection.hpp's project_selection otherwise, step by step: S from A_d's LU factors; for operational
  // velocities operational_space.hpp's operational_inverse). Springs and compliant wheels (their stored energy) and
  // an S that is not finite (a zero pivot) go through observe.
  void sample(const double* y, double& energy, double& residual, const py::object& rechoose);

  // S of project_selection (kernels/projection.hpp) without its condition number and span checks (sample); false
  // where it is not finite.
  bool sample_selection();

  // ------------------------------------------------------------------------------------------ constraint forces
  // lambda of A^T lambda = e, e = M a + C v + g - B tau (robotdyn/contact_forces.py), on the rows the projection
  // uses: with the LU factors of A_d (the projection's own factorisation), A_d^T lambda_r = e_d; with operational
  // velocities by the projection's K^-1 (K = [A_r; J_o]). Rows outside the projection's choice (redundant ones) get zero: lambda is the
  // basic solution, equal to every other solution on the rows that rigid-body dynamics determine (the Python side
  // reports the others with the null space of A^T). After dynamics() (forward: nudot from the torques) or with a
  // given full acceleration a (forces_at).
  void lambda_from(const Eigen::Ref<const VectorXd>& tau);

  // Forward dynamics at (q, nu, tau) and the constraint forces, into buffers read through the views nudot, lam,
  // e, wheel_local (nw, 3) along (t1, t2, n), wheel_world, wheel_frames (nw, 9: t1, t2, n), contact_points; returns
  // a counter that changes whenever a buffer moved (as compute).
  long forces(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu,
              const Eigen::Ref<const VectorXd>& tau);

  // The same for given full velocities v and accelerations a (inverse dynamics): (lambda, e, wheel forces, A).
  py::tuple forces_at(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& v,
                      const Eigen::Ref<const VectorXd>& a, const Eigen::Ref<const VectorXd>& tau);

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
  void set_normal_stiffness(const Eigen::Ref<const VectorXd>& k);
  void set_rigid_limit(bool on) { rigid_.on = on; }

  // Per wheel: the force along (t1, t2, n), the same in world axes, the contact frame (rows t1, t2, n: (nw, 9),
  // row-major) and the contact point (nw, 3).
  void fill_wheel_forces() { wheel_force_table(wheels_, geo_, lambda_, wl_, ww_, wf_, wp_); }
  py::tuple wheel_forces();
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
  VectorXd model_vector() const;
  Eigen::Index model_vector_size() const;
  void set_model_vector(const double* x);
  void set_model_vector_py(const VectorXd& x);

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
                         double time_limit);

  // The start of a run: the holonomic residuals within 1e-6 (Robot.check_constraints' tolerance).
  void check_start(const double* y, const py::object& rechoose);

  // A whole simulation (robotdyn/compiled_simulation.py) from (t0, q0, nu0) to t_end with samples at `samples`
  // (those >= t0). Runs without the GIL; every ~50 ms it takes the GIL to check for signals (Ctrl-C: status
  // INTERRUPTED, the samples so far kept) and to call progress(t) (None: no call).
  py::dict simulate(const VectorXd& q0, const VectorXd& nu0, double t0, double t_end,
                    const std::vector<double>& samples, double rtol, double atol, double alpha,
                    const robotdyn::TorqueProfile& profile, const std::vector<double>& breaks,
                    const std::string& method, py::object progress, py::object rechoose);

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
  py::dict profile(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& nu, int repeat, double alpha);

  // Many states: stacked M_r (N, k, k), h (N, k), g (N, k), S (N, n, k), w (N, n), B_r (N, k, motors).
  py::tuple evaluate_many(const Eigen::Ref<const RowMat>& Q, const Eigen::Ref<const RowMat>& NU);

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

  void project();  // projection.py _build / operational_space.py project_operational, with the given rows

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

}  // namespace compiled
}  // namespace robotdyn

// robotdyn._compiled: the reduced model evaluated in one compiled call (see robotdyn/fast/compiled.py).
//
// This file is the Python module: the bindings of the torque profiles, the feedback laws and the Evaluator, and the
// Evaluator's derivative set (the kernels robotdyn/kernels/*_derivatives.hpp). The Evaluator itself, its class and
// the kernels it orchestrates, is robotdyn/_evaluator.hpp; its member functions, the simulation drivers included,
// are robotdyn/_evaluator.cpp: a translation unit of its own, compiled in parallel with this one.
#include "_evaluator.hpp"
#include "kernels/reduced_dynamics_derivatives.hpp"  // the derivatives (robotdyn/fast/compiled_derivatives.py)
#include "kernels/contact_forces_derivatives.hpp"  // (robotdyn/contact/compiled_force_derivatives.py)
#include "kernels/operational_space_derivatives.hpp"  // ... with operational-space velocities
#include "kernels/sliding_derivatives.hpp"            // ... with slipping wheels

#include <pybind11/pybind11.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace py = pybind11;
namespace kernels = robotdyn::kernels;
using namespace robotdyn::kernels;  // pin, the Eigen names, RowMat, Matrix6x and the kernels
using robotdyn::compiled::Evaluator;
using robotdyn::compiled::call_seconds;

namespace {

// The derivative set at one state by the evaluator's kind (slipping wheels, operational velocities, else the reduced
// dynamics): for the "derivatives" binding and the batched and timed bindings below.
robotdyn::derivs::Result derivative_set(Evaluator& ev, const VectorXd& q, const VectorXd& nu, const VectorXd& tau) {
  try {
    if (ev.slipping()) return robotdyn::SlidingDerivatives<Evaluator>::run(ev, q, nu, tau);
    if (robotdyn::OperationalDerivatives<Evaluator>::serves(ev))
      return robotdyn::OperationalDerivatives<Evaluator>::run(ev, q, nu, tau);
    return robotdyn::ReducedDerivatives<Evaluator>::run(ev, q, nu, tau);
  } catch (const std::domain_error& e) {
    throw Fallback(e.what());
  }
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
      .def("derivatives",
           [](Evaluator& ev, const VectorXd& q, const VectorXd& nu, const VectorXd& tau) {
             robotdyn::derivs::Result r = derivative_set(ev, q, nu, tau);
             // moved into the arrays (no copies)
             return py::make_tuple(std::move(r.nudot), std::move(r.dq), std::move(r.dnu), std::move(r.dtau),
                                   std::move(r.v), std::move(r.Vq), std::move(r.S), std::move(r.A));
           },
           "(nudot, dnudot/dq, dnudot/dnu, dnudot/dtau, v, dv/dq, S, A) at (q, nu, tau) "
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

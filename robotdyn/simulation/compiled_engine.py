"""A whole simulation in one compiled call: the fast path of :func:`robotdyn.simulation.engine.simulate`.

The same ODE as the scipy path,

.. math:: \\dot q = S(q)\\nu - \\alpha A_h^+\\phi(q),\\qquad M_r\\dot\\nu = B_r\\tau(t) - C_r\\nu - g_r,

with the same stabilisation (:mod:`robotdyn.reduction.pull_back`), is integrated in C++ (``robotdyn/_integrator.hpp``) by
a Boost.Odeint stepper on the robot's compiled model (:mod:`robotdyn.fast.compiled`), with the torques of a
:class:`~robotdyn.simulation.torque_profile.TorqueProfile` evaluated in C++ as well: no Python per step. The default
integrator is odeint's variable-step, variable-order Adams-Bashforth-Moulton (orders up to 10; the samples between its
steps come from the degree-7 Hermite interpolant of its last four accepted points, so that the sampling does not
shorten its steps): on Quasimoro's 90 s manoeuvre it needs 9,420 evaluations where scipy's DOP853 needs 23,000 and
Bulirsch-Stoer 33,000, at the same tolerances and an error of the same size as DOP853's (largest q error against a
dopri5 run at rtol 1e-12: 1.7e-10 against 1.4e-10; ``bench/bench.py``); Bulirsch-Stoer and Dormand-Prince 5(4),
both with dense output, are there on request (``method``). Energies and holonomic residuals are computed at the
samples in C++, after the run: where it kept its row choice by a lean configuration pass (``Evaluator.sample``: no
gravity torques, motor columns or projection checks, which every evaluation of the run has passed; the same bits as
the whole pass, about 1.3x cheaper: 13-14 us a sample on the linkage rover instead of 17-18). Neither integrator steps across a breakpoint of the torque profile (they restart there; the scipy
path does the same). The GIL is released during the run and taken every ~50 ms to
check for signals (Ctrl-C keeps the samples so far, as on the scipy path) and to report progress.

Where the compiled model's row choice stops working (:class:`robotdyn.fast.compiled.Fallback`) the C++ side asks the
Python path for a new one at that state (:func:`rechooser`), or gets its usual error, as the scipy path does.

Robots with slipping wheels (:mod:`robotdyn.contact.sliding`, laws :class:`~robotdyn.contact.friction.RegularisedCoulomb` and
:class:`~robotdyn.contact.friction.LinearTyre`, encoded by :meth:`~robotdyn.contact.friction.FrictionLaw.encode`) run here too: the
accelerations and normal loads come from the same coupled linear system as :func:`robotdyn.contact.sliding.forward`
(``Evaluator.slip_rhs``), the friction work is an extra state, a singular system raises the Python path's
Painleve error, and the terminal lift-off event (the smallest normal load of a slipping wheel crossing zero
downwards) is located on the stepper's dense output, or for Adams on a Dormand-Prince re-integration of the step,
with the Python path's ``stats["event"]`` (and ``stats["t_event"]``). Where the rows leave the wheels' normal loads
open (a rigid chassis on four wheels), the loads come with the accelerations and the friction from the rigid limit
of the wheels' normal compliance, as :func:`robotdyn.contact.sliding_rigid_limit.coupled` solves them
(``kernels/sliding_rigid_limit.hpp``; wheels it holds at zero load are no lift-off), and a refusal there is the Python
path's error at that state. Feedback laws run with slipping wheels too, and so do joint springs and dampers (a URDF's
wheel damping): their generalised force joins the system's right-hand side and the damper work is a second extra
state, as on the scipy path. Exact stick-slip stays on the Python path, as do slipping wheels beside compliant wheels,
and the stiff methods (``rosenbrock4``, ``cvode``) refuse slipping wheels.

Robots with joint springs or compliant wheels (:mod:`robotdyn.contact.applied_forces`) run on their own compiled model
(:func:`engine_model`, :mod:`robotdyn.fast.compiled_applied`): the evaluator adds :math:`S^T Q(q, v)` and carries the
friction and damper work as two extra states (``Trajectory.friction_work``, ``damper_work``), its energies count the
stored elastic energy. Robots with compliant wheels are integrated by a stepper with dense output, on which each
wheel's lift-off and touch-down are located (``stats["flight"]``, as :mod:`robotdyn.simulation.flight` reports them
on the scipy path's LSODA): :data:`COMPLIANT_DEFAULT` by default, :data:`STIFF` (Boost.Odeint's ``rosenbrock4``, a
finite-difference Jacobian: ``robotdyn/_stiff_integrator.hpp``) for stiff contacts, or :data:`CVODE` (SUNDIALS'
variable-order BDF driven from Python, one compiled call per evaluation, its events by CVODE's rootfinding:
:mod:`robotdyn.simulation.cvode`); springs alone run on the default Adams stepper. Compliant wheels that roll while in contact run segment by segment between their contact
switches (:mod:`robotdyn.simulation.compiled_rolling`). Slipping wheels beside compliant wheels, model-based
controllers on such robots, and :func:`robotdyn.simulation.many_runs.simulate_many`, stay on the Python path (refused
in one line).

The scipy path (DOP853) stays the reference; ``tests/test_compiled_simulation.py`` checks the compiled trajectories
against it to 1e-8 on every compiled robot.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from ..fast.compiled import Fallback
from ..fast.dispatch import compiled_model
from ..errors import NonFiniteError, RobotDynError
from ..reduction.pull_back import failure_note
from ..contact.sliding import slipping_wheels
from ..contact.stick_slip_wheel import stick_slip_wheels
from ..contact.applied_forces import has_applied
from ..contact.compliant_contact import compliant_wheels
from .flight import airborne
from .feedback import FeedbackLaw
from .torque_profile import Constant, TorqueProfile, as_profile
from .trajectory import Trajectory
from .start_checks import start_dynamics
from .cvode import missing as missing_cvode


METHODS = ("adams", "bulirsch_stoer", "dopri5", "rosenbrock4")
"""The compiled integrators (Boost.Odeint steppers); the first is the default, the last the stiff one."""
STIFF = "rosenbrock4"
"""The compiled stiff integrator: Boost.Odeint's Rosenbrock method of order 4 with its step-size controller and dense
output (``robotdyn/_stiff_integrator.hpp``; its Jacobian by finite differences, one evaluation per state component
and step), for stiff contacts: stiffnesses far above the default rule's 1 mm deflection, strong damping, long runs
at rest on the tyres."""
COMPLIANT_DEFAULT = "dopri5"
"""The compiled integrator for robots with compliant wheels unless another is asked for: Dormand-Prince 5(4) with
dense output, on which the wheels' flight phases are located (Adams has none: refused for them). Tyres of the default
rule (1 mm static deflection) oscillate at about sqrt(g / 1 mm) = 99 rad/s, which an explicit stepper resolves at
the tolerances it is run at: the compliant linkage rover over its bump at 25 rad/s, rtol 1e-8, took 6,068
evaluations with dopri5 against 65,734 with :data:`STIFF` (whose finite-difference Jacobian costs 41 evaluations a
step); the scipy path's LSODA (:data:`robotdyn.simulation.flight.STIFF_METHOD`) switches between Adams and BDF
itself."""
DENSE = ("dopri5", "bulirsch_stoer", "rosenbrock4")
"""The compiled integrators with dense output, which can locate compliant wheels' flight phases."""
CVODE = "cvode"
"""SUNDIALS CVODE's variable-order BDF on the compiled model (:mod:`robotdyn.simulation.cvode`), for robots with
compliant wheels or joint springs: its events by CVODE's rootfinding."""

DONE, INTERRUPTED, FAILED = 0, 1, 3
"""How a compiled run ended (``robotdyn/_integrator.hpp``, ``Status``)."""


def native_profile(profile: TorqueProfile):
    """The C++ object of a :class:`~robotdyn.simulation.torque_profile.TorqueProfile` (``robotdyn._compiled.TorqueProfile``).

    Args:
        profile: The :class:`~robotdyn.simulation.torque_profile.TorqueProfile`.

    Returns:
        The ``robotdyn._compiled.TorqueProfile`` holding the same terms.
    """
    from .._compiled import TorqueProfile as Native

    kinds, coefs, pars = profile.encode()
    return Native(profile.motors, kinds, [np.atleast_2d(c) for c in coefs],
                  [p.tolist() for p in pars])


def run(robot, fast, t_end: float, q0: np.ndarray, nu0: np.ndarray, profile: TorqueProfile, t_eval: np.ndarray,
        rtol: float, atol: float, stabilisation: float, method: str, progress=None, t0: float = 0.0,
        controller: FeedbackLaw | None = None) -> dict:
    """Integrate on the compiled model ``fast`` of ``robot``.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        fast: Its :class:`~robotdyn.fast.compiled.CompiledModel` (projection chosen).
        t_end: Final time [s].
        q0, nu0: Initial state (at time ``t0``).
        profile: Motor torques.
        t_eval: Output times (sorted, from t0 to t_end).
        rtol, atol: Tolerances of the stepper's error control (per component: :math:`atol + rtol |y_i|`).
        stabilisation: Gain [1/s] of the holonomic pull-back.
        method: One of :data:`METHODS`, or :data:`CVODE` (run by :func:`robotdyn.simulation.cvode.run`).
        progress: ``progress(t)`` called about every 50 ms (None: not called).
        t0: Start time [s] (the profile is evaluated at absolute times).
        controller: A :class:`~robotdyn.simulation.feedback.FeedbackLaw` evaluated in C++ instead of ``profile``
            (``robotdyn/_controller.hpp``; default ``None``: the profile's torques).

    Returns:
        ``t`` (N,), ``y`` (N, n + k), ``energy`` (N,) [J], ``residual`` (N,), ``nfev``, ``steps`` and
        ``interrupted`` (a message, or None).

    Raises:
        RobotDynError: The integration failed (its step size vanished or the state became non-finite), or the
            Python path's own error where the projection had to be re-chosen.
    """
    if method not in (*METHODS, CVODE):
        raise RobotDynError(f"unknown compiled integrator {method!r}; expected one of {', '.join(METHODS)}, {CVODE}")
    native = _zero_native(profile) if controller is not None else native_profile(profile)
    points = set(map(float, profile.breakpoints()))
    if controller is not None:
        points.update(map(float, controller.breakpoints()))
    breaks = sorted(b for b in points if t0 < b < t_end)
    n = robot.nq
    rechoose = rechooser(robot, fast)
    fast.ev.set_controller(None if controller is None else controller.native_controller(robot, fast))
    try:
        if method == CVODE:  # SUNDIALS' BDF driven from Python (robotdyn.simulation.cvode): its own result
            from .cvode import run as run_cvode

            return run_cvode(robot, fast, t_end, q0, nu0, native, breaks, t_eval, rtol, atol, stabilisation,
                             rechoose, progress, t0)
        out = fast.ev.simulate(q0, nu0, float(t0), float(t_end), np.asarray(t_eval, float), rtol, atol, stabilisation,
                               native, breaks, method, progress, rechoose)
    except Fallback as exc:  # the Python path's row choice did not serve the compiled model either
        raise stuck(robot, rechoose.last, float(fast.ev.last_t), str(exc)) from None
    finally:
        fast.ev.set_controller(None)
    status, t_stop = out["status"], float(out["t_stop"])
    if out["slip_error"] >= 0:  # the slipping wheels' contact problem: the Python path's error, timed as its own
        raise at_time(_slip_error(robot, fast, out, profile, controller), t_stop) from None
    interrupted = None
    if status == INTERRUPTED:
        reached = float(out["t"][-1]) if len(out["t"]) else t0
        interrupted = f"interrupted at t = {t_stop:.6g} s: samples up to t = {reached:.6g} s of {t_end:g} s"
    elif status == FAILED:
        message = out["message"]
        if "non-finite" in message:
            raise NonFiniteError(f"the state became non-finite at t = {t_stop:.6g} s (the dynamics blew up: massless "
                                 "bodies, a singular state, or torques beyond what double precision holds)")
        raise RobotDynError(f"integration failed at t = {t_stop:.4g} s: {message}"
                            + failure_note(robot, np.asarray(out["y_stop"])[:n], stabilisation))
    return {"t": out["t"], "y": out["y"], "energy": out["energy"], "residual": out["residual"],
            "nfev": int(out["nfev"]), "steps": int(out["steps"]), "interrupted": interrupted,
            "event": (t_stop, np.asarray(out["y_stop"])) if out["event"] else None, "flights": out["flights"]}


def _slip_error(robot, fast, out: dict, profile: TorqueProfile, controller) -> RobotDynError:
    """The Python path's error where a compiled run stopped on its slipping wheels' contact problem (``out``: the
    run's result, its ``slip_error`` kind, value and wheels; see ``kernels/sliding.hpp``'s SlipError)."""
    from ..contact.sliding import painleve_error, redundant_load_error

    if fast.loads_open:  # coupled's refusals (Painleve on a basis of the loads' subspace): its own words
        try:
            _python_refusal(robot, float(out["t_stop"]), np.asarray(out["y_stop"]), profile, controller)
        except RobotDynError as exc:
            return exc
    wheels = slipping_wheels(robot)
    if out["slip_error"] == 0:
        return painleve_error(wheels, float(out["slip_value"]))
    if out["slip_error"] == 2:  # the effective normal matrix is no P-matrix (robotdyn.contact.painleve)
        from ..contact.painleve import painleve_sign_error

        mu_p, mask = float(out["slip_value"]), int(out["slip_wheels"])
        return painleve_sign_error([w for i, w in enumerate(wheels) if mask >> i & 1],
                                   mu_p if np.isfinite(mu_p) else None,
                                   [w for i, w in enumerate(wheels) if not mask >> i & 1])
    return redundant_load_error(wheels[int(out["slip_value"])])


def _python_refusal(robot, t: float, y: np.ndarray, profile: TorqueProfile, controller) -> None:
    """Raise the Python path's error at the state y = (q, nu, ...) where a compiled run with open loads stopped on a
    refusal of the slipping wheels' contact problem (:func:`robotdyn.contact.sliding.forward`); return where that
    path solves the state (the caller then words the compiled verdict)."""
    from ..contact.sliding import forward
    from ..fast.dispatch import use_compiled

    n, k = robot.nq, robot.mobility
    q, nu = y[:n], y[n:n + k]
    tau = controller(t, q, nu) if controller is not None else profile(t)  # (run's controller: the bound law)
    with use_compiled(False):
        forward(robot, q, nu, np.asarray(tau, float))


_ZERO: dict[int, object] = {}
"""The C++ zero profile by number of motors (:func:`_zero_native`)."""


def _zero_native(profile: TorqueProfile):
    """:func:`native_profile` of ``profile``, built once per number of motors where it is zero torques
    (:class:`~robotdyn.simulation.torque_profile.Constant`): the profile of every run with a feedback law, which the
    C++ run reads only as const."""
    if type(profile) is not Constant or profile.values.any():
        return native_profile(profile)
    m = len(profile.values)
    if m not in _ZERO:
        _ZERO[m] = native_profile(Constant(np.zeros(m)))
    return _ZERO[m]


def as_data(torque):
    """``torque`` if it is a closed loop given as data (a :class:`~robotdyn.simulation.feedback.FeedbackLaw`, or a
    controller whose ``compiled_form()`` says so, e.g. a
    :class:`~robotdyn.simulation.control.LinearisingController` on profile references), else None.

    Args:
        torque: The torque law.

    Returns:
        ``torque`` itself where the compiled loop can run it, else ``None``.
    """
    form = getattr(torque, "compiled_form", None)
    return torque if callable(form) and callable(getattr(torque, "native_controller", None)) and form() else None


SCIPY_METHODS = ("DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA")
"""``scipy.integrate.solve_ivp``'s methods by name (the scipy engine's)."""


def check_method(method) -> None:
    """Refuse an integrator that no engine has: the one check of a method's name, for every door.

    Args:
        method: ``None`` (the engine's default), a compiled method (:data:`METHODS` or :data:`CVODE`) or a scipy
            method name (:data:`SCIPY_METHODS`).

    Raises:
        RobotDynError: One line naming the method and every name expected.
    """
    if method is not None and not (isinstance(method, str) and method in (*METHODS, CVODE, *SCIPY_METHODS)):
        raise RobotDynError(f"method = {method!r}; expected one of {', '.join((*METHODS, CVODE))} (compiled) or "
                            f"{', '.join(SCIPY_METHODS)} (scipy)")


def choose_engine(robot, torque, method: str | None, engine: str) -> bool:
    """Whether :func:`robotdyn.simulation.engine.simulate` runs on the compiled engine (see its docstring).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        torque: The torque law (``None``, a profile, or a Python callable).
        method: The integrator method asked for (``None``: the engine's default).
        engine: ``auto``, ``compiled`` or ``scipy``.

    Returns:
        True for the compiled engine, False for scipy's.

    Raises:
        RobotDynError: An unknown engine or method, or ``engine="compiled"`` where it cannot run (naming why).
    """
    if engine not in ("auto", "compiled", "scipy"):
        raise RobotDynError(f"engine = {engine!r}; expected auto, compiled or scipy")
    check_method(method)  # (simulate checked it first, with the other run options; engine_reason asks here)
    if method is not None and method in (*METHODS, CVODE):
        if engine == "scipy":
            raise RobotDynError(f"method {method!r} is a compiled integrator; the scipy engine has DOP853, RK45, "
                                "LSODA, ...")
        engine = "compiled"
    if engine == "scipy" or (method is not None and engine == "auto"):
        return False
    reason = None
    forced = has_applied(robot)  # joint springs, compliant wheels: robotdyn.fast.compiled_applied
    fast = None if stick_slip_wheels(robot) else engine_model(robot)
    if stick_slip_wheels(robot):
        reason = "stick-slip wheels (exact switching) are simulated on the Python path"
    elif compliant_wheels(robot) and slipping_wheels(robot):
        reason = "slipping wheels on a robot with compliant wheels are simulated on the Python path"
    elif fast is None:
        from ..fast.dispatch import enabled
        from ..fast.compiled import why_not

        reason = why_not(robot, applied=forced) if enabled() else (
            "the compiled fast path is turned off (ROBOTDYN_COMPILED=0 or use_compiled(False))")
    elif fast.slip_refusal is not None and not fast.slip_simulated:  # (open loads, springs: its rhs is compiled)
        reason = fast.slip_refusal
    elif method in (STIFF, CVODE) and slipping_wheels(robot):
        reason = (f"method {method!r} does not run slipping wheels (their lift-off event is located on an explicit "
                  f"stepper's dense output); expected one of {', '.join(m for m in METHODS if m != STIFF)}")
    elif method == CVODE and not forced:
        reason = (f"method {CVODE!r} (SUNDIALS' stiff BDF) runs robots with compliant wheels or joint springs; "
                  f"expected one of {', '.join(METHODS)} for rigid contacts")
    elif method == CVODE and missing_cvode() is not None:
        reason = missing_cvode()
    elif compliant_wheels(robot) and method not in (None, CVODE, *DENSE):
        reason = (f"compliant wheels' flight phases are located on a dense output: method {COMPLIANT_DEFAULT} "
                  f"(default), {STIFF} (stiff), {CVODE} or bulirsch_stoer, not {method}")
    elif forced and as_data(torque) is not None and not isinstance(torque, FeedbackLaw):
        reason = ("model-based controllers on robots with joint springs or compliant wheels are simulated on the "
                  "Python path")
    elif torque is not None and not isinstance(torque, TorqueProfile) and as_data(torque) is None:
        reason = ("the torques are a Python function; give a robotdyn.simulation.torque_profile.TorqueProfile (constant, sine, "
                  "table, polynomial) or a robotdyn.simulation.feedback.FeedbackLaw to run them compiled")
    if reason is not None and engine == "compiled":
        raise RobotDynError(f"engine = 'compiled' cannot run this simulation: {reason}")
    return reason is None


def engine_model(robot):
    """The compiled model a compiled simulation of ``robot`` runs on: with its joint springs and compliant wheels
    where it has any (:func:`robotdyn.fast.applied_model.applied_model`), else the robot's compiled model.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The :class:`~robotdyn.fast.compiled.CompiledModel`, or ``None`` where the compiled path cannot serve it.
    """
    if has_applied(robot):
        from ..fast.applied_model import applied_model

        return applied_model(robot)
    return compiled_model(robot)


def default_method(robot) -> str:
    """The compiled integrator where none is asked for: :data:`COMPLIANT_DEFAULT` for robots with compliant wheels,
    else the first of :data:`METHODS`.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        One of :data:`METHODS`.
    """
    return COMPLIANT_DEFAULT if compliant_wheels(robot) else METHODS[0]


def simulate_compiled(robot, t_end, q0, nu0, torque, n_out, rtol, atol, method, stabilisation, progress,
                       offsets, t0: float = 0.0, times=None) -> Trajectory:
    """:func:`robotdyn.simulation.engine.simulate` on the compiled engine (:func:`run`), after its checks: a
    :class:`~robotdyn.simulation.trajectory.Trajectory` with ``stats["engine"]``. ``progress`` is the run's reporter
    (:class:`robotdyn.simulation.progress.Progress`: prints, and raises past the run's time limit). The run
    starts at ``t0`` [s] and samples ``times`` (default ``n_out`` evenly spaced from t0 to t_end).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        t_end: Final time [s].
        q0: Initial coordinates (n,) [m, rad].
        nu0: Initial independent velocities (k,).
        torque: ``None``, a :class:`~robotdyn.simulation.torque_profile.TorqueProfile` or a
            :class:`~robotdyn.simulation.feedback.FeedbackLaw`.
        n_out: Number of evenly spaced output samples (unless ``times``).
        rtol: Relative error tolerance.
        atol: Absolute error tolerance per component.
        method: One of :data:`METHODS` (``None``: adams).
        stabilisation: Gain alpha [1/s] of the pull-back of the holonomic residuals (0: none).
        progress: The run's :class:`~robotdyn.simulation.progress.Progress` reporter.
        offsets: Holonomic residuals kept as constant offsets, by row label [m or rad]
            (:func:`robotdyn.reduction.pull_back.start_offsets`).
        t0: Start time [s].
        times: Output times [s] (increasing, t0 to t_end; default ``None``: ``n_out`` evenly spaced).

    Returns:
        The :class:`~robotdyn.simulation.trajectory.Trajectory` of the run.
    """

    law = torque.bound(robot) if isinstance(torque, FeedbackLaw) else as_data(torque)
    profile = Constant(np.zeros(len(robot.motors))) if law is not None else as_profile(torque, len(robot.motors))
    tau0 = law(t0, q0, nu0) if law is not None else profile(t0)
    start_dynamics(robot, t0, q0, nu0, tau0)  # regular where the run starts (the Python path's errors), no load pulling
    fast = engine_model(robot)
    if not fast.ready:  # (forward_dynamics chose the rows of the robot's own compiled model, not of this one)
        fast._choose(q0, nu0)
    start = time.perf_counter()
    t_eval = np.linspace(t0, t_end, n_out) if times is None else times
    out = run(robot, fast, t_end, q0, nu0, profile, t_eval, rtol, atol, stabilisation, method,
              progress if progress.needed else None, t0, law)
    wall = time.perf_counter() - start
    n = robot.nq
    stats = {"nfev": out["nfev"], "steps": out["steps"], "wall": wall, "method": method, "rtol": rtol,
             "engine": f"compiled ({method})"}
    if "jacobians" in out:  # CVODE: the difference-quotient Jacobians it formed (their evaluations are in nfev)
        stats["jacobians"] = out["jacobians"]
    if out["interrupted"]:
        stats["partial"] = out["interrupted"]
    k = robot.mobility
    if out["event"] is not None:  # a slipping wheel's load reached zero: the contact model ends there
        from ..contact.sliding import lift_off_message

        t_ev, y_ev = out["event"]
        tau_ev = law(t_ev, y_ev[:n], y_ev[n:n + k]) if law is not None else profile(t_ev)
        stats["event"] = lift_off_message(robot, t_ev, y_ev[:n], y_ev[n:n + k], tau_ev)
        stats["t_event"] = t_ev
        print(f"simulate: {stats['event']}", file=sys.stderr, flush=True)
    if offsets:
        stats["offsets"] = offsets
    y = out["y"].reshape(len(out["t"]), -1)
    wheels = compliant_wheels(robot)
    work = y[:, n + k] if (slipping_wheels(robot) or wheels) else None  # the friction work, an extra state
    if wheels:  # flight phases, as robotdyn.simulation.flight reports them on the scipy path
        reached = float(out["t"][-1]) if len(out["t"]) else t0
        stats["flight"] = sorted(({"t": float(t), "wheel": wheels[i].name,
                                   "event": "touch-down" if d > 0 else "lift-off"}
                                  for t, i, d in out["flights"] if t <= reached), key=lambda e: e["t"])
        stats["airborne"] = airborne(robot, wheels, q0)
    traj = Trajectory(out["t"], y[:, :n], y[:, n:n + k], out["energy"], out["residual"], list(robot.coordinates),
                      list(robot.velocity_names), stats, robot.units, work)
    if has_applied(robot):
        traj.damper_work = y[:, n + k + 1]  # the joint dampers' and the contacts' damping work
    return traj


def at_time(exc: RobotDynError, t: float) -> RobotDynError:
    """The same error (class and attributes) with the simulated time where it happened in front of its message.

    Args:
        exc: The error raised at that time.
        t: The simulated time [s] at which it happened.

    Returns:
        A shallow copy of ``exc`` whose message reads ``at t = ... s: <message>`` (``exc`` itself is unchanged).
    """
    import copy

    out = copy.copy(exc)
    advice = MOBILITY_DROP if t > 0 and getattr(exc, "mobility", None) is not None else ""
    out.args = (f"at t = {t:.6g} s: {exc}{advice}",)
    return out


MOBILITY_DROP = ("; the motion has left the configuration it started in, where some constraint rows were dependent (as "
                 "rolling wheels' sideways rows can be at one configuration only), and rigid rows cannot follow it "
                 "without an impulse; give those wheels a friction law so that their rows become forces (friction = "
                 "'linear' or 'coulomb', with slip = 'lateral' to slide only sideways), or keep the motion in that "
                 "configuration")
"""The end of the one-line error of a run whose mobility drops on the way (:func:`at_time`, :func:`stuck`)."""


def stuck(robot, state, t: float, reason: str) -> RobotDynError:
    """The one-line error where the compiled engine's projection stops working at time t even after the Python
    path re-chose its rows at ``state`` = (q, nu) (e.g. a steerable base leaving its parallel-wheel configuration,
    where the mobility changes): the Python path's own error there without its cached row choice (the scipy
    engine's error at that state), with the time; else a message naming the reason.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` being simulated (its cached row choice is cleared).
        state: ``(q, nu)``, natural coordinates (n,) [m, rad] and independent velocities (k,) [m/s, rad/s], where
            the Python path last re-chose its rows, or None if it never did.
        t: The simulated time [s] where the compiled engine stopped.
        reason: The compiled engine's own message, quoted when nothing better is known.

    Returns:
        The error to raise (not raised here): the Python path's error at ``state`` with the time in front, a
        :class:`~robotdyn.errors.SingularConstraintError` when the rows' rank no longer leaves the mobility, or
        else a :class:`~robotdyn.errors.RobotDynError` naming ``reason``.
    """
    from ..fast.dispatch import use_compiled

    if state is not None:
        robot._projection_hint = None  # decide afresh, as a first evaluation would
        try:
            with use_compiled(False):
                robot.reduced(*state)
        except RobotDynError as exc:
            return at_time(exc, t)
        # the Python path's rank decision still passes here; the rows' exact rank says what the compiled check saw
        from ..errors import SingularConstraintError

        A = robot.rows_at(state[0]).A
        rank = int(np.linalg.matrix_rank(A)) if A.size else 0
        independent = getattr(robot, "independent_indices", None)
        if independent is not None and getattr(robot, "operational", None) is None \
                and robot.nq - rank != len(independent):
            names = robot.velocity_labels  # the message of robotdyn.reduction.projection.project
            return SingularConstraintError(
                f"at t = {t:.6g} s: {len(independent)} independent velocities chosen "
                f"({', '.join(names[i] for i in independent)}) but the constraints leave {robot.nq - rank} "
                f"(n = {robot.nq}, rank A = {rank}); expected exactly the mobility" + (MOBILITY_DROP if t > 0 else ""))
    return RobotDynError(f"at t = {t:.6g} s: the projection cannot be continued ({reason}): the constraints changed "
                         "rank here (e.g. steerable wheels leaving a parallel configuration); expected a motion that "
                         "keeps the mobility, or start away from this configuration")


def rechooser(robot, fast=None):
    """The callback with which the C++ integrator asks the Python path for a new row choice at (q, nu), where the
    compiled one stops working: returns ``(rows, independent, dependent)`` of the Python projection there (and
    makes ``fast``, if given, use it), or raises the Python path's error (e.g. a singular configuration).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        fast: The robot's compiled model, told to use the new choice (default ``None``).

    Returns:
        The callback, a function of (q, nu) returning ``(rows, independent, dependent)`` as lists of int.
    """
    from ..fast.dispatch import use_compiled

    def rechoose(q: np.ndarray, nu: np.ndarray) -> tuple[list[int], list[int], list[int]]:
        rechoose.last = (np.array(q), np.array(nu))  # where the compiled model last needed the Python path
        with use_compiled(False):
            proj = robot.reduced(q, nu).projection
        if fast is not None:
            fast.select(proj)
        independent = getattr(proj, "independent", None)
        dependent = getattr(proj, "dependent", None)
        return ([int(r) for r in proj.rows], [] if independent is None else [int(i) for i in independent],
                [] if dependent is None else [int(i) for i in dependent])

    rechoose.last = None
    return rechoose


__all__ = ["run", "simulate_compiled", "choose_engine", "check_method", "engine_model", "default_method", "native_profile", "rechooser",
           "at_time", "METHODS", "STIFF", "COMPLIANT_DEFAULT", "DENSE", "CVODE"]

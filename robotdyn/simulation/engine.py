"""Forward simulation in minimal coordinates.

State: natural coordinates q (n) and independent velocities nu (k). The ODE is

.. math:: \\dot q = S(q)\\nu - \\alpha\\, A_h^+ \\phi(q),\\qquad M_r \\dot\\nu = B_r \\tau(t, q, \\nu) - C_r\\nu - g_r,

integrated either wholly in C++ (:mod:`robotdyn.simulation.compiled_engine`, where the robot is compiled and the torques
are a :class:`~robotdyn.simulation.torque_profile.TorqueProfile`) or by scipy's ``solve_ivp`` loop (the reference), whose
right-hand side is one call of the robot's compiled model (:mod:`robotdyn.fast.compiled`) where it serves the robot,
else the Python path. Velocity constraints hold exactly (v = S nu by construction); the position residuals
:math:`\\phi` of holonomic rows (loop closures, contacts on a sloped or curved terrain) are pulled back with the
stabilisation gain :math:`\\alpha` [1/s] (0 disables it, :mod:`robotdyn.reduction.pull_back`) and reported.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

import numpy as np

from ..fast.compiled import Fallback
from ..fast.dispatch import compiled_model
from .compiled_engine import as_data, at_time, choose_engine, default_method, simulate_compiled
from ..errors import ConstraintError, NonFiniteError, RobotDynError
from ..reduction.projection import solve
from ..reduction.pull_back import STABILISATION, failure_note, position_rate
from ..reduction.reduced_dynamics import velocity
from ..contact.sliding import forward as forward_sliding
from ..contact.sliding import contact_load, lift_off_message, slipping_wheels
from ..contact.stick_slip_wheel import stick_slip_wheels
from ..contact.compliant_contact import compliant_wheels
from ..contact.applied_forces import applied, has_applied
from .flight import STIFF_METHOD, airborne, flight_events, flight_phases
from .progress import Progress
from .run_options import check_run_options
from .start_checks import start_dynamics, start_offsets
from .feedback import FeedbackLaw
from .torque_profile import TorqueProfile, as_profile
from .trajectory import Trajectory

TorqueFunction = Callable[[float, np.ndarray, np.ndarray], np.ndarray]

MAX_SAMPLES = 5_000_000
"""Largest number of output samples of one simulation (memory: 8 bytes x (2n + 3) columns each)."""
MIN_DURATION = 1e-6
"""Shortest simulation [s] (below it the output times are not distinct in double precision)."""


def simulate(
    robot,
    t_end: float,
    q0,
    nu0,
    torque: TorqueFunction | None = None,
    n_out: int = 1001,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    method: str | None = None,
    stabilisation: float = STABILISATION,
    progress: bool = True,
    engine: str = "auto",
    time_limit: float | None = None,
    *,
    t0: float = 0.0,
    times=None,
    sink=None,
) -> Trajectory:
    """Integrate the reduced equations from (q0, nu0) over [t0, t_end] (t0 = 0 unless continuing a run).

    Two engines integrate the same ODE: the compiled one (:mod:`robotdyn.simulation.compiled_engine`: the whole run in
    C++, Boost.Odeint's adaptive Adams-Bashforth-Moulton by default) and scipy's (``solve_ivp``'s DOP853 loop, the
    reference, with a Python call per evaluation). Both restart at the breakpoints of a torque profile. ``engine="auto"`` takes the compiled one where the robot has a compiled
    model (:func:`robotdyn.fast.compiled.why_not`; slipping wheels with a compiled friction law included, exact
    stick-slip not), and the torques are ``None`` or a
    :class:`~robotdyn.simulation.torque_profile.TorqueProfile` (a Python callable needs the scipy engine); ``stats["engine"]``
    says which ran.

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        t_end: Final time [s] (> 0).
        q0: Initial natural coordinates (must satisfy the holonomic constraints).
        nu0: Initial independent velocities; with stick-slip wheels also the full velocities v (n,), where the
            independent ones cannot give them (e.g. a vehicle launched sliding whose wheels all stick at rest:
            no independent velocity); each wheel then starts sliding where its slip speed exceeds 1e-9 m/s.
        torque: Motor torques: a :class:`~robotdyn.simulation.torque_profile.TorqueProfile`, any callable ``tau(t, q, nu)``
            (scipy engine), or ``None`` for no actuation.
        n_out: Number of output samples.
        rtol, atol: Error tolerances (relative, absolute per component) of either engine.
        method: The integrator: a ``scipy.integrate.solve_ivp`` method (default DOP853) or one of
            :data:`robotdyn.simulation.compiled_engine.METHODS` (default adams; dopri5 for compliant wheels,
            rosenbrock4 for stiff ones) or ``"cvode"`` (SUNDIALS CVODE's BDF on the compiled model, for robots with
            compliant wheels or joint springs: :mod:`robotdyn.simulation.cvode`); it selects the engine too.
        stabilisation: Gain [1/s] pulling holonomic residuals back to zero (:mod:`robotdyn.reduction.pull_back`).
        progress: Print progress to stderr on long runs.
        engine: ``auto``, ``compiled`` (an error naming why where it cannot run) or ``scipy``.
        time_limit: Wall-clock limit of the run [s] (None: none): past it the run raises
            :class:`~robotdyn.errors.TimeLimitError` (checked at every evaluation on the Python paths, about every
            50 ms on the compiled engine), so that a stiff or blown-up run in a sweep cannot stall it.
        t0: Start time [s] of (q0, nu0); torques are evaluated at absolute times. A run from t0 > 0 continues an
            earlier one (:mod:`robotdyn.simulation.streaming`): q0 is not checked against the holonomic constraints
            (its residual is the earlier run's drift, which the pull-back keeps reducing).
        times: Output times [s] (sorted, from t0 to t_end) instead of ``n_out`` evenly spaced ones.
        sink: A :class:`robotdyn.simulation.streaming.CsvSink`: the run streams to its file in segments of
            ``sink.segment`` samples (memory bounded whatever the duration; any ``n_out`` >= 2) and returns a
            :class:`robotdyn.simulation.streaming.StreamResult` instead of a Trajectory (see
            :func:`robotdyn.simulation.streaming.stream`: the integrator restarts at each segment boundary).

    Returns:
        The :class:`~robotdyn.simulation.trajectory.Trajectory` (t [s], q, nu, energy [J], residual), or the
        :class:`~robotdyn.simulation.streaming.StreamResult` when ``sink`` is given.

    Example:
        >>> import robotdyn
        >>> from robotdyn.simulation.engine import simulate
        >>> from robotdyn.simulation.torque_profile import Constant
        >>> robot = robotdyn.load("quasimoro")
        >>> traj = simulate(robot, 1.0, robot.neutral(), [0.0, 0.0, 0.0], Constant([0.1, 0.1]), n_out=11,
        ...                 progress=False)
        >>> traj.q.shape, traj.nu.shape
        ((11, 6), (11, 3))
        >>> bool(abs(traj.energy[-1] - traj.energy[0]) > 0)  # the motors did work
        True
    """
    if sink is not None:
        from .streaming import stream

        return stream(robot, t_end, q0, nu0, torque, n_out, sink, rtol=rtol, atol=atol, method=method,
                      stabilisation=stabilisation, progress=progress, engine=engine, time_limit=time_limit)
    t0 = float(t0)
    if times is not None:
        times = np.asarray(times, float)
        if times.ndim != 1 or len(times) < 2 or times[0] != t0 or times[-1] != t_end or np.any(np.diff(times) <= 0):
            raise RobotDynError(f"times: expected increasing output times from t0 = {t0:g} s to t_end = {t_end:g} s")
        n_out = len(times)
    if not np.isfinite(t0) or t0 < 0:
        raise RobotDynError(f"t0 = {t0} s; expected a finite start time >= 0")
    if t0 and not t_end > t0:
        raise RobotDynError(f"t_end = {t_end} s; expected a final time after t0 = {t0:g} s")
    if not np.isfinite(t_end) or t_end <= 0:
        raise RobotDynError(f"t_end = {t_end} s; expected a positive duration")
    if t_end - t0 < MIN_DURATION:
        raise RobotDynError(f"t_end = {t_end:g} s; expected a duration of at least {MIN_DURATION:g} s")
    if time_limit is not None and not (np.isfinite(time_limit) and time_limit > 0):
        raise RobotDynError(f"time_limit = {time_limit} s; expected a positive wall-clock duration or None")
    n_out = check_run_options(n_out, rtol, atol, method)  # robotdyn.simulation.run_options
    if not 2 <= n_out <= MAX_SAMPLES:
        width = 2 * robot.nq + 3
        raise RobotDynError(f"{n_out:.3g} output samples for t_end = {t_end:g} s ({8 * width * n_out / 1e9:.3g} GB); "
                            f"expected 2 to {MAX_SAMPLES:,} samples: give a shorter duration or fewer samples")
    q0 = robot.check_q(q0)
    v0 = None  # stick-slip wheels: the full velocities v may be given instead (a vehicle held when every wheel sticks)
    if stick_slip_wheels(robot) and np.ndim(nu0) == 1 and len(nu0) == robot.nq != robot.mobility:
        from ..inputs import MAX_VELOCITY, as_vector

        v0 = as_vector(nu0, robot.nq, "v", robot.velocity_labels, MAX_VELOCITY)
        nu0 = np.zeros(robot.mobility)
    nu0 = robot.check_nu(nu0)
    if isinstance(torque, TorqueProfile):
        as_profile(torque, len(robot.motors))  # one line if it is for another number of motors
    if isinstance(torque, FeedbackLaw):
        torque = torque.bound(robot)  # one line if it does not fit the robot; its model is the robot simulated
    # a continuation starts where the earlier run ended (its drift is reported, not refused); the compiled rows
    # where they settle both checks (robotdyn.simulation.start_checks)
    offsets = start_offsets(robot, q0, stabilisation, check=not t0)
    stiff_slip_warning(robot, t_end - t0)
    compiled_engine = choose_engine(robot, torque, method, engine)  # robotdyn.simulation.compiled_engine
    if stick_slip_wheels(robot):  # exact switching: segment by segment
        if has_applied(robot):
            from ..reduction.joint_springs import urdf_damping_hint

            raise RobotDynError("stick-slip wheels with joint springs or compliant wheels are not simulated; expected "
                                "friction = 'coulomb' or 'linear' on the wheels of a robot with springs"
                                + urdf_damping_hint(getattr(robot, "springs", ())))
        if t0 or times is not None:
            raise RobotDynError("t0/times: stick-slip wheels are simulated from t = 0 on n_out samples only")
        from .stick_slip import simulate as simulate_stick_slip

        return _applied(simulate_stick_slip(robot, t_end, q0, robot.velocity(q0, nu0) if v0 is None else v0, torque,
                                            n_out, rtol, atol,
                                            method or "DOP853", stabilisation, progress, time_limit=time_limit),
                        robot, torque)
    if compiled_engine:
        fast_run = simulate_compiled
        if any(w.rolling for w in compliant_wheels(robot)):  # rolling compliant wheels: a switching compiled run
            from .compiled_rolling import simulate_rolling_compiled as fast_run
        return _applied(fast_run(robot, t_end, q0, nu0, torque, n_out, rtol, atol, method or default_method(robot),
                                 stabilisation, Progress(t_end, progress, time_limit), offsets, t0, times),
                        robot, torque)
    compliant = compliant_wheels(robot)
    if any(w.rolling for w in compliant):  # compliant wheels rolling while in contact: a hybrid run
        from .compliant_rolling import simulate_rolling

        if slipping_wheels(robot):
            raise RobotDynError("compliant wheels that roll (friction = 'rolling') with rigid slipping wheels are not "
                                "simulated; expected contact = 'compliant' on the slipping wheels too")
        return _applied(simulate_rolling(robot, t_end, q0, nu0, torque, np.linspace(t0, t_end, n_out) if times is None
                                         else times, rtol, atol, method, stabilisation,
                                         Progress(t_end, progress, time_limit), t0), robot, torque)
    method = method or (STIFF_METHOD if compliant else "DOP853")
    n = robot.nq
    zero_tau = np.zeros(len(robot.motors))
    report = Progress(t_end, progress, time_limit)

    from scipy.integrate import solve_ivp

    slipping = slipping_wheels(robot)
    forced = has_applied(robot)  # joint springs, compliant wheels (robotdyn.contact.applied_forces)
    works = bool(slipping) or forced  # y[n + k:] = (friction work, damper work)
    # friction forces are added on the Python path; joint springs and dampers (forced) add two work states, which
    # the compiled rhs does not carry: robot.reduced below is still the compiled reduced model
    fast = None if slipping or forced else compiled_model(robot)
    k = robot.mobility

    # the dynamics must be regular where the run starts (a positive-definite mass matrix: robotdyn.reduction.reduced_dynamics.solve_mass),
    # and no slipping wheel may pull the ground there (its lift-off event only finds a downward crossing)
    start_dynamics(robot, t0, q0, nu0, zero_tau if torque is None else np.asarray(torque(t0, q0, nu0), float))

    def finite(t: float, y: np.ndarray) -> None:  # on the Python paths only: the compiled one stays lean
        if not np.isfinite(y).all():
            raise NonFiniteError(f"the state became non-finite at t = {t:.6g} s (the dynamics blew up: massless "
                                 "bodies, a singular state, or torques beyond what double precision holds)")

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        q, nu = y[:n], y[n:n + k]
        tau = zero_tau if torque is None else np.asarray(torque(t, q, nu), float)
        if slipping:  # normal loads and friction solved with the accelerations; y[-1] is the friction work
            finite(t, y)
            st = forward_sliding(robot, q, nu, tau)
            report(t)
            return np.concatenate([position_rate(st.reduced, stabilisation), st.nudot, [st.power, st.damper_power]])
        if fast is not None:
            try:  # the whole right-hand side in one compiled call (robotdyn.fast.compiled)
                out = fast.rhs(q, nu, tau, stabilisation)
                report(t)
                return out
            except Fallback:
                pass
        finite(t, y)
        red = robot.reduced(q, nu)
        if forced:
            app = applied(robot, q, red.v)
            nudot = solve(red.M, red.B @ tau - red.h + red.S.T @ app.Q)
            report(t)
            return np.concatenate([position_rate(red, stabilisation), nudot, [app.friction_power, app.damper_power]])
        nudot = solve(red.M, red.B @ tau - red.h)  # numpy.linalg.solve's LAPACK call, without its overhead
        report(t)
        return np.concatenate([position_rate(red, stabilisation), nudot])

    events = None
    if slipping:
        def lift_off(t: float, y: np.ndarray) -> float:  # the smallest normal load of a slipping wheel [N]
            q, nu = y[:n], y[n:n + k]
            tau = zero_tau if torque is None else np.asarray(torque(t, q, nu), float)
            return contact_load(robot, forward_sliding(robot, q, nu, tau))

        lift_off.terminal, lift_off.direction = True, -1.0
        events = [lift_off]
    flights = flight_events(robot, compliant, n)  # compliant wheels: lift-off and touch-down, recorded
    if flights:
        events = (events or []) + [e for e, _, _ in flights]
    t_eval = np.linspace(t0, t_end, n_out) if times is None else times
    start = time.perf_counter()
    y0 = np.concatenate([q0, nu0, [0.0, 0.0] if works else []])
    interrupted = None
    rhs = _timed(rhs)
    if events is None:
        data = isinstance(torque, (TorqueProfile, FeedbackLaw)) or as_data(torque) is not None
        breaks = torque.breakpoints() if data else ()
        sol, interrupted = _integrate(rhs, t_end, y0, method, t_eval, rtol, atol, breaks, t0)
    else:
        sol = solve_ivp(rhs, (t0, t_end), y0, method=method, t_eval=t_eval, rtol=rtol, atol=atol, events=events)
    wall = time.perf_counter() - start
    if not sol.success:
        raise RobotDynError(f"integration failed at t = {sol.t[-1]:.4g} s: {sol.message}"
                            + failure_note(robot, sol.y[:n, -1], stabilisation))
    stats_event = None
    if slipping and sol.status == 1 and len(sol.t_events[0]):  # a slipping wheel's load reached zero: the contact model ends there
        t_ev, y_ev = sol.t_events[0][0], sol.y_events[0][0]
        stats_event = lift_off_message(robot, t_ev, y_ev[:n], y_ev[n:n + k], zero_tau if torque is None else
                                       np.asarray(torque(t_ev, y_ev[:n], y_ev[n:n + k]), float))
        print(f"simulate: {stats_event}", file=sys.stderr, flush=True)
    q, nu = sol.y[:n].T, sol.y[n:n + k].T
    energy = np.empty(len(sol.t))
    residual = np.zeros(len(sol.t))
    times = sol.t
    try:
        for i in range(len(sol.t)):
            v, res, holonomic = _velocity(robot, fast, q[i], nu[i])
            energy[i] = robot.energy(q[i], v)
            if holonomic.any():
                residual[i] = np.max(np.abs(res[holonomic]))
    except KeyboardInterrupt:  # keep the samples whose energy and residual are known
        times, q, nu, energy, residual = sol.t[:i], q[:i], nu[:i], energy[:i], residual[:i]
        interrupted = (f"interrupted after the integration, while computing energies: samples up to t = "
                       f"{times[-1] if i else 0.0:.6g} s of {t_end:g} s")
    stats = {"nfev": int(sol.nfev), "wall": wall, "method": method, "rtol": rtol, "engine": f"scipy ({method})"}
    if interrupted is not None:
        stats["partial"] = interrupted
    if stats_event:
        stats["event"] = stats_event
        stats["t_event"] = float(sol.t_events[0][0])
    if offsets:
        stats["offsets"] = offsets
    if flights:
        stats["flight"] = flight_phases(flights, sol.t_events[len(events) - len(flights):], times[-1])
        stats["airborne"] = airborne(robot, compliant, q0)
    traj = Trajectory(times, q, nu, energy, residual, list(robot.coordinates), list(robot.velocity_names), stats,
                      robot.units, sol.y[n + k][: len(times)] if (slipping or compliant) else None, robot, torque)
    if forced:
        traj.damper_work = sol.y[n + k + 1][: len(times)]
    return traj


MAX_STEPS = 1e8
"""Integration steps beyond which :func:`stiff_slip_warning` warns (hours of wall time on either engine)."""


def stiff_slip_warning(robot, duration: float) -> None:
    """Warn (:class:`~robotdyn.errors.RobotDynWarning`) where a slipping wheel's friction law is so stiff that the
    run needs more than :data:`MAX_STEPS` steps. Near zero slip a law's force per unit load grows as :math:`k s`
    (:class:`~robotdyn.contact.friction.LinearTyre`: k its stiffness [s/m];
    :class:`~robotdyn.contact.friction.RegularisedCoulomb`: :math:`k = \\mu / v_s`), so a wheel carrying its share
    m of the weight (load m g) relaxes its slip at the rate :math:`k g` [1/s] at least (its own spin inertia only
    makes the mode faster). An explicit (or Adams) stepper needs steps of about :math:`1/(k g)`: a run of T seconds
    at least :math:`k g T` of them (e.g. k = 1e12 s/m: 1e13 steps a second, a run that never ends).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (its slipping wheels' friction laws and its gravity [m/s^2]).
        duration: The simulated duration T [s] of the run.
    """
    import warnings

    from ..errors import RobotDynWarning

    wheels = slipping_wheels(robot)
    if not wheels:  # (the usual case: nothing to compute)
        return
    g = float(np.linalg.norm(robot.model.gravity.linear))
    stiff = {}
    for wheel in wheels:
        law = getattr(wheel, "law", None)
        k = getattr(law, "stiffness", None)
        if k is None and getattr(law, "slip_velocity", None):
            k = law.mu / law.slip_velocity
        if k and k * g * duration > MAX_STEPS:
            stiff[wheel.name] = k
    if stiff:
        k = max(stiff.values())
        warnings.warn(RobotDynWarning(
            f"wheel(s) {', '.join(stiff)}: a friction law's slope up to k = {k:.3g} s/m relaxes slip at k g = "
            f"{k * g:.3g} 1/s, so a run of {duration:g} s needs at least {k * g * duration:.2g} integration steps "
            f"and will not end in a useful time (simulate --time-limit bounds it); expected k <= "
            f"{MAX_STEPS / (g * duration):.3g} s/m for this duration (a lower stiffness, a larger slip_velocity) or "
            "friction = 'rolling'"), stacklevel=3)


def _timed(rhs):
    """``rhs`` whose constraint errors (e.g. a singular configuration reached) name the simulated time, as the
    compiled engine's do (:func:`robotdyn.simulation.compiled_engine.at_time`)."""
    def timed(t: float, y: np.ndarray) -> np.ndarray:
        try:
            return rhs(t, y)
        except ConstraintError as exc:
            raise at_time(exc, t) from None

    return timed


def _applied(traj: Trajectory, robot, torque) -> Trajectory:
    """The trajectory with the robot and the torque law it was simulated with (:attr:`Trajectory.robot`)."""
    traj.robot, traj.torque = robot, torque
    return traj


def _integrate(rhs, t_end: float, y0: np.ndarray, method: str, t_eval: np.ndarray, rtol: float, atol: float,
               breaks=(), t0: float = 0.0):
    """scipy's ``solve_ivp`` loop (the same solver, steps and dense output at ``t_eval``, so the same numbers),
    written out so that an interruption (Ctrl-C, SIGTERM) keeps what was computed: returns the solution object
    and, if interrupted, a message saying up to which time the samples reach. The solver is restarted at each of
    ``breaks`` inside (t0, t_end) (the kinks of a torque profile), so that no step spans one."""
    from types import SimpleNamespace

    from scipy.integrate._ivp.ivp import METHODS as SCIPY

    bounds = [t0, *sorted(float(b) for b in breaks if t0 < b < t_end), t_end]
    ts, ys, i, status, message, interrupted, nfev = [], [], 0, None, "", None, 0
    y, solver = y0, None
    try:
        for a, b in zip(bounds[:-1], bounds[1:]):
            if solver is not None:
                nfev += solver.nfev
            solver = SCIPY[method](rhs, a, y, b, rtol=rtol, atol=atol)
            status = None
            while status is None:
                message = solver.step()
                if solver.status == "finished":
                    status = 0
                elif solver.status == "failed":
                    status = -1
                    break
                j = np.searchsorted(t_eval, solver.t, side="right")
                if j > i:
                    dense = solver.dense_output()
                    ts.append(t_eval[i:j])
                    ys.append(np.atleast_2d(dense(t_eval[i:j])).reshape(len(y0), j - i))
                    i = j
            if status == -1:
                break
            y = solver.y
    except KeyboardInterrupt:
        status = 0
        del ts[len(ys):], ys[len(ts):]  # the signal may fall between the two appends
        reached = float(ts[-1][-1]) if ts else t0
        now = solver.t if solver is not None else t0
        interrupted = f"interrupted at t = {now:.6g} s: samples up to t = {reached:.6g} s of {t_end:g} s"
    nfev += solver.nfev if solver is not None else 0
    t = np.concatenate(ts) if ts else np.zeros(0)
    y = np.hstack(ys) if ys else np.zeros((len(y0), 0))
    if status == -1:
        t, y = np.append(t, solver.t), np.column_stack([y, solver.y]) if y.size else solver.y[:, None]
    return SimpleNamespace(t=t, y=y, success=status >= 0, message=message or "", nfev=nfev,
                           status=status), interrupted


def _velocity(robot, fast, q: np.ndarray, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """v = S nu, the constraint residuals and which rows are holonomic: from the compiled model when it serves
    the robot, else from the Python path's kinematics (without dynamics)."""
    if fast is not None:
        try:
            out = fast.evaluate(q, nu)
            return out[6], out[8], fast.holonomic
        except Fallback:
            pass
    v, rows = velocity(robot, q, nu)
    return v, rows.residual, rows.holonomic


def power(robot, traj: Trajectory, torque: TorqueFunction | None) -> np.ndarray:
    """Motor power :math:`\\tau^T B_r^T \\nu` [W] along a trajectory (dE/dt must equal it without friction).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` simulated.
        traj: Its :class:`~robotdyn.simulation.trajectory.Trajectory`.
        torque: The torque law ``tau(t, q, nu)`` it was simulated with (``None``: unactuated, zero power).

    Returns:
        The power at each sample (N,) [W].
    """
    out = np.zeros(len(traj.t))
    if torque is None:
        return out
    for i, t in enumerate(traj.t):
        red = robot.reduced(traj.q[i], traj.nu[i])
        out[i] = np.asarray(torque(t, traj.q[i], traj.nu[i]), float) @ red.B.T @ traj.nu[i]
    return out


__all__ = ["simulate", "power", "Trajectory"]

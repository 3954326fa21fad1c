"""Exact stick-slip: wheels that roll without slipping while their contact force lies inside the friction cone
and slide under Coulomb friction when it would leave it, switched by events of the integrator (no regularisation).

A :class:`~robotdyn.contact.stick_slip_wheel.StickSlipWheel` is in one of two phases:

- **stick**: the three rolling rows (longitudinal, lateral, normal) are constraints; its contact force
  :math:`(\\lambda_t, \\lambda_n)` comes from :mod:`robotdyn.contact.contact_forces`. Event: :math:`\\mu\\lambda_n -
  \\|\\lambda_t\\| = 0` (decreasing) switches it to sliding, with the slip direction
  :math:`\\hat s_0 = -\\lambda_t/\\|\\lambda_t\\|` (the friction force is continuous at the switch: the motion starts
  opposite to the force the ground was exerting).
- **slide**: only the normal row is a constraint; the friction force is Coulomb's :math:`-\\mu f_n \\hat s` with
  :math:`\\hat s = s/\\|s\\|` (:math:`\\hat s_0` while :math:`\\|s\\|` is below 1e-12 m/s), the normal load solved
  together with the accelerations (:func:`robotdyn.contact.sliding.forward`). Event: :math:`s\\cdot\\hat s_0 = 0`
  (decreasing) tries sticking: the wheel sticks if the sticking solution's force lies inside the cone, else it
  keeps sliding in the direction of that force (the concepts page ``docs/concepts.md``).

On a statically indeterminate chassis (a rigid car or skid steer on four wheels) the normal loads are the rigid
limit of the wheels' normal compliance (with sliding wheels, from the coupled solve of accelerations, loads and
friction), and sticking wheels whose tangential forces stay open are decided together: they stick while some
admissible split keeps each in its cone (:mod:`robotdyn.contact.sticking_cone`, one event for the group).

Lift-off (a normal load reaching zero, decreasing) stops the run: the rigid normal row would have to pull. The
message names the wheel, time and load and the TOML key that lets a wheel fly and land
(:func:`robotdyn.contact.stick_slip_wheel.unloaded_message`).
The independent velocities change with the phases, so :func:`simulate` integrates segment by segment and reports
the full velocities v; the projection is rebuilt at every switch.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from ..contact.compliance import weight
from ..contact.contact_forces import constraint_forces
from ..errors import RobotDynError
from ..reduction.pull_back import STABILISATION
from ..contact.sliding import forward as forward_sliding
from ..contact.sliding import sliding_now
from ..contact.sliding import tangential as slip
from ..contact.stick_slip_wheel import StickSlipWheel, configure, holding_phases, unloaded_message
from ..contact.stick_slip_traction import phase_table, recorded_phases
from ..contact.sticking_cone import check as cone_check
from ..reduction.pull_back import position_rate
from .progress import Progress
from .trajectory import Trajectory

def _configure(robot) -> None:
    """Choose the independent velocities for the wheels' current phases at ``robot._stick_slip_q``."""
    configure(robot, robot._stick_slip_q)


def _phases(robot) -> list[StickSlipWheel]:
    return [c for c in robot.constraints if isinstance(c, StickSlipWheel)]


def _forces(robot, q, nu, tau):
    return constraint_forces(robot, q, nu, tau=tau)


@holding_phases
def simulate(robot, t_end: float, q0, v0, torque=None, n_out: int = 1001, rtol: float = 1e-10,
             atol: float = 1e-12, method: str = "DOP853", stabilisation: float = STABILISATION,
             progress: bool = True, max_switches: int = 10_000, time_limit: float | None = None):
    """Integrate a robot with stick-slip wheels over [0, t_end] from (q0, v0), switching phases exactly.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` with :class:`StickSlipWheel` constraints.
        t_end: Duration [s] (> 0).
        q0: Initial natural coordinates (n,) [m, rad].
        v0: Initial full velocities (n,) [m/s, rad/s] (each wheel starts sliding where its slip speed exceeds
            1e-9 m/s, else sticking; a sticking wheel outside its cone starts sliding).
        torque: Motor torques ``tau(t, q, nu)`` (None: unactuated); nu are the current phase's independent
            velocities, so torque laws should use q (or the returned full velocities) only.
        max_switches: Bound on the number of phase switches (Zeno behaviour stops the run with a message).
        time_limit: Wall-clock limit [s] (None: none), as in :func:`robotdyn.simulation.engine.simulate`.
        n_out: Number of output samples.
        rtol: Relative error tolerance of the integrator.
        atol: Absolute error tolerance per component.
        method: The ``scipy.integrate.solve_ivp`` method.
        stabilisation: Gain alpha [1/s] of the pull-back of the holonomic residuals (0: none).
        progress: Print progress to stderr on long runs.

    Returns:
        A :class:`~robotdyn.simulation.trajectory.Trajectory` whose velocity columns are the full velocities v (named
        ``<coordinate>_dot``), with ``friction_work``, ``stats["switches"]`` (time, wheel, phase), ``stats["phases"]``
        (each sample's phases: :func:`robotdyn.contact.stick_slip_traction.phase_table`, from which
        :func:`robotdyn.contact.traction.traction` reports the run's loads and friction) and, where the run stopped
        early, ``stats["event"]`` (and ``stats["lift_off"]``: time, wheel and load where a wheel unloaded).
    """
    from scipy.integrate import solve_ivp


    if not np.isfinite(t_end) or t_end <= 0:
        raise RobotDynError(f"t_end = {t_end} s; expected a positive duration")
    wheels = _phases(robot)
    q = robot.check_q(q0)
    v = np.asarray(v0, float)
    if v.shape != (robot.nq,) or not np.all(np.isfinite(v)):
        raise RobotDynError(f"v0 has shape {v.shape}; expected {robot.nq} finite full velocities")
    robot.check_constraints(q)
    zero_tau = np.zeros(len(robot.motors))
    n = robot.nq
    kin = _kin(robot, q, v)
    for w in wheels:
        s = slip(w, kin)[1]
        w.set_phase("slide", s) if np.linalg.norm(s) > 1e-9 else w.set_phase("stick")
    grid = np.linspace(0.0, t_end, n_out)
    out_t, out_q, out_v, out_w, out_p = [], [], [], [], []  # out_p: each sample's phases (recorded_phases)
    switches, stop, lift, work, t = [], None, None, 0.0, 0.0
    start = time.perf_counter()
    nfev = 0
    last_report = start
    limit = Progress(t_end, False, time_limit)  # raises past the time limit (the reports are printed below)
    while True:
        robot._stick_slip_q = q
        _configure(robot)
        nu = v[robot.independent_indices]
        tau_at = (lambda tt, qq, nn: zero_tau) if torque is None else \
            (lambda tt, qq, nn: np.asarray(torque(tt, qq, nn), float))
        # a sticking wheel whose force is outside the cone starts sliding at once (opposite to that force)
        forces = _forces(robot, q, nu, tau_at(t, q, nu))
        if len(nu) == 0:  # no velocity left (every wheel sticks, the vehicle is held): at rest while the cones hold
            grid_rest = grid[(grid > t) | ((grid == 0.0) & (t == 0.0))]
            constant = torque is None or type(torque).__name__ == "Constant"  # a TorqueProfile without time
            moved_at = _at_rest(robot, wheels, q, t, grid_rest, tau_at, constant)
            for tt in grid_rest[grid_rest < moved_at] if moved_at is not None else grid_rest:
                out_t.append(tt)
                out_q.append(q.copy())
                out_v.append(np.zeros(n))
                out_w.append(work)
                out_p.append(recorded_phases(wheels))
            if moved_at is None:
                break
            t = moved_at
            for wheel, direction in _breaking(robot, wheels, q, moved_at, tau_at):
                wheel.set_phase("slide", direction)
                switches.append({"t": t, "wheel": wheel.name, "phase": "slide"})
            v = np.zeros(n)
            continue
        sticking = [w for w in wheels if w.phase == "stick"]
        cones = cone_check(forces, sticking)
        group = [w for w, c in zip(sticking, cones.coupled) if c]  # decided together (open tangential forces)
        moved = False
        for w, c in zip(sticking, cones.coupled):
            if not c:
                f = forces.wheel(w.name)
                if w.mu * f.normal - np.hypot(f.force[0], f.force[1]) < -1e-12 * max(1.0, abs(f.normal)):
                    w.set_phase("slide", -f.force[:2])
                    switches.append({"t": t, "wheel": w.name, "phase": "slide"})
                    moved = True
        if group and cones.group_margin < -1e-12:
            for w, direction in cones.breaking():
                if w in group and w.phase == "stick":
                    w.set_phase("slide", direction)
                    switches.append({"t": t, "wheel": w.name, "phase": "slide"})
                    moved = True
        if moved:
            continue
        k = len(nu)

        def rhs(tt, y, k=k):
            nonlocal nfev, last_report
            nfev += 1
            qq, nn = y[:n], y[n:n + k]
            tau = tau_at(tt, qq, nn)
            limit(tt)
            if progress and time.perf_counter() - last_report > 1.0:
                last_report = time.perf_counter()
                print(f"simulate: t = {tt:.3f} / {t_end:g} s", file=sys.stderr, flush=True)
            if sliding_now(robot):
                st = forward_sliding(robot, qq, nn, tau)
                return np.concatenate([position_rate(st.reduced, stabilisation), st.nudot, [st.power]])
            red = robot.reduced(qq, nn)
            return np.concatenate([position_rate(red, stabilisation), np.linalg.solve(red.M, red.B @ tau - red.h), [0.0]])

        events = _events(robot, wheels, n, k, tau_at, group)
        seg = grid[(grid > t) | ((grid == 0.0) & (t == 0.0))]
        if len(seg) and seg[-1] < t_end:
            seg = np.append(seg, t_end)
        sol = solve_ivp(rhs, (t, t_end), np.concatenate([q, nu, [work]]), method=method, rtol=rtol, atol=atol,
                        t_eval=seg if len(seg) else None, events=[e for e, _, _ in events])
        if not sol.success:
            raise RobotDynError(f"integration failed at t = {sol.t[-1]:.4g} s: {sol.message}")
        for i, tt in enumerate(sol.t):
            if tt in grid or tt == t_end:
                out_t.append(tt)
                out_q.append(sol.y[:n, i])
                out_v.append(robot.velocity(sol.y[:n, i], sol.y[n:n + k, i]))
                out_w.append(sol.y[-1, i])
                out_p.append(recorded_phases(wheels))
        if sol.status != 1:
            break
        fired = [i for i, te in enumerate(sol.t_events) if len(te)]
        i = min(fired, key=lambda j: sol.t_events[j][0])
        t, y = float(sol.t_events[i][0]), sol.y_events[i][0]
        q, nu, work = y[:n], y[n:n + k], float(y[-1])
        v = robot.velocity(q, nu)
        _, wheel, kind = events[i]
        if kind == "slide" and _forces(robot, q, nu, tau_at(t, q, nu)).wheel(wheel.name).normal <= 1e-9 * weight(robot):
            kind = "lift-off"  # its cone's edge reached by its load going to zero (friction zero there): no slide
        if kind == "slide together":  # the group's best split reaches a cone's edge: those wheels slide
            cones = cone_check(_forces(robot, q, nu, tau_at(t, q, nu)), wheel)
            worst = int(np.argmax(cones.ratio))
            for w, direction in cones.breaking() or [(wheel[worst], -cones.force[worst])]:
                w.set_phase("slide", direction)
                switches.append({"t": t, "wheel": w.name, "phase": "slide"})
        elif kind == "lift-off":
            load = _forces(robot, q, nu, tau_at(t, q, nu)).wheel(wheel.name).normal
            stop = unloaded_message(wheel.name, t, load, "sliding" if wheel.phase == "slide" else "sticking")
            lift = {"t": t, "wheel": wheel.name, "load": float(load)}
            print(f"simulate: {stop}", file=sys.stderr, flush=True)
            break
        elif kind == "slide":  # the cone is reached: slide opposite to the sticking force
            f = _forces(robot, q, nu, tau_at(t, q, nu)).wheel(wheel.name)
            wheel.set_phase("slide", -f.force[:2])
            switches.append({"t": t, "wheel": wheel.name, "phase": wheel.phase})
        else:  # the slip along its initial direction reached zero: stick, if the sticking force is in the cone
            wheel.set_phase("stick")
            kin = _kin(robot, q, v)
            for w in wheels:  # wheels stopping together (a vehicle coming to rest) stick together
                if w.phase == "slide" and np.linalg.norm(slip(w, kin)[1]) <= 1e-9:
                    w.set_phase("stick")
                    switches.append({"t": t, "wheel": w.name, "phase": "stick"})
            robot._stick_slip_q = q
            _configure(robot)
            v = robot.velocity(q, v[robot.independent_indices])  # the rolling rows hold from here on
            switches.append({"t": t, "wheel": wheel.name, "phase": wheel.phase})
        if len(switches) > max_switches:
            stop = f"more than {max_switches} phase switches by t = {t:.6g} s (Zeno behaviour); the run stops there"
            print(f"simulate: {stop}", file=sys.stderr, flush=True)
            break
    wall = time.perf_counter() - start
    T = np.array(out_t)
    Q = np.array(out_q).reshape(len(T), n)
    V = np.array(out_v).reshape(len(T), n)
    energy = np.array([robot.energy(qq, vv) for qq, vv in zip(Q, V)])
    residual = np.array([np.max(np.abs(robot.constraint_residual(qq)), initial=0.0) for qq in Q])
    stats = {"nfev": nfev, "wall": wall, "method": method, "rtol": rtol, "engine": f"scipy ({method})",
             "switches": switches, "phases": phase_table([w.name for w in wheels], out_p, len(T))}
    if stop:
        stats["event"] = stop
    if lift:
        stats["lift_off"] = lift
    return Trajectory(T, Q, V, energy, residual, list(robot.coordinates), list(robot.velocity_labels), stats,
                      robot.units, np.array(out_w))


def _rest_margin(robot, wheels, q, t, tau_at):
    """At rest at q (no velocity left) at time t: the smallest cone margin :math:`1 - \\|f_t\\| / (\\mu f_n)` [-] of
    the sticking wheels and their :class:`~robotdyn.contact.sticking_cone.ConeCheck` (with statically indeterminate
    contacts, at the admissible split that keeps them furthest inside their cones)."""
    tau = tau_at(t, q, np.zeros(0))
    cones = cone_check(_forces(robot, q, np.zeros(0), tau), [w for w in wheels if w.phase == "stick"])
    return cones.margin, cones


def _at_rest(robot, wheels, q, t: float, grid: np.ndarray, tau_at, constant: bool) -> float | None:
    """A vehicle held at rest by its sticking wheels (no independent velocity) from time t: the time at which a
    wheel's force leaves its cone (located by bisection between the output samples, on the torques' time
    dependence), or ``None`` if the cones hold at every sample to the end. Gravity and the torques are the only
    forces at rest, so with torques constant in time (``constant``) the check at t decides the whole run.

    Raises:
        RobotDynError: A sticking wheel's normal load that nothing determines
            (:func:`robotdyn.contact.sticking_cone.check`)."""
    from scipy.optimize import brentq

    def margin(tt: float) -> float:
        return _rest_margin(robot, wheels, q, tt, tau_at)[0]

    tol = 1e-12
    times = [t] + [float(x) for x in grid if x > t]
    last = times[0]
    for i, tt in enumerate(times):
        m = margin(tt)
        if m < -tol:
            return tt if i == 0 else float(brentq(lambda x: margin(x) + tol, last, tt, xtol=1e-12))
        last = tt
        if constant:
            return None
    return None


def _breaking(robot, wheels, q, t: float, tau_at) -> list:
    """The sticking wheels whose force leaves its cone at time t and their slip directions (opposite to that force,
    at the split that keeps the wheels furthest inside their cones): ``[(wheel, direction), ...]``."""
    cones = _rest_margin(robot, wheels, q, t, tau_at)[1]
    j = int(np.argmax(cones.ratio))
    return cones.breaking() or [(cones.wheels[j], -cones.force[j])]


def _kin(robot, q, v):
    from ..constraints.constraint import KinematicState

    return KinematicState(robot.model, robot.data, q, v)


def _events(robot, wheels, n, k, tau_at, group=()):
    """Event functions of the current phases: (function, wheel, the phase it leads to or ``lift-off``); the sticking
    wheels of ``group`` (their tangential forces stay open) share one event, (function, group, ``slide together``)."""
    out = []
    last = {}

    def state(t, y):  # every event of a step asks at the same (t, y): the forces are computed once
        key = (t, y.tobytes())
        if last.get("key") != key:
            qq, nn = y[:n], y[n:n + k]
            last["key"], last["value"] = key, (qq, nn, _forces(robot, qq, nn, tau_at(t, qq, nn)))
        return last["value"]

    for w in wheels:
        if w.phase == "stick" and w not in group:
            def cone(t, y, w=w):
                f = state(t, y)[2].wheel(w.name)
                return w.mu * f.normal - np.hypot(f.force[0], f.force[1])

            cone.terminal, cone.direction = True, -1.0
            out.append((cone, w, "slide"))
        elif w.phase == "slide":
            def stops(t, y, w=w):
                qq, nn = y[:n], y[n:n + k]
                return float(slip(w, _kin(robot, qq, robot.velocity(qq, nn)))[1] @ w.direction)

            stops.terminal, stops.direction = True, -1.0
            out.append((stops, w, "stick"))

        def lift(t, y, w=w):
            return state(t, y)[2].wheel(w.name).normal

        lift.terminal, lift.direction = True, -1.0
        out.append((lift, w, "lift-off"))
    if group:
        def cones(t, y):
            return cone_check(state(t, y)[2], list(group)).margin

        cones.terminal, cones.direction = True, -1.0
        out.append((cones, list(group), "slide together"))
    return out

"""Simulation of robots whose compliant wheels roll while in contact (:mod:`robotdyn.contact.compliant_rolling`).

A hybrid run: between events the contact set C (the rolling wheels pressing on the ground) is fixed and scipy's
``solve_ivp`` integrates :math:`\\dot q = S\\nu - \\alpha A_h^+\\phi`,
:math:`\\dot\\nu` of :func:`robotdyn.contact.compliant_rolling.forward` with C's rolling rows as constraints (the
stiff normal laws: LSODA by default, :data:`robotdyn.simulation.flight.STIFF_METHOD`). Each rolling wheel's
contact indicator (> 0 exactly where its normal force is > 0) is a terminal event:

- **lift-off** (it falls through zero while the wheel is in C): the wheel leaves C; its rows are dropped. The
  velocities are continuous (the tangential force jumps to zero: an acceleration jump only).
- **touch-down** (it rises through zero while the wheel is out of C): the wheel joins C, and a plastic tangential
  impact (:func:`robotdyn.contact.compliant_rolling.touch_down`, :func:`robotdyn.contact.impulse.plastic_impact`)
  stops the tangential velocity of its contact point, keeping the wheels already in C rolling. The normal law
  gives no impulse. The kinetic energy it removes is recorded as that touch-down's ``loss`` [J].

Which velocities the state carries across a switch: the state is always (q, ν) with ν the independent velocities
of the robot's own projection, in which compliant wheels have no rows (the coordinates of the flight phase, the
largest set). With wheels in C the motion stays in the subspace :math:`G_r\\nu = 0`, whose minimal coordinates
would be a basis of the null space of :math:`G_r`; carrying ν itself instead keeps one state vector and one set of
columns through every phase: at a lift-off ν is continuous and nothing is mapped; at a touch-down ν jumps by the
impulse onto :math:`G_r\\nu^+ = 0` (its projection, in the kinetic-energy metric :math:`M_r`, onto the
new admissible subspace), which is exactly the state of the new phase. The rows' velocity residual
:math:`G_r\\nu` is held at the integrator's tolerance by the acceleration-level rows and pulled back with the
stabilisation gain; ``stats["rolling_residual"]`` reports its largest value at the samples [m/s].

Energy: E(t) - E(0) = motor work + friction work (friction laws of other compliant wheels) + damper work - the sum
of the touch-down losses up to t (``Trajectory.impact_loss``); the rolling rows' forces do no work.
"""

from __future__ import annotations

import time

import numpy as np

from ..constraints.constraint import KinematicState
from ..contact.compliant_contact import compliant_wheels
from ..contact.compliant_rolling import forward, pressing, rolling_wheels, rows, touch_down
from ..errors import NonFiniteError, RobotDynError
from ..reduction.pull_back import failure_note, position_rate
from ..reduction.reduced_dynamics import velocity
from .flight import STIFF_METHOD, airborne, flight_events, flight_phases
from .trajectory import Trajectory

START_SLIP = 1e-6
"""Slip speed [m/s] above which a wheel pressing at the start is reported as a touch-down at t0 (below it the start
impact, which still makes its rows exact, only removes rounding: e.g. 2e-7 m/s from a posture given to 1e-3 m)."""
SIMULTANEOUS = 1e-10
"""Contact indicator [m] within which other wheels switch with the wheel whose event fired (wheels that leave or
land together, e.g. on a symmetric axle, found one event apart only by rounding; dropping the rows of one of them
alone would change the other's motion at once)."""
MAX_SWITCHES = 10_000
"""Largest number of contact switches of one run (beyond it the run stops with an error: chattering contact)."""


def simulate_rolling(robot, t_end: float, q0: np.ndarray, nu0: np.ndarray, torque, t_eval: np.ndarray,
                     rtol: float, atol: float, method: str | None, stabilisation: float, report, t0: float = 0.0
                     ) -> Trajectory:
    """Integrate a robot with rolling compliant wheels from (q0, ν0) (see the module); called by
    :func:`robotdyn.simulation.engine.simulate`, whose checks have run.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        t_end: Final time [s].
        q0: Initial natural coordinates (n,).
        nu0: Initial independent velocities (k,). A rolling wheel pressing at the start with a slipping contact
            point gets the touch-down impact at t0 (recorded as a touch-down at t0).
        torque: ``tau(t, q, nu)`` or ``None``.
        t_eval: Output times [s] (sorted, from t0 to t_end).
        rtol, atol: Tolerances of ``solve_ivp``.
        method: A ``solve_ivp`` method (``None``: :data:`~robotdyn.simulation.flight.STIFF_METHOD`).
        stabilisation: Gain [1/s] of the holonomic pull-back and of the rolling rows' velocity residual.
        report: The :class:`~robotdyn.simulation.progress.Progress` of the run (called with the time).
        t0: Start time [s].

    Returns:
        The :class:`~robotdyn.simulation.trajectory.Trajectory`, with ``friction_work``, ``damper_work``,
        ``impact_loss`` (N,) [J] (the touch-down losses up to each sample), ``stats["flight"]`` (each event; a
        rolling wheel's touch-down carries its ``loss`` [J] and the contact-point slip it stopped, ``slip`` [m/s])
        and ``stats["touchdown_loss"]`` [J] (their sum).

    Raises:
        RobotDynError: The integration failed, or the contact switched more than :data:`MAX_SWITCHES` times.
    """
    from scipy.integrate import solve_ivp

    method = method or STIFF_METHOD
    n, k = robot.nq, robot.mobility
    zero_tau = np.zeros(len(robot.motors))
    wheels = rolling_wheels(robot)
    names = [w.name for w in wheels]
    others = [w for w in compliant_wheels(robot) if not w.rolling]

    def tau_at(t, q, nu):
        return zero_tau if torque is None else np.asarray(torque(t, q, nu), float)

    last: dict = {}  # the indicators at the last state asked for (one projection for every wheel's event)

    def indicators(y: np.ndarray) -> np.ndarray:
        key = np.asarray(y[:n + k], float).tobytes()
        if last.get("key") != key:
            q, nu = y[:n], y[n:n + k]
            last["key"], last["values"] = key, pressing(robot, q, robot.velocity(q, nu))
        return last["values"]

    events_log: list[dict] = []
    q_start, nu_start = np.asarray(q0, float), np.asarray(nu0, float)
    contact = tuple(nm for nm, p in zip(names, indicators(np.concatenate([q_start, nu_start]))) if p > 0.0)
    start_loss = 0.0
    if contact:  # wheels pressing at the start: their slip is stopped there (a touch-down at t0)
        nu_start, start_loss = _touch(robot, q_start, nu_start, contact, contact, t0, events_log, start=True)
    y = np.concatenate([q_start, nu_start, [0.0, 0.0]])
    t = float(t0)
    ts, ys, losses = [], [], []
    other_events = flight_events(robot, others, n)  # friction-law compliant wheels: recorded, not switched
    other_times: list[list[float]] = [[] for _ in other_events]
    nfev, switches = 0, 0
    start = time.perf_counter()
    while True:
        active = contact

        def rhs(t, y, active=active):
            if not np.isfinite(y).all():
                raise NonFiniteError(f"the state became non-finite at t = {t:.6g} s (the dynamics blew up)")
            q, nu = y[:n], y[n:n + k]
            st = forward(robot, q, nu, tau_at(t, q, nu), active, stabilisation)
            report(t)
            return np.concatenate([position_rate(st.reduced, stabilisation), st.nudot,
                                   [st.applied.friction_power, st.applied.damper_power]])

        switch = []
        for i, nm in enumerate(names):
            def event(t, y, i=i):
                return float(indicators(y)[i])

            event.terminal, event.direction = True, (-1.0 if nm in active else 1.0)
            switch.append(event)
        todo = t_eval[t_eval > t] if switches else t_eval[t_eval >= t]
        sol = solve_ivp(rhs, (t, t_end), y, method=method, t_eval=todo, rtol=rtol, atol=atol,
                        events=switch + [e for e, _, _ in other_events])
        nfev += int(sol.nfev)
        if not sol.success:
            raise RobotDynError(f"integration failed at t = {sol.t[-1] if len(sol.t) else t:.4g} s: {sol.message}"
                                + failure_note(robot, sol.y[:n, -1] if len(sol.t) else y[:n], stabilisation))
        if len(sol.t):  # (a segment between two events may hold no output time)
            ts.append(sol.t)
            ys.append(np.asarray(sol.y, float).reshape(len(y), -1))
        for j in range(len(other_events)):
            other_times[j].extend(float(x) for x in sol.t_events[len(switch) + j])
        if sol.status != 1:
            break
        hits = [(float(sol.t_events[i][0]), i) for i in range(len(switch)) if len(sol.t_events[i])]
        t_ev, i = min(hits)
        y = np.array(sol.y_events[i][0], float)
        for j, (_, _, kind) in enumerate(other_events):  # drop the other wheels' events found past the switch
            other_times[j] = [x for x in other_times[j] if x <= t_ev]
        t = t_ev
        switches += 1
        if switches > MAX_SWITCHES:
            raise RobotDynError(f"the rolling compliant wheels' contact switched more than {MAX_SWITCHES} times by "
                                f"t = {t:.6g} s (chattering contact); expected more normal damping or a shorter run")
        # the wheel whose event fired switches; any other wheel whose indicator has reached zero too (within
        # SIMULTANEOUS: e.g. the two wheels of a symmetric axle) switches with it
        signs = indicators(y)
        leaving = [nm for j, nm in enumerate(names) if nm in active and (j == i or signs[j] <= SIMULTANEOUS)]
        landing = [nm for j, nm in enumerate(names) if nm not in active and (j == i or signs[j] >= -SIMULTANEOUS)]
        for nm in leaving:
            events_log.append({"t": t, "wheel": nm, "event": "lift-off"})
        contact = tuple(x for x in names if (x in active and x not in leaving) or x in landing)
        if landing:
            y[n:n + k], loss = _touch(robot, y[:n], y[n:n + k], contact, landing, t, events_log)
            losses.append((t, loss))
        if t >= t_end:
            break
    wall = time.perf_counter() - start
    times = np.concatenate(ts)
    Y = np.hstack(ys)
    q, nu = Y[:n].T, Y[n:n + k].T
    energy = np.empty(len(times))
    residual = np.zeros(len(times))
    rolling_residual = 0.0
    impact = np.full(len(times), start_loss)
    for i in range(len(times)):
        v, rws = velocity(robot, q[i], nu[i])
        energy[i] = robot.energy(q[i], v)
        if rws.holonomic.any():
            residual[i] = np.max(np.abs(rws.residual[rws.holonomic]))
        impact[i] += sum(loss for t_s, loss in losses if t_s < times[i])
        kin = KinematicState(robot.model, robot.data, q[i], v)
        held = tuple(nm for nm, p in zip(names, pressing(robot, q[i], v, kin)) if p > 0.0)
        G, _, _ = rows(robot, kin, held)
        if G.shape[0]:
            rolling_residual = max(rolling_residual, float(np.max(np.abs(G @ v))))
    phases = flight_phases(other_events, other_times, times[-1]) if other_events else []
    flight = sorted(events_log + phases, key=lambda e: e["t"])
    stats = {"nfev": nfev, "wall": wall, "method": method, "rtol": rtol, "engine": f"scipy ({method})",
             "flight": [e for e in flight if e["t"] <= times[-1]],
             "airborne": airborne(robot, compliant_wheels(robot), q0),
             "touchdown_loss": float(impact[-1]), "rolling_residual": rolling_residual, "contact_switches": switches}
    traj = Trajectory(times, q, nu, energy, residual, list(robot.coordinates), list(robot.velocity_names), stats,
                      robot.units, Y[n + k], robot, torque)
    traj.damper_work = Y[n + k + 1]
    traj.impact_loss = impact
    return traj


def _touch(robot, q, nu, contact, landing, t, log, start: bool = False) -> tuple[np.ndarray, float]:
    """ν after the touch-down impact of the wheels ``landing`` (all of ``contact`` keep rolling) and its energy
    loss [J]; appends one touch-down entry per landing wheel to ``log`` (the impact's loss on the first, the slip
    speed [m/s] it stopped on each; at the ``start``, only for wheels slipping faster than :data:`START_SLIP`)."""
    kin = KinematicState(robot.model, robot.data, np.asarray(q, float), robot.velocity(q, nu))
    before = {nm: float(np.linalg.norm(rows(robot, kin, (nm,))[0] @ kin.v)) for nm in landing}
    nu_after, imp = touch_down(robot, q, nu, contact)
    for j, nm in enumerate(n for n in landing if not start or before[n] > START_SLIP):
        log.append({"t": float(t), "wheel": nm, "event": "touch-down", "slip": before[nm],
                    "loss": imp.energy_lost if j == 0 else 0.0})
    return nu_after, float(imp.energy_lost)


__all__ = ["simulate_rolling", "MAX_SWITCHES", "START_SLIP", "SIMULTANEOUS"]

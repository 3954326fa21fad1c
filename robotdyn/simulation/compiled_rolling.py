"""Compliant wheels that roll while in contact on the compiled engine: the compiled twin of
:mod:`robotdyn.simulation.compliant_rolling` (same hybrid run, same reports).

Between events the contact set C (the rolling wheels whose tangential rows hold) is data of the compiled run
(``Evaluator.set_rolling_mode``): the whole segment, with its right-hand side (the rows of C as constraints,
``robotdyn/kernels/compliant_rolling.hpp``, the same minimum-norm solve as
:func:`robotdyn.contact.compliant_rolling.forward`), runs in C++ on the stepper of
:mod:`robotdyn.simulation.compiled_engine` (dopri5 by default, rosenbrock4 or bulirsch_stoer on request). Its
terminal event is :math:`\\min_i s_i\\,p_i` with :math:`p_i` each rolling wheel's contact indicator
(:meth:`~robotdyn.contact.compliant_contact.NormalLaw.pressing`) and :math:`s_i = +1` for a wheel in C (its lift-off),
:math:`-1` out of it (its touch-down): it is >= 0 exactly until some wheel must switch, and its root is located on
the stepper's dense output (``robotdyn/_integrator.hpp``, to 4 eps in t), as solve_ivp locates each wheel's event
on the Python path.

At the event the run returns to Python, which switches C exactly as the Python path does (the wheel whose value
reached zero, and every other wheel within :data:`~robotdyn.simulation.compliant_rolling.SIMULTANEOUS` of zero), applies the
touch-down impact of landing wheels with :func:`robotdyn.contact.impulse.plastic_impact` (the Python path's own
function, on the compiled :math:`M_r`, rows G and S at that state: ``Evaluator.rolling_state``) and starts the next
compiled segment. Why there and not in C++: a switch happens a few times per second of a run (16 on
``examples/bump_base_rolling.toml``), its Python cost is about a millisecond (the segment's call and one compiled
evaluation), and one impact function then serves both engines, so the losses agree to rounding.

The friction and damper work are carried across segments (each compiled segment starts them at zero: their values
at the switch are added), energies and holonomic residuals come from the compiled samples, the rows' velocity
residual ``stats["rolling_residual"]`` [m/s] and the impact losses (``Trajectory.impact_loss``,
``stats["touchdown_loss"]``, the ``loss`` and ``slip`` of each touch-down in ``stats["flight"]``) are computed as on
the Python path.
"""

from __future__ import annotations

import time

import numpy as np

from ..contact.compliant_contact import compliant_wheels
from ..contact.compliant_rolling import rolling_wheels
from ..contact.impulse import plastic_impact
from ..errors import RobotDynError
from .compiled_engine import as_data, engine_model, run
from .compliant_rolling import MAX_SWITCHES, SIMULTANEOUS, START_SLIP
from .feedback import FeedbackLaw
from .flight import airborne
from .torque_profile import Constant, as_profile
from .trajectory import Trajectory


class _Rows:
    """The rolling wheels' rows on the compiled model ``fast``: each wheel's slice of G, the state of a switch."""

    def __init__(self, robot, fast) -> None:
        self.fast = fast
        self.names = [w.name for w in rolling_wheels(robot)]
        self.slices, i = {}, 0
        for w in rolling_wheels(robot):
            d = w.tangent_directions.shape[0]
            self.slices[w.name] = slice(i, i + d)
            i += d

    def state(self, q: np.ndarray, nu: np.ndarray) -> tuple:
        """(indicators [m], G of every rolling wheel, M_r, S, v) at (q, nu)."""
        return self.fast.ev.rolling_state(np.asarray(q, float), np.asarray(nu, float))

    def pick(self, G: np.ndarray, contact) -> np.ndarray:
        """The rows of G of the wheels in ``contact`` (in the wheels' order)."""
        rows = [np.arange(self.slices[nm].start, self.slices[nm].stop) for nm in self.names if nm in contact]
        return G[np.concatenate(rows)] if rows else np.zeros((0, G.shape[1]))

    def touch(self, q, nu, contact, landing, t, log, start: bool = False) -> tuple[np.ndarray, float]:
        """ν after the touch-down impact of ``landing`` (all of ``contact`` keep rolling) and its loss [J], logged
        as :func:`robotdyn.simulation.compliant_rolling._touch` logs it."""
        _, G, M, S, v = self.state(q, nu)
        before = {nm: float(np.linalg.norm(self.pick(G, (nm,)) @ v)) for nm in landing}
        imp = plastic_impact(M, self.pick(G, contact) @ S, nu)
        for j, nm in enumerate(n for n in landing if not start or before[n] > START_SLIP):
            log.append({"t": float(t), "wheel": nm, "event": "touch-down", "slip": before[nm],
                        "loss": imp.energy_lost if j == 0 else 0.0})
        return imp.nu_after, float(imp.energy_lost)


def simulate_rolling_compiled(robot, t_end, q0, nu0, torque, n_out, rtol, atol, method, stabilisation, progress,
                              offsets, t0: float = 0.0, times=None) -> Trajectory:
    """:func:`robotdyn.simulation.engine.simulate` of a robot with rolling compliant wheels on the compiled engine
    (see the module), after its checks; arguments and result as
    :func:`robotdyn.simulation.compiled_engine.simulate_compiled`, with the reports of
    :func:`robotdyn.simulation.compliant_rolling.simulate_rolling` (``impact_loss``, ``stats["touchdown_loss"]``,
    ``stats["rolling_residual"]``, ``stats["contact_switches"]``, touch-downs with ``loss`` and ``slip``).

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
        method: A compiled integrator with dense output (dopri5, bulirsch_stoer, rosenbrock4) or cvode.
        stabilisation: Gain [1/s] of the holonomic pull-back and of the rolling rows' velocity residual.
        progress: The run's :class:`~robotdyn.simulation.progress.Progress` reporter.
        offsets: Holonomic residuals kept as constant offsets, by row label [m or rad].
        t0: Start time [s].
        times: Output times [s] (increasing, t0 to t_end; default ``None``: ``n_out`` evenly spaced).

    Returns:
        The :class:`~robotdyn.simulation.trajectory.Trajectory` of the run.

    Raises:
        RobotDynError: The integration failed, or the contact switched more than
            :data:`~robotdyn.simulation.compliant_rolling.MAX_SWITCHES` times.
    """
    law = torque.bound(robot) if isinstance(torque, FeedbackLaw) else as_data(torque)
    profile = Constant(np.zeros(len(robot.motors))) if law is not None else as_profile(torque, len(robot.motors))
    tau0 = law(t0, q0, nu0) if law is not None else profile(t0)
    robot.forward_dynamics(q0, nu0, tau0)  # regular where the run starts (raises the Python path's error)
    fast = engine_model(robot)
    if not fast.ready:
        fast._choose(q0, nu0)
    n, k = robot.nq, robot.mobility
    t_eval = np.linspace(t0, t_end, n_out) if times is None else np.asarray(times, float)
    rows = _Rows(robot, fast)
    names = rows.names
    compliant = compliant_wheels(robot)
    report = progress if progress.needed else None
    start = time.perf_counter()
    log: list[dict] = []
    q, nu = np.asarray(q0, float), np.asarray(nu0, float)
    contact = tuple(nm for nm, p in zip(names, rows.state(q, nu)[0]) if p > 0.0)
    start_loss = 0.0
    if contact:  # wheels pressing at the start: their slip is stopped there (a touch-down at t0)
        nu, start_loss = rows.touch(q, nu, contact, contact, t0, log, start=True)
    t, work = float(t0), np.zeros(2)
    ts, ys, energy, residual, losses, flights = [], [], [], [], [], []
    nfev = steps = switches = 0
    interrupted = None
    while True:
        fast.ev.set_rolling_mode([int(nm in contact) for nm in names])
        todo = t_eval[t_eval > t] if switches else t_eval[t_eval >= t]
        out = run(robot, fast, t_end, q, nu, profile, todo, rtol, atol, stabilisation, method, report, t, law)
        nfev += out["nfev"]
        steps = None if steps is None or out["steps"] is None else steps + out["steps"]  # (CVODE: not known)
        y = np.asarray(out["y"], float).reshape(len(out["t"]), n + k + 2)  # (q, nu, friction work, damper work)
        y[:, n + k:] += work
        ts.append(np.asarray(out["t"], float))
        ys.append(y)
        energy.append(np.asarray(out["energy"], float))
        residual.append(np.asarray(out["residual"], float))
        t_stop = out["event"][0] if out["event"] is not None else float(t_end)
        flights += [(float(te), compliant[i].name, d) for te, i, d in out["flights"]
                    if not compliant[i].rolling and te <= t_stop]
        if out["interrupted"] or out["event"] is None:
            interrupted = out["interrupted"]
            break
        t, y_ev = float(out["event"][0]), np.asarray(out["event"][1], float)
        q, nu, work = y_ev[:n].copy(), y_ev[n:n + k].copy(), work + y_ev[n + k:n + k + 2]
        switches += 1
        if switches > MAX_SWITCHES:
            raise RobotDynError(f"the rolling compliant wheels' contact switched more than {MAX_SWITCHES} times by "
                                f"t = {t:.6g} s (chattering contact); expected more normal damping or a shorter run")
        # as on the Python path: the wheel whose value reached zero switches, with any other within SIMULTANEOUS
        signs = rows.state(q, nu)[0]
        value = np.array([p if nm in contact else -p for nm, p in zip(names, signs)])
        i = int(np.argmin(value))
        leaving = [nm for j, nm in enumerate(names) if nm in contact and (j == i or signs[j] <= SIMULTANEOUS)]
        landing = [nm for j, nm in enumerate(names) if nm not in contact and (j == i or signs[j] >= -SIMULTANEOUS)]
        log += [{"t": t, "wheel": nm, "event": "lift-off"} for nm in leaving]
        active = contact
        contact = tuple(x for x in names if (x in active and x not in leaving) or x in landing)
        if landing:
            nu, loss = rows.touch(q, nu, contact, landing, t, log)
            losses.append((t, loss))
        if t >= t_end:
            break
    wall = time.perf_counter() - start
    times_out = np.concatenate(ts)
    Y = np.vstack(ys)
    impact = np.full(len(times_out), start_loss)
    rolling_residual = 0.0
    for j, tj in enumerate(times_out):
        impact[j] += sum(loss for t_s, loss in losses if t_s < tj)
        p, G, _, _, v = rows.state(Y[j, :n], Y[j, n:n + k])
        Gh = rows.pick(G, tuple(nm for nm, x in zip(names, p) if x > 0.0))
        if Gh.shape[0]:
            rolling_residual = max(rolling_residual, float(np.max(np.abs(Gh @ v))))
    reached = float(times_out[-1]) if len(times_out) else t0
    phases = [{"t": te, "wheel": nm, "event": "touch-down" if d > 0 else "lift-off"} for te, nm, d in flights]
    stats = {"nfev": nfev, "steps": steps, "wall": wall, "method": method, "rtol": rtol,
             "engine": f"compiled ({method})",
             "flight": sorted((e for e in log + phases if e["t"] <= reached), key=lambda e: e["t"]),
             "airborne": airborne(robot, compliant, q0), "touchdown_loss": float(impact[-1]),
             "rolling_residual": rolling_residual, "contact_switches": switches}
    if interrupted:
        stats["partial"] = interrupted
    if offsets:
        stats["offsets"] = offsets
    traj = Trajectory(times_out, Y[:, :n], Y[:, n:n + k], np.concatenate(energy), np.concatenate(residual),
                      list(robot.coordinates), list(robot.velocity_names), stats, robot.units, Y[:, n + k])
    traj.damper_work = Y[:, n + k + 1]
    traj.impact_loss = impact
    return traj


__all__ = ["simulate_rolling_compiled"]

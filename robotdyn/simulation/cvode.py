"""SUNDIALS CVODE on the compiled model: the stiff integrator of compliant runs (``method="cvode"``).

CVODE (Hindmarsh et al., ACM TOMS 31, 2005; SUNDIALS 7 through the ``scikit-sundae`` wheel, module ``sksundae``)
integrates the same ODE as the compiled engine (:mod:`robotdyn.simulation.compiled_engine`),

.. math:: \\dot q = S(q)\\nu - \\alpha A_h^+\\phi(q),\\quad M_r\\dot\\nu = B_r\\tau - C_r\\nu - g_r + S^T Q(q, v),
   \\quad \\dot W_f = P_f,\\quad \\dot W_d = P_d,

with its variable-order (1 to 5), variable-step BDF formulas, a modified Newton iteration on a dense Jacobian
kept over many steps (CVODE asks for a new one when the Newton iteration slows, or every 50 steps; it is formed here
by forward differences of the compiled model, one evaluation per column of q and nu, the compiled projection told
so that a difference ~1e-8 off the constraints passes its span check), and its own local error control (weights
:math:`1/(rtol |y_i| + atol)`, the compiled engine's). Every evaluation of the right-hand side is one call of the compiled model (``Evaluator.deriv_into``,
the C++ ``deriv`` the compiled steppers use: the torque profile or feedback law, joint springs, compliant contacts
and the work rates in C++, written into CVODE's own array); no other Python runs per step.

Why: tyres of the default rule (1 mm static deflection) put the linkage rover's tyre-slip modes at -630 to -1010
1/s and its wheel hop near -218 +- 90i 1/s; an explicit stepper (dopri5) needs about 18,000 evaluations for its 2.2 s
bump run at rtol 1e-8, CVODE about 1,300 (``bench/bench.py compliant`` prints both with their errors against a
tight reference: 1e-8 for CVODE, 2e-11 for dopri5, which is why dopri5 stays the default).

Events: each compliant wheel's penetration (``Evaluator.depths_into``) is a root function of CVODE's rootfinding
(both directions, not terminal): the flight phases are reported as the compiled engine reports them
(``flights``: time, wheel, +1 touch-down / -1 lift-off). The terminal event of rolling compliant wheels (their
contact switch, :mod:`robotdyn.simulation.compiled_rolling`) is one more root function
(``Evaluator.event_value``, direction -1): the run stops there. Samples are CVODE's interpolant at the requested
times (``CV_NORMAL`` mode: the steps do not depend on the sampling); the solver is restarted at the breakpoints of
the torque profile (``tstop``), as the other integrators are.

:func:`run` returns the result of :func:`robotdyn.simulation.compiled_engine.run`, which hands
``method="cvode"`` to it. ``steps`` is not known to it (CVODE counts its steps, scikit-sundae does not return the
count); ``nfev`` counts every evaluation, those of the Jacobians' differences included, and ``jacobians``
the Jacobians formed.
"""

from __future__ import annotations

import contextlib
import io

import numpy as np

from ..errors import NonFiniteError, RobotDynError

METHOD = "cvode"
"""The method name of CVODE's BDF integrator (:func:`robotdyn.simulation.engine.simulate`'s ``method``)."""
MAX_STEPS = 10 ** 9
"""CVODE's limit on steps between two outputs (its default, 500, would stop long gaps between samples); a run is
bounded by ``time_limit`` instead, as on the other engines."""
POLL = 512
"""Evaluations between two calls of the run's progress reporter (progress, time limit), as the compiled engine's
poll about every 50 ms."""
ROOT_RETURN = 2
"""CVODE's return flag at a root of the event functions (``CV_ROOT_RETURN``)."""
ROOT_EPS = float(np.sqrt(np.finfo(float).eps))
"""Relative step of the Jacobian's forward differences (times max(1, abs(y_j)))."""


def missing() -> str | None:
    """Why ``method="cvode"`` cannot run here, or ``None`` where it can.

    Returns:
        A one-line reason (scikit-sundae not installed), or ``None``.
    """
    try:
        import sksundae  # noqa: F401
    except ImportError:
        return "method 'cvode' needs SUNDIALS CVODE from the scikit-sundae package: pip install scikit-sundae"
    return None


def run(robot, fast, t_end: float, q0: np.ndarray, nu0: np.ndarray, native, breaks, t_eval: np.ndarray, rtol: float,
        atol: float, stabilisation: float, rechoose, progress=None, t0: float = 0.0) -> dict:
    """Integrate with CVODE on the compiled model ``fast`` of ``robot`` (see the module), for
    :func:`robotdyn.simulation.compiled_engine.run`, which has set its feedback law (if any) on ``fast``.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (with joint springs or compliant wheels).
        fast: Its compiled model (:func:`robotdyn.simulation.compiled_engine.engine_model`, projection chosen).
        t_end: Final time [s].
        q0: Initial natural coordinates (n,) [m, rad] (at time ``t0``).
        nu0: Initial independent velocities (k,) [m/s, rad/s].
        native: The motor torques' ``robotdyn._compiled.TorqueProfile``
            (:func:`robotdyn.simulation.compiled_engine.native_profile`).
        breaks: Times [s] inside (t0, t_end) where the torques are not smooth (CVODE restarts there), sorted.
        t_eval: Output times [s] (sorted, from t0 to t_end).
        rtol: Relative tolerance of CVODE's local error test.
        atol: Absolute tolerance, every component.
        stabilisation: Gain alpha [1/s] of the holonomic pull-back.
        rechoose: The callback that re-chooses the projection's rows where the compiled one stops working
            (:func:`robotdyn.simulation.compiled_engine.rechooser`).
        progress: ``progress(t)`` called every :data:`POLL` evaluations (None: not called).
        t0: Start time [s] (the profile is evaluated at absolute times).

    Returns:
        As :func:`robotdyn.simulation.compiled_engine.run`: ``t`` (N,), ``y`` (N, state), ``energy`` (N,) [J],
        ``residual`` (N,), ``nfev``, ``steps`` (None: not known), ``jacobians``, ``interrupted`` (a message, or
        None), ``event`` ((t, y) of the terminal event, or None) and ``flights`` ((t, wheel, direction) each).

    Raises:
        RobotDynError: CVODE failed (its message, with the time), the state became non-finite, or the Python
            path's own error where the projection had to be re-chosen.
        robotdyn._compiled.Fallback: The compiled model's rows could not be re-chosen (the caller names why).
    """
    from sksundae.cvode import CVODE

    from ..contact.compliant_contact import compliant_wheels
    from ..reduction.pull_back import failure_note

    bounds = [float(t0), *map(float, breaks), float(t_end)]
    n, k = robot.nq, robot.mobility
    ev = fast.ev
    y = np.zeros(ev.state_size)
    y[:n], y[n:n + k] = q0, nu0
    compliant = compliant_wheels(robot)  # the compiled model's penetrations are in this order
    wheels, terminal = len(compliant), any(w.rolling for w in compliant)  # rolling: a terminal contact switch
    deriv, depths, event_value = ev.deriv_into, ev.depths_into, ev.event_value
    alpha = float(stabilisation)
    count = [0]

    def rhs(t: float, x: np.ndarray, dx: np.ndarray) -> None:
        count[0] += 1
        if progress is not None and not count[0] % POLL:
            progress(t)
        deriv(t, x, dx, alpha, native, rechoose)

    active = n + k  # the Jacobian's columns of the work states are zero: nothing depends on them
    shifted, column = np.empty(len(y)), np.empty(len(y))

    def jacobian(t: float, x: np.ndarray, fx: np.ndarray, J: np.ndarray) -> None:
        # forward differences, step sqrt(eps) max(1, abs(y_j)) as rosenbrock4's; the compiled model is told, so
        # that its projection's span check lets a state ~1e-8 off the constraints pass (CVODE's own difference
        # quotients would stop the run there on a robot with redundant rows, e.g. a sprung car's rolling wheels)
        count[0] += active
        shifted[:] = x
        ev.set_differencing(True)
        try:
            for j in range(active):
                h = ROOT_EPS * max(1.0, abs(x[j]))
                shifted[j] = x[j] + h
                deriv(t, shifted, column, alpha, native, rechoose)
                J[:, j] = (column - fx) / h
                shifted[j] = x[j]
        finally:
            ev.set_differencing(False)
        J[:, active:] = 0.0

    def roots(t: float, x: np.ndarray, g: np.ndarray) -> None:
        if wheels:
            depths(x, g[:wheels], rechoose)
        if terminal:
            g[wheels] = event_value(t, x, alpha, native, rechoose)

    m = wheels + terminal
    options = dict(method="BDF", rtol=float(rtol), atol=float(atol), max_num_steps=MAX_STEPS, jacfn=jacobian)
    if m:
        roots.terminal = [False] * m
        roots.direction = [0] * wheels + [-1] * terminal
        options.update(eventsfn=roots, num_events=m)
    solver = CVODE(rhs, **options)
    ts, ys, flights = [], [], []
    event, interrupted, jacobians, i = None, None, 0, 0
    t_eval = np.asarray(t_eval, float)
    while i < len(t_eval) and t_eval[i] <= t0:
        ts.append(t_eval[i])
        ys.append(y.copy())
        i += 1
    now = float(t0)
    text = io.StringIO()  # CVODE's own error lines (scikit-sundae prints them): kept for the error message
    try:
        with contextlib.redirect_stdout(text):
            for a, b in zip(bounds[:-1], bounds[1:]):
                solver.init_step(a, y)
                while event is None:
                    target = t_eval[i] if i < len(t_eval) and t_eval[i] <= b else b
                    res = solver.step(target, "normal", tstop=b)
                    now = float(res.t)
                    if not res.success:
                        jacobians += int(res.njev)
                        y = np.asarray(res.y, float)
                        if not np.isfinite(y).all():
                            raise NonFiniteError(f"the state became non-finite at t = {now:.6g} s (the dynamics blew "
                                                 "up: massless bodies, a singular state, or torques beyond what double "
                                                 "precision holds)")
                        said = " ".join(text.getvalue().split()) or res.message
                        raise RobotDynError(f"integration failed at t = {now:.4g} s: CVODE: {said}"
                                            + failure_note(robot, y[:n], stabilisation))
                    if res.status == ROOT_RETURN:
                        found = np.asarray(res.i_events[-1])
                        flights += [(now, int(j), int(found[j])) for j in np.flatnonzero(found[:wheels])]
                        if terminal and found[wheels] != 0:
                            event = (now, np.array(res.y, float))
                        continue
                    if i < len(t_eval) and t_eval[i] <= b and now >= t_eval[i]:
                        ts.append(t_eval[i])
                        ys.append(np.array(res.y, float))
                        i += 1
                    if now >= b:
                        break
                y = np.array(res.y, float)
                jacobians += int(res.njev)
                if event is not None:
                    break
    except KeyboardInterrupt:
        reached = float(ts[-1]) if ts else float(t0)
        interrupted = f"interrupted at t = {now:.6g} s: samples up to t = {reached:.6g} s of {t_end:g} s"
    Y = np.array(ys, float).reshape(len(ts), len(y))
    energy, residual = np.empty(len(ts)), np.empty(len(ts))
    for j in range(len(ts)):
        energy[j], residual[j] = ev.observe(Y[j, :n + k])
    return {"t": np.array(ts, float), "y": Y, "energy": energy, "residual": residual, "nfev": count[0], "steps": None,
            "jacobians": jacobians, "interrupted": interrupted, "event": event, "flights": flights}


__all__ = ["run", "missing", "METHOD"]

"""The dropped-row check of forward dynamics at compiled cost: a screen that proves a state violates no dropped row,
else the exact check.

:func:`robotdyn.constraints.redundancy.violations` tests each row the projection dropped as redundant at the
acceleration level, :math:`a_d a + \\dot a_d v`, against the scale :math:`|a_d||a| + |\\dot a_d||v| + s\\|a\\|_1 +
\\ell\\|v\\|_1` (:math:`s`, :math:`\\ell`: the largest entries of all rows A and of :math:`\\dot A`). Its
:math:`\\dot A` is a Python kinematics pass over every constraint, which costs ten to thirty compiled evaluations,
while at regular states (every built-in robot's) no dropped row is violated. :func:`violations` here first
estimates the drift :math:`d = \\dot A v` from the compiled rows: in natural coordinates (:math:`\\dot q = v`)
:math:`\\dot A = dA/dt` along :math:`q(t) = q + t v`, so the central difference

.. math:: d \\approx \\frac{A(q + \\epsilon v) - A(q - \\epsilon v)}{2\\epsilon}\\,v,\\qquad
          \\epsilon = h / \\max_i |v_i|

(two compiled evaluations, :data:`STEP` h) has a relative error of order :math:`(h/L)^2` from truncation, L the
length over which the rows change (a wheel's radius, a terrain's wavelength), and of order
:math:`\\varepsilon_{mach} L / h` from rounding: at most 1.5e-10 of the check's own scale on the built-in robots
(``tests/test_dropped_rows_screen.py`` asserts 1e-9), L down to a few millimetres staying below 1e-8. Since
:math:`|\\dot a_d||v| \\ge |d_d|` and :math:`\\ell\\|v\\|_1 \\ge \\max_i |d_i|`, the scale is at least
:math:`|a_d||a| + s\\|a\\|_1 + |d_d| + \\max_i |d_i|`; a state whose every dropped row stays below :data:`MARGIN`
times the check's tolerance of that lower bound (with the estimated d) violates none, with a factor
1 / MARGIN = 4 to spare for the estimate's error (hundreds of times larger than it). Any other state (a row near or
above the tolerance, a rank change, a compiled evaluation that falls back, no compiled model) gets the exact check,
which alone decides what is reported and by how much: the warnings and their numbers are the exact check's.
"""

from __future__ import annotations

import numpy as np

from ..constraints.redundancy import TOL, RowViolation, dropped_rows
from ..constraints.redundancy import violations as exact_violations
from .compiled import Fallback
from .dispatch import compiled_model

STEP = 1e-6
"""Largest coordinate change h [m or rad] of the central difference of the rows along v."""
MARGIN = 0.25
"""Fraction of the exact check's tolerance below which the screen clears a dropped row."""


def drift_estimate(robot, q: np.ndarray, v: np.ndarray) -> np.ndarray | None:
    """The drift :math:`\\dot A v` of every constraint row at (q, v), by the central difference of the compiled
    rows along v (see the module text), or ``None`` where the compiled model does not serve (none, no row choice
    yet, or a fallback at one of the two configurations).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        v: Full velocities (n,) [m/s, rad/s], not all zero.

    Returns:
        The estimated drift (m,) [m/s^2 or rad/s^2], rows in the robot's row order, or ``None``.
    """
    fast = compiled_model(robot)
    if fast is None or not fast.ready:
        return None
    eps = STEP / float(np.abs(v).max())
    zero = np.zeros(robot.mobility)
    try:
        plus = fast.evaluate(q + eps * v, zero)[7]
        minus = fast.evaluate(q - eps * v, zero)[7]
    except Fallback:
        return None
    return (plus - minus) @ v / (2.0 * eps)


def violations(robot, red, q: np.ndarray, nudot) -> list[RowViolation]:
    """:func:`robotdyn.constraints.redundancy.violations` of ``red`` and ``nudot``, with its :math:`\\dot A` pass
    skipped where the screen of the module text proves that no dropped row is violated.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        red: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu), either evaluation path.
        q: Natural coordinates (n,) [m, rad] of ``red``.
        nudot: Independent accelerations (k,) [m/s^2, rad/s^2] (``None``: the velocity level only, already cheap).

    Returns:
        The :class:`~robotdyn.constraints.redundancy.RowViolation` of each violated row (empty: consistent), exactly
        as :func:`robotdyn.constraints.redundancy.violations` gives them.
    """
    v = red.v
    if nudot is None:  # no Adot needed there: the exact check is already cheap
        return exact_violations(red, nudot)
    dropped = dropped_rows(red)
    if dropped.size == 0:
        return []
    A_all = red.jacobian_rows.A
    if v.any():  # the estimated drift, with MARGIN for its error
        d = drift_estimate(robot, np.asarray(q, float), v)
        if d is None or d.shape != (A_all.shape[0],) or not np.isfinite(d).all():
            return exact_violations(red, nudot)
        margin = MARGIN
    else:  # at rest (a run's start) the drift and every term in v are exact zeros: the exact check's own test, whose
        # tolerance is at least TOL (only the projection's condition number raises it), without the margin
        d, margin = np.zeros(A_all.shape[0]), 1.0
    A = A_all[dropped]
    size = float(np.abs(A_all).max())
    absv = np.abs(v)
    vel_ok = np.abs(A @ v) <= TOL * (np.abs(A) @ absv + size * absv.sum())  # the exact velocity-level test
    a = red.S @ np.asarray(nudot, float) + red.w
    absa = np.abs(a)
    dd = np.abs(d[dropped])
    lower = np.abs(A) @ absa + size * absa.sum() + dd + float(np.abs(d).max())
    acc_ok = np.abs(A @ a + d[dropped]) <= margin * TOL * lower
    if vel_ok.all() and acc_ok.all():
        return []
    return exact_violations(red, nudot)

__all__ = ["violations", "drift_estimate", "STEP", "MARGIN"]

"""Whether a base can turn (or translate) at *some* admissible configuration, not only at the one it is checked at.

At a steerable base's neutral configuration its wheels are often all parallel: the base can then translate but
not turn, while a few degrees of steering let it turn about any point. Telling such a base "turning requires slip"
is wrong advice. :func:`reachable_motion` answers the question generically: it looks for joint coordinates q
(moving only those that no holonomic row involves, e.g. steering and spin angles, so that q stays admissible) and a
velocity v with

.. math:: A(q)\\,v = 0, \\qquad v_i = 1

for the base coordinate i (yaw, x or y), by nonlinear least squares from a few starts near the neutral
configuration. A residual at round-off level is a configuration where the base moves that way without slip.
"""

from __future__ import annotations

import numpy as np

from ..description.urdf import _ROOT_CHAINS

TOL = 1e-9
"""Largest :math:`|A v|` (relative to the largest entry of A, with :math:`v_i = 1`) accepted as a motion without
slip."""


def free_coordinates(robot) -> np.ndarray:
    """Mask of the joint coordinates no holonomic row involves at the neutral configuration (the root's excluded):
    moving them keeps a configuration admissible.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        Boolean mask (n,), ordered as the robot's coordinates: True for a joint coordinate (steering, wheel spin)
        that no holonomic constraint row involves.
    """
    rows = robot.rows_at(robot.neutral())
    root = {name for name, _, _ in _ROOT_CHAINS[robot.spec.root]}
    free = np.array([j not in root for j in robot.description.joint_names])
    if rows.A.size and rows.holonomic.any():
        free &= ~np.any(np.abs(rows.A[rows.holonomic]) > 1e-12, axis=0)
    return free


def reachable_motion(robot, coordinate: str, starts: int = 4, seed: int = 0) -> np.ndarray | None:
    """An admissible configuration at which the base moves along ``coordinate`` without slip, or ``None``.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` with a planar or floating root.
        coordinate: The root coordinate's joint name (``psi``/``yaw`` for turning, ``x``, ``y``).
        starts: Number of starting points (the neutral configuration, then random steering about it).
        seed: Seed of the random starts.

    Returns:
        The configuration q (n,) found, or ``None`` if no start reaches a residual below :data:`TOL`.
    """
    from scipy.optimize import least_squares

    names = robot.description.joint_names
    i = names.index(coordinate)
    q0 = robot.neutral()
    free = np.flatnonzero(free_coordinates(robot))
    n = robot.nq
    lo, hi = robot.description.lower, robot.description.upper
    scale = max(1.0, float(np.abs(robot.rows_at(q0).A).max(initial=0.0)))

    def config(x):
        q = q0.copy()
        q[free] = np.clip(q0[free] + x[: free.size], lo[free], hi[free])
        return q

    def residual(x):
        v = x[free.size:]
        A = robot.rows_at(config(x)).A
        return np.concatenate([A @ v / scale, [v[i] - 1.0]])

    rng = np.random.default_rng(seed)
    for k in range(starts):
        dq = np.zeros(free.size) if k == 0 else rng.uniform(-0.6, 0.6, free.size)
        A = robot.rows_at(config(np.concatenate([dq, np.zeros(n)]))).A
        v0 = np.zeros(n)
        v0[i] = 1.0
        if A.size:  # the least-squares velocity with v_i = 1 at the start
            others = np.delete(np.arange(n), i)
            v0[others] = np.linalg.lstsq(A[:, others], -A[:, i], rcond=None)[0]
        try:
            fit = least_squares(residual, np.concatenate([dq, v0]), xtol=1e-15, ftol=1e-15, gtol=1e-15,
                                max_nfev=200)
        except (ValueError, np.linalg.LinAlgError):
            continue
        if np.abs(fit.fun).max() < TOL:
            return config(fit.x)
    return None

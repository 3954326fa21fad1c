"""Posture on a terrain: solve the holonomic constraints for the coordinates that are not prescribed.

Given some prescribed coordinates (typically the body's x, y and yaw) and the robot's terrain, find the remaining
coordinates q_f such that every holonomic row (wheel contact normal rows, loop closures) has zero position
residual: :math:`\\phi(q) = 0`. Because robotdyn's coordinates are natural (:math:`\\dot q = v`), the holonomic
rows of :math:`A(q)` restricted to the free columns are the Jacobian :math:`\\partial\\phi/\\partial q_f` (exactly
for the translation rows of loop closures, to first order in the residual for rotation rows and contact rows,
which is all Newton needs). The solve is a damped Gauss-Newton iteration with minimum-norm least-squares steps
(``scipy.linalg.lstsq``), so redundant rows (planar loops, coincident rows) and free coordinates that no holonomic
row involves (wheel spin angles) are handled without inverting anything singular. It iterates towards
1e-3 ``tol`` (Newton converges quadratically) and fails only above ``tol``.

The result is checked, never assumed: if the largest residual cannot be brought under the tolerance (no posture
exists, e.g. a wall taller than the suspension travel), or the converged posture leaves a joint range (the
mechanism would have to pass its stops), :class:`~robotdyn.errors.ConstraintError` is raised naming the worst
constraint row or the joint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConstraintError, InputError, RobotDynError
from ..inputs import MAX_POSITION
from .terrain import Terrain


@dataclass
class Posture:
    """A solved posture.

    Attributes:
        q: Natural coordinates (n,) [m, rad] satisfying every holonomic row to ``residual``.
        residual: Largest absolute holonomic residual at ``q`` [m or rad].
        iterations: Gauss-Newton iterations used.
        free: Names of the coordinates that were solved for.
    """

    q: np.ndarray
    residual: float
    iterations: int
    free: list[str]


def set_terrain(robot, terrain: Terrain) -> None:
    """Put every terrain-dependent constraint of ``robot`` (and ``robot.terrain``) on ``terrain``, in place.

    Cheaper than rebuilding the robot (no Xacro expansion) when many terrains are tried.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`, changed in place.
        terrain: The new :class:`~robotdyn.constraints.terrain.Terrain`.

    Raises:
        InputError: ``terrain`` is not a Terrain.
    """
    if not isinstance(terrain, Terrain):
        raise InputError(f"terrain {terrain!r} is not a robotdyn Terrain")
    robot.terrain = terrain
    for c in robot.constraints:
        if hasattr(c, "terrain"):
            c.terrain = terrain


def _holonomic(robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str]]:
    rows = robot.rows_at(q)
    hol = rows.holonomic
    return rows.residual[hol], rows.A[hol], [lab for lab, h in zip(rows.labels, hol) if h]


def solve_posture(
    robot,
    fixed: dict[str, float] | None = None,
    q0=None,
    tol: float = 1e-10,
    max_iter: int = 60,
    check_limits: bool = True,
) -> Posture:
    """Solve the holonomic constraints for every coordinate not in ``fixed``.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` (its terrain is the one its wheel constraints hold).
        fixed: Prescribed coordinates by name (e.g. ``{"x": 0.3, "y": 0.0, "yaw": 0.1}``) [m, rad]; they are
            set in the initial guess and never changed.
        q0: Initial guess (default ``robot.neutral()``); the solution found is the one Newton reaches from it.
        tol: Required largest absolute residual [m, rad].
        max_iter: Gauss-Newton iterations before giving up.
        check_limits: Refuse a posture outside the description's joint ranges.

    Returns:
        A :class:`Posture`.

    Raises:
        ConstraintError: No posture within ``tol`` was reached (naming the worst row), or the posture found is
            outside a joint range.
        InputError: Unknown coordinate names, a non-finite value, or a wrong-length guess.
    """
    n = robot.nq
    q = robot.neutral() if q0 is None else np.array(q0, dtype=float)
    if q.shape != (n,) or not np.all(np.isfinite(q)):
        raise InputError(f"posture guess q0 has shape {q.shape} or non-finite entries; expected {n} finite numbers")
    fixed = dict(fixed or {})
    fixed_idx = []
    for label, value in fixed.items():
        i = robot.coordinate_index(label)
        value = float(value)
        if not np.isfinite(value):
            raise InputError(f"prescribed coordinate {label} = {value}; expected a finite number")
        if abs(float(value)) > MAX_POSITION:
            raise InputError(f"prescribed coordinate {label} = {float(value):g}; expected a magnitude <= "
                             f"{MAX_POSITION:g} m or rad")
        q[i] = value
        fixed_idx.append(i)
    free = np.setdiff1d(np.arange(n), fixed_idx)
    if not np.isfinite(tol) or tol <= 0:
        raise InputError(f"tol = {tol}; expected a positive tolerance")

    def evaluate(qq):
        try:
            return _holonomic(robot, qq)
        except RobotDynError:
            return None

    state = evaluate(q)
    if state is None:
        _holonomic(robot, q)  # re-raise the constraint's own one-line error at the initial guess
    res, A, labels = state
    if res.size == 0:
        return Posture(q, 0.0, 0, [])
    norm = float(np.linalg.norm(res))
    it = 0
    target = 1e-3 * tol  # Newton converges quadratically: aim well below tol, fail only above it
    while np.max(np.abs(res)) > target:
        if it >= max_iter:
            break
        it += 1
        J = A[:, free]
        import scipy.linalg

        step, *_ = scipy.linalg.lstsq(J, -res, cond=1e-12, lapack_driver="gelsd")
        alpha, accepted = 1.0, False
        while alpha > 1e-6:
            trial = q.copy()
            trial[free] += alpha * step
            new = evaluate(trial)
            if new is not None and np.linalg.norm(new[0]) < norm * (1 - 1e-4 * alpha) + 1e-300:
                q, (res, A, labels), norm, accepted = trial, new, float(np.linalg.norm(new[0])), True
                break
            alpha *= 0.5
        if not accepted:
            break  # round-off floor, or a (local) minimum of the residual norm that is not a solution
    worst = int(np.argmax(np.abs(res)))
    if np.abs(res[worst]) > tol:
        raise ConstraintError(
            f"no posture found: residual of {labels[worst]} stays at {res[worst]:.3g} after {it} Newton steps "
            f"(expected |residual| <= {tol:g}); the terrain is out of the suspension's reach at these prescribed "
            "coordinates, or the initial guess is too far from a posture"
        )
    if check_limits:
        lo, hi = robot.description.lower, robot.description.upper
        bad = np.flatnonzero((q < lo - 1e-12) | (q > hi + 1e-12))
        if bad.size:
            i = int(bad[0])
            raise ConstraintError(
                f"the only posture found has {robot.coordinates[i]} = {q[i]:.4g}, outside its joint range "
                f"[{lo[i]:.4g}, {hi[i]:.4g}]: the terrain is out of the suspension's travel at these prescribed "
                "coordinates"
            )
    return Posture(q, float(np.max(np.abs(res))), it, [robot.coordinates[i] for i in free])


__all__ = ["Posture", "solve_posture", "set_terrain"]

"""Rows dropped as redundant, checked: a state must satisfy them too, at the velocity and acceleration level.

The projection (:mod:`robotdyn.reduction.projection`) keeps a maximal set of independent rows of :math:`A(q)` and drops the
others as redundant. A dropped row :math:`a_d` is a combination :math:`a_d = L A_k` of the kept ones *at q*, so any
:math:`v = S\\nu` satisfies it: :math:`a_d v = L A_k v = 0`. Its acceleration condition
:math:`a_d \\dot v + \\dot a_d v = 0` holds as well where the rows are dependent on a whole neighbourhood (rows that
are always redundant, e.g. a planar root's normal rows or two wheels on one rigid axle), since then
:math:`\\dot a_d = \\dot L A_k + L \\dot A_k`. It does **not** hold at a configuration where the rank drops and the
mobility rises (steerable wheels whose axles all meet in one point, e.g. all parallel): there
:math:`\\dot a_d v \\ne L \\dot A_k v` in general, and the accelerations of the reduced model violate the dropped
row (physically: such velocities leave the configurations where the mechanism can move, which would take an
impulsive constraint force). :func:`violations` measures this for a given state, on both evaluation paths (it uses
only the reduced model's ``S``, ``w``, its kept rows and the full rows with :math:`\\dot A`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TOL = 1e-7
"""Relative tolerance of a violation, against the size of the row's terms (:math:`|A||v|`, :math:`|A||a| +
|\\dot A||v|`, plus the largest entry of all rows times :math:`\\|a\\|_1` and :math:`\\|v\\|_1`: a row that vanishes
identically carries rounding at the size of the others), raised to 100 eps times the condition number of the
projection's solve where that is larger (the rounding of :math:`a` itself)."""


@dataclass
class RowViolation:
    """A dropped row that a state violates.

    Attributes:
        label: The row (``wheel.lateral``, ``closure.rz``, ...).
        velocity: :math:`a_d v` (the row's unit: m/s or rad/s).
        acceleration: :math:`a_d \\dot v + \\dot a_d v` (m/s^2 or rad/s^2), or None without accelerations.
    """

    label: str
    velocity: float
    acceleration: float | None = None

    @property
    def unit(self) -> str:
        """The row's unit of length: rad for rotation components of closures, else m (a joint coupling's row has
        its joint's unit)."""
        return "rad" if self.label.rsplit(".", 1)[-1] in ("rx", "ry", "rz") else "m"

    def __str__(self) -> str:
        u = self.unit
        if self.acceleration is None:
            return f"{self.label} by {self.velocity:.3g} {u}/s"
        return f"{self.label} by {self.acceleration:.3g} {u}/s^2 (velocity level: {self.velocity:.3g} {u}/s)"


def dropped_rows(red) -> np.ndarray:
    """The indices of the rows that the reduced model ``red``'s projection dropped as redundant.

    Args:
        red: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` (its ``jacobian_rows`` and
            ``projection.rows``; a projection without ``rows`` kept them all).

    Returns:
        The dropped rows' indices into ``red.jacobian_rows`` (sorted; empty: none dropped).
    """
    m = red.jacobian_rows.A.shape[0]
    kept = np.asarray(getattr(red.projection, "rows", np.arange(m)), dtype=int)
    keep = np.ones(m, dtype=bool)  # np.setdiff1d(np.arange(m), kept) without importing numpy.ma (np.unique)
    keep[kept[(kept >= 0) & (kept < m)]] = False
    return np.flatnonzero(keep)


def violations(red, nudot=None, tol: float = TOL) -> list[RowViolation]:
    """The rows that the reduced model ``red`` dropped as redundant and that its velocity :math:`v = S\\nu`, or its
    accelerations :math:`a = S\\dot\\nu + w` for ``nudot``, violate by more than ``tol`` (relative).

    Rows kept by the projection hold by construction and are not checked. At rest (v = 0) the terms in
    :math:`\\dot A v` vanish, so :math:`\\dot A` (a Python kinematics pass over every constraint) is not computed.

    Args:
        red: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu).
        nudot: Independent accelerations (k,) [m/s^2, rad/s^2] (default ``None``: the velocity level only).
        tol: Relative tolerance (of the row's scale times the velocity or acceleration).

    Returns:
        The :class:`RowViolation` of each violated row (empty: consistent).
    """
    rows = red.jacobian_rows
    dropped = dropped_rows(red)
    if dropped.size == 0:
        return []
    A = rows.A[dropped]
    v = red.v
    condition = float(getattr(red.projection, "condition", 1.0))
    tol = max(tol, 100.0 * np.finfo(float).eps * (condition if np.isfinite(condition) else 1e16))
    vel = A @ v
    size = float(np.abs(rows.A).max())  # rows that vanish identically carry rounding at the size of the others
    vel_scale = np.abs(A) @ np.abs(v) + size * np.abs(v).sum()
    acc = acc_scale = None
    if nudot is not None:
        a = red.S @ np.asarray(nudot, float) + red.w
        if v.any():
            every = red.rows.Adot
            Adot, largest = every[dropped], float(np.abs(every).max())
        else:  # (at rest: the same numbers without Adot, whose terms are all Adot times zeros)
            Adot, largest = np.zeros((dropped.size, v.size)), 0.0
        acc = A @ a + Adot @ v
        acc_scale = (np.abs(A) @ np.abs(a) + np.abs(Adot) @ np.abs(v)
                     + size * np.abs(a).sum() + largest * np.abs(v).sum())
    out = []
    for j, i in enumerate(dropped):
        bad_v = abs(vel[j]) > tol * vel_scale[j]
        bad_a = acc is not None and abs(acc[j]) > tol * acc_scale[j]
        if bad_v or bad_a:
            out.append(RowViolation(rows.labels[i], float(vel[j]), None if acc is None else float(acc[j])))
    return out


def message(found: list[RowViolation]) -> str:
    """One line naming every violated row and by how much.

    Args:
        found: The violations (:func:`violations`), not empty.

    Returns:
        The warning's text.
    """
    return (f"{len(found)} constraint row(s) dropped as redundant at this configuration are violated: "
            f"{'; '.join(map(str, found))}. The mobility changes here (rows dependent only at this configuration, "
            "e.g. steerable wheels all parallel or with axles through one point) and this motion leaves it, which "
            "takes an impulsive constraint force: these accelerations are not a motion of the robot. Choose "
            "velocities that keep the rows dependent, or start away from this configuration")


__all__ = ["RowViolation", "violations", "message", "TOL"]

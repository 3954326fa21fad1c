"""Equations of motion in minimal (independent) velocities.

With :math:`v = S\\nu` and :math:`a = S\\dot\\nu + w` (:math:`w = \\dot S \\nu`, see :mod:`robotdyn.projection`),
D'Alembert's principle (constraint forces do no work on admissible motions) gives

.. math:: M_r \\dot\\nu + C_r \\nu + g_r = B_r \\tau,\\qquad
          M_r = S^T M S,\\; C_r = S^T(M\\dot S + C S),\\; g_r = S^T g,\\; B_r = S^T B,

where :math:`C_r\\nu + g_r = S^T\\,\\mathrm{RNEA}(q, S\\nu, w)` (one RNEA call gives the whole reduced bias) and
:math:`\\dot M_r - 2C_r` is skew-symmetric because Pinocchio's C is Christoffel-consistent.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .actuation import input_matrix
from .constraint import ConstraintRows, KinematicState
from .projection import Projection, project


@dataclass
class ReducedDynamics:
    """The minimal-coordinate model at one state (q, nu).

    Attributes:
        M: :math:`M_r` (k, k) [kg m^2 or kg].
        h: :math:`C_r\\nu + g_r` (k,), the whole bias [N m or N].
        g: :math:`g_r` (k,).
        B: :math:`B_r` (k, n_motors).
        S: (n, k) with v = S nu.
        w: :math:`\\dot S\\nu` (n,), the acceleration offset.
        v: Full velocity :math:`S\\nu` (n,).
        C: :math:`C_r` (k, k), only when requested (else ``None``).
        Sdot: :math:`\\dot S` (n, k), only with C.
        projection: The :class:`~robotdyn.projection.Projection` used.
        jacobian_rows: The stacked constraint rows without their time derivative (A, residual, labels).
        rows: The stacked constraint rows at this state, ``Adot`` included (computed on first access).
    """

    M: np.ndarray
    h: np.ndarray
    g: np.ndarray
    B: np.ndarray
    S: np.ndarray
    w: np.ndarray
    v: np.ndarray
    projection: Projection
    jacobian_rows: ConstraintRows
    C: np.ndarray | None = None
    Sdot: np.ndarray | None = None
    _full_rows: ConstraintRows | Callable[[], ConstraintRows] | None = None

    @property
    def rows(self) -> ConstraintRows:
        """All constraint rows at (q, v), with ``Adot``."""
        if callable(self._full_rows):
            self._full_rows = self._full_rows()
        return self._full_rows

    def __repr__(self) -> str:
        return f"ReducedDynamics(k={self.M.shape[0]}, n={self.S.shape[0]}, motors={self.B.shape[1]})"


def reduce(robot, q: np.ndarray, nu: np.ndarray, coriolis: bool = False, independent=None) -> ReducedDynamics:
    """Evaluate the reduced model of ``robot`` at (q, nu).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,), already validated.
        nu: Independent velocities (k,).
        coriolis: Also build the matrix :math:`C_r` (costs a Coriolis matrix and :math:`\\dot S`).
        independent: Override of the independent velocity indices.
    """
    model, data = robot.model, robot.data
    ind = robot.independent_indices if independent is None else independent
    kin0 = KinematicState(model, data, q, np.zeros(model.nv))
    rows0 = ConstraintRows.stack([c.jacobian(kin0) for c in robot.constraints], model.nv)
    proj = project(rows0.A, ind, robot.velocity_labels, hint=robot._projection_hint)
    robot._projection_hint = proj
    v = proj.S @ nu
    kin = kin0.with_velocity(v)
    drift = np.concatenate([c.drift(kin) for c in robot.constraints]) if robot.constraints else np.zeros(0)
    B = input_matrix(robot.motors, kin)
    w = proj.offset(drift)
    S = proj.S
    full_rows = lambda: robot.constraint_rows(kin)  # noqa: E731  (frames it needs are cached in kin)
    if coriolis:
        full_rows = full_rows()
    M = pin.crba(model, data, q)
    Mr = S.T @ M @ S
    g = pin.computeGeneralizedGravity(model, data, q)
    h = S.T @ pin.rnea(model, data, q, v, w)
    out = ReducedDynamics(Mr, h, S.T @ g, S.T @ B, S, w, v, proj, rows0, _full_rows=full_rows)
    if coriolis:
        Sdot = proj.Sdot(full_rows.Adot)
        C = pin.computeCoriolisMatrix(model, data, q, v)
        out.C = S.T @ (M @ Sdot + C @ S)
        out.Sdot = Sdot
    return out

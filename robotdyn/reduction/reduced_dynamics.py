"""Equations of motion in minimal (independent) velocities.

With :math:`v = S\\nu` and :math:`a = S\\dot\\nu + w` (:math:`w = \\dot S \\nu`, see :mod:`robotdyn.reduction.projection`),
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

from ..errors import InputError, NonFiniteError
from ..inputs import all_finite
from .actuation import input_matrix
from ..constraints.constraint import ConstraintRows, KinematicState
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
        projection: The :class:`~robotdyn.reduction.projection.Projection` used.
        jacobian_rows: The stacked constraint rows without their time derivative (A, residual, labels).

    The property :attr:`rows` gives the stacked constraint rows with ``Adot`` (computed on first access).
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


class ConstraintSet:
    """A robot's constraints evaluated together: each constraint's own
    :meth:`~robotdyn.constraints.constraint.Constraint.jacobian` and
    :meth:`~robotdyn.constraints.constraint.Constraint.drift` (the reference formulas of
    :mod:`robotdyn.constraints`), rows stacked in the order of ``constraints``.

    Args:
        constraints: The constraints, in row order.
        nv: Number of velocities.
    """

    def __init__(self, constraints, nv: int) -> None:
        self.constraints = tuple(constraints)
        self.nv = nv

    def current(self, constraints) -> bool:
        """Whether this set still describes ``constraints`` (the same objects in the same order; a constraint
        changed in place, e.g. by :func:`robotdyn.constraints.posture.set_terrain`, evaluates with its new
        attributes).

        Args:
            constraints: The robot's current constraint objects.

        Returns:
            ``True`` if the set is up to date.
        """
        return len(constraints) == len(self.constraints) and all(
            a is b for a, b in zip(constraints, self.constraints))

    def jacobian(self, kin: KinematicState) -> ConstraintRows:
        """All rows without their time derivative, stacked in constraint order.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            The stacked :class:`~robotdyn.constraints.constraint.ConstraintRows` (m, nv).
        """
        parts = [c.jacobian(kin) for c in self.constraints]
        return ConstraintRows.stack(parts, self.nv) if len(parts) != 1 else parts[0]

    def drift(self, kin: KinematicState) -> np.ndarray:
        """All drift terms :math:`\\dot A v`, stacked in constraint order.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            The drift (m,), in row order.
        """
        with np.errstate(over="ignore", invalid="ignore"):  # beyond double precision: refused by checked, in one line
            parts = [c.drift(kin) for c in self.constraints]
        if not parts:
            return np.zeros(0)
        return np.concatenate(parts) if len(parts) != 1 else parts[0]


def constraint_set(robot) -> ConstraintSet:
    """The robot's :class:`ConstraintSet` (built once, rebuilt if ``robot.constraints`` was changed).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The :class:`ConstraintSet`.
    """
    cset = getattr(robot, "_constraint_set", None)
    if cset is None or not cset.current(robot.constraints):
        cset = ConstraintSet(robot.constraints, robot.model.nv)
        robot._constraint_set = cset
    return cset


def _project_at(robot, q: np.ndarray, independent) -> tuple[KinematicState, ConstraintRows, Projection]:
    """Kinematics at rest, the stacked rows without their derivative and the projection at q (the projection
    becomes the robot's hint for the next state)."""
    model = robot.model
    kin0 = KinematicState(model, robot.data, q, np.zeros(model.nv))
    rows0 = constraint_set(robot).jacobian(kin0)
    proj = project(rows0.A, independent, robot.velocity_labels, hint=robot._projection_hint)
    robot._projection_hint = proj
    return kin0, rows0, proj


def velocity(robot, q: np.ndarray, nu: np.ndarray) -> tuple[np.ndarray, ConstraintRows]:
    """Only :math:`v = S(q)\\nu` and the constraint rows at q (one kinematics pass, no dynamics): the same ``v`` and
    ``jacobian_rows`` as :func:`reduce` (or the robot's operational reduction) at a fraction of the cost.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.

    Returns:
        ``(v, rows)``: the full velocities (nv,) and the :class:`~robotdyn.constraints.constraint.ConstraintRows` at q.
    """
    if getattr(robot, "operational", None) is not None:
        red = robot.reduced(q, nu)
        return red.v, red.jacobian_rows
    _, rows0, proj = _project_at(robot, q, robot.independent_indices)
    return proj.S @ np.asarray(nu, float), rows0


def assemble(robot, q: np.ndarray, proj, rows0: ConstraintRows, v: np.ndarray, w: np.ndarray, B: np.ndarray,
             coriolis: bool, sdot: Callable[[np.ndarray], np.ndarray]) -> ReducedDynamics:
    """The dynamics shared by every reduction, once S, v = S nu, w and B are known:
    :math:`M_r = S^TMS`, :math:`C_r\\nu + g_r = S^T\\,\\mathrm{RNEA}(q, v, w)`, :math:`g_r`, :math:`B_r`, and with
    ``coriolis`` :math:`C_r = S^T(M\\dot S + CS)`, :math:`\\dot S` = ``sdot(Adot)``.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        proj: The projection (S and what differentiates it).
        rows0: The constraint rows at q (without dA/dt).
        v: Full velocity S nu (n,).
        w: The acceleration offset dS/dt nu (n,).
        B: The full input matrix (n, motors).
        coriolis: Also compute the matrix C_r (k, k) and dS/dt (default: only the bias h = C_r nu + g_r).
        sdot: ``sdot(Adot)`` -> dS/dt (n, k), called only with ``coriolis``.

    Returns:
        The :class:`ReducedDynamics`.
    """
    model, data = robot.model, robot.data
    S = proj.S
    # all rows with Adot, on first access: a fresh kinematics pass, since data may hold another state by then
    full_rows = lambda: robot.constraint_rows(KinematicState(model, data, q, v))  # noqa: E731
    if coriolis:
        full_rows = full_rows()
    M = pin.crba(model, data, q)
    g = pin.computeGeneralizedGravity(model, data, q)
    h = S.T @ pin.rnea(model, data, q, v, w)
    out = ReducedDynamics(S.T @ M @ S, h, S.T @ g, S.T @ B, S, w, v, proj, rows0, _full_rows=full_rows)
    if coriolis:
        Sdot = sdot(full_rows.Adot)
        C = pin.computeCoriolisMatrix(model, data, q, v)
        out.C = S.T @ (M @ Sdot + C @ S)
        out.Sdot = Sdot
    return out


def reduce(robot, q: np.ndarray, nu: np.ndarray, coriolis: bool = False, independent=None) -> ReducedDynamics:
    """Evaluate the reduced model of ``robot`` at (q, nu) in Python: the reference of the compiled fast path
    (:mod:`robotdyn.fast`; :func:`robotdyn.fast.dispatch.reduce` chooses between the two).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,), already validated.
        nu: Independent velocities (k,).
        coriolis: Also build the matrix :math:`C_r` (costs a Coriolis matrix and :math:`\\dot S`).
        independent: Override of the independent velocity indices.

    Returns:
        The :class:`ReducedDynamics` at (q, nu).
    """
    ind = robot.independent_indices if independent is None else independent
    kin0, rows0, proj = _project_at(robot, q, ind)
    v = proj.S @ nu
    kin = kin0.with_velocity(v)
    drift = constraint_set(robot).drift(kin)
    B = input_matrix(robot.motors, kin)
    return assemble(robot, q, proj, rows0, v, proj.offset(drift), B, coriolis, proj.Sdot)


def solve_mass(M: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:math:`M^{-1} b` for a reduced mass matrix, which must be positive definite (Cholesky); else a one-line
    :class:`~robotdyn.errors.InputError` naming the likely cause.

    Args:
        M: A reduced mass matrix (k, k), symmetric positive definite.
        b: The right-hand side (k,) or (k, p).

    Returns:
        :math:`M^{-1} b`, shaped like b.
    """
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        eig = np.linalg.eigvalsh(M) if np.all(np.isfinite(M)) else np.array([np.nan])
        raise InputError(f"the reduced mass matrix is not positive definite (smallest eigenvalue {eig.min():.3g}): "
                         "massless or zero-inertia bodies move freely; expected positive masses and inertias"
                         ) from None
    return np.linalg.solve(L.T, np.linalg.solve(L, b))


def reference(robot, q: np.ndarray, nu: np.ndarray, coriolis: bool = False, independent=None) -> ReducedDynamics:
    """The Python reference of the robot's reduced model: :func:`reduce`, or the robot's operational reduction
    (``robot.operational.reduce``) where its independent velocities are a frame twist.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.
        coriolis: Also compute the matrix C_r (k, k) and dS/dt (default: only the bias h = C_r nu + g_r).
        independent: Indices of the independent velocities in v (default ``None``: the robot's).

    Returns:
        The :class:`ReducedDynamics` at (q, nu).
    """
    op = getattr(robot, "operational", None)
    if op is not None:
        return op.reduce(robot, q, nu, coriolis)
    return reduce(robot, q, nu, coriolis, independent)


def checked(out: ReducedDynamics, q, nu) -> ReducedDynamics:
    """``out``, after checking that its M, h and w are finite.

    Args:
        out: The reduced model to check.
        q: Its configuration (for the message).
        nu: Its independent velocities (for the message).

    Returns:
        ``out`` unchanged.

    Raises:
        NonFiniteError: They are not (a state beyond what double precision holds).
    """
    if not all_finite((out.M, out.h, out.w)):
        raise NonFiniteError(f"the reduced model at this state is not finite (|q| up to "
                             f"{np.max(np.abs(q)):.3g}, |nu| up to {np.max(np.abs(nu), initial=0):.3g}): the "
                             "state is beyond what double precision holds")
    return out

"""Holonomic coupling between two one-degree-of-freedom joints: :math:`q_d = f(q_r)`.

A mechanism that sets one joint coordinate as a function of another (a gear, a cam, a linkage reduced to its
input-output law) is one holonomic row acting on Pinocchio's velocity vector (natural coordinates,
:math:`\\dot q = v`):

- residual :math:`\\phi(q) = q_d - f(q_r)` [unit of :math:`q_d`];
- Jacobian row :math:`A = e_d^T - f'(q_r)\\, e_r^T`, so :math:`A v = \\dot q_d - f'(q_r)\\dot q_r = \\dot\\phi`;
- its time derivative :math:`\\dot A = -f''(q_r)\\, \\dot q_r\\, e_r^T`, so the drift is
  :math:`\\dot A v = -f''(q_r)\\dot q_r^2`.

The law and its first two derivatives are supplied by the caller (they are not differentiated numerically).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .constraint import Constraint, ConstraintRows, KinematicState
from ..errors import DescriptionError

Law = Callable[[float], float]


@dataclass(frozen=True)
class CosineLaw:
    """The law :math:`f(q) = a\\cos(b q + c) + d` with its exact derivatives (a law given as data, which the compiled
    path of :mod:`robotdyn.fast.compiled` evaluates too; any other callable keeps a robot on the Python path).

    Attributes:
        amplitude: a [unit of the driven joint: m or rad].
        rate: b [1/unit of the driver].
        phase: c [rad].
        offset: d [unit of the driven joint].
    """

    amplitude: float
    rate: float
    phase: float = 0.0
    offset: float = 0.0

    def __call__(self, q: float) -> float:
        return self.amplitude * math.cos(self.rate * q + self.phase) + self.offset

    def d(self, q: float) -> float:
        """:math:`f'(q) = -ab\\sin(bq + c)`.

        Args:
            q: The driver's coordinate [m or rad].

        Returns:
            The derivative [unit of the driven joint per unit of the driver].
        """
        return -self.amplitude * self.rate * math.sin(self.rate * q + self.phase)

    def dd(self, q: float) -> float:
        """:math:`f''(q) = -ab^2\\cos(bq + c)`.

        Args:
            q: The driver's coordinate [m or rad].

        Returns:
            The second derivative.
        """
        return -self.amplitude * self.rate * self.rate * math.cos(self.rate * q + self.phase)


class JointCoupling(Constraint):
    """The holonomic constraint :math:`q_{\\text{driven}} = f(q_{\\text{driver}})` (one row).

    Args:
        description: The robot's :class:`~robotdyn.description.urdf.Description`.
        driven: Joint whose coordinate is set by the law (:math:`q_d`).
        driver: Joint whose coordinate is the law's argument (:math:`q_r`).
        law: :math:`f`, a callable of a float (the driver's coordinate) returning the driven one.
        dlaw: :math:`f'` (default ``None``: a :class:`CosineLaw`'s own; required for other laws).
        ddlaw: :math:`f''` (default ``None``: a :class:`CosineLaw`'s own; required for other laws).
        name: Name used in the row label (default ``"driven=f(driver)"``).

    Raises:
        DescriptionError: The same joint twice, or a law that is not callable.
    """

    def __init__(
        self, description, driven: str, driver: str, law: Law, dlaw: Law | None = None, ddlaw: Law | None = None,
        name: str | None = None,
    ) -> None:
        if isinstance(law, CosineLaw):
            dlaw = law.d if dlaw is None else dlaw
            ddlaw = law.dd if ddlaw is None else ddlaw
        if driven == driver:
            raise DescriptionError(f"joint coupling: driven and driver are both {driven!r}; expected two joints")
        for f, what in ((law, "law"), (dlaw, "dlaw"), (ddlaw, "ddlaw")):
            if not callable(f):
                raise DescriptionError(f"joint coupling {driven!r}: {what} is not callable; expected f(q) -> float")
        self.driven, self.driver = driven, driver
        self.i = description.q_index(driven)
        self.j = description.q_index(driver)
        self.nv = description.model.nv
        self.law, self.dlaw, self.ddlaw = law, dlaw, ddlaw
        self.name = name or f"{driven}=f({driver})"

    def __repr__(self) -> str:
        return f"JointCoupling(driven={self.driven!r}, driver={self.driver!r})"

    def residual(self, q: np.ndarray) -> float:
        """:math:`\\phi = q_d - f(q_r)` at configuration q.

        Args:
            q: Natural coordinates (n,) [m, rad].

        Returns:
            The residual [unit of the driven joint].
        """
        return float(q[self.i] - self.law(float(q[self.j])))

    def rows(self, kin: KinematicState) -> ConstraintRows:
        """The row :math:`\\dot q_d - f'(q_r)\\dot q_r = 0` with its time derivative and residual.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The :class:`~robotdyn.constraints.constraint.ConstraintRows` (one holonomic row).
        """
        qr, vr = float(kin.q[self.j]), float(kin.v[self.j])
        A = np.zeros((1, self.nv))
        A[0, self.i] = 1.0
        A[0, self.j] -= float(self.dlaw(qr))
        Adot = np.zeros((1, self.nv))
        Adot[0, self.j] = -float(self.ddlaw(qr)) * vr
        residual = np.array([self.residual(kin.q)])
        return ConstraintRows(A, Adot, residual, np.ones(1, bool), [f"{self.name}.coupling"])

    def jacobian(self, kin: KinematicState) -> ConstraintRows:
        """The row and residual without :math:`\\dot A` (the law's second derivative is not evaluated).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The :class:`~robotdyn.constraints.constraint.ConstraintRows`.
        """
        A = np.zeros((1, self.nv))
        A[0, self.i] = 1.0
        A[0, self.j] -= float(self.dlaw(float(kin.q[self.j])))
        return ConstraintRows(A, None, np.array([self.residual(kin.q)]), np.ones(1, bool), [f"{self.name}.coupling"])

    def drift(self, kin: KinematicState) -> np.ndarray:
        """:math:`\\dot A v = -f''(q_r)\\dot q_r^2`.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The drift (1,).
        """
        vr = float(kin.v[self.j])
        return np.array([-float(self.ddlaw(float(kin.q[self.j]))) * vr * vr])

    def solve_driven(self, q: np.ndarray) -> np.ndarray:
        """A copy of q with the driven coordinate set so that the residual vanishes (exact: the law is explicit).

        Args:
            q: Natural coordinates (n,) [m, rad].

        Returns:
            The corrected copy (n,).
        """
        out = np.array(q, dtype=float)
        out[self.i] = self.law(float(out[self.j]))
        return out

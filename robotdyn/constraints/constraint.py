"""Constraint interface and the shared kinematics evaluation.

A constraint contributes rows to the Pfaffian system :math:`A(q) v = 0` and their time derivative
:math:`\\dot A(q, v)`, so that accelerations satisfy :math:`A a + \\dot A v = 0` (the drift term is
:math:`\\dot A v`). Holonomic rows also give a position residual :math:`\\phi(q)` whose gradient they are (on the
constraint manifold). All rows act on Pinocchio's velocity vector; with robotdyn's natural coordinates
:math:`\\dot q = v`.

The kinematics (frame placements, LOCAL_WORLD_ALIGNED frame Jacobians and their time variation) is computed once
per state by :class:`KinematicState` and shared by every constraint, motor and the projection.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def skew(x: np.ndarray) -> np.ndarray:
    """:math:`[x]_\\times`, the 3x3 matrix with :math:`[x]_\\times y = x \\times y`.

    Args:
        x: A 3-vector.

    Returns:
        The skew-symmetric 3x3 matrix.
    """
    return np.array([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The cross product of two 3-vectors (cheaper than ``np.cross`` on 3-vectors).

    Args:
        a: A 3-vector.
        b: A 3-vector.

    Returns:
        a x b (3,).
    """
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


class KinematicState:
    """Kinematics of a model at one state (q, v), computed once.

    Runs ``computeJointJacobiansTimeVariation`` (placements, Jacobians and their time derivative) and
    ``updateFramePlacements``. Frame quantities are cached per frame; ``geometry`` is a cache for
    configuration-only quantities of constraints (e.g. a wheel's contact point), which
    :meth:`with_velocity` carries over to the same configuration at another velocity.

    Args:
        model: The Pinocchio model (natural coordinates: nq == nv).
        data: Its data, overwritten (one per thread).
        q: Natural coordinates (nq,) [m, rad].
        v: Velocities (nv,) [m/s, rad/s].

    Attributes:
        q, v: The state (natural coordinates, velocities), copied.
        geometry: Configuration-level cache, keyed by the constraint.
    """

    def __init__(self, model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> None:
        self.model, self.data = model, data
        self.q = np.array(q, dtype=float)
        self.v = np.array(v, dtype=float)
        self._moving = bool(self.v.any())
        if self._moving:
            pin.computeJointJacobiansTimeVariation(model, data, self.q, self.v)
        else:  # at rest the time variation is zero: plain Jacobians are enough
            pin.computeJointJacobians(model, data, self.q)
        pin.updateFramePlacements(model, data)
        self._poses: dict[int, tuple[pin.SE3, np.ndarray]] = {}
        self._frames: dict[int, tuple[pin.SE3, np.ndarray, np.ndarray]] = {}
        self.geometry: dict = {}

    def with_velocity(self, v: np.ndarray) -> KinematicState:
        """The same configuration at velocity ``v`` (recomputes the Jacobians' time variation, keeps the
        configuration-level caches: frame placements, Jacobians and :attr:`geometry`).

        Args:
            v: Velocities (nv,) [m/s, rad/s].

        Returns:
            A new :class:`KinematicState`.
        """
        out = KinematicState(self.model, self.data, self.q, v)
        out._poses = self._poses
        out.geometry = self.geometry
        return out

    def pose(self, fid: int) -> tuple[pin.SE3, np.ndarray]:
        """Placement and LOCAL_WORLD_ALIGNED Jacobian (6 x nv) of a frame (configuration-level, cached).

        Args:
            fid: The Pinocchio frame id.

        Returns:
            ``(placement, J)``: the frame's ``pin.SE3`` in the world and its Jacobian (6 x nv; rows: linear velocity
            of the frame origin [m/s], then angular velocity [rad/s], world axes).
        """
        if fid not in self._poses:
            self._poses[fid] = (
                self.data.oMf[fid].copy(),
                pin.getFrameJacobian(self.model, self.data, fid, LWA).copy(),
            )
        return self._poses[fid]

    def frame(self, fid: int) -> tuple[pin.SE3, np.ndarray, np.ndarray]:
        """Placement, Jacobian (6 x nv) and its time derivative for a frame, in LOCAL_WORLD_ALIGNED.

        The Jacobian's first three rows give the classical velocity of the frame origin in world axes [m/s],
        the last three the angular velocity [rad/s]; :math:`\\dot J v` is the classical acceleration at
        :math:`\\dot v = 0`.

        Args:
            fid: The Pinocchio frame id.

        Returns:
            ``(placement, J, Jdot)``.
        """
        if fid not in self._frames:
            placement, jac = self.pose(fid)
            if self._moving:
                djac = pin.getFrameJacobianTimeVariation(self.model, self.data, fid, LWA).copy()
            else:
                djac = np.zeros_like(jac)
            self._frames[fid] = (placement, jac, djac)
        return self._frames[fid]

    def joint_axis(self, jid: int) -> np.ndarray:
        """World direction of a one-degree-of-freedom joint's axis (its own Jacobian column).

        Args:
            jid: The Pinocchio joint id (a revolute or prismatic joint).

        Returns:
            The axis (3,) in world axes (the angular column for a revolute joint, the linear one for a prismatic).
        """
        jac = pin.getJointJacobian(self.model, self.data, jid, LWA)
        col = self.model.joints[jid].idx_v
        ang = jac[3:, col]
        return ang if np.linalg.norm(ang) > 0.5 else jac[:3, col]


@dataclass
class ConstraintRows:
    """Rows contributed by constraints at one state.

    Attributes:
        A: Constraint Jacobian, shape (k, nv).
        Adot: Its time derivative along the motion, shape (k, nv); the drift term is ``Adot @ v``
            (``None`` when only the Jacobian was asked for).
        residual: Position residual of holonomic rows (0 on nonholonomic rows), shape (k,).
        holonomic: Which rows are holonomic, shape (k,).
        labels: A name for each row (constraint name and component).
    """

    A: np.ndarray
    Adot: np.ndarray | None
    residual: np.ndarray
    holonomic: np.ndarray
    labels: list[str]

    @staticmethod
    def stack(parts: list[ConstraintRows], nv: int) -> ConstraintRows:
        """Stack the rows of several constraints (an empty list gives zero rows).

        Args:
            parts: The constraints' rows, in order.
            nv: Number of velocities (columns), for the empty case.

        Returns:
            One :class:`ConstraintRows` (``Adot`` is ``None`` if any part's is).
        """
        if not parts:
            return ConstraintRows(np.zeros((0, nv)), np.zeros((0, nv)), np.zeros(0), np.zeros(0, bool), [])
        return ConstraintRows(
            np.vstack([p.A for p in parts]),
            None if any(p.Adot is None for p in parts) else np.vstack([p.Adot for p in parts]),
            np.concatenate([p.residual for p in parts]),
            np.concatenate([p.holonomic for p in parts]),
            [label for p in parts for label in p.labels],
        )


class Constraint:
    """Base class of constraints (rolling contacts, loop closures, ...).

    Subclasses implement :meth:`rows`. ``name`` identifies the constraint in messages.
    """

    name: str = "constraint"

    def rows(self, kin: KinematicState) -> ConstraintRows:
        """The constraint's rows at the state held by ``kin`` (A, Adot, residual, ...).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The :class:`ConstraintRows` (A and Adot: rows x nv; residual [m or rad] of the holonomic rows).
        """
        raise NotImplementedError

    def jacobian(self, kin: KinematicState) -> ConstraintRows:
        """The rows without their time derivative (``Adot`` may be ``None``); only the configuration matters.
        Subclasses override it when that is cheaper than :meth:`rows`.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The :class:`ConstraintRows`.
        """
        return self.rows(kin)

    def drift(self, kin: KinematicState) -> np.ndarray:
        """The drift term :math:`\\dot A v` at the state of ``kin``. Subclasses override it when a vector
        formula is cheaper than the matrix :math:`\\dot A`.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            One value per row [m/s^2 or rad/s^2].
        """
        return self.rows(kin).Adot @ kin.v

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"

"""Operational-space reduction: minimal velocities that are a body twist, not a subset of the joint velocities.

The core projection (:mod:`robotdyn.reduction.projection`) takes independent velocities as a selection of the entries of
v. Here the independent velocities are instead linear functions of v, :math:`\\nu = J_o(q) v`, e.g. the twist
components of a frame in its own (body) axes -- the output velocity :math:`\\dot u` of a parallel/mobile robot.
With the independent rows :math:`A_r` of the constraint Jacobian (redundant rows removed by rank-revealing QR,
:func:`robotdyn.reduction.projection.independent_rows`) the square matrix

.. math:: K(q) = \\begin{bmatrix} A_r \\\\ J_o \\end{bmatrix},\\qquad K S = \\begin{bmatrix} 0 \\\\ I \\end{bmatrix}

gives :math:`v = S\\nu` with :math:`A S = 0` and :math:`J_o S = I`. Differentiating :math:`A v = 0` and
:math:`\\nu = J_o v`: :math:`a = S\\dot\\nu + w` with :math:`K w = -[\\dot A_r v;\\, \\dot J_o v]`, and
:math:`\\dot S = -K^{-1} \\dot K S`. The reduced equations are then those of
:mod:`robotdyn.reduction.reduced_dynamics` (:math:`M_r = S^T M S`, bias :math:`S^T\\,\\mathrm{RNEA}(q, S\\nu, w)`), i.e. the
operational-space inertia and bias in the sense of Freeman and Tesar's transfer method: :math:`M_r` is the
inertia seen by a generalised force :math:`T_u` doing power :math:`T_u\\cdot\\nu`.

K is singular only when the chosen output twist does not determine the mechanism's velocities (a genuine
singularity of the output); this is independent of which joints one would call "independent". The condition
number of K is reported and a singular K raises :class:`~robotdyn.errors.SingularConstraintError`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .actuation import input_matrix
from ..constraints.constraint import KinematicState
from ..errors import DescriptionError, InputError, SingularConstraintError
from .projection import MAX_CONDITION, independent_rows, inverse_and_condition
from .reduced_dynamics import ReducedDynamics, assemble, constraint_set

COMPONENTS = ("vx", "vy", "vz", "wx", "wy", "wz")
"""Twist components: linear velocity of the frame origin, then angular velocity."""


class FrameTwist:
    """Selected components of a frame's twist, in the frame's own axes (``"local"``) or world axes (``"world"``).

    Args:
        description: The robot's :class:`~robotdyn.description.urdf.Description`.
        frame: Frame (link) whose origin velocity and angular velocity are taken.
        components: Subset of ``vx vy vz wx wy wz`` (m/s, rad/s).
        axes: ``"local"`` (body axes: Pinocchio LOCAL) or ``"world"`` (LOCAL_WORLD_ALIGNED).
        names: Display names of the components (default ``<frame>.<component>``).
    """

    def __init__(self, description, frame: str, components=("vx", "vy", "wz"), axes: str = "local",
                 names: list[str] | None = None) -> None:
        self.frame = frame
        self.fid = description.frame_id(frame)
        bad = [c for c in components if c not in COMPONENTS]
        if bad or not components:
            raise DescriptionError(f"twist components {list(components)}; expected a subset of {' '.join(COMPONENTS)}")
        if axes not in ("local", "world"):
            raise DescriptionError(f"twist axes {axes!r}; expected 'local' or 'world'")
        self.components = tuple(components)
        self.select = np.array([COMPONENTS.index(c) for c in components])
        self.axes = axes
        self.reference = pin.ReferenceFrame.LOCAL if axes == "local" else pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        self.names = list(names) if names is not None else [f"{frame}.{c}" for c in components]
        if len(self.names) != len(self.components):
            raise DescriptionError(f"{len(self.names)} names for {len(self.components)} twist components")

    def __repr__(self) -> str:
        return f"FrameTwist(frame={self.frame!r}, components={list(self.components)}, axes={self.axes!r})"

    def rows(self, kin: KinematicState) -> tuple[np.ndarray, np.ndarray]:
        """:math:`J_o` (k, n) and its time derivative :math:`\\dot J_o` (k, n) at the state of ``kin``.

        ``kin`` must be the most recent kinematics pass on its data (its constructor ran
        ``computeJointJacobiansTimeVariation``), so that Pinocchio's frame Jacobian and its time variation refer to
        (kin.q, kin.v). In LOCAL axes :math:`\\dot J v` is the spatial acceleration's linear part, which is the time
        derivative of the body-axes velocity components (not the body components of the classical acceleration).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            ``(J_o, Jdot_o)``, each (k, n).
        """
        J = self.jacobian(kin)
        if not np.any(kin.v):  # at rest the time variation is zero (and kin may not have computed it)
            return J, np.zeros_like(J)
        dJ = pin.getFrameJacobianTimeVariation(kin.model, kin.data, self.fid, self.reference)
        return J, dJ[self.select].copy()

    def jacobian(self, kin: KinematicState) -> np.ndarray:
        """:math:`J_o` (k, n) at the configuration of ``kin`` (the most recent kinematics pass on its data).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            :math:`J_o` (k, n), a copy.
        """
        return pin.getFrameJacobian(kin.model, kin.data, self.fid, self.reference)[self.select].copy()


@dataclass
class OperationalProjection:
    """:math:`S(q)` of the operational reduction and what is needed to differentiate it.

    Attributes:
        S: (n, k) with :math:`v = S\\nu`, :math:`AS = 0`, :math:`J_oS = I`.
        rows: Indices of the independent constraint rows used.
        condition: 1-norm condition number of :math:`K = [A_r; J_o]`.
    """

    S: np.ndarray
    rows: np.ndarray
    condition: float
    _inv: np.ndarray = field(repr=False, default=None)

    @property
    def mobility(self) -> int:
        return int(self.S.shape[1])

    def offset(self, drift: np.ndarray, Jdot_v: np.ndarray) -> np.ndarray:
        """:math:`w` with :math:`A w = -\\text{drift}` (drift = :math:`\\dot A v`) and :math:`J_o w = -\\dot J_o v`.

        Args:
            drift: The constraints' drift terms dA/dt v (all rows).
            Jdot_v: dJ_o/dt v (k,), the outputs' drift.

        Returns:
            w (n,), in the model's velocity order.
        """
        return -self._inv @ np.concatenate([drift[self.rows], Jdot_v])

    def Sdot(self, Adot: np.ndarray, Jdot: np.ndarray) -> np.ndarray:
        """:math:`\\dot S = -K^{-1}\\dot K S` (n, k).

        Args:
            Adot: dA/dt (all rows x n) along the motion.
            Jdot: dJ_o/dt (k, n) along the motion.

        Returns:
            :math:`\\dot S` (n, k).
        """
        return -self._inv @ np.vstack([Adot[self.rows] @ self.S, Jdot @ self.S])


def project_operational(A: np.ndarray, J: np.ndarray, names: list[str] | None = None) -> OperationalProjection:
    """Build :math:`S` for constraint rows ``A`` (m, n) and output rows ``J`` (k, n).

    Args:
        A: Constraint Jacobian (m, n) (all rows; the independent ones are chosen here).
        J: Output Jacobian J_o (k, n): nu = J_o v.
        names: Names of the k outputs, for messages (default ``None``: nu0, nu1, ...).

    Returns:
        The :class:`OperationalProjection` (S, rows used, condition number).

    Raises:
        SingularConstraintError: k differs from the mobility n - rank(A), or K is singular / ill-conditioned
            (the outputs do not determine the motion here).
    """
    n = A.shape[1]
    k = J.shape[0]
    names = names or [f"nu{i}" for i in range(k)]
    rows = independent_rows(A)
    if rows.size + k != n:
        raise SingularConstraintError(
            f"{k} operational velocities ({', '.join(names)}) but the constraints leave {n - rows.size} "
            f"(n = {n}, rank A = {rows.size}); expected exactly the mobility"
        )
    Kinv, cond = inverse_and_condition(np.vstack([A[rows], J]))
    if not np.isfinite(cond) or cond > MAX_CONDITION:
        raise SingularConstraintError(
            f"the operational velocities ({', '.join(names)}) do not determine the motion here: [A; J] singular "
            f"(condition number {cond:.3g})",
            condition=cond,
        )
    return OperationalProjection(Kinv[:, rows.size:].copy(), rows, cond, Kinv)


def operational_projection(robot, twist: FrameTwist, q: np.ndarray) -> OperationalProjection:
    """Only the projection (S, condition) at configuration q: one kinematics pass, no dynamics.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        twist: The :class:`FrameTwist` whose components are the independent velocities.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.

    Returns:
        The :class:`OperationalProjection` at q.
    """
    kin = KinematicState(robot.model, robot.data, np.asarray(q, float), np.zeros(robot.model.nv))
    J = twist.jacobian(kin)
    A = constraint_set(robot).jacobian(kin).A
    return project_operational(A, J, twist.names)


def reduce_operational(robot, twist: FrameTwist, q: np.ndarray, nu: np.ndarray,
                       coriolis: bool = False) -> ReducedDynamics:
    """The reduced model of ``robot`` in operational velocities ``nu = J_o v`` at (q, nu).

    The Python reference (the compiled path: :func:`robotdyn.fast.dispatch.reduce`). Same content as
    :func:`robotdyn.reduction.reduced_dynamics.reduce` (``M`` = operational-space inertia,
    ``h`` = :math:`C_r\\nu + g_r`, ``B`` = :math:`S^T B`, ...), with ``projection`` an
    :class:`OperationalProjection`.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        twist: The :class:`FrameTwist` whose components are the independent velocities.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        nu: The twist components (k,) [m/s, rad/s], in the twist's axes and order.
        coriolis: Also compute the matrix C_r (k, k) and dS/dt (default: only the bias h = C_r nu + g_r).

    Returns:
        The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu) in operational velocities.
    """
    model, data = robot.model, robot.data
    q = np.asarray(q, float)
    nu = np.asarray(nu, float)
    kin0 = KinematicState(model, data, q, np.zeros(model.nv))
    rows0 = constraint_set(robot).jacobian(kin0)
    J = twist.jacobian(kin0)
    proj = project_operational(rows0.A, J, twist.names)
    S = proj.S
    v = S @ nu
    kin = kin0.with_velocity(v)
    _, Jdot = twist.rows(kin)  # before the constraints touch the shared data
    drift = constraint_set(robot).drift(kin)
    B = input_matrix(robot.motors, kin)
    w = proj.offset(drift, Jdot @ v)
    return assemble(robot, q, proj, rows0, v, w, B, coriolis, lambda Adot: proj.Sdot(Adot, Jdot))


@dataclass
class OperationalVelocities:
    """Declarative choice of operational minimal velocities for a :class:`~robotdyn.robot.RobotSpec`.

    Attributes:
        frame: The frame whose twist components are the independent velocities.
        components: Which components (``vx vy vz wx wy wz``).
        axes: ``"local"`` (body axes) or ``"world"``.
        names: Display names (default ``<frame>.<component>``).
    """

    frame: str
    components: tuple[str, ...] = ("vx", "vy", "wz")
    axes: str = "local"
    names: list[str] | None = None

    def build(self, description) -> OperationalModel:
        """The built :class:`OperationalModel` (the twist of ``frame`` in the robot's model).

        Args:
            description: The robot's :class:`~robotdyn.description.urdf.Description`.

        Returns:
            The :class:`OperationalModel`.
        """
        return OperationalModel(FrameTwist(description, self.frame, self.components, self.axes, self.names))


class OperationalModel:
    """A built :class:`OperationalVelocities`: names and ``reduce(robot, q, nu, coriolis)``.

    Args:
        twist: The built :class:`FrameTwist`.
    """

    def __init__(self, twist: FrameTwist) -> None:
        self.twist = twist
        self.names = list(twist.names)

    def __repr__(self) -> str:
        return f"OperationalModel({self.twist!r})"

    def projection(self, robot, q) -> OperationalProjection:
        """S(q) only (cheaper than :meth:`reduce` when no dynamics is needed, e.g. kinematic integration).

        Args:
            robot: The :class:`~robotdyn.robot.Robot`.
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.

        Returns:
            The :class:`OperationalProjection` at q.
        """
        return operational_projection(robot, self.twist, q)

    def check(self, nu) -> None:
        """Raises InputError unless ``nu`` has one value per operational velocity.

        Args:
            nu: The twist components (k,).
        """
        nu = np.asarray(nu, float)
        if nu.shape != (len(self.names),):
            raise InputError(f"nu has shape {nu.shape}; expected {len(self.names)} values ({', '.join(self.names)})")

    def reduce(self, robot, q, nu, coriolis: bool = False) -> ReducedDynamics:
        """The Python reference (:func:`reduce_operational`); the compiled path: :func:`robotdyn.fast.dispatch.reduce`.

        Args:
            robot: The :class:`~robotdyn.robot.Robot`.
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            nu: The twist components (k,) [m/s, rad/s].
            coriolis: Also compute the matrix C_r (k, k) and dS/dt (default: only the bias h = C_r nu + g_r).

        Returns:
            The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu).
        """
        self.check(nu)
        return reduce_operational(robot, self.twist, q, np.asarray(nu, float), coriolis)


__all__ = ["FrameTwist", "OperationalProjection", "project_operational", "operational_projection", "reduce_operational",
           "OperationalVelocities", "OperationalModel"]

"""Springs and dampers on joints: suspensions, rockers, passive axles.

A :class:`JointSpring` on a one-degree-of-freedom joint (revolute, continuous, prismatic) with coordinate
:math:`q_j` (natural units: m or rad) and velocity :math:`\\dot q_j` applies the generalised force

.. math:: Q_j = -k\\,(q_j - q_{j,0}) - c\\,\\dot q_j

on that coordinate (zero on every other), i.e. an equal and opposite force or torque on the joint's two bodies.
It enters the reduced equations through :math:`S^T` like any applied force (D'Alembert:
:math:`M_r\\dot\\nu + C_r\\nu + g_r = B_r\\tau + S^T Q`). Energy: the spring stores
:math:`\\tfrac12 k (q_j - q_{j,0})^2` (counted in :meth:`robotdyn.robot.Robot.energy`), the damper does the work
:math:`-\\int c\\,\\dot q_j^2\\,dt \\le 0` (``Trajectory.damper_work``).

Units: k in N/m (prismatic) or N m/rad (revolute), c in N s/m or N m s/rad, the rest position :math:`q_{j,0}` in
m or rad.

A URDF joint's ``<dynamics damping>`` d is applied as such a damper (c = d, k = 0; merged into a ``[[springs]]``
entry on the same joint that gives a stiffness only), unless the robot's ``urdf_damping`` is false
(:mod:`robotdyn.description.joint_dynamics`): :func:`build_springs`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

MAX_DAMPING = 1e12
"""Largest joint damping a description may give [N m s/rad or N s/m] (the bound of a ``[[springs]]`` damping)."""


@dataclass
class JointSpring:
    """A spring and damper on a joint's coordinate (declared in a :class:`~robotdyn.robot.RobotSpec` or a
    constraint file's ``[[springs]]``).

    Attributes:
        joint: The joint's name (URDF name or its coordinate label).
        stiffness: k [N/m or N m/rad] (>= 0).
        damping: c [N s/m or N m s/rad] (>= 0).
        rest: Rest position q0 [m or rad] (the coordinate where the spring force is zero).
        name: Name in messages (default: the joint's).
    """

    joint: str
    stiffness: float = 0.0
    damping: float = 0.0
    rest: float = 0.0
    name: str | None = None


class SpringForce:
    """A built :class:`JointSpring`: its velocity index in the model and its checked numbers.

    Args:
        spec: The declaration.
        index: Index of the joint's coordinate in q and v (natural coordinates: nq == nv).
        unit: ``m`` or ``rad`` (for messages and reports).

    Attributes:
        from_urdf: Whether its damping is the description's ``<dynamics damping>`` (set by :func:`build_springs`).

    Raises:
        InputError: a stiffness or damping that is not a finite number >= 0, or a non-finite rest position.
    """

    def __init__(self, spec: JointSpring, index: int, unit: str = "rad") -> None:
        self.name = spec.name or spec.joint
        self.joint = spec.joint
        self.index = int(index)
        self.unit = unit
        units = ("N/m", "N s/m") if unit == "m" else ("N m/rad", "N m s/rad")
        for what, value, u in (("stiffness", spec.stiffness, units[0]), ("damping", spec.damping, units[1])):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise InputError(f"spring {self.name!r}: {what} = {value!r}; expected a finite number >= 0 [{u}]")
        if not (isinstance(spec.rest, (int, float)) and math.isfinite(spec.rest)):
            raise InputError(f"spring {self.name!r}: rest = {spec.rest!r}; expected a finite position [{unit}]")
        self.stiffness = float(spec.stiffness)
        self.damping = float(spec.damping)
        self.rest = float(spec.rest)
        self.from_urdf = False

    def force(self, q: np.ndarray, v: np.ndarray) -> float:
        """:math:`-k(q_j - q_{j,0}) - c\\dot q_j` [N or N m]: the generalised force on the joint's coordinate j.

        Args:
            q: Natural coordinates (n,) [m, rad] (entry :attr:`index` is used).
            v: Full velocities (n,) [m/s, rad/s] (entry :attr:`index` is used).

        Returns:
            The generalised force [N or N m].
        """
        return -self.stiffness * (q[self.index] - self.rest) - self.damping * v[self.index]

    def potential(self, q: np.ndarray) -> float:
        """Stored energy :math:`\\tfrac12 k (q_j - q_{j,0})^2` [J].

        Args:
            q: Natural coordinates (n,) [m, rad] (entry :attr:`index` is used).

        Returns:
            The stored energy [J].
        """
        d = q[self.index] - self.rest
        return 0.5 * self.stiffness * d * d

    def damper_power(self, v: np.ndarray) -> float:
        """Power of the damper on the robot :math:`-c\\dot q_j^2` [W] (<= 0).

        Args:
            v: Full velocities (n,) [m/s, rad/s] (entry :attr:`index` is used).

        Returns:
            The damper's power [W] (<= 0).
        """
        return -self.damping * v[self.index] ** 2

    def __repr__(self) -> str:
        urdf = ", c from the URDF's <dynamics>" if getattr(self, "from_urdf", False) else ""
        return (f"SpringForce({self.name!r}, k={self.stiffness:g}, c={self.damping:g}, rest={self.rest:g} "
                f"{self.unit}{urdf})")


def spring_terms(springs, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The springs' generalised force and its derivatives, for the dynamics' derivatives
    (:mod:`robotdyn.reduction.dynamics_derivatives`, :mod:`robotdyn.contact.sliding_derivatives`).

    Args:
        springs: The robot's :class:`SpringForce` list (empty: zeros).
        q: Natural coordinates (n,) [m, rad].
        v: Full velocities (n,) [m/s, rad/s] (natural coordinates: nq == nv).

    Returns:
        ``(Q, dQ/dq, dQ/dv)``: Q (n,) [N, N m] and its Jacobians (n, n), diagonal: :math:`-k` and :math:`-c` at each
        spring's coordinate.
    """
    n = len(v)
    Q, dq, dv = np.zeros(n), np.zeros((n, n)), np.zeros((n, n))
    for s in springs:
        Q[s.index] += s.force(q, v)
        dq[s.index, s.index] -= s.stiffness
        dv[s.index, s.index] -= s.damping
    return Q, dq, dv


def spring_forces(springs, Q: np.ndarray, V: np.ndarray) -> np.ndarray:
    """The springs' generalised force at many states at once (:meth:`SpringForce.force` row by row).

    Args:
        springs: The robot's :class:`SpringForce` list.
        Q: Natural coordinates (N, n) [m, rad].
        V: Full velocities (N, n) [m/s, rad/s].

    Returns:
        Q_springs (N, n) [N, N m]: nonzero on the springs' coordinates only.
    """
    out = np.zeros(np.shape(V))
    for s in springs:
        out[:, s.index] += -s.stiffness * (Q[:, s.index] - s.rest) - s.damping * V[:, s.index]
    return out


def build_springs(robot, springs, dampers=()) -> list[SpringForce]:
    """The robot's :class:`SpringForce` list from its spec's :class:`JointSpring` declarations and the URDF's joint
    damping.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` under construction (description and coordinates set).
        springs: The declarations.
        dampers: The description's damped joints to apply
            (:class:`~robotdyn.description.joint_dynamics.JointDamper`, from
            :func:`~robotdyn.description.joint_dynamics.urdf_dampers`; default none): each becomes a damper of
            stiffness 0, or gives its damping to a declared spring on that joint that has a stiffness only.

    Returns:
        One :class:`SpringForce` per declaration, in declaration order, then one per damped joint without a
        declaration (empty without either).

    Raises:
        InputError: an unknown joint, a joint with more than one coordinate, two springs on one joint, bad numbers,
            a URDF damping that is negative or above :data:`MAX_DAMPING`, or a joint damped both by the URDF and by a
            declared spring (one line each).
    """
    out: list[SpringForce] = []
    names = robot.description.joint_names
    for s in springs:
        if s.joint in names:
            i = names.index(s.joint)
        elif s.joint in robot.coordinates:
            i = robot.coordinates.index(s.joint)
        else:
            raise InputError(f"spring {s.name or s.joint!r}: unknown joint {s.joint!r}; expected one of "
                             f"{', '.join(robot.coordinates)}")
        unit = robot.units.get(robot.coordinates[i], "rad")
        spring = SpringForce(s, i, "m" if unit == "m" else "rad")
        if any(o.index == i for o in out):
            raise InputError(f"spring {spring.name!r}: a second spring on joint {s.joint!r}; expected one spring "
                             "per joint (add the stiffnesses)")
        out.append(spring)
    for d in dampers:
        if not (math.isfinite(d.damping) and 0.0 <= d.damping <= MAX_DAMPING):  # (as a [[springs]] damping)
            raise InputError(f"joint {d.joint!r}: the description's <dynamics damping=\"{d.damping:g}\">; expected a "
                             f"damping >= 0 and <= {MAX_DAMPING:g} {d.unit} (or urdf_damping = false to leave it out)")
        i = names.index(d.joint) if d.joint in names else int(d.index)
        same = next((o for o in out if o.index == i), None)
        if same is not None and same.damping > 0:  # never both: that would apply the damping twice
            raise InputError(
                f"joint {d.joint!r} is damped twice: {d.damping:g} {d.unit} by the description's <dynamics damping> "
                f"(applied by default) and {same.damping:g} {d.unit} by spring {same.name!r}; expected one: remove "
                "the spring's damping, or set urdf_damping = false to keep the spring's only")
        if same is None:
            unit = "m" if robot.units.get(robot.coordinates[i], "rad") == "m" else "rad"
            same = SpringForce(JointSpring(d.joint, damping=d.damping), i, unit)
            out.append(same)
        else:  # a stiffness-only spring on that joint takes the URDF's damping
            same.damping = float(d.damping)
        same.from_urdf = True
    return out


def urdf_damping_hint(springs) -> str:
    """The words to add to a refusal of joint springs where some of them are a URDF's joint damping.

    Args:
        springs: The robot's :class:`SpringForce` list.

    Returns:
        ``""`` where no spring's damping comes from the URDF; otherwise a clause naming the switch that leaves it
        out (``urdf_damping = false``).
    """
    joints = [s.joint for s in springs if getattr(s, "from_urdf", False)]
    if not joints:
        return ""
    return (f" (the description's <dynamics damping> on {', '.join(joints)} is applied as joint dampers: "
            "urdf_damping = false in the constraint file leaves it out)")


__all__ = ["JointSpring", "SpringForce", "build_springs", "spring_forces", "spring_terms", "urdf_damping_hint"]

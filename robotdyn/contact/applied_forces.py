"""Applied generalised forces that depend on the state only: joint springs and dampers
(:mod:`robotdyn.reduction.joint_springs`) and compliant wheel contacts (:mod:`robotdyn.contact.compliant_contact`).

Their sum :math:`Q(q, v)` (nv,) enters every door's equations of motion the same way, through :math:`S^T`:

.. math:: M_r\\dot\\nu + C_r\\nu + g_r = B_r\\tau + S^T Q(q, v)

(forward and inverse dynamics, the slipping wheels' coupled solve, the constraint forces' residual, simulate).
Their energy: :func:`stored_energy` (springs' and contacts' elastic energy, part of
:meth:`robotdyn.robot.Robot.energy`), and the powers of their dampers and friction (:class:`Applied`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..constraints.constraint import KinematicState


@dataclass
class Applied:
    """The applied forces at one state.

    Attributes:
        Q: Generalised force (nv,) [N, N m].
        friction_power: Power of the compliant wheels' friction forces [W] (<= 0).
        damper_power: Power of the joint dampers and of the contacts' damping [W] (<= 0).
        wheels: Each compliant wheel's :meth:`~robotdyn.contact.compliant_contact.CompliantWheel.state` by name.
    """

    Q: np.ndarray
    friction_power: float = 0.0
    damper_power: float = 0.0
    wheels: dict = field(default_factory=dict)


def has_applied(robot) -> bool:
    """Whether the robot has joint springs or compliant wheels.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` (its ``springs`` and constraints).

    Returns:
        ``True`` if the robot has at least one joint spring or compliant wheel.
    """
    from .compliant_contact import compliant_wheels

    return bool(getattr(robot, "springs", None)) or bool(compliant_wheels(robot))


def applied(robot, q: np.ndarray, v: np.ndarray, kin: KinematicState | None = None) -> Applied:
    """The joint springs' and compliant wheels' generalised force and powers at (q, v).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], in the robot's coordinate order.
        v: Full velocities (n,) [m/s, rad/s], same order (natural coordinates: nq == nv).
        kin: The kinematics at (q, v) if already computed (its caches are shared; recomputed if its v differs).

    Returns:
        The :class:`Applied`: the generalised force Q (nv,) and the powers of friction and dampers.
    """
    from .compliant_contact import compliant_wheels

    q, v = np.asarray(q, float), np.asarray(v, float)
    Q = np.zeros(robot.model.nv)
    out = Applied(Q)
    for s in getattr(robot, "springs", ()):
        Q[s.index] += s.force(q, v)
        out.damper_power += s.damper_power(v)
    wheels = compliant_wheels(robot)
    if wheels:
        if kin is None or not np.array_equal(kin.v, v):
            kin = KinematicState(robot.model, robot.data, q, v)
        for w in wheels:
            st = w.state(kin)
            Q += st["Q"]
            out.friction_power += st["friction_power"]
            out.damper_power += st["damper_power"]
            out.wheels[w.name] = st
    return out


def stored_energy(robot, q: np.ndarray) -> float:
    """Elastic energy of the joint springs and compliant contacts at q [J].

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], in the robot's coordinate order.

    Returns:
        :math:`\\sum \\tfrac12 k (q_j - q_{j,0})^2` of the springs plus each compliant wheel's :math:`U(\\delta)`
        [J] (zero for wheels in the air).
    """
    from .compliant_contact import compliant_wheels

    q = np.asarray(q, float)
    out = sum(s.potential(q) for s in getattr(robot, "springs", ()))
    wheels = compliant_wheels(robot)
    if wheels:
        kin = KinematicState(robot.model, robot.data, q, np.zeros(robot.model.nv))
        out += sum(w.normal_law.potential(w.penetration(kin)) for w in wheels)
    return float(out)


def reduced_applied(robot, red, q: np.ndarray) -> tuple[np.ndarray, Applied | None]:
    """:math:`S^T Q` (k,) at the reduced model ``red``'s state and the :class:`Applied` (``None`` and zeros without
    springs or compliant wheels).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        red: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at the state (its ``S`` (n, k) and
            full velocities ``v`` (n,) are used).
        q: Natural coordinates (n,) [m, rad] of that state.

    Returns:
        ``(S^T Q, applied)``: the reduced generalised force (k,), conjugate to the independent velocities (in
        their order), and the :class:`Applied` (``None`` without springs or compliant wheels).
    """
    if not has_applied(robot):
        return np.zeros(red.S.shape[1]), None
    app = applied(robot, q, red.v)
    return red.S.T @ app.Q, app


__all__ = ["Applied", "applied", "has_applied", "stored_energy", "reduced_applied"]

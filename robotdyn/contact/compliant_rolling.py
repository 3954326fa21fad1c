"""Compliant wheels that roll without slipping while in contact (``contact = "compliant"``, ``friction = "rolling"``).

Such a wheel (:class:`~robotdyn.contact.compliant_contact.CompliantWheel` with ``rolling``) has a normal force law
:math:`f_n(\\delta, \\dot\\delta) \\ge 0` of its penetration, like every compliant wheel, and no friction law: while it
presses on the ground (:math:`f_n > 0`) its tangential rows

.. math:: G_i(q)\\,v = D_i\\,(t_1, t_2)^T A_{w,i}(q)\\,v = 0

(the rigid wheel's longitudinal and lateral rows: the velocity of its material point at the contact, along its
directions :math:`D_i`, :mod:`robotdyn.constraints.rolling_contact`) are constraints of the motion; in flight
(:math:`f_n = 0`) they are dropped. The contact set C (the rolling wheels with :math:`f_n > 0`) is thus a function
of the state; its changes are the events of :mod:`robotdyn.simulation.compliant_rolling`.

Dynamics with the contact set C, on top of the robot's projection v = S ν (in which compliant wheels have no rows):
with :math:`G_r = G S`, the reduced model :math:`M_r, h_r, B_r` and the applied forces :math:`Q` (springs, the
normal laws, friction laws of other compliant wheels, :mod:`robotdyn.contact.applied_forces`),

.. math::
    M_r\\dot\\nu = B_r\\tau - h_r + S^T Q + G_r^T\\lambda,\\qquad
    G_r\\dot\\nu = -(G w + \\dot G v) - \\beta\\, G_r\\nu,

where :math:`a = S\\dot\\nu + w` and :math:`\\beta` [1/s] (the stabilisation gain) pulls the rows' drift back to zero.
:math:`\\lambda` (N) is each wheel's tangential contact force along its directions :math:`D_i` (on the wheel's
material point at the contact, in its contact frame); it does no work on the admissible motion. Redundant rows
(e.g. two wheels on one axle both resisting side slip) get the minimum-norm :math:`\\lambda` (their split is not
determined by rigid dynamics; their sum is). The required friction of a rolling wheel is
:math:`\\|F_t\\|/f_n` with :math:`F_t = D_i^T\\lambda_i`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..constraints.constraint import KinematicState
from ..errors import NonFiniteError
from .applied_forces import Applied, applied
from .compliant_contact import CompliantWheel, compliant_wheels

RCOND = 1e-10
"""Relative eigenvalue cut of :math:`G_r M_r^{-1} G_r^T` below which rows count as redundant."""


def rolling_wheels(robot) -> list[CompliantWheel]:
    """The robot's compliant wheels that roll while in contact, in constraint order (empty: none).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.

    Returns:
        Its :class:`~robotdyn.contact.compliant_contact.CompliantWheel` constraints with ``rolling`` set.
    """
    return [w for w in compliant_wheels(robot) if w.rolling]


def pressing(robot, q: np.ndarray, v: np.ndarray, kin: KinematicState | None = None) -> np.ndarray:
    """Each rolling wheel's contact indicator [m] (> 0 exactly where its normal force is > 0;
    :meth:`~robotdyn.contact.compliant_contact.NormalLaw.pressing`).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,).
        v: Full velocities (nv,).
        kin: The kinematics at (q, v) if already computed.

    Returns:
        (len(rolling_wheels(robot)),) indicators [m], in their order.
    """
    kin = kin if kin is not None else KinematicState(robot.model, robot.data, np.asarray(q, float),
                                                     np.asarray(v, float))
    return np.array([w.pressing(kin) for w in rolling_wheels(robot)], float)


def contact_set(robot, q: np.ndarray, v: np.ndarray) -> tuple[str, ...]:
    """The names of the rolling wheels pressing on the ground at (q, v) (normal force > 0).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,).
        v: Full velocities (nv,).

    Returns:
        Their names, in constraint order.
    """
    wheels = rolling_wheels(robot)
    return tuple(w.name for w, p in zip(wheels, pressing(robot, q, v)) if p > 0.0)


def rows(robot, kin: KinematicState, contact) -> tuple[np.ndarray, np.ndarray, dict[str, slice]]:
    """The rolling rows of the wheels in ``contact``: G (m, nv), their drift :math:`\\dot G v` (m,) [m/s^2] and
    each wheel's slice of rows.

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        kin: The kinematics at (q, v).
        contact: Names of the rolling wheels in contact.

    Returns:
        ``(G, Gdot_v, slices)``.
    """
    parts, drifts, slices, i = [], [], {}, 0
    for w in rolling_wheels(robot):
        if w.name in contact:
            G, d = w.tangential_rows(kin)
            parts.append(G)
            drifts.append(d)
            slices[w.name] = slice(i, i + G.shape[0])
            i += G.shape[0]
    if not parts:
        return np.zeros((0, robot.model.nv)), np.zeros(0), slices
    return np.vstack(parts), np.concatenate(drifts), slices


@dataclass
class RollingState:
    """Forward dynamics of a robot with rolling compliant wheels at one state.

    Attributes:
        nudot: :math:`\\dot\\nu` (k,).
        reduced: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at the state.
        applied: The :class:`~robotdyn.contact.applied_forces.Applied` forces there.
        contact: The names of the rolling wheels whose rows held.
        tangential: By wheel in contact: its tangential force :math:`F_t = D^T\\lambda` (2,) [N] in (t1, t2).
        rows: G (m, nv) of the wheels in contact (world rows, :func:`rows`).
        slices: Each wheel's rows in G.
        multipliers: :math:`\\lambda` (m,) [N].
    """

    nudot: np.ndarray
    reduced: object
    applied: Applied
    contact: tuple[str, ...]
    tangential: dict[str, np.ndarray] = field(default_factory=dict)
    rows: np.ndarray | None = None
    slices: dict[str, slice] = field(default_factory=dict)
    multipliers: np.ndarray | None = None


def forward(robot, q: np.ndarray, nu: np.ndarray, tau: np.ndarray, contact=None, stabilisation: float = 0.0,
            red=None) -> RollingState:
    """:math:`\\dot\\nu` and the rolling wheels' tangential forces at (q, ν) under torques τ (see the module).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad].
        nu: Independent velocities (k,) of the robot's projection.
        tau: Motor torques (n_motors,) [N m or N].
        contact: Names of the rolling wheels whose rows hold (``None``: those with a normal force > 0 at the state).
        stabilisation: :math:`\\beta` [1/s] pulling the rows' velocity residual :math:`G_r\\nu` back to zero.
        red: The reduced model at (q, ν) if already computed.

    Returns:
        The :class:`RollingState`.

    Raises:
        NonFiniteError: The accelerations are not finite.
    """
    from ..reduction.reduced_dynamics import solve_mass

    q, nu, tau = np.asarray(q, float), np.asarray(nu, float), np.asarray(tau, float)
    red = robot.reduced(q, nu) if red is None else red
    kin = KinematicState(robot.model, robot.data, q, red.v)
    app = applied(robot, q, red.v, kin)
    f = red.B @ tau - red.h + red.S.T @ app.Q
    if contact is None:
        contact = tuple(w.name for w in rolling_wheels(robot) if app.wheels[w.name]["normal"] > 0.0)
    G, drift, slices = rows(robot, kin, contact)
    if G.shape[0] == 0:
        return RollingState(solve_mass(red.M, f), red, app, tuple(contact))
    Gr = G @ red.S
    target = -(G @ red.w + drift) - stabilisation * (Gr @ nu)
    Minv = np.linalg.solve(red.M, np.column_stack([f, Gr.T]))
    Minv_f, Minv_GT = Minv[:, 0], Minv[:, 1:]
    W = Gr @ Minv_GT
    W = 0.5 * (W + W.T)
    vals, vecs = np.linalg.eigh(W)
    keep = vals > RCOND * max(vals.max(initial=0.0), np.finfo(float).tiny)
    lam = vecs[:, keep] @ ((vecs[:, keep].T @ (target - Gr @ Minv_f)) / vals[keep])
    nudot = Minv_f + Minv_GT @ lam
    if not (np.all(np.isfinite(nudot)) and np.all(np.isfinite(lam))):
        raise NonFiniteError("the accelerations of the rolling compliant wheels' motion are not finite at this state")
    by_name = {w.name: w for w in rolling_wheels(robot)}
    tangential = {name: by_name[name].tangent_directions.T @ lam[s] for name, s in slices.items()}
    return RollingState(nudot, red, app, tuple(contact), tangential, G, slices, lam)


def touch_down(robot, q: np.ndarray, nu: np.ndarray, contact) -> tuple[np.ndarray, object]:
    """The plastic tangential impact of wheels touching down (:func:`robotdyn.contact.impulse.plastic_impact`):
    the impulse on the rows of every rolling wheel in ``contact`` (those already rolling keep rolling) that makes
    their contact points' tangential velocities zero. Compliant normal laws give no normal impulse.

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) at the touch-down.
        nu: Independent velocities (k,) just before it.
        contact: Names of the rolling wheels in contact just after it.

    Returns:
        ``(nu_after, impulse)`` with the :class:`~robotdyn.contact.impulse.PlasticImpulse` (its ``energy_lost``
        [J] >= 0).
    """
    from .impulse import plastic_impact

    red = robot.reduced(q, nu)
    kin = KinematicState(robot.model, robot.data, np.asarray(q, float), red.v)
    G, _, _ = rows(robot, kin, contact)
    out = plastic_impact(red.M, G @ red.S, nu)
    return out.nu_after, out


__all__ = ["rolling_wheels", "pressing", "contact_set", "rows", "RollingState", "forward", "touch_down", "RCOND"]

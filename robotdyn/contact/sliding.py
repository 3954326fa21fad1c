"""Wheels that slip: a normal contact kept as a constraint, the tangential force from a friction law.

A :class:`SlippingWheel` contributes only its holonomic normal row (it stays on the terrain); the no-slip rows
are replaced by the force of its :class:`~robotdyn.contact.friction.FrictionLaw`, applied at the contact point:
:math:`J_t^T F_t` with :math:`J_t` the tangential rows of the rolling Jacobian (the slip velocity is
:math:`s = J_t v`) and :math:`F_t = -f_n c(s)`. The normal load :math:`f_n` is a constraint force, so it depends on
the accelerations; with the friction direction fixed by the current slip, the system in
:math:`(\\dot\\nu, \\lambda)` stays linear and is solved exactly at each evaluation (no lagged load,
the concepts page ``docs/concepts.md``):

.. math:: M S\\dot\\nu - \\Big(A_R^T - \\sum_i J_{t,i}^T c_i e_{n_i}^T\\Big)\\lambda = B\\tau - \\mathrm{RNEA}(q, v, w),

with :math:`A_R` the independent constraint rows the projection uses and :math:`e_{n_i}` selecting wheel i's
normal multiplier. A singular system is the Painlevé paradox of Coulomb friction (no or many solutions): it is
reported, never regularised silently.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..reduction.actuation import input_matrix
from .applied_forces import applied, has_applied
from ..constraints.constraint import KinematicState
from ..errors import ConstraintError, InputError, SingularConstraintError
from .friction import FrictionLaw
from ..constraints.rolling_contact import SupportWheel
from . import painleve

PAINLEVE_CONDITION = 1e12
"""Condition number of the coupled system above which it counts as singular."""


SLIP_DIRECTIONS = ("both", "lateral")
"""Which tangential directions of a slipping wheel follow its law: ``both`` (the wheel slides freely in its
tangent plane) or ``lateral`` (it rolls without slipping along t1 and slides sideways along t2: the tyre model
of vehicle dynamics that neglects longitudinal slip)."""


class SlippingWheel(SupportWheel):
    """A wheel that keeps contact (its normal row) and slips under a friction law.

    With ``slip="lateral"`` it also keeps its longitudinal no-slip row (t1; the rolling constraint force is the
    traction) and only its lateral force (t2) follows the law, from the lateral slip velocity. The law then sees a
    purely lateral slip, so the lateral force alone is bounded by :math:`\\mu f_n`; the combined force
    :math:`\\|(f_{t1}, f_{t2})\\|/f_n` is reported by :mod:`robotdyn.contact.contact_forces` (``required_mu``), and exceeding
    :math:`\\mu` there means the longitudinal no-slip assumption breaks too.

    Args:
        law: The :class:`~robotdyn.contact.friction.FrictionLaw` of its tangential force.
        slip: ``both`` (default) or ``lateral`` (:data:`SLIP_DIRECTIONS`).
        **kwargs: The other arguments of :class:`~robotdyn.constraints.rolling_contact.RollingWheel`.
        description: The robot's :class:`~robotdyn.description.urdf.Description`.
        frame: Frame (link) whose origin is the wheel centre.
        radius: Wheel radius R [m] (> 0).
    """

    sliding = True  # its friction force comes from a law (robotdyn.contact.sliding.forward)

    def __init__(self, description, frame: str, radius: float, law: FrictionLaw, slip: str = "both",
                 **kwargs) -> None:
        super().__init__(description, frame, radius, **kwargs)
        if slip not in SLIP_DIRECTIONS:
            raise InputError(f"wheel {self.name!r}: slip = {slip!r}; expected one of {', '.join(SLIP_DIRECTIONS)}")
        self.law = law
        self.slip_directions = slip
        self._free = np.array([1.0, 1.0]) if slip == "both" else np.array([0.0, 1.0])
        if slip == "lateral":  # the longitudinal no-slip row stays a constraint
            self._directions = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
            self._row_names = ("longitudinal", "normal")

    def friction_coefficient(self, s: np.ndarray) -> np.ndarray:
        """:math:`c(s)` of its law on the free directions: the friction force is :math:`-f_n c(s)` (t1, t2), zero
        along a direction that rolls without slipping.

        Args:
            s: The slip velocity (2,) [m/s] of the wheel's material point at the contact, in (t1, t2) of its contact
                frame.

        Returns:
            c(s) (2,) [-].
        """
        return self.law.coefficient(s * self._free) * self._free

    def __repr__(self) -> str:
        slip = "" if self.slip_directions == "both" else ", slip='lateral'"
        return (f"SlippingWheel(frame={self.frame!r}, radius={self.radius}, law={self.law!r}{slip}, "
                f"terrain={self.terrain!r})")

    def slip(self, kin: KinematicState) -> tuple[np.ndarray, np.ndarray]:
        """The tangential rows :math:`J_t` (2, nv) and the slip velocity (2,) [m/s]: :func:`tangential`.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            ``(Jt, s)``: the tangential rows (2, nv) and the slip velocity (2,) [m/s] in (t1, t2) of the contact frame.
        """
        return tangential(self, kin)

    def compiled_friction(self) -> tuple[tuple, np.ndarray] | str:
        """What the compiled evaluator needs for this wheel's friction: its law as data
        (:meth:`~robotdyn.contact.friction.FrictionLaw.encode`) and the mask of its free directions (t1, t2); or,
        as a string, why its friction stays on the Python path (a subclass with its own formulas, a law without
        compiled formula).

        Returns:
            ``(code, free)``: the law's :meth:`~robotdyn.contact.friction.FrictionLaw.encode` tuple and the
            free-direction mask (2,) (1.0 where free); or a one-line string saying why not.
        """
        if type(self).friction_coefficient is not SlippingWheel.friction_coefficient or \
                type(self).slip is not SlippingWheel.slip:
            return f"wheel {self.name!r} ({type(self).__name__}) is simulated on the Python path"
        code = self.law.encode()
        if code is None:
            return f"wheel {self.name!r} has the friction law {self.law!r}, whose formula is not compiled"
        return code, np.asarray(self._free, float)


def tangential(wheel, kin: KinematicState) -> tuple[np.ndarray, np.ndarray]:
    """A wheel's tangential rows :math:`J_t` (2, nv) (t1 longitudinal, t2 lateral of the contact frame) and its slip
    velocity :math:`s = J_t v` (2,) [m/s] at the state of ``kin`` (the velocity of its material point at the
    contact, in the tangent plane).

    Args:
        wheel: A rolling-contact wheel (:class:`~robotdyn.constraints.rolling_contact.RollingWheel` or a subclass).
        kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

    Returns:
        ``(Jt, s)``: the tangential rows (2, nv) and the slip velocity ``Jt @ kin.v`` (2,) [m/s], rows (t1, t2).
    """
    Aw, geo = wheel._world_jacobian(kin)
    Jt = geo[9][:, :2].T @ Aw
    return Jt, Jt @ kin.v


def sliding_now(robot) -> list:
    """The robot's wheels whose tangential force currently comes from friction (slipping wheels, and stick-slip
    wheels in their sliding phase).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The wheels (constraint objects) whose tangential force is friction now.
    """
    return [c for c in robot.constraints if getattr(c, "sliding", False)]


def slipping_wheels(robot) -> list[SlippingWheel]:
    """The robot's slipping wheels (empty: every wheel rolls without slipping).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The :class:`SlippingWheel` constraints of the robot.
    """
    return [c for c in robot.constraints if isinstance(c, SlippingWheel)]


@dataclass
class SlidingState:
    """Forward dynamics with slipping wheels at one state.

    Attributes:
        nudot: Independent accelerations (k,).
        reduced: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at the state (S, w, v, rows).
        normal: Normal load of each slipping wheel (W,) [N].
        slip: Slip velocity of each slipping wheel (W, 2) [m/s] (t1, t2).
        force: Friction force on each slipping wheel (W, 2) [N] (t1, t2).
        power: Power of the friction forces :math:`\\sum F_t\\cdot s` [W] (<= 0 while loads are positive), the
            compliant wheels' included.
        damper_power: Power of joint dampers and compliant contacts' damping [W] (<= 0;
            :mod:`robotdyn.contact.applied_forces`).
        lam: (m,) every constraint row's multiplier [N, N m], in the order of ``reduced.jacobian_rows.labels``,
            where the open loads are split by the rigid limit of the wheels' normal compliance; ``None`` otherwise.
        unloaded: Names of the wheels the rigid limit leaves unloaded (they would pull); empty otherwise.
    """

    nudot: np.ndarray
    reduced: object
    normal: np.ndarray
    slip: np.ndarray
    force: np.ndarray
    power: float
    lam: np.ndarray | None = None  # (m,) every row's multiplier where the loads are split by the rigid limit
    unloaded: tuple = ()  # wheels the rigid limit leaves unloaded (they would pull)
    damper_power: float = 0.0


def forward(robot, q: np.ndarray, nu: np.ndarray, tau: np.ndarray) -> SlidingState:
    """Accelerations and normal loads with the slipping wheels' friction, solved together (see the module).

    Where the rows are redundant so that rigid-body dynamics leave wheel loads open (a rigid chassis on four
    wheels), the loads are those of the rigid limit of the wheels' normal compliance, solved together with the
    accelerations and friction (:func:`robotdyn.contact.sliding_rigid_limit.coupled`).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.
        tau: Motor torques [N m] (forces [N] on prismatic joints), one per motor in the robot's motor order.

    Returns:
        The :class:`SlidingState` (``nudot`` (k,), the slipping wheels' normal loads [N] and friction forces [N]).

    Raises:
        SingularConstraintError: the coupled system is singular (Painlevé).
    """
    wheels = sliding_now(robot)
    red = robot.reduced(q, nu)
    model, data = robot.model, robot.data
    kin = KinematicState(model, data, q, red.v)
    rows = red.jacobian_rows
    kept = np.asarray(red.projection.rows, int)
    if len(kept) < rows.A.shape[0]:
        from .sliding_rigid_limit import coupled

        out = coupled(robot, q, red, kin, wheels, tau)
        if out is not None:
            return out
    G = rows.A[kept].T.copy()
    slip = np.zeros((len(wheels), 2))
    coef = np.zeros((len(wheels), 2))
    position = np.zeros(len(wheels), int)
    U = np.zeros((G.shape[0], len(wheels)))  # each wheel's friction column J_t^T c (robotdyn.contact.painleve)
    for i, wheel in enumerate(wheels):
        row = rows.labels.index(f"{wheel.name}.normal")
        hit = np.flatnonzero(kept == row)
        if not hit.size:
            raise redundant_load_error(wheel)
        Jt, slip[i] = tangential(wheel, kin)
        coef[i] = wheel.friction_coefficient(slip[i])
        position[i] = hit[0]
        U[:, i] = Jt.T @ coef[i]
        G[:, hit[0]] -= U[:, i]
    M = pin.crba(model, data, q)
    K = np.hstack([M @ red.S, -G])
    rhs = input_matrix(robot.motors, kin) @ tau - pin.rnea(model, data, q, red.v, red.w)
    app = applied(robot, q, red.v, kin) if has_applied(robot) else None
    if app is not None:  # joint springs, compliant wheels: known at the state (robotdyn.contact.applied_forces)
        rhs += app.Q
    cond = np.linalg.cond(K)
    if not np.isfinite(cond) or cond > PAINLEVE_CONDITION:
        raise painleve_error(wheels, cond)
    sol = np.linalg.solve(K, rhs)
    k = red.S.shape[1]
    if wheels:  # a unique, consistent solution needs a P-matrix of effective normal coefficients
        AR = rows.A[kept]
        E = np.zeros((len(kept), len(wheels)))
        E[position, np.arange(len(wheels))] = 1.0
        painleve.check(K, k + position, M @ (AR.T @ np.linalg.solve(AR @ AR.T, E)), wheels, slip, U)
    normal = sol[k + position]
    force = -normal[:, None] * coef
    power = float(np.sum(force * slip)) + (app.friction_power if app is not None else 0.0)
    return SlidingState(sol[:k], red, normal, slip, force, power,
                        damper_power=app.damper_power if app is not None else 0.0)


def painleve_error(wheels, cond: float) -> SingularConstraintError:
    """The error of a singular contact problem of slipping ``wheels`` (condition number ``cond`` of the coupled
    system), the same on every engine.

    Args:
        wheels: The slipping wheels.
        cond: Condition number of the coupled system.

    Returns:
        The :class:`~robotdyn.errors.SingularConstraintError` to raise (not raised here).
    """
    return SingularConstraintError(
        f"the friction of slipping wheels {', '.join(w.name for w in wheels)} makes the contact problem "
        f"singular (condition {cond:.3g}; Painleve paradox: the accelerations and loads have no or many "
        "solutions); expected a smaller mu or another friction law", cond)


def redundant_load_error(wheel) -> ConstraintError:
    """The error of a slipping wheel whose normal row is redundant (its load is not determined).

    Args:
        wheel: The slipping wheel.

    Returns:
        The :class:`~robotdyn.errors.ConstraintError` to raise (not raised here).
    """
    return ConstraintError(f"slipping wheel {wheel.name!r}: its normal row is redundant here, so its load "
                           "(and its friction) is not determined by rigid-body dynamics")


def contact_load(robot, st: SlidingState) -> float:
    """The smallest normal load [N] of the slipping wheels that carry load at a state: the lift-off event's value
    (it reaches zero where a wheel would have to leave the ground).

    Wheels that the rigid limit of normal compliance leaves unloaded (``st.unloaded``: on a statically
    indeterminate chassis, a wheel that would pull) are left out: they stay on the ground at zero load while the
    chassis rests on the others, which is not a lift-off (the rigid-limit split unloads and reloads them itself).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        st: Its :class:`SlidingState` at the state (:func:`forward`).

    Returns:
        The smallest load [N] among the loaded slipping wheels (the smallest of all where every wheel is unloaded).
    """
    names = [w.name for w in sliding_now(robot)]
    loaded = np.array([name not in st.unloaded for name in names], bool)
    return float(np.min(st.normal[loaded] if loaded.any() else st.normal))


def check_start_loads(robot, t0: float, q0: np.ndarray, nu0: np.ndarray, tau0: np.ndarray) -> None:
    """Refuse a run whose slipping wheels' smallest load is already negative where it starts (the same on every
    engine).

    The lift-off event stops a run where that load falls through zero (:func:`contact_load`); a run that starts
    below zero has no crossing to find, so it would go on with a rigid contact pulling the ground and a friction
    force of the wrong sign (:math:`-\\mu N` with N < 0). A load within :data:`~robotdyn.contact.rigid_limit.PULL_TOL`
    of the largest one counts as zero (rounding), as the rigid limit's split counts it.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (with slipping wheels).
        t0: Start time [s] (for the message).
        q0: Natural coordinates (n,) [m, rad] where the run starts.
        nu0: Independent velocities (k,) [m/s, rad/s] there.
        tau0: Motor torques (one per motor) [N m or N] there.

    Raises:
        InputError: A slipping wheel carrying a negative load at the start (one line: the wheel, its load, what
            to change).
    """
    from .rigid_limit import PULL_TOL

    st = forward(robot, q0, nu0, tau0)
    load = contact_load(robot, st)
    if load >= -PULL_TOL * max(float(np.max(np.abs(st.normal), initial=0.0)), 1e-300):
        return
    wheels = sliding_now(robot)
    i = min((j for j, w in enumerate(wheels) if w.name not in st.unloaded), key=lambda j: st.normal[j],
            default=int(np.argmin(st.normal)))
    raise InputError(f"at t = {t0:g} s slipping wheel {wheels[i].name} would pull the ground (normal load "
                     f"{st.normal[i]:.4g} N): the rigid contact cannot start there; expected a start where every "
                     "slipping wheel presses on the ground (e.g. a smaller mu, speed or torque), or contact = "
                     "\"compliant\" in its [[wheels]] entry to let it fly and land")


def lift_off_message(robot, t: float, q: np.ndarray, nu: np.ndarray, tau: np.ndarray) -> str:
    """``stats["event"]`` of a run stopped where a slipping wheel's normal load reached zero at time t [s] and
    state (q, nu), with torques tau there (the same on every engine).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        t: Time of the lift-off [s].
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.
        tau: Motor torques [N m] (forces [N] on prismatic joints), one per motor in the robot's motor order.

    Returns:
        The one-line message (time in s, load in N).
    """
    wheels = sliding_now(robot)
    st = forward(robot, q, nu, tau)
    load = np.array([np.inf if w.name in st.unloaded else f for w, f in zip(wheels, st.normal)])
    i = int(np.argmin(load)) if np.isfinite(load).any() else int(np.argmin(st.normal))
    from .stick_slip_wheel import unloaded_message

    return unloaded_message(wheels[i].name, t, float(st.normal[i]), "slipping")


@dataclass
class SlidingInverse:
    """Inverse dynamics with slipping wheels at one state (:func:`inverse`).

    Attributes:
        tau: Motor torques (n_motors,) [N m or N].
        multipliers: The constraint rows' forces by label (rows of :meth:`Robot.constraint_rows`) [N, N m].
        normal: Normal load of each sliding wheel (W,) [N].
        slip: Slip velocity of each sliding wheel (W, 2) [m/s] (t1, t2).
        force: Friction force of each sliding wheel from its law (W, 2) [N] (t1, t2).
        residual: :math:`\\|K x - b\\|` of the least-squares solve [N, N m] (0: the motion is exactly realisable by
            these motors and contacts).
        rank: Rank of K; below its column count the torques and forces are not all determined.
        condition: 2-norm condition number of K (largest over smallest singular value; large: the force system is
            nearly singular and its torques and loads are ill-determined).
    """

    tau: np.ndarray
    multipliers: dict[str, float]
    normal: np.ndarray
    slip: np.ndarray
    force: np.ndarray
    residual: float
    rank: int
    condition: float = 1.0


def inverse(robot, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> SlidingInverse:
    """Motor torques and contact forces that produce the full accelerations ``a`` at (q, v), with the sliding
    wheels' friction from their laws.

    The friction forces are linear in the (unknown) normal loads, so torques and constraint forces solve one linear
    system, by least squares with its residual and rank reported:

    .. math:: \\Big[B \\;\\; A^T - \\sum_i J_{t,i}^T c_i e_{n_i}^T\\Big] \\begin{bmatrix}\\tau\\\\ \\lambda\\end{bmatrix}
        = \\mathrm{RNEA}(q, v, a).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` (its sliding wheels as :func:`sliding_now` lists them).
        q, v, a: Natural coordinates, full velocities (consistent with the constraints) and full accelerations.

    Returns:
        A :class:`SlidingInverse`: motor torques, multipliers by row label, normal loads [N], slip and the friction
        forces.
    """
    q, v, a = (np.asarray(x, float) for x in (q, v, a))
    wheels = sliding_now(robot)
    model, data = robot.model, robot.data
    kin = KinematicState(model, data, q, v)
    from ..reduction.reduced_dynamics import constraint_set

    rows = constraint_set(robot).jacobian(kin)
    G = rows.A.T.copy()
    slip = np.zeros((len(wheels), 2))
    coef = np.zeros((len(wheels), 2))
    normal_row = np.zeros(len(wheels), int)
    for i, wheel in enumerate(wheels):
        normal_row[i] = rows.labels.index(f"{wheel.name}.normal")
        Jt, slip[i] = tangential(wheel, kin)
        coef[i] = wheel.friction_coefficient(slip[i])
        G[:, normal_row[i]] -= Jt.T @ coef[i]
    B = input_matrix(robot.motors, kin)
    K = np.hstack([B, G])
    b = pin.rnea(model, data, q, v, a)
    if has_applied(robot):
        b -= applied(robot, q, v, kin).Q
    x, _, rank, sv = np.linalg.lstsq(K, b, rcond=None)
    n_tau = B.shape[1]
    lam = x[n_tau:]
    normal = lam[normal_row]
    return SlidingInverse(x[:n_tau], dict(zip(rows.labels, lam.tolist())), normal, slip, -normal[:, None] * coef,
                          float(np.linalg.norm(K @ x - b)), int(rank),
                          float(sv[0] / sv[-1]) if sv.size and sv[-1] > 0 else float("inf"))


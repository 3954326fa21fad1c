"""Wheels that fly and land: a normal force law of penetration instead of a normal constraint.

A :class:`CompliantWheel` contributes no constraint rows. At every state its contact geometry (the rolling wheel's:
contact point p, contact frame E = (t1, t2, n), :mod:`robotdyn.constraints.rolling_contact`) gives

- the penetration :math:`\\delta = -\\phi(q)` [m] (:math:`\\phi` the signed distance of the wheel's lowest rim
  point above the terrain, along its normal) and its rate :math:`\\dot\\delta = -G v` [m/s] with
  :math:`G = \\partial\\phi/\\partial q` (1, nv), :func:`penetration_gradient`: exactly the time derivative of
  the same :math:`\\phi(q)` (on a plane :math:`G = n^T A_w`, the normal velocity of the wheel's material point at
  p; on curved terrain G adds a term of order :math:`\\phi` times the terrain's curvature);
- the normal force :math:`f_n = N(\\delta, \\dot\\delta) \\ge 0` of its :class:`NormalLaw` (zero while
  :math:`\\delta \\le 0`: the wheel flies; never pulling);
- the tangential force of its friction law :math:`F_t = -f_n c(s)` (:mod:`robotdyn.contact.friction`) from the slip
  velocity :math:`s = (t_1, t_2)^T A_w v`, on the wheel's own tangential directions (both for a standard wheel,
  the rollers' driving direction for an omni wheel, none for a support);

(a wheel declared with ``friction = "rolling"`` has no friction law: while :math:`f_n > 0` its tangential rows are
constraints of the motion instead, and its tangential force is their multiplier,
:mod:`robotdyn.contact.compliant_rolling`; :meth:`CompliantWheel.state` gives its normal force only)
and applies :math:`Q = A^T (F_{t1}, F_{t2}, f_n)` with A (3, nv) the rows :math:`(t_1, t_2)^T A_w` and G: the
tangential force on the wheel's material point at p, the normal force along :math:`\\partial\\phi/\\partial q`
(the contact force at p along n, to first order in :math:`\\phi`). Energy: the law's elastic part stores
:math:`U(\\delta)`, whose rate :math:`f_e(\\delta)\\dot\\delta` is then exactly minus the elastic force's power;
the rest of the normal force does the work :math:`-\\int (f_n - f_e(\\delta))\\,\\dot\\delta\\,dt \\le 0` (the
damper's), friction :math:`\\int F_t \\cdot s\\,dt \\le 0`: kinetic + potential + stored energy change by motor
work + damper work + friction work, on any terrain.

Laws (:math:`\\delta` the penetration [m], :math:`\\dot\\delta` its rate [m/s]):

- :class:`LinearContact`: :math:`f_n = \\max(0, k\\delta + c\\dot\\delta)` for :math:`\\delta > 0`.
- :class:`HuntCrossley`: :math:`f_n = \\max(0, \\delta^n (k + \\lambda\\dot\\delta))` (Hunt & Crossley 1975, in the
  form of Marhefka & Orin 1999: :math:`\\lambda = \\tfrac32 \\alpha k`), whose force is continuous at touch-down.

References (the site's bibliography, ``docs/bibliography.md``): K. H. Hunt, F. R. E. Crossley, *Coefficient of
restitution interpreted as damping in vibroimpact*, Journal of Applied Mechanics (ASME) 42(2), pp. 440-445, 1975;
D. W. Marhefka, D. E. Orin, *A compliant contact model with nonlinear damping for simulation of robotic systems*,
IEEE Transactions on Systems, Man, and Cybernetics, Part A: Systems and Humans 29(6), pp. 566-572, 1999.
"""

from __future__ import annotations

import math

import numpy as np

from ..constraints.constraint import ConstraintRows, KinematicState
from ..constraints.rolling_contact import RollingWheel
from ..errors import InputError

HUNT_CROSSLEY_EXPONENT = 1.5
"""Default exponent n of the Hunt-Crossley law (Hertz's for a sphere or a crowned tyre on a plane)."""
HUNT_CROSSLEY_ALPHA = 0.2
"""Default :math:`\\alpha` [s/m] of the Hunt-Crossley law's damping :math:`\\lambda = 1.5\\alpha k` (Marhefka & Orin
1999 list 0.08 to 0.32 s/m for common materials)."""
CONTACT_LAWS = ("linear", "hunt_crossley")
"""The normal force laws by the name used in TOML files and the API."""


class NormalLaw:
    """A normal force law of penetration :math:`\\delta` [m] and its rate :math:`\\dot\\delta` [m/s]."""

    name = "law"

    def force(self, delta: float, rate: float) -> float:
        """:math:`f_n \\ge 0` [N] (zero for :math:`\\delta \\le 0`).

        Args:
            delta: Penetration :math:`\\delta` [m] (> 0: in contact).
            rate: Its rate :math:`\\dot\\delta` [m/s] (> 0: pressing in).

        Returns:
            The normal force :math:`f_n \\ge 0` [N] (0.0 out of contact).
        """
        raise NotImplementedError

    def elastic(self, delta: float) -> float:
        """The elastic part :math:`f_e(\\delta)` [N] (zero for :math:`\\delta \\le 0`).

        Args:
            delta: Penetration :math:`\\delta` [m].

        Returns:
            The elastic force :math:`f_e(\\delta)` [N] (0.0 out of contact).
        """
        raise NotImplementedError

    def pressing(self, delta: float, rate: float) -> float:
        """A continuous function [m] of the penetration and its rate that is > 0 exactly where the law pushes
        (:math:`f_n > 0`): the contact indicator whose zero crossings are a rolling compliant wheel's touch-down
        (upwards) and lift-off (downwards) events (:mod:`robotdyn.contact.compliant_rolling`).

        Args:
            delta: Penetration :math:`\\delta` [m].
            rate: Its rate :math:`\\dot\\delta` [m/s].

        Returns:
            The indicator [m] (> 0: the law pushes).
        """
        raise NotImplementedError

    def potential(self, delta: float) -> float:
        """Stored energy :math:`U(\\delta) = \\int_0^\\delta f_e` [J] (zero for :math:`\\delta \\le 0`).

        Args:
            delta: Penetration :math:`\\delta` [m].

        Returns:
            The stored energy :math:`U(\\delta)` [J] (0.0 out of contact).
        """
        raise NotImplementedError


class LinearContact(NormalLaw):
    """:math:`f_n = \\max(0, k\\delta + c\\dot\\delta)` for :math:`\\delta > 0`, else 0.

    Args:
        stiffness: k [N/m] (> 0).
        damping: c [N s/m] (>= 0).
    """

    name = "linear"

    def __init__(self, stiffness: float, damping: float = 0.0) -> None:
        self.stiffness = _number(stiffness, "normal_stiffness", "N/m", positive=True)
        self.damping = _number(damping, "normal_damping", "N s/m")

    def force(self, delta: float, rate: float) -> float:
        return max(0.0, self.stiffness * delta + self.damping * rate) if delta > 0.0 else 0.0

    def elastic(self, delta: float) -> float:
        return self.stiffness * delta if delta > 0.0 else 0.0

    def pressing(self, delta: float, rate: float) -> float:
        return min(delta, delta + self.damping / self.stiffness * rate)  # > 0 iff delta > 0 and k d + c d' > 0

    def potential(self, delta: float) -> float:
        return 0.5 * self.stiffness * delta * delta if delta > 0.0 else 0.0

    def __repr__(self) -> str:
        return f"LinearContact(k={self.stiffness:g} N/m, c={self.damping:g} N s/m)"


class HuntCrossley(NormalLaw):
    """:math:`f_n = \\max(0, \\delta^n (k + \\lambda\\dot\\delta))` for :math:`\\delta > 0`, else 0 [N], with the
    penetration :math:`\\delta` [m] and its rate [m/s] (Hunt & Crossley 1975, full reference in the module docstring).

    Args:
        stiffness: k [N/m^n] (> 0).
        damping: :math:`\\lambda` [N s/m^(n+1)] (>= 0).
        exponent: n (dimensionless, >= 1; default 1.5, Hertz's for a sphere or a crowned tyre on a plane).
    """

    name = "hunt_crossley"

    def __init__(self, stiffness: float, damping: float = 0.0, exponent: float = HUNT_CROSSLEY_EXPONENT) -> None:
        self.stiffness = _number(stiffness, "normal_stiffness", "N/m^n", positive=True)
        self.damping = _number(damping, "normal_damping", "N s/m^(n+1)")
        self.exponent = _number(exponent, "contact_exponent", "")
        if self.exponent < 1.0:
            raise InputError(f"contact_exponent = {exponent}; expected an exponent n >= 1")

    def force(self, delta: float, rate: float) -> float:
        return max(0.0, delta ** self.exponent * (self.stiffness + self.damping * rate)) if delta > 0.0 else 0.0

    def elastic(self, delta: float) -> float:
        return self.stiffness * delta ** self.exponent if delta > 0.0 else 0.0

    def pressing(self, delta: float, rate: float) -> float:
        return min(delta, delta * (1.0 + self.damping / self.stiffness * rate))  # > 0 iff d > 0, k + lambda d' > 0

    def potential(self, delta: float) -> float:
        n = self.exponent
        return self.stiffness * delta ** (n + 1.0) / (n + 1.0) if delta > 0.0 else 0.0

    def __repr__(self) -> str:
        return f"HuntCrossley(k={self.stiffness:g}, lambda={self.damping:g}, n={self.exponent:g})"


def make_normal_law(name: str, stiffness: float, damping: float | None, exponent: float | None = None,
                    wheel: str = "wheel") -> NormalLaw:
    """A normal law from its name and numbers, with one-line errors naming the wheel.

    Args:
        name: ``linear`` or ``hunt_crossley``.
        stiffness: k [N/m, or N/m^n for hunt_crossley].
        damping: c [N s/m] (linear) or :math:`\\lambda` [N s/m^(n+1)] (hunt_crossley); ``None``: 0 (linear),
            :math:`1.5\\,\\alpha k` with :data:`HUNT_CROSSLEY_ALPHA` (hunt_crossley).
        exponent: n of hunt_crossley (>= 1; ``None``: :data:`HUNT_CROSSLEY_EXPONENT`); must be ``None`` for linear.
        wheel: The wheel's name, for the error messages.

    Returns:
        A :class:`LinearContact` or a :class:`HuntCrossley`.

    Raises:
        InputError: an unknown law name, an exponent given to the linear law, or a stiffness that is not a finite
            number > 0, a damping not >= 0, an exponent < 1 (one line naming the wheel).
    """
    try:
        if name == "linear":
            if exponent is not None:
                raise InputError("contact_exponent belongs to contact_law = 'hunt_crossley'")
            return LinearContact(stiffness, 0.0 if damping is None else damping)
        if name == "hunt_crossley":
            n = HUNT_CROSSLEY_EXPONENT if exponent is None else exponent
            lam = 1.5 * HUNT_CROSSLEY_ALPHA * float(stiffness) if damping is None else damping
            return HuntCrossley(stiffness, lam, n)
    except InputError as exc:
        raise InputError(f"wheel {wheel!r}: {exc}") from None
    raise InputError(f"wheel {wheel!r}: contact_law = {name!r}; expected one of {', '.join(CONTACT_LAWS)}")


class CompliantWheel(RollingWheel):
    """A wheel whose normal contact is a force law (it can leave the ground and land) and whose tangential side
    follows a friction law, or rolls without slipping while in contact (see the module).

    Args:
        description, frame, radius: As :class:`~robotdyn.constraints.rolling_contact.RollingWheel`.
        normal: Its :class:`NormalLaw`.
        law: Its :class:`~robotdyn.contact.friction.FrictionLaw` (``None``: frictionless, e.g. a support, or
            rolling).
        directions: The tangential directions the law (or the rolling rows) act on, as rows of coefficients of
            (t1, t2): (2, 2) identity for a standard wheel, the rollers' driving direction (1, 2) for an omni
            wheel, (0, 2) for a frictionless support.
        kind: ``standard``, ``omni`` or ``support`` (reports).
        rolling: ``True``: while the normal force is > 0 the wheel rolls without slipping along ``directions``
            (those rows are constraints of the motion, :mod:`robotdyn.contact.compliant_rolling`); ``law`` must
            then be ``None``.
        **kwargs: axis, terrain, radius_joint, name (as RollingWheel).
    """

    compliant = True

    def __init__(self, description, frame: str, radius: float, normal: NormalLaw, law=None,
                 directions=np.eye(2), kind: str = "standard", rolling: bool = False, **kwargs) -> None:
        super().__init__(description, frame, radius, **kwargs)
        self.normal_law = normal
        self.law = law
        self.tangent_directions = np.atleast_2d(np.asarray(directions, float)).reshape(-1, 2)
        self.kind = kind
        self.rolling = bool(rolling) and self.tangent_directions.shape[0] > 0 and law is None
        # the rolling rows D (t1, t2)^T A_w through RollingWheel.jacobian/drift (self's own give no rows)
        self._directions = np.hstack([self.tangent_directions, np.zeros((self.tangent_directions.shape[0], 1))])

    def __getstate__(self) -> dict:
        """Pickle without a traction pass's memory of the contact state (an instance attribute ``state`` over the
        method, :mod:`robotdyn.contact.traction_memo`: a copy made during a pass is the wheel as it is outside it)."""
        state = self.__dict__.copy()
        state.pop("state", None)
        return state

    def rolling_labels(self) -> list[str]:
        """Labels of the rolling rows, in the order of :meth:`tangential_rows`.

        Returns:
            ``<name>.longitudinal``, ``<name>.lateral`` for a standard wheel, ``<name>.driving`` for an omni wheel;
            an empty list for a wheel that does not roll (a friction law, a support).
        """
        if not self.rolling:
            return []
        rows = ("longitudinal", "lateral") if self.kind == "standard" else ("driving",)
        return [f"{self.name}.{r}" for r in rows]

    def tangential_rows(self, kin: KinematicState) -> tuple[np.ndarray, np.ndarray]:
        """The rolling rows :math:`G = D\\,(t_1, t_2)^T A_w` (d, nv) and their drift :math:`\\dot G v` (d,)
        [m/s^2]: the velocity of the wheel's material point at the contact along its tangential directions D
        (the rigid wheel's tangential rows, :class:`~robotdyn.constraints.rolling_contact.RollingWheel`).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            ``(G, Gdot_v)``.
        """
        return RollingWheel.jacobian(self, kin).A, RollingWheel.drift(self, kin)

    def pressing(self, kin: KinematicState) -> float:
        """The normal law's contact indicator :meth:`NormalLaw.pressing` [m] at (q, v) of ``kin``: > 0 exactly
        where the normal force is > 0.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (v: full velocities).

        Returns:
            The indicator [m].
        """
        rate = float(penetration_gradient(self, kin) @ kin.v)  # d phi / dt
        return self.normal_law.pressing(self.penetration(kin), -rate)

    def __repr__(self) -> str:
        return (f"CompliantWheel(frame={self.frame!r}, radius={self.radius}, normal={self.normal_law!r}, "
                + (f"law={self.law!r}, " if not self.rolling else "rolling while in contact, ")
                + f"terrain={self.terrain!r})")

    # no constraint rows: the normal direction is a force law, the tangential ones a friction law
    def _labels(self) -> list[str]:
        return []

    def jacobian(self, kin: KinematicState) -> ConstraintRows:
        return ConstraintRows(np.zeros((0, self.nv)), None, np.zeros(0), np.zeros(0, bool), [])

    def rows(self, kin: KinematicState) -> ConstraintRows:
        return ConstraintRows(np.zeros((0, self.nv)), np.zeros((0, self.nv)), np.zeros(0), np.zeros(0, bool), [])

    def drift(self, kin: KinematicState) -> np.ndarray:
        return np.zeros(0)

    def penetration(self, kin: KinematicState) -> float:
        """:math:`\\delta = -\\phi` [m] at the configuration of ``kin`` (> 0: in contact).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` (its q is used).

        Returns:
            The penetration :math:`\\delta` [m] (> 0 in contact, <= 0 in the air).
        """
        return -float(self._geometry(kin)[7])

    def state(self, kin: KinematicState) -> dict:
        """The contact at the state of ``kin``: ``delta``, ``rate`` [m/s], ``normal`` f_n [N], ``slip`` s (2,)
        [m/s] (:math:`-\\dot\\phi`), ``force`` (3,) in the contact frame (t1, t2, n) [N], ``E`` (3, 3), ``point`` p,
        ``Q`` (nv,) the generalised force (the normal force along :math:`\\partial\\phi/\\partial q`, see the module), ``friction_power`` :math:`F_t\\cdot s` [W] (<= 0), ``damper_power``
        :math:`-(f_n - f_e)\\dot\\delta` [W] (<= 0).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (v: full velocities (nv,)).

        Returns:
            A dict with the keys listed above (floats [m, m/s, N, W] and NumPy arrays; contact-frame quantities in (t1,
            t2, n), ``point`` in the world frame, ``Q`` in the model's velocity order).
        """
        Aw, geo = self._world_jacobian(kin)
        E = geo[9]
        A = E.T @ Aw
        A[2] = penetration_gradient(self, kin)  # (n^T A_w on a plane)
        u = A @ kin.v
        delta, rate = -float(geo[7]), -float(u[2])
        fn = self.normal_law.force(delta, rate)
        slip = u[:2]
        ft = np.zeros(2)
        if fn > 0.0 and self.law is not None and self.tangent_directions.shape[0]:
            D = self.tangent_directions
            along = D.T @ (D @ slip)  # the slip along the law's directions
            ft = -fn * (D.T @ (D @ self.law.coefficient(along)))
        force = np.array([ft[0], ft[1], fn])
        damper = -(fn - self.normal_law.elastic(delta)) * rate if delta > 0.0 else 0.0
        return dict(delta=delta, rate=rate, normal=fn, slip=slip, force=force, E=E, point=geo[5], Q=A.T @ force,
                    friction_power=float(ft @ slip), damper_power=float(damper))


def penetration_gradient(wheel: RollingWheel, kin: KinematicState) -> np.ndarray:
    """:math:`G = \\partial\\phi/\\partial q` (nv,): the gradient of the wheel's signed distance
    :math:`\\phi(q) = (p_z - f(p_x, p_y))\\,s(p)`, :math:`s = 1/\\|(-f_x, -f_y, 1)\\|`, above the terrain z = f(x, y)
    (:class:`~robotdyn.constraints.rolling_contact.RollingWheel`'s contact point p, the rim point below the centre
    along the terrain normal n taken at p itself), so that :math:`\\dot\\phi = G v` exactly.

    With :math:`\\nabla\\phi` at p equal to :math:`n + (\\phi / s)(\\nabla s, 0)` and
    :math:`\\nabla s = -s^3 H \\nabla f` (H the terrain's Hessian), and the contact point's velocity
    :math:`\\dot p = A_w v - R(\\dot u - \\omega \\times u)` whose second part is along :math:`a \\times u`, normal to
    n (u, a the unit vector from p to the centre and the axle):

    :math:`G = n^T A_w + w^T J_p`, :math:`w = (-\\phi s^2 H \\nabla f, 0)`, :math:`J_p = J_c - u\\,\\partial R/\\partial q
    - R J_u` the contact point's Jacobian, :math:`J_u = K^{-1} P (Q_a N (J_c - u\\,\\partial R/\\partial q) + (a n^T +
    (n\\cdot a) I)[a]_\\times J_\\omega)` the derivative of u (the implicit solve of
    :meth:`~robotdyn.constraints.rolling_contact.RollingWheel.contact`: :math:`P = (I - u u^T)/|n - (n\\cdot a) a|`,
    :math:`Q_a = I - a a^T`, N = dn/dp, :math:`K = I + R P Q_a N`). On a plane (H = 0) :math:`G = n^T A_w`.

    Args:
        wheel: The wheel (a :class:`CompliantWheel` or any rolling wheel).
        kin: The :class:`~robotdyn.constraints.constraint.KinematicState` (its q).

    Returns:
        G (nv,) [m per unit of each coordinate].
    """
    Aw, geo = wheel._world_jacobian(kin)
    c, a, R, n, u, p, nw, phi, N, E, nc1 = geo
    row = n @ Aw
    if N is None:
        return row
    terrain = wheel.terrain
    grad = np.asarray(terrain.gradient(p[0], p[1]), float)
    H = np.asarray(terrain.hessian(p[0], p[1]), float)
    w = np.zeros(3)
    w[:2] = -phi / (1.0 + grad @ grad) * (H @ grad)
    if not np.any(w):
        return row
    _, jac = kin.pose(wheel.fid)
    Jc = jac[:3].copy()
    if wheel.radius_index is not None:
        Jc[:, wheel.radius_index] -= u  # the centre's velocity less R-dot u
    P = (np.eye(3) - np.outer(u, u)) / nw
    Qa = np.eye(3) - np.outer(a, a)
    K = np.eye(3) + R * P @ Qa @ N
    z = P @ np.linalg.solve(K.T, w)  # w^T K^-1 P = z^T
    skew_a = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    Ju = Qa @ N @ Jc + (np.outer(a, n) + (n @ a) * np.eye(3)) @ skew_a @ jac[3:]  # K P^-1 J_u, on the plane of u
    return row + w @ Jc - R * (z @ Ju)


def compliant_wheels(robot) -> list[CompliantWheel]:
    """The robot's compliant wheels (empty: every wheel's normal contact is a constraint).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` (its ``constraints``, in their order).

    Returns:
        The :class:`CompliantWheel` constraints of ``robot``, in constraint order (empty if none).
    """
    return [c for c in robot.constraints if isinstance(c, CompliantWheel)]


def _number(value, what: str, unit: str, positive: bool = False) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if not math.isfinite(x) or x < 0 or (positive and x == 0):
        raise InputError(f"{what} = {value!r}; expected a finite number {'> 0' if positive else '>= 0'}"
                         + (f" [{unit}]" if unit else ""))
    return x


__all__ = ["NormalLaw", "LinearContact", "HuntCrossley", "CompliantWheel", "make_normal_law", "compliant_wheels", "compliant_wheel",
           "penetration_gradient", "CONTACT_LAWS"]


def compliant_wheel(robot, w, radius: float, roller_angle: float, **kwargs) -> CompliantWheel:
    """A :class:`CompliantWheel` from a spec's :class:`~robotdyn.robot.Wheel` with ``contact = "compliant"``.

    The normal law's numbers: the wheel's ``normal_stiffness`` and ``normal_damping``, or the default rule of
    :mod:`robotdyn.contact.compliance` (1 mm static deflection under an equal share of the weight; for
    hunt_crossley the same deflection: :math:`k = (m g / n) / \\delta_0^{\\,n}`, damping
    :math:`1.5\\,\\alpha k`). The friction law (``friction`` = coulomb or linear, with its mu, slip_velocity,
    stiffness) acts on the wheel's tangential directions by kind; with ``friction = "rolling"`` (the default) the
    wheel rolls without slipping along them while it presses on the ground; a support wheel is frictionless.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` under construction (description, mass, gravity and spec wheels
            set: the default rule uses its weight and number of wheels).
        w: The :class:`~robotdyn.robot.Wheel` declaration.
        radius: The wheel's radius [m] (parameters resolved).
        roller_angle: Omni wheels: the rollers' angle [rad] from the rolling direction (see
            :class:`~robotdyn.robot.Wheel`); the friction law acts along (cos, sin) of it in (t1, t2). Unused for
            other kinds.
        **kwargs: axis, terrain, radius_joint, name: passed to :class:`CompliantWheel` (as
            :class:`~robotdyn.constraints.rolling_contact.RollingWheel`).

    Returns:
        The :class:`CompliantWheel`.

    Raises:
        InputError: contact not rigid/compliant, stick_slip or slip = 'lateral' on a compliant wheel, a friction
            law on a support, bad numbers. (``friction = "rolling"``, the default, on a standard or omni wheel:
            it rolls without slipping while in contact, :mod:`robotdyn.contact.compliant_rolling`.)
    """
    from .compliance import STATIC_DEFLECTION, normal_compliance, weight
    from .friction import make_law

    name = w.name or w.frame
    if w.contact != "compliant":
        raise InputError(f"wheel {name!r}: contact = {w.contact!r}; expected 'rigid' or 'compliant'")
    if w.kind not in ("standard", "omni", "support"):
        raise InputError(f"wheel {name!r}: kind {w.kind!r}; expected 'standard', 'omni' or 'support'")
    law = None
    rolling = False
    if w.kind == "support":
        if w.friction not in ("rolling", None):
            raise InputError(f"wheel {name!r}: friction law {w.friction!r} on a support wheel (frictionless)")
        directions = np.zeros((0, 2))
    else:
        if w.friction == "stick_slip" or w.slip != "both":
            raise InputError(f"wheel {name!r}: contact = 'compliant' takes friction = 'rolling' (rolls while in "
                             "contact), 'coulomb' or 'linear' with slip = 'both'")
        if w.friction in ("rolling", None):
            if w.mu is not None and not (math.isfinite(float(w.mu)) and float(w.mu) >= 0):
                raise InputError(f"wheel {name!r}: mu = {w.mu}; expected a friction coefficient >= 0")
            rolling = True  # robotdyn.contact.compliant_rolling: its tangential rows hold while it presses
        else:
            law = make_law(w.friction, w.mu, w.slip_velocity, w.stiffness, wheel=name)
        directions = np.eye(2) if w.kind == "standard" else \
            np.array([[math.cos(roller_angle), math.sin(roller_angle)]])
    if w.normal_stiffness is not None:
        k = w.normal_stiffness
    else:  # the rule of robotdyn.contact.compliance: 1 mm under an equal share of the weight
        share = weight(robot) / max(len(robot.spec.wheels), 1)
        n = 1.0 if w.contact_law == "linear" else (HUNT_CROSSLEY_EXPONENT if w.contact_exponent is None
                                                   else float(w.contact_exponent))
        k = share / STATIC_DEFLECTION ** n
    damping = w.normal_damping
    if damping is None and w.contact_law == "linear":
        names = [x.name or x.frame for x in robot.spec.wheels]
        rule = normal_compliance(robot)
        i = names.index(name) if name in names else 0
        damping = float(rule.damping[i])  # c = 2 * 0.3 * sqrt(k m / n) with this wheel's k
    normal = make_normal_law(w.contact_law, k, damping, w.contact_exponent, wheel=name)
    return CompliantWheel(robot.description, w.frame, radius, normal, law, directions, w.kind, rolling, **kwargs)

"""Friction laws of a wheel that slips: the tangential contact force as a function of the slip velocity and the
normal load.

The slip velocity :math:`s` (2,) [m/s] is the velocity of the wheel's material point at the contact, in the
contact frame's tangent plane (t1 longitudinal, t2 lateral; :mod:`robotdyn.constraints.rolling_contact`). Every law here is
linear in the normal load :math:`f_n` [N]:

.. math:: F_t = -f_n\\, c(s),

which keeps the dynamics with an unknown, acceleration-dependent :math:`f_n` a linear system
(:mod:`robotdyn.contact.sliding`). The dissipated power is :math:`F_t\\cdot s = -f_n\\, c(s)\\cdot s \\le 0` for
:math:`f_n \\ge 0`.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError


class FrictionLaw:
    """Base class: the friction coefficient vector :math:`c(s)` with :math:`F_t = -f_n c(s)`."""

    name = "law"

    def coefficient(self, s: np.ndarray) -> np.ndarray:
        """:math:`c(s)` (2,) for the slip velocity s (2,) [m/s].

        Args:
            s: The slip velocity (2,) [m/s] of the wheel's material point at the contact, in (t1, t2) of its contact
                frame.

        Returns:
            c(s) (2,) [-]: the friction force is -f_n c(s).
        """
        raise NotImplementedError

    def force(self, s: np.ndarray, normal: float) -> np.ndarray:
        """Tangential force on the wheel :math:`F_t = -f_n c(s)` (2,) [N].

        Args:
            s: The slip velocity (2,) [m/s] of the wheel's material point at the contact, in (t1, t2) of its contact
                frame.
            normal: The normal load f_n [N] (>= 0).

        Returns:
            The tangential force (2,) [N] in (t1, t2).
        """
        return -float(normal) * self.coefficient(np.asarray(s, float))

    def encode(self) -> tuple[int, float, float] | None:
        """The law as data for the compiled engine (``robotdyn/kernels/sliding.hpp``, ``Slip``): ``(code, p0, p1)``, or
        ``None`` where its formula is not compiled (the robot then runs on the Python path).

        Returns:
            ``(code, p0, p1)`` (an int and two floats in the law's own units), or ``None``.
        """
        return None


class RegularisedCoulomb(FrictionLaw):
    """Coulomb friction smoothed near zero slip:

    .. math:: c(s) = \\mu\\, \\frac{s}{\\sqrt{\\|s\\|^2 + v_s^2}},

    equal to Coulomb's :math:`\\mu\\,\\hat s` to a relative :math:`(v_s/\\|s\\|)^2/2` once the slip is well above the
    slip-velocity scale :math:`v_s`, and viscous (:math:`\\mu s / v_s`) below it, so a wheel never sticks exactly:
    it creeps at a slip of order :math:`v_s\\, \\mu_{req}/\\mu`.

    Args:
        mu: Friction coefficient (>= 0).
        slip_velocity: The regularisation scale :math:`v_s` [m/s] (> 0).
    """

    name = "coulomb"

    def __init__(self, mu: float, slip_velocity: float = 1e-3) -> None:
        self.mu = _coefficient(mu, "mu")
        self.slip_velocity = _positive(slip_velocity, "slip_velocity", "m/s")

    def coefficient(self, s: np.ndarray) -> np.ndarray:
        return self.mu * s / math.sqrt(float(s @ s) + self.slip_velocity**2)

    def encode(self) -> tuple[int, float, float] | None:
        """``(0, mu, slip_velocity)`` (:meth:`FrictionLaw.encode`; a subclass with its own formula: ``None``).

        Returns:
            ``(0, mu, slip_velocity)`` (mu dimensionless, slip_velocity [m/s]), or ``None``.
        """
        return (0, self.mu, self.slip_velocity) if type(self).coefficient is RegularisedCoulomb.coefficient else None

    def __repr__(self) -> str:
        return f"RegularisedCoulomb(mu={self.mu}, slip_velocity={self.slip_velocity} m/s)"


class LinearTyre(FrictionLaw):
    """A linear (brush-type) law, saturated at Coulomb's limit:

    .. math:: c(s) = \\min(k\\|s\\|, \\mu)\\, \\hat s,

    i.e. a force per unit load proportional to the slip velocity with slip stiffness k [s/m] until it reaches
    :math:`\\mu` (the brush model's fully sliding regime).

    Args:
        stiffness: k [s/m] (> 0): force per unit normal load per unit slip velocity.
        mu: Saturation friction coefficient (>= 0; ``inf`` for a purely linear law).
    """

    name = "linear"

    def __init__(self, stiffness: float, mu: float = math.inf) -> None:
        self.stiffness = _positive(stiffness, "stiffness", "s/m")
        self.mu = float(mu) if mu == math.inf else _coefficient(mu, "mu")

    def coefficient(self, s: np.ndarray) -> np.ndarray:
        speed = math.sqrt(float(s @ s))
        if speed * self.stiffness <= self.mu:
            return self.stiffness * s
        return self.mu * s / speed

    def encode(self) -> tuple[int, float, float] | None:
        """``(1, stiffness, mu)`` (:meth:`FrictionLaw.encode`; a subclass with its own formula: ``None``).

        Returns:
            ``(1, stiffness, mu)`` (stiffness [s/m], mu dimensionless), or ``None``.
        """
        return (1, self.stiffness, self.mu) if type(self).coefficient is LinearTyre.coefficient else None

    def __repr__(self) -> str:
        return f"LinearTyre(stiffness={self.stiffness} s/m, mu={self.mu})"


class ExactCoulomb(FrictionLaw):
    """Coulomb friction without regularisation, for wheels that stick and slide with exact switching
    (:mod:`robotdyn.simulation.stick_slip`): sticking inside the cone :math:`\\|f_t\\| \\le \\mu f_n`, sliding with
    :math:`c = \\mu\\hat s`.

    Args:
        mu: Friction coefficient (>= 0).
    """

    name = "stick_slip"

    def __init__(self, mu: float) -> None:
        self.mu = _coefficient(mu, "mu")

    def coefficient(self, s: np.ndarray) -> np.ndarray:
        speed = math.sqrt(float(s @ s))
        if speed == 0.0:
            raise InputError("exact Coulomb friction has no direction at zero slip; expected a sliding wheel")
        return self.mu * s / speed

    def __repr__(self) -> str:
        return f"ExactCoulomb(mu={self.mu})"


LAWS = {"coulomb": RegularisedCoulomb, "linear": LinearTyre}
"""The friction laws by the name used in TOML files and the API (``rolling``: no slip, the default)."""


def make_law(name: str, mu: float | None = None, slip_velocity: float | None = None,
             stiffness: float | None = None, wheel: str = "wheel") -> FrictionLaw:
    """A friction law from its name and parameters, with one-line errors naming the wheel.

    Args:
        name: ``coulomb`` (needs ``mu``; ``slip_velocity`` default 1e-3 m/s), ``linear`` (needs ``stiffness``;
            ``mu`` saturates it, default none) or ``stick_slip`` (needs ``mu``: exact switching,
            :mod:`robotdyn.simulation.stick_slip`).
        wheel: The wheel's name, for messages.
        mu: Friction coefficient (>= 0; default ``None``: not given).
        slip_velocity: The coulomb law's regularisation velocity [m/s] (> 0; default ``None``: 1e-3).
        stiffness: The linear law's slip stiffness [s/m] (> 0; default ``None``).

    Returns:
        The :class:`FrictionLaw` instance (:class:`ExactCoulomb`, :class:`RegularisedCoulomb` or :class:`LinearTyre`).
    """
    try:
        if name == "stick_slip":
            if mu is None:
                raise InputError("the stick_slip law needs mu")
            if slip_velocity is not None or stiffness is not None:
                raise InputError("stick_slip is exact Coulomb friction: no slip_velocity or stiffness")
            return ExactCoulomb(mu)
        if name == "coulomb":
            if mu is None:
                raise InputError("the coulomb law needs mu")
            return RegularisedCoulomb(mu, 1e-3 if slip_velocity is None else slip_velocity)
        if name == "linear":
            if stiffness is None:
                raise InputError("the linear law needs stiffness [s/m]")
            if slip_velocity is not None:
                raise InputError("slip_velocity belongs to the coulomb law")
            return LinearTyre(stiffness, math.inf if mu is None else mu)
    except InputError as exc:
        raise InputError(f"wheel {wheel!r}: {exc}") from None
    raise InputError(f"wheel {wheel!r}: unknown friction law {name!r}; expected one of rolling, {', '.join(LAWS)}, "
                     "stick_slip")


def _coefficient(value, what: str) -> float:
    value = float(value)
    if not math.isfinite(value) or value < 0:
        raise InputError(f"{what} = {value}; expected a finite friction coefficient >= 0")
    return value


def _positive(value, what: str, unit: str) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0:
        raise InputError(f"{what} = {value} {unit}; expected a finite number > 0")
    return value

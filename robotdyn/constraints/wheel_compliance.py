"""The wheels' normal (radial) compliance: a stiffness and a damping per wheel, given or by a stated rule.

Each wheel of a robot's spec may carry ``normal_stiffness`` k [N/m] and ``normal_damping`` c [N s/m] (the
constraint file's wheel keys of the same names). Where they are not given, the default rule is

- stiffness: :math:`k = m g / (n\\,\\delta_0)`, the robot's weight shared equally by its n wheels deflecting each
  wheel by :data:`STATIC_DEFLECTION` (1 mm, a solid rubber or small pneumatic tyre of a mobile robot). The rule
  uses the robot's total mass and the number of wheels only, never the loads themselves (on a statically
  indeterminate chassis the loads are what the stiffnesses are asked to decide, so a rule from them is circular;
  the concepts page ``docs/concepts.md``, "Determined and undetermined forces"). All defaulted wheels of a robot
  get the same k.
- damping: :math:`c = 2\\zeta\\sqrt{k\\,m/n}` with :data:`DAMPING_RATIO` :math:`\\zeta = 0.3`: the wheel's share
  m/n of the mass on the wheel's stiffness k (given or default) is damped at that ratio.

(In the constraints stage, so that the compiled model of :mod:`robotdyn.fast` reads the same values;
:mod:`robotdyn.contact.compliance` is its public name in the contact stage.) The rigid limit of the loads
(:mod:`robotdyn.contact.rigid_limit`) depends only on the ratios k_i / k_j, so with
the default rule every wheel weighs the same; a compliant (flying) contact model uses the values themselves.
A robot without mass (or without gravity) takes m g = 1 N in the rule (only the ratios then matter).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError

STATIC_DEFLECTION = 1e-3
"""Static deflection [m] of a wheel carrying its equal share of the robot's weight, for the default stiffness."""

DAMPING_RATIO = 0.3
"""Damping ratio of a wheel's share of the robot's mass on its normal stiffness, for the default damping."""


@dataclass(frozen=True)
class NormalCompliance:
    """The wheels' normal stiffness and damping, in the order of the robot's spec wheels.

    Attributes:
        names: The wheels' names.
        stiffness: (n,) normal stiffness k [N/m], > 0.
        damping: (n,) normal damping c [N s/m], >= 0.
        given: (n,) whether the stiffness was given (False: the default rule).
        rule: The default rule in words (for reports).
    """

    names: tuple[str, ...]
    stiffness: np.ndarray
    damping: np.ndarray
    given: np.ndarray
    rule: str


def weight(robot) -> float:
    """The robot's weight m g [N] for the default rule (1 N for a robot without mass or gravity).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`: its model's total mass m [kg] and the norm of its gravity g
            [m/s^2].

    Returns:
        m g [N] if finite and > 0, else 1.0.
    """
    mass = float(pin.computeTotalMass(robot.model))
    g = float(np.linalg.norm(robot.model.gravity.linear))
    w = mass * g
    return w if np.isfinite(w) and w > 0 else 1.0


def normal_compliance(robot) -> NormalCompliance:
    """Each wheel's normal stiffness and damping: the spec's values, or the default rule of this module.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` (its ``spec.wheels`` and model's mass and gravity).

    Returns:
        The :class:`NormalCompliance` of the spec's wheels, in their order.

    Raises:
        InputError: A given stiffness is not a finite number > 0, or a damping not a finite number >= 0.
    """
    wheels = list(robot.spec.wheels)
    n = max(len(wheels), 1)
    w = weight(robot)
    g = float(np.linalg.norm(robot.model.gravity.linear)) or 9.81
    share = w / g / n  # each wheel's share of the mass [kg]
    k_default = w / (n * STATIC_DEFLECTION)
    names, k, c, given = [], [], [], []
    for wheel in wheels:
        name = wheel.name or wheel.frame
        ki = wheel.normal_stiffness
        if ki is not None and not (np.isfinite(float(ki)) and float(ki) > 0):
            raise InputError(f"wheel {name!r}: normal_stiffness = {ki}; expected a stiffness in N/m, > 0")
        ci = wheel.normal_damping
        if ci is not None and not (np.isfinite(float(ci)) and float(ci) >= 0):
            raise InputError(f"wheel {name!r}: normal_damping = {ci}; expected a damping in N s/m, >= 0")
        kv = float(ki) if ki is not None else k_default
        names.append(name)
        k.append(kv)
        c.append(float(ci) if ci is not None else 2.0 * DAMPING_RATIO * np.sqrt(kv * share))
        given.append(ki is not None)
    rule = (f"default k = m g / (n * {STATIC_DEFLECTION * 1e3:g} mm) = {k_default:.4g} N/m, "
            f"c = 2 * {DAMPING_RATIO:g} * sqrt(k m / n)")
    return NormalCompliance(tuple(names), np.array(k, float), np.array(c, float), np.array(given, bool), rule)


def wheel_stiffness(robot, names: list[str]) -> np.ndarray:
    """The normal stiffness [N/m] of the robot's wheels called ``names`` (:func:`normal_compliance`, kept on the
    robot as ``_normal_compliance``; a wheel constraint that is not among the spec's wheels gets the default
    rule's value).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        names: Wheel names, e.g. those of its wheel constraints in their order.

    Returns:
        (len(names),) stiffnesses [N/m].
    """
    comp = getattr(robot, "_normal_compliance", None)
    if comp is None:
        comp = robot._normal_compliance = normal_compliance(robot)
    by_name = dict(zip(comp.names, comp.stiffness))
    default = weight(robot) / (max(len(comp.names), 1) * STATIC_DEFLECTION)
    return np.array([by_name.get(n, default) for n in names], float)


__all__ = ["NormalCompliance", "normal_compliance", "wheel_stiffness", "weight", "STATIC_DEFLECTION", "DAMPING_RATIO"]

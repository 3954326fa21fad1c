"""Joint springs and compliant wheels on the compiled model: the applied forces of
:mod:`robotdyn.contact.applied_forces` encoded for ``robotdyn/_compiled.cpp`` (formulas in
``robotdyn/kernels/joint_springs.hpp`` and ``robotdyn/kernels/compliant_contact.hpp``).

The general compiled model (:func:`robotdyn.fast.dispatch.compiled_model`, behind every door that evaluates a
reduced model) still refuses robots with springs or compliant wheels in one line (:func:`robotdyn.fast.compiled.why_not`):
their doors add the applied forces on the Python path. The compiled *simulation* of such robots
(:mod:`robotdyn.simulation.compiled_engine`, default integrator ``rosenbrock4``) takes its own model from
:func:`applied_model`, in which the evaluator adds :math:`S^T Q(q, v)` to the reduced equations, carries the
friction and damper work as two extra states and counts the stored energy, exactly as the scipy path does with
:func:`robotdyn.contact.applied_forces.applied`.
"""

from __future__ import annotations

import threading

import numpy as np

from ..errors import RobotDynError

LAW_KINDS = {"linear": 0, "hunt_crossley": 1}
"""The C++ codes of the normal force laws (``kernels::NormalLaw``)."""


def compliant_refusal(wheel) -> str | None:
    """Why a compliant wheel's laws are not compiled (``None``: they are).

    Args:
        wheel: A :class:`~robotdyn.contact.compliant_contact.CompliantWheel`.

    Returns:
        A one-line reason, or ``None``.
    """
    from ..contact.compliant_contact import HuntCrossley, LinearContact

    law = wheel.normal_law
    if type(law) not in (LinearContact, HuntCrossley):
        return f"wheel {wheel.name!r}: its normal law {law!r} is not compiled"
    if wheel.law is not None and wheel.law.encode() is None:
        return f"wheel {wheel.name!r}: its friction law {wheel.law!r} is not compiled"
    return None


def add_compliant_wheel(ev, wheel, frame: int) -> None:
    """Give the evaluator ``ev`` a compliant wheel: its contact geometry (as a wheel without rows), its normal law
    and its friction law on its tangential directions.

    Args:
        ev: The ``robotdyn._compiled.Evaluator`` under construction.
        wheel: The :class:`~robotdyn.contact.compliant_contact.CompliantWheel`.
        frame: The evaluator's index of the wheel's frame.
    """
    law = wheel.normal_law
    kind = LAW_KINDS[law.name]
    exponent = float(getattr(law, "exponent", 1.0))
    code, p0, p1 = (-1, 0.0, 0.0) if wheel.law is None else wheel.law.encode()
    D = np.asarray(wheel.tangent_directions, float).reshape(-1, 2)
    if wheel.law is None:
        D = np.zeros((0, 2))
    ev.add_compliant_wheel(frame, np.asarray(wheel.axis, float), float(wheel.radius),
                           -1 if wheel.radius_index is None else int(wheel.radius_index), kind,
                           float(law.stiffness), float(law.damping), exponent, int(code), float(p0), float(p1), D)


def add_springs(ev, robot) -> None:
    """Give the evaluator ``ev`` the robot's joint springs (:class:`~robotdyn.reduction.joint_springs.SpringForce`).

    Args:
        ev: The ``robotdyn._compiled.Evaluator`` under construction.
        robot: The :class:`~robotdyn.robot.Robot`.
    """
    for s in getattr(robot, "springs", ()):
        ev.add_spring(int(s.index), float(s.stiffness), float(s.damping), float(s.rest))


def _key(robot) -> tuple:
    """What the applied model is built from (a change rebuilds it)."""
    springs = tuple((s.index, s.stiffness, s.damping, s.rest) for s in getattr(robot, "springs", ()))
    laws = tuple((id(c), getattr(c, "terrain", None), getattr(c, "radius", None), getattr(c, "law", None),
                  repr(getattr(c, "normal_law", None))) for c in robot.constraints)
    return springs, laws, tuple(robot.model.gravity.linear)


def applied_model(robot):
    """The robot's compiled model with its joint springs and compliant wheels, for the calling thread (built once
    per thread and rebuilt when its constraints, laws, springs or gravity change), or ``None`` where the compiled
    path is off or cannot serve it (:func:`robotdyn.fast.compiled.why_not` with ``applied=True`` names why).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (with springs or compliant wheels).

    Returns:
        The :class:`~robotdyn.fast.compiled.CompiledModel`, or ``None``.
    """
    from .compiled import CompiledModel, why_not
    from .dispatch import enabled

    if not enabled() or why_not(robot, applied=True) is not None:
        return None
    key = (threading.get_ident(), _key(robot))
    cached = robot.__dict__.get("_applied_model")
    if cached is not None and cached[0] == key:
        return cached[1]
    fast = CompiledModel(robot)
    robot.__dict__["_applied_model"] = (key, fast)
    return fast


def applied_state(fast, q: np.ndarray, nu: np.ndarray) -> tuple:
    """The compiled :func:`robotdyn.contact.applied_forces.applied` at (q, nu).

    Args:
        fast: An :func:`applied_model`.
        q: Natural coordinates (n,) [m, rad].
        nu: Independent velocities (k,).

    Returns:
        ``(Q, friction_power, damper_power, contacts)``: Q (n,) [N, N m], the powers [W], and per compliant wheel
        (delta [m], rate [m/s], F_t1, F_t2, f_n [N]) as rows (w, 5).
    """
    if not fast.ready:
        fast._choose(q, nu)
    try:
        return fast.ev.applied_state(np.asarray(q, float), np.asarray(nu, float))
    except RuntimeError as exc:
        raise RobotDynError(f"compiled applied forces: {exc}") from None


__all__ = ["applied_model", "applied_state", "add_compliant_wheel", "add_springs", "compliant_refusal", "LAW_KINDS"]

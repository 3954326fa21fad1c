"""Joint springs and compliant wheels on the compiled model: the applied forces of
:mod:`robotdyn.contact.applied_forces` encoded for ``robotdyn/_compiled.cpp`` (formulas in
``robotdyn/kernels/joint_springs.hpp`` and ``robotdyn/kernels/compliant_contact.hpp``).

This module encodes them for :class:`robotdyn.fast.compiled.CompiledModel`. Joint springs and dampers are in the
general compiled model (:func:`robotdyn.fast.dispatch.compiled_model`, behind every door that evaluates a reduced
model): its reduced model is without them (as the Python path's, whose doors add :math:`S^T Q`), its forward
dynamics, derivative set and constraint forces carry them (``robotdyn/kernels/joint_springs_derivatives.hpp``). The
general model still refuses compliant wheels in one line (:func:`robotdyn.fast.compiled.why_not`). The compiled
*simulation* of a robot with either (:mod:`robotdyn.simulation.compiled_engine`) takes its own model from
:func:`robotdyn.fast.applied_model.applied_model`, in which the evaluator adds :math:`S^T Q(q, v)` to the reduced
equations, carries the friction and damper work as two extra states and counts the stored energy, exactly as the
scipy path does with :func:`robotdyn.contact.applied_forces.applied`.
"""

from __future__ import annotations

import numpy as np

LAW_KINDS = {"linear": 0, "hunt_crossley": 1}
"""The C++ codes of the normal force laws (``kernels::NormalLaw``)."""


def compliant_refusal(wheel) -> str | None:
    """Why a compliant wheel's laws are not compiled (``None``: they are).

    Args:
        wheel: A :class:`~robotdyn.contact.compliant_contact.CompliantWheel`.

    Returns:
        A one-line reason, or ``None``.
    """
    law = wheel.normal_law  # (by its class's name: this stage does not import the contact stage)
    if type(law).__name__ not in ("LinearContact", "HuntCrossley") or getattr(law, "name", None) not in LAW_KINDS:
        return f"wheel {wheel.name!r}: its normal law {law!r} is not compiled"
    if wheel.law is not None and wheel.law.encode() is None:
        return f"wheel {wheel.name!r}: its friction law {wheel.law!r} is not compiled"
    return None


def add_compliant_wheel(ev, wheel, frame: int) -> None:
    """Give the evaluator ``ev`` a compliant wheel: its contact geometry (as a wheel without rows), its normal law
    and its friction law on its tangential directions, or, for a wheel that rolls while in contact
    (:mod:`robotdyn.contact.compliant_rolling`), its rolling rows on those directions.

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
    if getattr(wheel, "rolling", False):  # rolls while in contact (kernels/compliant_rolling.hpp)
        ev.add_rolling_rows(np.asarray(wheel.tangent_directions, float).reshape(-1, 2))


def add_springs(ev, robot) -> None:
    """Give the evaluator ``ev`` the robot's joint springs (:class:`~robotdyn.reduction.joint_springs.SpringForce`).

    Args:
        ev: The ``robotdyn._compiled.Evaluator`` under construction.
        robot: The :class:`~robotdyn.robot.Robot`.
    """
    for s in getattr(robot, "springs", ()):
        ev.add_spring(int(s.index), float(s.stiffness), float(s.damping), float(s.rest))


__all__ = ["add_compliant_wheel", "add_springs", "compliant_refusal", "LAW_KINDS"]

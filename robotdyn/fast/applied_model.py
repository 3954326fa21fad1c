"""The compiled model of a robot with joint springs or compliant wheels, for its compiled simulation
(:mod:`robotdyn.simulation.compiled_engine`): :func:`applied_model` builds it (the encoding is
:mod:`robotdyn.fast.compiled_applied`'s), :func:`applied_state` evaluates its applied forces at one state.
"""

from __future__ import annotations

import threading

import numpy as np

from ..errors import RobotDynError
from .compiled import CompiledModel, why_not
from .dispatch import enabled


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
    if not enabled() or why_not(robot, applied=True) is not None:
        return None
    # kept in the robot's per-thread storage (as compiled_model does): one slot shared by all threads made two
    # threads rebuild each other's model at every run (11 ms on examples/bump_base_rolling.toml), and a robot
    # holding it could not be pickled (Robot.__getstate__ drops the per-thread storage)
    local = getattr(robot, "_local", None)
    key = (threading.get_ident(), _key(robot))
    cached = getattr(local, "applied", None) if local is not None else robot.__dict__.get("_applied_model")
    if cached is not None and cached[0] == key:
        return cached[1]
    fast = CompiledModel(robot)
    if local is not None:
        local.applied = (key, fast)
    else:
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


__all__ = ["applied_model", "applied_state"]

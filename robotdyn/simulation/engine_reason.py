"""Why a simulation runs on the Python (scipy) path rather than the compiled engine, in words, for the run's
summary: a run on the Python path can take a hundred times longer (a rigid four-wheel Husky turning in place under
a Coulomb law took 78 s for 1 s simulated there, before its coupled solve was compiled), and its user should learn
why without reading the source."""

from __future__ import annotations

from ..errors import RobotDynError

_PREFIX = "engine = 'compiled' cannot run this simulation: "


def python_path_reason(robot, torque, method: str | None = None) -> str | None:
    """The reason the compiled engine cannot run a simulation of ``robot`` under ``torque`` (None: it can).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` simulated.
        torque: Its torque law (``None``, a profile, a feedback law or a Python callable).
        method: The integrator method asked for (``None``: the default).

    Returns:
        The reason in one line (:func:`robotdyn.simulation.compiled_engine.choose_engine`'s), or None.
    """
    from .compiled_engine import choose_engine

    try:
        choose_engine(robot, torque, method, "compiled")
    except RobotDynError as exc:
        text = str(exc)
        return text[len(_PREFIX):] if text.startswith(_PREFIX) else text
    return None


__all__ = ["python_path_reason"]

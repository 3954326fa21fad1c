"""robotdyn: dynamics of wheeled mobile robots with closed kinematic loops and rolling contacts.

Quick start::

    import robotdyn
    robot = robotdyn.load("quasimoro")
    red = robot.reduced(q=[0, 0, 0, 0, 0, 0.1], nu=[1.0, 1.0, 0.0])
    red.M, red.h
"""

from __future__ import annotations

from .errors import RobotDynError
from .robot import Robot, RobotSpec

__all__ = ["Robot", "RobotSpec", "RobotDynError", "load", "robots_available"]
__version__ = "0.1.0"


def robots_available() -> list[str]:
    """Names of the registered robots."""
    from .robots import names

    return names()


def load(name: str, params: dict | None = None, terrain=None) -> Robot:
    """Build a registered robot with optional parameter overrides (name -> value)."""
    from .robots import module

    return Robot(module(name).SPEC, params, terrain)

"""robotdyn: dynamics of wheeled mobile robots with closed kinematic loops and rolling contacts.

Quick start::

    import robotdyn
    robot = robotdyn.load("quasimoro")
    red = robot.reduced(q=[0, 0, 0, 0, 0, 0.1], nu=[1.0, 1.0, 0.0])
    red.M, red.h
"""

from __future__ import annotations

from ._lazy import lazy_exports
from .errors import RobotDynError
from .robot import Robot, RobotSpec

__all__ = ["Robot", "RobotSpec", "RobotDynError", "load", "load_robot", "robots_available"]
__getattr__ = lazy_exports(__name__, {"load_robot": "interfaces.constraint_file"})  # your own robot, from TOML


def _version() -> str:
    """The installed distribution's version (one source of truth: ``version`` in pyproject.toml)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("robotdyn")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "0+unknown"


__version__ = _version()
"""robotdyn's version, from the package metadata (``version`` in pyproject.toml)."""


def robots_available() -> list[str]:
    """Names of the registered robots."""
    from .robots import names

    return names()


def load(name: str, params: dict | None = None, terrain=None) -> Robot:
    """Build a registered robot with optional parameter overrides (name -> value)."""
    from .errors import UnknownRobotError
    from .robots import module

    if isinstance(name, str) and name.lower().endswith((".toml", ".urdf", ".xacro")):
        raise UnknownRobotError(f"load({name!r}): load() takes a registered robot's name (robotdyn.robots_available()); "
                                "for your own robot's constraint file use robotdyn.load_robot(path)")
    return Robot(module(name).SPEC, params, terrain)

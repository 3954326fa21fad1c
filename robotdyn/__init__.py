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
    """Names of the registered robots.

    Returns:
        The names :func:`load` accepts, sorted.

    Example:
        >>> import robotdyn
        >>> "quasimoro" in robotdyn.robots_available()
        True
    """
    from .robots import names

    return names()


def load(name: str, params: dict | None = None, terrain=None) -> Robot:
    """Build a registered robot (``robotdyn list``) with optional parameter overrides.

    For your own robot, described by a constraint file and a URDF, use
    :func:`robotdyn.load_robot` instead.

    Args:
        name: The robot's registry name (:func:`robots_available`).
        params: Parameter values by name, in the units ``robotdyn info NAME`` lists (default ``None``: the
            defaults); an unknown name is an error.
        terrain: A :class:`~robotdyn.constraints.terrain.Terrain` replacing the robot's own (default ``None``: its
            own, usually flat ground z = 0).

    Returns:
        The built :class:`~robotdyn.robot.Robot`.

    Raises:
        UnknownRobotError: No registered robot has that name (a file name is answered with a hint of
            :func:`load_robot`).
        InputError: An unknown parameter or an invalid value.

    Example:
        >>> import robotdyn
        >>> robot = robotdyn.load("quasimoro", {"M": 6.0})
        >>> robot.coordinates
        ['x', 'y', 'psi', 'theta1', 'theta2', 'theta3']
        >>> robot.velocity_names
        ['theta1_dot', 'theta2_dot', 'theta3_dot']
    """
    from .errors import UnknownRobotError
    from .robots import module

    if isinstance(name, str) and name.lower().endswith((".toml", ".urdf", ".xacro")):
        raise UnknownRobotError(f"load({name!r}): load() takes a registered robot's name (robotdyn.robots_available()); "
                                "for your own robot's constraint file use robotdyn.load_robot(path)")
    return Robot(module(name).SPEC, params, terrain)

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
    :func:`robotdyn.interfaces.constraint_file.load_robot` instead.

    Args:
        name: The robot's registry name (:func:`robots_available`).
        params: Parameter values by name, in the units ``robotdyn info NAME`` lists (default ``None``: the
            defaults); an unknown name is an error.
        terrain: A :class:`~robotdyn.constraints.terrain.Terrain` replacing the robot's own (default ``None``: its
            own, usually flat ground z = 0).

    Returns:
        The built :class:`~robotdyn.robot.Robot`.

    Raises:
        UnknownRobotError: No registered robot has that name.
        InputError: An unknown parameter or an invalid value.

    Example:
        >>> import robotdyn
        >>> robot = robotdyn.load("quasimoro", {"M": 6.0})
        >>> robot.coordinates
        ['x', 'y', 'psi', 'theta1', 'theta2', 'theta3']
        >>> robot.velocity_names
        ['theta1_dot', 'theta2_dot', 'theta3_dot']
    """
    from .robots import module

    return Robot(module(name).SPEC, params, terrain)

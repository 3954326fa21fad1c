"""MMR12-EOD climbing a slope in the posture that needs the least friction (issue 26, item 3).

The robot of :func:`robotdyn.robots.mmr12_eod.model.climbing_robot` (floating root on a ramp, the drive wheels rolling
without slipping, the rear arms' tip wheels as frictionless supports, sec 2.11 e of Zuniga-Aviles et al. 2014),
with the platform lift ``lambda_C`` locked: on a floating root it only duplicates the root's height through a
massless link, so that the reduced mass matrix is singular and the forward dynamics (hence the forces under given
motor torques) is not defined with it free.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...robot import Robot
from .model import climbing_robot, climbing_state


def locked_climbing_robot(slope: float, robot: Robot | None = None) -> Robot:
    """:func:`~robotdyn.robots.mmr12_eod.model.climbing_robot` with ``lambda_C`` locked at 0 (the platform on its
    drive wheels, eq (1)).

    Args:
        slope: Ramp angle [rad] (abs(slope) < pi/2).
        robot: The robot whose parameters are kept (default ``None``: the defaults).

    Returns:
        The climbing :class:`~robotdyn.robot.Robot` (18 coordinates, mobility 11, 12 motors).
    """
    base = climbing_robot(slope, robot)
    spec = dataclasses.replace(base.spec, locked={**(base.spec.locked or {}), "lambda_C_joint": 0.0})
    return Robot(spec, base.params, base.terrain)


def locked_climbing_state(robot: Robot, slope: float) -> np.ndarray:
    """:func:`~robotdyn.robots.mmr12_eod.model.climbing_state` on the robot of :func:`locked_climbing_robot`.

    Args:
        robot: The robot of :func:`locked_climbing_robot`.
        slope: Ramp angle [rad].

    Returns:
        Natural coordinates (n,) [m, rad].
    """
    full = climbing_robot(slope, robot)
    q = climbing_state(full, slope)
    return np.array([q[full.coordinate_index(c)] for c in robot.coordinates])


__all__ = ["locked_climbing_robot", "locked_climbing_state"]

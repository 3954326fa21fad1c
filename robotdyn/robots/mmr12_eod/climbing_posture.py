"""MMR12-EOD climbing a slope in the posture that needs the least friction (issue 26, item 3).

The robot of :func:`robotdyn.robots.mmr12_eod.model.climbing_robot` (floating root on a ramp, the drive wheels rolling
without slipping, the rear arms' tip wheels as frictionless supports, sec 2.11 e of Zuniga-Aviles et al. 2014),
with the platform lift ``lambda_C`` locked: on a floating root it only duplicates the root's height through a
massless link, so that the reduced mass matrix is singular and the forward dynamics (hence the forces under given
motor torques) is not defined with it free.

The least-friction posture (:func:`climbing_posture_problem`): at rest on the ramp, holding (the robot's motors
hold it still: :math:`\\dot\\nu = 0`), the manipulator (theta1, lambda2, theta3, theta4), the load slide (lambda6)
and the rear arms (theta_C4; theta_C3 follows from the tips' contact) chosen with the holding torques to minimise
the larger required mu of the two drive wheels, each rear tip keeping a load of at least ``min_tip_load``
(:class:`robotdyn.optimisation.posture.PostureProblem`). The manipulator moves in the robot's plane of symmetry, so
the drive wheels' lateral forces (a squeeze rigid-body dynamics leave open) are zero in the best split and in the
minimum-norm one alike.

A closed form bounds it: the tips are frictionless, so the drive wheels' traction is the whole weight's component
along the ramp, :math:`F_R + F_L = mg\\sin\\psi`, while their loads are the normal component less the tips',
:math:`N_R + N_L = mg\\cos\\psi - N_3 - N_4`; hence :math:`\\max(\\mu_R, \\mu_L) \\ge (F_R + F_L)/(N_R + N_L)
\\ge mg\\sin\\psi / (mg\\cos\\psi - 2F_{\\min})` (:func:`least_mu_bound`), reached by a symmetric posture that
leaves each tip exactly :math:`F_{\\min}` where the joint ranges allow it (a family of postures does: the optimum's
cost is unique, its posture is not). There is no collision model: the posture found is checked against the joint
ranges only.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...robot import Robot
from .model import climbing_robot, climbing_state

POSTURE = ("theta1", "lambda2", "theta3", "theta4", "lambda6", "theta_C4")
"""The decision coordinates of :func:`climbing_posture_problem` (manipulator, load slide, rear arms)."""

TIP_LOAD_SHARE = 0.01
"""Default smallest load of each rear tip, as a share of the robot's weight (keeps it on the ground)."""


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


def weight(robot: Robot) -> float:
    """The robot's weight m g [N].

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.

    Returns:
        Its total mass times the gravitational acceleration [N].
    """
    import pinocchio as pin

    return float(pin.computeTotalMass(robot.model) * np.linalg.norm(robot.model.gravity.linear))


def least_mu_bound(robot: Robot, slope: float, min_tip_load: float) -> float:
    """The closed-form lower bound of the peak required mu on the ramp (module docstring):
    :math:`mg\\sin\\psi / (mg\\cos\\psi - 2F_{\\min})`.

    Args:
        robot: The climbing robot (its mass and gravity).
        slope: Ramp angle psi [rad].
        min_tip_load: Smallest load of each rear tip [N].

    Returns:
        The bound [-].
    """
    mg = weight(robot)
    return mg * np.sin(slope) / (mg * np.cos(slope) - 2.0 * min_tip_load)


def climbing_posture_problem(slope: float, min_tip_load: float | None = None, derivatives: str = "analytic",
                             robot: Robot | None = None):
    """The least-friction climbing posture at rest on a ramp of ``slope`` (module docstring).

    Args:
        slope: Ramp angle [rad] (abs(slope) < pi/2).
        min_tip_load: Smallest load of each rear tip [N] (default: :data:`TIP_LOAD_SHARE` of the weight).
        derivatives: ``analytic`` (default) or ``finite-difference``.
        robot: The robot whose parameters are kept (default ``None``: the defaults).

    Returns:
        The :class:`~robotdyn.optimisation.posture.PostureProblem` (its ``robot`` is the climbing robot; start: the
        posture of :func:`~robotdyn.robots.mmr12_eod.model.climbing_state`).
    """
    from ...optimisation.posture import PostureProblem

    climber = locked_climbing_robot(slope, robot)
    if min_tip_load is None:
        min_tip_load = TIP_LOAD_SHARE * weight(climber)
    return PostureProblem(climber, locked_climbing_state(climber, slope), list(POSTURE),
                          friction_wheels=["W_R", "W_L"], min_load={"tip3": min_tip_load, "tip4": min_tip_load},
                          derivatives=derivatives)


__all__ = ["locked_climbing_robot", "locked_climbing_state", "climbing_posture_problem", "least_mu_bound", "weight",
           "POSTURE", "TIP_LOAD_SHARE"]

"""The six-wheel linkage rover with compliant tyres: the wheels can leave the ground and land.

:func:`compliant_spec` is ``SPEC`` with every wheel's normal contact a spring-damper of its penetration
(:mod:`robotdyn.contact.compliant_contact`; stiffness and damping by the default rule of
:mod:`robotdyn.contact.compliance`, about 1 mm of static deflection, unless given) and a linear tyre law on its
tangential directions (the omni wheels' along their rollers' driving direction, the middle wheels' both), and
automatic independent velocities. :func:`bump_run` drives it (or the rigid rover) over a bump at the section 3
peak wheel speed held by the motors, from the rigid rover's posture before the bump: the run that ``make bench``
times side by side with the rigid one.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...robot import Robot, RobotSpec
from .model import PEAK_SPEED, SPEC, SPEED_GAIN, TERRAINS

TYRE_STIFFNESS = 5.0
"""Slip stiffness of the compliant rover's linear tyre law [s/m] (force per unit load per m/s of slip)."""
TYRE_MU = 0.8
"""Saturation friction coefficient of the compliant rover's tyre law."""


def compliant_spec(stiffness: float | None = None, damping: float | None = None) -> RobotSpec:
    """``SPEC`` with compliant wheels (see the module).

    Args:
        stiffness: Each wheel's normal stiffness [N/m] (None: the default rule, 1 mm under an equal share).
        damping: Each wheel's normal damping [N s/m] (None: the default rule).

    Returns:
        The new :class:`~robotdyn.robot.RobotSpec` (``SPEC`` is not changed).
    """
    wheels = [replace(w, contact="compliant", friction="linear", stiffness=TYRE_STIFFNESS, mu=TYRE_MU,
                      normal_stiffness=stiffness, normal_damping=damping) for w in SPEC.wheels]
    return replace(SPEC, name="linkage_suspension_compliant", wheels=wheels, independent=None,
                   title=SPEC.title + ", compliant tyres")


def _hold_speed(robot: Robot, speed: float = PEAK_SPEED):
    """Torques holding both sides' middle wheels at ``speed`` [rad/s] (gain SPEED_GAIN), from the full
    velocities."""
    labels = list(robot.velocity_labels)
    i2, i5 = labels.index("phi2_dot"), labels.index("phi5_dot")

    def tau(t, q, nu):
        v = robot.velocity(q, nu)
        right = SPEED_GAIN * (speed - v[i2])
        left = SPEED_GAIN * (speed - v[i5])
        return np.array([right, right, right, left, left, left])

    return tau


def hold_speed_law(robot: Robot, speed: float = PEAK_SPEED):
    """The torques of :func:`_hold_speed` as a :class:`~robotdyn.simulation.feedback.FeedbackLaw` (data, so the
    compiled engine evaluates them without Python): tau = K speed - K nu_j with nu_j the side's middle wheel speed,
    which must be an independent velocity (it is for the rigid rover and for :func:`compliant_spec`).

    Args:
        robot: The rigid or compliant rover.
        speed: The wheel speed [rad/s] held (default: the section 3 peak).

    Returns:
        The :class:`~robotdyn.simulation.feedback.FeedbackLaw`.
    """
    from ...simulation.feedback import FeedbackLaw
    from ...simulation.torque_profile import Constant

    names = list(robot.velocity_names)
    Knu = np.zeros((6, robot.mobility))
    Knu[:3, names.index("phi2_dot")] = SPEED_GAIN
    Knu[3:, names.index("phi5_dot")] = SPEED_GAIN
    return FeedbackLaw(feedforward=Constant(np.full(6, SPEED_GAIN * speed)), Knu=Knu)


def bump_run(robot: Robot, t_end: float = 1.5, rigid: Robot | None = None, speed: float = PEAK_SPEED,
             feedback: bool = False, **options):
    """Drive ``robot`` over the 5 cm bump of ``TERRAINS["bump"]`` (the rigid rover's ``bump`` scenario: from
    x = -0.6 m at the wheel speed ``speed`` [rad/s], the section 3 peak by default, held by the motors; at about
    25 rad/s, 3.5 m/s, the wheels leave the ground over the bump's crest).

    Args:
        robot: The rigid rover (``SPEC``) or a compliant one (:func:`compliant_spec`).
        t_end: Duration [s].
        rigid: The rigid rover whose posture starts the run (built here if None); a compliant rover starts at it,
            lowered by its wheels' static deflection (the weight shared by six wheels on their stiffness).
        speed: The wheel speed [rad/s] the motors hold, also the initial independent wheel speeds (default: the
            section 3 peak ``PEAK_SPEED``).
        feedback: Hold the speed with :func:`hold_speed_law` (data: the compiled engine can run it) instead of a
            Python function (default ``False``).
        **options: Passed to :func:`robotdyn.simulation.engine.simulate` (rtol, method, ...).

    Returns:
        The :class:`~robotdyn.simulation.trajectory.Trajectory`.
    """
    from ...constraints.posture import set_terrain, solve_posture
    from ...contact.compliance import weight
    from ...contact.compliant_contact import compliant_wheels
    from ...simulation.engine import simulate

    rigid = rigid or Robot(SPEC)
    set_terrain(rigid, TERRAINS["bump"]())
    q0 = solve_posture(rigid, {"x": -0.6, "y": 0.0, "yaw": 0.0}).q
    nu_r = np.array([speed, speed])
    v0 = rigid.velocity(q0, nu_r)
    wheels = compliant_wheels(robot)
    if wheels:
        set_terrain(robot, TERRAINS["bump"]())
        share = weight(robot) / len(wheels)
        q0 = q0.copy()
        q0[robot.coordinate_index("z")] -= float(np.mean([share / w.normal_law.stiffness for w in wheels]))
        nu0 = v0[robot.independent_indices]
    else:
        nu0 = nu_r
    torque = hold_speed_law(robot, speed) if feedback else _hold_speed(robot, speed)
    return simulate(robot, t_end, q0, nu0, torque, progress=False, **options)


__all__ = ["compliant_spec", "bump_run", "hold_speed_law", "TYRE_STIFFNESS", "TYRE_MU"]

"""Quasimoro's minimum-effort rest-to-rest motion along a straight line (trajectory optimisation, issue 26).

The body starts and ends hanging at rest (:math:`\\theta_3 = 0`, all velocities zero); the robot moves ``distance``
along x in ``t_end`` seconds, minimising :math:`\\int_0^T (\\tau_1^2 + \\tau_2^2)\\,dt` with the wheel torques
bounded, :math:`|\\tau_i| \\le \\tau_{max}`, and the body pitch bounded, :math:`|\\theta_3| \\le \\theta_{max}`
(accelerating swings the pendulum body: without the bound, 1 m in 3 s swings it to about 0.10 rad). The final
wheel angles are free; y and the heading end at zero. The problem is
:class:`robotdyn.optimisation.trajectory.TrajectoryProblem`; this module only states it for this robot.
"""

from __future__ import annotations

from ...optimisation.trajectory import TrajectoryProblem, TrajectorySolution

DISTANCE, T_END, NODES, TAU_MAX, PITCH_MAX = 1.0, 3.0, 41, 0.6, 0.06
"""The example's defaults: 1 m in 3 s on 41 nodes, torques within +-0.6 N m, body pitch within +-0.06 rad."""


def rest_to_rest(distance: float = DISTANCE, t_end: float = T_END, nodes: int = NODES, tau_max: float = TAU_MAX,
                 pitch_max: float = PITCH_MAX, derivatives: str = "analytic", robot=None) -> TrajectoryProblem:
    """The rest-to-rest problem (see the module docstring).

    Args:
        distance: Distance along x [m].
        t_end: Duration [s] (> 0).
        nodes: Collocation nodes (>= 3).
        tau_max: Torque bound per wheel motor [N m] (> 0).
        pitch_max: Body pitch bound :math:`|\\theta_3|` [rad] (> 0).
        derivatives: ``analytic`` or ``finite-difference`` (the constraint Jacobian's source).
        robot: A Quasimoro :class:`~robotdyn.robot.Robot` (default: ``robotdyn.load("quasimoro")``).

    Returns:
        A :class:`~robotdyn.optimisation.trajectory.TrajectoryProblem`; ``.solve()`` gives the motion.
    """
    import math

    from ...errors import InputError

    for name, value in (("distance", distance), ("tau_max", tau_max), ("pitch_max", pitch_max)):
        ok = isinstance(value, (int, float)) and math.isfinite(value) and (value > 0 or name == "distance")
        if not ok:
            raise InputError(f"{name} = {value!r}; expected a finite number{'' if name == 'distance' else ' > 0'}")
    if robot is None:
        from ... import load

        robot = load("quasimoro")
    return TrajectoryProblem(robot, t_end, nodes, [0.0] * len(robot.coordinates),
                             q_end={"x": distance, "y": 0.0, "psi": 0.0, "theta3": 0.0},
                             tau_bounds=(-tau_max, tau_max), bounds={"theta3": (-pitch_max, pitch_max)},
                             derivatives=derivatives)


__all__ = ["rest_to_rest", "TrajectorySolution", "DISTANCE", "T_END", "NODES", "TAU_MAX", "PITCH_MAX"]

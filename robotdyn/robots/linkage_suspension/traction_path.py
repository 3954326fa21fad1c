"""The six-wheel linkage rover's straight path in minimum effort within a friction limit (issue 26, item 3).

The rover (Chen et al.'s linkage suspension, :mod:`robotdyn.robots.linkage_suspension.model`, wheels rolling
without slip on flat ground) starts at rest in its neutral posture and drives ``distance`` straight ahead in
``t_end`` seconds to rest again, its six wheel motors free to share the work. Trajectory optimisation
(:class:`robotdyn.optimisation.trajectory.TrajectoryProblem`) chooses the motion and the six torques that minimise
the effort :math:`\\int_0^T\\lVert\\tau\\rVert^2dt` [N^2 m^2 s] with every wheel's load at least ``min_load`` and,
where ``mu_max`` is given, every wheel's required friction coefficient :math:`\\lVert f_t\\rVert/f_n` at most
``mu_max`` at every node (:mod:`robotdyn.optimisation.contact_limits`).

The wheel loads are determined here: the linkage (two rocker-bogies joined through the differential rods) leaves
one load per wheel, unlike a rigid chassis on four or more wheels, whose loads rigid-body dynamics leave open.
At rest they are 50.5, 68.9 and 57.1 N on the front, middle and rear
wheels of each side. The minimum-effort motion drives the six wheels with equal torques, so that the lightest
loaded wheel (the front, while accelerating; the rear, with load transferred forward, while braking) needs the most
friction: a peak of 0.187 (5 nodes). With ``mu_max`` below that the optimiser shifts torque from the wheels that
would slip to the heavier ones: with ``mu_max = 0.15`` the cone binds at the start on the front wheels and at the
end on the rear wheels, for 0.46 % more effort (5.454 against 5.429 N^2 m^2 s, 5 nodes).

Derivatives: ``analytic`` (:meth:`~robotdyn.robot.Robot.dynamics_derivatives` and
:meth:`~robotdyn.robot.Robot.contact_force_derivatives`) or ``finite-difference``; the latter steps the
coordinates along the loops' level set (:mod:`robotdyn.optimisation.manifold_steps`: a plain step of a dependent
coordinate opens the loops and the reduced dynamics refuse the state).
"""

from __future__ import annotations

import numpy as np

from ...optimisation.trajectory import TrajectoryProblem

DISTANCE, T_END, NODES, MIN_LOAD, MU_MAX = 0.5, 1.5, 5, 10.0, 0.15
"""The example's defaults: 0.5 m in 1.5 s on 5 nodes, every wheel loaded with at least 10 N, the friction limit
0.15 (below the minimum-effort motion's peak required mu, 0.187, so that the limit binds)."""


def traction_path(mu_max: float | None = MU_MAX, distance: float = DISTANCE, t_end: float = T_END,
                  nodes: int = NODES, min_load: float = MIN_LOAD, derivatives: str = "analytic",
                  robot=None) -> TrajectoryProblem:
    """The minimum-effort straight path (see the module docstring).

    Args:
        mu_max: Largest required friction coefficient of every wheel at every node (``None``: no friction limit,
            the comparison).
        distance: Distance straight ahead (x) [m].
        t_end: Duration [s] (> 0).
        nodes: Collocation nodes (>= 3).
        min_load: Least normal load of every wheel [N] (>= 0).
        derivatives: ``analytic`` or ``finite-difference`` (dynamics and contact forces alike).
        robot: The linkage rover (default: ``robotdyn.load("linkage_suspension")`` on flat ground).

    Returns:
        A :class:`~robotdyn.optimisation.trajectory.TrajectoryProblem`; ``.solve()`` gives the motion.
    """
    import robotdyn

    robot = robotdyn.load("linkage_suspension") if robot is None else robot
    return TrajectoryProblem(robot, t_end, nodes, robot.neutral(), q_end={"x": distance}, min_load=min_load,
                             mu_max=mu_max, derivatives=derivatives)


def replay(solution, robot, n_out: int = 61) -> tuple:
    """Re-simulate a solution with the exact model, open loop: its torques, linear between the nodes (what the
    collocation assumed), from its initial state; then the contact forces along the simulated motion.

    Args:
        solution: A :class:`~robotdyn.optimisation.trajectory.TrajectorySolution` of :func:`traction_path`.
        robot: The robot it was solved for.
        n_out: Output samples.

    Returns:
        ``(trajectory, forces (n_out, 6, 3) [N] along (t1, t2, n), required mu (n_out, 6))``.
    """
    from ...optimisation.contact_limits import ContactLimits, required_mu
    from ...simulation.engine import simulate

    profile = solution.profile()
    traj = simulate(robot, solution.t[-1], solution.q[0], solution.nu[0], profile, n_out=n_out, progress=False)
    limits = ContactLimits(robot, solution.q[0], min_load=0.0)
    tau = profile.at(np.asarray(traj.t))
    forces = np.array([limits.forces(q, nu, u) for q, nu, u in zip(traj.q, traj.nu, tau)])
    return traj, forces, required_mu(forces)

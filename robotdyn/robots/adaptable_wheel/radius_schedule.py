"""The adaptable-wheel tricycle's wheel-radius schedule with the least peak required friction (issue 26, item 3).

Mardani & Ebrahimi adapt the wheel radii so that the body follows its commands over the rough terrain of Table 1
(:math:`Z = \\sin(0.5(x + y))/15`); the purpose of the design is to keep the wheels' demands low there. Here the
robot starts at rest at the path origin in the paper's IK configuration (eqs 4-24: h_CG = 0.15 m, body level),
heading along the terrain's gradient (yaw 45 deg, so that the ground does not slope across its path), and drives
``distance`` along that heading in ``t_end`` seconds to rest again, keeping to its path (within ``path_tol`` of the
straight line's box and heading). Trajectory optimisation (:class:`robotdyn.optimisation.trajectory.TrajectoryProblem`,
cost ``peak-mu``) chooses the motion, the three adjustment angles :math:`q_i(t)` (the radius schedule,
:math:`R_{T,i} = R_{ru} + w\\cos(q_i/2)\\cos(\\pi/6)`, eq 1, within the mechanism range ``q_range``) and the six motor
torques so that the largest required friction coefficient :math:`\\max_{i,t}\\|f_{t,i}\\|/f_{n,i}` is least, every
wheel carrying at least ``min_load``.

The comparison (``fixed=True``): the same problem with each radius held at its initial value (the paper's IK
configuration at the start), the conventional tricycle the adaptable wheel is meant to improve on.
:func:`compare` solves the fixed-radius case first and starts the schedule from its optimum (a feasible point of the
scheduled problem), so that the schedule's optimal cost is at most the fixed one's: the problem is not convex, and
from other starts IPOPT finds worse local optima (measured: peak mu 0.098 from the minimum-effort motion against
0.081 with fixed radii, 9 nodes, effort weight 1e-2).

Result (measured, 5 and 7 nodes): the schedule does not lower the peak required mu beyond the discretisation error
(0.07896 against 0.07901 with fixed radii at 5 nodes, 0.07395 against 0.07385 at 7), and lowers the effort
(130 to 106 and 120 N^2 m^2 s). Where the peak is reached all three wheels need the same mu, equal to the whole
robot's ratio of tangential to normal ground force (0.07901 at the start node, contact normals parallel within
0.001 deg): a ratio of the total force that accelerates the robot up the slope, which the share among the wheels,
what the radii change, cannot lower.

Model: ``lateral = slip`` (each wheel rolls along its rolling direction; sideways it slides without friction), the
paper's own kinematic assumption for its missions (``docs/errata/adaptable_wheel.md``): with wheels that roll
without slipping sideways, moving forward needs the radii to change (at the start, the dependent ``q_fl`` changes
with the forward wheel speed), so the fixed-radius case would have no motion at all. The required mu is then the
traction over the load, :math:`|f_{t1}|/f_n`.
"""

from __future__ import annotations

import numpy as np

from ...errors import InputError
from ...optimisation.trajectory import TrajectoryProblem

DISTANCE, T_END, NODES, MIN_LOAD, PATH_TOL, EFFORT_WEIGHT, RATE_WEIGHT = 1.0, 3.0, 5, 5.0, 0.02, 1e-5, 1e-4
"""The example's defaults: 1 m in 3 s on 5 nodes (seconds per solve; 7 or more resolve the motion better), every wheel loaded with at least 5 N, within 2 cm / 0.02 rad of
the path, the effort weighted 1e-5 beside the squared peak mu (small beside it: about 1e-3 against 7e-3 at the
fixed-radius optimum; it makes the optimum unique), the torques' rate weighted 1e-4 (it removes the node-to-node
oscillation of the torques that the massless mechanism leaves free: measured, peak mu 0.0739 with it against 0.0736
without, fixed radii)."""
REPLAY_GAIN = 100.0
"""Stiffness [N m/rad] of the adjustment motors' tracking of the schedule in :func:`replay` (damping 0.6 sqrt of it)."""
HEADING = float(np.pi / 4)
"""Heading [rad] of the path: along the gradient of Table 1's terrain, which then does not slope across it."""
Q_RANGE = (0.35, 2.97)
"""Adjustment-angle range [rad] (20-170 deg: the range of the paper's Fig. 11)."""
WHEELS = ("fr", "fl", "r")


def radius_schedule(distance: float = DISTANCE, t_end: float = T_END, nodes: int = NODES, fixed: bool = False,
                    min_load: float = MIN_LOAD, path_tol: float = PATH_TOL, q_range: tuple = Q_RANGE,
                    effort_weight: float = EFFORT_WEIGHT, rate_weight: float = RATE_WEIGHT,
                    derivatives: str = "analytic", robot=None
                    ) -> TrajectoryProblem:
    """The least-peak-mu problem (see the module docstring).

    Args:
        distance: Distance along the heading [m] (> 0).
        t_end: Duration [s] (> 0).
        nodes: Collocation nodes (>= 3).
        fixed: Hold each wheel's radius at its initial value (the comparison) instead of scheduling it.
        min_load: Least normal load of every wheel [N] (>= 0).
        path_tol: Margin [m] of x and y beyond the straight path's box, and of the heading [rad] (> 0).
        q_range: ``(lowest, highest)`` adjustment angle [rad] of the schedule.
        effort_weight: Weight of :math:`\\int\\|\\tau\\|^2 dt` beside the squared peak mu [1/(N^2 m^2 s)] (>= 0).
        rate_weight: Weight of the torques' rate :math:`\\int\\|\\dot\\tau\\|^2 dt` (>= 0).
        derivatives: ``analytic`` or ``finite-difference`` (dynamics and contact forces alike).
        robot: An adaptable-wheel :class:`~robotdyn.robot.Robot` with ``lateral = slip`` (default: built so).

    Returns:
        A :class:`~robotdyn.optimisation.trajectory.TrajectoryProblem` whose initial guess holds the robot with
        its static holding torques; ``.solve()`` gives the motion.
    """
    import math

    for name, value in (("distance", distance), ("path_tol", path_tol)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise InputError(f"{name} = {value!r}; expected a finite number > 0")
    robot, q0, holding = start(robot)
    e = distance / math.sqrt(2.0)
    bounds = {"x": (q0[0] - path_tol, e + path_tol), "y": (q0[1] - path_tol, e + path_tol),
              "yaw": (HEADING - path_tol, HEADING + path_tol)}
    for tag in WHEELS:
        value = q0[robot.coordinate_index(f"q_{tag}")]
        bounds[f"q_{tag}"] = (value, value) if fixed else tuple(q_range)
    problem = TrajectoryProblem(robot, t_end, nodes, q0, q_end={"x": e, "y": e, "yaw": HEADING},
                                bounds=bounds, derivatives=derivatives, min_load=min_load, cost="peak-mu",
                                effort_weight=effort_weight, rate_weight=rate_weight)
    z = problem._initial()
    X, _ = problem._split(z)
    problem.guess = (X[:, :problem.n], X[:, problem.n:], np.tile(holding, (nodes, 1)))
    return problem


def start(robot=None) -> tuple:
    """The robot (``lateral = slip``), its start configuration (the paper's IK at the path origin: h_CG = 0.15 m,
    body level, heading :data:`HEADING`) and the static holding torques there (least squares of
    :math:`B_r\\tau = g_r`).

    Args:
        robot: An adaptable-wheel :class:`~robotdyn.robot.Robot` with ``lateral = slip`` (default: built so).

    Returns:
        ``(robot, q0 (n,) [m, rad], holding torques (6,) [N m])``.
    """
    from ... import load
    from .comparison import model_configuration
    from .paper import Commands, solve_ik

    if robot is None:
        robot = load("adaptable_wheel", {"lateral": "slip"})
    elif robot.spec.name != "adaptable_wheel" or robot.params["lateral"] != "slip":
        raise InputError("the radius schedule needs the adaptable_wheel robot with lateral = slip")
    cmd = Commands(0.0, 0.0, 0.15, qz=HEADING)
    x, _, _ = solve_ik(cmd, robot.params, robot.terrain)
    q0 = model_configuration(robot, cmd, x)
    red = robot.reduced(q0, np.zeros(robot.mobility))
    holding = np.linalg.lstsq(red.B, red.g, rcond=None)[0]
    return robot, q0, holding


def compare(derivatives: str = "analytic", robot=None, **options) -> tuple:
    """The fixed-radius optimum, then the radius schedule started from it (see the module docstring).

    Args:
        derivatives: ``analytic`` or ``finite-difference``.
        robot: As :func:`radius_schedule`.
        **options: Further arguments of :func:`radius_schedule` (``distance``, ``nodes`` ...), the same for both.

    Returns:
        ``(fixed, scheduled)``: the two :class:`~robotdyn.optimisation.trajectory.TrajectorySolution`.
    """
    fixed = radius_schedule(fixed=True, derivatives=derivatives, robot=robot, **options).solve()
    problem = radius_schedule(fixed=False, derivatives=derivatives, robot=robot, **options)
    problem.guess = (fixed.q, fixed.nu, fixed.tau)
    return fixed, problem.solve()


def replay(solution, robot=None, gain: float = REPLAY_GAIN, n_out: int = 61) -> tuple:
    """Re-simulate a solution with the exact model: its torques (linear between nodes, what the collocation
    assumed), the adjustment motors also tracking the schedule :math:`q_i(t)` (a cubic spline through the nodes) with
    a PD of stiffness ``gain``; then the contact forces along the simulated motion.

    The feedback is needed: with massless wheel mechanisms the body stands on three legs whose force the
    adjustment torques set, with no stiffness of their own, so that an open-loop replay drifts away from any motion
    (measured: the fixed-radius optimum's torques alone fail at t = 0.70 s, the integrator's step collapsing as a
    radius runs away). The PD adds torque only where the motion leaves the schedule.

    Args:
        solution: A :class:`~robotdyn.optimisation.trajectory.TrajectorySolution` of :func:`radius_schedule`.
        robot: The robot it was solved for (default: :func:`start`'s).
        gain: PD stiffness [N m/rad] (damping :math:`0.6\\sqrt{gain}` N m s/rad); 0: open loop.
        n_out: Output samples.

    Returns:
        ``(trajectory, forces (n_out, 3, 3) [N] along (t1, t2, n), required mu (n_out, 3), torques (n_out, 6))``.
    """
    from scipy.interpolate import CubicSpline

    from ...optimisation.contact_limits import ContactLimits, required_mu
    from ...simulation.engine import simulate

    robot = start(robot)[0] if robot is None else robot
    adjust = [robot.coordinate_index(f"q_{tag}") for tag in WHEELS]
    motors = [[m.name for m in robot.motors].index(f"adjust_{tag}") for tag in WHEELS]
    schedule = CubicSpline(solution.t, solution.q[:, adjust])
    profile = solution.profile()
    damping = 0.6 * np.sqrt(gain)

    def torque(t, q, nu):
        u = profile.at(np.array([t]))[0].copy()
        if gain:
            v = robot.velocity(q, nu)
            u[motors] += gain * (schedule(t) - q[adjust]) + damping * (schedule(t, 1) - v[adjust])
        return u

    traj = simulate(robot, solution.t[-1], solution.q[0], solution.nu[0], torque if gain else profile, n_out=n_out,
                    progress=False)
    limits = ContactLimits(robot, solution.q[0], min_load=0.0)
    tau = np.array([torque(t, q, nu) for t, q, nu in zip(traj.t, traj.q, traj.nu)])
    forces = np.array([limits.forces(q, nu, u) for q, nu, u in zip(traj.q, traj.nu, tau)])
    return traj, forces, required_mu(forces), tau


def peak_mu(solution) -> float:
    """The largest required friction coefficient over the wheels and nodes of a solution.

    Args:
        solution: A :class:`~robotdyn.optimisation.trajectory.TrajectorySolution` with forces.

    Returns:
        :math:`\\max_{i,j}\\|f_t\\|/f_n`.
    """
    return float(np.max(solution.required_mu))


def radii(robot, q: np.ndarray) -> np.ndarray:
    """Total wheel radii :math:`R_T = R_{ru} + R_{ch}` [m] at the configurations ``q`` (N, n), wheels fr, fl, r.

    Args:
        robot: The adaptable-wheel :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (N, n) [m, rad].

    Returns:
        (N, 3) [m].
    """
    q = np.atleast_2d(q)
    return robot.params["R_ru"] + q[:, [robot.coordinate_index(f"Rch_{t}") for t in WHEELS]]


__all__ = ["radius_schedule", "radii", "DISTANCE", "T_END", "NODES", "MIN_LOAD", "PATH_TOL", "EFFORT_WEIGHT",
           "RATE_WEIGHT", "REPLAY_GAIN", "Q_RANGE", "HEADING", "start", "compare", "peak_mu",
           "replay"]

"""MMR12-EOD climbing a slope in the posture that needs the least friction (issue 26, item 3).

The robot of :func:`robotdyn.robots.mmr12_eod.model.climbing_robot` (floating root on a ramp, the drive wheels rolling
without slipping, the rear arms' tip wheels as frictionless supports, sec 2.11 e of Zuniga-Aviles et al. 2014),
with the platform lift ``lambda_C`` locked: on a floating root it only duplicates the root's height through a
massless link, so that the reduced mass matrix is singular and the forward dynamics (hence the forces under given
motor torques) is not defined with it free.

The least-friction posture (:func:`climbing_posture_problem`): at rest on the ramp, holding (the robot's motors
hold it still: :math:`\\dot\\nu = 0`), the manipulator (theta1, lambda2, theta3, theta4), the load slide (lambda6)
and the rear arms (theta_C4; theta_C3 follows from the tips' contact) chosen with the holding torques to minimise
the larger required mu of the two drive wheels (the drive wheels' axle held where it is on the ramp: x, y, yaw
and the wheel angles; the platform's height, pitch and roll and theta_C3 follow), each rear tip keeping a load
of at least ``min_tip_load`` (:class:`robotdyn.optimisation.posture.PostureProblem`). The manipulator moves in
the robot's plane of symmetry, so the drive wheels' lateral forces (a squeeze rigid-body dynamics leave open) are
zero in the best split and in the minimum-norm one alike.

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
                          held=("x", "y", "yaw", "theta_R", "theta_L"), derivatives=derivatives)


def cmd_climbing_posture(args) -> int:
    """``robotdyn climbing-posture ROBOT --slope DEG [--min-tip-load N] [--derivatives analytic|finite-difference]``:
    :func:`climbing_posture_problem` solved, with the closed-form bound and the default posture's mu beside it.

    Args:
        args: The parsed command line (argparse namespace of :func:`register_cli`'s parser).

    Returns:
        The exit status (0; a problem IPOPT could not solve raises a one-line error and prints nothing else).
    """
    from ...cli.commands import _emit, _load
    from ...errors import RobotDynError
    from .model import climbing_forces

    _, robot = _load(args)
    if robot.spec.name != "mmr12_eod":
        raise RobotDynError(f"climbing-posture is MMR12-EOD's (robot {robot.spec.name!r}); expected mmr12_eod")
    slope = np.radians(args.slope)
    problem = climbing_posture_problem(slope, args.min_tip_load, args.derivatives, robot)
    s = problem.solve()
    if not s.success:
        raise RobotDynError(f"the posture optimisation did not converge: IPOPT {s.status} after {s.iterations} "
                            "iterations (a smaller slope or tip load may make it feasible)")
    f_min = problem.min_load[problem.wheels.index("tip3")]
    bound = least_mu_bound(problem.robot, slope, f_min)
    default = climbing_forces(slope, robot).minimum_mu()
    out = {"robot": args.robot, "slope_deg": args.slope, "min_tip_load": f_min, "status": s.status,
           "success": s.success, "peak_mu": s.peak_mu, "bound": bound, "default_posture_mu": default,
           "iterations": s.iterations, "wall_time": s.wall_time, "derivatives": s.derivatives,
           "posture": dict(zip(s.variables, s.x.tolist())), "coordinates": problem.robot.coordinates, "q": s.q,
           "motors": [m.name for m in problem.robot.motors], "tau": s.tau, "loads": dict(zip(s.wheels, s.loads))}
    text = "\n".join([
        repr(problem), f"IPOPT: {s.status} after {s.iterations} iterations ({s.wall_time:.3g} s)",
        f"least peak required mu {s.peak_mu:.6f} (closed-form bound {bound:.6f}; default climbing posture "
        f"{default:.6f}; tan(slope) {np.tan(slope):.6f})",
        "posture: " + ", ".join(f"{n} {v:.6g}" for n, v in zip(s.variables, s.x)),
        "normal loads [N]: " + ", ".join(f"{w} {v:.6g}" for w, v in zip(s.wheels, s.loads))])
    _emit(args, out, text)
    return 0


def register_cli(subparsers, parents) -> None:
    """``robotdyn climbing-posture ROBOT --slope DEG ...`` (:func:`cmd_climbing_posture`).

    Args:
        subparsers: The CLI's subparsers (``argparse`` action).
        parents: Parsers whose arguments it inherits (the common and robot arguments).
    """
    import argparse

    def slope(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not (np.isfinite(value) and 0.0 < value < 60.0):
            raise argparse.ArgumentTypeError(f"{text!r}; expected a ramp angle in deg, 0 < slope < 60")
        return value

    def load(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not (np.isfinite(value) and value >= 0.0):
            raise argparse.ArgumentTypeError(f"{text!r}; expected a load >= 0 [N]")
        return value

    p = subparsers.add_parser("climbing-posture", parents=parents,
                              help="MMR12-EOD: the posture on a ramp that needs the least friction (IPOPT)")
    p.add_argument("--slope", type=slope, required=True, help="ramp angle [deg]")
    p.add_argument("--min-tip-load", type=load, default=None,
                   help="smallest load of each rear tip [N] (default 1 %% of the weight)")
    p.add_argument("--derivatives", choices=("analytic", "finite-difference"), default="analytic",
                   help="the constraint Jacobian from the analytic force derivatives (default) or finite differences")
    p.set_defaults(func=cmd_climbing_posture)


__all__ = ["locked_climbing_robot", "locked_climbing_state", "climbing_posture_problem", "least_mu_bound", "weight",
           "POSTURE", "TIP_LOAD_SHARE", "cmd_climbing_posture", "register_cli"]

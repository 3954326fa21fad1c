"""Six-wheel mobile robot with linkage suspension (Chen, Wang, Zhong, Zhu, Wang): the model side.

Paper: "Kinematics Analysis and Simulation of Mobile Robot Based on Linkage Suspension"
(Chen et al., ``docs/bibliography.md``). Description: ``urdf/linkage_suspension.urdf.xacro``
(the mechanism, our reading of Figs. 1-3, and the dimensions, our own: the paper prints none).

Coordinates: floating root (x, y, z, yaw, pitch, roll) of the body frame R (origin at the body's centre of gravity,
x forward, z up); theta1/theta2 the right/left rocker angles about +y_R (Table 1's theta1: the back arm points at
(-sin theta, -cos theta) in the x-z plane); beta1/beta2 the bogie (rear linkage) angles about -y_R (Table 1's beta1,
bogie level at beta = theta + pi/2); gamma, sigma the front rod and slider block angles; psi the suspension link;
rod*_x, rod*_y the connecting rods' universal joints; phi1..phi6 the wheel spins about +y (forward rolling positive),
wheels 1-3 right (front, middle, rear), 4-6 left. Independent velocities: the middle wheel spins (phi2', phi5').

Omni wheels: ``OmniWheel(roller_angle=rho)``; the constrained direction at the contact is x of eq (2)'s frame H
(x_A rotated by rho towards the axle), so the model's roller angle is the paper's rho (0 for the paper's 90-degree
omni wheels, the default).

This module holds ``SPEC`` (the paper prints no dimensions: ours), the section-3 wheel-speed profile and the
kinematic runs on the model, example terrains, ``SCENARIOS``, the ``linkage-posture`` CLI subcommand and the
posture-versus-rigid-chassis study. The paper's closed forms (Table 1, eqs 1-4, 10) are in :mod:`robotdyn.robots.linkage_suspension.paper`, the
comparison (eqs 3, 4, 9, 10, section 3) in :mod:`robotdyn.robots.linkage_suspension.comparison`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ...constraints.constraint import KinematicState
from ...robot import Closure, MotorSpec, Parameter, Robot, RobotSpec, Wheel
from ...simulation.scenario import Scenario
from ...constraints.terrain import BumpTerrain, FlatTerrain, RampTerrain, SineTerrain, Terrain


THETA0 = np.pi / 3
"""Default nominal rocker angle theta0 [rad] (xacro default)."""

_WHEEL_KIND = {1: "omni", 2: "standard", 3: "omni", 4: "omni", 5: "standard", 6: "omni"}

SPEC = RobotSpec(
    name="linkage_suspension",
    title="Six-wheel robot with linkage suspension on uneven terrain (Chen et al., wheel-centre kinematics)",
    xacro="linkage_suspension.urdf.xacro",
    root="floating",
    paper=("Chen, Wang, Zhong, Zhu & Wang, "
           "Kinematics analysis and simulation of mobile robot based on linkage suspension"),
    parameters=[
        Parameter("a1", 0.05, "m", "Table 1: rocker pivot D ahead of the body frame R (an offset: 0 or < 0, behind R, are valid geometries)"),
        Parameter("d1", 0.10, "m", "Table 1: rocker pivot D below R (an offset: any sign)"),
        Parameter("a5", 0.20, "m", "Table 1: rocker back arm D -> bogie pivot B2", positive=True),
        Parameter("d5", 0.175, "m", "Table 1: half track (2 pivot-steering turns, Fig. 12)", positive=True),
        Parameter("a6", 0.1232, "m", "Table 1: bogie pivot -> middle wheel", positive=True),
        Parameter("a7", 0.15, "m", "Table 1: bogie pivot -> rear wheel", positive=True),
        Parameter("theta0", float(THETA0), "rad", "nominal rocker angle (posture on flat ground)"),
        Parameter("r", 0.14, "m", "wheel radius (0.73 m/s / 300 deg/s = 0.139 m, section 3)", positive=True),
        Parameter("xF", 0.10, "m", "front-rod pivot F on the body, x in R"),
        Parameter("zF", -0.05, "m", "front-rod pivot F, z in R"),
        Parameter("xW", 0.32, "m", "front wheel centre, x in R (nominal)"),
        Parameter("lam", 0.5, "-", "slider pivot G = F + lam (W - F) on the front rod"),
        Parameter("xO", 0.15, "m", "suspension-link pivot O, x in R"),
        Parameter("zO", 0.10, "m", "suspension-link pivot O, z in R"),
        Parameter("wL", 0.16, "m", "half length of the suspension link", positive=True),
        Parameter("hr", 0.20, "m", "connecting-rod length (suspension link -> rocker ball joint)", positive=True),
        Parameter("m_body", 25.0, "kg", "body mass", positive=True),
        Parameter("m_rocker", 1.2, "kg", "rocker mass (each)"),
        Parameter("m_bogie", 0.8, "kg", "bogie (rear linkage) mass (each)"),
        Parameter("m_rod", 0.6, "kg", "front linkage mass (each)"),
        Parameter("m_wheel", 1.0, "kg", "middle rubber wheel mass (each)"),
        Parameter("m_omni", 0.8, "kg", "omni wheel mass (each)"),
        Parameter("m_link", 0.3, "kg", "suspension link mass"),
        Parameter("rho", 0.0, "rad", "omni roller angle rho of eq 2 (0: 90-degree omni wheel)", xacro=False),
        Parameter("g", 9.81, "m/s^2", "gravitational acceleration", xacro=False),
    ],
    wheels=[
        Wheel(f"wheel{i}", "r", kind=_WHEEL_KIND[i], roller_angle="rho" if _WHEEL_KIND[i] == "omni" else 0.0,
              name=f"wheel{i}")
        for i in range(1, 7)
    ],
    closures=[
        Closure("guide_R", "block_R", ("y", "z", "rx", "ry", "rz"), name="slider_R"),
        Closure("guide_L", "block_L", ("y", "z", "rx", "ry", "rz"), name="slider_L"),
        Closure("ball_R", "rod_R_end", ("x", "y", "z"), name="ball_R"),
        Closure("ball_L", "rod_L_end", ("x", "y", "z"), name="ball_L"),
    ],
    motors=[MotorSpec(f"m{i}", f"wheel{i}_joint") for i in range(1, 7)],
    labels={
        "rocker_R_joint": "theta1", "rocker_L_joint": "theta2",
        "bogie_R_joint": "beta1", "bogie_L_joint": "beta2",
        "front_rod_R_joint": "gamma1", "front_rod_L_joint": "gamma2",
        "slider_R_joint": "sigma1", "slider_L_joint": "sigma2",
        "susp_link_joint": "psi",
        "rod_R_x": "rod1_x", "rod_R_y": "rod1_y", "rod_L_x": "rod2_x", "rod_L_y": "rod2_y",
        **{f"wheel{i}_joint": f"phi{i}" for i in range(1, 7)},
    },
    independent=["phi2", "phi5"],
    neutral={"z": 0.34, "theta1": float(THETA0), "theta2": float(THETA0),
             "beta1": float(THETA0 + np.pi / 2), "beta2": float(THETA0 + np.pi / 2)},
)


# --------------------------------------------------------------------------------------- section 3
PEAK_SPEED = np.radians(300.0)
"""Peak wheel speed of Figs. 6, 9, 10: 300 deg/s [rad/s] (the text says 300 rad/s; see the errata)."""
PROFILE = (0.2, 1.2, 3.2, 4.2, 4.5)
"""Wheel-speed profile times [s]: rest until 0.2, ramp up until 1.2, hold until 3.2, ramp down until 4.2, rest."""


def wheel_speed(t: float, peak: float = PEAK_SPEED) -> tuple[float, float]:
    """Section 3 wheel-speed profile and its derivative at time t: (omega [rad/s], omega' [rad/s^2]).

    The ramps are half-cosine blends (the paper says the acceleration 'shows a trigonometric function tendency'
    during the ramps); any ramp symmetric about its midpoint gives the same distance.

    Args:
        t: Time [s].
        peak: Peak wheel speed [rad/s].

    Returns:
        ``(omega, omega_dot)``: [rad/s] and [rad/s^2].
    """
    t0, t1, t2, t3, _ = PROFILE
    if t <= t0 or t >= t3:
        return 0.0, 0.0
    if t < t1:
        s = np.pi * (t - t0) / (t1 - t0)
        return 0.5 * peak * (1 - np.cos(s)), 0.5 * peak * np.pi / (t1 - t0) * np.sin(s)
    if t <= t2:
        return peak, 0.0
    s = np.pi * (t - t2) / (t3 - t2)
    return 0.5 * peak * (1 + np.cos(s)), -0.5 * peak * np.pi / (t3 - t2) * np.sin(s)


def profile_distance(peak_speed: float) -> float:
    """Distance [m] covered under the section 3 profile by a point whose peak speed is ``peak_speed`` [m/s]:
    the hold lasts t2 - t1 and each symmetric ramp counts for half its duration.

    Args:
        peak_speed: The point's peak speed [m/s].

    Returns:
        The distance [m].
    """
    t0, t1, t2, t3, _ = PROFILE
    return peak_speed * ((t1 - t0) / 2 + (t2 - t1) + (t3 - t2) / 2)


def kinematic_run(robot: Robot, direction: tuple[float, float], q0: np.ndarray | None = None, n_out: int = 91,
                  rtol: float = 1e-8) -> dict[str, np.ndarray]:
    """Drive the middle wheels with the section 3 profile (times ``direction`` = signs for phi2, phi5) and integrate
    q' = S(q) nu kinematically, as the paper's ADAMS motion drivers do.

    Args:
        robot: The linkage-suspension :class:`~robotdyn.robot.Robot`.
        direction: Signs (+1 or -1) of the right and left middle wheel speeds (phi2, phi5): equal for a straight
            run, opposite for pivot steering.
        q0: Initial configuration (default ``None``: the neutral one).
        n_out: Number of output samples.
        rtol: Integrator tolerance.

    Returns:
        dict with ``t`` [s], ``q`` (N, n), ``com``, ``vcom``, ``acom`` (N, 3) of the whole robot's centre of mass
        in the world frame [m, m/s, m/s^2], ``yaw`` [rad].
    """
    from scipy.integrate import solve_ivp

    from ...constraints.posture import solve_posture

    sgn = np.asarray(direction, float)
    if q0 is None:
        q0 = solve_posture(robot, {"x": 0.0, "y": 0.0, "yaw": 0.0}).q
    t_end = PROFILE[-1]

    def rhs(t, q):
        return robot.reduced(q, sgn * wheel_speed(t)[0]).v

    t = np.linspace(0.0, t_end, n_out)
    sol = solve_ivp(rhs, (0.0, t_end), q0, t_eval=t, rtol=rtol, atol=1e-10, max_step=0.1)
    com, vcom, acom = (np.zeros((len(t), 3)) for _ in range(3))
    for i, ti in enumerate(sol.t):
        q = sol.y[:, i]
        w, wd = wheel_speed(ti)
        red = robot.reduced(q, sgn * w)
        a = red.S @ (sgn * wd) + red.w
        pin.centerOfMass(robot.model, robot.data, q, red.v, a)
        com[i], vcom[i], acom[i] = robot.data.com[0], robot.data.vcom[0], robot.data.acom[0]
    return {"t": sol.t, "q": sol.y.T, "com": com, "vcom": vcom, "acom": acom,
            "yaw": sol.y[robot.coordinate_index("yaw")], "nfev": sol.nfev}


def centroid_circle_radius(run: dict[str, np.ndarray]) -> float:
    """Half the horizontal extent of the centre-of-mass path of a pivot-steering run [m] (Fig. 12).

    Args:
        run: A :func:`kinematic_run` result.

    Returns:
        The radius [m].
    """
    return float(np.mean(np.ptp(run["com"][:, :2], axis=0)) / 2)


# ---------------------------------------------------------------------------------- terrains, scenarios
TERRAINS: dict[str, Callable[[], Terrain]] = {
    "flat": lambda: FlatTerrain(),
    "ramp": lambda: RampTerrain(0.15, 0.6),
    "bump": lambda: BumpTerrain(0.05, 0.2, 0.15),
    "sine": lambda: SineTerrain(0.02, 2 * np.pi / 0.8, 2 * np.pi / 1.3),
}
"""Example terrains: flat; a 15 % ramp rising towards heading 0.6 rad; a smooth 5 cm step at x = 0.2 m
(tanh, width 0.15 m); a 2 cm sinusoid with wavelengths 0.8 m (x) and 1.3 m (y)."""

SPEED_GAIN = 2.0
"""Gain [N m s/rad] of the wheel-speed tracking torques of the section 3 scenarios."""


@dataclass
class TerrainScenario(Scenario):
    """A scenario on a named terrain, starting from the posture solved at ``start`` (x, y, yaw).

    Attributes:
        name: Identifier (``robotdyn simulate ROBOT --scenario NAME``).
        description: One line, citing the paper's section.
        t_end: Default duration [s].
        torque: Motor torques ``tau(t, q, nu)`` (or a profile; ``None``: unactuated).
        q0: Initial coordinates by name (the posture is solved from them).
        nu0: Initial independent velocities by name.
        n_out: Default number of output samples.
        plot: Columns to plot.
        zoom: Length [s] of the zoomed window in plots (``None``: none).
        references: Horizontal reference lines per plotted column.
        terrain: The terrain's name (:data:`TERRAINS`).
        start: Body x [m], y [m] and yaw [rad] at which the posture is solved.
    """

    terrain: str = "flat"
    start: dict[str, float] = field(default_factory=lambda: {"x": 0.0, "y": 0.0, "yaw": 0.0})

    def initial_state(self, robot) -> tuple[np.ndarray, np.ndarray]:
        from ...constraints.posture import set_terrain, solve_posture

        terrain = TERRAINS[self.terrain]()
        if not _on_terrain(robot, terrain):  # (a new terrain object would rebuild the robot's compiled model)
            set_terrain(robot, terrain)
        q0 = solve_posture(robot, self.start).q
        nu0 = np.zeros(robot.mobility)
        for label, value in self.nu0.items():
            nu0[robot.velocity_names.index(label)] = value
        return q0, nu0


def _on_terrain(robot, terrain: Terrain) -> bool:
    """Whether every terrain-bearing constraint of ``robot`` already stands on one terrain object equal to
    ``terrain`` (same class, equal attributes), so that a scenario need not replace it: the compiled model is cached
    on the identity of its constraints' terrains (:func:`robotdyn.fast.dispatch.compiled_model`), and a fresh but
    equal terrain object at every run would rebuild it (about 8 ms on this robot) at every run.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        terrain: The terrain asked for.

    Returns:
        True when nothing would change by putting ``robot`` on ``terrain``.
    """
    current = getattr(robot, "terrain", None)
    if type(current) is not type(terrain) or vars(current).keys() != vars(terrain).keys():
        return False
    if not all(np.array_equal(vars(current)[key], value) for key, value in vars(terrain).items()):
        return False
    return all(getattr(c, "terrain", current) is current for c in robot.constraints)


def speed_reference(signs=(1.0,), peak: float = PEAK_SPEED):
    """The section 3 wheel-speed profile :func:`wheel_speed` as data: a
    :class:`~robotdyn.simulation.torque_profile.TorqueProfile` of one value per sign (``signs[i] * omega(t)``
    [rad/s]). Each half-cosine ramp is a windowed constant plus a windowed sine, the hold a windowed constant (a sine
    of zero frequency at phase pi/2); the windows meet without overlapping (each starts one double after the
    previous one ends).

    Args:
        signs: The factors of the profile (e.g. +1 and -1 for pivot steering).
        peak: Peak wheel speed [rad/s].

    Returns:
        The :class:`~robotdyn.simulation.torque_profile.TorqueProfile` of width ``len(signs)``: the wheel speeds
        [rad/s] against time [s].
    """
    from ...simulation.torque_profile import Sine

    t0, t1, t2, t3, _ = PROFILE
    w1, w2 = np.pi / (t1 - t0), np.pi / (t3 - t2)
    after = lambda t: float(np.nextafter(t, np.inf))  # noqa: E731
    half, full = 0.5 * peak * np.asarray(signs, float), peak * np.asarray(signs, float)
    return (Sine(half, 0.0, np.pi / 2, t0, t1) + Sine(half, w1, -w1 * t0 - np.pi / 2, t0, t1)
            + Sine(full, 0.0, np.pi / 2, after(t1), t2)
            + Sine(half, 0.0, np.pi / 2, after(t2), t3) + Sine(half, w2, -w2 * t2 + np.pi / 2, after(t2), t3))


def _tracking(signs: tuple[float, float], profile: bool = True):
    """Torques of the six wheel motors tracking the section 3 wheel-speed profile (right side signs[0], left
    signs[1]) with gain SPEED_GAIN: tau_right = SPEED_GAIN (signs[0] omega(t) - phi2'), tau_left likewise with
    phi5' (nu = (phi2', phi5'), the right and left middle wheel speeds), as a
    :class:`~robotdyn.simulation.feedback.FeedbackLaw` (it runs compiled)."""
    from ...simulation.feedback import FeedbackLaw
    from ...simulation.torque_profile import Constant

    ref = speed_reference(signs) if profile else Constant(PEAK_SPEED * np.asarray(signs, float))
    Knu = SPEED_GAIN * np.array([[1.0, 0.0]] * 3 + [[0.0, 1.0]] * 3)
    return FeedbackLaw(Knu=Knu, nu_ref=ref)


SCENARIOS = {
    "straight_line": TerrainScenario(
        "straight_line", "sec 3.1: six wheel motors track the speed profile (0 / ramp to 300 deg/s / hold / ramp "
        "down / rest), flat ground", PROFILE[-1], torque=_tracking((1.0, 1.0)), plot=["x", "phi2_dot"]),
    "pivot_steering": TerrainScenario(
        "pivot_steering", "sec 3.2: right wheels track -profile, left wheels +profile (pivot steering), flat ground",
        PROFILE[-1], torque=_tracking((-1.0, 1.0)), plot=["yaw", "phi2_dot", "phi5_dot"]),
    "bump": TerrainScenario(
        "bump", "over a smooth 5 cm step at x = 0.2 m at 300 deg/s wheel speed held by the motors (torque inputs)",
        2.2, torque=_tracking((1.0, 1.0), profile=False), terrain="bump", start={"x": -0.6, "y": 0.0, "yaw": 0.0},
        nu0={"phi2_dot": float(PEAK_SPEED), "phi5_dot": float(PEAK_SPEED)},
        plot=["z", "pitch", "theta1", "beta1", "phi2_dot"]),
    "ramp_free": TerrainScenario(
        "ramp_free", "torque-free, friction-free on a 15 % ramp across the heading (energy must stay constant)",
        2.0, terrain="ramp", nu0={"phi2_dot": 2.0, "phi5_dot": 3.0}, plot=["x", "y", "yaw", "phi2_dot", "phi5_dot"]),
}


# ------------------------------------------------------------------------------------------------ CLI
def _cmd_posture(args) -> int:
    import json

    from ...cli.commands import _jsonable
    from ...errors import InputError
    from ...inputs import parse_assignments
    from ...constraints.posture import set_terrain, solve_posture

    if args.terrain not in TERRAINS:
        raise InputError(f"unknown terrain {args.terrain!r}; expected one of {', '.join(TERRAINS)}")
    robot = Robot(SPEC, parse_assignments(args.param))
    set_terrain(robot, TERRAINS[args.terrain]())
    post = solve_posture(robot, {"x": args.x, "y": args.y, "yaw": args.yaw})
    out = {"terrain": repr(robot.terrain), "q": dict(zip(robot.coordinates, post.q)), "residual": post.residual,
           "iterations": post.iterations}
    text = [f"posture on {robot.terrain!r} at x = {args.x}, y = {args.y}, yaw = {args.yaw}: max residual "
            f"{post.residual:.2e} after {post.iterations} Newton steps",
            *(f"  {c:<8} {v: .10g}" for c, v in zip(robot.coordinates, post.q) if not c.startswith(("phi", "rod")))]
    if args.v is not None:
        from ...inputs import MAX_VELOCITY, as_vector

        nu = robot.check_nu(as_vector(args.v, 2, "--v", ["phi2'", "phi5'"], MAX_VELOCITY, "rad/s"), "v")
        red = robot.reduced(post.q, nu, coriolis=True)
        out.update(M=red.M, C=red.C, g=red.g, B=red.B, mobility=red.projection.mobility)
        names = robot.velocity_names
        text += [f"reduced dynamics in {', '.join(names)}:", f"  M_r = {np.array2string(red.M, precision=8)}",
                 f"  C_r = {np.array2string(red.C, precision=8)}", f"  g_r = {np.array2string(red.g, precision=8)}"]
    print(json.dumps(out, indent=2, default=_jsonable) if args.json else "\n".join(text))
    return 0


def register_cli(subparsers, parents) -> None:
    """``robotdyn linkage-posture``: the posture on an example terrain (and the reduced dynamics there).

    Args:
        subparsers: The CLI's subparsers (``argparse`` action).
        parents: Parsers whose arguments it inherits (the common and robot arguments).
    """
    p = subparsers.add_parser("linkage-posture", parents=[parents[0]],
                              help="linkage_suspension: posture on a terrain (and M_r, C_r, g_r there)")
    p.add_argument("--terrain", default="bump", help=f"one of {', '.join(TERRAINS)}")
    p.add_argument("--x", type=float, default=0.0, help="body x [m]")
    p.add_argument("--y", type=float, default=0.0, help="body y [m]")
    p.add_argument("--yaw", type=float, default=0.0, help="body yaw [rad]")
    p.add_argument("--v", nargs=2, help="independent velocities phi2' phi5' [rad/s]: also print M_r, C_r, g_r")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="override a parameter")
    p.set_defaults(func=_cmd_posture)


# ------------------------------------------------------------------------------ posture vs rigid chassis
def side_bump(height: float = 0.06, x0: float = 0.0, length: float = 0.5, width: float = 0.12,
              side_width: float = 0.04) -> Terrain:
    """A smooth plateau of ``height`` [m] for x in [x0, x0 + length] under the right-hand wheels only (y < 0):
    :math:`z = h\\,s(x)\\,\\tfrac12(1 - \\tanh(y / w_y))`, s a tanh plateau of ramp width ``width``.

    Args:
        height: Plateau height h [m].
        x0: World x [m] where it starts.
        length: Its length along x [m].
        width: Ramp width of the tanh plateau along x [m].
        side_width: Width w_y [m] of the side transition across y = 0.

    Returns:
        The :class:`~robotdyn.constraints.terrain.FunctionTerrain`.
    """
    from ...constraints.terrain import FunctionTerrain

    bx = BumpTerrain(height, x0, width, length)

    def lat(y):
        t = np.tanh(y / side_width)
        return 0.5 * (1 - t), -0.5 * (1 - t * t) / side_width, t * (1 - t * t) / side_width**2

    def f(x, y):
        return bx.height(x, 0.0) * lat(y)[0]

    def grad(x, y):
        ly = lat(y)
        return np.array([bx.gradient(x, 0.0)[0] * ly[0], bx.height(x, 0.0) * ly[1]])

    def hess(x, y):
        ly = lat(y)
        fx, fxx = bx.gradient(x, 0.0)[0], bx.hessian(x, 0.0)[0, 0]
        return np.array([[fxx * ly[0], fx * ly[1]], [fx * ly[1], bx.height(x, 0.0) * ly[2]]])

    return FunctionTerrain(f, grad, hess)


def contact_gaps(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Signed distance-like contact residuals of the six wheels (> 0: off the ground) [m].

    Args:
        robot: The linkage-suspension :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad].

    Returns:
        The six residuals [m].
    """
    kin = KinematicState(robot.model, robot.data, q, np.zeros(robot.nq))
    return np.array([c.rows(kin).residual[-1] for c in robot.constraints if c.name.startswith("wheel")])


def rigid_chassis_posture(robot: Robot, x: float, y: float = 0.0, yaw: float = 0.0) -> np.ndarray:
    """Posture of the same robot with its suspension locked at the nominal angles, resting on the terrain:
    the lowest body height (minimum potential energy) over (z, pitch, roll) with no wheel below the surface.

    Args:
        robot: The linkage-suspension :class:`~robotdyn.robot.Robot`.
        x: Body x [m].
        y: Body y [m].
        yaw: Body yaw [rad].

    Returns:
        q with the suspension coordinates at their neutral values.
    """
    from scipy.optimize import minimize

    from ...errors import ConstraintError

    q = robot.neutral()
    idx = [robot.coordinate_index(c) for c in ("z", "pitch", "roll")]
    for c, v in (("x", x), ("y", y), ("yaw", yaw)):
        q[robot.coordinate_index(c)] = v
    q[idx[0]] += max(robot.terrain.height(x, y), 0.0) + 0.2

    def full(p):
        qq = q.copy()
        qq[idx] = p
        return qq

    def com_z(p):
        return pin.centerOfMass(robot.model, robot.data, full(p))[2]

    res = minimize(com_z, q[idx], method="SLSQP", constraints=[{"type": "ineq", "fun": lambda p: contact_gaps(
        robot, full(p))}], options={"ftol": 1e-12, "maxiter": 200})
    if not res.success:
        raise ConstraintError(f"rigid-chassis posture not found at x = {x}: {res.message}")
    return full(res.x)

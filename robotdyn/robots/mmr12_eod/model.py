"""MMR12-EOD: a differential-drive mobile manipulator with four lifting arms (Zuniga-Aviles et al., 2014): the model side.

Paper: L. A. Zuniga-Aviles, J. C. Pedraza-Ortega et al., "HTG-Based Kinematic Modeling for Positioning of a
Multi-Articulated Wheeled Mobile Manipulator", J. Intell. Robot. Syst. (2014)
(Zúñiga-Avilés et al. 2014, ``docs/bibliography.md``). Description: ``urdf/mmr12_eod.urdf.xacro``, built from
Table 2's Denavit-Hartenberg rows (Paul's convention) so that every HTG frame of eq (2) is a named frame.

Coordinates (natural, m and rad): the planar root (x, y, psi) of the ground footprint under the platform frame C,
``lambda_C`` = the lift Delta lambda_C of eq (1) (vertical prismatic, 0 on the drive wheels), the drive-wheel
angles ``theta_R``, ``theta_L`` (right wheel at y = -b, forward rolling positive), the lifting-arm angles
``theta_C1..4`` (positive = tip down), the manipulator's ``theta1``, ``lambda2``, ``theta3``, ``theta4`` (Table 2;
theta1 is the DH angle, i.e. theta'_1 + 90 deg) and the load joints ``lambda6`` (E_muP) and ``theta_mu`` (E_muR).
Independent velocities: every actuated joint (wheels, arms, manipulator, load); (x, y, psi, lambda_C) are
dependent through the rolling constraints of Table 3 (eqs 12-14) and the wheels' ground contact.

This module holds ``SPEC`` (Table 2, section 3; masses assumed), the CLI hook, the control scenarios (eqs 23-25 on
the model: Table 4 tracking, the Fig. 9 manipulation, the sec 2.11 d lifting), the climbing balance of
sec 2.11 e and the climbing posture's contact forces on a ramp (:func:`climbing_forces`). The paper's closed forms (eqs 1-2, 3-5, 10-14, 26) and printed transforms (eqs 27-31) are in
:mod:`robotdyn.robots.mmr12_eod.paper`, the comparison in :mod:`robotdyn.robots.mmr12_eod.comparison`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...errors import InputError
from ...inputs import MAX_FRICTION
from ...robot import MotorSpec, Parameter, Robot, RobotSpec, Wheel


_ARMS = (1, 2, 3, 4)
MANIPULATOR = ("theta1", "lambda2", "theta3", "theta4")
LOAD = ("lambda6", "theta_mu")
ACTUATED = ("theta_R", "theta_L", *(f"theta_C{i}" for i in _ARMS), *MANIPULATOR, *LOAD)

SPEC = RobotSpec(
    name="mmr12_eod",
    title="MMR12-EOD: differential-drive mobile manipulator, 4 lifting arms, RPRR arm (Zuniga-Aviles, HTG)",
    xacro="mmr12_eod.urdf.xacro",
    root="planar",
    paper=("Zúñiga-Avilés et al. 2014, "
           "HTG-based kinematic modeling for positioning of a multi-articulated wheeled mobile manipulator"),
    parameters=[
        Parameter("lambda_C0", 0.15, "m", "height of C over the ground = drive-wheel radius (sec 3, conclusion)",
                  positive=True),
        Parameter("b", 0.4, "m", "half track: drive wheels at y = -b (right) and +b (left), eqs 13-14, eq 28",
                  positive=True),
        Parameter("l_cs", 0.33, "m", "lifting-arm pivot offset from C along x, Table 2 row C1 (an offset: any sign)"),
        Parameter("d", 0.35, "m", "lifting-arm lateral offset, eq 31 (an offset: any sign)"),
        Parameter("l_cs1", 0.44, "m", "lifting-arm length, Table 2 row CS1", positive=True),
        Parameter("r", 0.08, "m", "lifting-arm tip-wheel radius, eq 26", positive=True),
        Parameter("lambda0", 0.16, "m", "Table 2 row 0 (a DH offset: any sign)"),
        Parameter("l0", 0.33, "m", "Table 2 row 0 (DH l_0 = -0.33; an offset: any sign)"),
        Parameter("l3", 0.15, "m", "Table 2 row 3 (a DH offset: 0 is valid, the wrist on the boom axis)"),
        Parameter("lambda5", 0.38, "m", "Table 2 row E (a DH offset: any sign)"),
        Parameter("lambda2_max", 1.5, "m", "stroke of the prismatic joint 2 (eq 29 uses 1.4; assumed)", positive=True),
        Parameter("lambda6_max", 0.3, "m", "stroke of E_muP (Table 2: 0.05, eq 29: 0.25; assumed)", positive=True),
        Parameter("m_platform", 60.0, "kg", "platform mass (assumed; box 0.9 x 0.6 x 0.2 m)", positive=True),
        Parameter("m_wheel", 3.0, "kg", "drive-wheel mass (assumed)"),
        Parameter("m_arm", 2.0, "kg", "lifting-arm mass (assumed)"),
        Parameter("m_turret", 6.0, "kg", "link 1 mass (assumed)"),
        Parameter("m_boom", 5.0, "kg", "link 2 (telescopic boom) mass (assumed)"),
        Parameter("m_link3", 2.0, "kg", "link 3 mass (assumed)"),
        Parameter("m_link4", 1.5, "kg", "link 4 / gripper mass (assumed)"),
        Parameter("m_load", 10.0, "kg", "load at the end effector (sec 2.1: 10 kg)"),
        Parameter("g", 9.81, "m/s^2", "gravitational acceleration", xacro=False),
        Parameter("mu", 0.1, "-", "rolling-resistance coefficient of the climbing balance (assumed)", xacro=False,
                  minimum=0.0, maximum=MAX_FRICTION),
    ],
    wheels=[Wheel("W_R", "lambda_C0", name="W_R"), Wheel("W_L", "lambda_C0", name="W_L")],
    motors=[
        MotorSpec("tau_R", "theta_R_joint"),
        MotorSpec("tau_L", "theta_L_joint"),
        *(MotorSpec(f"tau_C{i}", f"theta_C{i}_joint") for i in _ARMS),
        MotorSpec("tau_1", "theta1_joint"),
        MotorSpec("f_2", "lambda2_joint"),
        MotorSpec("tau_3", "theta3_joint"),
        MotorSpec("tau_4", "theta4_joint"),
        MotorSpec("f_6", "lambda6_joint"),
        MotorSpec("tau_mu", "theta_mu_joint"),
    ],
    labels={
        "lambda_C_joint": "lambda_C",
        "theta_R_joint": "theta_R",
        "theta_L_joint": "theta_L",
        **{f"theta_C{i}_joint": f"theta_C{i}" for i in _ARMS},
        "theta1_joint": "theta1",
        "lambda2_joint": "lambda2",
        "theta3_joint": "theta3",
        "theta4_joint": "theta4",
        "lambda6_joint": "lambda6",
        "theta_mu_joint": "theta_mu",
    },
    independent=list(ACTUATED),
    neutral={"theta1": 3 * np.pi / 4, "lambda2": 0.4, "theta3": -np.pi / 2, "theta4": np.pi / 2, "lambda6": 0.05},
)


# ------------------------------------------------------------------------------------------- configurations
def state(robot: Robot, **values: float) -> np.ndarray:
    """Natural coordinates: the robot's neutral configuration with the given coordinates overridden.

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        **values: Coordinate values by name [m or rad].

    Returns:
        Natural coordinates (n,).
    """
    q = robot.neutral()
    for label, value in values.items():
        q[robot.coordinate_index(label)] = value
    return q


# ------------------------------------------------------------------------------------------------- CLI
def register_cli(subparsers, parents) -> None:
    """``robotdyn fk ROBOT --q ... --frame NAME`` (generic forward kinematics, see :mod:`robotdyn.description.kinematics`)
    and ``robotdyn climbing-posture ROBOT --slope DEG`` (:mod:`robotdyn.robots.mmr12_eod.climbing_posture`).

    Args:
        subparsers: The CLI's subparsers (``argparse`` action).
        parents: Parsers whose arguments it inherits (the common and robot arguments).
    """
    from ...cli.fk import register_fk_cli
    from .climbing_posture import register_cli as register_climbing

    register_fk_cli(subparsers, parents)
    register_climbing(subparsers, parents)


# ------------------------------------------------------------------------------------- control scenarios
LOOK_AHEAD = 0.565
"""Distance [m] of the controlled point P ahead of C on the platform's axis: the output of the linearising
feedback (C itself cannot be: a differential drive's axle centre has a singular decoupling matrix); the paper's
"ideal diameter of 1,130 mm" (sec 2.11 a) is read as the circle P sweeps when the platform turns on the spot."""

GAINS = {"kp": 4.0, "kd": 4.0, "damping": 2.0}
"""Eq 25 gains K_p [1/s^2], K_d [1/s] (not printed in the paper: critically damped, natural frequency 2 rad/s)."""


def _quintic(t: float, T: float, a, b) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A rest-to-rest quintic from a to b over [0, T] (value, rate, acceleration)."""
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    s = min(max(t / T, 0.0), 1.0)
    inside = 0.0 < t < T
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    dp = (30 * s**2 - 60 * s**3 + 30 * s**4) / T if inside else 0.0
    ddp = (60 * s - 180 * s**2 + 120 * s**3) / T**2 if inside else 0.0
    return a + (b - a) * p, (b - a) * dp, (b - a) * ddp


def quintic_reference(T: float, a, b):
    """:func:`_quintic` as data (:class:`~robotdyn.simulation.control.ProfileReference`): the rest-to-rest quintic
    a + (b - a)(10 s^3 - 15 s^4 + 6 s^5), s = t / T, as polynomials of t on [0, T] (rate and acceleration too),
    then b held (a window starting one double after T).

    Args:
        T: Duration [s].
        a, b: Start and end values (same shape).

    Returns:
        The :class:`~robotdyn.simulation.control.ProfileReference` (value, rate, acceleration), each of the width of
        ``a``, in the units of ``a`` per s^0, s^1, s^2.
    """
    from ...simulation.control import ProfileReference
    from ...simulation.torque_profile import Polynomial, Sine

    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    d, z = b - a, np.zeros_like(a)
    after = float(np.nextafter(T, np.inf))
    value = Polynomial([a, z, z, 10 * d / T**3, -15 * d / T**4, 6 * d / T**5], 0.0, T) + Sine(b, 0.0, np.pi / 2, after)
    rate = Polynomial([z, z, 30 * d / T**3, -60 * d / T**4, 30 * d / T**5], 0.0, T)
    acceleration = Polynomial([z, 60 * d / T**3, -180 * d / T**4, 120 * d / T**5], 0.0, T)
    return ProfileReference(value, rate, acceleration)


def table4_reference(name: str, omega: float = 0.5):
    """Table 4's platform references as t -> (p_d, p_d', p_d'') of the controlled point [m], given as data
    (:class:`~robotdyn.simulation.control.ProfileReference`: sines and polynomials of t, so that the controller
    runs on the compiled engine): ``orientation`` (turning about the centre x = y = 0: P on a circle of radius
    LOOK_AHEAD at omega rad/s), ``straight`` (x = 30, y = t), ``sinusoid`` (x = 40 cos 0.25t + 2.5t,
    y = 30 sin 0.25t).

    Args:
        name: ``orientation``, ``straight`` or ``sinusoid``.
        omega: Turning rate of the orientation task [rad/s].

    Returns:
        A function of t [s] returning ``(p_d, p_d', p_d'')``, each (2,) [m, m/s, m/s^2] in the world x, y.
    """
    from ...simulation.control import ProfileReference
    from ...simulation.torque_profile import Constant, Polynomial, Sine

    L, c = LOOK_AHEAD, np.pi / 2  # cos(x) = sin(x + pi/2)
    x, y = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    if name == "orientation":
        return ProfileReference(Sine(L * x, omega, c) + Sine(L * y, omega),
                                Sine(-L * omega * x, omega) + Sine(L * omega * y, omega, c),
                                Sine(-L * omega**2 * x, omega, c) + Sine(-L * omega**2 * y, omega))
    if name == "straight":
        return ProfileReference(Polynomial([[30.0, 0.0], [0.0, 1.0]]), Constant([0.0, 1.0]), Constant([0.0, 0.0]))
    if name == "sinusoid":
        return ProfileReference(Sine(40 * x, 0.25, c) + Sine(30 * y, 0.25) + Polynomial([[0.0, 0.0], [2.5, 0.0]]),
                                Sine(-10 * x, 0.25) + Sine(7.5 * y, 0.25, c) + Constant([2.5, 0.0]),
                                Sine(-2.5 * x, 0.25, c) + Sine(-1.875 * y, 0.25))
    raise InputError(f"unknown Table 4 trajectory {name!r}; expected orientation, straight or sinusoid")


def _hold_task(robot: Robot, labels, q0):
    from ...simulation.control import CoordinateTask, hold_data

    return CoordinateTask(list(labels), hold_data([q0[robot.coordinate_index(c)] for c in labels]))


def platform_controller(robot: Robot, name: str, q0: np.ndarray | None = None):
    """Eqs 23-25 for a Table 4 trajectory: P tracks the reference, every other actuated joint holds its value.

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        name: The Table 4 trajectory (:func:`table4_reference`).
        q0: The configuration whose joint values are held (default ``None``: the neutral one).

    Returns:
        The :class:`~robotdyn.simulation.control.LinearisingController`.
    """
    from ...simulation.control import LinearisingController, PointTask

    q0 = robot.neutral() if q0 is None else q0
    others = [c for c in ACTUATED if c not in ("theta_R", "theta_L")]
    tasks = [PointTask("C", table4_reference(name), offset=(LOOK_AHEAD, 0.0, 0.0), axes=(0, 1)),
             _hold_task(robot, others, q0)]
    return LinearisingController(robot, tasks, **GAINS)


def platform_initial(robot: Robot, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Start on the reference: P at p_d(0), heading along p_d'(0) (or along +x at rest), wheels rolling at the
    reference speed (at rest for the orientation task).

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        name: The Table 4 trajectory (:func:`table4_reference`).

    Returns:
        ``(q0, nu0)``: the configuration (nq,) and the independent velocities (k,).
    """
    pd, vd, _ = table4_reference(name)(0.0)
    speed = float(np.linalg.norm(vd))
    psi = float(np.arctan2(vd[1], vd[0])) if name != "orientation" else 0.0
    c = pd - LOOK_AHEAD * np.array([np.cos(psi), np.sin(psi)])
    q0 = state(robot, x=c[0], y=c[1], psi=psi)
    nu0 = np.zeros(robot.mobility)
    if name != "orientation":
        for w in ("theta_R_dot", "theta_L_dot"):
            nu0[robot.velocity_names.index(w)] = speed / robot.params["lambda_C0"]
    return q0, nu0


MANIPULATION_TARGET = np.array([2.0, 2.0, 1.5])
"""Sec 3 / Fig. 9: the target on the wall at x = 2, y = 2, z = 1.5 m (robot placed at 45 degrees)."""


def manipulation_goal(robot: Robot, q0: np.ndarray | None = None):
    """A final configuration putting E on MANIPULATION_TARGET: numerical IK over (x, y, theta3) with the heading
    kept and the boom raised to theta1 = 2.7 rad, lambda2 = 1.1 m (inside the joint ranges).

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        q0: The starting configuration (default ``None``: :func:`manipulation_initial`).

    Returns:
        The :class:`~robotdyn.description.kinematics.IKResult` of the solve.
    """
    from ...description.kinematics import position_ik

    q0 = manipulation_initial(robot)[0] if q0 is None else q0
    guess = q0.copy()
    guess[robot.coordinate_index("theta1")] = 2.7
    guess[robot.coordinate_index("lambda2")] = 1.1
    return position_ik(robot, "E", MANIPULATION_TARGET, guess, ["x", "y", "theta3"])


def manipulation_controller(robot: Robot, q0: np.ndarray | None = None, T: float = 10.0):
    """End effector E to MANIPULATION_TARGET along a rest-to-rest quintic over T s (primary output, eq 25); arms,
    theta4 and the load hold; in the null space, (theta1, lambda2, theta3) follow quintics to the IK goal posture
    so that the joints stay in range and the platform drives the rest.

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        q0: The starting configuration (default ``None``: :func:`manipulation_initial`).
        T: Duration of the quintic [s].

    Returns:
        The :class:`~robotdyn.simulation.control.LinearisingController`.
    """
    from ...simulation.control import CoordinateTask, LinearisingController, PointTask
    from ...description.kinematics import frame_pose

    q0 = manipulation_initial(robot)[0] if q0 is None else q0
    start = frame_pose(robot, q0, "E")[:3, 3]
    goal = manipulation_goal(robot, q0)
    if not goal.success:
        raise InputError(f"manipulation target {MANIPULATION_TARGET.tolist()} not reachable (IK error {goal.error:.3g} m)")
    arm = list(MANIPULATOR[:3])
    idx = [robot.coordinate_index(c) for c in arm]
    ref = quintic_reference(T, start, MANIPULATION_TARGET)
    posture = quintic_reference(T, q0[idx], goal.q[idx])
    held = [*(f"theta_C{i}" for i in _ARMS), "theta4", *LOAD]
    return LinearisingController(robot, [PointTask("E", ref), _hold_task(robot, held, q0)],
                                 secondary=[CoordinateTask(arm, posture)], **GAINS)


def manipulation_initial(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """At the origin, heading 45 degrees towards the wall target, arm in the neutral posture, at rest.

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.

    Returns:
        ``(q0, nu0)``: the configuration (nq,) and zero independent velocities (k,).
    """
    return state(robot, psi=np.pi / 4), np.zeros(robot.mobility)


# ------------------------------------------------------------------------------------------- lifting
LIFT_END = 1.54
"""Final arm angle [rad] of the lifting run: just short of pi/2, where d lambda_C / d theta_C = 0 (a dead point
of the arms: the constraint block is singular there); lambda_C0 + Delta lambda_C = 0.5198 m (eq 30: 0.52)."""


def lift_spec(spec: RobotSpec = SPEC) -> RobotSpec:
    """The robot standing on its four lifting-arm tip wheels (frictionless supports, normal rows only), drive
    wheels in the air: the lifting configuration of sec 2.11 d (Fig. 5).

    Args:
        spec: The robot's :class:`~robotdyn.robot.RobotSpec`.

    Returns:
        The lifting :class:`~robotdyn.robot.RobotSpec`.
    """
    return dataclasses.replace(
        spec,
        name=f"{spec.name}_lifting",
        wheels=[Wheel(f"CS{i}", "r", axis=(0.0, 0.0, 1.0), kind="support", name=f"tip{i}") for i in _ARMS],
        independent=["x", "y", "psi", "theta_R", "theta_L", "theta_C1", *MANIPULATOR, *LOAD],
    )


def lift_robot(robot: Robot | None = None) -> Robot:
    """The lifting configuration of ``robot`` (same parameters).

    Args:
        robot: The robot whose parameters are kept (default ``None``: the defaults).

    Returns:
        The lifting :class:`~robotdyn.robot.Robot`.
    """
    params = robot.params if robot is not None else None
    return Robot(lift_spec(robot.spec if robot is not None else SPEC), params)


def contact_angle(p: dict) -> float:
    """Arm angle [rad] at which the tip wheels touch the ground with the drive wheels still on it (eq 1 = 0).

    Args:
        p: The parameters as a plain dict (Table 2 names of :data:`.model.SPEC`; lengths [m], angles [rad]).

    Returns:
        The angle [rad].
    """
    return float(np.arcsin((p["lambda_C0"] - p["r"]) / p["l_cs1"]))


def lifting_initial(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """All four arms at the contact angle, lambda_C = 0, at rest.

    Args:
        robot: The lifting robot (:func:`lift_robot`).

    Returns:
        ``(q0, nu0)``: the configuration (nq,) and zero independent velocities (k,).
    """
    th = contact_angle(robot.params)
    return state(robot, lambda_C=0.0, **{f"theta_C{i}": th for i in _ARMS}), np.zeros(robot.mobility)


def lifting_controller(robot: Robot, T: float = 5.0, end: float = LIFT_END):
    """Arm 1 (the others follow through the contacts) along a quintic from the contact angle to ``end`` in T s,
    the manipulator, load and wheels hold; x, y, psi are unactuated (free on frictionless tips).

    Args:
        robot: The lifting robot (:func:`lift_robot`).
        T: Duration of the quintic [s].
        end: Final arm angle [rad].

    Returns:
        The :class:`~robotdyn.simulation.control.LinearisingController`.
    """
    from ...simulation.control import CoordinateTask, LinearisingController

    q0 = lifting_initial(robot)[0]
    th0 = contact_angle(robot.params)
    tasks = [CoordinateTask(["theta_C1"], quintic_reference(T, th0, end)),
             _hold_task(robot, [*MANIPULATOR, *LOAD, "theta_R", "theta_L"], q0)]
    return LinearisingController(robot, tasks, controlled=["theta_R", "theta_L", "theta_C1", *MANIPULATOR, *LOAD],
                                 **GAINS)


# ------------------------------------------------------------------------------------------- climbing
def climbing_balance(robot: Robot, slope: float, mu: float | None = None) -> dict[str, float]:
    """Static force balance on a slope (sec 2.11 e): F_climb = m g (sin psi + mu cos psi).

    The gravity part is also taken from the model: the platform on a plane inclined by ``slope`` [rad] along its
    heading is the flat-ground model with gravity tilted by the slope, and the reduced gravity of the two
    wheel coordinates, (g_R + g_L) / R, is the force the wheels must push with to hold the robot (no climbing in the
    simulator: the planar root keeps the platform parallel to the ground; rolling resistance mu N is not modelled).

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        slope: Slope angle psi [rad] (abs(slope) < pi/2).
        mu: Rolling-resistance coefficient (default ``None``: the robot's parameter ``mu``).

    Returns:
        ``mass`` [kg], ``F_paper`` = m g (sin + mu cos) [N], ``F_gravity_paper`` = m g sin [N],
        ``F_gravity_model`` [N], ``wheel_torque`` = F_paper R / 2 per drive wheel [N m].
    """
    import pinocchio as pin

    if not np.isfinite(slope) or abs(slope) >= np.pi / 2:
        raise InputError(f"slope = {slope} rad; expected |slope| < pi/2")
    mu = robot.params["mu"] if mu is None else mu
    g = robot.params["g"]
    m = float(pin.computeTotalMass(robot.model))
    saved = robot.model.gravity.linear.copy()
    try:
        robot.model.gravity.linear = g * np.array([-np.sin(slope), 0.0, -np.cos(slope)])
        red = robot.reduced(state(robot, psi=0.0), np.zeros(robot.mobility))
    finally:
        robot.model.gravity.linear = saved
    iR, iL = robot.velocity_names.index("theta_R_dot"), robot.velocity_names.index("theta_L_dot")
    R = robot.params["lambda_C0"]
    F = m * g * (np.sin(slope) + mu * np.cos(slope))
    return {"mass": m, "F_paper": F, "F_gravity_paper": m * g * np.sin(slope),
            "F_gravity_model": float((red.g[iR] + red.g[iL]) / R), "wheel_torque": F * R / 2}


# ------------------------------------------------------------------------------------------- climbing on forces
CLIMB_ARMS_UP = 0.6
"""How far [rad] the front arms (1, 2) are raised above the contact angle in :func:`climbing_robot`."""


def climbing_robot(slope: float, robot: Robot | None = None) -> Robot:
    """The robot holding itself on a ramp of ``slope`` [rad] (rising along world x): floating root, the two drive
    wheels rolling without slipping and the rear arms' tip wheels (3, 4) as frictionless supports, the front arms
    raised (sec 2.11 e's climbing with the arms as outriggers; the real robot's tracks are not in the
    description).

    Args:
        slope: Ramp angle [rad] (abs(slope) < pi/2).
        robot: The robot whose parameters are kept (default ``None``: the defaults).

    Returns:
        The climbing :class:`~robotdyn.robot.Robot`.
    """
    from ...constraints.terrain import RampTerrain

    if not np.isfinite(slope) or abs(slope) >= np.pi / 2:
        raise InputError(f"slope = {slope} rad; expected |slope| < pi/2")
    base = robot.spec if robot is not None else SPEC
    spec = dataclasses.replace(
        base, name=f"{base.name}_climbing", root="floating", independent=None,
        wheels=[*base.wheels, *(Wheel(f"CS{i}", "r", axis=(0.0, 0.0, 1.0), kind="support", name=f"tip{i}")
                                for i in (3, 4))])
    return Robot(spec, robot.params if robot is not None else None, RampTerrain(float(np.tan(slope))))


def climbing_state(robot: Robot, slope: float) -> np.ndarray:
    """The climbing posture on the ramp of :func:`climbing_robot`: facing uphill (pitch = -slope about the ramp
    line through the origin), rear arms at the contact angle (their tips and the drive wheels on the ramp), front
    arms :data:`CLIMB_ARMS_UP` higher, manipulator neutral.

    Args:
        robot: The climbing robot (:func:`climbing_robot`).
        slope: Ramp angle [rad].

    Returns:
        Natural coordinates (n,).
    """
    th = contact_angle(robot.params)
    return state(robot, pitch=-slope, theta_C1=th - CLIMB_ARMS_UP, theta_C2=th - CLIMB_ARMS_UP, theta_C3=th,
                 theta_C4=th)


def climbing_forces(slope: float, robot: Robot | None = None):
    """Contact forces holding the robot at rest on a ramp of ``slope`` [rad] (:func:`climbing_robot`, every motor
    holding its coordinate): the :class:`~robotdyn.contact.contact_forces.ConstraintForces` (drive-wheel traction and
    loads, tip loads, ``minimum_mu``: the smallest friction coefficient that holds the robot there).

    Args:
        slope: Ramp angle [rad] (abs(slope) < pi/2).
        robot: The robot whose parameters are kept (default ``None``: the defaults).

    Returns:
        The :class:`~robotdyn.contact.contact_forces.ConstraintForces` (forces in N).
    """
    climber = climbing_robot(slope, robot)
    zero = np.zeros(climber.mobility)
    return climber.contact_forces(climbing_state(climber, slope), zero, nudot=zero)


# ------------------------------------------------------------------------------------------- scenarios
def _scenarios() -> dict:
    from ...simulation.control import ControlledScenario

    out = {}
    for name, desc in (
        ("orientation", "Table 4 task 1: turning about its centre (P on a 0.565 m circle at 0.5 rad/s), from rest"),
        ("straight", "Table 4 task 2: straight line x = 30 m, y = t, started on the reference"),
        ("sinusoid", "Table 4: x = 40 cos 0.25t + 2.5t, y = 30 sin 0.25t, started on the reference"),
    ):
        out[name] = ControlledScenario(
            name, desc + " (eqs 23-25, 200 s)", 200.0, n_out=2001, plot=["x", "y", "psi"],
            make_controller=lambda robot, name=name: platform_controller(robot, name, platform_initial(robot, name)[0]),
            initial=lambda robot, name=name: platform_initial(robot, name))
    out["manipulation"] = ControlledScenario(
        "manipulation", "sec 3 / Fig. 9: end effector E to the wall target (2, 2, 1.5) m in 10 s (eqs 23-25)", 15.0,
        n_out=301, plot=["x", "y", "theta1", "lambda2", "theta3"],
        make_controller=lambda robot: manipulation_controller(robot), initial=manipulation_initial)
    out["lifting"] = ControlledScenario(
        "lifting", "sec 2.11 d: the four arms lift the platform from 0.15 to 0.52 m in 5 s (robot on the arm tips)",
        6.0, n_out=121, plot=["lambda_C", "theta_C1", "theta_C2"],
        adapt_robot=lift_robot, make_controller=lambda robot: lifting_controller(robot), initial=lifting_initial)
    return out


SCENARIOS = _scenarios()

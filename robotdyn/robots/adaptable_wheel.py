"""Three-wheeled robot with adaptable-radius wheels on rough terrain (Mardani & Ebrahimi 2016).

Paper: A. Mardani, S. Ebrahimi, "A Novel Multimode Mobile Robot with Adaptable Wheel Geometry for Maneuverability
Improvement" (``shared/papers/mardani_ebrahimi_2016_adaptable_wheel_robot.txt``).
Description: ``urdf/adaptable_wheel.urdf.xacro``.

Model (derived by Pinocchio from the description): floating body (x, y, z, yaw, pitch, roll; Z-Y-X Euler) with
three wheels fr, fl, r at the eq-8 positions, each with a spin joint ``theta_<i>`` (wheel motor), an adjustment
angle ``q_<i>`` (adjustment motor, 0-180 deg) and a prismatic radius ``Rch_<i>`` (the close-loop pattern radius).
The wheel radius is :math:`R_T = R_{ru} + R_{ch}` and the mechanism law of eq 1,
:math:`R_{ch} = w\\cos(q/2)\\cos(\\pi/6)`, is a holonomic :class:`~robotdyn.constraints.joint_coupling.JointCoupling`, so
the radius follows the configuration through the constraint layer. Each wheel rolls on the terrain
(:class:`~robotdyn.constraints.rolling_contact.RollingWheel` with ``radius_joint``); ``lateral=slip`` drops the lateral
no-slip row (the paper's kinematic missions turn the robot about a vertical axis away from its wheel axles,
which rolling without lateral slip forbids: see ``docs/errata/adaptable_wheel.md``).

Paper transcription, kept apart from the model: the inverse kinematics of eqs 4-24 (:func:`solve_ik`,
:func:`run_mission`), the static torque estimate of eq 35 (:func:`paper_torque_eq35`) and the fuller route of
eqs 25-34 (:func:`static_torques`), with the contact forces from :func:`robotdyn.contact.statics.solve_contact_forces`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

import numpy as np
import pinocchio as pin

from ..reduction.actuation import input_matrix
from ..interfaces.comparison import Comparison
from ..constraints.constraint import KinematicState
from ..errors import ConstraintError, InputError, RobotDynError
from ..contact.friction import LinearTyre, RegularisedCoulomb
from ..constraints.joint_coupling import CosineLaw, JointCoupling
from ..robot import MotorSpec, Parameter, Robot, RobotSpec
from ..constraints.rolling_contact import OmniWheel, RollingWheel
from ..simulation.scenario import Scenario
from ..contact.sliding import SlippingWheel
from ..contact.statics import solve_contact_forces
from ..constraints.terrain import FlatTerrain, RampTerrain, SineTerrain, Terrain
from ..simulation.torque_profile import Constant

WHEELS = ("fr", "fl", "r")
"""Wheel tags: front right, front left, rear (eq 8)."""
COS30 = float(np.cos(np.pi / 6))
IK_TOL = 1e-10
LATERAL_SLIP_VELOCITY = 1e-3
"""Slip-velocity scale [m/s] of the regularised Coulomb law of ``lateral=coulomb`` (mission 1 slides at ~0.6 m/s, so
the law is Coulomb's to a relative 1e-6 there)."""
LATERAL_STIFFNESS = 10.0
"""Slip stiffness [s/m] of the brush law of ``lateral=linear`` (saturated at mu; not in the paper)."""
"""Convergence criterion ||C|| of the inverse kinematics (the paper used 1e-5, Table 1)."""


# ------------------------------------------------------------------------------------------ the mechanism
def radius_law(q: float, w: float) -> float:
    """Eq 1: close-loop pattern radius :math:`R_{ch} = w\\cos(q/2)\\cos(\\pi/6)` [m] for adjustment angle q [rad]."""
    return w * np.cos(0.5 * q) * COS30


def radius_law_d(q: float, w: float) -> float:
    """Eq 33: :math:`dR_{ch}/dq = -\\tfrac12 w\\sin(q/2)\\cos(\\pi/6)` [m/rad]."""
    return -0.5 * w * np.sin(0.5 * q) * COS30


def radius_law_dd(q: float, w: float) -> float:
    """:math:`d^2R_{ch}/dq^2 = -\\tfrac14 w\\cos(q/2)\\cos(\\pi/6)` [m/rad^2]."""
    return -0.25 * w * np.cos(0.5 * q) * COS30


def _terrain(p: dict) -> Terrain:
    if p["terrain"] == "rough":
        return SineTerrain(1.0 / 15.0, 0.5, 0.5)  # Table 1: Z = sin(0.5(x + y))/15
    if p["terrain"] == "ramp":
        return RampTerrain(p["ramp_slope"], p["ramp_heading"])
    return FlatTerrain()


def _wheel_factory(tag: str) -> Callable[[Robot], RollingWheel]:
    def make(robot: Robot) -> RollingWheel:
        lateral = robot.params["lateral"]
        kind = {"rolling": RollingWheel, "slip": partial(OmniWheel, roller_angle=0.0)}.get(lateral)
        if kind is None:  # rolling along t1, sliding sideways under a friction law of coefficient mu
            law = RegularisedCoulomb(robot.params["mu"], LATERAL_SLIP_VELOCITY) if lateral == "coulomb" else \
                LinearTyre(LATERAL_STIFFNESS, robot.params["mu"])
            kind = partial(SlippingWheel, law=law, slip="lateral")
        return kind(robot.description, f"wheel_{tag}", robot.params["R_ru"], axis=(0.0, 1.0, 0.0),
                    terrain=robot.terrain, radius_joint=f"radius_{tag}_joint", name=tag)

    return make


def _coupling_factory(tag: str) -> Callable[[Robot], JointCoupling]:
    def make(robot: Robot) -> JointCoupling:
        w = robot.params["w"]
        # eq 1 as data (radius_law with its derivatives eq 33), so that the compiled path can evaluate it
        return JointCoupling(robot.description, f"radius_{tag}_joint", f"adjust_{tag}_joint",
                             CosineLaw(w * COS30, 0.5), name=f"eq1_{tag}")

    return make


_Q0 = 2 * np.pi / 3
_NEUTRAL_Q = {"fr": 1.9, "fl": 2.3, "r": _Q0}
"""Adjustment angles of the neutral configuration. The front radii differ on purpose: with equal front radii the
lateral rows of the two front wheels coincide on flat ground (a kinematic singularity, see the errata), and the
automatic choice of independent velocities is made at the neutral configuration."""
SPEC = RobotSpec(
    name="adaptable_wheel",
    title="Tricycle with adaptable-radius wheels on rough terrain (Mardani & Ebrahimi 2016)",
    xacro="adaptable_wheel.urdf.xacro",
    root="floating",
    paper="mardani_ebrahimi_2016_adaptable_wheel_robot.txt",
    parameters=[
        Parameter("m", 10.0, "kg", "total mass (Table 1)"),
        Parameter("m_wheel", 0.0, "kg", "mass of each wheel hub (paper: all mass lumped in the body)"),
        Parameter("I_adjust", 0.0, "kg m^2", "rotor inertia of each adjustment motor (not in the paper)"),
        Parameter("w", 0.3, "m", "cross-linkage leg length (Table 1, eq 1)"),
        Parameter("Lx", 0.6, "m", "Table 1 L_x (see L_reading)"),
        Parameter("Ly", 0.6, "m", "Table 1 L_y (see L_reading)"),
        Parameter("L_reading", "half", "", "half: Lx, Ly are the eq-8 offsets (body 2Lx x 2Ly); full: body Lx x Ly",
                  choices=("half", "full")),
        Parameter("R_ru", 0.02, "m", "rubber height, added to the pattern radius (Table 1)"),
        Parameter("body_height", 0.05, "m", "body plate thickness (inertia only; not in the paper)"),
        Parameter("mu", 1.0, "-", "static friction coefficient (Table 1)", xacro=False),
        Parameter("g", 9.81, "m/s^2", "gravitational acceleration (not printed in the paper)", xacro=False),
        Parameter("terrain", "rough", "", "rough: Z = sin(0.5(x+y))/15 (Table 1); ramp; flat",
                  choices=("rough", "ramp", "flat"), xacro=False),
        Parameter("ramp_slope", 0.2, "-", "slope of the ramp terrain (mission 2)", xacro=False),
        Parameter("ramp_heading", -np.pi / 2, "rad", "direction in which the ramp rises (mission 2)", xacro=False),
        Parameter("lateral", "rolling", "", "rolling: wheels roll without slipping; slip: lateral row dropped "
                  "(frictionless); coulomb, linear: sideways sliding under that friction law with mu",
                  choices=("rolling", "slip", "coulomb", "linear"), xacro=False),
    ],
    constraints=[_wheel_factory(t) for t in WHEELS] + [_coupling_factory(t) for t in WHEELS],
    motors=[MotorSpec(f"spin_{t}", f"wheel_{t}_joint") for t in WHEELS]
    + [MotorSpec(f"adjust_{t}", f"adjust_{t}_joint") for t in WHEELS],
    labels={
        **{f"wheel_{t}_joint": f"theta_{t}" for t in WHEELS},
        **{f"adjust_{t}_joint": f"q_{t}" for t in WHEELS},
        **{f"radius_{t}_joint": f"Rch_{t}" for t in WHEELS},
    },
    terrain=_terrain,
    neutral={
        "z": 0.02 + radius_law(_Q0, 0.3),
        **{f"q_{t}": _NEUTRAL_Q[t] for t in WHEELS},
        **{f"Rch_{t}": radius_law(_NEUTRAL_Q[t], 0.3) for t in WHEELS},
    },
)


def offsets(p: dict) -> dict[str, np.ndarray]:
    """Eq 8: wheel centres in the body frame X_CG Y_CG Z_CG [m] (Lx, Ly read per ``L_reading``)."""
    s = 1.0 if p["L_reading"] == "half" else 0.5
    lx, ly = s * p["Lx"], s * p["Ly"]
    return {"fr": np.array([lx, -ly, 0.0]), "fl": np.array([lx, ly, 0.0]), "r": np.array([-lx, 0.0, 0.0])}


def q_range_radius(p: dict) -> tuple[float, float]:
    """Smallest and largest total radius R_T [m] over the adjustment range q in [0, pi] (eq 1)."""
    return p["R_ru"], p["R_ru"] + p["w"] * COS30


# ------------------------------------------------------------------------------------ eqs 4-24 (transcribed)
def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


_R2 = {"fr": _rx(np.pi / 2), "r": _rx(np.pi / 2), "fl": _rx(-np.pi / 2)}  # eq 9
_SIGN = {"fr": -1.0, "r": -1.0, "fl": 1.0}  # eq 11: translation (0, -+R_T, 0) in frame b


def paper_normal(terrain: Terrain, x: float, y: float) -> np.ndarray:
    """Eq 3 (read as :math:`N = (-f_x, -f_y, 1)`, not normalised)."""
    fx, fy = terrain.gradient(x, y)
    return np.array([-fx, -fy, 1.0])


@dataclass
class Commands:
    """The six commands of section 3 at one instant: path point (x_d, y_d) [m], height h_CG [m] along the normal,
    and the body angles q_xd, q_yd, q_zd [rad] of eq 4 (rotations about fixed Y, then X, then Z)."""

    xd: float
    yd: float
    h: float
    qx: float = 0.0
    qy: float = 0.0
    qz: float = 0.0


def body_pose(cmd: Commands, terrain: Terrain) -> tuple[np.ndarray, np.ndarray]:
    """Eqs 4-6: rotation :math:`R_{CG}^0 = R_y(q_{yd}) R_x(q_{xd}) R_z(q_{zd})` and CG position
    :math:`d_{CG}^0 = [x_d, y_d, f(x_d, y_d)] + h_{CG}\\,n(x_d, y_d)` (world frame, m)."""
    R = _ry(cmd.qy) @ _rx(cmd.qx) @ _rz(cmd.qz)
    n = terrain.normal(cmd.xd, cmd.yd)
    d = np.array([cmd.xd, cmd.yd, terrain.height(cmd.xd, cmd.yd)]) + cmd.h * n
    return R, d


def contact_frame(R_cg: np.ndarray, d_cg: np.ndarray, offset: np.ndarray, tag: str, beta: float,
                  RT: float) -> tuple[np.ndarray, np.ndarray]:
    """Eqs 7-11: rotation :math:`R_{3i}^0` and origin :math:`d_{3i}^0` of the contact frame of wheel ``tag``."""
    R3 = R_cg @ _R2[tag] @ _rz(beta)
    d3 = d_cg + R_cg @ offset + R3 @ np.array([0.0, _SIGN[tag] * RT, 0.0])
    return R3, d3


def wheel_constraints(R_cg, d_cg, offset, tag, beta, RT, terrain) -> np.ndarray:
    """Eqs 12 and 14 of one wheel: :math:`C_i = d_{3i}(3) - f(d_{3i}(1), d_{3i}(2))` and
    :math:`CC_i = [1\\,0\\,0] (R_{3i}^0)^T N` at the contact point."""
    R3, d3 = contact_frame(R_cg, d_cg, offset, tag, beta, RT)
    return np.array([d3[2] - terrain.height(d3[0], d3[1]), R3[:, 0] @ paper_normal(terrain, d3[0], d3[1])])


def ik_residual(x: np.ndarray, R_cg, d_cg, p: dict, terrain: Terrain) -> np.ndarray:
    """Eq 15: :math:`C = [C_{fr}, C_{fl}, C_r, CC_{fr}, CC_{fl}, CC_r]` for the unknowns of eq 16,
    :math:`x = [\\beta_{fr}, \\beta_{fl}, \\beta_r, q_{fr}, q_{fl}, q_r]` (rad)."""
    off = offsets(p)
    out = np.empty(6)
    for k, tag in enumerate(WHEELS):
        RT = p["R_ru"] + radius_law(x[3 + k], p["w"])
        out[[k, 3 + k]] = wheel_constraints(R_cg, d_cg, off[tag], tag, x[k], RT, terrain)
    return out


class MechanismRangeError(InputError):
    """A command needs an adjustment angle outside the mechanism's range 0-180 deg."""


def _needed_radius(R_cg, d_cg, p, terrain, tag, beta0: float) -> float:
    """The radius R_T [m] wheel ``tag`` would need (eqs 12, 14 solved for (beta, R_T): always well posed)."""
    off = offsets(p)[tag]
    RT0 = float(d_cg[2] - terrain.height(*(d_cg + R_cg @ off)[:2]))
    fun = partial(_wheel_rt, R_cg=R_cg, d_cg=d_cg, offset=off, tag=tag, terrain=terrain)
    from scipy.optimize import root

    sol = root(fun, [beta0, RT0], method="hybr", options={"xtol": 1e-14})
    if np.linalg.norm(fun(sol.x)) > 1e-8:
        raise ConstraintError(f"wheel {tag}: cannot touch the surface with any radius at these commands")
    return float(sol.x[1])


def _wheel_rt(z, R_cg, d_cg, offset, tag, terrain):
    return wheel_constraints(R_cg, d_cg, offset, tag, z[0], z[1], terrain)


def solve_ik(cmd: Commands, p: dict, terrain: Terrain, guess: np.ndarray | None = None,
             tol: float = IK_TOL) -> tuple[np.ndarray, float, int]:
    """Solve eq 15 for eq 16's unknowns by scipy's root finder (eq 24's Newton-Raphson, hybrid variant).

    Args:
        cmd: The six commands.
        p: Parameters (w, Lx, Ly, L_reading, R_ru).
        terrain: The surface of eq 2.
        guess: Initial (beta_fr, beta_fl, beta_r, q_fr, q_fl, q_r) [rad]; default zeros and 120 deg.
        tol: Required ||C|| (eq 24's error).

    Returns:
        ``(x, error, nfev)``: the solution (q in [0, pi]), ||C|| and the number of residual evaluations.

    Raises:
        MechanismRangeError: a wheel needs q outside 0-180 deg (names the wheel, the radius and the limit).
        ConstraintError: no solution found.
    """
    R_cg, d_cg = body_pose(cmd, terrain)
    x0 = np.array([0.0, 0.0, 0.0, _Q0, _Q0, _Q0]) if guess is None else np.array(guess, float)
    f = partial(ik_residual, R_cg=R_cg, d_cg=d_cg, p=p, terrain=terrain)
    from scipy.optimize import root

    sol = root(f, x0, method="hybr", options={"xtol": 1e-15})
    x = sol.x.copy()
    x[3:] = np.abs(x[3:])  # eq 1 is even in q: -q and q give the same radius
    err = float(np.linalg.norm(f(x)))
    lo, hi = q_range_radius(p)
    for k, tag in enumerate(WHEELS):
        if err > tol or not (0.0 <= x[3 + k] <= np.pi):
            RT = _needed_radius(R_cg, d_cg, p, terrain, tag, x[k] if np.isfinite(x[k]) else 0.0)
            if RT > hi + 1e-12:
                raise MechanismRangeError(
                    f"wheel {tag}: the commands need radius R_T = {RT:.4f} m, more than the {hi:.4f} m the mechanism "
                    "gives at its limit q = 0 deg (adjustment range 0-180 deg)")
            if RT < lo - 1e-12:
                raise MechanismRangeError(
                    f"wheel {tag}: the commands need radius R_T = {RT:.4f} m, less than the {lo:.4f} m the mechanism "
                    "gives at its limit q = 180 deg (adjustment range 0-180 deg)")
    if err > tol:
        raise ConstraintError(f"inverse kinematics did not converge: ||C|| = {err:.3g} > {tol:g} ({sol.message})")
    off = offsets(p)
    for k, tag in enumerate(WHEELS):  # eq 14 also holds at the top of the rim: keep the contact below the centre
        R3, d3 = contact_frame(R_cg, d_cg, off[tag], tag, x[k], p["R_ru"] + radius_law(x[3 + k], p["w"]))
        if (d_cg + R_cg @ off[tag] - d3) @ terrain.normal(d3[0], d3[1]) <= 0:
            raise ConstraintError(f"wheel {tag}: the solution found touches the surface with the top of the rim "
                                  f"(beta = {np.degrees(x[k]):.1f} deg); expected a wheel standing on the surface")
    return x, err, int(sol.nfev)


def euler_zyx(R: np.ndarray) -> tuple[float, float, float]:
    """(yaw, pitch, roll) [rad] with :math:`R = R_z(yaw) R_y(pitch) R_x(roll)` (the floating root's convention)."""
    return float(np.arctan2(R[1, 0], R[0, 0])) + 0.0, float(np.arcsin(-np.clip(R[2, 0], -1, 1))) + 0.0, float(
        np.arctan2(R[2, 1], R[2, 2]))


def model_configuration(robot: Robot, cmd: Commands, x: np.ndarray, spins: np.ndarray | None = None) -> np.ndarray:
    """The model's natural coordinates for commands ``cmd`` and an IK solution ``x`` (eq 16).

    The body pose comes from eqs 4-6 (converted to the root's Z-Y-X Euler angles), q_i from x and the radius
    coordinates from the coupling law (eq 1). Wheel spin angles are ``spins`` (default 0; they do not change the
    contact geometry of a round wheel).
    """
    R, d = body_pose(cmd, robot.terrain)
    q = robot.neutral()
    for label, value in zip(("x", "y", "z"), d):
        q[robot.coordinate_index(label)] = value
    for label, value in zip(("yaw", "pitch", "roll"), euler_zyx(R)):
        q[robot.coordinate_index(label)] = value
    for k, tag in enumerate(WHEELS):
        q[robot.coordinate_index(f"q_{tag}")] = x[3 + k]
        q[robot.coordinate_index(f"Rch_{tag}")] = radius_law(x[3 + k], robot.params["w"])
        q[robot.coordinate_index(f"theta_{tag}")] = 0.0 if spins is None else spins[k]
    return q


# ------------------------------------------------------------------------------------------- missions (sec 7)
@dataclass
class Mission:
    """A kinematic mission of section 7: a path (x_d, y_d)(t) with its velocity, h_CG and body angles.

    Attributes:
        name, description: Identification.
        terrain: ``"rough"`` or ``"ramp"`` (the parameter values of :data:`SPEC` give the surface).
        path: t -> (x_d, y_d, dx_d/dt, dy_d/dt) [m, m/s].
        h: h_CG [m].
        qx, qy: t -> q_xd, q_yd [rad] (body roll/pitch commands of eq 4).
        t_end, dt: Simulation times (Table 1: 0-5 s, 0.01 s).
    """

    name: str
    description: str
    terrain: str
    path: Callable[[float], tuple[float, float, float, float]]
    h: float = 0.15
    qx: Callable[[float], float] = lambda t: 0.0
    qy: Callable[[float], float] = lambda t: 0.0
    t_end: float = 5.0
    dt: float = 0.01


MISSIONS = {
    "mission1": Mission(
        "mission1", "sec 7 / Table 1: circle x_d = sin t, y_d = cos t on Z = sin(0.5(x+y))/15, h_CG = 0.15 m, "
        "body level, 0-5 s step 0.01 s", "rough", lambda t: (np.sin(t), np.cos(t), np.cos(t), -np.sin(t))),
    "mission2": Mission(
        "mission2", "sec 7: body kept level on a ramp of slope 0.2 (rising towards -y), straight path along +x at "
        "0.2 m/s (path and heading not printed: our choice), h_CG = 0.15 m, 0-5 s step 0.01 s", "ramp",
        lambda t: (0.2 * t, 0.0, 0.2, 0.0)),
}


@dataclass
class IKRun:
    """Inverse kinematics along a mission (one row per time step).

    Attributes:
        t: Times [s]. beta, q: (N, 3) eq 16's unknowns per wheel (fr, fl, r) [rad]. RT: (N, 3) radii [m].
        error: (N,) ||C|| (eq 24). yaw: (N,) q_zd [rad]. cg: (N, 3) CG position [m].
        contacts: (N, 3, 3) contact points [m]. nfev: (N,) residual evaluations of the root finder.
    """

    mission: Mission
    t: np.ndarray
    beta: np.ndarray
    q: np.ndarray
    RT: np.ndarray
    error: np.ndarray
    yaw: np.ndarray
    cg: np.ndarray
    contacts: np.ndarray
    nfev: np.ndarray
    commands: list = field(default_factory=list)


def yaw_update(qz: float, path_angle_change: float, R_cg: np.ndarray, dqx: float, dqy: float) -> float:
    """Eqs 18-23 over one step: :math:`\\Delta q_{zd} = (\\Delta q_{path} - R_{CG}^0(3,1{:}2)[\\Delta q_{xd},
    \\Delta q_{yd}]) / R_{CG}^0(3,3)` (eq 22 times dt; q_path is the path tangent's direction, eq 18)."""
    return qz + (path_angle_change - R_cg[2, :2] @ np.array([dqx, dqy])) / R_cg[2, 2]


def run_mission(mission: Mission | str, params: dict | None = None, tol: float = IK_TOL) -> IKRun:
    """Inverse kinematics at every step of a mission (the flowchart of Fig. 8).

    Each step solves eq 15 by :func:`solve_ik` from the previous step's solution and updates q_zd by eqs 18-23.

    Raises:
        MechanismRangeError, ConstraintError: as :func:`solve_ik`, with the time of the failing step.
    """
    if isinstance(mission, str):
        if mission not in MISSIONS:
            raise InputError(f"unknown mission {mission!r}; expected one of {', '.join(MISSIONS)}")
        mission = MISSIONS[mission]
    p = {q.name: q.convert(q.default) for q in SPEC.parameters}
    for name, value in (params or {}).items():
        p[name] = SPEC.parameter(name).convert(value)
    p["terrain"] = mission.terrain
    terrain = _terrain(p)
    t = np.arange(0.0, mission.t_end + 0.5 * mission.dt, mission.dt)
    n = len(t)
    out = IKRun(mission, t, np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n), np.zeros(n),
                np.zeros((n, 3)), np.zeros((n, 3, 3)), np.zeros(n, int))
    x_prev = None
    x0, y0, vx, vy = mission.path(t[0])
    path_angle = np.arctan2(vy, vx)
    qz = path_angle
    off = offsets(p)
    for i, ti in enumerate(t):
        xd, yd, vx, vy = mission.path(ti)
        new_angle = np.arctan2(vy, vx)
        if i > 0:
            change = (new_angle - path_angle + np.pi) % (2 * np.pi) - np.pi
            qx_prev, qy_prev = mission.qx(t[i - 1]), mission.qy(t[i - 1])
            R_prev, _ = body_pose(Commands(xd, yd, mission.h, qx_prev, qy_prev, qz), terrain)
            qz = yaw_update(qz, change, R_prev, mission.qx(ti) - qx_prev, mission.qy(ti) - qy_prev)
        path_angle = new_angle
        cmd = Commands(xd, yd, mission.h, mission.qx(ti), mission.qy(ti), qz)
        try:
            x, err, nfev = solve_ik(cmd, p, terrain, x_prev, tol)
        except RobotDynError as exc:
            raise type(exc)(f"{mission.name}, t = {ti:.2f} s: {exc}") from None
        x_prev = x
        R, d = body_pose(cmd, terrain)
        out.beta[i], out.q[i], out.error[i], out.nfev[i], out.yaw[i], out.cg[i] = x[:3], x[3:], err, nfev, qz, d
        out.RT[i] = p["R_ru"] + radius_law(x[3:], p["w"])
        for k, tag in enumerate(WHEELS):
            out.contacts[i, k] = contact_frame(R, d, off[tag], tag, x[k], out.RT[i, k])[1]
        out.commands.append(cmd)
    return out


# ------------------------------------------------------------------------------------------ statics (sec 5)
def paper_torque_eq35(q, p: dict):
    """Eq 35 as printed: :math:`t_i = -0.5\\,m g w \\sin(q_i/2)\\cos(\\pi/6) / 3` [N m] (flat-ground worst case)."""
    return -0.5 * p["m"] * p["g"] * p["w"] * np.sin(0.5 * np.asarray(q)) * COS30 / 3.0


@dataclass
class StaticResult:
    """Statics of one configuration by eqs 25-34.

    Attributes:
        torque: (3,) adjustment-motor torques t_i of eq 34 [N m] (fr, fl, r; the model's sign: q_i positive
            shrinks the wheel, so holding the weight needs t_i < 0 like eq 35).
        forces: (3, 3) contact forces on the robot, world frame [N] (eq 25).
        along_u: (3,) :math:`F_i^{3i}(2)`, read as the component along the contact-to-centre line [N].
        normal, friction, ratio: eq 27-30 quantities per wheel [N, N, -].
        contacts, normals: (3, 3) contact points [m] and unit normals.
        equilibrium: Residual of eq 25.
        method: How the forces were found (``kkt`` closed form or ``slsqp``).
    """

    torque: np.ndarray
    forces: np.ndarray
    along_u: np.ndarray
    normal: np.ndarray
    friction: np.ndarray
    ratio: np.ndarray
    contacts: np.ndarray
    normals: np.ndarray
    equilibrium: float
    method: str


def static_torques(cmd: Commands, x: np.ndarray, p: dict, terrain: Terrain,
                   extra_force=None, extra_moment=None, objective: str = "friction") -> StaticResult:
    """Eqs 25-34 at an IK solution: contact forces by constrained optimisation, then virtual work.

    The contacts must carry the weight m g acting at the CG (eq 25, read with the forces acting on the robot:
    :math:`\\sum F_i = (0, 0, mg)`, :math:`\\sum V_{CG}^i \\times F_i = 0`), plus an optional extra wrench about
    the CG (kinetostatics: minus the inertial forces). The free components are fixed by minimising the friction
    forces subject to :math:`F_i\\cdot n_i \\ge 0` (eq 28) and :math:`|F_t| \\le \\mu F_n` (eq 30); then
    eq 31 and eq 34, :math:`t_i = -0.5 F_i^{3i}(2)\\, w \\sin(q_i/2)\\cos(\\pi/6)`.
    """
    R_cg, d_cg = body_pose(cmd, terrain)
    off = offsets(p)
    pts, nrm, us = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    for k, tag in enumerate(WHEELS):
        RT = p["R_ru"] + radius_law(x[3 + k], p["w"])
        R3, d3 = contact_frame(R_cg, d_cg, off[tag], tag, x[k], RT)
        pts[k], nrm[k] = d3, terrain.normal(d3[0], d3[1])
        us[k] = -_SIGN[tag] * R3[:, 1]  # eq 11: the centre is at -/+ R_T Y_3 from the contact point
    force = np.array([0.0, 0.0, p["m"] * p["g"]])
    moment = np.zeros(3)
    if extra_force is not None:
        force = force + np.asarray(extra_force, float)
    if extra_moment is not None:
        moment = moment + np.asarray(extra_moment, float)
    cf = solve_contact_forces(pts, nrm, force, moment, d_cg, p["mu"], objective)
    along = np.einsum("ij,ij->i", cf.forces, us)  # eq 31, second component (contact -> centre)
    torque = along * radius_law_d(x[3:], p["w"])  # eq 34 (= eq 32 with eq 33)
    return StaticResult(torque, cf.forces, along, cf.normal, cf.friction, cf.ratio, pts, nrm, cf.equilibrium,
                        cf.method)


def model_static_check(robot: Robot, cmd: Commands, x: np.ndarray, res: StaticResult) -> dict:
    """Check eqs 25-34 against the Pinocchio model at the same configuration (independent of eq 34).

    1. Generalised equilibrium of the whole model: :math:`g(q) = B\\tau + \\sum_i A_{w,i}^T F_i +
       A_{eq1}^T\\mu` solved for the six motor torques and the three coupling forces, with :math:`A_{w,i}` the
       world rows of wheel i's rolling contact (its material contact point's velocity, radius rate included).
       The residual tests the contact forces against the model's gravity; the adjustment torques must equal
       eq 34's.
    2. Virtual work by finite differences: :math:`t_i = -F_i\\cdot\\partial p_i/\\partial q_i`, where
       :math:`p_i(q_i)` is the material rim point at the contact (wheel-fixed direction), computed from the
       model's kinematics with the radius coordinate set by the coupling, at :math:`q_i \\pm \\varepsilon`.

    Returns:
        dict with ``tau`` (6, model order of motors), ``residual``, ``tau_fd`` (3,).
    """
    if robot.params["lateral"] != "rolling":
        raise InputError("model_static_check needs the rolling wheels (lateral=rolling)")
    q = model_configuration(robot, cmd, x)
    nv = robot.nq
    kin = KinematicState(robot.model, robot.data, q, np.zeros(nv))
    g = pin.computeGeneralizedGravity(robot.model, robot.data, q)
    load = np.zeros(nv)
    couplings, wheels = [], {}
    for c in robot.constraints:
        if isinstance(c, JointCoupling):
            couplings.append(c.rows(kin).A[0])
        else:
            geo = c.contact(kin)
            rows = c.rows(kin)
            Aw = geo["E"] @ rows.A  # world rows (E orthonormal: rows = E^T A_w)
            wheels[c.name] = (geo, Aw)
    for k, tag in enumerate(WHEELS):
        load += wheels[tag][1].T @ res.forces[k]
    B = input_matrix(robot.motors, kin)
    K = np.column_stack([B, np.array(couplings).T])
    sol, *_ = np.linalg.lstsq(K, g - load, rcond=None)
    residual = float(np.linalg.norm(K @ sol - (g - load)))
    tau = sol[: B.shape[1]]
    # virtual work by finite differences on the model's kinematics
    eps = 1e-6
    tau_fd = np.zeros(3)
    coupling = {c.driver: c for c in robot.constraints if isinstance(c, JointCoupling)}
    for k, tag in enumerate(WHEELS):
        geo = wheels[tag][0]
        u = geo["u"]
        c_join = coupling[f"adjust_{tag}_joint"]
        frame = robot.model.getFrameId(f"wheel_{tag}")

        def rim_point(dq):
            qq = q.copy()
            qq[robot.coordinate_index(f"q_{tag}")] += dq
            qq = c_join.solve_driven(qq)
            pin.forwardKinematics(robot.model, robot.data, qq)
            centre = pin.updateFramePlacement(robot.model, robot.data, frame).translation
            return centre - (robot.params["R_ru"] + qq[robot.coordinate_index(f"Rch_{tag}")]) * u

        tau_fd[k] = -res.forces[k] @ (rim_point(eps) - rim_point(-eps)) / (2 * eps)
    names = [m.name for m in robot.motors]
    return {"tau": dict(zip(names, tau)), "residual": residual, "tau_fd": tau_fd,
            "tau_adjust": np.array([tau[names.index(f"adjust_{t}")] for t in WHEELS])}


# ------------------------------------------------------------------------------- dynamics (beyond the paper)
_BODY = ("x", "y", "z", "yaw", "pitch", "roll")


def _commands_at(run: IKRun, t: float) -> Commands:
    """The commands at any time t in the run's interval, q_zd continued from the nearest step (eqs 18-23 with a
    body of constant roll/pitch command: the yaw changes exactly as the path angle)."""
    m = run.mission
    i = int(np.clip(round(t / m.dt), 0, len(run.t) - 1))
    xd, yd, vx, vy = m.path(t)
    _, _, vx0, vy0 = m.path(run.t[i])
    change = (np.arctan2(vy, vx) - np.arctan2(vy0, vx0) + np.pi) % (2 * np.pi) - np.pi
    return Commands(xd, yd, m.h, m.qx(t), m.qy(t), run.yaw[i] + change)


def body_coordinates(run: IKRun, t: float, terrain: Terrain) -> np.ndarray:
    """(x, y, z, yaw, pitch, roll) of the body at time t from the commands (eqs 4-6)."""
    R, d = body_pose(_commands_at(run, t), terrain)
    return np.concatenate([d, euler_zyx(R)])


@dataclass
class DynamicsRun:
    """Adjustment and wheel torques along a mission from the full model (kinetostatics with Pinocchio's RNEA).

    Attributes:
        t: (N,) times [s].
        tau_dynamic: (N, 6) motor torques with inertia (spin fr, fl, r, adjust fr, fl, r) [N m].
        tau_static: (N, 3) adjustment torques of eqs 25-34 at the same configurations (no inertia) [N m].
        tau_eq35: (N, 3) eq 35 [N m].
        normal_dynamic: (N, 3) normal contact forces with inertia [N].
        ratio_dynamic: (N, 3) friction use with inertia.
        lateral_slip: (N, 3) lateral sliding speed of each wheel's material contact point [m/s] (what rolling
            without slipping would forbid).
        qdot_model, qdot_fd: (N, 3) adjustment rates from the constraint layer (S nu) and from finite
            differences of the IK in time [rad/s].
        residual: (N,) residual of the model's generalised force balance [N, N m].
    """

    t: np.ndarray
    tau_dynamic: np.ndarray
    tau_static: np.ndarray
    tau_eq35: np.ndarray
    normal_dynamic: np.ndarray
    ratio_dynamic: np.ndarray
    lateral_slip: np.ndarray
    qdot_model: np.ndarray
    qdot_fd: np.ndarray
    residual: np.ndarray


def _derivatives(f: Callable[[float], np.ndarray], t: float, h: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """First and second derivatives by five-point central differences (truncation O(h^4))."""
    f2, f1, f0, g1, g2 = (f(t + k * h) for k in (-2, -1, 0, 1, 2))
    d1 = (f2 - 8 * f1 + 8 * g1 - g2) / (12 * h)
    d2 = (-f2 + 16 * f1 - 30 * f0 + 16 * g1 - g2) / (12 * h * h)
    return d1, d2


class MissionModel:
    """The full model along a kinematic mission: states from the IK and the constraint layer, torques from RNEA.

    The body follows the commanded pose (eqs 4-6, 18-23); the constraint layer (rolling rows without the lateral
    one, and the eq-1 couplings) gives the full velocity v = S(q) nu and acceleration a = S nu' + w for the body
    velocities nu (five-point differences of the commanded pose); Pinocchio's RNEA gives the generalised forces
    :math:`\\tau_{RNEA}(q, v, a)`. Its six root rows are the wrench the contacts must supply (weight plus inertial
    forces: eq 25 with inertia); the contact forces are chosen as in eqs 28-30
    (:func:`robotdyn.contact.statics.solve_contact_forces`); the remaining rows give the six motor torques and the three
    coupling forces by least squares (residual reported).

    Args:
        run: An :class:`IKRun` (its mission fixes the terrain).
        params: Parameter overrides (e.g. ``m_wheel``, ``I_adjust``).
    """

    def __init__(self, run: IKRun, params: dict | None = None) -> None:
        p = {**(params or {}), "terrain": run.mission.terrain}
        self.run = run
        self.rolling = Robot(SPEC, {**p, "lateral": "rolling"})
        self.slip = Robot(SPEC, {**p, "lateral": "slip"})
        self.p = self.slip.params
        self.body = np.array([self.slip.coordinate_index(c) for c in _BODY])
        self.adjust = np.array([self.slip.coordinate_index(f"q_{t}") for t in WHEELS])
        names = [m.name for m in self.rolling.motors]
        self.order = [names.index(f"spin_{t}") for t in WHEELS] + [names.index(f"adjust_{t}") for t in WHEELS]
        kin = KinematicState(self.rolling.model, self.rolling.data, self.rolling.neutral(), np.zeros(self.rolling.nq))
        labels = self.rolling.constraint_rows(kin).labels
        self.lateral_rows = [i for i, c in enumerate(labels) if c.endswith(".lateral")]

    def ik_at(self, t: float, guess=None) -> tuple[Commands, np.ndarray]:
        """Commands and IK solution at any time t of the run."""
        cmd = _commands_at(self.run, t)
        if guess is None:
            i = int(np.clip(round(t / self.run.mission.dt), 0, len(self.run.t) - 1))
            guess = np.concatenate([self.run.beta[i], self.run.q[i]])
        return cmd, solve_ik(cmd, self.p, self.slip.terrain, guess)[0]

    def state(self, t: float) -> tuple[Commands, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(commands, IK solution, q, v, a) at time t (natural coordinates of the model)."""
        from ..fast.dispatch import reduce

        cmd, x = self.ik_at(t)
        q = model_configuration(self.slip, cmd, x)
        nu, nudot = _derivatives(lambda s: body_coordinates(self.run, s, self.slip.terrain), t)
        red = reduce(self.slip, q, nu, independent=self.body)
        return cmd, x, q, red.v, red.S @ nudot + red.w

    def at(self, t: float) -> dict:
        """Torques, contact forces and checks at time t (see :class:`DynamicsRun` for the meaning)."""
        rolling, pr = self.rolling, self.p
        cmd, x, q, v, a = self.state(t)
        tau_rnea = pin.rnea(rolling.model, rolling.data, q, v, a)
        kin = KinematicState(rolling.model, rolling.data, q, v)
        Eul = kin.frame(rolling.description.frame_id("body"))[1][3:][:, self.body[3:]]
        force = tau_rnea[self.body[:3]]
        moment = np.linalg.solve(Eul.T, tau_rnea[self.body[3:]])
        res = static_torques(cmd, x, pr, self.slip.terrain, extra_force=force - [0, 0, pr["m"] * pr["g"]],
                             extra_moment=moment)
        load = np.zeros(rolling.nq)
        couplings = []
        contact_power = 0.0
        k = 0
        for c in rolling.constraints:
            if isinstance(c, JointCoupling):
                couplings.append(c.rows(kin).A[0])
            else:
                Aw = c.contact(kin)["E"] @ c.rows(kin).A
                load += Aw.T @ res.forces[k]
                contact_power += res.forces[k] @ (Aw @ v)
                k += 1
        B = input_matrix(rolling.motors, kin)
        K = np.column_stack([B, np.array(couplings).T])
        sol, *_ = np.linalg.lstsq(K, tau_rnea - load, rcond=None)
        tau = sol[: B.shape[1]]
        rows = rolling.constraint_rows(kin)
        return {
            "q": q, "v": v, "a": a, "x": x, "tau": tau[self.order], "forces": res.forces, "normal": res.normal,
            "ratio": res.ratio, "residual": float(np.linalg.norm(K @ sol - (tau_rnea - load))),
            "lateral_slip": np.abs(rows.A[self.lateral_rows] @ v), "motor_power": float(tau @ (B.T @ v)),
            "contact_power": float(contact_power), "energy": rolling.energy(q, v),
            "tau_static": static_torques(cmd, x, pr, self.slip.terrain).torque,
            "tau_eq35": paper_torque_eq35(x[3:], pr),
        }


def mission_dynamics(run: IKRun, params: dict | None = None, every: int = 1) -> DynamicsRun:
    """Motor torques along a kinematic mission from the full model, with inertia (see :class:`MissionModel`).

    Args:
        run: An :class:`IKRun`.
        params: Parameter overrides (e.g. ``m_wheel``, ``I_adjust``).
        every: Use every n-th step of the run.
    """
    mm = MissionModel(run, params)
    idx = np.arange(0, len(run.t), every)
    n = len(idx)
    out = DynamicsRun(run.t[idx], np.zeros((n, 6)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
                      np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n))
    for row, i in enumerate(idx):
        t = run.t[i]
        r = mm.at(t)
        out.tau_dynamic[row], out.tau_static[row], out.tau_eq35[row] = r["tau"], r["tau_static"], r["tau_eq35"]
        out.normal_dynamic[row], out.ratio_dynamic[row] = r["normal"], r["ratio"]
        out.lateral_slip[row], out.residual[row] = r["lateral_slip"], r["residual"]
        out.qdot_model[row] = r["v"][mm.adjust]
        out.qdot_fd[row] = _derivatives(lambda s: mm.ik_at(s, r["x"])[1][3:], t)[0]
    return out



@dataclass
class FrictionRun:
    """Mission kinematics with a real lateral friction law (:func:`mission_friction`).

    The wheels roll along their rolling direction and slide sideways under the law of ``lateral`` (Coulomb with the
    robot's mu, Table 1: 1.0), so each lateral force is :math:`-\\mu f_n` times the slip direction: known once the
    normal loads are. Torques, normal loads and traction then follow from one square linear system per state
    (:func:`robotdyn.contact.sliding.inverse`).

    Attributes:
        t: (N,) times [s].
        tau: (N, 6) motor torques (spin fr, fl, r, adjust fr, fl, r) [N m].
        normal: (N, 3) normal loads [N].
        longitudinal: (N, 3) traction (the rolling rows' forces) [N].
        lateral: (N, 3) lateral friction forces from the law [N].
        slip: (N, 3) lateral slip velocities [m/s].
        required_mu: (N, 3) :math:`\\|(f_{t1}, f_{t2})\\| / f_n` (inf where :math:`f_n \\le 0`).
        residual: (N,) least-squares residual [N, N m] (> 0: no torques and contact forces realise the motion).
        rank: (N,) rank of the system (15 when regular).
        power: (N, 2) motor power and friction power [W] (their sum is dE/dt).
        energy: (N,) the robot's total energy [J].
    """

    t: np.ndarray
    tau: np.ndarray
    normal: np.ndarray
    longitudinal: np.ndarray
    lateral: np.ndarray
    slip: np.ndarray
    required_mu: np.ndarray
    residual: np.ndarray
    rank: np.ndarray
    power: np.ndarray
    energy: np.ndarray


def mission_friction(run: IKRun, lateral: str = "coulomb", params: dict | None = None, every: int = 1) -> FrictionRun:
    """Torques and contact forces along a kinematic mission with wheels that slide sideways under a friction law.

    Args:
        run: An :class:`IKRun` (its mission fixes the terrain).
        lateral: ``coulomb`` or ``linear`` (the ``lateral`` parameter of :data:`SPEC`).
        params: Parameter overrides (e.g. ``mu``).
        every: Use every n-th step of the run.
    """
    from ..contact.sliding import inverse

    if lateral not in ("coulomb", "linear"):
        raise InputError(f"lateral = {lateral!r}; expected a friction law: coulomb or linear")
    mm = MissionModel(run, params)
    robot = Robot(SPEC, {**(params or {}), "terrain": run.mission.terrain, "lateral": lateral})
    idx = np.arange(0, len(run.t), every)
    n = len(idx)
    out = FrictionRun(run.t[idx], *(np.zeros((n, k)) for k in (6, 3, 3, 3, 3, 3)), np.zeros(n), np.zeros(n, int),
                      np.zeros((n, 2)), np.zeros(n))
    for row, i in enumerate(idx):
        _, _, q, v, a = mm.state(run.t[i])
        inv = inverse(robot, q, v, a)
        kin = KinematicState(robot.model, robot.data, q, v)
        out.tau[row] = inv.tau[mm.order]
        out.normal[row], out.lateral[row], out.slip[row] = inv.normal, inv.force[:, 1], inv.slip[:, 1]
        out.longitudinal[row] = [inv.multipliers[f"{t}.longitudinal"] for t in WHEELS]
        with np.errstate(divide="ignore", invalid="ignore"):
            out.required_mu[row] = np.where(inv.normal > 0, np.hypot(out.longitudinal[row], out.lateral[row])
                                            / inv.normal, np.inf)
        out.residual[row], out.rank[row] = inv.residual, inv.rank
        out.power[row] = inv.tau @ (input_matrix(robot.motors, kin).T @ v), float(np.sum(inv.force * inv.slip))
        out.energy[row] = robot.energy(q, v)
    return out

# ------------------------------------------------------------------------------------------------ scenarios
class HoldScenario(Scenario):
    """The robot at rest at the path origin (IK of h_CG = 0.15 m, body level) with constant motor torques that
    balance gravity in the reduced model (least squares of :math:`B_r\\tau = g_r`): it must stay at rest."""

    def initial_state(self, robot: Robot) -> tuple[np.ndarray, np.ndarray]:
        cmd = Commands(0.0, 0.0, 0.15)
        x, _, _ = solve_ik(cmd, robot.params, robot.terrain)
        q0 = model_configuration(robot, cmd, x)
        red = robot.reduced(q0, np.zeros(robot.mobility))
        tau, *_ = np.linalg.lstsq(red.B, red.g, rcond=None)
        self.holding = tau
        self.torque = Constant(tau)  # torques as data: simulated by the compiled engine
        return q0, np.zeros(robot.mobility)


SCENARIOS = {
    "hold": HoldScenario(
        "hold", "at rest on the terrain (h_CG = 0.15 m, body level) with the static holding torques; stays at rest "
        "(statics through the forward dynamics)", 1.0, n_out=101),
}


# ------------------------------------------------------------------------------------------------ comparison
TABLE2 = {"r": (3.9, 115.0), "fl": (1.7, 55.0), "fr": (3.4, 160.0)}
"""Table 2 (mission 2): torque [N m] and angle [deg] of each adjustment motor."""


def compare(robot: Robot | None = None, runs: dict | None = None) -> Comparison:
    """The paper's printed numbers (section 7, Table 2) against the transcribed IK/statics and the model.

    Tolerances: angles read off the figures or printed to 5 deg: 2.5 deg; torques printed to 0.1 N m: 0.05 N m;
    the "4" N m of section 7: 0.5; convergence: the paper's criterion 1e-5.
    """
    robot = robot or Robot(SPEC)
    params = {k: v for k, v in robot.params.items() if k != "terrain"}
    runs = runs or {name: run_mission(name, params) for name in MISSIONS}
    m1, m2 = runs["mission1"], runs["mission2"]
    reading = params["L_reading"]
    cmp = Comparison(f"Mardani & Ebrahimi 2016 vs robotdyn (L_reading={reading}: offsets {offsets(params)['fr'][:2]})")
    worst = max(m1.error.max(), m2.error.max())
    cmp.add("eq 24: max ||C|| over missions 1-2 (criterion 1e-5)", 1e-5, worst, 1e-5,
            note="our criterion is 1e-10; the paper's 1e-5 is met")
    qd = np.degrees(m1.q)
    cmp.add("Fig. 11 / sec 7: min adjustment angle, mission 1 [deg]", 20.0, qd.min(), 2.5)
    cmp.add("Fig. 11 / sec 7: max adjustment angle, mission 1 [deg]", 170.0, qd.max(), 2.5)
    cmp.add("sec 8: min adjustment angle (40-170 deg) [deg]", 40.0, qd.min(), 2.5)
    t35 = np.abs(paper_torque_eq35(m1.q, params))
    cmp.add("sec 7: min torque, mission 1, eq 35 [N m]", 1.4, t35.min(), 0.05)
    cmp.add("sec 7: max torque, mission 1, eq 35 [N m]", 4.0, t35.max(), 0.5)
    full = np.array([np.abs(static_torques(m1.commands[i], np.concatenate([m1.beta[i], m1.q[i]]), params,
                                           _terrain({**params, "terrain": "rough"})).torque)
                     for i in range(0, len(m1.t), 5)])
    cmp.add("sec 7: min torque, mission 1, eqs 25-34 [N m]", 1.4, full.min(), 0.05)
    cmp.add("sec 7: max torque, mission 1, eqs 25-34 [N m]", 4.0, full.max(), 0.5)
    ramp = _terrain({**params, "terrain": "ramp"})
    x2 = np.concatenate([m2.beta[0], m2.q[0]])
    st2 = static_torques(m2.commands[0], x2, params, ramp)
    for k, tag in enumerate(WHEELS):
        torque, angle = TABLE2[tag]
        cmp.add(f"Table 2: angle {tag} [deg]", angle, np.degrees(m2.q[0, k]), 2.5)
        cmp.add(f"Table 2: torque {tag}, eq 35 at our angle [N m]", torque,
                abs(paper_torque_eq35(m2.q[0, k], params)), 0.05)
        cmp.add(f"Table 2: torque {tag}, eqs 25-34 at our angle [N m]", torque, abs(st2.torque[k]), 0.05)
        cmp.add(f"Table 2: torque {tag}, eq 35 at Table 2's angle [N m]", torque,
                abs(paper_torque_eq35(np.radians(angle), params)), 0.05,
                note="internal consistency of Table 2 with eq 35")
    return cmp


# ------------------------------------------------------------------------------------------------------ CLI
def cmd_ik(args) -> int:
    """``robotdyn ik adaptable_wheel --commands x_d y_d h_CG q_xd q_yd q_zd``: eqs 4-24 and the static torques."""
    import json

    from ..cli.commands import _jsonable
    from ..inputs import as_vector, parse_assignments

    if args.robot != SPEC.name:
        raise InputError(f"ik is implemented for {SPEC.name} only, not {args.robot!r}")
    robot = Robot(SPEC, parse_assignments(args.param))
    p = robot.params
    if args.mission:
        run = run_mission(args.mission, {k: v for k, v in p.items() if k != "terrain"})
        data = {"mission": run.mission.name, "description": run.mission.description, "steps": len(run.t),
                "max_error": float(run.error.max()), "q_min_deg": np.degrees(run.q.min(0)),
                "q_max_deg": np.degrees(run.q.max(0))}
        if args.csv:
            cols = np.column_stack([run.t, run.cg, run.yaw, run.beta, run.q, run.RT, run.error])
            header = "t,x_cg,y_cg,z_cg,q_zd," + ",".join(
                [f"beta_{t}" for t in WHEELS] + [f"q_{t}" for t in WHEELS] + [f"RT_{t}" for t in WHEELS]) + ",error"
            np.savetxt(args.csv, cols, delimiter=",", header=header, comments="")
            data["csv"] = args.csv
        text = [f"{run.mission.name}: {run.mission.description}",
                f"{len(run.t)} steps, max ||C|| = {run.error.max():.3g}",
                *(f"  q_{t}: {np.degrees(run.q[:, k].min()):.3f} .. {np.degrees(run.q[:, k].max()):.3f} deg"
                  for k, t in enumerate(WHEELS))]
        if args.csv:
            text.append(f"wrote {args.csv}")
    else:
        if args.commands is None:
            raise InputError("ik needs --commands x_d y_d h_CG q_xd q_yd q_zd (m, m, m, rad, rad, rad) or --mission")
        c = as_vector(args.commands, 6, "commands", ["x_d", "y_d", "h_CG", "q_xd", "q_yd", "q_zd"])
        if c[2] <= 0:
            raise InputError(f"commands[h_CG] = {c[2]:g} m; expected a positive height above the surface")
        cmd = Commands(c[0], c[1], c[2], c[3], c[4], c[5])
        x, err, nfev = solve_ik(cmd, p, robot.terrain)
        res = static_torques(cmd, x, p, robot.terrain)
        q = model_configuration(robot, cmd, x)
        data = {"beta": dict(zip(WHEELS, x[:3])), "q_deg": dict(zip(WHEELS, np.degrees(x[3:]))),
                "q": dict(zip(WHEELS, x[3:])), "R_T": dict(zip(WHEELS, p["R_ru"] + radius_law(x[3:], p["w"]))),
                "error": err, "evaluations": nfev, "torque_eq35": dict(zip(WHEELS, paper_torque_eq35(x[3:], p))),
                "torque_eq34": dict(zip(WHEELS, res.torque)), "contact_forces": res.forces,
                "model_q": dict(zip(robot.coordinates, q))}
        text = [f"inverse kinematics (eqs 4-24) on {robot.terrain!r}: ||C|| = {err:.3g} ({nfev} evaluations)",
                f"{'wheel':>6} {'beta [deg]':>11} {'q [deg]':>9} {'R_T [m]':>9} {'t eq35':>9} {'t eq34':>9}"
                f" {'F_n [N]':>9}"]
        for k, t in enumerate(WHEELS):
            text.append(f"{t:>6} {np.degrees(x[k]):>11.5f} {np.degrees(x[3 + k]):>9.4f} "
                        f"{data['R_T'][t]:>9.5f} {data['torque_eq35'][t]:>9.4f} {res.torque[k]:>9.4f} "
                        f"{res.normal[k]:>9.4f}")
        text.append("model coordinates: " + " ".join(f"{v:.10g}" for v in q))
    if args.json:
        print(json.dumps(data, indent=2, default=_jsonable))
    else:
        print("\n".join(text))
    return 0


def register_cli(subparsers, parents) -> None:
    """Add ``robotdyn ik ROBOT --commands ...`` (or ``--mission NAME``)."""
    name = "ik" if "ik" not in subparsers.choices else "wheel-ik"
    p = subparsers.add_parser(name, parents=parents,
                              help="adaptable_wheel: inverse kinematics (eqs 4-24) and static torques")
    p.add_argument("--commands", nargs="+", help="x_d y_d h_CG q_xd q_yd q_zd [m, m, m, rad, rad, rad]")
    p.add_argument("--mission", choices=sorted(MISSIONS), help="run a whole mission of section 7 instead")
    p.add_argument("--csv", help="with --mission: write the solution at every step to this CSV file")
    p.set_defaults(func=cmd_ik)

"""MMR12-EOD: a differential-drive mobile manipulator with four lifting arms (Zuniga-Aviles et al., 2014).

Paper: L. A. Zuniga-Aviles, J. C. Pedraza-Ortega et al., "HTG-Based Kinematic Modeling for Positioning of a
Multi-Articulated Wheeled Mobile Manipulator", J. Intell. Robot. Syst. (2014)
(``shared/papers/zuniga_aviles_2014_mmr12_eod_htg.txt``). Description: ``urdf/mmr12_eod.urdf.xacro``, built from
Table 2's Denavit-Hartenberg rows (Paul's convention) so that every HTG frame of eq (2) is a named frame.

Coordinates (natural, m and rad): the planar root (x, y, psi) of the ground footprint under the platform frame C,
``lambda_C`` = the lift Delta lambda_C of eq (1) (vertical prismatic, 0 on the drive wheels), the drive-wheel
angles ``theta_R``, ``theta_L`` (right wheel at y = -b, forward rolling positive), the lifting-arm angles
``theta_C1..4`` (positive = tip down), the manipulator's ``theta1``, ``lambda2``, ``theta3``, ``theta4`` (Table 2;
theta1 is the DH angle, i.e. theta'_1 + 90 deg) and the load joints ``lambda6`` (E_muP) and ``theta_mu`` (E_muR).
Independent velocities: every actuated joint (wheels, arms, manipulator, load); (x, y, psi, lambda_C) are
dependent through the rolling constraints of Table 3 (eqs 12-14) and the wheels' ground contact.

This module holds the parameters (Table 2, section 3), the paper's closed forms transcribed separately from the
model (eqs 1-2, 3-11, 12-14, 26, printed transforms 27-31), the scenarios (Table 4 tracking, lifting, climbing)
and the comparison.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from ..interfaces.comparison import Comparison
from ..errors import InputError
from ..robot import MotorSpec, Parameter, Robot, RobotSpec, Wheel

_ARMS = (1, 2, 3, 4)
MANIPULATOR = ("theta1", "lambda2", "theta3", "theta4")
LOAD = ("lambda6", "theta_mu")
ACTUATED = ("theta_R", "theta_L", *(f"theta_C{i}" for i in _ARMS), *MANIPULATOR, *LOAD)

SPEC = RobotSpec(
    name="mmr12_eod",
    title="MMR12-EOD: differential-drive mobile manipulator, 4 lifting arms, RPRR arm (Zuniga-Aviles, HTG)",
    xacro="mmr12_eod.urdf.xacro",
    root="planar",
    paper="zuniga_aviles_2014_mmr12_eod_htg.txt",
    parameters=[
        Parameter("lambda_C0", 0.15, "m", "height of C over the ground = drive-wheel radius (sec 3, conclusion)"),
        Parameter("b", 0.4, "m", "half track: drive wheels at y = -b (right) and +b (left), eqs 13-14, eq 28"),
        Parameter("l_cs", 0.33, "m", "lifting-arm pivot offset from C along x, Table 2 row C1"),
        Parameter("d", 0.35, "m", "lifting-arm lateral offset, eq 31"),
        Parameter("l_cs1", 0.44, "m", "lifting-arm length, Table 2 row CS1"),
        Parameter("r", 0.08, "m", "lifting-arm tip-wheel radius, eq 26"),
        Parameter("lambda0", 0.16, "m", "Table 2 row 0"),
        Parameter("l0", 0.33, "m", "Table 2 row 0 (DH l_0 = -0.33)"),
        Parameter("l3", 0.15, "m", "Table 2 row 3"),
        Parameter("lambda5", 0.38, "m", "Table 2 row E"),
        Parameter("lambda2_max", 1.5, "m", "stroke of the prismatic joint 2 (eq 29 uses 1.4; assumed)"),
        Parameter("lambda6_max", 0.3, "m", "stroke of E_muP (Table 2: 0.05, eq 29: 0.25; assumed)"),
        Parameter("m_platform", 60.0, "kg", "platform mass (assumed; box 0.9 x 0.6 x 0.2 m)"),
        Parameter("m_wheel", 3.0, "kg", "drive-wheel mass (assumed)"),
        Parameter("m_arm", 2.0, "kg", "lifting-arm mass (assumed)"),
        Parameter("m_turret", 6.0, "kg", "link 1 mass (assumed)"),
        Parameter("m_boom", 5.0, "kg", "link 2 (telescopic boom) mass (assumed)"),
        Parameter("m_link3", 2.0, "kg", "link 3 mass (assumed)"),
        Parameter("m_link4", 1.5, "kg", "link 4 / gripper mass (assumed)"),
        Parameter("m_load", 10.0, "kg", "load at the end effector (sec 2.1: 10 kg)"),
        Parameter("g", 9.81, "m/s^2", "gravitational acceleration", xacro=False),
        Parameter("mu", 0.1, "-", "rolling-resistance coefficient of the climbing balance (assumed)", xacro=False),
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


# ------------------------------------------------------------------------------------ paper transcription
def dh(theta: float, lam: float, l: float, alpha: float) -> np.ndarray:
    """Paul's link transform A = Rot(z, theta) Trans(0, 0, lambda) Trans(l, 0, 0) Rot(x, alpha) (Table 2)."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, l * ct], [st, ct * ca, -ct * sa, l * st], [0.0, sa, ca, lam],
                     [0.0, 0.0, 0.0, 1.0]])


def _trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def paper_delta_lambda(p: dict, theta_C1: float, r: float | None = None) -> float:
    """Eqs (1)/(26): Delta lambda_C = l_CS1 sin(theta_C1) - lambda_C0 + r when >= 0, else 0 [m]."""
    r = p["r"] if r is None else r
    value = p["l_cs1"] * np.sin(theta_C1) - p["lambda_C0"] + r
    return float(value) if value >= 0 else 0.0


def paper_A_C(p: dict, x: float, y: float, phi: float, dlam: float) -> np.ndarray:
    """Sec 2.7.1 a): A_C = Trans(x_C0, y_C0, z_C0) Rot(z, phi) Trans(0, 0, Delta lambda_C), z_C0 = lambda_C0."""
    return _trans(x, y, p["lambda_C0"]) @ dh(phi, 0.0, 0.0, 0.0) @ _trans(0.0, 0.0, dlam)


def paper_htg_chain(p: dict, x, y, phi, dlam, theta1, lambda2, theta3, theta4, lambda6, theta_mu=0.0) -> np.ndarray:
    """The HTG product X_M = A_C A_0 A_1 A_2 A_3 A_4 E E_muP E_muR of sec 2.7.1 with Table 2's rows.

    Rows: 0 (alpha pi/2, l = -l0, lambda0, theta 0), 1 (alpha pi/2, theta1), 2 (alpha -pi/2, lambda2),
    3 (alpha pi/2, l3, theta3), 4 (theta4), E (lambda5), E_muP (lambda6), E_muR (alpha pi/2, theta_mu).
    """
    h = np.pi / 2
    chain = [dh(0.0, p["lambda0"], -p["l0"], h), dh(theta1, 0.0, 0.0, h), dh(0.0, lambda2, 0.0, -h),
             dh(theta3, 0.0, p["l3"], h), dh(theta4, 0.0, 0.0, 0.0), dh(0.0, p["lambda5"], 0.0, 0.0),
             dh(0.0, lambda6, 0.0, 0.0), dh(theta_mu, 0.0, 0.0, h)]
    T = paper_A_C(p, x, y, phi, dlam)
    for A in chain:
        T = T @ A
    return T


def paper_X_M(p: dict, x, y, phi, dlam, theta1, lambda2, theta3, theta4, lambda6) -> np.ndarray:
    """Eq (2) exactly as printed: X_M = GT_4 E E_mu (load frame in global coordinates)."""
    SC, CC = np.sin(phi), np.cos(phi)
    S1, C1 = np.sin(theta1), np.cos(theta1)
    S13, C13 = np.sin(theta1 + theta3), np.cos(theta1 + theta3)
    S4, C4 = np.sin(theta4), np.cos(theta4)
    l0, l3, lam0, lam5, lam6 = p["l0"], p["l3"], p["lambda0"], p["lambda5"], lambda6
    reach = S1 * lambda2 + l3 * C13 - l0
    return np.array([
        [S4 * SC + CC * C13 * C4, CC * S13, CC * C13 * S4 - C4 * SC, x + CC * reach + CC * lam5 * S13 + CC * lam6 * S13],
        [SC * C13 * C4 - CC * S4, SC * C13, SC * C13 * S4 + C4 * CC, y + SC * reach + SC * lam5 * S13 + SC * lam6 * S13],
        [S13 * C4, -C13, S13 * S4, p["lambda_C0"] + dlam + lam0 - lam5 * C13 - C1 * lambda2 + l3 * S13 - lam6 * C13],
        [0.0, 0.0, 0.0, 1.0],
    ])


def paper_platform_rates(p: dict, phi: float, thR_dot: float, thL_dot: float) -> np.ndarray:
    """Eqs (12)-(14) solved for (x', y', phi') given the wheel rates (r of eqs 13-14 = the drive-wheel radius)."""
    R, b = p["lambda_C0"], p["b"]
    phidot = R / (2 * b) * (thR_dot - thL_dot)  # eq 14
    v = thR_dot * R - phidot * b  # eq 13: x' cos + y' sin = theta_r' r - phi' b
    return np.array([v * np.cos(phi), v * np.sin(phi), phidot])  # eq 12: no lateral velocity


def paper_ik(p: dict, target, lambda2: float, theta1: float, theta3: float) -> dict[str, float]:
    """The evaluable inverse-kinematics equations (3), (4), (5), (10), (11).

    Args:
        p: Parameters.
        target: (d_x, d_y, d_z): the end-effector target; for eq 3 and eqs 10-11 in global coordinates, for eqs 4-5
            relative to the manipulator base (frame 0) as Fig. 8 suggests.
        lambda2, theta1, theta3: Arm values used on the right-hand sides.

    Returns:
        ``phi`` (eq 3), ``theta3`` (eq 4, NaN if the arccos argument leaves [-1, 1]), ``lambda2`` (eq 5),
        ``x_C`` (eq 10), ``y_C`` (eq 11). Eqs 6-9 use symbols (d_0, d_1, d_2, d_C, E1, P1) that the text never
        defines, so they are not transcribed.
    """
    dx, dy, dz = (float(t) for t in target)
    l0, l3, lam0, lam5 = p["l0"], p["l3"], p["lambda0"], p["lambda5"]
    c = (dx**2 + dy**2 + dz**2 - lambda2**2 - lam5**2) / (-2 * lambda2 * lam5)
    th3 = float(np.arccos(c)) if abs(c) <= 1 else float("nan")
    C3, S3 = np.cos(theta3), np.sin(theta3)
    lam2 = (dz + lam0 - lam5 * C3 + l3 * S3) / C3 if abs(C3) > 1e-12 else float("nan")
    phi = float(np.arctan2(dy, dx))
    S1, S13, C13 = np.sin(theta1), np.sin(theta1 + theta3), np.cos(theta1 + theta3)
    reach = lambda2 * S1 - l0 + l3 * C13 + lam5 * S13
    return {"phi": phi, "theta3": th3, "lambda2": float(lam2), "x_C": dx - np.cos(phi) * reach,
            "y_C": dy - np.sin(phi) * reach}


# printed numeric transforms, eqs (27)-(31), with the parameters printed beside each (sec 3)
PRINTED = {
    "eq 27": np.array([[1, 2.4493e-15, 0, 0], [-2.4493e-15, 1, 0, 0], [0, 0, 1, 0.15], [0, 0, 0, 1]]),
    "eq 28": np.array([[0.7071, -0.7071, 0, 2], [0.7071, 0.7071, 0, 2], [0, 0, 1, 0.15], [0, 0, 0, 1]]),
    "eq 29": np.array([[0.7071, 0.5, 0.5, 2.8567], [-0.7071, 0.5, 0.5, 2.8567], [0, -0.7071, -0.7071, 1.3305],
                       [0, 0, 0, 1]]),
    "eq 30": np.array([[0.7071, -0.7071, 0, 0], [0.7071, 0.7071, 0, 0], [0, 0, 1, 0.52], [0, 0, 0, 1]]),
    "eq 31": np.array([[0.7071, 0, -0.7071, 0], [0.7071, 0, 0.7071, 0], [0, -1, 0, 0.47], [0, 0, 0, 1]]),
}
"""The 4x4 matrices of eqs (27)-(31) as printed (4 decimals, except eq 27's 2.4493e-15)."""


# ------------------------------------------------------------------------------------------ model side
def state(robot: Robot, **values: float) -> np.ndarray:
    """Natural coordinates: the robot's neutral configuration with the given coordinates overridden."""
    q = robot.neutral()
    for label, value in values.items():
        q[robot.coordinate_index(label)] = value
    return q


def model_lift(robot: Robot, theta_C: float, arm: int = 1) -> float:
    """Delta lambda_C from the model: how far the platform must rise for arm ``arm``'s tip wheel (radius r) at
    angle theta_C to touch the ground, i.e. max(0, r - z_tip) with z_tip the tip-frame height at lambda_C = 0."""
    from ..description.kinematics import frame_pose

    q = state(robot, lambda_C=0.0, **{f"theta_C{arm}": theta_C})
    z_tip = frame_pose(robot, q, f"CS{arm}")[2, 3]
    return max(0.0, robot.params["r"] - z_tip)


def printed_states(p: dict) -> dict[str, tuple[dict, dict, str, str]]:
    """For each printed transform (eqs 27-31): parameter overrides, coordinate values, model frame, reading.

    The coordinate values are the ones printed beside each equation (sec 3); Delta lambda_C comes from eq 26.
    """
    h = np.pi / 2
    lift = paper_delta_lambda(p, h)  # eq 26 at theta_C1 = pi/2, r = 0.08: 0.37
    arms_down = {f"theta_C{i}": h for i in _ARMS}
    return {
        "eq 27": ({}, dict(x=0.0, y=0.0, psi=20 * np.pi, lambda_C=0.0), "C",
                  "platform turning about its axis: phi = 20 pi (10 turns), x = y = 0, no lift (the list's "
                  "x_C0 = y_C0 = 2 and theta_C1 = pi/2 are not what the matrix shows)"),
        "eq 28": ({}, dict(x=2.0, y=2.0, psi=np.pi / 4, lambda_C=0.0), "C", "x_C = y_C = 2, phi = pi/4, no lift"),
        "eq 29": ({}, dict(x=2.0, y=2.0, psi=np.pi / 4, lambda_C=lift, theta1=3 * np.pi / 4, lambda2=1.4,
                           theta3=-h, theta4=h, lambda6=0.25, theta_mu=0.0, **arms_down), "X",
                  f"load frame X; Delta lambda_C = {lift:.2f} from eq 26 (theta_C1 = pi/2, r = 0.08)"),
        "eq 30": ({}, dict(x=0.0, y=0.0, psi=np.pi / 4, lambda_C=lift, **arms_down), "C",
                  f"lifted platform, Delta lambda_C = {lift:.2f} (eq 26), phi = pi/4 from sec 3's list"),
        "eq 31": ({"r": 0.10}, dict(x=0.0, y=0.0, psi=np.pi / 4,
                                    lambda_C=paper_delta_lambda(dict(p, r=0.10), h), theta_C1=0.0), "C1",
                  "arm 1 link frame at the pivot; arm angle theta_C1 + theta_CS1 = pi/2 - pi/2 = 0; "
                  "Delta lambda_C from eq 26 with eq 31's r = 0.10"),
    }


def model_printed(robot: Robot, key: str) -> np.ndarray:
    """The model's pose for printed equation ``key`` (see :func:`printed_states`)."""
    from ..description.kinematics import frame_pose

    overrides, values, frame, _ = printed_states(robot.params)[key]
    rob = robot if not overrides else Robot(robot.spec, {**robot.params, **overrides})
    return frame_pose(rob, state(rob, **values), frame)


def _printed_entries(key: str, paper: np.ndarray, model: np.ndarray) -> list[tuple[str, float, float, float]]:
    out = []
    for i in range(3):
        for j in range(4):
            val = paper[i, j]
            tol = 5e-20 if 0 < abs(val) < 1e-10 else 5e-5  # half a unit of the last printed digit
            out.append((f"{key} [{i + 1},{j + 1}]", val, model[i, j], tol))
    return out


def ik_cases(robot: Robot, n: int = 5, seed: int = 0) -> list[dict]:
    """Targets in the manipulation range (sec 2.11 c: x, y <= 2.5 m, z <= 1.5 m), solved numerically on the model.

    For each target the platform heading is eq 3's phi = atan2(d_y, d_x) and the arm values (theta1, lambda2,
    theta3) are drawn at random; the numerical IK (scipy, bounded least squares) then finds the platform position
    (x, y) putting the end effector E on the target. A second, fully numerical IK solves (x, y, psi, theta1,
    lambda2, theta3) from the neutral posture with minimum change.
    """
    from ..description.kinematics import position_ik

    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        target = np.array([rng.uniform(0.5, 2.5), rng.uniform(0.5, 2.5), rng.uniform(0.5, 1.5)])
        phi = float(np.arctan2(target[1], target[0]))
        arm = dict(theta1=rng.uniform(1.2, 2.6), lambda2=rng.uniform(0.3, 1.2), theta3=rng.uniform(-2.0, -0.6))
        q0 = state(robot, psi=phi, **arm)
        platform = position_ik(robot, "E", target, q0, ["x", "y", "lambda_C"])
        if not platform.success:
            continue
        free = position_ik(robot, "E", target, state(robot, psi=phi), ["x", "y", "psi", "theta1", "lambda2", "theta3"],
                           regularisation=1e-3)
        out.append(dict(target=target, arm=arm, phi=phi, platform=platform, free=free))
    return out


def compare(robot: Robot | None = None, states: int = 50, seed: int = 0) -> Comparison:
    """The paper's kinematics (eqs 1-2, 3-5, 10-14, 26-31) against the model.

    Closed forms are compared at ``states`` random configurations (worst deviation reported, tolerance 1e-9);
    printed numbers with half a unit of their last printed digit.
    """
    robot = robot or Robot(SPEC)
    p = robot.params
    cmp = Comparison("MMR12-EOD (Zuniga-Aviles et al. 2014): paper vs model")
    rng = np.random.default_rng(seed)
    names = ["x", "y", "psi", "lambda_C", "theta1", "lambda2", "theta3", "theta4", "lambda6"]
    dev_printed = np.zeros((4, 4))
    dev_chain = np.zeros((4, 4))
    first = None
    from ..description.kinematics import frame_pose

    for _ in range(states):
        vals = dict(x=rng.uniform(-3, 3), y=rng.uniform(-3, 3), psi=rng.uniform(-np.pi, np.pi),
                    lambda_C=rng.uniform(0, 0.37), theta1=rng.uniform(0, np.pi), lambda2=rng.uniform(0, 1.5),
                    theta3=rng.uniform(-np.pi, np.pi), theta4=rng.uniform(-np.pi, np.pi), lambda6=rng.uniform(0, 0.3))
        args = [vals[k] for k in names]
        T = frame_pose(robot, state(robot, theta_mu=0.0, **vals), "X")
        P = paper_X_M(p, *args)
        H = paper_htg_chain(p, *args)
        if first is None:
            first = (P, T)
        dev_printed = np.maximum(dev_printed, np.abs(P - T))
        dev_chain = np.maximum(dev_chain, np.abs(H - T))
    for i in range(3):
        for j in range(4):
            row = cmp.add(f"eq 2 X_M[{i + 1},{j + 1}] (as printed)", first[0][i, j], first[1][i, j], 1e-9,
                          note=f"max |diff| over {states} random states: {dev_printed[i, j]:.3g}")
            if dev_printed[i, j] > row.tol and row.deviation <= row.tol:
                row.model = row.paper + dev_printed[i, j]
    cmp.add("eq 2: HTG chain of Table 2 (numeric product), max entry diff", 0.0, float(dev_chain.max()), 1e-12,
            note=f"over {states} random states")
    # eqs 1 / 26: lift from the arm angle
    for th in (np.pi / 6, np.pi / 4, np.pi / 3, np.pi / 2):
        cmp.add(f"eq 26: Delta lambda_C at theta_C1 = {np.degrees(th):.0f} deg [m]", paper_delta_lambda(p, th),
                model_lift(robot, th), 1e-12, note="model: tip wheel of arm 1 touching the ground")
    # eqs 12-14
    worst = 0.0
    iR, iL = robot.velocity_names.index("theta_R_dot"), robot.velocity_names.index("theta_L_dot")
    idx = [robot.coordinate_index(c) for c in ("x", "y", "psi")]
    for _ in range(10):
        psi = rng.uniform(-np.pi, np.pi)
        nu = rng.normal(size=robot.mobility)
        v = robot.reduced(state(robot, psi=psi), nu).v
        worst = max(worst, float(np.max(np.abs(v[idx] - paper_platform_rates(p, psi, nu[iR], nu[iL])))))
    cmp.add("eqs 12-14: platform rates from wheel rates, max |diff|", 0.0, worst, 1e-12, note="10 random states")
    # printed transforms (27)-(31)
    for key, paper in PRINTED.items():
        model = model_printed(robot, key)
        for label, a, b, tol in _printed_entries(key, paper, model):
            cmp.add(label, a, b, tol)
        ortho, det = _defects(paper[:3, :3])
        cmp.add(f"{key}: det R of the printed matrix", det + 1.0, 1.0, 1e-3,
                note=f"max|R^T R - I| of the printed matrix = {ortho:.3g}")
    # climbing (sec 2.11 e): the gravity part of F_climb from the model on a 20 degree slope
    bal = climbing_balance(robot, np.radians(20.0))
    cmp.add("sec 2.11 e: m g sin(psi) at psi = 20 deg [N]", bal["F_gravity_paper"], bal["F_gravity_model"], 1e-9,
            note=f"model: wheel forces holding the robot, tilted gravity; m = {bal['mass']:.4g} kg (assumed masses)")
    # inverse kinematics
    for k, case in enumerate(ik_cases(robot)):
        target, arm = case["target"], case["arm"]
        num = case["platform"].q
        ik = paper_ik(p, target, arm["lambda2"], arm["theta1"], arm["theta3"])
        cmp.add(f"IK case {k + 1}: eq 10 x_C [m]", ik["x_C"], num[robot.coordinate_index("x")], 1e-9,
                note=f"target {np.round(target, 3).tolist()} for E; numerical IK error {case['platform'].error:.1e}")
        cmp.add(f"IK case {k + 1}: eq 11 y_C [m]", ik["y_C"], num[robot.coordinate_index("y")], 1e-9)
        qf = case["free"].q
        C = frame_pose(robot, qf, "C")[:3, 3]
        rel = target - frame_pose(robot, qf, "frame0")[:3, 3]
        th3, lam2, th1 = (qf[robot.coordinate_index(c)] for c in ("theta3", "lambda2", "theta1"))
        cmp.add(f"IK case {k + 1}: eq 3 phi = atan(dy/dx) of the target seen from C [rad]",
                float(np.arctan2(target[1] - C[1], target[0] - C[0])), qf[robot.coordinate_index("psi")], 1e-6,
                note=f"free numerical IK (x, y, psi, theta1, lambda2, theta3), error {case['free'].error:.1e}")
        e4 = paper_ik(p, rel, lam2, th1, th3)
        cmp.add(f"IK case {k + 1}: eq 4 theta3 vs model pi - |theta3| [rad]", e4["theta3"], np.pi - abs(th3), 1e-6,
                note="target relative to frame 0; eq 4 is the law of cosines for the interior angle, l3 neglected")
        e5 = paper_ik(p, rel, lam2, th1, th3)
        cmp.add(f"IK case {k + 1}: eq 5 lambda2 [m]", e5["lambda2"], lam2, 1e-6,
                note="d_z relative to frame 0, with the model's theta3")
    return cmp


def _defects(R: np.ndarray) -> tuple[float, float]:
    from ..description.kinematics import rotation_defects

    return rotation_defects(R)


# ------------------------------------------------------------------------------------------------- CLI
def register_cli(subparsers, parents) -> None:
    """``robotdyn fk ROBOT --q ... --frame NAME`` (generic forward kinematics, see :mod:`robotdyn.description.kinematics`)."""
    from ..cli.fk import register_fk_cli

    register_fk_cli(subparsers, parents)


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


def table4_reference(name: str, omega: float = 0.5) -> Callable:
    """Table 4's platform references as t -> (p_d, p_d', p_d'') of the controlled point [m]:
    ``orientation`` (turning about the centre x = y = 0: P on a circle of radius LOOK_AHEAD at omega rad/s),
    ``straight`` (x = 30, y = t), ``sinusoid`` (x = 40 cos 0.25t + 2.5t, y = 30 sin 0.25t)."""
    L = LOOK_AHEAD
    if name == "orientation":
        return lambda t: (L * np.array([np.cos(omega * t), np.sin(omega * t)]),
                          L * omega * np.array([-np.sin(omega * t), np.cos(omega * t)]),
                          -L * omega**2 * np.array([np.cos(omega * t), np.sin(omega * t)]))
    if name == "straight":
        return lambda t: (np.array([30.0, t]), np.array([0.0, 1.0]), np.zeros(2))
    if name == "sinusoid":
        return lambda t: (np.array([40 * np.cos(0.25 * t) + 2.5 * t, 30 * np.sin(0.25 * t)]),
                          np.array([-10 * np.sin(0.25 * t) + 2.5, 7.5 * np.cos(0.25 * t)]),
                          np.array([-2.5 * np.cos(0.25 * t), -1.875 * np.sin(0.25 * t)]))
    raise InputError(f"unknown Table 4 trajectory {name!r}; expected orientation, straight or sinusoid")


def _hold_task(robot: Robot, labels, q0):
    from ..simulation.control import CoordinateTask, hold

    return CoordinateTask(list(labels), hold([q0[robot.coordinate_index(c)] for c in labels]))


def platform_controller(robot: Robot, name: str, q0: np.ndarray | None = None):
    """Eqs 23-25 for a Table 4 trajectory: P tracks the reference, every other actuated joint holds its value."""
    from ..simulation.control import LinearisingController, PointTask

    q0 = robot.neutral() if q0 is None else q0
    others = [c for c in ACTUATED if c not in ("theta_R", "theta_L")]
    tasks = [PointTask("C", table4_reference(name), offset=(LOOK_AHEAD, 0.0, 0.0), axes=(0, 1)),
             _hold_task(robot, others, q0)]
    return LinearisingController(robot, tasks, **GAINS)


def platform_initial(robot: Robot, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Start on the reference: P at p_d(0), heading along p_d'(0) (or along +x at rest), wheels rolling at the
    reference speed (at rest for the orientation task)."""
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
    kept and the boom raised to theta1 = 2.7 rad, lambda2 = 1.1 m (inside the joint ranges)."""
    from ..description.kinematics import position_ik

    q0 = manipulation_initial(robot)[0] if q0 is None else q0
    guess = q0.copy()
    guess[robot.coordinate_index("theta1")] = 2.7
    guess[robot.coordinate_index("lambda2")] = 1.1
    return position_ik(robot, "E", MANIPULATION_TARGET, guess, ["x", "y", "theta3"])


def manipulation_controller(robot: Robot, q0: np.ndarray | None = None, T: float = 10.0):
    """End effector E to MANIPULATION_TARGET along a rest-to-rest quintic over T s (primary output, eq 25); arms,
    theta4 and the load hold; in the null space, (theta1, lambda2, theta3) follow quintics to the IK goal posture
    so that the joints stay in range and the platform drives the rest."""
    from ..simulation.control import CoordinateTask, LinearisingController, PointTask
    from ..description.kinematics import frame_pose

    q0 = manipulation_initial(robot)[0] if q0 is None else q0
    start = frame_pose(robot, q0, "E")[:3, 3]
    goal = manipulation_goal(robot, q0)
    if not goal.success:
        raise InputError(f"manipulation target {MANIPULATION_TARGET.tolist()} not reachable (IK error {goal.error:.3g} m)")
    arm = list(MANIPULATOR[:3])
    idx = [robot.coordinate_index(c) for c in arm]
    ref = lambda t: _quintic(t, T, start, MANIPULATION_TARGET)  # noqa: E731
    posture = lambda t: _quintic(t, T, q0[idx], goal.q[idx])  # noqa: E731
    held = [*(f"theta_C{i}" for i in _ARMS), "theta4", *LOAD]
    return LinearisingController(robot, [PointTask("E", ref), _hold_task(robot, held, q0)],
                                 secondary=[CoordinateTask(arm, posture)], **GAINS)


def manipulation_initial(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """At the origin, heading 45 degrees towards the wall target, arm in the neutral posture, at rest."""
    return state(robot, psi=np.pi / 4), np.zeros(robot.mobility)


# ------------------------------------------------------------------------------------------- lifting
LIFT_END = 1.54
"""Final arm angle [rad] of the lifting run: just short of pi/2, where d lambda_C / d theta_C = 0 (a dead point
of the arms: the constraint block is singular there); lambda_C0 + Delta lambda_C = 0.5198 m (eq 30: 0.52)."""


def lift_spec(spec: RobotSpec = SPEC) -> RobotSpec:
    """The robot standing on its four lifting-arm tip wheels (frictionless supports, normal rows only), drive
    wheels in the air: the lifting configuration of sec 2.11 d (Fig. 5)."""
    return dataclasses.replace(
        spec,
        name=f"{spec.name}_lifting",
        wheels=[Wheel(f"CS{i}", "r", axis=(0.0, 0.0, 1.0), kind="support", name=f"tip{i}") for i in _ARMS],
        independent=["x", "y", "psi", "theta_R", "theta_L", "theta_C1", *MANIPULATOR, *LOAD],
    )


def lift_robot(robot: Robot | None = None) -> Robot:
    """The lifting configuration of ``robot`` (same parameters)."""
    params = robot.params if robot is not None else None
    return Robot(lift_spec(robot.spec if robot is not None else SPEC), params)


def contact_angle(p: dict) -> float:
    """Arm angle [rad] at which the tip wheels touch the ground with the drive wheels still on it (eq 1 = 0)."""
    return float(np.arcsin((p["lambda_C0"] - p["r"]) / p["l_cs1"]))


def lifting_initial(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """All four arms at the contact angle, lambda_C = 0, at rest."""
    th = contact_angle(robot.params)
    return state(robot, lambda_C=0.0, **{f"theta_C{i}": th for i in _ARMS}), np.zeros(robot.mobility)


def lifting_controller(robot: Robot, T: float = 5.0, end: float = LIFT_END):
    """Arm 1 (the others follow through the contacts) along a quintic from the contact angle to ``end`` in T s,
    the manipulator, load and wheels hold; x, y, psi are unactuated (free on frictionless tips)."""
    from ..simulation.control import CoordinateTask, LinearisingController

    q0 = lifting_initial(robot)[0]
    th0 = contact_angle(robot.params)
    tasks = [CoordinateTask(["theta_C1"], lambda t: _quintic(t, T, th0, end)),
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


# ------------------------------------------------------------------------------------------- scenarios
def _scenarios() -> dict:
    from ..simulation.control import ControlledScenario

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

"""MMR12-EOD: the model against the paper (:func:`compare`) and the functions that bring both together.

Model: :mod:`robotdyn.robots.mmr12_eod.model` (Pinocchio, ``urdf/mmr12_eod.urdf.xacro``) -- the lift, frame poses and numerical IK computed
on it (``model_*``, :func:`ik_cases`), and the model states matching each printed transform
(:func:`printed_states`). Paper: :mod:`robotdyn.robots.mmr12_eod.paper` (eqs 1-2, 3-5, 10-14, 26-31 of
Zúñiga-Avilés et al. 2014, ``docs/bibliography.md``). Verdicts and evidence: ``docs/errata/mmr12_eod.md``.
"""

from __future__ import annotations

import numpy as np

from ...interfaces.comparison import Comparison
from ...robot import Robot
from .model import _ARMS, SPEC, climbing_balance, state
from .paper import (
    PRINTED,
    paper_delta_lambda,
    paper_htg_chain,
    paper_ik,
    paper_platform_rates,
    paper_X_M,
)


def model_lift(robot: Robot, theta_C: float, arm: int = 1) -> float:
    """Delta lambda_C from the model: how far the platform must rise for arm ``arm``'s tip wheel (radius r) at
    angle theta_C to touch the ground, i.e. max(0, r - z_tip) with z_tip the tip-frame height at lambda_C = 0.

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        theta_C: The arm angle theta_C [rad].
        arm: The lifting arm's number (1 to 4).

    Returns:
        Delta lambda_C [m].
    """
    from ...description.kinematics import frame_pose

    q = state(robot, lambda_C=0.0, **{f"theta_C{arm}": theta_C})
    z_tip = frame_pose(robot, q, f"CS{arm}")[2, 3]
    return max(0.0, robot.params["r"] - z_tip)


def printed_states(p: dict) -> dict[str, tuple[dict, dict, str, str]]:
    """For each printed transform (eqs 27-31): parameter overrides, coordinate values, model frame, reading.

    The coordinate values are the ones printed beside each equation (sec 3); Delta lambda_C comes from eq 26.

    Args:
        p: The parameters as a plain dict (Table 2 names of :data:`.model.SPEC`; lengths [m], angles [rad]).

    Returns:
        A dict of printed equation key to ``(overrides, values, frame, reading)``.
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
    """The model's pose for printed equation ``key`` (see :func:`printed_states`).

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        key: The printed equation's key (:func:`printed_states`).

    Returns:
        The model's homogeneous transform (4, 4) [m] of that frame.
    """
    from ...description.kinematics import frame_pose

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

    Args:
        robot: The MMR12-EOD :class:`~robotdyn.robot.Robot`.
        n: Number of targets.
        seed: Seed of the targets and arm values.

    Returns:
        One dict per target with keys ``target``, ``arm``, ``phi``, ``platform`` and ``free``.
    """
    from ...description.kinematics import position_ik

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

    Args:
        robot: The robot (default ``None``: built with the default parameters).
        states: Number of random configurations.
        seed: Seed of the configurations.

    Returns:
        The :class:`~robotdyn.interfaces.comparison.Comparison`.
    """
    robot = robot or Robot(SPEC)
    p = robot.params
    cmp = Comparison("MMR12-EOD (Zuniga-Aviles et al. 2014): paper vs model")
    rng = np.random.default_rng(seed)
    names = ["x", "y", "psi", "lambda_C", "theta1", "lambda2", "theta3", "theta4", "lambda6"]
    dev_printed = np.zeros((4, 4))
    dev_chain = np.zeros((4, 4))
    first = None
    from ...description.kinematics import frame_pose

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
    from ...description.kinematics import rotation_defects

    return rotation_defects(R)

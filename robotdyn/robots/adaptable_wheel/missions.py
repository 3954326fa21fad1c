"""Adaptable-wheel tricycle: the kinematic missions of section 7, solved by the paper's inverse kinematics.

Paper: Mardani & Ebrahimi 2016, ``docs/bibliography.md``, section 7 and Table 1 (mission 1: a circle
on the rough terrain; mission 2: a straight run across a ramp, path and heading not printed: ours) and the
flowchart of Fig. 8 (:func:`run_mission`: eqs 15-24 at every step, the yaw by eqs 18-23). The computation is the
paper's (:mod:`robotdyn.robots.adaptable_wheel.paper`); only the parameter defaults and the terrain come from the model's ``SPEC``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ...errors import InputError, RobotDynError
from .model import SPEC, WHEELS, _terrain
from .paper import IK_TOL, Commands, body_pose, contact_frame, offsets, radius_law, solve_ik, yaw_update


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
        mission: The :class:`Mission` solved.
        t: Times (N,) [s].
        beta: (N, 3) eq 16's contact angles per wheel (fr, fl, r) [rad].
        q: (N, 3) eq 16's adjustment angles per wheel (fr, fl, r) [rad].
        RT: (N, 3) total wheel radii [m].
        error: (N,) ||C|| (eq 24).
        yaw: (N,) q_zd [rad].
        cg: (N, 3) CG position [m], world frame.
        contacts: (N, 3, 3) contact points [m], world frame.
        nfev: (N,) residual evaluations of the root finder.
        commands: The :class:`~robotdyn.robots.adaptable_wheel.paper.Commands` of each step.
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


def run_mission(mission: Mission | str, params: dict | None = None, tol: float = IK_TOL) -> IKRun:
    """Inverse kinematics at every step of a mission (the flowchart of Fig. 8).

    Each step solves eq 15 by :func:`solve_ik` from the previous step's solution and updates q_zd by eqs 18-23.

    Args:
        mission: A :class:`Mission` or its name (:data:`MISSIONS`).
        params: Parameter overrides (default ``None``).
        tol: Required ||C|| of each step's IK (eq 24).

    Returns:
        The :class:`IKRun`.

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

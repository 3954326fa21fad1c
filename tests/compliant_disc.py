"""The compliant disc of the compliant-contact tests (tests/data/disc.urdf on a planar root, one compliant wheel
under a Coulomb law), its states and its flight phases: shared by the Python-path and the compiled-engine tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robotdyn.robot import Parameter, Robot, RobotSpec, Wheel

DISC = Path(__file__).parent / "data" / "disc.urdf"
M, R = 2.0, 0.3  # tests/data/disc.urdf's mass [kg]; the wheel radius [m]


def disc(g: float = 0.0, motors=(), **contact) -> Robot:
    """The disc with gravity g [m/s^2], the given motors and the compliant wheel's contact keys."""
    wheel = Wheel("disc", R, contact="compliant", friction="coulomb", mu=0.5, **contact)
    spec = RobotSpec(name="disc", title="compliant disc", xacro=DISC, root="planar", wheels=[wheel],
                     parameters=[Parameter("g", g, "m/s^2", xacro=False)], motors=list(motors))
    return Robot(spec)


def state(robot, z: float, vz: float, vx: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(q, nu) with the disc's centre at height z [m] moving at (vx, vz) [m/s]."""
    q = np.zeros(robot.nq)
    q[robot.coordinate_index("z")] = z
    nu = np.zeros(robot.mobility)
    nu[robot.velocity_names.index("z_dot")] = vz
    nu[robot.velocity_names.index("x_dot")] = vx
    return q, nu


def phases(traj) -> dict[str, list[float]]:
    """The times [s] of a run's touch-downs and lift-offs."""
    out: dict[str, list[float]] = {"touch-down": [], "lift-off": []}
    for e in traj.stats["flight"]:
        out[e["event"]].append(e["t"])
    return out


def landing(k: float, zeta: float, v_in: float) -> tuple[float, float]:
    """The damped landing's closed form (mass M on a linear spring-damper k, c = 2 zeta sqrt(k M), touching down
    at speed v_in [m/s], no gravity): the contact time [s] until the force k x + c x' returns to zero, plus the
    flight back up to the undeformed height, and the rebound velocity [m/s] (negative: upward is -v_in's sign).

    x(t) = v_in / w_d exp(-s t) sin(w_d t) (s = zeta w_n, w_d = w_n sqrt(1 - zeta^2)); the force is zero at
    w_d t* = pi - atan2(2 zeta sqrt(1 - zeta^2), 1 - 2 zeta^2), where the disc is still x* deep and leaves at
    v_out = x'(t*); it then rises x* at v_out."""
    wn = np.sqrt(k / M)
    s, wd = zeta * wn, wn * np.sqrt(1 - zeta**2)
    theta = np.pi - np.arctan2(2 * zeta * np.sqrt(1 - zeta**2), 1 - 2 * zeta**2)
    t_star = theta / wd
    x_star = v_in / wd * np.exp(-s * t_star) * np.sin(theta)
    v_out = -v_in * np.exp(-s * t_star) * (np.cos(theta) - s / wd * np.sin(theta))
    return t_star + x_star / v_out, v_out

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

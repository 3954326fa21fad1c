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


def check_landing(traj, k: float, zeta: float, v_in: float, gap: float) -> None:
    """Assert a dropped disc's run (touching down at v_in [m/s] after falling gap [m], no gravity) against
    :func:`landing`'s closed form: touch-down time to 1e-9 s, contact time and rebound speed to 1e-7 relative, the
    damper's work equal to the kinetic energy lost, and energy = damper work + friction work at every sample."""
    import pytest

    contact, v_out = landing(k, zeta, v_in)
    ev = phases(traj)
    assert ev["touch-down"] == pytest.approx([gap / v_in], abs=1e-9)
    assert len(ev["lift-off"]) == 1
    assert ev["lift-off"][0] - ev["touch-down"][0] == pytest.approx(contact, rel=1e-7)
    assert traj.column("z_dot")[-1] / v_in == pytest.approx(v_out / v_in, rel=1e-7)
    lost = 0.5 * M * (v_in**2 - v_out**2)
    assert -traj.damper_work[-1] == pytest.approx(lost, rel=1e-7, abs=1e-12)
    assert np.max(np.abs(traj.energy - traj.energy[0] - traj.damper_work - traj.friction_work)) < 1e-8 * M * v_in**2
    assert traj.stats["airborne"] == ["disc"]

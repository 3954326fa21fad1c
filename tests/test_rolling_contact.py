"""The rolling contact on its own: a thin disc (the rolling coin) on flat and curved terrain.

Checks the Jacobian and the drift against finite differences of A(q(t)) in time, the vector drift against the
matrix one, and that a torque-free simulation WITHOUT position stabilisation keeps the disc on the terrain and
conserves energy (a body-fixed contact point would sink the hub at about R |omega|^2)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from robotdyn.constraints.constraint import KinematicState
from robotdyn.errors import ConstraintError, DescriptionError
from robotdyn.robot import Robot, RobotSpec, Wheel
from robotdyn.constraints.rolling_contact import OmniWheel, RollingWheel
from robotdyn.simulation.engine import simulate
from robotdyn.constraints.terrain import BumpTerrain, FlatTerrain, RampTerrain, SineTerrain

DISC = Path(__file__).parent / "data" / "disc.urdf"
R = 0.3
TERRAINS = {
    "flat": FlatTerrain(0.1),
    "ramp": RampTerrain(0.2, heading=0.7),
    "sine": SineTerrain(1 / 15, 0.5, 0.5),
    "bump": BumpTerrain(0.05, x0=0.2, width=0.3),
}


def disc(terrain, omni: bool = False) -> Robot:
    kind = dict(kind="omni", roller_angle=0.4) if omni else {}
    spec = RobotSpec(name="disc", title="rolling disc", xacro=DISC, root="planar",
                     wheels=[Wheel("disc", R, **kind)], independent=None if omni else ["psi", "lean", "spin"])
    return Robot(spec, terrain=terrain)


def on_terrain(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Solve the contact condition for the height z."""
    iz = robot.coordinate_index("z")

    def gap(z):
        qq = q.copy()
        qq[iz] = z
        return robot.constraint_residual(qq)[0]

    q = q.copy()
    q[iz] = brentq(gap, -2.0, 2.0, xtol=1e-15)
    return q


def random_state(robot, rng):
    q = np.zeros(robot.nq)
    for name, value in zip(["x", "y", "psi", "lean", "spin"], rng.uniform([-2, -2, -3, -0.6, -3], [2, 2, 3, 0.6, 3])):
        q[robot.coordinate_index(name)] = value
    return on_terrain(robot, q), rng.normal(size=robot.nq)


def rows_at(robot, q, v):
    wheel = robot.constraints[0]
    kin = KinematicState(robot.model, robot.data, q, v)
    return wheel.rows(kin), wheel.drift(kin)


@pytest.mark.parametrize("name", list(TERRAINS))
@pytest.mark.parametrize("omni", [False, True])
def test_jacobian_time_derivative_matches_finite_differences(name, omni):
    """Adot equals (A(q + h v) - A(q - h v)) / 2h and drift() equals Adot v, at 20 random states."""
    robot = disc(TERRAINS[name], omni)
    rng = np.random.default_rng(0)
    h = 1e-6
    for _ in range(20):
        q, v = random_state(robot, rng)
        rows, drift = rows_at(robot, q, v)
        Ap, _ = rows_at(robot, q + h * v, v)
        Am, _ = rows_at(robot, q - h * v, v)
        fd = (Ap.A - Am.A) / (2 * h)
        assert np.max(np.abs(rows.Adot - fd)) < 1e-7 * max(1.0, np.abs(fd).max())
        assert np.allclose(drift, rows.Adot @ v, atol=1e-12)


@pytest.mark.parametrize("name", list(TERRAINS))
def test_normal_row_is_the_gradient_of_the_contact_residual(name):
    """On the manifold the normal row equals d(phi)/dq (finite differences along random directions)."""
    robot = disc(TERRAINS[name])
    rng = np.random.default_rng(1)
    h = 1e-6
    for _ in range(10):
        q, v = random_state(robot, rng)
        rows, _ = rows_at(robot, q, v)
        dphi = (robot.constraint_residual(q + h * v)[0] - robot.constraint_residual(q - h * v)[0]) / (2 * h)
        assert abs(rows.A[2] @ v - dphi) < 1e-7


@pytest.mark.parametrize("name", ["flat", "sine", "bump"])
def test_rolling_disc_stays_on_terrain_and_conserves_energy(name):
    """Torque-free rolling coin, 3 s, no stabilisation: contact residual < 1e-8 m, energy constant to 1e-8."""
    robot = disc(TERRAINS[name])
    q = np.zeros(robot.nq)
    q[robot.coordinate_index("lean")] = 0.25
    q = on_terrain(robot, q)
    nu = np.array([1.2, 0.3, 6.0])  # psi_dot, lean_dot, spin_dot: a fast, precessing, leaning coin
    traj = simulate(robot, 3.0, q, nu, None, n_out=301, rtol=1e-11, atol=1e-12, stabilisation=0.0, progress=False)
    assert np.max(traj.residual) < 1e-8
    assert np.max(np.abs(traj.energy - traj.energy[0])) < 1e-8 * abs(traj.energy[0])
    assert np.max(np.abs(traj.column("lean"))) < 1.2  # it did not fall over in this time


def test_upright_disc_rolls_straight_at_constant_speed():
    """Upright, rolling straight on a level plane: centre speed = R * spin rate, no precession, no lean."""
    robot = disc(FlatTerrain())
    q = on_terrain(robot, np.zeros(robot.nq))
    traj = simulate(robot, 2.0, q, [0.0, 0.0, 5.0], None, n_out=21, progress=False)
    assert np.allclose(traj.column("x"), R * 5.0 * traj.t, atol=1e-9)
    assert np.max(np.abs(traj.column("lean"))) < 1e-12
    assert np.allclose(traj.column("spin_dot"), 5.0, atol=1e-9)


def test_bad_wheels_give_clear_errors():
    robot = disc(FlatTerrain())
    with pytest.raises(DescriptionError, match="radius"):
        RollingWheel(robot.description, "disc", 0.0)
    with pytest.raises(DescriptionError, match="zero length"):
        RollingWheel(robot.description, "disc", 0.3, axis=(0, 0, 0))
    with pytest.raises(DescriptionError, match="no frame named 'dsic'"):
        OmniWheel(robot.description, "dsic", 0.3)
    q = on_terrain(robot, np.zeros(robot.nq))
    q[robot.coordinate_index("lean")] = np.pi / 2  # axle vertical: the disc lies flat
    with pytest.raises(ConstraintError, match="lying flat"):
        robot.constraint_residual(q)

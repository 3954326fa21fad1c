"""Wheels that slip (robotdyn.contact.sliding, robotdyn.contact.friction) against closed forms: a disc sliding down an incline
under Coulomb friction, a disc launched sliding on flat ground reaching pure rolling, the energy balance with the
friction work, the linear tyre law, and the one-line errors of the interfaces."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from robotdyn.errors import InputError
from robotdyn.robot import Robot, RobotSpec, Wheel
from robotdyn.simulation.engine import simulate
from robotdyn.constraints.terrain import RampTerrain

DISC = Path(__file__).parent / "data" / "disc.urdf"
M, I, R, G = 2.0, 0.04, 0.3, 9.81  # tests/data/disc.urdf: mass, axle inertia; wheel radius; gravity
K = I / (M * R**2)  # inertia ratio (1/2 for a solid disc)


def disc(slope: float = 0.0, independent=("x", "y", "psi", "lean", "spin"), **friction) -> tuple[Robot, np.ndarray]:
    spec = RobotSpec(name="disc", title="sliding disc", xacro=DISC, root="planar",
                     wheels=[Wheel("disc", R, **friction)], independent=None if independent is None else list(independent))
    robot = Robot(spec, terrain=RampTerrain(slope))
    return robot, on_ground(robot, np.zeros(robot.nq))


def on_ground(robot: Robot, q: np.ndarray) -> np.ndarray:
    """q with the disc's height z solving its contact row (Brent, to 1e-15 m)."""
    q = q.copy()
    iz = robot.coordinate_index("z")

    def gap(z):
        qq = q.copy()
        qq[iz] = z
        return robot.constraint_residual(qq)[0]

    q[iz] = brentq(gap, -2.0, 2.0, xtol=1e-15)
    return q


@pytest.mark.parametrize("slope, mu", [(1.0, 0.1), (2.0, 0.3)])
def test_disc_sliding_down_incline_coulomb(slope, mu):
    """Sliding down (no spin, 1 m/s downhill): the centre accelerates at g(sin a - mu cos a) along the slope,
    the spin at mu g cos(a) R m / I, and the normal load is m g cos(a) (Coulomb: the regularisation's relative
    error is (v_s/|s|)^2/2 = 5e-13 here)."""
    robot, q = disc(slope, friction="coulomb", mu=mu, slip_velocity=1e-6)
    alpha = np.arctan(slope)
    nu = np.array([-np.cos(alpha), 0.0, 0.0, 0.0, 0.0])  # 1 m/s down the slope, no spin
    nudot = robot.forward_dynamics(q, nu, [])
    along = G * (np.sin(alpha) - mu * np.cos(alpha))
    assert nudot[0] == pytest.approx(-along * np.cos(alpha), rel=1e-9)
    assert abs(nudot[4]) == pytest.approx(mu * G * np.cos(alpha) * R * M / I, rel=1e-9)
    f = robot.contact_forces(q, nu).wheels[0]
    assert f.kind == "slipping"
    assert f.normal == pytest.approx(M * G * np.cos(alpha), rel=1e-12)
    assert f.tangential == pytest.approx(mu * f.normal, rel=1e-9)
    assert f.world[0] < 0  # friction up the slope


@pytest.fixture(scope="module")
def launched():
    """A disc launched sliding at v0 = 2 m/s without spin on flat ground, mu = 0.3 (regularised, v_s = 1e-3)."""
    robot, q0 = disc(0.0, friction="coulomb", mu=0.3, slip_velocity=1e-3)
    traj = simulate(robot, 0.15, q0, [2.0, 0, 0, 0, 0], n_out=3001, rtol=1e-10, atol=1e-12, progress=False)
    return robot, traj


def test_launched_disc_reaches_rolling(launched):
    """Pure rolling at t* = v0 k / (mu g (1 + k)) with v* = v0 / (1 + k) (2 v0/3 and v0/(3 mu g) for a solid
    disc): the slip falls linearly at mu g (1 + k)/k until then."""
    robot, traj = launched
    v0, mu = 2.0, 0.3
    rate = mu * G * (1 + K) / K
    t_star = v0 / rate
    slip = traj.column("x_dot") - R * traj.column("spin_dot")
    assert traj.column("x_dot")[-1] == pytest.approx(v0 / (1 + K), rel=1e-7)
    assert abs(slip[-1]) < 1e-7
    level = 0.05  # well above v_s: Coulomb's linear decrease, to the regularisation's (v_s/s)^2 error
    i = np.flatnonzero(slip < level)[0]
    t_cross = np.interp(level, [slip[i], slip[i - 1]], [traj.t[i], traj.t[i - 1]])
    assert t_cross == pytest.approx(t_star - level / rate, rel=1e-3)


def test_energy_lost_to_friction(launched):
    """E(t) - E(0) equals the friction work at every sample (1e-6 of the loss), the friction never delivers
    energy, and the total loss is m v0^2 k / (2 (1 + k)) (m v0^2/6 for a solid disc) to the regularisation."""
    robot, traj = launched
    loss = M * 2.0**2 * K / (2 * (1 + K))
    np.testing.assert_allclose(traj.energy - traj.energy[0], traj.friction_work, atol=1e-6 * loss)
    assert np.all(np.diff(traj.friction_work) <= 1e-12)
    assert -traj.friction_work[-1] == pytest.approx(loss, rel=2e-3)


def test_linear_tyre_law():
    """Below saturation the linear law's force is -f_n k s; above, mu f_n against the slip."""
    robot, q = disc(0.0, friction="linear", stiffness=2.0, mu=0.8)
    nu = np.array([0.1, 0.05, 0.0, 0.0, 0.0])  # slip (0.1, 0.05) m/s: k|s| = 0.22 < mu
    f = robot.contact_forces(q, nu).wheels[0]
    np.testing.assert_allclose(f.force[:2], -f.normal * 2.0 * np.array([0.1, 0.05]), rtol=1e-12)
    f = robot.contact_forces(q, 10 * nu).wheels[0]
    assert f.tangential == pytest.approx(0.8 * f.normal, rel=1e-12)


@pytest.mark.parametrize("kw, match", [
    (dict(friction="coulomb", mu=-0.1), "mu"),
    (dict(friction="coulomb", mu=float("nan")), "mu"),
    (dict(friction="coulomb"), "needs mu"),
    (dict(friction="ice", mu=0.1), "unknown friction law 'ice'"),
    (dict(friction="linear", mu=0.5), "needs stiffness"),
    (dict(friction="linear", stiffness=-1.0), "stiffness"),
    (dict(friction="coulomb", mu=0.5, slip_velocity=0.0), "slip_velocity"),
    (dict(friction="coulomb", mu=0.5, kind="support"), "support wheel"),
    (dict(mu=-1.0), "mu"),
    (dict(slip_velocity=1e-3), "friction = 'rolling'"),
])
def test_bad_friction_input_is_one_line(kw, match):
    with pytest.raises(InputError, match=match) as exc:
        disc(0.0, **kw)
    assert "\n" not in str(exc.value) and "disc" in str(exc.value)

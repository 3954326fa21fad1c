"""The six-wheel linkage robot on asymmetric terrain: with rigid no-slip middle wheels its mobility drops from 2 to 1
wherever the terrain makes beta1 != beta2 (it can still move, along one path: the model's two independent
velocities are then refused with SingularConstraintError, docs/errata/linkage_suspension.md); with its two middle
(standard) wheels slipping under regularised Coulomb friction it moves freely, and its energy balance holds:
torque-free, E(t) - E(0) equals the friction work (robotdyn.contact.sliding). The slip run's figures quoted in the
errata are computed here (test_slip_run_figures_of_the_errata)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import robotdyn
from robotdyn.errors import SingularConstraintError
from robotdyn.constraints.posture import set_terrain, solve_posture
from robotdyn.robot import Robot
from robotdyn.simulation.engine import simulate
from robotdyn.constraints.terrain import SineTerrain

TERRAIN = dict(amplitude=0.03, kx=2.0, ky=3.0)


def _robot(slipping: bool) -> tuple[Robot, np.ndarray]:
    base = robotdyn.load("linkage_suspension")
    wheels = base.spec.wheels
    if slipping:
        wheels = [replace(w, friction="coulomb", mu=0.8, slip_velocity=0.01) if w.kind == "standard" else w
                  for w in wheels]
    robot = Robot(replace(base.spec, wheels=wheels, independent=None if slipping else base.spec.independent))
    set_terrain(robot, SineTerrain(**TERRAIN))
    return robot, solve_posture(robot, {"x": 0.0, "y": 0.0, "yaw": 0.0}).q


def test_rolling_middle_wheels_refuse_two_independent_velocities_on_asymmetric_terrain():
    robot, q0 = _robot(slipping=False)
    beta = [q0[robot.coordinate_index(b)] for b in ("beta1", "beta2")]
    assert abs(beta[0] - beta[1]) > 1e-3
    with pytest.raises(SingularConstraintError):
        robot.reduced(q0, np.zeros(robot.mobility))


def test_rolling_middle_wheels_leave_mobility_one_not_a_lock():
    """Not locked: the rows have rank 24 of 25, and the one admissible motion (SVD null space, an independent check
    of the projection) moves the body forward with both middle wheels rolling."""
    robot, q0 = _robot(slipping=False)
    A = robot.rows_at(q0).A
    _, s, Vt = np.linalg.svd(A)
    rank = int(np.sum(s > 1e-9 * s[0]))
    assert rank == 24 and robot.nq == 25  # mobility 1 (2 on flat or laterally symmetric ground)
    v = Vt[-1] / Vt[-1][robot.coordinate_index("phi2")]  # the middle right wheel at 1 rad/s
    assert np.abs(A @ v).max() < 1e-9
    assert abs(v[robot.coordinate_index("x")]) > 0.1  # the body moves: about r = 0.14 m/s forward
    assert abs(v[robot.coordinate_index("phi5")]) > 0.5  # the left middle wheel rolls too, its rate tied


def test_slip_run_figures_of_the_errata():
    """The figures docs/errata/linkage_suspension.md quotes: the six wheel motors track the section 3 speed profile
    (gain 2 N m s/rad, on the middle wheels' rates) for 2 s from rest on SineTerrain(0.03, 2, 3), the middle wheels
    slipping under regularised Coulomb friction (mu = 0.8, 0.01 m/s). LSODA at rtol 1e-5 (the numbers agree with
    DOP853 at 1e-8 to 4 digits); loads and the omni wheels' friction need from the contact forces at 41 samples."""
    from robotdyn.robots.linkage_suspension import model as lm

    robot, q0 = _robot(slipping=True)
    i2, i5 = robot.velocity_names.index("phi2_dot"), robot.velocity_names.index("phi5_dot")

    def tau(t, q, nu):
        ref = lm.wheel_speed(t)[0]
        right, left = lm.SPEED_GAIN * (ref - nu[i2]), lm.SPEED_GAIN * (ref - nu[i5])
        return np.array([right, right, right, left, left, left])

    traj = simulate(robot, 2.0, q0, np.zeros(robot.mobility), torque=tau, n_out=41, progress=False, rtol=1e-5,
                    atol=1e-9, method="LSODA")
    moved = {c: traj.column(c)[-1] - traj.column(c)[0] for c in ("x", "y", "yaw")}
    assert moved["x"] == pytest.approx(0.8835, abs=5e-4)
    assert moved["y"] == pytest.approx(0.0227, abs=5e-4) and moved["yaw"] == pytest.approx(0.0036, abs=2e-4)
    assert traj.friction_work[-1] == pytest.approx(-0.1087, abs=5e-4)  # the middle wheels' friction dissipates
    loads, omni_mu = [], []
    for t, q, nu in zip(traj.t, traj.q, traj.nu):
        f = robot.contact_forces(q, nu, tau=tau(t, q, nu))
        loads += [w.normal for w in f.wheels]
        omni_mu += [w.required_mu for w in f.wheels if w.kind == "omni"]
    assert min(loads) == pytest.approx(29.69, abs=0.02) and max(loads) == pytest.approx(79.28, abs=0.02)
    assert max(omni_mu) == pytest.approx(0.328, abs=0.001)


def test_slipping_middle_wheels_cross_it_with_energy_balance():
    robot, q0 = _robot(slipping=True)
    assert robot.mobility == 5
    nu0 = np.zeros(robot.mobility)
    nu0[robot.velocity_names.index("phi2_dot")] = nu0[robot.velocity_names.index("phi5_dot")] = 3.0
    traj = simulate(robot, 0.3, q0, nu0, n_out=31, progress=False)
    scale = abs(traj.friction_work[-1])
    assert scale > 1e-4  # the middle wheels do slip
    np.testing.assert_allclose(traj.energy - traj.energy[0], traj.friction_work, atol=1e-6 * max(scale, 1.0))
    f = robot.contact_forces(traj.q[-1], traj.nu[-1])
    assert all(w.normal > 0 for w in f.wheels)
    assert {w.kind for w in f.wheels} == {"omni", "slipping"}

"""The six-wheel linkage robot on asymmetric terrain: with rigid no-slip middle wheels it is locked wherever the
terrain makes beta1 != beta2 (SingularConstraintError, docs/errata/linkage_suspension.md); with its two middle
(standard) wheels slipping under regularised Coulomb friction it moves, and its energy balance holds: torque-free,
E(t) - E(0) equals the friction work (robotdyn.contact.sliding)."""

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


def test_rolling_middle_wheels_lock_on_asymmetric_terrain():
    robot, q0 = _robot(slipping=False)
    beta = [q0[robot.coordinate_index(b)] for b in ("beta1", "beta2")]
    assert abs(beta[0] - beta[1]) > 1e-3
    with pytest.raises(SingularConstraintError):
        robot.reduced(q0, np.zeros(robot.mobility))


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

"""MMR12-EOD climbing against the force model (sec 2.11 e): the robot held at rest on a ramp by its drive wheels
(rolling) and its rear arm tips (frictionless supports). Independent references: the whole robot's wrench balance
from Pinocchio's centre of mass (the only external forces are gravity and the contacts), the same problem posed as
flat ground with gravity tilted by the slope, and the paper's gravity part m g sin(psi)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.robots.mmr12_eod.model import climbing_forces, climbing_robot, climbing_state


@pytest.mark.parametrize("deg", [5.0, 20.0, 30.0])
def test_contact_wrench_balances_gravity(deg):
    slope = np.radians(deg)
    robot = climbing_robot(slope)
    q = climbing_state(robot, slope)
    forces = climbing_forces(slope)
    m = pin.computeTotalMass(robot.model)
    c = pin.centerOfMass(robot.model, robot.model.createData(), q)
    weight = m * robot.model.gravity.linear
    total = sum(w.world for w in forces.wheels) + weight
    moment = sum(np.cross(w.point, w.world) for w in forces.wheels) + np.cross(c, weight)
    assert np.abs(total).max() < 1e-9 * m * 9.81 and np.abs(moment).max() < 1e-9 * m * 9.81
    g = robot.params["g"]
    by = {w.name: w for w in forces.wheels}
    traction = by["W_R"].force[0] + by["W_L"].force[0]
    normal = sum(w.force[2] for w in forces.wheels)
    assert traction == pytest.approx(m * g * np.sin(slope), rel=1e-10)  # the paper's gravity part (sec 2.11 e)
    assert normal == pytest.approx(m * g * np.cos(slope), rel=1e-10)
    assert by["tip3"].force[:2] == pytest.approx([0.0, 0.0], abs=1e-9)  # frictionless supports
    # symmetric: the best split of the (undetermined) lateral forces is zero, mu = traction / load per wheel
    assert forces.minimum_mu() == pytest.approx(by["W_R"].force[0] / by["W_R"].force[2], rel=1e-9)


def test_ramp_equals_flat_ground_with_tilted_gravity():
    """Two constraint geometries of one mechanics: the ramp, and flat ground under gravity rotated by the slope."""
    slope = np.radians(20.0)
    on_ramp = climbing_forces(slope)
    flat = climbing_robot(0.0)
    g = flat.params["g"]
    flat.model.gravity.linear = g * np.array([-np.sin(slope), 0.0, -np.cos(slope)])
    zero = np.zeros(flat.mobility)
    tilted = flat.contact_forces(climbing_state(flat, 0.0), zero, nudot=zero)
    for a, b in zip(on_ramp.wheels, tilted.wheels):
        assert a.name == b.name and a.load_determined == b.load_determined
        assert a.force[[0, 2]] == pytest.approx(b.force[[0, 2]], rel=1e-9, abs=1e-9)


def test_required_mu_exceeds_the_slope_tangent():
    """The rear tips take part of the load (they are frictionless), so the drive wheels need mu > tan(slope):
    0.4096 at 20 deg (tan 0.364); mu = 0.6 holds the robot up to 26.85 deg (not the 30.96 deg of tan = mu)."""
    from scipy.optimize import brentq

    assert climbing_forces(np.radians(20.0)).minimum_mu() == pytest.approx(0.409582, abs=5e-7)
    top = brentq(lambda a: climbing_forces(a).minimum_mu() - 0.6, np.radians(10), np.radians(40), xtol=1e-10)
    assert np.degrees(top) == pytest.approx(26.846, abs=1e-3)
    assert np.degrees(top) < np.degrees(np.arctan(0.6)) - 4.0


def test_rear_tips_unload_on_a_shallow_slope():
    """The centre of mass is ahead of the axle: below about 0.72 deg the rear tips would have to pull."""
    from scipy.optimize import brentq

    def tip_load(a):
        return {w.name: w for w in climbing_forces(a).wheels}["tip3"].force[2]

    assert tip_load(np.radians(0.5)) < 0 < tip_load(np.radians(1.0))
    assert np.degrees(brentq(tip_load, 0.0, np.radians(10), xtol=1e-12)) == pytest.approx(0.7217, abs=1e-4)

"""MMR12-EOD: what the paper's 10 kg payload (sec 2.1, ``m_load``) does to the loads of the climbing posture (drive
wheels rolling, rear arm tips as frictionless outriggers). The paper prints no wheel load; the reference is the lever
rule about the drive axle on flat ground with Pinocchio's centre of mass (numbers of docs/errata/mmr12_eod.md)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import robotdyn
from robotdyn.robots.mmr12_eod.model import climbing_forces, climbing_robot, climbing_state


@pytest.mark.parametrize("m_load, tips, ahead", [(0.0, 42.716, -37.5), (10.0, -3.865, 3.1)])
def test_flat_tip_loads_are_the_lever_rule_about_the_drive_axle(m_load, tips, ahead):
    """On flat ground the drive wheels (axle at x_a) and the two tips (at x_t) carry the weight m g at x_G: moments
    about the axle give N_tips = m g (x_a - x_G) / (x_a - x_t)."""
    base = robotdyn.load("mmr12_eod", {"m_load": m_load})
    robot = climbing_robot(0.0, base)
    q = climbing_state(robot, 0.0)
    forces = climbing_forces(0.0, base)
    by = {w.name: w for w in forces.wheels}
    x_G = pin.centerOfMass(robot.model, robot.model.createData(), q)[0]
    x_a, x_t = by["W_R"].point[0], by["tip3"].point[0]
    assert by["W_L"].point[0] == pytest.approx(x_a, abs=1e-12) and by["tip4"].point[0] == pytest.approx(x_t, abs=1e-12)
    mg = pin.computeTotalMass(robot.model) * robot.params["g"]
    lever = mg * (x_a - x_G) / (x_a - x_t)
    assert by["tip3"].normal + by["tip4"].normal == pytest.approx(lever, rel=1e-9)
    assert lever == pytest.approx(tips, abs=1e-3)
    assert 1000 * (x_G - x_a) == pytest.approx(ahead, abs=0.05)


def test_payload_lowers_the_grip_needed_on_a_slope():
    slope = np.radians(20.0)
    with_load = climbing_forces(slope, robotdyn.load("mmr12_eod", {"m_load": 10.0})).minimum_mu()
    without = climbing_forces(slope, robotdyn.load("mmr12_eod", {"m_load": 0.0})).minimum_mu()
    assert with_load == pytest.approx(0.4096, abs=5e-5) and without == pytest.approx(0.4314, abs=5e-5)

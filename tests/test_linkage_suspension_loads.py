"""Six-wheel linkage-suspension robot (Chen et al.): wheel loads and grip along the section-3 runs on flat ground.
The paper prints no load; it explains its experiment's error by slip while the wheels speed up or slow down.
References: the loads sum to the weight (flat ground, no vertical acceleration of the centre of mass) and the
longitudinal contact forces to the mass times the centre of mass's acceleration (Newton, Pinocchio's com
acceleration from the kinematic run). Numbers of docs/errata/linkage_suspension.md."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.constraints.posture import set_terrain
from robotdyn.constraints.terrain import FlatTerrain
from robotdyn.robot import Robot
from robotdyn.robots.linkage_suspension import model as ls


@pytest.fixture(scope="module")
def runs():
    robot = Robot(ls.SPEC)
    set_terrain(robot, FlatTerrain())
    return robot, {"straight": (ls.kinematic_run(robot, (1.0, 1.0)), np.array([1.0, 1.0])),
                   "pivot": (ls.kinematic_run(robot, (-1.0, 1.0)), np.array([-1.0, 1.0]))}


def _forces(robot, run, sgn, i):
    w, wd = ls.wheel_speed(run["t"][i])
    return robot.contact_forces(run["q"][i], sgn * w, nudot=sgn * wd)


@pytest.mark.parametrize("name, t_peak, mu_peak, mu_cruise", [("straight", 0.7, 0.1684, 0.0),
                                                               ("pivot", 3.7, 0.2627, 0.0066)])
def test_grip_is_needed_only_in_the_speed_ramps(runs, name, t_peak, mu_peak, mu_cruise):
    robot, named = runs
    run, sgn = named[name]
    m = pin.computeTotalMass(robot.model)
    mg = m * robot.params["g"]
    i = int(np.argmin(np.abs(run["t"] - t_peak)))
    peak = _forces(robot, run, sgn, i)
    assert peak.minimum_mu() == pytest.approx(mu_peak, abs=1e-4)
    cruise = _forces(robot, run, sgn, int(np.argmin(np.abs(run["t"] - 2.2))))
    assert cruise.minimum_mu() == pytest.approx(mu_cruise, abs=1e-4)
    for f in (peak, cruise):
        assert sum(w.normal for w in f.wheels) == pytest.approx(mg, rel=1e-9)
    if name == "straight":  # sum of the ground's forces along x = m a_com,x (Newton)
        fx = sum(w.world[0] for w in peak.wheels)
        assert fx == pytest.approx(m * run["acom"][i, 0], rel=1e-6)
        assert abs(fx) > 10.0

"""Omni caster platform (Chung et al.): wheel loads and the grip the section-5 circle needs. The paper says nothing
about loads; the numbers are robotdyn's (docs/errata/omni_caster.md). Reference at rest: the lever rule of
Pinocchio's centre of mass over the three contact points (three supports: statically determinate)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.robot import Robot
from robotdyn.robots.omni_caster import model as oc


@pytest.fixture(scope="module")
def circle():
    robot = Robot(oc.SPEC)
    return robot, oc.plan(robot, "circle", n=241, rtol=1e-8)


def test_loads_at_rest_are_the_lever_rule(circle):
    """sum N_i = m g and sum N_i p_i = m g c (horizontal components): three equations for three loads."""
    robot, plan = circle
    q = plan["q"][0]
    forces = robot.contact_forces(q, np.zeros(3), tau=np.zeros(len(robot.motors)))
    pts = np.array([w.point[:2] for w in forces.wheels])
    c = pin.centerOfMass(robot.model, robot.model.createData(), q)[:2]
    mg = pin.computeTotalMass(robot.model) * 9.81
    lever = np.linalg.solve(np.vstack([np.ones(3), pts.T]), [mg, *(mg * c)])
    np.testing.assert_allclose([w.normal for w in forces.wheels], lever, rtol=1e-9)
    assert lever.max() - lever.min() > 10.0  # the casters' offsets make them unequal (12.4 N apart here)


def test_circle_loads_and_grip(circle):
    robot, plan = circle
    cf = [robot.contact_forces(q, nu, nudot=a) for q, nu, a in
          zip(plan["q"][::4], plan["nu"][::4], plan["nudot"][::4])]
    normal = np.array([[w.normal for w in f.wheels] for f in cf])
    need = np.array([[w.required_mu for w in f.wheels] for f in cf])
    mg = pin.computeTotalMass(robot.model) * 9.81
    np.testing.assert_allclose(normal.sum(1), mg, rtol=1e-9)  # planar motion: no vertical acceleration
    assert normal.min() == pytest.approx(16.92, abs=0.01) and normal.max() == pytest.approx(29.87, abs=0.01)
    assert need.max() == pytest.approx(0.0228, abs=1e-4)

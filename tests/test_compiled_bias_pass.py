"""The compiled evaluation's C v pass (kernels/reduced_dynamics.hpp, bias_forces): Pinocchio's RNEA on the joint
placements that configure's CRBA left at the same q. Where the simulation's right-hand side keeps a configuration
(joint springs and compliant wheels: the stiff integrator's differences in nu keep q), it must not reuse placements
that another call moved to another q in between (Evaluator.full computes the full model at any q)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from robotdyn.fast.dispatch import available
from robotdyn.simulation.compiled_engine import engine_model

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_joint_springs import car  # noqa: E402  (the sprung car: joint springs, rolling wheels)

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")


def test_right_hand_side_after_the_full_model_at_another_q():
    """rhs(q, nu) is the same bit for bit before and after full(q2, ...) at another configuration, and equal to a
    fresh copy's. Before full() marked the configuration stale, the second call kept q's rows and projection but
    read CRBA's M (and, with the reused placements, RNEA's) at q2."""
    robot = car(4.0e4, 2.0e3)
    fast = engine_model(robot)  # with its joint springs (robotdyn.fast.applied_model)
    assert fast is not None
    ev = fast.ev
    rng = np.random.default_rng(3)
    q = robot.neutral()
    nu = 0.5 * rng.normal(size=robot.mobility)
    tau = np.zeros(len(robot.motors))
    fast.compute(q, nu)  # chooses the rows and independent velocities (the Python path's choice)
    first = np.array(ev.rhs(q, nu, tau, 1.0))
    q2 = q + 0.3 * rng.normal(size=q.size)
    ev.full(q2, rng.normal(size=q.size), np.zeros(q.size))
    again = np.array(ev.rhs(q, nu, tau, 1.0))
    fresh = np.array(type(ev)(ev).rhs(q, nu, tau, 1.0))
    assert np.array_equal(first, again) and np.array_equal(first, fresh)
    assert np.all(np.isfinite(first)) and np.max(np.abs(first[q.size:])) > 1e-3  # the dynamics are not trivial

"""The compiled derivatives (robotdyn.fast.compiled_derivatives) at the states an optimiser's line search visits and
in the order it visits them, against the Python reference (robotdyn.reduction.dynamics_derivatives):

- off the holonomic manifold (q moved at random by 1e-6 and 1e-3 in every coordinate, constraint residuals up to
  2e-3): the formulas differentiate A(q), S(q) and the dynamics at any q, so both paths must agree there too, to
  1e-10 relative (measured 1e-16 to 2e-13);
- after evaluations at other states on the same compiled model (IPOPT interleaves the dynamics at trial points with
  the Jacobian at the iterate): nothing from an earlier call may leak into a later one, so a call repeated after
  others gives the same bits.

The linkage rover is left out of the first: its rows are exactly redundant on the manifold, and off it (residual
1e-9 and up) their rank grows and the reduction refuses the state on both paths (SingularConstraintError)."""

from __future__ import annotations

import numpy as np
import pytest
from test_dynamics_derivatives import START, admissible_state

from robotdyn.fast.compiled import available
from robotdyn.fast.compiled_derivatives import compiled_derivatives
from robotdyn.fast.dispatch import compiled_model
from robotdyn.reduction.dynamics_derivatives import dynamics_derivatives
from robotdyn.robot import Robot
from robotdyn.robots import module

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")
FIELDS = ("nudot", "dq", "dnu", "dtau", "qdot", "dqdot_dq", "S")


def off_manifold(robot, start, rng, scale):
    """An admissible state with every coordinate then moved by ``scale`` at random (within the joint limits)."""
    q, nu, tau = admissible_state(robot, start, rng)
    q = np.clip(q + scale * rng.normal(size=q.size), robot.description.lower, robot.description.upper)
    return q, nu, tau


@pytest.mark.parametrize("name", [n for n in START if n != "linkage_suspension"])
def test_compiled_derivatives_equal_python_off_the_manifold(name):
    robot = Robot(module(name).SPEC)
    rng = np.random.default_rng(3)
    for scale in (1e-6, 1e-3):
        q, nu, tau = off_manifold(robot, START[name], rng, scale)
        C = compiled_derivatives(robot, q, nu, tau)
        assert C is not None
        P = dynamics_derivatives(robot, q, nu, tau)
        for field in FIELDS:
            got, ref = getattr(C, field), getattr(P, field)
            assert np.abs(got - ref).max() <= 1e-10 * max(1.0, np.abs(ref).max()), (field, scale)
        assert np.abs(C.dq).max() > 1e-6 and np.abs(C.dnu).max() > 1e-6  # not a vacuous comparison


@pytest.mark.parametrize("name", ["linkage_suspension", "mmr12_eod", "adaptable_wheel"])
def test_compiled_derivatives_do_not_depend_on_earlier_calls(name):
    """Derivatives at state 1, then the rhs and the derivatives at state 2 on the same compiled model, then the
    derivatives at state 1 again: the same bits as the first time."""
    robot = Robot(module(name).SPEC)
    rng = np.random.default_rng(11)
    q1, nu1, tau1 = admissible_state(robot, START[name], rng)
    q2, nu2, tau2 = admissible_state(robot, START[name], rng)
    first = compiled_derivatives(robot, q1, nu1, tau1)
    assert first is not None
    fast = compiled_model(robot)
    fast.rhs(q2, nu2, tau2, 0.0)
    other = compiled_derivatives(robot, q2, nu2, tau2)
    fast.rhs(q2, 2.0 * nu2, tau2, 0.0)
    again = compiled_derivatives(robot, q1, nu1, tau1)
    for field in FIELDS:
        assert np.array_equal(getattr(first, field), getattr(again, field)), field
    assert np.abs(other.dq - first.dq).max() > 1e-6  # the state in between did differ

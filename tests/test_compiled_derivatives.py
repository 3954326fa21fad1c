"""The compiled derivatives of the reduced forward dynamics (robotdyn.fast.compiled_derivatives, the C++ kernels
robotdyn/kernels/*_derivatives.hpp) against their Python reference (robotdyn.reduction.dynamics_derivatives,
itself checked against Richardson differences and sympy in tests/test_dynamics_derivatives.py, which now runs
through the compiled path wherever it serves): equal to 1e-10 relative (to the largest entry, or absolute below 1)
at random admissible states of every built-in robot the compiled model serves, on flat, ramp, bump and sine
terrains; the operational-space omni platform and slipping wheels: tests/test_compiled_opspace_slip_derivatives.py."""

from __future__ import annotations

import numpy as np
import pytest
from test_dynamics_derivatives import START, admissible_state

from robotdyn.constraints.posture import set_terrain, solve_posture
from robotdyn.constraints.terrain import BumpTerrain, SineTerrain
from robotdyn.fast.compiled import available
from robotdyn.fast.compiled_derivatives import compiled_derivatives
from robotdyn.fast.dispatch import use_compiled
from robotdyn.reduction.dynamics_derivatives import dynamics_derivatives
from robotdyn.robot import Robot
from robotdyn.robots import module

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")
FIELDS = ("nudot", "dq", "dnu", "dtau", "qdot", "dqdot_dq", "S", "tangent", "dq_manifold")


def assert_same(C, P):
    for name in FIELDS:
        got, ref = getattr(C, name), getattr(P, name)
        assert got.shape == ref.shape, name
        assert np.abs(got - ref).max(initial=0.0) <= 1e-10 * max(1.0, np.abs(ref).max(initial=0.0)), \
            (name, np.abs(got - ref).max())
    assert np.array_equal(C.positions, P.positions) and C.numerical == () == P.numerical
    assert (C.coordinates, C.velocities, C.motors) == (P.coordinates, P.velocities, P.motors)


@pytest.mark.parametrize("name", [n for n in START if n != "omni_caster"])
def test_compiled_derivatives_equal_python_on_built_in_robots(name):
    robot = Robot(module(name).SPEC)
    rng = np.random.default_rng(5)
    for _ in range(2):
        q, nu, tau = admissible_state(robot, START[name], rng)
        C = compiled_derivatives(robot, q, nu, tau)
        assert C is not None
        P = dynamics_derivatives(robot, q, nu, tau)
        assert_same(C, P)
        assert np.abs(C.dq).max() > 1e-6 and np.abs(C.dnu).max() > 1e-6  # not a vacuous comparison


@pytest.mark.parametrize("name, terrain", [("adaptable_wheel", BumpTerrain(0.05, 0.1, 0.2)),
                                           ("adaptable_wheel", SineTerrain(0.03, 2.0, 1.5, 0.3)),
                                           ("linkage_suspension", None)])
def test_compiled_derivatives_equal_python_on_curved_and_sloped_terrain(name, terrain):
    """Curved terrain (the terrain's third derivatives in the drift's q-derivative), a joint-driven radius
    (adaptable wheel), and loop closures on a ramp (the linkage rover)."""
    mod = module(name)
    robot = Robot(mod.SPEC)
    rng = np.random.default_rng(9)
    if terrain is None:
        set_terrain(robot, mod.TERRAINS["ramp"]())
        q = solve_posture(robot, {"x": 0.1, "y": 0.05, "yaw": 0.3}, tol=1e-13).q
        nu, tau = rng.normal(size=robot.mobility) * 0.5, rng.normal(size=len(robot.motors))
    else:
        q, nu, tau = admissible_state(robot, START[name], rng)
        set_terrain(robot, terrain)
    C = compiled_derivatives(robot, q, nu, tau)
    assert C is not None
    assert_same(C, dynamics_derivatives(robot, q, nu, tau))


def test_robot_dynamics_derivatives_dispatch():
    """Robot.dynamics_derivatives takes the compiled path where it serves and the Python path under
    use_compiled(False), with the same numbers; the operational-space omni platform too (its compiled twin)."""
    robot = Robot(module("quasimoro").SPEC)
    q, nu, tau = admissible_state(robot, None, np.random.default_rng(2))
    fast = robot.dynamics_derivatives(q, nu, tau)
    with use_compiled(False):
        assert compiled_derivatives(robot, q, nu, tau) is None
        slow = robot.dynamics_derivatives(q, nu, tau)
    assert_same(fast, slow)
    omni = Robot(module("omni_caster").SPEC)
    q, nu, tau = admissible_state(omni, START["omni_caster"], np.random.default_rng(2))
    assert compiled_derivatives(omni, q, nu, tau) is not None
    assert_same(omni.dynamics_derivatives(q, nu, tau), dynamics_derivatives(omni, q, nu, tau))

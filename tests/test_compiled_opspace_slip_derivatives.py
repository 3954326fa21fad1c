"""The compiled derivatives of the reduced forward dynamics with operational-space velocities
(robotdyn/kernels/operational_space_derivatives.hpp) and with slipping wheels (robotdyn/kernels/sliding_derivatives.hpp).

References, independent of the kernels under test:
- the Python path (robotdyn.reduction.dynamics_derivatives, robotdyn.contact.sliding_derivatives, themselves checked
  against Richardson differences of the Python forward dynamics in tests/test_dynamics_derivatives.py): equal to
  1e-10 relative (to the largest entry, or absolute below 1) at random states;
- Richardson-extrapolated central differences (h and h/2, truncation O(h^4)) of the compiled forward dynamics
  itself (the compiled evaluation, or the compiled slipping right-hand side), along the holonomic manifold (each
  perturbed configuration re-solved onto it): agreement 1e-7 relative.

Robots: the omni-caster platform (its body twist in body axes), TIAGo driven by its base twist in body axes and in
world axes, the skid-steer example (linear tyre law as shipped, in its linear and in its saturated range; regularised
Coulomb friction; rear wheels slipping sideways only).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from test_compiled_derivatives import assert_same
from test_dynamics_derivatives import EXAMPLES, START, admissible_state, richardson, skid_steer

from robotdyn.constraints.posture import solve_posture
from robotdyn.contact.sliding_derivatives import sliding_derivatives
from robotdyn.errors import InputError
from robotdyn.fast.compiled import available
from robotdyn.fast.compiled_derivatives import compiled_derivatives
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.interfaces.constraint_file import read
from robotdyn.reduction.dynamics_derivatives import dynamics_derivatives
from robotdyn.reduction.operational_space import OperationalVelocities
from robotdyn.robot import Robot
from robotdyn.robots import module

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")


def tiago(axes: str) -> Robot:
    """TIAGo (examples/tiago.toml) whose independent velocities are its base's forward speed and yaw rate."""
    spec = read(EXAMPLES / "tiago.toml").SPEC
    twist = OperationalVelocities("base_footprint", ("vx", "wz"), axes, ["vx", "wz"])
    return Robot(replace(spec, independent=None, operational=twist))


def tiago_state(robot, rng):
    q = robot.neutral()
    q[:5] = rng.uniform(-2, 2, 5)
    return q, rng.normal(size=2), rng.normal(size=2) * 3


def skid_state(robot, rng, scale=0.5):
    q = robot.neutral()
    for c in ("x", "y", "yaw", "front_left_spin", "rear_right_spin"):
        q[robot.coordinate_index(c)] = rng.uniform(-1, 1)
    return q, rng.normal(size=robot.mobility) * scale, rng.normal(size=4) * 3


def compiled_nudot(robot, q, nu, tau):
    """The compiled forward dynamics: M_r^-1 (B_r tau - h) from one compiled evaluation, or the slipping
    right-hand side's accelerations."""
    fast = compiled_model(robot)
    if fast.ev.slipping:
        return fast.ev.slip_rhs(q, nu, tau, 0.0)[0][robot.nq:robot.nq + robot.mobility]
    M, h, _, B, *_ = fast.evaluate(q, nu)
    return np.linalg.solve(M, B @ tau - h)


def check_against_compiled_differences(robot, q, nu, tau):
    D = compiled_derivatives(robot, q, nu, tau)
    assert D is not None
    names = [robot.coordinates[i] for i in D.positions]
    on_manifold = lambda qp: solve_posture(robot, dict(zip(names, qp)), q0=q, tol=1e-13,  # noqa: E731
                                           check_limits=False).q
    if len(D.positions) == robot.nq:
        on_manifold = lambda qp: qp  # noqa: E731 (no holonomic row restricts q)
    refs = {"dq_manifold": richardson(lambda x: compiled_nudot(robot, on_manifold(x), nu, tau), q[D.positions]),
            "dnu": richardson(lambda x: compiled_nudot(robot, q, x, tau), nu),
            "dtau": richardson(lambda x: compiled_nudot(robot, q, nu, x), tau)}
    np.testing.assert_allclose(D.nudot, compiled_nudot(robot, q, nu, tau), rtol=1e-12, atol=1e-12)
    for name, ref in refs.items():
        got = getattr(D, name)
        assert np.abs(got - ref).max() <= 1e-7 * max(1.0, np.abs(ref).max()), (name, np.abs(got - ref).max())
    return D


@pytest.mark.parametrize("which", ["omni_caster", "tiago_local", "tiago_world"])
def test_operational_derivatives_equal_python_and_differences(which):
    rng = np.random.default_rng(3)
    if which == "omni_caster":
        robot = Robot(module(which).SPEC)
        states = [admissible_state(robot, START[which], rng) for _ in range(2)]
    else:
        robot = tiago(which.partition("_")[2])
        states = [tiago_state(robot, rng) for _ in range(2)]
    for q, nu, tau in states:
        C = compiled_derivatives(robot, q, nu, tau)
        assert C is not None
        assert_same(C, dynamics_derivatives(robot, q, nu, tau))
        # not a vacuous comparison (in body axes the twist dynamics do not depend on x, y, psi: dq is small there)
        assert np.abs(C.dq).max() > 1e-8 and np.abs(C.dnu).max() > 1e-6
    check_against_compiled_differences(robot, *states[0])


@pytest.mark.parametrize("variant", ["linear", "linear_saturated", "coulomb", "lateral"])
def test_slipping_derivatives_equal_python_and_differences(variant, tmp_path):
    """The skid-steer example: the linear tyre law in its linear range (small slip) and saturated at Coulomb's
    limit (large slip), regularised Coulomb friction, and its rear wheels slipping sideways only."""
    if variant.startswith("linear"):
        robot = read(EXAMPLES / "skid_steer.toml").robot()
    elif variant == "coulomb":
        robot = skid_steer(tmp_path, {"friction": "coulomb", "mu": 0.8, "slip_velocity": 0.05})
    else:
        robot = skid_steer(tmp_path, lateral=True)
    rng = np.random.default_rng(9)
    scale = {"linear": 0.01, "linear_saturated": 2.0}.get(variant, 0.5)
    states = [skid_state(robot, rng, scale) for _ in range(2)]
    fast = compiled_model(robot)
    for q, nu, tau in states:
        C = compiled_derivatives(robot, q, nu, tau)
        assert C is not None
        assert_same(C, sliding_derivatives(robot, q, nu, tau))
        assert np.abs(C.dnu).max() > 1.0  # the friction forces depend on the slip velocities
        if variant.startswith("linear"):  # the law's range the state is in (k |s| <= mu: linear)
            slip = fast.ev.slip_rhs(q, nu, tau, 0.0)[2]
            linear = 5.0 * np.linalg.norm(slip, axis=1) <= 0.8
            assert linear.all() if variant == "linear" else not linear.any(), slip
    check_against_compiled_differences(robot, *states[0])


def test_robot_dynamics_derivatives_takes_the_compiled_twins(tmp_path):
    """Robot.dynamics_derivatives: the compiled twin for operational and slipping robots, equal to the Python path
    under use_compiled(False); the one-line refusals on both paths; an indeterminate slipping chassis (its loads
    from the rigid limit, simulated on the Python path) stays on the Python path and its refusal."""
    rng = np.random.default_rng(4)
    for robot in (tiago("local"), read(EXAMPLES / "skid_steer.toml").robot()):
        q, nu, tau = tiago_state(robot, rng) if robot.operational is not None else skid_state(robot, rng)
        fast = robot.dynamics_derivatives(q, nu, tau)
        assert type(fast).__name__ == "_CompiledDerivatives"
        with use_compiled(False):
            slow = robot.dynamics_derivatives(q, nu, tau)
        assert type(slow).__name__ == "DynamicsDerivatives"
        assert_same(fast, slow)
    exact = skid_steer(tmp_path, {"friction": "stick_slip", "mu": 0.8})
    for flag in (True, False):
        with use_compiled(flag), pytest.raises(InputError, match="friction law|stick"):
            exact.dynamics_derivatives(exact.neutral(), np.ones(exact.mobility), np.zeros(4))
    husky = read(EXAMPLES / "husky_like.toml").robot()
    q, nu, tau = husky.neutral(), np.ones(husky.mobility) * 0.3, np.ones(4)
    assert compiled_derivatives(husky, q, nu, tau) is None
    for flag in (True, False):
        with use_compiled(flag), pytest.raises(InputError, match="no derivative rule"):
            husky.dynamics_derivatives(q, nu, tau)

"""A compliant wheel on curved terrain: its penetration rate is the time derivative of the same signed distance
phi(q) that gives its stored energy U(-phi) (robotdyn.contact.compliant_contact.penetration_gradient, and its twin
in robotdyn/kernels/compliant_contact.hpp), so that the normal force's power is exactly minus the rate of stored
energy plus the damper's power.

The reference is independent of the formula: central differences (fourth order) of the penetration itself along
the motion, -(phi(q + e v) - phi(q - e v)) / (2 e) with Richardson's correction. The old rate, the normal velocity
n^T A_w v of the wheel's material point at the contact point, is the derivative of phi only on a plane: on the
bump of examples/bump_base.toml it is off by 1e-4 to 1e-2 m/s at 5 to 40 mm of penetration, which is what made
that example's energy balance miss by 0.1 J of 246 J (tests/test_compliant_compiled.py now asserts it on both
engines).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.constraints.constraint import KinematicState
from robotdyn.contact.compliant_contact import compliant_wheels

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module")
def bump_base():
    from robotdyn.interfaces.constraint_file import read

    cf = read(EXAMPLES / "bump_base.toml")
    robot = cf.robot()
    return robot, cf.SCENARIOS["bump"].initial_state(robot)


def states(robot, q0):
    """(q, nu) with the base on the bump's rising flank (x = 0.5, 0.55 m: the front wheels 21 and 5 mm deep, on
    the curved ramp) and before it (0.35 m), moving with random velocities."""
    rng = np.random.default_rng(7)
    for x in (0.35, 0.5, 0.55):
        q = q0.copy()
        q[robot.coordinate_index("x")] = x
        q[robot.coordinate_index("z")] += 0.02 * (x - 0.3)
        yield q, rng.normal(size=robot.mobility)


def along(robot, fn, q, v, e: float = 1e-5) -> float:
    """d/dt of fn(q) along v by central differences with Richardson's correction (error O(e^4))."""
    def at(s):
        return fn(KinematicState(robot.model, robot.data, q + s * v, v))

    return (8 * (at(e) - at(-e)) - (at(2 * e) - at(-2 * e))) / (12 * e)


def penetration_rate_fd(robot, wheel, q, v) -> float:
    """d delta/dt = -d phi/dt along v (differences)."""
    return along(robot, wheel.penetration, q, v)


def test_penetration_rate_is_the_derivative_of_phi(bump_base):
    robot, (q0, _) = bump_base
    old_misses = []
    for q, nu in states(robot, q0):
        v = robot.velocity(q, nu)
        for w in compliant_wheels(robot):
            kin = KinematicState(robot.model, robot.data, q, v)
            st = w.state(kin)
            Aw, geo = w._world_jacobian(kin)
            old = -float(geo[9][:, 2] @ (Aw @ v))  # the rate before: -n^T A_w v
            ref = penetration_rate_fd(robot, w, q, v)
            assert abs(st["rate"] - ref) < 1e-9 * max(1.0, abs(ref)), (w.name, st["rate"], ref)
            old_misses.append(abs(old - ref))
    assert max(old_misses) > 1e-3  # (the old rate: off on the curved flank, so the check above can fail)


def test_normal_force_power_is_minus_the_stored_energy_rate(bump_base):
    """The contact's power Q . v = friction power + damper power - dU/dt, dU/dt of the stored energy U(delta(q))
    by differences along the motion: the energy balance's integrand, at each wheel."""
    robot, (q0, _) = bump_base
    old_misses = []
    for q, nu in states(robot, q0):
        v = robot.velocity(q, nu)
        for w in compliant_wheels(robot):
            kin = KinematicState(robot.model, robot.data, q, v)
            st = w.state(kin)
            if abs(st["delta"]) < 1e-4:  # (U's second derivative jumps at delta = 0, within the differences' reach)
                continue
            Aw, geo = w._world_jacobian(kin)
            elastic = w.normal_law.elastic(st["delta"])
            dU = along(robot, lambda k: w.normal_law.potential(w.penetration(k)), q, v)
            power = st["Q"] @ v
            expected = st["friction_power"] + st["damper_power"] - dU
            assert abs(power - expected) < 1e-8 * max(1.0, abs(elastic * st["rate"])), (w.name, power, expected)
            # before: Q = A^T force with the n row n^T A_w and the rate -n^T A_w v
            old_rate = -float(geo[9][:, 2] @ (Aw @ v))
            old_power = st["friction_power"] - st["force"][2] * old_rate if st["delta"] > 0 else 0.0
            old_damper = -(st["force"][2] - elastic) * old_rate if st["delta"] > 0 else 0.0
            old_misses.append(abs(old_power - (st["friction_power"] + old_damper - dU)))
    assert max(old_misses) > 1e-2  # [W]: the old power missed -dU/dt by f_e times the rate's error


def test_compiled_rates_and_forces_equal_python(bump_base):
    from robotdyn.contact.applied_forces import applied
    from robotdyn.fast.applied_model import applied_model, applied_state

    robot, (q0, _) = bump_base
    fast = applied_model(robot)
    if fast is None:
        pytest.skip("the compiled extension was not built")
    for q, nu in states(robot, q0):
        Q, friction, damper, contacts = applied_state(fast, q, nu)
        ref = applied(robot, q, robot.velocity(q, nu))
        assert np.allclose(Q, ref.Q, rtol=1e-12, atol=1e-9)
        assert damper == pytest.approx(ref.damper_power, rel=1e-12, abs=1e-9)
        rates = [ref.wheels[w.name]["rate"] for w in compliant_wheels(robot)]
        assert np.allclose(contacts[:, 1], rates, rtol=1e-12, atol=1e-13)

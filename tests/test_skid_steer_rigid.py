"""Rigid four-wheel skid steers taken as their descriptions ship (examples/husky_like, examples/jackal_like: no
roll axle, so their normal loads are statically indeterminate) turn under a friction law: the loads are the rigid
limit of the wheels' normal compliance, solved together with the accelerations and friction
(robotdyn.contact.rigid_limit.coupled; issue 23).

Coulomb threshold for turning in place (derived here). Wheels at (+-a, +-b), equal loads N = m g / 4 (the centre
of mass over the middle: by symmetry the rigid limit splits equally), torques -tau (left) and +tau (right). Once
the wheels slide, each carries a friction force of magnitude mu N (Coulomb), whose longitudinal part F_x balances
the wheel's torque (F_x = tau / r, wheel inertia aside) and whose lateral part F_y = sqrt((mu N)^2 - F_x^2)
resists the yaw (the lateral slip of a contact point turning about the middle is a psi_dot, the longitudinal
part of the turning velocity b psi_dot is taken up by the wheel spin). The yaw moment of the four wheels is
4 (b F_x - a F_y): the base spins up iff b F_x > a F_y, i.e. tau > tau* = mu N r a / sqrt(a^2 + b^2); then its
yaw acceleration is at most 4 (b F_x - a F_y) / I_z (wheel inertia and the law's regularisation only lower it).
Below tau* the sliding stops and the base only creeps at the law's regularisation speed.

ICR relation (Mandow et al. 2007; Kozlowski & Pazderski 2004, as in tests/test_skid_steer.py): with the linear
tyre law F = -f_n k s and equal loads, turning in place at wheel rate phi and yaw rate omega is steady when
omega (a^2 + b^2) = b r phi and phi = tau (a^2 + b^2) / (r^2 f_n k a^2); the sides' ICRs lie at
y = +-(a^2 + b^2) / b (expansion factor 1 + (a/b)^2)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.interfaces.constraint_file import read
from robotdyn.robot import Robot
from robotdyn.simulation.engine import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
A, B, R, MU = 0.256, 0.2775, 0.165, 0.6  # examples/husky_like: half wheelbase, half track, radius, mu [m, -]


@pytest.fixture(scope="module")
def husky():
    mod = read(EXAMPLES / "husky_like.toml")
    return mod, mod.robot()


def _yaw_izz(robot: Robot) -> float:
    """The whole robot's moment of inertia about the vertical through its centre [kg m^2] (Pinocchio)."""
    data = robot.model.createData()
    q = robot.neutral()
    pin.ccrba(robot.model, data, q, np.zeros(robot.nq))
    return float(data.Ig.inertia[2, 2])


def test_turning_in_place_against_the_coulomb_threshold(husky):
    _, robot = husky
    m = float(pin.computeTotalMass(robot.model))
    N = m * 9.81 / 4
    star = MU * N * R * A / np.hypot(A, B)  # 9.29 N m
    sign = np.array([-1.0, 1.0, -1.0, 1.0])
    slow = simulate(robot, 0.4, robot.neutral(), np.zeros(robot.mobility), lambda t, q, nu: 0.8 * star * sign,
                    n_out=5, progress=False)
    fast = simulate(robot, 0.4, robot.neutral(), np.zeros(robot.mobility), lambda t, q, nu: 1.2 * star * sign,
                    n_out=5, progress=False)
    assert "engine" not in slow.stats or "compiled" not in slow.stats["engine"]
    below, above = slow.column("yaw_dot"), fast.column("yaw_dot")
    # below: a creep at the regularisation speed (slip_velocity 0.05 m/s over the arm ~0.38 m), no spin-up
    assert abs(below[-1]) < 2 * 0.05 / np.hypot(A, B) and abs(below[-1] - below[-2]) < 0.05 * abs(below[-1])
    Fx = 1.2 * star / R
    bound = 4 * (B * Fx - A * np.sqrt((MU * N) ** 2 - Fx**2)) / _yaw_izz(robot)  # ~4.2 rad/s^2
    rate = (above[-1] - above[-3]) / (fast.t[-1] - fast.t[-3])
    assert 0.5 * bound < rate <= bound
    np.testing.assert_allclose(fast.column("x")[-1], 0.0, atol=1e-9)  # about its centre
    f = robot.contact_forces(fast.q[-1], fast.nu[-1], tau=1.2 * star * sign)
    np.testing.assert_allclose([w.normal for w in f.wheels], N, rtol=1e-6)
    assert all(w.source == "rigid limit of compliance" for w in f.wheels)


def test_steady_turn_in_place_meets_the_icr_relation(husky):
    """The linear law's closed-form steady turn is a state of zero accelerations of the rigid chassis."""
    mod, _ = husky
    k, tau = 5.0, 2.0
    spec = mod.SPEC
    wheels = [replace(w, friction="linear", stiffness=k, slip_velocity=None, mu=None) for w in spec.wheels]
    robot = Robot(replace(spec, wheels=wheels))
    fn = float(pin.computeTotalMass(robot.model)) * 9.81 / 4
    phi = tau * (A**2 + B**2) / (R**2 * fn * k * A**2)
    omega = B * R * phi / (A**2 + B**2)
    nu = np.array([0.0, 0.0, omega, -phi, phi, -phi, phi])
    nudot = robot.forward_dynamics(robot.neutral(), nu, tau * np.array([-1.0, 1.0, -1.0, 1.0]))
    np.testing.assert_allclose(nudot, 0.0, atol=1e-9 * phi)
    assert (R * phi / omega) / B == pytest.approx(1 + (A / B) ** 2, rel=1e-12)  # the sides' ICR expansion


@pytest.mark.parametrize("name", ["husky_like", "jackal_like"])
def test_examples_turn_in_place_and_on_a_curve(name):
    mod = read(EXAMPLES / f"{name}.toml")
    robot = mod.robot()
    spin = mod.SCENARIOS["turn_in_place"].run(robot, t_end=0.3, n_out=4, progress=False)
    assert spin.column("yaw")[-1] > 0.01 and abs(spin.column("x")[-1]) < 0.05
    curve = mod.SCENARIOS["curve"].run(robot, t_end=0.3, n_out=4, progress=False)
    assert curve.column("x")[-1] > 0.01 and curve.column("yaw")[-1] > 0.005 and "event" not in curve.stats
    assert curve.stats["engine"].startswith("compiled")  # (tests/test_compiled_skid_slip.py: equal to scipy's)


def test_the_compiled_engine_runs_it(husky):
    """It used to refuse in one line ("statically indeterminate ... Python path"): the coupled solve is compiled
    (robotdyn/kernels/sliding_rigid_limit.hpp)."""
    mod, robot = husky
    from robotdyn.simulation.torque_profile import Constant

    traj = simulate(robot, 0.01, robot.neutral(), np.zeros(robot.mobility), Constant([-12.0, 12.0, -12.0, 12.0]),
                    engine="compiled", n_out=3, progress=False)
    assert traj.stats["engine"].startswith("compiled") and traj.column("yaw_dot")[-1] > 0


def test_a_wheel_the_rigid_limit_unloads_is_not_a_lift_off():
    """Centre of mass near the front-left corner: on equal springs the rear-right wheel would pull (the linear
    split W/4 (1 - x_G/a - y_G/b) < 0 for x_G/a + y_G/b > 1), so the rigid limit leaves it unloaded and the chassis
    rests on the other three, whose loads are then the three-wheel statics (derived here): with wheels 1 (a, b),
    2 (a, -b), 3 (-a, b),
        F1 + F2 + F3 = W,   a (F1 + F2 - F3) = W x_G,   b (F1 - F2 + F3) = W y_G.
    The run used to stop at t ~ 1e-6 s with 'lift-off of wheel rear_right'; the wheel is on the ground at zero load,
    so the base must turn in place for the whole run."""
    mod = read(EXAMPLES / "husky_like.toml", xacro_args={"com_x": "0.19", "com_y": "0.21"})
    robot = mod.robot()
    q = robot.neutral()
    data = robot.model.createData()
    G = pin.centerOfMass(robot.model, data, q)
    W = float(sum(inertia.mass for inertia in robot.model.inertias)) * 9.81
    assert G[0] / A + G[1] / B > 1.0  # the linear split would pull on the rear-right wheel
    F = np.linalg.solve([[1, 1, 1], [A, A, -A], [B, -B, B]], [W, W * G[0], W * G[1]])
    assert (F > 0).all()
    forces = robot.contact_forces(q, np.zeros(robot.mobility), tau=np.zeros(4))
    got = [forces.wheel(name).normal for name in ("front_left", "front_right", "rear_left", "rear_right")]
    assert np.allclose(got, [*F, 0.0], rtol=0, atol=1e-9 * W)
    spin = mod.SCENARIOS["turn_in_place"].run(robot, t_end=0.3, n_out=4, progress=False)
    assert "event" not in spin.stats and spin.t[-1] == pytest.approx(0.3)
    assert spin.stats["engine"].startswith("compiled")  # (the compiled active set: kernels/sliding_rigid_limit.hpp)
    assert spin.column("yaw")[-1] > 0.01


def test_derivatives_of_a_rigid_chassis_with_slipping_wheels_are_refused_saying_why(husky):
    """Forward dynamics splits the husky's open loads by the rigid limit solved with the friction; that coupled
    solve has no derivative rule: one line that says so (it used to say the load is not determined, which
    contact_forces contradicts)."""
    from robotdyn.errors import InputError

    _, robot = husky
    with pytest.raises(InputError, match="redundant normal row.*rigid limit") as info:
        robot.dynamics_derivatives(robot.neutral(), np.zeros(robot.mobility), np.zeros(4))
    assert "\n" not in str(info.value)

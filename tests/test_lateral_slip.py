"""Wheels that roll along their rolling direction and slide sideways (``slip = "lateral"``): the skid-steer rover of
examples/skid_steer.toml turning in place, against a closed form derived here from the power balance.

Closed form. Wheels at (+-a, +-b) in the chassis frame, radius r, equal loads f_n = m g / 4 (the oscillating front
axle's roll axis lies at ground level, and turning in place about the centre of mass makes no net lateral or
longitudinal force, so no load moves between wheels). Turning in place at yaw rate omega, wheel i's contact point
moves at (-omega y_i, omega x_i) with the chassis; rolling along t1 gives its spin rate phi_i = -omega y_i / r, and
its lateral slip is s_i = omega x_i. The kinetic energy is J omega^2 / 2 with J = s^T M s, s the full velocity per
unit yaw rate (M from Pinocchio's CRBA, s by hand). Power: the motors (-tau on the left, +tau on the right) give
4 tau b omega / r; the lateral friction F_i = -f_n c(s_i) gives sum_i F_i s_i. Hence

    J domega/dt = 4 tau b / r - 4 f_n a c(omega a),

with c(s) = k s (linear law) or mu s / sqrt(s^2 + v_s^2) (regularised Coulomb). The linear law gives
omega(t) = omega* (1 - exp(-t / T)), omega* = tau b / (r f_n k a^2), T = J / (4 f_n k a^2); the Coulomb law a scalar
ODE integrated here with scipy.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.interfaces.constraint_file import ConstraintFileError, read
from robotdyn.errors import InputError
from robotdyn.robot import Robot
from robotdyn.simulation.engine import simulate
from robotdyn.contact.sliding import forward as forward_sliding
from robotdyn.contact.sliding import inverse

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "skid_steer.toml"
A, B, R, G = 0.25, 0.22, 0.1, 9.81
SIDE = {"front_left": 1, "rear_left": 1, "front_right": -1, "rear_right": -1}  # sign of y_i
FRONT = {"front_left": 1, "front_right": 1, "rear_left": -1, "rear_right": -1}  # sign of x_i


def _rover(**wheel) -> Robot:
    mod = read(EXAMPLE)
    spec = replace(mod.SPEC, wheels=[replace(w, slip="lateral", **wheel) for w in mod.SPEC.wheels],
                   independent=["x", "y", "yaw"])
    return Robot(spec)


def _yaw_inertia(robot: Robot) -> float:
    """J = s^T M s with s the full velocity per unit yaw rate while turning in place (phi_i = -y_i / r)."""
    q = robot.neutral()
    s = np.zeros(robot.nq)
    s[robot.coordinate_index("yaw")] = 1.0
    for wheel, side in SIDE.items():
        s[robot.coordinate_index(f"{wheel}_spin")] = -side * B / R
    return float(s @ pin.crba(robot.model, robot.data, q) @ s)


def _torque(tau: float):
    return lambda t, q, nu: np.array([-tau, tau, -tau, tau])  # fl, fr, rl, rr


def test_rows_and_mobility():
    """A lateral-slip wheel keeps its longitudinal and normal rows: the rover moves in the plane (x, y, yaw)."""
    robot = _rover()
    labels = robot.rows_at(robot.neutral()).labels
    assert sorted(labels) == sorted(f"{w}.{row}" for w in SIDE for row in ("longitudinal", "normal"))
    assert robot.mobility == 3


def test_linear_law_turn_in_place_closed_form():
    robot = _rover()
    mass = sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))
    fn, k, tau = mass * G / 4, 5.0, 0.3
    J = _yaw_inertia(robot)
    omega_star, T = tau * B / (R * fn * k * A**2), J / (4 * fn * k * A**2)
    assert k * omega_star * A < 0.8  # below the law's saturation
    traj = simulate(robot, 0.2, robot.neutral(), np.zeros(3), _torque(tau), n_out=21, progress=False)
    omega = traj.column("yaw_dot")
    assert omega == pytest.approx(omega_star * (1 - np.exp(-traj.t / T)), rel=1e-7, abs=1e-12)
    drift = max(np.abs(traj.column("x_dot")).max(), np.abs(traj.column("y_dot")).max())
    assert drift < 1e-6 * omega_star * A  # it turns about its centre (the integrator's tolerance aside)
    # the wheels roll: phi_i = -y_i omega / r, and the energy balance closes with the friction work
    v = robot.velocity(traj.q[-1], traj.nu[-1])
    for wheel, side in SIDE.items():
        assert v[robot.coordinate_index(f"{wheel}_spin")] == pytest.approx(-side * B * omega[-1] / R, rel=1e-9)
    t = traj.t
    work = 4 * tau * B / R * omega_star * (t - T * (1 - np.exp(-t / T)))  # the integral of 4 tau b omega / r
    assert traj.energy - traj.energy[0] - traj.friction_work == pytest.approx(work, rel=1e-6, abs=1e-12)


@pytest.mark.parametrize("steady", [True, False])
def test_loads_forces_and_required_friction(steady):
    """Contact forces while turning: the lateral force is the law's -f_n k s_i at each wheel's own load, the yaw
    acceleration follows the power balance, and the required mu is the combined force over the load. In steady
    turning every wheel carries m g / 4 and pushes with tau / r (to O(omega^2) centripetal pitch terms, ~1e-7 here);
    while the yaw rate grows, the front axle's lateral acceleration at the axle height r above its roll pivot moves
    load across it (front loads differ by 2 m_front omegadot a r / (2 b), physics, not an error)."""
    robot = _rover()
    mass = sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))
    fn, k, tau = mass * G / 4, 5.0, 0.3
    omega = tau * B / (R * fn * k * A**2) if steady else 0.02
    forces = robot.contact_forces(robot.neutral(), [0.0, 0.0, omega], tau=[-tau, tau, -tau, tau])
    by_name = {w.name: w for w in forces.wheels}
    for wheel, front in FRONT.items():
        w = by_name[wheel]
        assert w.kind == "slipping" and w.load_determined
        assert w.force[1] == pytest.approx(-w.normal * k * omega * A * front, rel=1e-9)
        assert w.required_mu == pytest.approx(np.hypot(w.force[0], w.force[1]) / w.normal, rel=1e-12)
        if steady:
            assert w.normal == pytest.approx(fn, rel=1e-6)
            assert w.force[0] == pytest.approx(SIDE[wheel] * -tau / R, rel=1e-6)
    assert sum(w.normal for w in forces.wheels) == pytest.approx(mass * G, rel=1e-12)
    J = _yaw_inertia(robot)
    omegadot = (4 * tau * B / R - 4 * fn * A * k * omega * A) / J
    assert forces.nudot[2] == pytest.approx(omegadot, rel=1e-6, abs=1e-9)


def test_coulomb_law_turn_in_place():
    """Regularised Coulomb friction sideways: above the break-away torque mu f_n a r / b the rover spins up at the
    rate of the scalar power-balance ODE (integrated independently with scipy)."""
    from scipy.integrate import solve_ivp

    mu, vs, tau = 0.8, 1e-3, 8.0
    robot = _rover(friction="coulomb", stiffness=None, mu=mu, slip_velocity=vs)
    mass = sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))
    fn, J = mass * G / 4, _yaw_inertia(robot)
    assert tau > mu * fn * A * R / B
    traj = simulate(robot, 0.5, robot.neutral(), np.zeros(3), _torque(tau), n_out=11, progress=False)
    ref = solve_ivp(lambda t, w: [(4 * tau * B / R - 4 * fn * A * mu * w[0] * A / np.hypot(w[0] * A, vs)) / J],
                    (0, 0.5), [0.0], t_eval=traj.t, rtol=1e-12, atol=1e-14, method="LSODA")
    assert traj.column("yaw_dot") == pytest.approx(ref.y[0], rel=1e-6, abs=1e-9)
    assert np.all(np.diff(traj.friction_work) <= 1e-12)


def test_lateral_slip_needs_a_friction_law():
    mod = read(EXAMPLE)
    spec = replace(mod.SPEC, wheels=[replace(w, slip="lateral", friction="rolling", stiffness=None)
                                     for w in mod.SPEC.wheels], independent=None)
    with pytest.raises(InputError, match="slip"):
        Robot(spec)
    spec = replace(mod.SPEC, wheels=[replace(w, slip="sideways") for w in mod.SPEC.wheels], independent=None)
    with pytest.raises(InputError, match="sideways"):
        Robot(spec)
    spec = replace(mod.SPEC, wheels=[replace(w, slip="lateral", friction="stick_slip", stiffness=None)
                                     for w in mod.SPEC.wheels], independent=None)
    with pytest.raises(InputError, match="stick_slip"):
        Robot(spec)


def test_lateral_slip_from_toml(tmp_path):
    text = EXAMPLE.read_text().replace('urdf = "skid_steer.urdf.xacro"',
                                       f'urdf = "{EXAMPLE.parent / "skid_steer.urdf.xacro"}"')
    text = text.replace('independent = ["x", "y", "yaw", "front_left_spin", "front_right_spin", "rear_left_spin", '
                        '"rear_right_spin"]', 'independent = ["x", "y", "yaw"]')
    path = tmp_path / "lateral.toml"
    path.write_text(text.replace('friction = "linear"', 'friction = "linear"\nslip = "lateral"'))
    robot = read(path).robot()
    assert robot.mobility == 3
    path.write_text(text.replace('friction = "linear"', 'friction = "linear"\nslip = "sideway"'))
    with pytest.raises(ConstraintFileError, match="sideway"):
        read(path)


@pytest.mark.parametrize("slip", ["lateral", "both"])
def test_inverse_reproduces_forward(slip):
    """robotdyn.contact.sliding.inverse (torques and loads from the accelerations, least squares) against
    robotdyn.contact.sliding.forward (accelerations and loads from the torques, the coupled solve): at a turning state the
    accelerations of forward give back the same loads and the same generalised motor forces. With lateral slip the
    four torques are not all determined (each side's wheels roll on one line, so shifting torque between a side's
    front and rear wheel only changes their traction split: two free combinations), with free slip they are."""
    robot = _rover() if slip == "lateral" else read(EXAMPLE).robot()
    q = robot.neutral()
    nu = [0.1, -0.05, 0.3] if slip == "lateral" else [0.1, -0.05, 0.3, -2.0, 2.5, -2.2, 2.4]
    tau = np.array([-0.4, 0.7, -0.2, 0.5])
    fwd = forward_sliding(robot, q, np.asarray(nu, float), tau)
    a = fwd.reduced.S @ fwd.nudot + fwd.reduced.w
    inv = inverse(robot, q, fwd.reduced.v, a)
    assert inv.residual < 1e-9
    assert inv.normal == pytest.approx(fwd.normal, rel=1e-9)
    assert inv.force == pytest.approx(fwd.force, rel=1e-9, abs=1e-12)
    S, B = fwd.reduced.S, fwd.reduced.B
    assert B @ inv.tau == pytest.approx(B @ tau, rel=1e-9, abs=1e-12)
    if slip == "both":
        assert inv.rank == 8 and inv.tau == pytest.approx(tau, rel=1e-9)
    else:
        assert inv.rank == 10  # 12 unknowns: two combinations free
        assert inv.tau[[0, 2]].sum() == pytest.approx(tau[[0, 2]].sum(), rel=1e-9)  # each side's total is determined
        assert inv.tau[[1, 3]].sum() == pytest.approx(tau[[1, 3]].sum(), rel=1e-9)

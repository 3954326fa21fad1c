"""Joint springs and dampers (robotdyn.reduction.joint_springs) against closed forms, on the sprung car of
examples/sprung_car.urdf.xacro (a floating chassis on four vertical suspensions, wheels rolling without slipping):

- heave of a symmetric car released at zero suspension travel with unloaded springs: the wheels' contact rows hold
  the uprights at their height, so the chassis (mass m_s) is a mass on four parallel springs 4k and dampers 4c:
  z(t) = h - d (1 - e^{-s t} (cos(w_d t) + s/w_d sin(w_d t))), static deflection d = m_s g / (4 k),
  w_n = sqrt(4 k / m_s), s = 4 c / (2 m_s), w_d = sqrt(w_n^2 - s^2);
- energy: E(t) - E(0) = damper work at every sample (E counting the springs' energy), and braking:
  E(t) - E(0) = motor work + damper work, the constant brake torques doing the work tau (phi(t) - phi(0));
- braking load transfer (examples/sprung_car.toml as shipped): in steady deceleration a (constant pitch), the
  moment balance of the whole car about its centre of mass G (pitch axis y) with the wheels' spin angular momentum
  4 I_w v / R changing at -4 I_w a / R gives the front axle's load
  N_f = (m g (x_G - x_r) + m a h_G + 4 I_w a / R) / (x_f - x_r), x_f, x_r the axles' contact points, h_G the
  height of G: the load transfer m a h / wheelbase plus the wheels' spin term; and a = 4 tau / (R (m + 4 I_w / R^2)).
- one-line errors. The heave runs on the compiled engine where it is built (tests/test_compliant_compiled.py compares
  it with the scipy path).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.errors import InputError, RobotDynError
from robotdyn.reduction.joint_springs import JointSpring
from robotdyn.robot import Parameter, Robot, RobotSpec, Wheel
from robotdyn.simulation.engine import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CORNERS = ("front_left", "front_right", "rear_left", "rear_right")
M_S, H_CG, R, G = 1200.0, 0.55, 0.3, 9.81  # the xacro's defaults: chassis mass, its height, wheel radius


def car(k: float, c: float, rest: float = 0.0, lf: float = 1.3, lr: float = 1.3) -> Robot:
    spec = RobotSpec(name="car", title="sprung car", xacro=EXAMPLES / "sprung_car.urdf.xacro", root="floating",
                     parameters=[Parameter("g", G, "m/s^2", xacro=False)],
                     wheels=[Wheel(f"{n}_wheel", R, name=n) for n in CORNERS],
                     springs=[JointSpring(f"{n}_suspension", k, c, rest) for n in CORNERS],
                     independent=["x", "z", "pitch", "roll"], neutral={"z": H_CG},
                     xacro_args={"lf": str(lf), "lr": str(lr)})
    return Robot(spec)


@pytest.mark.parametrize("c", [0.0, 2.0e3])
def test_heave_static_deflection_and_frequency(c):
    k = 2.5e4
    robot = car(k, c)
    q0 = robot.neutral()
    traj = simulate(robot, 1.5, q0, np.zeros(4), n_out=301, rtol=1e-10, atol=1e-12, progress=False)
    d = M_S * G / (4 * k)
    wn, s = np.sqrt(4 * k / M_S), 4 * c / (2 * M_S)
    wd = np.sqrt(wn**2 - s**2)
    t = traj.t
    expected = H_CG - d * (1 - np.exp(-s * t) * (np.cos(wd * t) + s / wd * np.sin(wd * t)))
    z = traj.column("z")
    assert np.max(np.abs(z - expected)) < 1e-7 * d
    travel = traj.q[:, robot.coordinate_index("front_left_suspension")]
    assert np.max(np.abs(travel - (H_CG - z))) < 1e-12  # the wheel stays on the ground: travel = chassis sink
    # energy: E(t) - E(0) = damper work (<= 0), the springs' energy counted in E
    assert traj.damper_work is not None
    scale = abs(traj.energy[0]) + M_S * G * d
    assert np.max(np.abs(traj.energy - traj.energy[0] - traj.damper_work)) < 1e-8 * scale
    if c:
        assert traj.damper_work[-1] < -0.1 * M_S * G * d


def test_braking_load_transfer():
    from robotdyn.interfaces.constraint_file import read

    cf = read(EXAMPLES / "sprung_car.toml")
    robot, sc = cf.robot(), cf.SCENARIOS["brake"]
    q0, nu0 = sc.initial_state(robot)
    tau = np.asarray(sc.torque(0.0, q0, nu0), float)
    traj = simulate(robot, 3.5, q0, nu0, sc.torque, n_out=51, progress=False)  # (still rolling: 1.5 m/s)
    # energy at every sample: E(t) - E(0) = motor work + damper work; constant torques do the work tau * (spin angle)
    spins = [robot.coordinate_index(f"{n}_spin") for n in CORNERS]
    motor_work = (traj.q[:, spins] - traj.q[0, spins]) @ tau
    balance = traj.energy - traj.energy[0] - motor_work - traj.damper_work
    assert np.max(np.abs(balance)) < 1e-7 * abs(motor_work[-1])
    assert traj.damper_work[-1] < 0
    q, nu = traj.q[-1], traj.nu[-1]
    assert abs(nu[robot.velocity_names.index("pitch_dot")]) < 1e-8  # steady pitch: the moment balance holds
    m = pin.computeTotalMass(robot.model)
    I_w, brake = 0.6, -tau[0]  # the xacro's wheel spin inertia; the brake torque per wheel [N m]
    a = 4 * brake / (R * (m + 4 * I_w / R**2))
    xdot = traj.column("x_dot")
    assert np.gradient(xdot, traj.t)[-5:] == pytest.approx(-a, rel=1e-6)
    forces = robot.contact_forces(q, nu, tau=tau)
    G_ = pin.centerOfMass(robot.model, robot.data, q)
    wheels = {w.name: w for w in forces.wheels}
    x_f = wheels["front_left"].point[0]
    x_r = wheels["rear_left"].point[0]
    assert wheels["front_right"].point[0] == pytest.approx(x_f, abs=1e-12)
    n_front = wheels["front_left"].normal + wheels["front_right"].normal
    expected = (m * G * (G_[0] - x_r) + m * a * G_[2] + 4 * I_w * a / R) / (x_f - x_r)
    assert n_front == pytest.approx(expected, rel=1e-8)  # (the pitch transient has decayed to 1e-9 of it)
    static = m * G * (G_[0] - x_r) / (x_f - x_r)
    assert n_front - static > 0.1 * static  # a real transfer, not a rounding


@pytest.mark.parametrize("unit, stiffness, damping", [("rad", "N m/rad", "N m s/rad"), ("m", "N/m", "N s/m")])
def test_a_negative_spring_constant_is_refused_in_its_own_unit(unit, stiffness, damping):
    """The one-line refusal names the unit of the number refused (a damping's was written 'N m/rad s')."""
    from robotdyn.reduction.joint_springs import SpringForce

    with pytest.raises(InputError, match=rf"stiffness = -1\.0; expected a finite number >= 0 \[{stiffness}\]$"):
        SpringForce(JointSpring("hinge", stiffness=-1.0), 0, unit)
    with pytest.raises(InputError, match=rf"damping = -1\.0; expected a finite number >= 0 \[{damping}\]$"):
        SpringForce(JointSpring("hinge", damping=-1.0), 0, unit)

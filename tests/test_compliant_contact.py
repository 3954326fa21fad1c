"""Wheels that fly and land (robotdyn.contact.compliant_contact) against closed forms, on the disc of
tests/data/disc.urdf (height z, lean and spin below a planar root) standing upright:

- a disc thrown at the ground at v_in with gravity off lands on a linear spring-damper (k, c; zeta = c / (2 sqrt(k m))
  < 1/sqrt(2)): the penetration is x(t) = (v_in / w_d) e^{-s t} sin(w_d t) (s = zeta w_n, w_d = w_n sqrt(1 - zeta^2))
  until the force k x + c x' returns to zero, at w_d t* = pi - atan2(2 zeta sqrt(1 - zeta^2), 1 - 2 zeta^2) (the law
  never pulls: THIS is the end of the force; the penetration is still x(t*) > 0 there). The disc then leaves at
  the speed v_out = -x'(t*) and its penetration reaches zero at t* + x(t*) / v_out (the lift-off event's time after
  touch-down). Restitution e = v_out / v_in; energy lost m (v_in^2 - v_out^2) / 2 = -damper work. (If the contact
  could pull until the penetration returns to zero, e would be exp(-zeta pi / sqrt(1 - zeta^2)) and the contact
  pi / w_d: for zeta = 0.5 that is 0.163, against this law's larger e.) zeta = 0: e = 1, contact pi / w_n.
- Hunt-Crossley with no damping and n = 3/2 (Hertz): the contact lasts
  t_c = 2 (d_max / v_in) Gamma(7/5) sqrt(pi) / Gamma(9/10) = 2.9432 d_max / v_in, d_max = (5 m v_in^2 / (4 k))^(2/5).
- with gravity and a sliding landing (forward speed, no spin, Coulomb friction): E(t) - E(0) = friction work + damper
  work at every sample, both <= 0.
- the rigid limit: the sprung car braking on compliant tyres converges to the rigid-contact car (same tyre law)
  as the tyre stiffness k grows, its error falling like 1/k (the static deflection m g / (4 k)).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.special import gamma

from robotdyn.errors import InputError, RobotDynError
from robotdyn.reduction.joint_springs import JointSpring
from robotdyn.robot import Parameter, Robot, RobotSpec, Wheel
from robotdyn.simulation.engine import simulate

from compliant_disc import DISC, M, R, disc, landing, phases, state  # noqa: F401 (tests/compliant_disc.py)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("engine", ["auto", "scipy"])  # the compiled engine where built; the Python path (LSODA)
@pytest.mark.parametrize("zeta", [0.0, 0.2, 0.5])
def test_landing_on_a_linear_spring_damper(zeta, engine):
    k, v_in, gap = 2.0e4, 1.0, 0.01
    c = 2 * zeta * np.sqrt(k * M)
    robot = disc(normal_stiffness=k, normal_damping=c)
    q0, nu0 = state(robot, R + gap, -v_in)
    traj = simulate(robot, 0.1, q0, nu0, n_out=101, rtol=1e-10, atol=1e-13, progress=False, engine=engine)
    contact, v_out = landing(k, zeta, v_in)  # tests/compliant_disc.py
    ev = phases(traj)
    assert ev["touch-down"] == pytest.approx([gap / v_in], abs=1e-9)
    assert len(ev["lift-off"]) == 1
    assert ev["lift-off"][0] - ev["touch-down"][0] == pytest.approx(contact, rel=1e-7)
    e = traj.column("z_dot")[-1] / v_in
    assert e == pytest.approx(v_out / v_in, rel=1e-7)
    if zeta == 0.0:
        assert e == pytest.approx(1.0, abs=1e-8) and contact == pytest.approx(np.pi / np.sqrt(k / M))
    else:
        assert e > np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))  # the no-pull law rebounds more (see the module)
    lost = 0.5 * M * (v_in**2 - v_out**2)
    assert -traj.damper_work[-1] == pytest.approx(lost, rel=1e-7, abs=1e-12)
    assert np.max(np.abs(traj.energy - traj.energy[0] - traj.damper_work - traj.friction_work)) < 1e-8 * M * v_in**2


def test_hertz_contact_time_of_hunt_crossley():
    k, v_in, gap = 1.0e6, 0.5, 0.005
    robot = disc(normal_stiffness=k, normal_damping=0.0, contact_law="hunt_crossley", contact_exponent=1.5)
    q0, nu0 = state(robot, R + gap, -v_in)
    traj = simulate(robot, 0.04, q0, nu0, n_out=41, rtol=1e-10, atol=1e-13, progress=False)
    d_max = (5 * M * v_in**2 / (4 * k)) ** 0.4
    t_c = 2 * d_max / v_in * gamma(1.4) * np.sqrt(np.pi) / gamma(0.9)
    ev = phases(traj)
    assert ev["lift-off"][0] - ev["touch-down"][0] == pytest.approx(t_c, rel=1e-6)
    assert traj.column("z_dot")[-1] == pytest.approx(v_in, rel=1e-7)  # elastic: e = 1


def test_energy_balance_sliding_landing_with_gravity():
    """E(t) - E(0) = motor work + friction work + damper work at every sample; the motor on the spin joint applies a
    constant torque, whose work is tau (spin(t) - spin(0)) exactly."""
    from robotdyn.robot import MotorSpec
    from robotdyn.simulation.torque_profile import Constant

    robot = disc(g=9.81, motors=[MotorSpec("m", "spin")], normal_stiffness=5.0e4, normal_damping=60.0)
    q0, nu0 = state(robot, R + 0.02, 0.0, vx=1.0)
    tau = 0.8
    traj = simulate(robot, 0.4, q0, nu0, Constant([tau]), n_out=201, rtol=1e-10, atol=1e-13, progress=False)
    spin = traj.q[:, robot.coordinate_index("spin")]
    motor = tau * (spin - spin[0])
    assert motor[-1] > 0.1
    balance = traj.energy - traj.energy[0] - motor - traj.friction_work - traj.damper_work
    assert np.max(np.abs(balance)) < 1e-7 * abs(traj.energy[0])
    assert traj.friction_work[-1] < -1e-3 and traj.damper_work[-1] < -1e-3
    assert np.all(np.diff(traj.friction_work) <= 1e-12) and np.all(np.diff(traj.damper_work) <= 1e-12)
    assert len(phases(traj)["touch-down"]) >= 1


def test_rigid_limit_sliding_disc_over_a_bump():
    """The disc sliding (no spin, Coulomb mu = 0.2) at 1.5 m/s over a smooth 3 cm bump, its normal load changing
    with the terrain's curvature: the compliant disc (k, damping ratio 0.5, started at its static deflection)
    converges to the rigid-contact disc (same law) as k grows. The velocity error falls at least like 1/k
    (measured: x4 in k divides it by 7.4 then 6.6); the height error is about the static deflection m g / k."""
    from robotdyn.constraints.terrain import BumpTerrain

    def robot(**contact):
        spec = RobotSpec(name="disc", title="disc", xacro=DISC, root="planar",
                         wheels=[Wheel("disc", R, friction="coulomb", mu=0.2, **contact)],
                         parameters=[Parameter("g", 9.81, "m/s^2", xacro=False)])
        return Robot(spec, terrain=BumpTerrain(0.03, 0.4, 0.15))

    def run(r, dz=0.0):
        q0 = np.zeros(r.nq)
        q0[r.coordinate_index("x")] = -0.6
        q0[r.coordinate_index("z")] = R + r.terrain.height(-0.6, 0.0) - dz
        v0 = np.zeros(r.nq)
        v0[r.coordinate_index("x")] = 1.5
        traj = simulate(r, 1.0, q0, v0[r.independent_indices], n_out=2, rtol=1e-9, atol=1e-12, progress=False)
        return traj.q[-1], r.velocity(traj.q[-1], traj.nu[-1])

    rigid = robot()
    q_r, v_r = run(rigid)
    assert q_r[rigid.coordinate_index("x")] > 0.55  # past the bump
    errors = []
    for k in (1e4, 4e4, 1.6e5):
        r = robot(contact="compliant", normal_stiffness=k, normal_damping=2 * 0.5 * np.sqrt(k * M))
        q, v = run(r, M * 9.81 / k)
        errors.append(np.max(np.abs(v - v_r)))
        assert r.coordinate_index("z") == rigid.coordinate_index("z")
        assert q[r.coordinate_index("z")] - q_r[r.coordinate_index("z")] == pytest.approx(-M * 9.81 / k, rel=0.05)  # (the load there: m g + curvature)
    assert errors[0] < 1e-3 * 1.5
    assert errors[0] / errors[1] > 3.5 and errors[1] / errors[2] > 3.5

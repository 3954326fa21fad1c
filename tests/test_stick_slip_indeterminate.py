"""Exact stick-slip on a statically indeterminate chassis (issue 23, item 2): a rigid four-wheel base
(examples/husky_like.urdf.xacro: wheels at x = +-L/2, y = +-b, radius R, no suspension) whose wheels stick or
slide (friction = "stick_slip", mu = 0.6). Its normal loads are the rigid limit of the wheels' normal compliance
(equal stiffnesses), and the sticking wheels whose lateral forces rigid-body dynamics leave open stick while some
admissible split keeps each in its cone (robotdyn.contact.sticking_cone).

Closed forms derived here (g = 9.81, chassis mass m_c with its centre of mass x_c ahead of the axles' middle at
height h above the ground, wheels of mass m_w and axle inertia I_w = m_w R^2 / 2, M = m_c + 4 m_w, L = wheelbase):

- Driven car, all wheels sticking, torque tau = c t on each rear wheel. Rolling: (M + 4 I_w / R^2) a = 2 tau / R;
  a rear wheel's ground force F = (tau - I_w a / R) / R. Moments about the rear contact line (the rate of angular
  momentum: chassis h m_c a, wheels R m_w a each, spins I_w alpha_i) give the rear axle's load
  N_r L = m_c g l_f + 2 m_w g L + a (m_c h + 4 m_w R) + sum_i I_w alpha_i, l_f = L/2 - x_c, alpha_i = a / R.
  Equal stiffnesses split it equally between the two rear wheels (symmetry). The rear wheels start to slide when
  F = mu N_r / 2: both sides are linear in tau, so tau* = mu N_0 / (k_F - mu k_N) with N_r / 2 = N_0 + k_N tau,
  F = k_F tau; t* = tau* / c. Before t*: kinetic energy = motor work = c^2 t^4 / (2 R^2 (M + 4 I_w / R^2)).
  Sliding (rear wheels), at torque tau: I_w alpha_r = tau - R mu N_r / 2, (M + 2 I_w / R^2) a = mu N_r, and the
  moment balance above with sum_i I_w alpha_i = 2 I_w a / R + 2 I_w alpha_r: three linear equations.
- Skid steer turning in place, torques -tau (left) and +tau (right), centre of mass over the middle: at rest every
  wheel carries N = M g / 4 and the longitudinal force tau / R (no spin), whose yaw moment 4 b tau / R the lateral
  forces balance: front and rear axles carry -+ 2 b tau / (a R) with a = L / 2, split inside each axle by static
  friction. The best split is the equal one, so the wheels stick iff (tau / R) sqrt(1 + b^2 / a^2) <= mu N, i.e.
  tau <= tau* = mu N R a / sqrt(a^2 + b^2): the Coulomb threshold of turning in place
  (tests/test_skid_steer_rigid.py). Above it all four wheels slide from the start.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from robotdyn.contact.sticking_cone import check
from robotdyn.contact.traction import traction
from robotdyn.interfaces.constraint_file import read
from robotdyn.robot import Robot
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.torque_profile import Constant

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
L, B, R, MU, G = 0.512, 0.2775, 0.165, 0.6, 9.81
MC, MW, XC, H = 46.0, 2.6, 0.08, 0.165 + 0.06
M, IW = MC + 4 * MW, MW * R**2 / 2
SIGN = np.array([-1.0, 1.0, -1.0, 1.0])


def base(com_x: float = 0.0) -> Robot:
    spec = read(EXAMPLES / "husky_like.toml").SPEC
    wheels = [replace(w, friction="stick_slip", mu=MU, slip_velocity=None) for w in spec.wheels]
    return Robot(replace(spec, wheels=wheels, independent=None, xacro_args={"com_x": str(com_x)}))


def rear_load(a: float, spins: float) -> float:
    """N_r [N] from the moments about the rear contact line (spins = sum_i I_w alpha_i)."""
    return (MC * G * (L / 2 - XC) + 2 * MW * G * L + a * (MC * H + 4 * MW * R) + spins) / L


def sliding(tau: float) -> tuple[float, float, float]:
    """(a, alpha_r, N_r) with the rear wheels sliding at torque tau."""
    K = np.array([[0.0, IW, R * MU / 2],
                  [M + 2 * IW / R**2, 0.0, -MU],
                  [-(MC * H + 4 * MW * R + 2 * IW / R), -2 * IW, L]])
    return tuple(np.linalg.solve(K, [tau, 0.0, MC * G * (L / 2 - XC) + 2 * MW * G * L]))


def test_driven_car_starts_to_slip_at_the_closed_form():
    robot = base(XC)
    c = 200.0
    a1 = 2 / (R * (M + 4 * IW / R**2))  # a = a1 tau while rolling
    kF = (1 - IW * a1 / R) / R
    N0 = rear_load(0.0, 0.0) / 2
    kN = (rear_load(a1, 4 * IW * a1 / R) / 2 - N0)
    t_star = MU * N0 / (kF - MU * kN) / c  # 0.0717 s
    torque = lambda t, q, nu: np.array([0.0, 0.0, c * t, c * t])  # noqa: E731
    t_end = t_star + 2e-8  # the switch, and the slide's first instant (slip below 1e-12 m/s: no stiff sliding yet)
    traj = simulate(robot, t_end, robot.neutral(), np.zeros(robot.nq), torque, n_out=21, progress=False)
    switches = traj.stats["switches"]
    assert [(s["wheel"], s["phase"]) for s in switches] == [("rear_left", "slide"), ("rear_right", "slide")]
    assert all(s["t"] == pytest.approx(t_star, rel=1e-8) for s in switches)
    t = traj.t[:-1]  # rolling: x = a1 c t^3 / 6, energy = motor work, no friction work
    np.testing.assert_allclose(traj.column("x")[:-1], a1 * c * t**3 / 6, rtol=1e-8, atol=1e-13)
    np.testing.assert_allclose(traj.energy[:-1] - traj.energy[0], c**2 * t**4 / (2 * R**2 * (M + 4 * IW / R**2)),
                               rtol=1e-8, atol=1e-12)
    assert np.all(traj.friction_work[:-1] == 0.0) and abs(traj.friction_work[-1]) < 1e-12
    # sliding at mu N, with the loads of the coupled solve (rigid limit, friction moment included)
    tau = c * t_end
    a, alpha_r, Nr = sliding(tau)
    nu = traj.nu[-1][robot.independent_indices]  # the full velocities v
    f = robot.contact_forces(traj.q[-1], nu, tau=np.array([0.0, 0.0, tau, tau]))
    for name in ("rear_left", "rear_right"):
        w = f.wheel(name)
        assert w.normal == pytest.approx(Nr / 2, rel=1e-9)
        assert w.force[0] == pytest.approx(MU * Nr / 2, rel=1e-9) and abs(w.force[1]) < 1e-9
    assert sum(w.normal for w in f.wheels) == pytest.approx(M * G, rel=1e-12)
    assert robot.forward_dynamics(traj.q[-1], nu, np.array([0.0, 0.0, tau, tau]))[
        robot.velocity_names.index("rear_left_wheel_dot")] == pytest.approx(alpha_r, rel=1e-9)
    assert alpha_r > a / R  # the driven wheels spin up faster than the car: they slip
    # the traction report of the run (robotdyn.contact.traction): the same slip onset, the phases, the loads
    tr = traction(robot, traj, torque)
    assert [(e.kind, e.wheel) for e in tr.events] == [("slide", "rear_left"), ("slide", "rear_right")]
    assert all(e.t == pytest.approx(t_star, rel=1e-8) for e in tr.events)
    rear = [tr.wheels.index(w) for w in ("rear_left", "rear_right")]
    assert not tr.phases[:-1].any() and tr.phases[-1, rear].all() and tr.phases[-1].sum() == 2
    for j in rear:  # rolling: N_r / 2, linear in the torque
        np.testing.assert_allclose(tr.normal[:-1, j], N0 + kN * c * t, rtol=1e-9)
    np.testing.assert_allclose(tr.normal[-1, rear], Nr / 2, rtol=1e-9)  # sliding: the three-equation closed form
    np.testing.assert_allclose(tr.tangential[-1, rear], MU * Nr / 2, rtol=1e-9)
    assert "holds" not in tr.summary()

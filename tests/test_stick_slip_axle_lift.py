"""A rigid four-wheel car whose front axle slides and then lifts (issue 23): examples/husky_like.urdf.xacro with
stick-slip wheels, front mu_f = 0.3, rear mu_r = 2.0, a torque tau = c t on each rear wheel. The coupled solve of
accelerations, loads and friction on this statically indeterminate chassis once stopped here with "Painleve
paradox ... condition 4e17" at the first integrator stage past the front axle's lift-off: both front loads came
out negative, the rigid-limit split held both at zero although only one load-moving direction (the warp) is
open, and that system is singular by construction. It is no Painleve case; the run must stop at the lift-off.

Closed forms of the planar car (g, chassis mass m_c with its centre of mass over the axles' middle at height h,
wheels of mass m_w, radius R, axle inertia I_w = m_w R^2 / 2, M = m_c + 4 m_w, wheelbase L; loads and forces are
per axle; tests/test_stick_slip_indeterminate.py derives the rolling ones):

- Moments about the front contact line (the ground forces have no arm there): N_r L = W_0 + a c_1 + sum_i I_w
  alpha_i, W_0 = m_c g L / 2 + 2 m_w g L, c_1 = m_c h + 4 m_w R; N_f = M g - N_r.
- All rolling: a = a_1 tau, a_1 = 2 / (R (M + 4 I_w / R^2)), alpha_i = a / R; a front wheel's ground force is
  I_w a / R^2 (backwards: it spins the wheel up). The front wheels slide when 2 I_w a / R^2 = mu_f N_f (tau_s).
- Front sliding forwards (friction -mu_f N_f), rear rolling: (M + 2 I_w / R^2) a + mu_f N_f = 2 tau / R, and with
  2 I_w alpha_f = R mu_f N_f: (c_1 + 2 I_w / R) a + (L + R mu_f) N_f = M g L - W_0. Its determinant
  D = (M + 2 I_w / R^2)(L + R mu_f) - mu_f (c_1 + 2 I_w / R) is the front contact's effective normal stiffness
  (the LCP's coefficient): unique solution iff D > 0, i.e. mu_f < mu_P = (M + 2 I_w / R^2) L / (m_c (h - R)) =
  10.9 here. mu_f = 0.3 is far from the Painleve paradox.
- Lift-off: N_f = 0 gives a* = (M g L - W_0) / (c_1 + 2 I_w / R), tau* = R (M + 2 I_w / R^2) a* / 2.
- Energy: E - E_0 = motor work (2 tau v / R, the rear wheels rolling) + friction work (-mu_f N_f times the front
  slip speed v - R omega_f), each a polynomial in t here.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.polynomial import Polynomial as P

from robotdyn.contact.sliding import forward
from robotdyn.contact.stick_slip_wheel import configure
from robotdyn.errors import SingularConstraintError
from robotdyn.interfaces.constraint_file import read
from robotdyn.robot import Robot
from robotdyn.simulation.engine import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
L, R, G = 0.512, 0.165, 9.81
MC, MW, H = 46.0, 2.6, 0.165 + 0.06
M, IW = MC + 4 * MW, MW * R**2 / 2
MU_F, MU_R = 0.3, 2.0
W0, C1 = MC * G * L / 2 + 2 * MW * G * L, MC * H + 4 * MW * R
MP = M + 2 * IW / R**2
A1 = 2 / (R * (M + 4 * IW / R**2))
SLIDE = np.array([[MP, MU_F], [C1 + 2 * IW / R, L + R * MU_F]])  # (a, N_f) with the front axle sliding


def car(mu_f: float = MU_F) -> Robot:
    spec = read(EXAMPLES / "husky_like.toml").SPEC
    mu = {"front_left": mu_f, "front_right": mu_f, "rear_left": MU_R, "rear_right": MU_R}
    wheels = [replace(w, friction="stick_slip", mu=mu[w.name], slip_velocity=None) for w in spec.wheels]
    return Robot(replace(spec, wheels=wheels, independent=None))


def front_sliding_at_rest(robot: Robot, tau: float):
    """The coupled solve with the front wheels sliding forwards, at rest in the neutral pose, rear torques tau."""
    for w in robot.constraints[:2]:
        w.set_phase("slide", np.array([1.0, 0.0]))
    q = robot.neutral()
    configure(robot, q)
    return forward(robot, q, np.zeros(len(robot.independent_indices)), np.array([0.0, 0.0, tau, tau]))


def sliding(tau: float) -> np.ndarray:
    """(a, N_f) with the front axle sliding at rear torque tau per wheel."""
    return np.linalg.solve(SLIDE, [2 * tau / R, M * G * L - W0])


def test_painleve_only_at_the_closed_form_mu():
    """The model's coupled solve is singular exactly at mu_P = 10.945 (D = 0) and gives the closed-form loads at
    mu_P (1 - 1e-7) (huge, positive); above mu_P (D < 0: no or two solutions) it refuses in one line naming the
    front wheels, mu and the threshold (robotdyn.contact.painleve on the rigid limit's one load direction of the
    front axle) instead of returning the negative loads. mu_f = 0.3 is far below it. Sliding backwards
    (friction +mu N_f, mu -> -mu in the closed form: D > 0 at every mu) it is no Painleve case at 2 mu_P."""
    mu_p = MP * L / (MC * (H - R))
    assert mu_p == pytest.approx(10.945, abs=1e-3) and MU_F < mu_p / 30
    with pytest.raises(SingularConstraintError, match="Painleve"):
        front_sliding_at_rest(car(mu_p), 10.0)
    closed = lambda mu: np.linalg.solve([[MP, mu], [C1 + 2 * IW / R, L + R * mu]], [20.0 / R, M * G * L - W0])  # noqa
    mu = mu_p * (1 - 1e-7)
    nf = closed(mu)[1]
    assert nf > 1e9
    np.testing.assert_allclose(front_sliding_at_rest(car(mu), 10.0).normal, [nf / 2, nf / 2], rtol=1e-5)
    for factor in (1 + 1e-7, 1 + 1e-3):
        with pytest.raises(SingularConstraintError) as exc:
            front_sliding_at_rest(car(mu_p * factor), 10.0)
        assert str(exc.value).startswith(f"sliding wheels front_left, front_right (mu = {mu_p * factor:g}): "
                                         "Painleve paradox, their friction presses them into the ground")
        assert f"; mu_P = {mu_p:.6g} for this sliding direction;" in str(exc.value)
    robot = car(2 * mu_p)
    for w in robot.constraints[:2]:
        w.set_phase("slide", np.array([-1.0, 0.0]))
    q = robot.neutral()
    configure(robot, q)
    st = forward(robot, q, np.zeros(len(robot.independent_indices)), np.array([0.0, 0.0, 10.0, 10.0]))
    nf = closed(-2 * mu_p)[1]
    assert 0 < nf < M * G
    np.testing.assert_allclose(st.normal, [nf / 2, nf / 2], rtol=1e-9)


def test_coupled_solve_past_the_lift_off_gives_the_pulling_loads():
    """Front wheels sliding, at rest, tau above tau*: no split keeps both front loads >= 0; the solve returns the
    compatible loads (each N_f / 2 < 0, from the closed form) for the lift-off event (it raised Painleve before)."""
    robot = car()
    tau = 60.0  # tau* = 55.18 N m
    st = front_sliding_at_rest(robot, tau)
    a, nf = sliding(tau)
    assert nf < 0 and st.unloaded == ()
    np.testing.assert_allclose(st.normal, [nf / 2, nf / 2], rtol=1e-9)
    np.testing.assert_allclose(st.force[:, 0], -MU_F * nf / 2, rtol=1e-9)
    rate = dict(zip(robot.velocity_names, st.nudot))
    assert rate["rear_left_wheel_dot"] == pytest.approx(a / R, rel=1e-9)  # the rear wheels roll
    assert rate["front_left_wheel_dot"] == pytest.approx(R * MU_F * nf / (2 * IW), rel=1e-9)


def test_front_axle_slides_then_lifts_at_the_closed_forms():
    robot = car()
    c = 2000.0
    nf_roll = lambda tau: M * G - (W0 + A1 * tau * (C1 + 4 * IW / R)) / L  # noqa: E731
    tau_s = MU_F * nf_roll(0.0) / (2 * IW * A1 / R**2 - MU_F * (nf_roll(1.0) - nf_roll(0.0)))
    a_star = (M * G * L - W0) / (C1 + 2 * IW / R)
    tau_star = R * MP * a_star / 2
    t_s, t_star = tau_s / c, tau_star / c  # 0.020730 s, 0.027588 s
    torque = lambda t, q, nu: np.array([0.0, 0.0, c * t, c * t])  # noqa: E731
    traj = simulate(robot, 0.03, robot.neutral(), np.zeros(robot.nq), torque, n_out=31, progress=False)
    assert [(s["wheel"], s["phase"]) for s in traj.stats["switches"]] == [("front_left", "slide"),
                                                                          ("front_right", "slide")]
    assert all(s["t"] == pytest.approx(t_s, rel=1e-8) for s in traj.stats["switches"])
    lift = traj.stats["lift_off"]
    assert lift["wheel"].startswith("front_") and lift["t"] == pytest.approx(t_star, rel=1e-8)
    assert "Painleve" not in traj.stats["event"] and "compliant" in traj.stats["event"]
    # velocity, positions and work as polynomials in t: rolling up to t_s, front sliding after
    t = traj.t
    assert t[-1] < t_star < t[-1] + 1e-3
    a_roll = P([0.0, A1 * c])
    (p0, _), (p1, _) = sliding(0.0), sliding(1.0) - sliding(0.0)  # a = p0 + p1 tau while sliding
    n0, n1 = sliding(0.0)[1], (sliding(1.0) - sliding(0.0))[1]  # N_f = n0 + n1 tau
    v_roll = a_roll.integ()
    a_sl = P([p0, p1 * c])
    v_sl = a_sl.integ(lbnd=t_s, k=v_roll(t_s))
    nf = P([n0, n1 * c])
    w_f = (R * MU_F * nf / (2 * IW)).integ(lbnd=t_s, k=v_roll(t_s) / R)  # front spin: 2 I_w alpha_f = R mu N_f
    motor = lambda v: (P([0.0, 2 * c / R]) * v)  # noqa: E731  (2 tau v / R)
    wm_roll = motor(v_roll).integ()
    wm_sl = motor(v_sl).integ(lbnd=t_s, k=wm_roll(t_s))
    wf_sl = (-MU_F * nf * (v_sl - R * w_f)).integ(lbnd=t_s)
    x_roll = v_roll.integ()
    x_sl = v_sl.integ(lbnd=t_s, k=x_roll(t_s))
    before = t < t_s
    x = np.where(before, x_roll(t), x_sl(t))
    work_motor = np.where(before, wm_roll(t), wm_sl(t))
    work_friction = np.where(before, 0.0, wf_sl(t))
    np.testing.assert_allclose(traj.column("x"), x, rtol=1e-8, atol=1e-13)
    np.testing.assert_allclose(traj.friction_work, work_friction, rtol=1e-7, atol=1e-12)
    assert work_friction[-1] < -4e-4  # 0.45 mJ
    np.testing.assert_allclose(traj.energy - traj.energy[0], work_motor + traj.friction_work, rtol=1e-8, atol=1e-10)
    # the loads of the sliding phase: each front wheel N_f / 2 with friction mu_f N_f / 2
    i = int(np.flatnonzero(~before)[-1])
    tau = c * t[i]
    nu = traj.nu[i][robot.independent_indices]
    f = robot.contact_forces(traj.q[i], nu, tau=np.array([0.0, 0.0, tau, tau]))
    for name in ("front_left", "front_right"):
        w = f.wheel(name)
        assert w.normal == pytest.approx(sliding(tau)[1] / 2, rel=1e-9)
        assert -w.force[0] == pytest.approx(MU_F * w.normal, rel=1e-9)


def test_shipped_coulomb_car_lifts_its_front_axle_instead_of_a_painleve_error():
    """The same bug on examples/husky_like.toml as shipped (a regularised Coulomb law, mu = 0.6, on all four
    wheels, so all slip): under a rear torque 20000 t per wheel it raised "Painleve ... condition 6e18". Now it stops
    at the front axle's lift-off, and at every sample before it the front axle's load is the moment balance about
    the front contact line, N_f = M g - (W_0 + a c_1 + I_w sum_i alpha_i) / L, with the model's accelerations."""
    from robotdyn.simulation.torque_profile import Polynomial

    robot = Robot(read(EXAMPLES / "husky_like.toml").SPEC)
    c = 20000.0
    torque = Polynomial([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, c, c]])
    traj = simulate(robot, 0.005, robot.neutral(), np.zeros(robot.mobility), torque, n_out=11, progress=False,
                    engine="scipy")
    assert traj.stats["event"].startswith("wheel front_left unloads at t = 0.0031") and "Painleve" not in \
        traj.stats["event"]
    assert traj.t[-1] < traj.stats["t_event"] < traj.t[-1] + 5e-4
    names = robot.velocity_names
    spins = [names.index(f"{w}_wheel_dot") for w in ("front_left", "front_right", "rear_left", "rear_right")]
    last = None
    for t, q, nu in zip(traj.t[1:], traj.q[1:], traj.nu[1:]):
        tau = torque(t, q, nu)
        acc = robot.forward_dynamics(q, nu, tau)
        f = robot.contact_forces(q, nu, tau=tau)
        front = f.wheel("front_left").normal + f.wheel("front_right").normal
        closed = M * G - (W0 + acc[names.index("x_dot")] * C1 + IW * np.sum(acc[spins])) / L
        assert front == pytest.approx(closed, rel=1e-8)
        last = front
    assert 0 < last < 0.3 * M * G

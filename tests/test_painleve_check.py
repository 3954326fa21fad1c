"""The Painleve check of sliding wheels (robotdyn.contact.painleve, its compiled twin kernels/painleve.hpp): above
the threshold the contact problem has no or two solutions, and both engines refuse the state in one line naming
the wheel, its mu and the threshold mu_P; below it they give the closed-form loads.

The planar car: a bicycle-like chassis on a floating root, one front wheel that slides (exact Coulomb: a linear
tyre saturated at mu), one rear wheel that rolls; both centred (y = 0), so that the loads are determined (no
redundant row: the compiled engine runs it) and, at this instant, the motion stays in the vertical plane x-z.
Chassis of mass m_c, its centre of mass at height h over the point L_f behind the front axle; wheels of mass m_w,
radius R, axle inertia I_w; M = m_c + 2 m_w, wheelbase L = L_f + L_r. At rest, the front wheel spinning backwards so
that it slides forwards (slip s = -R omega_f > 0: friction -mu N_f), a torque tau on the rear wheel; unknowns a
(the forward acceleration), N_f, N_r, the rear ground force F_r and alpha_f:

- Front wheel: I_w alpha_f = R mu N_f (its friction spins it up). Rear wheel (rolling, alpha_r = a / R):
  I_w a / R = tau - R F_r. Horizontal momentum: M a = F_r - mu N_f, so (M + I_w / R^2) a + mu N_f = tau / R.
- Moments about the front contact line (its ground forces have no arm there; the rear ground force acts at ground
  level, the bodies' momenta m a at their heights): L N_r - L_f m_c g - L m_w g = (m_c h + 2 m_w R) a +
  I_w alpha_f + I_w a / R, with N_f = M g - N_r:
  (c_1 + I_w / R) a + (L + R mu) N_f = M g L - W_0, c_1 = m_c h + 2 m_w R, W_0 = L_f m_c g + L m_w g.
- The determinant D(mu) = (M + I_w / R^2)(L + R mu) - mu (c_1 + I_w / R) = (M + I_w / R^2) L - mu m_c (h - R)
  (R M - c_1 = -m_c (h - R)) is the front contact's effective normal coefficient times a positive factor: the loads
  are unique and consistent iff D > 0, i.e. mu < mu_P = (M + I_w / R^2) L / (m_c (h - R)) (the four-wheel car's
  formula of tests/test_stick_slip_axle_lift.py with one wheel per axle). Here mu_P = (44 + 1) 0.6 / (40 * 0.2) =
  3.375 exactly.
- Sliding backwards (s < 0: friction +mu N_f, the spin-up reversed) the same balances hold with mu -> -mu:
  D = (M + I_w / R^2) L + mu m_c (h - R) > 0 at every mu: the friction lifts the front; no Painleve case.

Several sliding wheels: the tricycle (the rear axle's two wheels slip sideways, slip = "lateral"): D is a 3 x 3
matrix; both engines refuse the same states with the same line, and the threshold it names is where the verdict
flips.
"""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.contact.sliding import forward
from robotdyn.errors import SingularConstraintError
from robotdyn.fast.dispatch import compiled_model
from robotdyn.interfaces.constraint_file import read
from robotdyn.simulation import simulate
from robotdyn.simulation.torque_profile import Constant

G = 9.81
MC, MW, R, H = 40.0, 2.0, 0.15, 0.35
LF, LR, B = 0.3, 0.3, 0.25
L = LF + LR
IW = MW * R**2 / 2
M = MC + 2 * MW
MP = M + IW / R**2
C1 = MC * H + 2 * MW * R
W0 = LF * MC * G + L * MW * G
MU_P = MP * L / (MC * (H - R))
TAU = 1.0
SPIN = -2.0  # the front wheel's spin [rad/s] at rest: it slides forwards at 0.3 m/s


def _wheel(joint: str, x: float, y: float) -> str:
    link = f"{joint}_wheel"
    return (f'<link name="{link}"><inertial><mass value="{MW}"/><inertia ixx="{IW / 2}" iyy="{IW}" izz="{IW / 2}" '
            f'ixy="0" ixz="0" iyz="0"/></inertial></link>'
            f'<joint name="{joint}" type="continuous"><parent link="base_link"/><child link="{link}"/>'
            f'<origin xyz="{x} {y} 0"/><axis xyz="0 1 0"/></joint>')


def _robot(tmp_path, mu: float, rear: dict):
    """The bicycle (rear = {"rear": 0.0}) or the tricycle (rear = {"rear_left": B, "rear_right": -B}): the front
    wheel slides under a saturated linear tyre (exact Coulomb), the rear wheels roll (bicycle) or slip sideways."""
    urdf = (f'<robot name="cycle"><link name="base_link"><inertial><origin xyz="0 0 {H - R}"/><mass value="{MC}"/>'
            f'<inertia ixx="1" iyy="2" izz="2.5" ixy="0" ixz="0" iyz="0"/></inertial></link>'
            + _wheel("front", LF, 0.0) + "".join(_wheel(j, -LR, y) for j, y in rear.items()) + "</robot>")
    (tmp_path / "cycle.urdf").write_text(urdf)
    lateral = len(rear) > 1
    law = '\nfriction = "linear"\nstiffness = 10.0\nslip = "lateral"' if lateral else ""
    wheels = "".join(f'[[wheels]]\njoint = "{j}"\nradius = {R}{law}\n[[motors]]\nname = "tau_{j}"\njoint = "{j}"\n'
                     for j in rear)
    independent = '["x", "y", "yaw", "front"]' if lateral else '["x", "roll", "yaw", "front"]'
    path = tmp_path / "cycle.toml"
    path.write_text(f'''urdf = "cycle.urdf"
root = "floating"
neutral = {{ z = {R} }}
independent = {independent}
[[wheels]]
joint = "front"
radius = {R}
friction = "linear"
stiffness = 1e9
mu = {mu!r}
{wheels}''')
    return read(path).robot()


def _bicycle(tmp_path, mu: float):
    return _robot(tmp_path, mu, {"rear": 0.0})


def _tricycle(tmp_path, mu: float):
    return _robot(tmp_path, mu, {"rear_left": B, "rear_right": -B})


def _state(robot, spin: float = SPIN):
    """At rest in the neutral pose, the front wheel spinning at `spin`, a torque TAU on each rear wheel."""
    nu = np.zeros(robot.mobility)
    nu[list(robot.velocity_names).index("front_dot")] = spin
    return robot.neutral(), nu, np.full(len(robot.motors), TAU)


def _closed_form(mu: float) -> tuple[float, float]:
    """(a, N_f) of the bicycle's front wheel sliding forwards (the module's two equations)."""
    return tuple(np.linalg.solve([[MP, mu], [C1 + IW / R, L + R * mu]], [TAU / R, M * G * L - W0]))


def _compiled_normal(robot, q, nu, tau, projection):
    fast = compiled_model(robot)
    fast.select(projection)
    return fast.ev.slip_rhs(q, nu, tau, 0.0)[1]


def _refusals(robot, q, nu, tau) -> list[str]:
    """The one-line refusals of forward, of simulate on both engines and of the dynamics derivatives at the state
    (q, nu, tau)."""
    out = []
    with pytest.raises(SingularConstraintError) as python:
        forward(robot, q, nu, tau)
    out.append(str(python.value))
    fast = compiled_model(robot)
    fast.select(robot.reduced(q, nu).projection)
    with pytest.raises(RuntimeError, match="no P-matrix"):
        fast.ev.slip_rhs(q, nu, tau, 0.0)
    for engine in ("compiled", "scipy"):  # through simulate: the compiled error becomes the same line
        with pytest.raises(SingularConstraintError) as run:
            simulate(robot, 0.01, q, nu, Constant(list(tau)), n_out=3, engine=engine, progress=False)
        out.append(str(run.value))
    with pytest.raises(SingularConstraintError) as derivatives:  # no derivatives where forward dynamics refuses
        robot.dynamics_derivatives(q, nu, tau)
    out.append(str(derivatives.value))
    assert all("\n" not in m for m in out)
    return out


def test_threshold_is_the_closed_form():
    assert MU_P == pytest.approx(3.375, rel=1e-14)


def test_below_the_threshold_both_engines_give_the_closed_form_loads(tmp_path):
    mu = MU_P * (1 - 1e-3)
    robot = _bicycle(tmp_path, mu)
    q, nu, tau = _state(robot)
    st = forward(robot, q, nu, tau)
    a, nf = _closed_form(mu)
    assert nf > 1e4  # near the threshold the load is large (D small), and positive
    np.testing.assert_allclose(st.normal, [nf], rtol=1e-8)
    np.testing.assert_allclose(st.force[0], [-mu * nf, 0.0], rtol=1e-8, atol=1e-9 * nf)
    assert st.nudot[list(robot.velocity_names).index("x_dot")] == pytest.approx(a, rel=1e-8)
    np.testing.assert_allclose(_compiled_normal(robot, q, nu, tau, st.reduced.projection), st.normal, rtol=1e-9)


def test_above_the_threshold_both_engines_refuse_with_one_message(tmp_path):
    robot = _bicycle(tmp_path, MU_P * (1 + 1e-3))
    messages = _refusals(robot, *_state(robot))
    assert messages[0].startswith("sliding wheel front_wheel (mu = 3.37838): Painleve paradox, its friction presses")
    assert "; mu_P = 3.375 for this sliding direction;" in messages[0]  # the closed form
    assert messages[1:] == messages[:1] * 3


def test_sliding_backwards_is_no_painleve_case_at_any_mu(tmp_path):
    """Friction lifting the front wheel (it slides backwards): D > 0 at every mu; at mu = 3 mu_P both engines give
    the closed form with mu -> -mu."""
    mu = 3 * MU_P
    robot = _bicycle(tmp_path, mu)
    q, nu, tau = _state(robot, spin=-SPIN)
    st = forward(robot, q, nu, tau)
    a, nf = _closed_form(-mu)
    assert 0 < nf < M * G
    np.testing.assert_allclose(st.normal, [nf], rtol=1e-9)
    np.testing.assert_allclose(st.force[0], [mu * nf, 0.0], rtol=1e-9, atol=1e-9 * nf)
    np.testing.assert_allclose(_compiled_normal(robot, q, nu, tau, st.reduced.projection), st.normal, rtol=1e-9)


def test_several_sliding_wheels_one_verdict_and_its_threshold(tmp_path):
    """The tricycle at mu = 3.3: D's first minor that is not positive is the front wheel's with the rear loads
    at zero (the rear wheels keep their longitudinal rows); both engines say so in the same line, and the threshold
    it names is where forward's verdict flips (mu_P (1 -+ 1e-6))."""
    robot = _tricycle(tmp_path, 3.3)
    messages = _refusals(robot, *_state(robot))
    assert messages[1:] == messages[:1] * 3
    head = "sliding wheel front_wheel (mu = 3.3): Painleve paradox with the loads of rear_left_wheel, " \
           "rear_right_wheel at zero, its friction presses it into the ground"
    assert messages[0].startswith(head), messages[0]
    mu_p = float(messages[0].split("mu_P = ")[1].split(" ")[0])
    assert 2.0 < mu_p < 3.3
    for factor, refused in ((1 - 1e-5, False), (1 + 1e-5, True)):
        robot = _tricycle(tmp_path, mu_p * factor)
        try:
            forward(robot, *_state(robot))
            assert not refused
        except SingularConstraintError as exc:
            assert refused and str(exc).startswith("sliding wheel front_wheel"), str(exc)

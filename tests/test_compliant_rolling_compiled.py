"""Compliant wheels that roll while in contact on the compiled engine (robotdyn.simulation.compiled_rolling,
robotdyn/kernels/compliant_rolling.hpp) against the landing disc's closed form and against the Python path
(robotdyn.simulation.compliant_rolling, scipy LSODA): trajectories to the integration tolerance, event times to
1e-6 s, touch-down losses to 1e-9 relative.

The disc (tests/test_compliant_rolling.py: m = 2 kg, spin inertia I = 0.04 kg m^2, radius r = 0.3 m, no gravity)
lands at v_in = 1 m/s moving at v0 with spin w0: the plastic tangential impulse passes through the contact point, so
the angular momentum about it, m r v + I w, is conserved: v1 = (m r^2 v0 + I r w0) / (m r^2 + I), and the energy
lost is (1/2) m I / (m r^2 + I) (v0 - r w0)^2 (the kinetic energy of the stopped relative motion). It lifts off when
the damped spring's force returns to zero, theta / w_d after the touch-down (tests/compliant_disc.py, landing).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robotdyn.simulation.engine import simulate
from test_compliant_rolling import I, M, R, disc, events, state

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "bump_base_rolling.toml"


def same_run(a, b, q_tol: float) -> None:
    """The compiled run ``a`` equals the Python path's ``b``: samples, states, events, losses and energies."""
    assert a.stats["engine"].startswith("compiled") and b.stats["engine"].startswith("scipy")
    assert np.array_equal(a.t, b.t)
    assert np.max(np.abs(a.q - b.q)) < q_tol and np.max(np.abs(a.nu - b.nu)) < 100 * q_tol
    ea, eb = a.stats["flight"], b.stats["flight"]
    assert [(e["wheel"], e["event"]) for e in ea] == [(e["wheel"], e["event"]) for e in eb]
    assert [e["t"] for e in ea] == pytest.approx([e["t"] for e in eb], abs=1e-6)
    for x, y in zip(ea, eb):
        if "loss" in y:
            assert x["loss"] == pytest.approx(y["loss"], rel=1e-9, abs=1e-12)
    assert a.stats["touchdown_loss"] == pytest.approx(b.stats["touchdown_loss"], rel=1e-9, abs=1e-12)
    assert a.stats["contact_switches"] == b.stats["contact_switches"]
    assert np.allclose(a.impact_loss, b.impact_loss, rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(a.energy - b.energy)) < 1e3 * q_tol * max(1.0, np.max(np.abs(b.energy)))


@pytest.mark.parametrize("v0, w0", [(2.0, 1.0), (1.0, -4.0)])  # top spin short of rolling; back spin
def test_landing_disc_on_both_engines_against_the_closed_form(v0, w0):
    k, zeta, v_in, gap = 2.0e4, 0.3, 1.0, 0.01
    robot = disc(normal_stiffness=k, normal_damping=2 * zeta * np.sqrt(k * M))
    q0, nu0 = state(robot, R + gap, -v_in, v0, w0)
    options = dict(n_out=8, rtol=1e-10, atol=1e-13, progress=False)  # no sample at the touch-down t = 0.01 s (an impact instant: pre- or post-impact state by 1e-15 s)
    a = simulate(robot, 0.06, q0, nu0, engine="compiled", **options)
    b = simulate(robot, 0.06, q0, nu0, engine="scipy", **options)
    same_run(a, b, 1e-8)
    v1 = (M * R**2 * v0 + I * R * w0) / (M * R**2 + I)
    lost = 0.5 * M * I / (M * R**2 + I) * (v0 - R * w0) ** 2
    down, up = events(a, "touch-down"), events(a, "lift-off")
    assert [e["t"] for e in down] == pytest.approx([gap / v_in], abs=1e-9)
    assert down[0]["loss"] == pytest.approx(lost, rel=1e-10) == a.stats["touchdown_loss"]
    assert a.column("x_dot")[-1] == pytest.approx(v1, rel=1e-9)
    assert R * a.column("spin_dot")[-1] == pytest.approx(v1, rel=1e-9)
    wn = np.sqrt(k / M)
    s, wd = zeta * wn, wn * np.sqrt(1 - zeta**2)
    theta = np.pi - np.arctan2(2 * zeta * np.sqrt(1 - zeta**2), 1 - 2 * zeta**2)
    assert len(up) == 1 and up[0]["t"] - down[0]["t"] == pytest.approx(theta / wd, rel=1e-7)
    balance = a.energy - a.energy[0] - a.damper_work + a.impact_loss
    assert np.max(np.abs(balance)) < 1e-8 * a.energy[0]
    assert a.stats["rolling_residual"] < 1e-8


def test_compiled_right_hand_side_equals_the_python_forward():
    """The compiled accelerations with the disc's rows held (the contact set as data) equal
    robotdyn.contact.compliant_rolling.forward at a pressed, slipping, spinning state, with and without the
    residual's stabilisation; without the rows they are the free disc's."""
    from robotdyn.contact.compliant_rolling import forward
    from robotdyn.simulation.compiled_engine import engine_model

    robot = disc(g=9.81, motors=[], normal_stiffness=2e4, normal_damping=40.0)
    q, nu = state(robot, R - 0.002, vz=-0.3, vx=1.2, w=3.0)
    fast = engine_model(robot)
    fast._choose(q, nu)
    for beta in (0.0, 20.0):
        for on in ((), ("disc",)):
            fast.ev.set_rolling_mode([int(bool(on))])
            got = fast.ev.rhs(q, nu, np.zeros(0), beta)[robot.nq:]
            want = forward(robot, q, nu, np.zeros(0), on, beta).nudot
            assert np.allclose(got, want, rtol=1e-12, atol=1e-12), (beta, on)
    p, G, Mr, S, v = fast.ev.rolling_state(q, nu)
    assert p[0] == pytest.approx(min(0.002, 0.002 + 40.0 / 2e4 * 0.3), rel=1e-9)  # NormalLaw.pressing


def test_example_base_on_rolling_tyres_compiled_equals_python():
    """examples/bump_base_rolling.toml over the bump's crest (the front wheels leave it together, fly and land):
    the compiled run equals the Python path's."""
    from robotdyn.interfaces.constraint_file import read

    cf = read(EXAMPLE)
    robot, scenario = cf.robot(), cf.SCENARIOS["bump"]
    options = dict(t_end=0.2, n_out=21, rtol=1e-8, atol=1e-10, progress=False)
    a = scenario.run(robot, engine="compiled", **options)
    b = scenario.run(robot, engine="scipy", **options)
    assert {e["wheel"] for e in a.stats["flight"] if e["event"] == "lift-off"} >= {"front_left", "front_right"}
    same_run(a, b, 1e-6)

"""The traction report of exact stick-slip runs (issue 23, item 4: one force story), against closed forms.

- A disc (mass m, axle inertia I, radius R, k = I / (m R^2): tests/test_sliding.py) launched sliding at v0 on flat
  ground slides until t* = v0 k / (mu g (1 + k)) with the friction force mu m g on the load m g, then rolls on
  with no friction force (tests/test_stick_slip.py derives t*).
- The same disc at rest on an incline of angle a rolls iff the friction it needs, f / N = tan(a) k / (1 + k)
  (f = m g sin(a) k / (1 + k), N = m g cos(a)), is at most mu; else it slides from t = 0 with f = mu N.
- The disc pushed up by a force c t on its height coordinate z (a motor on the joint z) keeps the load
  N = m g - c t, which reaches zero at t = m g / c: the rigid contact cannot pull, so the run stops there.
- The locked tricycle of tests/test_at_rest.py slides on its rear wheels at deceleration a (its closed form
  there); horizontally m a = mu N_r - f with the front contact's force f = I_f a / r^2, so each rear wheel
  carries N_r / 2 = (m + I_f / r^2) a / (2 mu) and the friction force mu N_r / 2.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from robotdyn.contact.traction import traction
from robotdyn.errors import InputError
from robotdyn.robot import MotorSpec, Robot, RobotSpec, Wheel
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.stick_slip import simulate as hybrid

from test_sliding import DISC, G, K, M, R, disc, on_ground


def test_launched_disc_reports_its_slide_then_its_roll():
    mu, v0 = 0.3, 2.0
    robot, q0 = disc(0.0, friction="stick_slip", mu=mu)
    v = np.zeros(robot.nq)
    v[robot.coordinate_index("x")] = v0
    traj = hybrid(robot, 0.3, q0, v, n_out=31, progress=False)
    t_star = v0 * K / (mu * G * (1 + K))
    tr = traction(robot, traj)
    slides = traj.t < t_star
    assert 0 < slides.sum() < len(slides)
    np.testing.assert_array_equal(tr.phases[:, 0], slides)
    np.testing.assert_allclose(tr.normal[:, 0], M * G, rtol=1e-12)
    np.testing.assert_allclose(tr.tangential[slides, 0], mu * M * G, rtol=1e-9)  # Coulomb while sliding
    assert np.all(tr.tangential[~slides, 0] < 1e-9 * M * G)  # rolling on flat ground: no friction force
    columns = tr.columns()
    np.testing.assert_array_equal(columns["disc.sliding"], slides.astype(float))
    np.testing.assert_array_equal(columns["disc.friction"], tr.tangential[:, 0])
    assert tr.max_required_mu()["disc"] < 1e-12  # the need while sticking, not the slide's mu
    assert [(e.kind, e.wheel, e.t) for e in tr.events] == [("slide", "disc", 0.0)]
    assert not tr.broken().any()
    text = tr.summary()
    assert "holds" not in text and "disc starts to slide at t = 0 s" in text and "disc 41.9 %" in text
    assert traction(robot, traj, mu=mu).summary() == text  # its own mu is accepted
    with pytest.raises(InputError, match=r"mu = 0.2 for wheel 'disc'.* has mu = 0.3"):
        traction(robot, traj, mu=0.2)


@pytest.mark.parametrize("factor", [1.01, 0.99])
def test_disc_on_incline_needs_the_closed_form_friction(factor):
    slope = 1.0
    alpha = np.arctan(slope)
    mu_c = np.tan(alpha) * K / (1 + K)
    robot, q0 = disc(slope, independent=None, friction="stick_slip", mu=factor * mu_c)
    traj = simulate(robot, 0.2, q0, np.zeros(robot.mobility), n_out=5, progress=False)
    tr = traction(robot, traj)
    np.testing.assert_allclose(tr.normal[:, 0], M * G * np.cos(alpha), rtol=1e-9)
    if factor > 1:  # rolls: it needs tan(a) k / (1 + k), within its mu
        assert not tr.phases.any()
        np.testing.assert_allclose(tr.required_mu[:, 0], mu_c, rtol=1e-9)
        assert tr.max_required_mu()["disc"] == pytest.approx(mu_c, rel=1e-9)
        assert "no-slip assumption holds" in tr.summary() and not tr.events
    else:  # slides from the start at mu N
        assert tr.phases.all()
        np.testing.assert_allclose(tr.tangential[:, 0], factor * mu_c * M * G * np.cos(alpha), rtol=1e-9)
        assert tr.max_required_mu() == {}
        assert "holds" not in tr.summary() and [e.kind for e in tr.events] == ["slide"]


def test_disc_unloaded_by_a_lifting_force_stops_with_what_happened():
    """Before: the cone's edge (mu N - abs(f_t) = 0, with f_t = 0) and the zero load come at the same instant and
    the run switched the wheel to sliding in no direction (0/0: 'SVD did not converge'); the lift-off message
    said 'a wheel in flight is not modelled'."""
    spec = RobotSpec(name="disc", title="lifted disc", xacro=DISC, root="planar",
                     wheels=[Wheel("disc", R, friction="stick_slip", mu=0.3)], motors=[MotorSpec("lift", "z")])
    robot = Robot(spec)
    q0 = on_ground(robot, np.zeros(robot.nq))
    c = 100.0
    torque = lambda t, q, nu: np.array([c * t])  # noqa: E731
    traj = simulate(robot, 0.3, q0, np.zeros(robot.nq), torque, n_out=31, progress=False)
    t_off = M * G / c
    assert traj.stats["lift_off"]["t"] == pytest.approx(t_off, rel=1e-9)
    message = traj.stats["event"]
    assert message.startswith(f"wheel disc unloads at t = {t_off:.6g} s")
    assert "cannot leave the ground" in message and 'contact = "compliant"' in message
    assert "flight is not modelled" not in message
    tr = traction(robot, traj, torque)
    np.testing.assert_allclose(tr.normal[:, 0], M * G - c * traj.t, rtol=1e-9)
    assert traj.t[-1] < t_off and not tr.phases.any()
    [event] = tr.events
    assert (event.kind, event.wheel) == ("lift-off", "disc") and event.t == pytest.approx(t_off, rel=1e-9)
    assert tr.summary().endswith(f"first: lift-off of wheel disc at t = {t_off:.4g} s (load {event.value:.4g} N)")


def test_cli_reports_the_tricycle_sliding_and_refuses_another_mu(tmp_path, capsys):
    from robotdyn.cli import main
    from test_at_rest import I, MU, URDF, V0, closed_form
    from test_at_rest import M as MASS
    from test_at_rest import R as RADIUS

    wheels = "".join(f"""
[[wheels]]
name = "{w}"
frame = "{w}"
axis = [0, 1, 0]
radius = {RADIUS}
friction = "stick_slip"
mu = {MU}
""" for w in ("rear_left", "rear_right"))
    path = tmp_path / "tricycle.toml"
    path.write_text(f"""name = "locked_tricycle"
urdf = "{URDF}"
root = "floating"
neutral = {{ z = {RADIUS} }}
{wheels}
[[wheels]]
name = "front"
joint = "front_spin"
radius = {RADIUS}

[[scenarios]]
name = "launch"
t_end = 1.0
nu0 = {{ x = {V0}, front_spin = {V0 / RADIUS} }}
""")
    run = ["simulate", "--constraints", str(path), "--scenario", "launch", "--quiet", "--t-end", "0.05"]
    assert main(run + ["--mu", "0.3"]) == 2  # refused before the run, naming both values
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "mu = 0.3 for wheel 'rear_left'" in err and "has mu = 0.5" in err
    plot, csv = tmp_path / "traction.png", tmp_path / "run.csv"
    assert main(run + ["--mu", "0.5", "--json", "--traction-plot", str(plot), "--csv", str(csv)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["engine"] == "scipy (DOP853)"  # exact stick-slip runs on scipy's loop between its switches (was null)
    assert plot.stat().st_size > 0
    summary = out["traction"]["summary"]
    assert "holds" not in summary and "rear_left starts to slide at t = 0 s" in summary
    assert out["traction"]["events"][0] == {"kind": "slide", "wheel": "rear_left", "t": 0.0, "value": MU}
    header = csv.read_text().splitlines()[0].split(",")
    data = dict(zip(header, np.loadtxt(csv, delimiter=",", skiprows=1, unpack=True)))
    half = (MASS + I / RADIUS**2) * closed_form() / (2 * MU)  # N_r / 2
    np.testing.assert_array_equal(data["rear_left.sliding"], 1.0)
    np.testing.assert_allclose(data["rear_left.normal"], half, rtol=1e-9)
    np.testing.assert_allclose(data["rear_right.normal"], half, rtol=1e-9)

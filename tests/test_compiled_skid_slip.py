"""Slipping wheels whose normal loads rigid statics leave open, on the compiled engine (robotdyn/kernels/
sliding_rigid_limit.hpp, the twin of robotdyn.contact.sliding_rigid_limit.coupled): a rigid four-wheel skid steer
(examples/husky_like: wheels at (+-a, +-b), radius r, Coulomb law regularised at v_s) against the Python path and
against closed forms derived here.

Braking, wheels at rest, base sliding forward at v (every contact slips at s = v, so each wheel carries
F_i = -mu_e N_i with mu_e = mu v / sqrt(v^2 + v_s^2)): the centre of mass decelerates at x'' = sum F / m = -mu_e g,
and the pitch balance about the centre of mass G (height h, the wheels' spin taking the torque -r F_i each, so that
sum (x_i - x_G) N_i = -(h - r) sum F) with N_f + N_r = m g gives the axle loads; equal stiffnesses leave no warp and
the sides are symmetric, so each wheel carries half its axle's load. Spinning in place at yaw rate w, wheels at
rest: every contact slips at w rho (rho = sqrt(a^2 + b^2)) perpendicular to its arm, the forces cancel in pairs, so
each wheel carries m g / 4 and psi'' = -mu_e m g rho / I_z (mu_e at s = w rho, I_z the whole robot's yaw inertia)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robotdyn.contact.sliding import forward
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.interfaces.constraint_file import read
from robotdyn.simulation import simulate
from robotdyn.simulation.torque_profile import Constant

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
A, B, R, MU, VS = 0.256, 0.2775, 0.165, 0.6, 0.05  # husky_like: half wheelbase, half track, radius, mu, v_s
G0 = 9.81

VARIANTS = {
    "centred": {},
    "corner": {"com_x": "0.19", "com_y": "0.21"},  # the rear-right wheel would pull: the rigid limit unloads it
    "short": {"wheelbase": "0.04"},  # braking lifts the rear axle: the compatible loads, some negative
}


@pytest.fixture(scope="module", params=list(VARIANTS))
def husky(request):
    mod = read(EXAMPLES / "husky_like.toml", xacro_args=VARIANTS[request.param] or None)
    return request.param, mod.robot()


def _compiled(robot, q, nu, tau):
    """The compiled right-hand side at one state: (nudot, every multiplier, loads, power, unloaded names)."""
    fast = compiled_model(robot)
    assert fast.loads_open and fast.ev.slipping == 4
    fast.select(robot.reduced(q, nu).projection)
    out, normal, _, _ = fast.ev.slip_rhs(q, nu, tau, 0.0)
    lam, unloaded = fast.ev.slip_multipliers()
    n, k = robot.nq, robot.mobility
    return out[n:n + k], lam, normal, out[n + k], tuple(fast.wheels[j].name for j in unloaded)


def _states(robot, count=4, seed=7):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q = robot.neutral()
        for name in ("x", "y", "yaw", "front_left_wheel", "rear_right_wheel"):
            q[robot.coordinate_index(name)] = rng.uniform(-np.pi, np.pi)
        yield q, rng.uniform(-1.5, 1.5, robot.mobility), rng.uniform(-15.0, 15.0, 4)


def test_right_hand_side_equals_the_python_path(husky):
    name, robot = husky
    seen = set()
    states = list(_states(robot))
    if name != "centred":  # at rest (the corner: a wheel held at zero load) and braking hard (the short base)
        states.append((robot.neutral(), np.array([1.0, 0, 0, 0, 0, 0, 0]), np.zeros(4)))
    for q, nu, tau in states:
        with use_compiled(False):
            st = forward(robot, q, nu, tau)
        nudot, lam, normal, power, unloaded = _compiled(robot, q, nu, tau)
        scale = np.max(np.abs(st.lam))
        np.testing.assert_allclose(nudot, st.nudot, rtol=0, atol=1e-10 * max(1.0, np.max(np.abs(st.nudot))))
        np.testing.assert_allclose(lam, st.lam, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(normal, st.normal, rtol=0, atol=1e-10 * scale)
        assert power == pytest.approx(st.power, rel=1e-10, abs=1e-12)
        assert unloaded == st.unloaded
        seen.add(unloaded)
        if name == "short" and not st.unloaded and np.min(st.normal) < 0:
            seen.add("negative")
    if name == "corner":
        assert ("rear_right",) in seen  # the active set was exercised
    if name == "short":
        assert "negative" in seen  # ... and the fallback of a whole axle that would pull


def _centred():
    mod = read(EXAMPLES / "husky_like.toml")
    robot = mod.robot()
    data = robot.model.createData()
    m = float(pin.computeTotalMass(robot.model))
    G = pin.centerOfMass(robot.model, data, robot.neutral())
    pin.ccrba(robot.model, data, robot.neutral(), np.zeros(robot.model.nv))
    return robot, m, G, float(data.Ig.inertia[2, 2])


def test_braking_at_the_closed_form():
    robot, m, G, _ = _centred()
    v = 1.0
    mu_e = MU * v / np.hypot(v, VS)
    nudot, lam, normal, power, _ = _compiled(robot, robot.neutral(), np.array([v, 0, 0, 0, 0, 0, 0]), np.zeros(4))
    sum_f = -mu_e * m * G0
    front, rear = np.linalg.solve([[1.0, 1.0], [A - G[0], -A - G[0]]], [m * G0, -(G[2] - R) * sum_f])
    assert front > rear  # braking loads the front axle
    np.testing.assert_allclose(normal, [front / 2, front / 2, rear / 2, rear / 2], rtol=1e-12)
    assert nudot[0] == pytest.approx(-mu_e * G0, rel=1e-12)
    np.testing.assert_allclose(nudot[1:3], 0.0, atol=1e-12)
    assert power == pytest.approx(sum_f * v, rel=1e-12)  # friction power F . s


def test_spinning_in_place_at_the_closed_form():
    robot, m, G, Iz = _centred()
    w = 2.0
    rho = np.hypot(A, B)
    mu_e = MU * w * rho / np.hypot(w * rho, VS)
    nudot, _, normal, _, _ = _compiled(robot, robot.neutral(), np.array([0, 0, w, 0, 0, 0, 0]), np.zeros(4))
    np.testing.assert_allclose(normal, m * G0 / 4, rtol=1e-12)
    assert nudot[2] == pytest.approx(-mu_e * m * G0 * rho / Iz, rel=1e-12)
    np.testing.assert_allclose(nudot[:2], 0.0, atol=1e-12)


def _run(robot, engine, t_end, nu0, tau, n_out=5, **kw):
    return simulate(robot, t_end, robot.neutral(), np.asarray(nu0, float), tau, n_out=n_out, rtol=1e-10,
                    atol=1e-12, engine=engine, progress=False, **kw)


def test_energy_balance_of_a_compiled_turn():
    """Motor work (constant torques: sum tau_i times each wheel's turn) plus the friction work (a state of the run,
    <= 0) equals the change of mechanical energy, sample by sample."""
    robot, *_ = _centred()
    tau = np.array([-12.0, 12.0, -12.0, 12.0])
    traj = _run(robot, "compiled", 0.5, [0.3, 0, 0.5, 0, 0, 0, 0], Constant(tau), n_out=11)
    assert traj.stats["engine"].startswith("compiled")
    wheels = [robot.coordinate_index(f"{c}_wheel") for c in ("front_left", "front_right", "rear_left", "rear_right")]
    motor = (traj.q[:, wheels] - traj.q[0, wheels]) @ tau
    assert traj.friction_work[-1] < -1.0
    np.testing.assert_allclose(traj.energy - traj.energy[0], motor + traj.friction_work, rtol=0, atol=1e-7)


@pytest.mark.parametrize("variant", ["centred", "corner"])
def test_compiled_run_equals_the_scipy_run(variant):
    """Sliding forward while turning (far from zero slip, so that scipy's explicit steps stay few); the corner
    variant keeps its rear-right wheel at zero load throughout."""
    robot = read(EXAMPLES / "husky_like.toml", xacro_args=VARIANTS[variant] or None).robot()
    tau = Constant([-6.0, 9.0, -6.0, 9.0])
    nu0 = [1.0, 0.0, 0.8, 0.0, 0.0, 0.0, 0.0]
    runs = [_run(robot, engine, 0.02, nu0, tau) for engine in ("compiled", "scipy")]
    assert runs[0].stats["engine"].startswith("compiled") and runs[1].stats["engine"].startswith("scipy")
    np.testing.assert_allclose(runs[0].q, runs[1].q, rtol=0, atol=1e-8)
    np.testing.assert_allclose(runs[0].nu, runs[1].nu, rtol=0, atol=1e-7)
    np.testing.assert_allclose(runs[0].friction_work, runs[1].friction_work, rtol=0, atol=1e-7)
    assert "event" not in runs[0].stats and "event" not in runs[1].stats
    if variant == "corner":
        with use_compiled(False):
            assert forward(robot, runs[0].q[-1], runs[0].nu[-1], tau(0.02)).unloaded == ("rear_right",)


def test_a_feedback_law_runs_compiled_with_slipping_wheels():
    """A wheel-speed PI-less law (K_nu on the wheel rates towards a turn in place) used to be refused on the compiled
    engine with slipping wheels; both engines now give the same run."""
    from robotdyn.simulation.feedback import FeedbackLaw

    robot, *_ = _centred()
    Knu = np.zeros((4, 7))
    Knu[np.arange(4), 3 + np.arange(4)] = 5.0
    law = FeedbackLaw(Knu=Knu, nu_ref=Constant([0.0, 0.0, 0.0, -20.0, 20.0, -20.0, 20.0]))
    runs = [_run(robot, engine, 0.02, [1.0, 0, 0.8, 0, 0, 0, 0], law) for engine in ("compiled", "scipy")]
    assert runs[0].stats["engine"].startswith("compiled")
    np.testing.assert_allclose(runs[0].q, runs[1].q, rtol=0, atol=1e-8)
    np.testing.assert_allclose(runs[0].nu, runs[1].nu, rtol=0, atol=1e-7)


def test_the_cli_simulates_a_slipping_skid_steer_compiled(capsys):
    import json

    from robotdyn.cli import main

    argv = ["simulate", "--constraints", str(EXAMPLES / "husky_like.toml"), "--scenario", "turn_in_place",
            "--t-end", "0.05", "--quiet", "--json"]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["engine"].startswith("compiled") and not data.get("engine_reason")


def test_derivatives_still_refuse_open_loads_in_one_line():
    """The compiled derivatives do not serve open loads (the Python path's refusal, as before)."""
    from robotdyn.errors import InputError

    robot, *_ = _centred()
    assert compiled_model(robot).slip_refusal is not None
    with pytest.raises(InputError, match="redundant normal row.*rigid limit") as info:
        robot.dynamics_derivatives(robot.neutral(), np.zeros(robot.mobility), np.zeros(4))
    assert "\n" not in str(info.value)


def test_an_axle_lifting_stops_both_engines_at_the_same_instant():
    """examples/husky_like as shipped under a rear torque 20000 t per wheel (tests/test_stick_slip_axle_lift.py
    derives the front axle's load): once no split keeps both front loads >= 0 the coupled solve returns the
    compatible loads and the lift-off event stops the run; the compiled engine stops where scipy's does."""
    from robotdyn.simulation.torque_profile import Polynomial

    robot, *_ = _centred()
    torque = Polynomial([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 20000.0, 20000.0]])
    runs = [_run(robot, engine, 0.005, np.zeros(7), torque) for engine in ("compiled", "scipy")]
    assert runs[0].stats["engine"].startswith("compiled")
    assert runs[0].stats["t_event"] == pytest.approx(runs[1].stats["t_event"], rel=1e-8)
    assert 0.0031 < runs[0].stats["t_event"] < 0.0032
    head = [r.stats["event"].split(" (normal load")[0] for r in runs]
    assert head[0] == head[1] and head[0].startswith("wheel front_left unloads at t = 0.0031")


@pytest.mark.parametrize("mu, refused", [(5.0, False), (8.0, False), (12.0, True), (25.0, True)])
def test_painleve_verdicts_equal_the_python_path(mu, refused):
    """Base sliding forward at 1 m/s on locked front wheels, rear wheels rolling, every wheel at mu: the coupled
    system's effective normal matrix on the loads' subspace is no P-matrix above mu_P = 10.48 (the Python path's
    threshold): both paths refuse the same states (at mu = 8 the rear axle would pull: the compatible loads)."""
    from dataclasses import replace

    from robotdyn.errors import SingularConstraintError
    from robotdyn.robot import Robot

    spec = read(EXAMPLES / "husky_like.toml").SPEC
    robot = Robot(replace(spec, wheels=[replace(w, mu=mu) for w in spec.wheels]))
    q, nu, tau = robot.neutral(), np.array([1.0, 0, 0, 0, 0, 1 / R, 1 / R]), np.zeros(4)
    if not refused:
        with use_compiled(False):
            st = forward(robot, q, nu, tau)
        np.testing.assert_allclose(_compiled(robot, q, nu, tau)[2], st.normal, rtol=1e-10)
        return
    with use_compiled(False), pytest.raises(SingularConstraintError, match="Painleve paradox"):
        forward(robot, q, nu, tau)
    with pytest.raises(RuntimeError, match="no P-matrix"):
        _compiled(robot, q, nu, tau)
    # where a compiled run stops on it, the error raised is the Python path's at the stopping state, word for word
    from robotdyn.simulation.compiled_engine import _python_refusal

    with pytest.raises(SingularConstraintError) as run:
        _python_refusal(robot, 0.1, np.concatenate([q, nu, [0.0]]), Constant(tau), None)
    with use_compiled(False), pytest.raises(SingularConstraintError) as python:
        forward(robot, q, nu, tau)
    assert str(run.value) == str(python.value) and "\n" not in str(run.value)
    from robotdyn.simulation.compiled_engine import _slip_error, at_time

    stop = {"slip_error": 2, "slip_value": float("nan"), "slip_wheels": 15, "t_stop": 0.1,
            "y_stop": np.concatenate([q, nu, [0.0]])}
    error = at_time(_slip_error(robot, compiled_model(robot), stop, Constant(tau), None), 0.1)
    assert str(error) == f"at t = 0.1 s: {python.value}"  # as the scipy engine words an error at that time


def test_a_start_with_a_wheel_pulling_the_ground_is_refused_on_both_engines():
    """examples/husky_like with a 4 cm wheelbase braking from 1 m/s: the pitch balance (module text) needs the rear
    axle to pull, and no split of the rigid limit avoids it (an axle, not one wheel), so the rear loads are
    negative from t = 0. A lift-off event only finds a crossing; without this check both engines ran on with a
    friction force of the wrong sign. The loads still sum to m g (flat ground, no vertical acceleration)."""
    from robotdyn.errors import InputError

    robot = read(EXAMPLES / "husky_like.toml", xacro_args={"wheelbase": "0.04"}).robot()
    nu0 = np.zeros(robot.mobility)
    nu0[0] = 1.0
    with use_compiled(False):
        st = forward(robot, robot.neutral(), nu0, np.zeros(4))
    assert np.all(st.normal[2:] < 0) and st.normal.sum() == pytest.approx(
        float(pin.computeTotalMass(robot.model)) * G0, rel=1e-9)
    for engine in ("compiled", "scipy"):
        with pytest.raises(InputError) as err:
            _run(robot, engine, 0.01, nu0, None)
        text = str(err.value)
        assert "\n" not in text and text.startswith("at t = 0 s slipping wheel rear_")
        assert f"(normal load {st.normal[2]:.4g} N)" in text and "contact = \"compliant\"" in text

"""Slipping wheels on the compiled engine (robotdyn/_compiled.cpp: Evaluator.slip_rhs, robotdyn/_integrator.hpp: the
lift-off event) against the Python reference path (robotdyn.contact.sliding.forward, scipy's solve_ivp with its event) and
closed forms: one state at a time, whole trajectories of the skid-steer rover (both directions and lateral slip,
linear and Coulomb laws), a disc sliding down an incline (g (sin a - mu cos a) when tan a > 3 mu), the energy
balance with the friction work, and a disc lifting off over a bump."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from robotdyn.fast.dispatch import compiled_model
from robotdyn.simulation.compiled_engine import choose_engine
from robotdyn.interfaces.constraint_file import read
from robotdyn.errors import RobotDynError
from robotdyn.contact.friction import RegularisedCoulomb
from robotdyn.constraints.posture import set_terrain
from robotdyn.robot import Robot
from robotdyn.simulation import simulate
from robotdyn.contact.sliding import forward, slipping_wheels
from robotdyn.constraints.terrain import BumpTerrain
from robotdyn.simulation.torque_profile import Constant

sys.path.insert(0, str(Path(__file__).parent))
from test_sliding import G, disc, on_ground  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "skid_steer.toml"


def _rover(**wheel) -> Robot:
    mod = read(EXAMPLE)
    if not wheel:
        return mod.robot()
    independent = ["x", "y", "yaw"] if wheel.get("slip") == "lateral" else mod.SPEC.independent
    return Robot(replace(mod.SPEC, wheels=[replace(w, **wheel) for w in mod.SPEC.wheels], independent=independent))


ROVERS = {
    "linear": dict(),
    "coulomb": dict(friction="coulomb", mu=0.6, slip_velocity=0.01, stiffness=None),
    "lateral linear": dict(slip="lateral"),
    "lateral coulomb": dict(slip="lateral", friction="coulomb", mu=0.6, slip_velocity=0.01, stiffness=None),
}


def _tilted_states(robot, count: int = 5, seed: int = 3):
    """Random states of a rover: (q: rolled by up to 0.05 rad, any yaw; nu; tau), seeded."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q = robot.neutral()
        q[robot.coordinate_index("roll")] = rng.uniform(-0.05, 0.05)
        q[robot.coordinate_index("yaw")] = rng.uniform(-np.pi, np.pi)
        yield q, rng.uniform(-1.0, 1.0, robot.mobility), rng.uniform(-1.0, 1.0, 4)


@pytest.mark.parametrize("kind", ROVERS)
def test_one_state_equals_the_python_path(kind):
    """Accelerations, normal loads, slip velocities, friction forces and power of Evaluator.slip_rhs equal
    robotdyn.contact.sliding.forward at random states (tilted chassis, random velocities and torques)."""
    robot = _rover(**ROVERS[kind])
    fast = compiled_model(robot)
    assert fast.slip_refusal is None and fast.ev.slipping == 4
    n, k = robot.nq, robot.mobility
    for q, nu, tau in _tilted_states(robot):
        ref = forward(robot, q, nu, tau)
        fast.select(ref.reduced.projection)
        out, normal, slip, force = fast.ev.slip_rhs(q, nu, tau, 0.0)
        np.testing.assert_allclose(out[:n], ref.reduced.v, rtol=0, atol=1e-12)
        np.testing.assert_allclose(out[n:n + k], ref.nudot, rtol=1e-10, atol=1e-10 * np.max(np.abs(ref.nudot)))
        np.testing.assert_allclose(normal, ref.normal, rtol=1e-10)
        np.testing.assert_allclose(slip, ref.slip, rtol=0, atol=1e-12)
        np.testing.assert_allclose(force, ref.force, rtol=1e-10, atol=1e-12)
        assert out[-1] == pytest.approx(ref.power, rel=1e-10, abs=1e-12)


def _both(robot, t_end, q0, nu0, torque, **kw):
    a = simulate(robot, t_end, q0, nu0, torque, progress=False, **kw)
    b = simulate(robot, t_end, q0, nu0, torque, progress=False, engine="scipy", **kw)
    assert a.stats["engine"].startswith("compiled") and b.stats["engine"].startswith("scipy")
    return a, b


@pytest.mark.parametrize("scenario", ["turn_in_place", "straight"])
def test_skid_steer_trajectories_agree(scenario):
    """The rover's scenarios (linear law, both directions slip) on both engines: q to 1e-8, nu and the friction
    work to 1e-7; the work is never positive."""
    mod = read(EXAMPLE)
    robot = mod.robot()
    sc = mod.SCENARIOS[scenario]
    q0, nu0 = sc.initial_state(robot)
    a, b = _both(robot, 0.5, q0, nu0, sc.torque, n_out=51)
    np.testing.assert_array_equal(a.t, b.t)
    assert np.max(np.abs(a.q - b.q)) < 1e-8
    assert np.max(np.abs(a.nu - b.nu)) < 1e-7
    assert np.max(np.abs(a.friction_work - b.friction_work)) < 1e-7
    assert np.all(np.diff(a.friction_work) <= 1e-12) and a.friction_work[-1] < -1e-3


@pytest.mark.parametrize("law", ["lateral linear", "lateral coulomb"])
def test_lateral_slip_turn_agrees(law):
    """Lateral slip (longitudinal no-slip rows kept), turning in place under constant torques: both engines agree
    to 1e-8 on q, and the yaw rate follows the closed form of tests/test_lateral_slip.py for the linear law
    (omega* (1 - exp(-t/T)), checked on the compiled trajectory against the scipy one's closed-form error)."""
    robot = _rover(**ROVERS[law])
    tau = 0.3
    torque = Constant([-tau, tau, -tau, tau])
    a, b = _both(robot, 0.3, robot.neutral(), np.zeros(3), torque, n_out=31)
    assert np.max(np.abs(a.q - b.q)) < 1e-8
    assert np.max(np.abs(a.nu - b.nu)) < 1e-7
    assert np.max(np.abs(a.friction_work - b.friction_work)) < 1e-8
    if law == "lateral linear":
        from test_lateral_slip import A, B, R, _yaw_inertia

        mass = sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))
        fn, stiffness = mass * G / 4, 5.0
        omega_star = tau * B / (R * fn * stiffness * A**2)
        T = _yaw_inertia(robot) / (4 * fn * stiffness * A**2)
        closed = omega_star * (1 - np.exp(-a.t / T))
        assert np.max(np.abs(a.column("yaw_dot") - closed)) < 1e-6 * omega_star


def test_linkage_slip_energy_balance():
    """The six-wheel linkage robot on a sine terrain with its middle wheels slipping (Coulomb), torque-free: both
    engines agree to 1e-8 on q, and on each E(t) - E(0) equals the friction work to 1e-6 of the loss."""
    from test_linkage_slip import _robot

    robot, q0 = _robot(slipping=True)
    nu0 = np.zeros(robot.mobility)
    nu0[robot.velocity_names.index("phi2_dot")] = nu0[robot.velocity_names.index("phi5_dot")] = 3.0
    a, b = _both(robot, 0.3, q0, nu0, None, n_out=31)
    assert np.max(np.abs(a.q - b.q)) < 1e-8
    for traj in (a, b):
        scale = abs(traj.friction_work[-1])
        assert scale > 1e-4
        np.testing.assert_allclose(traj.energy - traj.energy[0], traj.friction_work, atol=1e-6 * max(scale, 1.0))


@pytest.mark.parametrize("engine", ["compiled", "scipy"])
def test_disc_slides_down_incline_at_the_closed_form(engine):
    """A disc sliding down a slope tan a = 2 > 3 mu (mu = 0.3, Coulomb, v_s = 1e-6 m/s), launched at 1 m/s without
    spin, keeps sliding: along the slope d(t) = v0 t + g (sin a - mu cos a) t^2 / 2, the spin rate
    mu g cos(a) R m / I t, the energy lost equals the friction work."""
    from test_sliding import I, M, R

    slope, mu = 2.0, 0.3
    robot, q0 = disc(slope, friction="coulomb", mu=mu, slip_velocity=1e-6)
    alpha = np.arctan(slope)
    nu0 = np.array([-np.cos(alpha), 0.0, 0.0, 0.0, 0.0])
    traj = simulate(robot, 0.5, q0, nu0, n_out=51, progress=False, engine=engine)
    assert traj.stats["engine"].startswith(engine)
    t = traj.t
    d = t + G * (np.sin(alpha) - mu * np.cos(alpha)) * t**2 / 2
    np.testing.assert_allclose(-(traj.column("x") - q0[0]) / np.cos(alpha), d, rtol=1e-9, atol=1e-11)
    spin = mu * G * np.cos(alpha) * R * M / I * t
    np.testing.assert_allclose(np.abs(traj.column("spin_dot")), spin, rtol=1e-8, atol=1e-10)
    loss = traj.energy - traj.energy[0]
    np.testing.assert_allclose(loss, traj.friction_work, atol=1e-8 * abs(traj.friction_work[-1]))


@pytest.fixture(scope="module")
def over_the_bump():
    """A disc sliding and spinning at 6 m/s towards a smooth step (0.1 m high, 0.3 m wide): its normal load reaches
    zero on the step's convex edge (lift-off), on both engines."""
    robot, q = disc(0.0, friction="coulomb", mu=0.5, slip_velocity=1e-2)
    set_terrain(robot, BumpTerrain(0.1, 1.0, 0.3))
    q = on_ground(robot, q)
    return robot, _both(robot, 0.3, q, [6.0, 0, 0, 0, 10.0], None, n_out=301)


def test_lift_off_time_equals_the_python_path(over_the_bump):
    """The terminal event: the same lift-off time to 1e-8 s, the same message, the load zero there (to the event
    location), the samples up to it and equal to 1e-8 on q."""
    robot, (a, b) = over_the_bump
    assert "event" in a.stats and "event" in b.stats
    assert abs(a.stats["t_event"] - b.stats["t_event"]) < 1e-8
    assert 0.1 < a.stats["t_event"] < 0.3
    for traj in (a, b):
        assert traj.stats["event"].startswith(f"wheel disc unloads at t = {traj.stats['t_event']:.6g} s")
        assert 'contact = "compliant"' in traj.stats["event"]  # what lets it fly (before: "not modelled")
        assert traj.t[-1] <= traj.stats["t_event"] < traj.t[-1] + 1e-3
    assert a.stats["event"].split("(")[0] == b.stats["event"].split("(")[0]
    np.testing.assert_array_equal(a.t, b.t)
    assert np.max(np.abs(a.q - b.q)) < 1e-8
    # the load just before the event is positive and falling to zero at it
    last = forward(robot, a.q[-1], a.nu[-1], np.zeros(0)).normal[0]
    assert 0 < last < 0.05 * M_G(robot)


def M_G(robot) -> float:
    return G * sum(robot.model.inertias[i].mass for i in range(robot.model.njoints))


@pytest.mark.parametrize("method", ["bulirsch_stoer", "dopri5"])
def test_lift_off_on_the_dense_output_steppers(over_the_bump, method):
    """The event located on the dense output of the other compiled integrators: the same time to 1e-8 s."""
    robot, (_, ref) = over_the_bump
    traj = simulate(robot, 0.3, ref.q[0], ref.nu[0], None, n_out=301, progress=False, method=method)
    assert abs(traj.stats["t_event"] - ref.stats["t_event"]) < 1e-8


def test_engine_choice():
    """engine="auto" takes the compiled engine for slipping wheels with compiled laws, the scipy engine when asked;
    a law without a compiled formula or exact stick-slip keeps the robot on the Python path, with the reason."""
    robot = _rover()
    assert choose_engine(robot, None, None, "auto") is True
    assert choose_engine(robot, None, None, "scipy") is False

    class Cubic(RegularisedCoulomb):
        def coefficient(self, s):
            return self.mu * s * float(s @ s)

    other = _rover()
    wheel = slipping_wheels(other)[0]
    wheel.law = Cubic(0.5)
    assert compiled_model(other).slip_refusal is not None  # another law: the compiled model is rebuilt
    assert choose_engine(other, None, None, "auto") is False
    with pytest.raises(RobotDynError, match="whose formula is not compiled") as exc:
        choose_engine(other, None, None, "compiled")
    assert "\n" not in str(exc.value)
    stick, _ = disc(0.0, friction="stick_slip", mu=0.3)
    with pytest.raises(RobotDynError, match="stick-slip wheels"):
        choose_engine(stick, None, None, "compiled")


def test_simulate_many_refuses_slipping_wheels():
    from robotdyn.simulation.many_runs import simulate_many

    robot = _rover()
    with pytest.raises(RobotDynError, match="slipping wheels") as exc:
        simulate_many(robot, 0.1, robot.neutral(), np.zeros(robot.mobility))
    assert "\n" not in str(exc.value)


# ------------------------------------------------------------------ the Painleve test (singularity of the coupled system)
def _python_condition(monkeypatch):
    """A spy on np.linalg.cond as robotdyn.contact.sliding.forward calls it: the coupled system K of its last call."""
    seen = {}
    cond = np.linalg.cond

    def spy(K, p=None):
        if p is None:
            seen["K"] = np.array(K, copy=True)
        return cond(K, p)

    monkeypatch.setattr(np.linalg, "cond", spy)
    return seen


@pytest.mark.parametrize("kind", ROVERS)
def test_painleve_test_clears_regular_states_from_the_estimate(kind, monkeypatch):
    """At the regular states of test_one_state_equals_the_python_path, Evaluator.slip_rhs takes the Python path's
    decision (np.linalg.cond(K) <= 1e12: no error) from LAPACK's 1-norm estimate alone (no singular values), and
    that estimate is the exact 1-norm condition number of K to within the factor 100 the rule relies on."""
    seen = _python_condition(monkeypatch)
    robot = _rover(**ROVERS[kind])
    fast = compiled_model(robot)
    for q, nu, tau in _tilted_states(robot):
        ref = forward(robot, q, nu, tau)
        K = seen["K"]
        assert np.linalg.cond(K) <= 1e12  # regular on the Python path
        fast.select(ref.reduced.projection)
        fast.ev.slip_rhs(q, nu, tau, 0.0)  # regular on the compiled path (a SlipError would raise)
        estimate, exact = fast.ev.slip_condition
        assert np.isnan(exact)  # decided by the estimate
        kappa1 = np.linalg.cond(K, 1)
        assert kappa1 / 100 <= estimate <= kappa1 * (1 + 1e-9)
        assert len(K) * estimate <= 1e10


def test_painleve_decision_near_the_singular_friction_coefficient(monkeypatch):
    """A constructed Painleve case: at a fixed state of the rover (Coulomb law, both directions slip) K is affine
    in mu, K(mu) = K0 + mu D, and singular at a real mu* (about 6.7 here: an eigenvalue of -K0^-1 D). At friction
    coefficients far from mu* and approaching it from both sides, conditions from 1e3 to beyond 1e15, Evaluator.slip_rhs raises
    exactly where np.linalg.cond(K) > 1e12 (on the Python path, sliding.forward raises there), with the same
    condition number; the states near the threshold (2-norm condition above 1e10) all went to the singular values
    (none was cleared by the estimate). Where K is regular but the effective normal matrix is no P-matrix (beyond
    mu*: robotdyn.contact.painleve), both refuse with the Painleve check instead."""
    from robotdyn.contact.friction import RegularisedCoulomb as Coulomb
    from robotdyn.errors import SingularConstraintError

    seen = _python_condition(monkeypatch)
    robot = _rover(**ROVERS["coulomb"])
    k = robot.mobility
    q = robot.neutral()
    q[robot.coordinate_index("roll")] = -0.007
    nu = np.array([0.17, 0.48, 0.91, -0.43, 0.3, 0.39, -0.41])
    tau = np.array([-1.0, 0.95, -0.4, -0.37])
    assert len(nu) == k

    def with_mu(mu):
        for wheel in slipping_wheels(robot):
            wheel.law = Coulomb(mu, 0.01)  # a new law object: the compiled model is rebuilt with it

    def python_K(mu):
        with_mu(mu)
        seen["refusal"] = None
        try:
            forward(robot, q, nu, tau)
        except SingularConstraintError as exc:
            seen["refusal"] = str(exc)
        return seen["K"]

    K0, K1 = python_K(0.0), python_K(1.0)
    eig = np.linalg.eigvals(-np.linalg.solve(K0, K1 - K0))
    roots = [1 / e.real for e in eig if abs(e) > 1e-12 and abs(e.imag) <= 1e-9 * abs(e)]
    mu_star = min((r for r in roots if r > 0), default=None)
    assert mu_star is not None and 1.0 < mu_star < 20.0, roots
    projection = robot.reduced(q, nu).projection  # K's row choice does not depend on mu
    # cond(K(mu* + d)) ~ a / |d| near the root: distances for conditions of about 1e3 ... 1e15
    a = np.linalg.cond(python_K(mu_star * 0.999)) * mu_star * 1e-3
    mus = [0.5, 0.5 * mu_star, 2.0 * mu_star]  # far from it
    for target in (1e8, 1e9, 1e10, 1e11, 3e11, 6e11, 1.6e12, 3e12, 1e13, 1e15):
        mus += [mu_star - a / target, mu_star + a / target]
    results, refused = [], []
    for mu in mus:
        cond = np.linalg.cond(python_K(mu))  # the Python path's decision
        python_singular = not np.isfinite(cond) or cond > 1e12
        fast = compiled_model(robot)
        fast.select(projection)
        python_painleve = not python_singular and seen["refusal"] is not None  # (the Painleve check's refusal)
        try:
            fast.ev.slip_rhs(q, nu, tau, 0.0)
            compiled_singular = compiled_painleve = False
        except RuntimeError as exc:
            compiled_singular = "singular slipping contact problem" in str(exc)
            compiled_painleve = "no P-matrix" in str(exc)
            assert compiled_singular or compiled_painleve, str(exc)
        estimate, exact = fast.ev.slip_condition
        results.append((mu, cond, compiled_singular))
        assert compiled_singular == python_singular, (mu, cond, estimate, exact)
        assert compiled_painleve == python_painleve, (mu, cond, seen["refusal"])
        refused.append(compiled_painleve)
        if cond > 1e10:
            assert not np.isnan(exact), (mu, cond, estimate)  # the singular values decided
        if not np.isnan(exact) and cond < 1e14:  # the same number (both from singular values)
            assert exact == pytest.approx(cond, rel=1e-3)
    assert not refused[0] and refused[2]  # regular at mu = 0.5, the Painleve check's refusal at 2 mu*
    conds = [c for _, c, _ in results]
    assert min(conds) < 1e5 and max(conds) > 1e14  # the sweep spans the threshold widely
    assert any(1e11 < c <= 1e12 for c in conds) and any(1e12 < c < 1e13 for c in conds)  # and near it

"""Feedback laws as data (robotdyn.simulation.feedback, its C++ twin robotdyn/_controller.hpp): the C++ torques equal
the Python law's at random states, the built-in controller scenarios run on the compiled engine and end where
their scipy runs end, and the data forms of the scenarios' references equal their closed forms."""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn
from robotdyn.errors import InputError, RobotDynError
from robotdyn.fast.dispatch import available, compiled_model
from robotdyn.robots import module
from robotdyn.simulation.compiled_engine import choose_engine, native_profile
from robotdyn.simulation.engine import simulate
from robotdyn.simulation.feedback import FeedbackLaw, lqr_law
from robotdyn.simulation.torque_profile import Constant, Polynomial, Sine, Table

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")


def test_polynomial_profile_is_the_same_in_cpp_and_python_bit_for_bit():
    """A windowed cubic (two values): C++ and Python give the same bits, the closed form to 1e-15, zero outside."""
    coef = np.array([[0.5, -1.0], [0.25, 2.0], [-3.0, 0.125], [1.5, 0.75]])
    p = Polynomial(coef, 0.2, 1.7) + Constant([0.1, 0.0])
    nat = native_profile(p)
    for t in np.linspace(-0.5, 2.0, 41):
        assert np.array_equal(np.asarray(nat(t)), p(t))
        inside = 0.2 <= t <= 1.7
        closed = np.array([0.1, 0.0]) + inside * sum(coef[i] * t**i for i in range(4))
        assert np.allclose(p(t), closed, rtol=0, atol=1e-15)
    assert np.array_equal(p.at([0.3, 1.9]), np.stack([p(0.3), p(1.9)]))
    assert p.breakpoints().tolist() == [0.2, 1.7]
    with pytest.raises(InputError, match="window"):
        Polynomial([1.0], 2.0, 1.0)


def test_linkage_speed_reference_is_the_half_cosine_profile():
    """The data form of the section 3 wheel-speed profile equals wheel_speed's closed form (ramps, hold, rest),
    also at the window edges, where the windows must not add up."""
    lk = module("linkage_suspension")
    ref = lk.speed_reference((1.0, -1.0))
    t = np.concatenate([np.linspace(-0.1, 4.6, 301), lk.PROFILE[:4]])
    for ti in t:
        w = lk.wheel_speed(ti)[0]
        assert ref(ti) == pytest.approx([w, -w], abs=1e-13)


def test_circle_law_acceleration_is_the_path_acceleration():
    """The circle's reference acceleration as a polynomial in t equals path_state's u'' (eq 61 derivative)."""
    oc = module("omni_caster")
    robot = robotdyn.load("omni_caster")
    law = oc.circle_law(robot)
    t = np.linspace(-1.0, oc.CIRCLE["T"] + 1.0, 97)
    assert np.allclose(law.acceleration.at(t), oc.path_state("circle", t)["nudot"], rtol=0, atol=1e-15)


def test_ellipse_law_acceleration_is_the_path_acceleration():
    """The ellipse's reference acceleration as a piecewise polynomial (a fit: u'' is a function of beta(t), not a
    polynomial of t) equals path_state's u'' to 1e-13 (max |u''| = 0.84) on [0, T], zero outside, for both headings;
    its only breakpoints are the ends of the motion."""
    oc = module("omni_caster")
    robot = robotdyn.load("omni_caster")
    t = np.linspace(-1.0, oc.ELLIPSE["T"] + 1.0, 4001)
    for params in (None, {"heading": "fixed"}):
        law = oc.ellipse_law(robot, params)
        assert np.abs(law.acceleration.at(t) - oc.path_state("ellipse", t, params)["nudot"]).max() < 1e-13
        assert law.acceleration.breakpoints().tolist() == [0.0, oc.ELLIPSE["T"]]


def test_ellipse_runs_compiled_and_ends_where_the_closed_form_law_ends_on_scipy():
    """The ellipse scenario (its law as data, compiled) against the same feed-forward written with path_state's
    closed-form u''(t) as a Python callable on scipy's LSODA, both at rtol = atol = 1e-9, over 6 s: the final states
    agree to 1e-6 (the circle's tolerance), and the platform twist follows the plan to 1e-7 at every sample."""
    oc = module("omni_caster")
    robot = robotdyn.load("omni_caster")
    sc = oc.SCENARIOS["ellipse"]
    fast = sc.run(robot, t_end=6.0, n_out=13, progress=False)
    q0, nu0 = sc.initial_state(robot)

    def closed_form(t, q, nu):
        red = robot.reduced(q, nu)
        return np.linalg.lstsq(red.B, red.M @ oc.path_state("ellipse", t)["nudot"] + red.h, rcond=None)[0]

    ref = simulate(robot, 6.0, q0, nu0, closed_form, n_out=13, method="LSODA", rtol=1e-9, atol=1e-9,
                   progress=False)
    assert fast.stats["engine"].startswith("compiled") and ref.stats["engine"].startswith("scipy")
    assert np.abs(fast.q[-1] - ref.q[-1]).max() <= 1e-6 and np.abs(fast.nu[-1] - ref.nu[-1]).max() <= 1e-6
    assert np.abs(fast.nu - oc.path_state("ellipse", fast.t)["nu"]).max() < 1e-7
    assert np.abs(fast.q[-1] - fast.q[0]).max() > 1e-2


def _random_states(robot, qs, rng):
    """The configurations ``qs`` (on the constraint manifold) with random independent velocities."""
    return [(q, rng.normal(size=robot.mobility)) for q in qs]


def _along(scenario):
    """Configurations along 1 s of ``scenario`` (6 samples after the start)."""
    def qs(robot):
        return scenario.run(robot, t_end=1.0, n_out=7, progress=False).q[1:]
    return qs


def _near_neutral(robot):
    rng = np.random.default_rng(4)
    return [robot.neutral() + 0.05 * rng.normal(size=robot.nq) for _ in range(6)]


def _laws():
    """(robot name, law builder, start state builder): each term of the law on a robot that needs it."""
    lk = module("linkage_suspension")
    oc = module("omni_caster")
    yield "linkage_suspension", lambda r: lk.SCENARIOS["straight_line"].torque, _along(lk.SCENARIOS["straight_line"])
    yield "omni_caster", lambda r: oc.circle_law(r), _along(oc.SCENARIOS["circle"])

    def full(r):  # every term at once, random gains
        rng = np.random.default_rng(3)
        m, n, k = len(r.motors), r.nq, r.mobility
        return FeedbackLaw(Sine(rng.normal(size=m), 1.3, 0.2), rng.normal(size=(m, n)),
                           Table([0.0, 1.0], rng.normal(size=(2, n))), rng.normal(size=(m, k)),
                           Polynomial(rng.normal(size=(3, k)), 0.0, 2.0), Sine(rng.normal(size=k), 0.7), robot=r)

    yield "quasimoro", full, _near_neutral
    yield "mmr12_eod", full, _near_neutral


@pytest.mark.parametrize("name, build, start", list(_laws()), ids=[c[0] for c in _laws()])
def test_cpp_law_equals_python_law_at_random_states(name, build, start):
    """C++ torques (Evaluator.control_torque) equal the Python law's (on the Python reduced model) to 1e-12
    (relative to the largest torque), at six states with random velocities and times."""
    robot = robotdyn.load(name)
    law = build(robot).bound(robot)
    fast = compiled_model(robot)
    native = law.native(robot)
    rng = np.random.default_rng(11)
    qs = start(robot)
    fast.compute(qs[0], np.zeros(robot.mobility))  # a row choice for the compiled model (as a run makes)
    for q, nu in _random_states(robot, qs, rng):
        t = float(rng.uniform(0.0, 4.0))
        red = robot.reduced(q, nu)
        want = law.torque(t, q, nu, red.M, red.h, red.B)
        got = np.asarray(fast.ev.control_torque(native, t, q, nu))
        assert np.abs(got - want).max() <= 1e-12 * max(1.0, np.abs(want).max())


def _scenario_runs():
    """(label, robot, run(engine) -> trajectory, tolerance on the final state): the built-in controller
    scenarios that are feedback laws. Tolerances: 1e-7 at rtol 1e-10 (linkage); 1e-6 at rtol 1e-9 on the circle,
    whose wheel angles reach 45 rad (2e-8 relative)."""
    lk = module("linkage_suspension")
    link = robotdyn.load("linkage_suspension")
    yield "linkage straight_line", link, lambda e: lk.SCENARIOS["straight_line"].run(link, progress=False, engine=e), 1e-7
    yield "linkage pivot_steering 2 s", link, lambda e: lk.SCENARIOS["pivot_steering"].run(
        link, t_end=2.0, progress=False, engine=e), 1e-7
    oc = module("omni_caster")
    caster = robotdyn.load("omni_caster")
    yield "omni circle 10 s", caster, lambda e: oc.SCENARIOS["circle"].run(caster, t_end=10.0, progress=False,
                                                                            engine=e), 1e-6


@pytest.mark.parametrize("label, robot, run, tol", list(_scenario_runs()), ids=[c[0] for c in _scenario_runs()])
def test_controller_scenarios_run_compiled_and_end_where_scipy_ends(label, robot, run, tol):
    """Both engines at the scenario's tolerances (rtol 1e-10, atol 1e-12; the circle 1e-9, 1e-9): the final
    states agree to ``tol`` (each engine's global error is some hundred times its local tolerance over these
    runs), and the closed loop did something (the state moved)."""
    fast, ref = run("auto"), run("scipy")
    assert fast.stats["engine"].startswith("compiled") and ref.stats["engine"].startswith("scipy")
    assert np.array_equal(fast.t, ref.t)
    assert np.abs(fast.q[-1] - ref.q[-1]).max() <= tol
    assert np.abs(fast.nu[-1] - ref.nu[-1]).max() <= tol
    assert np.abs(fast.q[-1] - fast.q[0]).max() > 1e-2


def test_lqr_law_is_lqr_torque_and_holds_quasimoro_compiled():
    """lqr_law gives lqr_torque's torques (1e-12) and holds Quasimoro's inverted body on the compiled engine as on
    scipy's (final states within 1e-7)."""
    from robotdyn.reduction.linearization import linearize, lqr, lqr_torque

    robot = robotdyn.load("quasimoro")
    q0 = robot.neutral()
    q0[robot.coordinate_index("theta3")] = np.pi  # the body upright: unstable without the controller
    model = linearize(robot, q0, np.zeros(3), np.zeros(2)).restrict(["theta3", "theta1_dot", "theta2_dot",
                                                                      "theta3_dot"])
    K, _ = lqr(model, np.eye(4), np.eye(2))
    law, ref = lqr_law(model, K), lqr_torque(model, K)
    rng = np.random.default_rng(2)
    for _ in range(5):
        q, nu = q0 + 0.1 * rng.normal(size=robot.nq), rng.normal(size=3)
        assert np.abs(law(0.0, q, nu) - ref(0.0, q, nu)).max() <= 1e-12
    start = q0.copy()
    start[robot.coordinate_index("theta3")] += 0.1
    fast = simulate(robot, 5.0, start, np.zeros(3), law, n_out=11, rtol=1e-10, atol=1e-12, progress=False)
    slow = simulate(robot, 5.0, start, np.zeros(3), law, n_out=11, rtol=1e-10, atol=1e-12, progress=False,
                    engine="scipy")
    assert fast.stats["engine"].startswith("compiled")
    assert np.abs(fast.q[-1] - slow.q[-1]).max() <= 1e-7 and np.abs(fast.nu[-1] - slow.nu[-1]).max() <= 1e-7
    assert abs(fast.q[-1, robot.coordinate_index("theta3")] - np.pi) < 0.1 * 0.1  # held upright


def test_engine_choice_for_laws_and_one_line_errors():
    """A law runs compiled under auto; a Python callable does not (one line under engine='compiled'); a law for
    another robot is a one-line InputError."""
    robot = robotdyn.load("quasimoro")
    law = FeedbackLaw(Knu=np.ones((2, 3)))
    assert choose_engine(robot, law, None, "auto") is True
    assert choose_engine(robot, lambda t, q, nu: np.zeros(2), None, "auto") is False
    with pytest.raises(RobotDynError, match="Python function.*FeedbackLaw"):
        choose_engine(robot, lambda t, q, nu: np.zeros(2), None, "compiled")
    with pytest.raises(InputError, match=r"K_nu of size \(3, 3\).*expects \(2, 3\)"):
        simulate(robot, 1.0, robot.neutral(), np.zeros(3), FeedbackLaw(Knu=np.ones((3, 3))), progress=False)
    with pytest.raises(InputError, match="without its gain"):
        FeedbackLaw(nu_ref=Constant([0.0, 0.0, 0.0]))
    with pytest.raises(InputError, match="needs a robot"):
        FeedbackLaw(acceleration=Constant([0.0, 0.0, 0.0]))(0.0, robot.neutral(), np.zeros(3))


def test_windows_meeting_one_double_apart_make_one_breakpoint():
    """The linkage reference's windows meet one double apart: the law has one breakpoint per kink (0.2, 1.2, 3.2,
    4.2 s), so that no integrator is asked for a one-ulp step there (dopri5 failed at t = 1.2 s before)."""
    lk = module("linkage_suspension")
    law = lk.SCENARIOS["straight_line"].torque
    assert law.breakpoints().tolist() == list(lk.PROFILE[:4])
    robot = robotdyn.load("linkage_suspension")
    traj = lk.SCENARIOS["straight_line"].run(robot, t_end=1.5, n_out=4, progress=False, method="dopri5")
    assert traj.stats["engine"] == "compiled (dopri5)" and traj.t[-1] == 1.5


# ------------------------------------------------------------------ the linearising controller on the compiled loop
@pytest.mark.parametrize("name", ["orientation", "straight", "sinusoid"])
def test_table4_references_as_data_are_the_closed_forms(name):
    """MMR12-EOD's Table 4 references (sines and polynomials) equal the printed closed forms to 1e-13."""
    ref = module("mmr12_eod").table4_reference(name)
    L, w = module("mmr12_eod").LOOK_AHEAD, 0.5
    for t in np.linspace(0.0, 200.0, 41):
        if name == "orientation":
            want = (L * np.array([np.cos(w * t), np.sin(w * t)]), L * w * np.array([-np.sin(w * t), np.cos(w * t)]),
                    -L * w**2 * np.array([np.cos(w * t), np.sin(w * t)]))
        elif name == "straight":
            want = (np.array([30.0, t]), np.array([0.0, 1.0]), np.zeros(2))
        else:
            want = (np.array([40 * np.cos(0.25 * t) + 2.5 * t, 30 * np.sin(0.25 * t)]),
                    np.array([-10 * np.sin(0.25 * t) + 2.5, 7.5 * np.cos(0.25 * t)]),
                    np.array([-2.5 * np.cos(0.25 * t), -1.875 * np.sin(0.25 * t)]))
        for got, exp in zip(ref(t), want):
            assert np.allclose(got, exp, rtol=0, atol=1e-13 * max(1.0, t))


def test_cpp_linearising_controller_equals_python_at_states_along_a_run():
    """The C++ Linearising law (point task with an offset, coordinate hold task, null-space damping, computed
    torque) gives LinearisingController.command's torques to 1e-12 (relative) at states along the sinusoid run,
    with random velocities."""
    mm = module("mmr12_eod")
    robot = robotdyn.load("mmr12_eod")
    sc = mm.SCENARIOS["sinusoid"]
    run_robot, ctrl = sc.prepare(robot)
    traj = sc.run(robot, t_end=2.0, n_out=5, progress=False)
    fast = compiled_model(run_robot)
    native = ctrl.native_controller(run_robot, fast)
    rng = np.random.default_rng(5)
    for t, q in zip(traj.t, traj.q):
        nu = 0.3 * rng.normal(size=run_robot.mobility)
        want = ctrl.command(t, q, nu)[1]
        got = np.asarray(fast.ev.control_torque(native, t, q, nu))
        assert np.abs(got - want).max() <= 1e-12 * max(1.0, np.abs(want).max())


@pytest.mark.parametrize("name", ["orientation", "sinusoid"])
def test_mmr12_platform_scenarios_run_compiled_and_end_where_scipy_ends(name):
    """Table 4 tasks over 20 s at the scenario's tolerances (rtol 1e-8, atol 1e-10): compiled under auto, and the
    final states within 1e-5 of the scipy run's (the tracking error is what the paper plots)."""
    robot = robotdyn.load("mmr12_eod")
    sc = module("mmr12_eod").SCENARIOS[name]
    fast = sc.run(robot, t_end=20.0, n_out=21, progress=False)
    ref = sc.run(robot, t_end=20.0, n_out=21, progress=False, engine="scipy")
    assert fast.stats["engine"].startswith("compiled") and ref.stats["engine"].startswith("scipy")
    assert np.abs(fast.q[-1] - ref.q[-1]).max() <= 1e-5 and np.abs(fast.nu[-1] - ref.nu[-1]).max() <= 1e-5


def test_quintic_reference_as_data_is_the_quintic():
    """MMR12-EOD's rest-to-rest quintic as data equals _quintic (value, rate, acceleration) to 1e-13, before, inside
    and after the motion."""
    from robotdyn.robots.mmr12_eod.model import _quintic as quintic

    mm = module("mmr12_eod")
    a, b, T = np.array([0.3, -1.0]), np.array([2.0, 0.5]), 5.0
    ref = mm.quintic_reference(T, a, b)
    for t in [*np.linspace(0.0, 7.0, 57), T]:
        for got, exp in zip(ref(t), quintic(t, T, a, b)):
            assert np.allclose(got, exp, rtol=0, atol=1e-13)


@pytest.mark.parametrize("name, t_end", [("manipulation", 12.0), ("lifting", 6.0)])
def test_mmr12_quintic_scenarios_run_compiled_and_end_where_scipy_ends(name, t_end):
    """The manipulation (secondary posture task) and lifting (underactuated: x, y, psi free) scenarios run compiled,
    their C++ torques equal the Python controller's to 1e-12 along the run, and the final states are within 1e-5 of
    the scipy run's."""
    robot = robotdyn.load("mmr12_eod")
    sc = module("mmr12_eod").SCENARIOS[name]
    fast = sc.run(robot, t_end=t_end, n_out=7, progress=False)
    ref = sc.run(robot, t_end=t_end, n_out=7, progress=False, engine="scipy")
    assert fast.stats["engine"].startswith("compiled") and ref.stats["engine"].startswith("scipy")
    assert np.abs(fast.q[-1] - ref.q[-1]).max() <= 1e-5 and np.abs(fast.nu[-1] - ref.nu[-1]).max() <= 1e-5
    run_robot, ctrl = fast.stats["robot"], fast.stats["controller"]
    comp = compiled_model(run_robot)
    native = ctrl.native_controller(run_robot, comp)
    for t, q, nu in zip(fast.t, fast.q, fast.nu):
        want = ctrl.command(t, q, nu)[1]
        got = np.asarray(comp.ev.control_torque(native, t, q, nu))
        assert np.abs(got - want).max() <= 1e-12 * max(1.0, np.abs(want).max())

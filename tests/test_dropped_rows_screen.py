"""The screen of forward dynamics' dropped-row check (robotdyn.fast.dropped_rows): its drift estimate (a central
difference of the compiled rows along v) against the Python rows' Adot v, and its verdicts against the exact check
(robotdyn.constraints.redundancy.violations), where no row is violated (the built-in robots) and where one is (the
swerve base at zero steering, whose closed form tests/test_ros_descriptions.py states)."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import robotdyn
from robotdyn.constraints import redundancy
from robotdyn.errors import RobotDynWarning
from robotdyn.fast import dropped_rows
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.interfaces.constraint_file import load_robot
from robotdyn.reduction.reduced_dynamics import solve_mass

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_dynamics_derivatives import START, admissible_state  # noqa: E402

SWERVE = Path(__file__).resolve().parent.parent / "examples" / "ros_ws" / "src" / "demo_description" / "robotdyn"


def warned(fn, *args):
    """``fn(*args)`` with robotdyn's warnings recorded: (result, [messages])."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args)
    return out, [str(w.message) for w in caught if issubclass(w.category, RobotDynWarning)]


@pytest.fixture(scope="module")
def swerve():
    return load_robot(SWERVE / "swerve3.toml")


@pytest.mark.parametrize("name", sorted(START))
def test_drift_estimate_is_the_python_rows_drift_well_within_the_checks_tolerance(name):
    """The estimate's error, against the exact check's own scale (largest |Adot| entry times ||v||_1), is far below
    the 0.75 TOL that the screen's margin leaves it (measured about 1e-11; 1e-9 asserted)."""
    robot = robotdyn.load(name)
    rng = np.random.default_rng(4)
    for _ in range(2):
        q, nu, tau = admissible_state(robot, START[name], rng)
        red = robot.reduced(q, nu)
        rows = red.rows  # the Python rows with Adot
        d = dropped_rows.drift_estimate(robot, q, red.v)
        assert d is not None  # the compiled model serves every built-in robot
        scale = np.abs(rows.Adot).max() * np.abs(red.v).sum()
        assert np.abs(d - rows.Adot @ red.v).max() <= 1e-9 * scale
        assert 1e-9 < (1 - dropped_rows.MARGIN) * redundancy.TOL
        nudot = solve_mass(red.M, red.B @ tau - red.h)
        assert dropped_rows.violations(robot, red, q, nudot) == redundancy.violations(red, nudot) == []


def test_screen_gives_the_exact_checks_violations_and_messages(swerve, monkeypatch):
    """Near the swerve base's zero steering (rear lateral rows coincident, dropped one violated by
    abs(s'_rl - s'_rr) x'), random rear steering rates: the screen's list equals the exact check's at every state,
    violated or not; forward_dynamics' and inverse_dynamics' warning is the exact check's message; a screen that
    cleared everything would fail here (the violated states are more than half)."""
    rng = np.random.default_rng(5)
    q = swerve.neutral()
    exact_calls = []
    exact = dropped_rows.exact_violations
    monkeypatch.setattr(dropped_rows, "exact_violations", lambda *a: exact_calls.append(1) or exact(*a))
    violated = 0
    for i in range(12):
        nu = rng.normal(size=4)
        if i % 3 == 0:
            nu[3] = nu[2]  # rear wheels steered at the same rate: the rows stay dependent
        nudot, messages = warned(swerve.forward_dynamics, q, nu, np.zeros(4))
        red = swerve.reduced(q, nu)
        found = exact(red, nudot)
        assert dropped_rows.violations(swerve, red, q, nudot) == found
        assert messages == ([redundancy.message(found)] if found else [])
        assert warned(swerve.inverse_dynamics, q, nu, nudot)[1] == messages  # the same check, the same warning
        violated += bool(found)
        if found:
            assert abs(found[0].acceleration) == pytest.approx(abs(nu[2] - nu[3]) * abs(nu[0]), rel=1e-9)
    assert violated >= 6 and len(exact_calls) >= 3 * violated  # each violated state went to the exact check


def test_screen_without_a_compiled_model_is_the_exact_check(swerve):
    q = swerve.neutral()
    nu = np.array([1.0, 0.0, 0.5, -0.3])
    with use_compiled(False):
        assert compiled_model(swerve) is None and dropped_rows.drift_estimate(swerve, q, np.ones(swerve.nq)) is None
        nudot, messages = warned(swerve.forward_dynamics, q, nu, np.zeros(4))
    (found,) = redundancy.violations(swerve.reduced(q, nu), nudot)
    assert len(messages) == 1 and "0.8 m/s^2" in messages[0] and found.label in messages[0]

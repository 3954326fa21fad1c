"""simulate()'s start checks on the compiled rows (robotdyn.simulation.start_checks) and the at-rest dropped-row screen
(robotdyn.fast.dropped_rows): the same refusals, offsets and warnings as the Python rows and the exact check, without
their cost where a start is clean."""

from __future__ import annotations

import importlib
from types import SimpleNamespace

import numpy as np
import pytest

import robotdyn
from robotdyn.constraints.redundancy import violations as exact_violations
from robotdyn.errors import ConstraintError
from robotdyn.fast.dispatch import compiled_model
from robotdyn.fast.dropped_rows import violations as screened_violations
from robotdyn.reduction.pull_back import start_offsets as python_start_offsets
from robotdyn.simulation import start_checks
from robotdyn.simulation.engine import simulate


@pytest.fixture(scope="module")
def adaptable():
    """The adaptable-wheel tricycle (floating root, three wheels and a coupling: 4 holonomic rows), its compiled
    model's rows chosen at the hold scenario's solved posture."""
    robot = robotdyn.load("adaptable_wheel")
    q0, nu0 = importlib.import_module("robotdyn.robots.adaptable_wheel").SCENARIOS["hold"].initial_state(robot)
    simulate(robot, 1e-3, q0, nu0, n_out=2, progress=False)
    assert compiled_model(robot).ready
    return robot, q0, nu0


def _python_refusal(robot, q) -> str:
    with pytest.raises(ConstraintError) as exc:
        robot.check_constraints(q)  # the Python rows' check, as simulate ran it before
    return str(exc.value)


def test_bad_starts_are_refused_with_the_python_rows_message(adaptable):
    robot, q0, nu0 = adaptable
    lifted = q0.copy()
    lifted[robot.coordinate_index("z")] += 1e-3  # every wheel 1 mm above the ground: the root-height advice
    tilted = robot.neutral()  # the wheels at three heights (0.014-0.021 m off): the named row
    for q in (lifted, tilted):
        residual = start_checks.compiled_residuals(robot, q)
        assert residual is not None and np.abs(residual).max() > 1e-4  # the compiled rows see it
        expected = _python_refusal(robot, q)
        with pytest.raises(ConstraintError) as exc:
            simulate(robot, 1e-3, q, nu0, n_out=2, progress=False)
        assert str(exc.value) == expected and "\n" not in expected
    # a continuation (t0 > 0) is not refused for its drift, on either route
    assert start_checks.start_offsets(robot, lifted, 10.0, check=False) == python_start_offsets(
        robot, lifted, 10.0)


def test_a_clean_start_needs_no_python_rows(adaptable, monkeypatch):
    robot, q0, nu0 = adaptable
    residual = start_checks.compiled_residuals(robot, q0)
    python = robot.rows_at(q0).residual
    assert np.abs(residual - python).max() <= 1e-15 and np.abs(residual).max() <= start_checks.CLEAR
    assert python_start_offsets(robot, q0, 10.0) == {}  # what the compiled route returns
    monkeypatch.setattr(robot, "rows_at", lambda q: pytest.fail("the Python rows were computed for a clean start"))
    assert start_checks.start_offsets(robot, q0, 10.0) == {}
    assert simulate(robot, 1e-3, q0, nu0, n_out=2, progress=False).stats["engine"].startswith("compiled")


def test_a_start_off_by_more_than_rounding_takes_the_python_rows(adaptable):
    robot, q0, _ = adaptable
    q = q0.copy()
    q[robot.coordinate_index("z")] += 1e-9  # above CLEAR, within check_constraints' 1e-6
    calls = []
    rows_at = robot.rows_at
    robot.rows_at = lambda q_: calls.append(1) or rows_at(q_)
    try:
        assert start_checks.start_offsets(robot, q, 10.0) == python_start_offsets(robot, q, 10.0)
    finally:
        del robot.rows_at
    assert calls  # decided by the Python rows, whose offsets and refusals are the reference


def _rest_model(violated: bool, projection):
    """A reduced model at rest (v = 0) with rows 0, 1 kept (``projection``'s rows), row 2 a combination of them and
    row 3 not (violated by the accelerations; with ``violated`` False a combination too)."""
    rng = np.random.default_rng(11)
    n, k = 5, 2
    A = rng.normal(size=(4, n))
    A[2] = 0.4 * A[0] - 1.5 * A[1]
    if not violated:
        A[3] = -0.7 * A[0] + 0.2 * A[1]
    N = np.linalg.svd(A[:2])[2][2:].T  # null space of the kept rows
    S, w = N @ rng.normal(size=(n - 2, k)), N @ rng.normal(size=n - 2)
    red = SimpleNamespace(jacobian_rows=SimpleNamespace(A=A, labels=["k0", "k1", "dep", "free"]), S=S, w=w,
                          v=np.zeros(n), projection=projection, rows=None)
    return red, rng.normal(size=k)


class _Refused:
    """A projection whose condition number must not be computed (its rows as given)."""

    rows = np.array([0, 1])

    @property
    def condition(self):
        raise AssertionError("the projection's condition number was computed for a consistent state at rest")


def test_the_at_rest_screen_gives_the_exact_checks_violations():
    red, nudot = _rest_model(False, _Refused())
    assert screened_violations(None, red, np.zeros(5), nudot) == []  # no inverse of A_d for a clean state
    red, nudot = _rest_model(True, SimpleNamespace(rows=np.array([0, 1]), condition=3.0))
    found = screened_violations(None, red, np.zeros(5), nudot)
    assert [f.label for f in found] == ["free"] and found == exact_violations(red, nudot)

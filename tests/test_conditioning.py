"""Issue 24, item 5: accelerations beyond what a state can produce carry a warning naming the ill-conditioned part.

Reference: the adaptable-wheel tricycle near its mechanism limits (adjustment angles near 0 or pi, where the
massless radius linkage stops moving anything: dR/dq = 0 at q = 0 by eq 1, R = w cos(q/2) cos 30 deg, and
R = 0 at q = pi). There the reduced mass matrix S^T M S loses rank while the projection's A_d (the condition number
``dump`` prints) stays regular: the warning must name the mass matrix and its condition number, which is checked
against numpy's eigenvalues, and the acceleration bound |nudot| <= |B tau - h| / lambda_min(S^T M S) (the reason a
huge result needs a huge condition number) is checked on every state.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import robotdyn
from robotdyn.constraints.posture import solve_posture
from robotdyn.errors import RobotDynError, RobotDynWarning
from robotdyn.fast.dispatch import use_compiled
from robotdyn.reduction.conditioning import NAME_CONDITION, PLAUSIBLE_ACCELERATION, ill_conditioned

REPRODUCER = [0, 0, 0.20976393562760176, 0, 0.07393109297367735, -0.18279414161980892, 0, 3.141592643589793,
              1.2990381136904203e-09, 0, 1e-08, 0.2598076211353316, 0, 1e-08, 0.2598076211353316]
HUGE = 1e8  # rad/s^2 for unit torques: the "huge" (1e8 to 3.3e19)


@pytest.fixture(scope="module")
def robot():
    return robotdyn.load("adaptable_wheel")


def _states(robot, near: bool, n: int, seed: int):
    """Valid configurations (posture solved): adjustment angles within 1e-9..3e-2 rad of 0 or pi (near) or in
    [0.4, pi - 0.4] (regular); the configurations where the projection itself is singular (refused in one line,
    not computed) are skipped."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        fixed = {"x": 0.0, "y": 0.0, "yaw": rng.uniform(-1, 1)}
        for t in ("fr", "fl", "r"):
            if near:
                e = 10 ** rng.uniform(-9, -1.5)
                fixed[f"q_{t}"] = e if rng.random() < 0.5 else np.pi - e
            else:
                fixed[f"q_{t}"] = rng.uniform(0.4, np.pi - 0.4)
            fixed[f"theta_{t}"] = rng.uniform(-3, 3)
        q = solve_posture(robot, fixed).q
        try:
            robot.reduced(q, np.full(3, 0.1))
        except RobotDynError:
            continue
        out.append(q)
    return out


def _forward(robot, q):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        a = robot.forward_dynamics(q, np.full(3, 0.1), np.ones(6))
    return a, [str(w.message) for w in caught if issubclass(w.category, RobotDynWarning)
               and "beyond what it can produce" in str(w.message)]


def test_reproducer_names_the_mass_matrix_not_the_projection(robot):
    q = np.array(REPRODUCER)
    red = robot.reduced(q, np.full(3, 0.1))
    ev = np.linalg.eigvalsh(red.M)
    assert red.projection.condition < 1e3  # what dump reports: regular
    assert ev[-1] / ev[0] > 1e15  # the mass matrix: singular to double precision
    for compiled in (True, False):
        with use_compiled(compiled):
            a, found = _forward(robot, q)
        assert np.abs(a).max() > 1e17
        assert len(found) == 1 and "reduced mass matrix S^T M S has condition number" in found[0]
        assert "q_fr_dot" in found[0] and "projection" not in found[0]
    # without torques too: a condition number above 1e10 is reported whatever the result
    assert [p.part for p in robot.conditioning(q, np.full(3, 0.1))] == ["mass matrix"]
    parts = robot.conditioning(q, np.full(3, 0.1), np.ones(6))
    assert [p.part for p in parts] == ["mass matrix"]
    assert parts[0].condition == pytest.approx(ev[-1] / ev[0], rel=1e-6)


@pytest.mark.parametrize("compiled", [True, False])
def test_every_huge_result_near_the_limits_is_warned_and_regular_states_are_not(robot, compiled):
    near, regular = _states(robot, True, 200, 11), _states(robot, False, 30, 12)
    huge = 0
    with use_compiled(compiled):
        for q in near:
            a, found = _forward(robot, q)
            red = robot.reduced(q, np.full(3, 0.1))
            ev = np.linalg.eigvalsh(red.M)
            # |nudot| <= |B tau - h| / lambda_min: a huge result needs a tiny lambda_min or a huge right side
            # (checked where lambda_min itself is resolved in double precision)
            if ev[0] > 0 and ev[-1] / ev[0] < 1e10:
                assert np.linalg.norm(a) <= np.linalg.norm(red.B @ np.ones(6) - red.h) / ev[0] * (1 + 1e-6)
            if np.abs(a).max() > HUGE:
                huge += 1
                assert found, f"no warning at |a| = {np.abs(a).max():.3g}"
            assert bool(found) == bool(ill_conditioned(red, nudot=a))
        for q in regular:
            a, found = _forward(robot, q)
            assert not found and np.abs(a).max() < 1e4
    assert huge >= 40  # the near-limit sample does reach the huge results


def test_cli_dump_warns_once_on_stderr(robot, capsys):
    from robotdyn.cli import main

    args = ["dump", "adaptable_wheel", "--q", *map(str, REPRODUCER), "--v", "0.1", "0.1", "0.1",
            "--tau", "1", "1", "1", "1", "1", "1"]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert captured.err.count("reduced mass matrix S^T M S has condition number 5.61e+15") == 1
    assert "constraint block condition 176, S^T M S condition 5.61e+15" in captured.out  # both shown
    assert main(args[:-7]) == 0  # no torques, no accelerations: nothing to warn about ...
    assert "beyond what it can produce" not in capsys.readouterr().err
    assert main([*args, "--json"]) == 0
    import json

    data = json.loads(capsys.readouterr().out)
    assert data["mass_matrix_condition"] == pytest.approx(5.61e15, rel=1e-2)
    assert [p["part"] for p in data["ill_conditioned"]] == ["mass matrix"]


def test_built_in_robots_are_far_from_the_thresholds_at_neutral():
    """Unit torques at the neutral configuration of each built-in robot: accelerations and conditioning far below
    the thresholds (the largest: MMR12-EOD's S^T M S, 5.8e4, its 0.2 kg slider beside a 99 kg robot)."""
    for name in robotdyn.robots_available():
        r = robotdyn.load(name)
        red = r.reduced(r.neutral(), np.zeros(r.mobility))
        a = r.forward_dynamics(r.neutral(), np.zeros(r.mobility), np.ones(len(r.motors)))
        assert np.abs(a).max() < PLAUSIBLE_ACCELERATION / 100 and red.projection.condition < NAME_CONDITION, name
        assert not ill_conditioned(red, nudot=a), name

"""The dropped-row check (robotdyn.constraints.redundancy.violations) at rest needs no dA/dt: where v = 0 every term
in dA/dt (dA/dt v, abs(dA/dt) abs(v), max abs(dA/dt) times sum abs(v)) is zero, so the check gives the same
violations, bit for bit, without the Python kinematics pass that computes dA/dt (about 0.3-1 ms of every simulate()
call, which checks its start: most built-in scenarios start at rest)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import robotdyn
from robotdyn.constraints.redundancy import TOL, RowViolation, violations


def _reference(red, nudot, Adot) -> list[RowViolation]:
    """The check written out with dA/dt (as before the shortcut): |a_d a + adot_d v| against the row's scale."""
    rows, m = red.jacobian_rows, red.jacobian_rows.A.shape[0]
    dropped = np.setdiff1d(np.arange(m), red.projection.rows)
    A, v = rows.A[dropped], red.v
    size = float(np.abs(rows.A).max())
    a = red.S @ nudot + red.w
    acc = A @ a + Adot[dropped] @ v
    scale = (np.abs(A) @ np.abs(a) + np.abs(Adot[dropped]) @ np.abs(v) + size * np.abs(a).sum()
             + float(np.abs(Adot).max()) * np.abs(v).sum())
    return [RowViolation(rows.labels[i], float(A[j] @ v), float(acc[j])) for j, i in enumerate(dropped)
            if abs(acc[j]) > TOL * scale[j]]


class _NoRows:
    """A reduced model whose full rows (with dA/dt) must not be asked for."""

    def __init__(self, **fields) -> None:
        self.__dict__.update(fields)

    @property
    def rows(self):
        raise AssertionError("dA/dt computed at rest")


def test_at_rest_the_check_gives_the_same_violations_without_dA_dt():
    rng = np.random.default_rng(7)
    n, k = 5, 2
    A = rng.normal(size=(4, n))  # rows 0, 1 kept; row 2 a combination of them; row 3 not (violated by a)
    A[2] = 0.4 * A[0] - 1.5 * A[1]
    N = np.linalg.svd(A[:2])[2][2:].T  # (null space of the kept rows: A_k S = 0, A_k w = -dA_k/dt v = 0 at rest)
    S, w = N @ rng.normal(size=(n - 2, k)), N @ rng.normal(size=n - 2)
    Adot = rng.normal(size=(4, n))
    fields = dict(jacobian_rows=SimpleNamespace(A=A, labels=["k0", "k1", "dep", "free"]),
                  projection=SimpleNamespace(rows=np.array([0, 1]), condition=3.0), S=S, w=w, v=np.zeros(n))
    nudot = rng.normal(size=k)
    found = violations(_NoRows(**fields), nudot)
    expected = _reference(SimpleNamespace(**fields), nudot, Adot)
    assert [f.label for f in found] == ["free"] and found == expected  # (dataclass equality: the same floats)
    assert found[0].acceleration == pytest.approx(float(A[3] @ (S @ nudot + w)), rel=1e-14)  # a_d a only
    moving = dict(fields, v=rng.normal(size=n), rows=SimpleNamespace(Adot=Adot))
    assert violations(SimpleNamespace(**moving), nudot) == _reference(SimpleNamespace(**moving), nudot, Adot)


@pytest.mark.parametrize("name", ["quasimoro", "linkage_suspension"])
def test_forward_dynamics_at_rest_skips_the_python_rows(name, monkeypatch):
    robot = robotdyn.load(name)
    q = robot.neutral()
    robot.forward_dynamics(q, np.zeros(robot.mobility), np.zeros(len(robot.motors)))  # (the projection chosen)
    calls = []
    full = robot.constraint_rows
    monkeypatch.setattr(robot, "constraint_rows", lambda kin: calls.append(1) or full(kin))
    robot.forward_dynamics(q, np.zeros(robot.mobility), np.ones(len(robot.motors)))
    assert calls == []
    red = robot.reduced(q, np.zeros(robot.mobility))
    assert len(red.jacobian_rows.labels) > len(red.projection.rows)  # (rows are dropped: the check has work)
    nu = np.linspace(0.1, 0.3, robot.mobility)  # in motion: dA/dt v counts
    robot.forward_dynamics(robot.neutral(), nu, np.ones(len(robot.motors)))
    assert calls == []  # forward dynamics: the compiled rows' screen clears the state (robotdyn.fast.dropped_rows)
    robot.redundant_row_violations(robot.neutral(), nu, np.ones(robot.mobility))
    assert calls == [1]  # the exact check computes the Python rows once

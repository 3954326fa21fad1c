"""robot.contact_forces' cost (issue 26): a planar model's own forces are solved (where a wheel's normal row is
exactly zero: it acts on nothing, so its load is open without a solve) and assembled only where its floating twin
cannot replace them (the twin's only where it can), and the reasons for undetermined rows are found row by row in one vectorised pass; the
results are those of the eager composition (the planar forces assembled first, then replaced), bit for bit, on a
robot whose twin holds the loads (QuasiMoRo) and one whose twin cannot (MMR12-EOD, on its two wheels)."""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn
from robotdyn.contact import contact_forces as cf
from robotdyn.reduction.reduced_dynamics import solve_mass

STATES = {"quasimoro": ([0, 0, 0, 0, 0, 0.1], [0.4, -0.2, 0.3], [0.3, -0.1]),
          "mmr12_eod": (None, None, None), "omni_caster": (None, None, None)}


def eager(robot, q, nu, tau):
    """The composition as it was: the planar model's forces assembled, then replaced by the twin's."""
    red = robot.reduced(q, nu)
    nudot = solve_mass(red.M, red.B @ tau - red.h)
    a = red.S @ nudot + red.w
    out = cf._assemble(robot, cf._solve(robot, q, red.v, a, tau, red.jacobian_rows, {}), nudot, tau, {})
    unsupported = False
    if any(not w.determined[2] for w in out.wheels):
        planar = out
        out = cf._from_floating_twin(robot, q, red.v, a, tau, nudot, lambda: planar)
        unsupported = out is planar
    if not unsupported:
        cf.apply_rigid_limit(robot, out)
    return out


def state(robot, name):
    q, nu, tau = STATES[name]
    rng = np.random.default_rng(6)
    q = robot.neutral() if q is None else np.asarray(q, float)
    nu = rng.normal(size=robot.mobility) * 0.5 if nu is None else np.asarray(nu, float)
    tau = rng.normal(size=len(robot.motors)) if tau is None else np.asarray(tau, float)
    return q, nu, tau


@pytest.mark.parametrize("name,twin_holds", [("quasimoro", True), ("omni_caster", True), ("mmr12_eod", False)])
def test_lazy_planar_assembly_gives_the_eager_result_bit_for_bit(name, twin_holds, monkeypatch):
    robot = robotdyn.load(name)
    q, nu, tau = state(robot, name)
    robot.reduced(q, nu)  # (the projection chosen: both compositions below then take the compiled path)
    ref = eager(robot, q, nu, tau)
    calls, solves = [], []
    assemble, solve = cf._assemble, cf._solve
    monkeypatch.setattr(cf, "_assemble", lambda r, *a: calls.append(r) or assemble(r, *a))
    monkeypatch.setattr(cf, "_solve", lambda r, *a: solves.append(r) or solve(r, *a))
    got = robot.contact_forces(q, nu, tau=tau)
    # QuasiMoRo's and the omni platform's planar normal rows are zero (no planar solve); MMR12-EOD's are not
    assert [r is robot for r in solves] == ([False] if name != "mmr12_eod" else [True, False])
    assert any(TWIN in n for n in got.notes) == twin_holds
    # the twin's forces assembled only where it holds the loads, the planar model's only where it cannot
    assert [r is robot for r in calls] == ([False] if twin_holds else [True])
    for field in ("lam", "determined", "null_space", "open"):
        np.testing.assert_array_equal(getattr(got, field), getattr(ref, field))
    assert (got.labels, got.rank, got.residual, got.condition, got.notes, got.undetermined_reason, got.unloaded) == \
        (ref.labels, ref.rank, ref.residual, ref.condition, ref.notes, ref.undetermined_reason, ref.unloaded)
    for w, v in zip(got.wheels, ref.wheels, strict=True):
        assert w.name == v.name and w.kind == v.kind
        for field in ("force", "determined", "world", "point", "compliance"):
            np.testing.assert_array_equal(getattr(w, field), getattr(v, field))


TWIN = "normal loads from the out-of-plane equilibrium"


def test_reasons_name_the_rows_of_the_row_by_row_tests():
    """Rows acting on no coordinate, and the rows with a weight in some null-space direction, against the per-entry
    tests written out (a random null space with a zero row and a mixed normal row)."""
    rng = np.random.default_rng(8)
    labels = ["a.longitudinal", "a.lateral", "a.normal", "b.lateral", "b.normal"]
    A = rng.normal(size=(5, 4))
    A[2] = 0.0  # acts on no coordinate
    N = np.zeros((5, 2))
    N[2, 0] = 1.0
    N[[1, 3], 1] = [0.6, 0.8]
    N[4, 1] = 0.5 * cf.DETERMINED_TOL  # below the tolerance: not named
    zero = [lab for lab, row in zip(labels, A) if np.abs(row).max(initial=0.0) <= 1e-12]
    mixed = sorted({lab for col in N.T for lab, c in zip(labels, col) if abs(c) > cf.DETERMINED_TOL} - set(zero))
    assert zero == ["a.normal"] and mixed == ["a.lateral", "b.lateral"]
    reasons = cf._reasons(A, labels, N)
    assert len(reasons) == 2 and reasons[0].startswith("rows a.normal act on no coordinate")
    assert "1 combination(s) of rows a.lateral, b.lateral " in reasons[1] and "no normal load" in reasons[1]


@pytest.mark.parametrize("name", ["quasimoro", "omni_caster", "mmr12_eod"])
def test_an_exactly_zero_normal_row_is_an_open_normal_load_after_the_solve(name):
    """The shortcut's premise, at random states of the planar built-in robots: where _inert_normal sees a zero
    normal row, the solve's null space leaves that load open (_normal_open); MMR12-EOD's planar normal rows are not
    zero (its rows involve its tracks' joints), so it always takes the solve."""
    robot = robotdyn.load(name)
    rng = np.random.default_rng(10)
    inert = []
    for _ in range(4):
        q = robot.neutral()
        q[robot.coordinate_index("psi")] = rng.uniform(-3, 3)
        nu, tau = rng.normal(size=robot.mobility), rng.normal(size=len(robot.motors))
        red = robot.reduced(q, nu)
        nudot = solve_mass(red.M, red.B @ tau - red.h)
        solved = cf._solve(robot, q, red.v, red.S @ nudot + red.w, tau, red.jacobian_rows, {})
        inert.append(cf._inert_normal(robot, red.jacobian_rows))
        assert not inert[-1] or cf._normal_open(robot, solved)
    assert all(inert) == (name != "mmr12_eod") and any(inert) == (name != "mmr12_eod")

"""robot.contact_forces' cost (issue 26): a planar model's own forces are assembled only where its floating twin
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
    out = cf._forces(robot, q, red.v, a, tau, red.jacobian_rows, {}, nudot)
    unsupported = False
    if any(not w.determined[2] for w in out.wheels):
        planar = out
        out = cf._from_floating_twin(robot, q, red.v, a, tau, nudot, out)
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
    calls = []
    assemble = cf._assemble
    monkeypatch.setattr(cf, "_assemble", lambda r, *a: calls.append(r) or assemble(r, *a))
    got = robot.contact_forces(q, nu, tau=tau)
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

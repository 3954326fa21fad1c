"""The rows the reduction evaluates against the full rows, and the batch path against one state at a time, on every
registered robot.

:class:`robotdyn.reduction.reduced_dynamics.ConstraintSet` stacks each constraint's :meth:`jacobian` (no
:math:`\\dot A`) and :meth:`drift` (:math:`\\dot A v` from 3-vectors, no matrix :math:`\\dot A`); they must give the
same Jacobian rows, residuals and drift terms as each constraint's full :meth:`rows` (whose ``Adot`` is checked
against finite differences in tests/test_rolling_contact.py and tests/test_loop_closure.py), at states off the
constraint manifold too (the formulas do not assume A v = 0).
"""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn
from robotdyn.constraints.constraint import ConstraintRows, KinematicState
from robotdyn.reduction.reduced_dynamics import constraint_set, velocity
from robotdyn.robots import names


@pytest.fixture(scope="module", params=names())
def robot(request):
    return robotdyn.load(request.param)


def test_jacobian_and_drift_match_the_full_rows(robot):
    rng = np.random.default_rng(7)
    cset = constraint_set(robot)
    for trial in range(4):
        q = robot.neutral() + (0.0 if trial == 0 else 0.02) * rng.normal(size=robot.nq)
        v = rng.normal(size=robot.nq)
        ref_kin = KinematicState(robot.model, robot.data, q, v)
        ref = ConstraintRows.stack([c.rows(ref_kin) for c in robot.constraints], robot.nq)
        ref_drift = ref.Adot @ v
        kin = KinematicState(robot.model, robot.data, q, v)
        rows = cset.jacobian(kin)
        drift = cset.drift(kin)
        scale = 1.0 + np.abs(ref.A).max()
        assert rows.labels == ref.labels
        assert np.array_equal(rows.holonomic, ref.holonomic)
        assert np.abs(rows.A - ref.A).max() <= 1e-13 * scale
        assert np.abs(rows.residual - ref.residual).max() <= 1e-13
        assert np.abs(drift - ref_drift).max() <= 1e-12 * (1.0 + np.abs(ref_drift).max())


def test_at_rest_drift_is_zero(robot):
    kin = KinematicState(robot.model, robot.data, robot.neutral(), np.zeros(robot.nq))
    assert not np.any(constraint_set(robot).drift(kin))


def test_velocity_matches_reduce(robot):
    rng = np.random.default_rng(3)
    q = robot.neutral()
    nu = rng.normal(size=robot.mobility)
    red = robot.reduced(q, nu)
    v, rows = velocity(robot, q, nu)
    assert np.abs(v - red.v).max() <= 1e-14 * (1.0 + np.abs(red.v).max())
    assert np.array_equal(rows.A, red.jacobian_rows.A)
    assert np.abs(red.rows.A @ v).max() <= 1e-12 * (1.0 + np.abs(v).max())


def test_batch_vectorised_equals_one_by_one(robot):
    from robotdyn.simulation.batch import _evaluate_loop, evaluate

    rng = np.random.default_rng(5)
    N = 12
    Q = np.tile(robot.neutral(), (N, 1))
    if not robot.spec.closures:  # loop closures would be violated by a random perturbation
        Q += 1e-3 * rng.normal(size=Q.shape)
    NU = rng.normal(size=(N, robot.mobility))
    batch = evaluate(robot, Q, NU, processes=1)
    for name, ref in zip(("M", "h", "g", "B", "S"), _evaluate_loop(robot, Q, NU, 0)):
        got = getattr(batch, name)
        assert got.shape == ref.shape
        assert np.abs(got - ref).max() <= 1e-12 * (1.0 + np.abs(ref).max()), name


def test_batch_singular_state_is_named():
    from robotdyn.simulation.batch import evaluate
    from robotdyn.errors import SingularConstraintError

    rob = robotdyn.load("quasimoro")
    rob.independent_indices = np.array([rob.coordinate_index(c) for c in ("x", "y", "theta3")])
    Q = np.tile(rob.neutral(), (3, 1))
    with pytest.raises(SingularConstraintError, match="state 0"):
        evaluate(rob, Q, np.zeros((3, 3)), processes=1)


def test_terrain_changed_in_place_is_seen():
    from robotdyn.constraints.posture import set_terrain
    from robotdyn.constraints.terrain import RampTerrain

    rob = robotdyn.load("mmr12_eod")
    q = rob.neutral()
    v = np.random.default_rng(2).normal(size=rob.nq)
    rob.reduced(q, np.zeros(rob.mobility))  # builds the constraint set on the flat ground
    flat = constraint_set(rob).jacobian(KinematicState(rob.model, rob.data, q, v))
    set_terrain(rob, RampTerrain(0.2, 0.4, -0.3))
    kin = KinematicState(rob.model, rob.data, q, v)
    rows, drift = constraint_set(rob).jacobian(kin), constraint_set(rob).drift(kin)
    ref_kin = KinematicState(rob.model, rob.data, q, v)
    ref = ConstraintRows.stack([c.rows(ref_kin) for c in rob.constraints], rob.nq)
    assert np.abs(rows.A - ref.A).max() <= 1e-13
    assert np.abs(rows.residual - ref.residual).max() <= 1e-13
    assert np.abs(drift - ref.Adot @ v).max() <= 1e-12
    assert np.abs(rows.residual).max() > 0.1  # the wheels are now off the lowered ramp
    assert not np.allclose(rows.A, flat.A)

"""Constraint forces in the compiled fast path (CompiledModel.forces, and robot.contact_forces where it serves):
against Pinocchio's own KKT solve of the constrained dynamics, and against the Python path of
robotdyn.contact.contact_forces, on every robot."""

from __future__ import annotations

import numpy as np
import pytest
from test_contact_forces import ROBOTS, _pinocchio_kkt

import robotdyn
from robotdyn.fast.dispatch import available, compiled_model, use_compiled

pytestmark = pytest.mark.skipif(not available(), reason="compiled extension not built")


@pytest.fixture(scope="module")
def robots():
    return {name: robotdyn.load(name) for name in ROBOTS}


def _states(robot, n: int = 3, seed: int = 5):
    rng = np.random.default_rng(seed)
    q = robot.neutral()
    for _ in range(n):
        yield q, rng.normal(scale=0.5, size=robot.mobility), rng.normal(size=len(robot.motors))


@pytest.mark.parametrize("name", ROBOTS)
def test_compiled_forces_match_pinocchio_kkt(robots, name):
    """The compiled multipliers on the projection's rows satisfy A^T lambda = e and equal Pinocchio's KKT
    multipliers on every row rigid-body dynamics determine; nudot equals the forward dynamics; the wheel forces
    are D^T lambda in the contact frame, and the frame is orthonormal."""
    robot = robots[name]
    fast = compiled_model(robot)
    for q, nu, tau in _states(robot):
        nudot, lam, e, local, world, frames, points = (np.array(x) for x in fast.forces(q, nu, tau))
        red = robot.reduced(q, nu)
        np.testing.assert_allclose(nudot, robot.forward_dynamics(q, nu, tau), rtol=1e-10, atol=1e-10)
        kin = robotdyn.constraints.constraint.KinematicState(robot.model, robot.data, q, red.v)
        B = robotdyn.reduction.actuation.input_matrix(robot.motors, kin)
        a_pin, A, sel, lam_pin = _pinocchio_kkt(robot, q, red.v, B @ tau)
        scale = 1.0 + np.abs(e).max()
        np.testing.assert_allclose(A.T @ lam, e, atol=1e-9 * scale)
        np.testing.assert_allclose(A.T @ lam, A[sel].T @ lam_pin, atol=1e-9 * scale)
        ref = robot.contact_forces(q, nu, tau=tau, twin=False)
        np.testing.assert_allclose(lam[ref.determined], ref.lam[ref.determined], atol=1e-9 * scale)
        for i, w in enumerate(ref.wheels):
            E = frames[i].reshape(3, 3)
            np.testing.assert_allclose(E @ E.T, np.eye(3), atol=1e-12)
            np.testing.assert_allclose(world[i], E.T @ local[i], atol=1e-12 * scale)
            np.testing.assert_allclose(points[i], w.point, atol=1e-12)
            if w.load_determined:
                np.testing.assert_allclose(local[i], w.force, atol=1e-9 * scale)


@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("twin", [False, True])
def test_contact_forces_compiled_equal_python(robots, name, twin):
    """robot.contact_forces on the compiled path (lambda from the C++ evaluation, made minimum-norm with the null
    space of A^T) equals the Python path to 1e-9: multipliers, what is determined, wheel and closure forces,
    contact points, the undetermined combinations and the minimum friction coefficient."""
    robot = robots[name]
    for q, nu, tau in _states(robot, seed=11):
        fast = robot.contact_forces(q, nu, tau=tau, twin=twin)
        with use_compiled(False):
            ref = robot.contact_forces(q, nu, tau=tau, twin=twin)
        scale = 1.0 + np.abs(ref.lam).max(initial=0.0)
        np.testing.assert_allclose(fast.lam, ref.lam, atol=1e-9 * scale)
        assert np.array_equal(fast.determined, ref.determined) and fast.rank == ref.rank
        assert fast.residual < 1e-10 and fast.undetermined_reason == ref.undetermined_reason
        np.testing.assert_allclose(fast.null_space @ fast.null_space.T, ref.null_space @ ref.null_space.T,
                                   atol=1e-9)
        for a, b in zip(fast.wheels, ref.wheels):
            assert a.name == b.name and np.array_equal(a.determined, b.determined)
            np.testing.assert_allclose(a.force, b.force, atol=1e-9 * scale)
            np.testing.assert_allclose(a.world, b.world, atol=1e-9 * scale)
            np.testing.assert_allclose(a.point, b.point, atol=1e-12)
        for c in ref.closures:
            np.testing.assert_allclose(list(fast.closures[c].values()), list(ref.closures[c].values()),
                                       atol=1e-9 * scale)
        mu_fast, mu_ref = fast.minimum_mu(), ref.minimum_mu()
        assert (mu_fast is None) == (mu_ref is None)
        if mu_ref is not None and np.isfinite(mu_ref):
            assert mu_fast == pytest.approx(mu_ref, rel=1e-6)


def test_forces_are_views_of_the_evaluator(robots):
    robot = robots["quasimoro"]
    fast = compiled_model(robot)
    q, nu, tau = next(_states(robot))
    first = fast.forces(q, nu, tau)
    lam = np.array(first[1])
    second = fast.forces(q, 2 * nu, tau)
    assert second[1] is first[1] and not np.array_equal(second[1], lam)  # overwritten in place, as compute()

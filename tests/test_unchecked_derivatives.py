"""The fast entries of the derivatives (issue 26: the API's overhead per call): ``Robot.dynamics_derivatives`` with
``check=False`` gives the checked call's numbers bit for bit, on the compiled and on the Python path; the inputs'
vectorised check keeps every one-line refusal; the trajectory optimiser's stacked Jacobian assembly equals the
block-by-block one it replaced (the same numbers in the same order) and central differences of its constraints; the
compiled set's finiteness, tested in C++, is the API's NonFiniteError."""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn
from robotdyn.errors import InputError, NonFiniteError
from robotdyn.fast.compiled import available
from robotdyn.fast.compiled_derivatives import raw_derivatives
from robotdyn.fast.dispatch import compiled_model, use_compiled
from robotdyn.inputs import as_vector

FIELDS = ("nudot", "dq", "dnu", "dtau", "qdot", "dqdot_dq", "S", "dq_manifold")


@pytest.fixture(scope="module")
def robot():
    return robotdyn.load("quasimoro")


@pytest.mark.parametrize("compiled", [True, False])
def test_unchecked_call_equals_the_checked_one(robot, compiled):
    q = np.array([0.1, -0.05, 0.3, 0.02, 0.4, -0.2])[:robot.nq]
    nu, tau = np.array([0.1, 0.2, -0.1]), np.array([0.3, -0.2])
    with use_compiled(compiled):
        a = robot.dynamics_derivatives(q, nu, tau)
        b = robot.dynamics_derivatives(q, nu, tau, check=False)
    for name in FIELDS:
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert np.abs(a.dq).max() > 1e-3  # not a vacuous comparison


def test_vectorised_input_check_keeps_the_one_line_refusals():
    x = np.array([1.0, 2.0])
    y = as_vector(x, 2, "q", ["x", "y"], 1e6, "m")
    assert y is not x and np.array_equal(x, y)  # a copy, as the loop gave
    for bad, needle in ((np.array([1.0, np.nan]), "q[y] = "), (np.array([1.0, 2e6]), "beyond what a robot reaches"),
                        (np.array([1.0, 2.0, 3.0]), "q has 3 values; expected 2 values (x, y)")):
        with pytest.raises(InputError) as err:
            as_vector(bad, 2, "q", ["x", "y"], 1e6, "m")
        assert needle in str(err.value) and "\n" not in str(err.value)


def test_stacked_jacobian_assembly_equals_blocks_and_differences(robot):
    from robotdyn.robots.quasimoro.optimal_motion import rest_to_rest

    p = rest_to_rest(nodes=4, robot=robot)
    z = p._initial() + 0.01 * np.sin(np.arange(p.nz))
    got = p.jacobian_values(z)
    X, U = p._split(z)
    h = p.t_end / (p.nodes - 1)
    I, k = np.eye(p.nx)[p.keep], p.keep
    node = [p._jac_node(X[j], U[j]) for j in range(p.nodes)]
    ref = []
    for j in range(p.nodes - 1):  # the block-by-block assembly (_blocks' order, each row-major)
        (Fx0, Fu0), (Fx1, Fu1) = node[j], node[j + 1]
        ref += [(-I - 0.5 * h * Fx0[k]).ravel(), (I - 0.5 * h * Fx1[k]).ravel(), (-0.5 * h * Fu0[k]).ravel(),
                (-0.5 * h * Fu1[k]).ravel()]
    assert np.array_equal(got, np.concatenate(ref))
    rows, cols = p._pattern()
    J = np.zeros((p.n_constraints, p.nz))
    J[rows, cols] = got
    fd = np.empty_like(J)
    for i in range(p.nz):  # central differences of the constraints
        e = np.zeros(p.nz)
        e[i] = 1e-6
        fd[:, i] = (p.constraints(z + e) - p.constraints(z - e)) / 2e-6
    assert np.abs(fd - J).max() <= 1e-6 * max(1.0, np.abs(J).max())


@pytest.mark.skipif(not available(), reason="compiled extension not built")
def test_compiled_finiteness_bits_and_the_non_finite_error(robot):
    """The compiled set tests its outputs' finiteness in C++ (Evaluator.derivatives_checked: bit i for output i):
    the bits equal numpy's test of the returned arrays, at a regular state (none) and at an infinite torque (the
    acceleration and what follows from it); the API's NonFiniteError names the first non-finite output, and the
    optimiser's raw entry answers None there."""
    q = robot.neutral()
    nu, tau = np.array([0.1, 0.2, -0.1]), np.array([0.3, -0.2])
    fast = compiled_model(robot)
    robot.dynamics_derivatives(q, nu, tau)  # (the projection chosen)
    for t in (tau, np.array([np.inf, 0.0])):
        *out, bits = fast.ev.derivatives_checked(q, nu, t)
        assert bits == sum(1 << i for i, x in enumerate(out[:6]) if not np.isfinite(x).all())
        for x, y in zip(out, fast.ev.derivatives(q, nu, t)):
            assert x.tobytes() == y.tobytes()
    assert bits & 1 and not bits & 16  # nudot infinite, qdot = S nu finite
    assert raw_derivatives(fast, q, nu, tau) is not None and raw_derivatives(fast, q, nu, t) is None
    with pytest.raises(NonFiniteError, match="nudot is not finite"):
        robot.dynamics_derivatives(q, nu, t, check=False)

"""A collocation's dynamics at all its nodes in one compiled call (robotdyn.optimisation.node_batches) and the
constraints' Jacobian pattern that the optimiser's callback declares to CasADi (robotdyn.optimisation.callbacks).

References: node by node, the same compiled calls through :meth:`TrajectoryProblem._f` and ``_jac_node`` (the
batched results must equal them bit for bit: same states, same steps, same C++); the analytic Jacobians against the
batched central differences (an independent route: the differences' own error, about 1e-7 relative); CasADi's
symbolic Jacobian of the callback, whose pattern must be the declared one (without the declaration CasADi takes it
dense: IPOPT counted 38,700 nonzeros (180 rows x 215 free variables) for Quasimoro on 21 nodes instead of 3,960, and
factored a dense KKT system).
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("casadi")

import robotdyn  # noqa: E402
from robotdyn.optimisation import node_batches  # noqa: E402
from robotdyn.robots.quasimoro.optimal_motion import rest_to_rest  # noqa: E402


def _problem(derivatives: str, nodes: int = 7):
    p = rest_to_rest(nodes=nodes, robot=robotdyn.load("quasimoro"), derivatives=derivatives)
    if p._fast is None or not hasattr(p._fast.ev, "derivatives_many"):
        pytest.skip("the compiled extension is not built (or predates the batched calls)")
    rng = np.random.default_rng(3)
    X, U = p._split(p._initial())
    X = X + 0.05 * rng.standard_normal(X.shape)
    U = U + 0.3 * rng.standard_normal(U.shape)
    return p, X, U


def test_batched_rhs_equals_the_nodes_one_by_one():
    p, X, U = _problem("analytic")
    F = node_batches.rhs_nodes(p._fast, p.n, X, U)
    assert F.shape == (len(X), p.nx)
    np.testing.assert_array_equal(F, np.array([p._f(x, u) for x, u in zip(X, U)]))


@pytest.mark.parametrize("derivatives", ["analytic", "finite-difference"])
def test_batched_jacobians_equal_the_nodes_one_by_one(derivatives):
    p, X, U = _problem(derivatives)
    if derivatives == "analytic":
        Fx, Fu = node_batches.analytic_jacobians(p._fast, p.n, X, U)
    else:
        Fx, Fu, evaluations = node_batches.central_jacobians(p._fast, p.n, X, U, p.steps)
        assert evaluations == 2 * len(X) * (p.nx + p.m)  # 2 (n + k + m) per node, as node by node
    single = [p._jac_node(x, u) for x, u in zip(X, U)]
    np.testing.assert_array_equal(Fx, np.array([s[0] for s in single]))
    np.testing.assert_array_equal(Fu, np.array([s[1] for s in single]))


def test_batched_analytic_jacobians_equal_central_differences():
    p, X, U = _problem("analytic")
    Ax, Au = node_batches.analytic_jacobians(p._fast, p.n, X, U)
    Cx, Cu, _ = node_batches.central_jacobians(p._fast, p.n, X, U)
    scale = max(np.abs(Ax).max(), 1.0)
    assert np.abs(Ax - Cx).max() / scale < 1e-6 and np.abs(Au - Cu).max() / scale < 1e-6
    assert np.abs(Ax[:, p.n:, :p.n]).max() > 1e-2  # (d nudot/dq is not trivially zero at these states)


def test_batches_answer_none_without_a_compiled_model():
    X, U = np.zeros((3, 9)), np.zeros((3, 2))
    assert node_batches.rhs_nodes(None, 6, X, U) is None
    assert node_batches.analytic_jacobians(None, 6, X, U) is None
    assert node_batches.central_jacobians(None, 6, X, U) is None


def test_the_callbacks_jacobian_has_the_declared_pattern():
    import casadi as ca

    p = rest_to_rest(nodes=21, robot=robotdyn.load("quasimoro"))
    rows, cols = p._pattern()
    assert len(rows) == 3960 < p.n_constraints * p.nz == 180 * 231
    from robotdyn.optimisation.callbacks import exact_zeros, sparse_callback

    keep: list = []
    g = sparse_callback("g", p.nz, p.n_constraints, p.constraints, p.jacobian_values, rows, cols, keep)
    z = ca.MX.sym("z", p.nz)
    J = ca.jacobian(g(z), z)
    assert J.sparsity().nnz() == len(rows)
    z0 = p._initial()
    dense = np.zeros((p.n_constraints, p.nz))
    dense[rows, cols] = exact_zeros(p.jacobian_values(z0), rows, p.n_constraints)  # rounding residues as zeros
    np.testing.assert_array_equal(np.asarray(ca.Function("J", [z], [J])(z0)), dense)


def test_batched_central_differences_step_along_the_holonomic_level_set():
    from robotdyn.optimisation import TrajectoryProblem

    robot = robotdyn.load("mmr12_eod")  # one holonomic row: q is stepped along its level set (manifold_steps)
    p = TrajectoryProblem(robot, 1.0, 3, robot.neutral(), derivatives="finite-difference")
    if p._fast is None or not hasattr(p._fast.ev, "rhs_many"):
        pytest.skip("the compiled extension is not built (or predates the batched calls)")
    assert p.mh == 1 and p.steps is not None
    rng = np.random.default_rng(5)
    X, U = p._split(p._initial())
    X[:, p.n:] += 0.2 * rng.standard_normal((len(X), p.k))  # (q stays on the manifold)
    U = U + rng.standard_normal(U.shape)
    Fx, Fu, evaluations = node_batches.central_jacobians(p._fast, p.n, X, U, p.steps)
    single = [p._jac_node(x, u) for x, u in zip(X, U)]
    np.testing.assert_array_equal(Fx, np.array([s[0] for s in single]))
    np.testing.assert_array_equal(Fu, np.array([s[1] for s in single]))
    dependent = np.setdiff1d(np.arange(p.n), p.positions)
    assert np.all(Fx[:, :, dependent] == 0.0)  # the dependent coordinates' columns, as node by node
    assert evaluations == 2 * len(X) * (p.nx + p.m - len(dependent))

"""The six-wheel linkage rover's minimum-effort straight path within a friction limit (issue 26, item 3's last
example; :mod:`robotdyn.robots.linkage_suspension.traction_path`).

References: central differences of the dynamics and of the contact forces, stepped along the loops' level set,
against the analytic derivatives on every tangent vector of the holonomic manifold; the cached optimum
(``tests/data/rover_path_traction.npz``, from ``traction_path(...).solve()`` with analytic derivatives, 5 nodes;
the same cost to 1e-15 with finite differences, measured: one solve takes 15-30 s, too long for the suite, so the
notebook ``rover_path_traction.ipynb`` solves it and this file checks the stored optimum against the current model)
has zero defects and holonomic residuals, keeps the loads and the cone, the cone binding where the unconstrained
optimum violates it; a re-simulation of its torques with the exact model keeps them too.

The cache holds ``free_*`` (``mu_max=None``) and ``limited_*`` (``mu_max=0.15``) ``q``, ``nu``, ``tau`` and ``cost`` of
``traction_path(mu_max, robot=robotdyn.load("linkage_suspension")).solve()``: solve again and ``np.savez`` them
where a change of the model moves the optimum.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from scipy.linalg import null_space

pytest.importorskip("casadi")

import robotdyn  # noqa: E402
from robotdyn.errors import SingularConstraintError  # noqa: E402
from robotdyn.optimisation.trajectory import TrajectorySolution  # noqa: E402
from robotdyn.robots.linkage_suspension import traction_path as tp  # noqa: E402

CACHE = np.load(pathlib.Path(__file__).parent / "data" / "rover_path_traction.npz")


@pytest.fixture(scope="module")
def robot():
    return robotdyn.load("linkage_suspension")


def _z(tag: str) -> np.ndarray:
    return np.concatenate([np.hstack([CACHE[f"{tag}_q"], CACHE[f"{tag}_nu"]]).ravel(), CACHE[f"{tag}_tau"].ravel()])


def test_finite_differences_step_along_the_loops(robot):
    """A plain step of a dependent coordinate opens the loops (the reduced dynamics refuse the state: what made the
    finite-difference optimisation fail); stepped along the level set, the central differences of the dynamics and
    of the forces equal the analytic derivatives on the manifold's tangent vectors (step ~6e-6: truncation ~1e-10)."""
    fd = tp.traction_path(robot=robot, derivatives="finite-difference")
    an = tp.traction_path(robot=robot, derivatives="analytic")
    n = fd.n
    x, u = np.concatenate([CACHE["limited_q"][1], CACHE["limited_nu"][1]]), CACHE["limited_tau"][1]
    refused = 0
    for i in fd.steps.dependent:
        q = x[:n].copy()
        q[i] += 6e-6
        try:
            robot.reduced(q, x[n:])
        except SingularConstraintError:
            refused += 1
    assert refused > 0
    T = null_space(fd._holonomic(x[:n])[1])  # tangent basis of the manifold (n, n - mh)
    assert T.shape[1] == len(fd.positions)
    Fx_fd, Fu_fd = fd._jac_node(x, u)
    Fx_an, Fu_an = an._jac_node(x, u)
    scale = np.abs(Fx_an[:, :n] @ T).max()
    assert np.abs(Fx_fd[:, :n] @ T - Fx_an[:, :n] @ T).max() < 1e-6 * scale
    assert np.allclose(Fx_fd[:, n:], Fx_an[:, n:], rtol=1e-6, atol=1e-6 * np.abs(Fx_an[:, n:]).max())
    assert np.allclose(Fu_fd, Fu_an, rtol=1e-6, atol=1e-6 * np.abs(Fu_an).max())
    F, dF_fd = fd.limits.force_jacobian(x[:n], x[n:], u)
    _, dF_an = an.limits.force_jacobian(x[:n], x[n:], u)
    # on flat ground the forces hardly change along the manifold (analytic ~1e-14 N per unit): compared to the forces
    assert np.abs(dF_fd[..., :n] @ T - dF_an[..., :n] @ T).max() < 1e-7 * np.abs(F).max()
    assert np.allclose(dF_fd[..., n:], dF_an[..., n:], rtol=1e-6, atol=1e-6 * np.abs(dF_an).max())


def test_cached_optimum_holds_the_limits_that_the_free_optimum_breaks(robot):
    """The stored optima on the current model: collocation defects and loop residuals zero; every load >= 10 N;
    the minimum-effort motion needs mu 0.187 at its front wheels, the limited one at most 0.15 and exactly 0.15 at
    two nodes or more (the limit binds), for a little more effort (stored 5.42921 and 5.45396 N^2 m^2 s)."""
    limited = tp.traction_path(robot=robot)
    free = tp.traction_path(mu_max=None, robot=robot)
    h = tp.T_END / (tp.NODES - 1)
    peaks = {}
    for tag, p in (("free", free), ("limited", limited)):
        z = _z(tag)
        assert np.abs(p.defects(z)).max() < 1e-8
        assert max(np.abs(p._holonomic(q)[0]).max() for q in CACHE[f"{tag}_q"]) < 1e-9
        tau2 = np.sum(CACHE[f"{tag}_tau"] ** 2, axis=1)
        assert np.isclose(h * (tau2.sum() - 0.5 * (tau2[0] + tau2[-1])), float(CACHE[f"{tag}_cost"]), rtol=1e-12)
        F = np.array([p.limits.forces(q, nu, u) for q, nu, u in zip(CACHE[f"{tag}_q"], CACHE[f"{tag}_nu"],
                                                                      CACHE[f"{tag}_tau"])])
        assert F[..., 2].min() >= tp.MIN_LOAD
        mu = np.linalg.norm(F[..., :2], axis=-1) / F[..., 2]
        peaks[tag] = mu
        assert np.isclose(CACHE[f"{tag}_q"][-1, robot.coordinates.index("x")], tp.DISTANCE, atol=1e-9)
    assert peaks["free"].max() > 0.18
    assert peaks["limited"].max() <= tp.MU_MAX + 1e-7
    assert np.sum(peaks["limited"] > tp.MU_MAX - 1e-6) >= 2
    assert float(CACHE["free_cost"]) < float(CACHE["limited_cost"]) < 1.01 * float(CACHE["free_cost"])


def test_replay_with_the_exact_model_keeps_the_limits(robot):
    """The limited optimum's torques re-simulated open loop: the loads stay >= 10 N, the required mu <= 0.15
    (reached at the start), the rover stops (velocities ~0) 0.529 m ahead instead of 0.5: the 5-node trapezoid's
    discretisation error, 5.7 %."""
    s = TrajectorySolution(np.linspace(0, tp.T_END, tp.NODES), CACHE["limited_q"], CACHE["limited_nu"],
                           CACHE["limited_tau"], float(CACHE["limited_cost"]), "cached", True, 0, 0.0, 0, 0, 0.0,
                           "analytic")
    traj, F, mu = tp.replay(s, robot)
    assert F[..., 2].min() >= tp.MIN_LOAD
    assert mu.max() <= tp.MU_MAX + 1e-6
    x_end = traj.q[-1, robot.coordinates.index("x")]
    assert 0.5 < x_end < 0.54
    assert np.abs(traj.nu[-1]).max() < 1e-6


def test_rounding_residues_reach_ipopt_as_exact_zeros(robot):
    """The Jacobian IPOPT receives (through the CasADi callback) at the stored optimum: hundreds of entries that the
    kernels return as rounding residues of exact zeros (0 < abs <= 1e-12 of their row's largest) arrive as exact
    zeros; every other entry arrives unchanged. The residues misled MUMPS's scaling (optimisation.callbacks)."""
    import casadi as ca

    from robotdyn.optimisation.callbacks import ROUNDING, sparse_callback

    p = tp.traction_path(robot=robot)
    z = _z("limited")
    raw = p.jacobian_values(z)
    rows, cols = p._pattern()
    largest = np.zeros(p.n_constraints)
    np.maximum.at(largest, rows, np.abs(raw))
    residue = (raw != 0) & (np.abs(raw) <= ROUNDING * largest[rows])
    assert residue.sum() > 100  # measured: ~1,800 of 6,484 entries
    keep = []
    g = sparse_callback("g", p.nz, p.n_constraints, p.constraints, p.jacobian_values, rows, cols, keep)
    zs = ca.MX.sym("z", p.nz)
    J = ca.Function("J", [zs], [ca.jacobian(g(zs), zs)])(z)
    got = np.asarray(ca.DM(J).full())[rows, cols]
    assert np.all(got[residue] == 0.0)
    assert np.array_equal(got[~residue], raw[~residue])


def test_perturbed_start_converges(robot):
    """From the stored minimum-effort motion with its torques perturbed by 1e-2 (seed 0), IPOPT converges to the
    stored traction-limited optimum (cost to 1e-9 relative). Before the residues were zeroed, MUMPS's first
    factorization left a residual ratio of 1e6 there and the solve ended in Invalid_Number_Detected (measured: 0 of
    16 such starts converged; at 1e-8, 16 of 32 before the Jacobian's pattern was declared to CasADi)."""
    rng = np.random.default_rng(0)
    p = tp.traction_path(robot=robot)
    p.guess = (CACHE["free_q"], CACHE["free_nu"], CACHE["free_tau"] * (1 + 1e-2 * rng.normal(size=(tp.NODES, 6))))
    s = p.solve()
    assert s.success, s
    assert np.isclose(s.cost, float(CACHE["limited_cost"]), rtol=1e-9, atol=0)

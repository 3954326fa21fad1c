"""A collocation's dynamics at all its nodes in one call of the compiled model: the right-hand side
:math:`f(x_j, \\tau_j) = (S\\nu, \\dot\\nu)`, its Jacobians from the analytic derivative set, and the same Jacobians by
central finite differences, every perturbed state of every node evaluated in one call.

A trajectory optimiser asks for these at N nodes per iterate; node by node, each compiled call pays Python's
conversions and checks (about 10 us on a 3 us evaluation, 20 us on a 20 us derivative set), which then weigh more
than the dynamics themselves. Both Jacobians are batched alike, so that their comparison
(:class:`robotdyn.optimisation.trajectory.TrajectoryProblem`'s ``derivatives``) measures the derivatives, not the
wrappers: the central differences keep their 2 (n + k + m) evaluations per node (steps
:math:`\\epsilon^{1/3}(1 + \\lvert y_i\\rvert)`, as node by node, and along the holonomic level set where there are
holonomic rows, :mod:`robotdyn.optimisation.manifold_steps`).

Every function returns ``None`` where the compiled model does not serve (no model, an extension built without the
batched calls, slipping wheels it refuses, a compiled fallback at some node, a non-finite derivative): the caller
then goes node by node, where the Python path answers or raises its usual error.
"""

from __future__ import annotations

import numpy as np

from ..fast.compiled import Fallback

STEP = float(np.cbrt(np.finfo(float).eps))
"""Central differences' relative step: :math:`\\epsilon^{1/3}` times :math:`1 + \\lvert y_i\\rvert`."""


def _serves(fast, call: str) -> bool:
    if fast is None or not hasattr(fast.ev, call) or not fast.ready:
        return False
    fast._mine()  # (the model's buffers belong to the thread that built it)
    return True


def rhs_nodes(fast, n: int, X: np.ndarray, U: np.ndarray) -> np.ndarray | None:
    """:math:`f(x_j, \\tau_j) = (S\\nu, \\dot\\nu)` at every node by one compiled call, or ``None``.

    Args:
        fast: The robot's :class:`~robotdyn.fast.compiled.CompiledModel` (or ``None``).
        n: Number of natural coordinates (the first n columns of X).
        X: States (N, n + k): natural coordinates [m, rad], then independent velocities [m/s, rad/s].
        U: Motor torques (N, m) [N m or N].

    Returns:
        (N, n + k), each row :math:`(\\dot q, \\dot\\nu)`, or ``None``.
    """
    if not _serves(fast, "rhs_many"):
        return None
    try:
        return fast.ev.rhs_many(X[:, :n], X[:, n:], U, 0.0)
    except Fallback:
        return None


def analytic_jacobians(fast, n: int, X: np.ndarray, U: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """:math:`(\\partial f/\\partial x, \\partial f/\\partial\\tau)` at every node from the compiled derivative set
    (:mod:`robotdyn.fast.compiled_derivatives`), in one call, or ``None``.

    Args:
        fast: The robot's :class:`~robotdyn.fast.compiled.CompiledModel` (or ``None``).
        n: Number of natural coordinates (the first n columns of X).
        X: States (N, n + k), as for :func:`rhs_nodes`.
        U: Motor torques (N, m).

    Returns:
        ``(Fx (N, n + k, n + k), Fu (N, n + k, m))``: rows :math:`(\\dot q, \\dot\\nu)`, columns (q, nu) in natural
        coordinates and tau; or ``None``.
    """
    if not _serves(fast, "derivatives_many") or fast.slip_refusal is not None:
        return None
    N, nx = X.shape
    try:
        Fx, Fu = fast.ev.derivatives_many(X[:, :n], X[:, n:], U)
    except Fallback:
        return None
    if not (np.isfinite(Fx).all() and np.isfinite(Fu).all()):
        return None  # (node by node, the Python path names what is not finite)
    return Fx.reshape(N, nx, nx), Fu.reshape(N, nx, U.shape[1])


def central_jacobians(fast, n: int, X: np.ndarray, U: np.ndarray,
                      steps=None) -> tuple[np.ndarray, np.ndarray, int] | None:
    """:math:`(\\partial f/\\partial x, \\partial f/\\partial\\tau)` at every node by central differences of the
    compiled right-hand side, all perturbed states in one call, or ``None``.

    Args:
        fast: The robot's :class:`~robotdyn.fast.compiled.CompiledModel` (or ``None``).
        n: Number of natural coordinates (the first n columns of X).
        X: States (N, n + k), as for :func:`rhs_nodes`.
        U: Motor torques (N, m).
        steps: With holonomic rows, the :class:`~robotdyn.optimisation.manifold_steps.ManifoldSteps` that move q
            along the level set (its columns of dependent coordinates are zero); ``None`` without.

    Returns:
        ``(Fx (N, n + k, n + k), Fu (N, n + k, m), evaluations)``, or ``None``.
    """
    if not _serves(fast, "rhs_many"):
        return None
    N, nx = X.shape
    Y = np.hstack([X, U])
    ni = Y.shape[1]
    H = STEP * (1.0 + np.abs(Y))
    plus = np.repeat(Y[:, None, :], ni, axis=1)  # (N, ni, ni): node, stepped input, state
    minus = plus.copy()
    i = np.arange(ni)
    plus[:, i, i] += H
    minus[:, i, i] -= H
    used = np.ones((N, ni), bool)
    if steps is not None:
        for j in range(N):
            for c in range(n):
                pair = steps.pair(X[j, :n], c, H[j, c])
                if pair is None:
                    used[j, c] = False
                else:
                    plus[j, c, :n], minus[j, c, :n] = pair
    P, M = plus[used], minus[used]
    V = len(P)
    points = np.concatenate([P, M])
    try:
        F = fast.ev.rhs_many(points[:, :n], points[:, n:nx], points[:, nx:], 0.0)
    except Fallback:
        return None
    D = np.zeros((N, ni, nx))
    D[used] = (F[:V] - F[V:]) / (2.0 * H[used])[:, None]
    J = D.transpose(0, 2, 1)
    return J[:, :, :nx], J[:, :, nx:], 2 * V

"""Units for IPOPT's torques and objective, taken from the problem's own magnitudes (the minimum-effort cost).

IPOPT approximates the Lagrangian's Hessian by limited-memory BFGS from a multiple of the identity, so it assumes
that the variables are measured in units of comparable effect. A small robot breaks that in SI units: on a 1 kg
differential drive with 30 g wheels (``tests/data/light_diff_drive``), 1 N m of wheel torque gives about 2,000
rad/s^2, the optimal torques are a few mN m and the effort about 1e-4 N^2 m^2 s, while the states are metres and
radians of order 0.1-10. The effort's Hessian on the torques then outweighs the dynamics' curvature on the states by
about 1e5, and IPOPT wandered for 500 iterations on feasible points (largest defect 1e-5 or less) without reaching
the optimum, with 11 nodes and with 21 alike, with analytic and finite-difference Jacobians alike.

So :class:`~robotdyn.optimisation.trajectory.TrajectoryProblem` hands IPOPT the torques in units of their own
expected size, and the objective in units of its own expected value, both from a motion the robot can follow:

1. the prescribed coordinates' smooth rest-to-rest ramp of the initial guess (those with a final value that
   moves), followed by the independent velocities that best produce it through :math:`\\dot q = S(q)\\nu` at each
   node (least squares on those coordinates' rows of S only; the free coordinates, e.g. a wheel's angle, follow);
2. the accelerations of these velocities (central differences over the nodes) and the torques that best produce
   them at each node, in least squares through the forward dynamics, which are affine in the torques:
   :math:`\\dot\\nu(x, \\tau) = \\dot\\nu(x, 0) + \\sum_i \\tau_i (\\dot\\nu(x, e_i) - \\dot\\nu(x, 0))` (m + 1
   evaluations per node, on the compiled batch where it serves);
3. each motor's unit is its root-mean-square torque over the nodes (at least :data:`FLOOR` of the largest
   motor's), the objective's unit :data:`OBJECTIVE_SHARE` times the effort of these torques; each rounded to a power of
   2, so that the scaling is exact in floating point (IPOPT's iterates map back to the same bits, and the optimum's
   cost is unchanged by it).

Measured on the fixture (0.3 m in 2 s): 11, 21, 41 and 81 nodes converge (``Solve_Succeeded``) in 15-18 iterations,
with analytic and finite-difference Jacobians, to the same cost (12 digits). The built-in optimisations keep their
optima (within 1.3e-9 in cost): Quasimoro's rest-to-rest (``bench/bench.py trajectory``) 14 -> 15 iterations, the
rover's traction path 18 -> 14, the sprung car 8 -> 6, the adaptable tricycle's fixed radii 24 -> 24. The ``peak-mu`` cost (a squared
friction coefficient, already of order 1) is left in SI units. Where the guessed motion's torques cannot be found
(a model that refuses a node, non-finite values, a motion that needs no torque) the units stay 1: the problem as
it was.
"""

from __future__ import annotations

import numpy as np

from .node_batches import rhs_nodes

FLOOR = 1e-3
"""A motor's unit is at least this fraction of the largest motor's (a motor the guessed motion does not use)."""
OBJECTIVE_SHARE = 8.0
"""The objective's unit as a multiple of the guessed motion's effort. Measured (12 problems: the fixture at 5
distances, times and node counts, the sprung car, Quasimoro): 8 took 228 IPOPT iterations in all, 1 took 266, mostly on the sprung car, whose Python-path derivatives leave IPOPT's dual infeasibility a floor near
its tolerance; on the fixture and Quasimoro the two differ by a few iterations either way."""


def power_of_two(x: np.ndarray | float) -> np.ndarray:
    """The nearest powers of 2 (in the logarithm) to positive finite numbers.

    Args:
        x: Positive finite numbers.

    Returns:
        :math:`2^{\\mathrm{round}(\\log_2 x)}`, elementwise.
    """
    return np.exp2(np.round(np.log2(x)))


def guessed_torques(problem, X: np.ndarray) -> np.ndarray:
    """The torques (N, m) [N m or N] that best produce a smooth rest-to-rest motion of the prescribed coordinates
    at the nodes (steps 1 and 2 of the module docstring).

    Args:
        problem: The :class:`~robotdyn.optimisation.trajectory.TrajectoryProblem`.
        X: The initial guess's states (N, n + k): natural coordinates [m, rad], independent velocities [m/s, rad/s]
            (the coordinates are kept, the velocities replaced).

    Returns:
        The torques at the nodes (N, m).
    """
    N, n, k, m = problem.nodes, problem.n, problem.k, problem.m
    X = np.array(X, float)
    moved = np.isfinite(problem.x_end[:n]) & (np.nan_to_num(problem.x_end[:n]) != problem.q0)
    P = np.flatnonzero(moved)
    dq = problem.x_end[P] - problem.q0[P]
    t = np.linspace(0.0, problem.t_end, N)
    sdot = 0.5 * np.pi / problem.t_end * np.sin(np.pi * t / problem.t_end)
    if P.size:  # the guess's S(q_j) where it built them (the same coordinates), else built here
        S, q = getattr(problem, "_guess_S_q", (None, None))  # (one read: the pair the guess published)
        if S is None or S.shape[0] != N - 2 or not np.array_equal(q, X[1:-1, :n]):
            S = np.array([problem.robot.reduced(X[j, :n], np.zeros(k)).S for j in range(1, N - 1)])
        X[1:-1, n:] = np.einsum("jkp,p->jk", np.linalg.pinv(S[:, P]), dq) * sdot[1:-1, None]
        X[[0, -1], n:] = 0.0
    accel = np.gradient(X[:, n:], t, axis=0)
    F = []
    for i in range(m + 1):  # tau = 0, then each unit torque: the forward dynamics are affine in tau
        U = np.zeros((N, m))
        if i:
            U[:, i - 1] = 1.0
        Fi = rhs_nodes(problem._fast, n, X, U)
        F.append(np.array([problem._f(X[j], U[j]) for j in range(N)]) if Fi is None else Fi)
    B = np.stack([F[i + 1][:, n:] - F[0][:, n:] for i in range(m)], axis=2)  # (N, k, m)
    return np.einsum("jmk,jk->jm", np.linalg.pinv(B), accel - F[0][:, n:])


def effort_units(problem, z0: np.ndarray) -> tuple[np.ndarray, float]:
    """The torques' units and the objective's factor for IPOPT (step 3 of the module docstring).

    Args:
        problem: The :class:`~robotdyn.optimisation.trajectory.TrajectoryProblem` (cost ``effort``).
        z0: Its initial decision vector (states, then torques, node after node).

    Returns:
        ``(units, factor)``: each motor's torque unit (m,) [N m or N] and the factor [1/(N^2 m^2 s)] IPOPT's
        objective is multiplied by, all powers of 2; ``(ones, 1.0)`` where no such motion is found.
    """
    N, nx, m = problem.nodes, problem.nx, problem.m
    X, U = problem._split(z0)
    none = (np.ones(m), 1.0)
    try:
        tau = U if problem.guess is not None and np.any(U != 0.0) else guessed_torques(problem, X)
    except Exception:  # noqa: BLE001 - a node the model refuses: the problem in SI units (its error comes in solve)
        return none
    rms = np.sqrt(np.mean(tau ** 2, axis=0))
    if not (np.all(np.isfinite(rms)) and rms.max() > 0.0):
        return none
    units = power_of_two(np.maximum(rms, FLOOR * rms.max()))
    effort = problem.t_end * float(np.sum(rms ** 2))
    return units, float(power_of_two(1.0 / (OBJECTIVE_SHARE * effort)))


__all__ = ["FLOOR", "OBJECTIVE_SHARE", "effort_units", "guessed_torques", "power_of_two"]

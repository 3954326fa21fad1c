"""Contact forces that balance a given wrench, inside friction cones (statics or kinetostatics).

A body (or a whole robot treated as one) touches the ground at points :math:`p_i` with upward unit normals
:math:`n_i` and receives contact forces :math:`F_i` (world frame, N). The six equilibrium equations

.. math:: \\sum_i F_i = F_{req}, \\qquad \\sum_i (p_i - o) \\times F_i = M_{req}

(:math:`F_{req}, M_{req}` the wrench the contacts must supply about the point o, e.g. minus gravity for statics,
plus the inertial wrench for kinetostatics) leave :math:`3k - 6` force components free for k contacts. They are
fixed by minimising the friction forces :math:`\\sum_i \\|F_i - (F_i\\cdot n_i)n_i\\|^2` (or the forces,
:math:`\\sum_i \\|F_i\\|^2`) subject to unilateral contact :math:`F_i\\cdot n_i \\ge 0` and the Coulomb cone
:math:`\\|F_i - (F_i\\cdot n_i)n_i\\| \\le \\mu\\, F_i\\cdot n_i`. The equality-constrained minimum is found in closed
form (KKT system); only if it violates an inequality is scipy's SLSQP run with all constraints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..constraints.constraint import skew
from ..errors import ConstraintError, InputError


@dataclass
class ContactForces:
    """Result of :func:`solve_contact_forces`.

    Attributes:
        forces: (k, 3) contact forces on the robot, world frame [N].
        normal: (k,) normal components :math:`F_i\\cdot n_i` [N].
        friction: (k,) magnitudes of the tangential parts [N].
        ratio: (k,) friction use :math:`|F_t| / (\\mu F_n)` (<= 1 inside the cone).
        equilibrium: Norm of the residual of the six equilibrium equations [N, N m].
        method: ``"kkt"`` (closed form) or ``"slsqp"``.
    """

    forces: np.ndarray
    normal: np.ndarray
    friction: np.ndarray
    ratio: np.ndarray
    equilibrium: float
    method: str


def equilibrium_matrix(points: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """G (6, 3k) with :math:`G\\,[F_1; ...; F_k] = [\\sum F_i; \\sum (p_i - o)\\times F_i]`.

    Args:
        points: Contact points p_i (k, 3) [m], world frame.
        origin: The point o (3,) [m] about which moments are taken.

    Returns:
        G (6, 3k).
    """
    k = len(points)
    G = np.zeros((6, 3 * k))
    for i, p in enumerate(points):
        G[:3, 3 * i: 3 * i + 3] = np.eye(3)
        G[3:, 3 * i: 3 * i + 3] = skew(np.asarray(p, float) - origin)
    return G


def solve_contact_forces(
    points,
    normals,
    force,
    moment,
    origin,
    mu: float,
    objective: str = "friction",
    tol: float = 1e-9,
) -> ContactForces:
    """Contact forces supplying the wrench (force, moment about origin) with the least friction.

    Args:
        points: (k, 3) contact points [m].
        normals: (k, 3) upward unit normals of the ground at the contacts.
        force: (3,) total force the contacts must supply [N].
        moment: (3,) total moment about ``origin`` they must supply [N m].
        origin: (3,) reduction point of the moment [m].
        mu: Static friction coefficient (> 0).
        objective: ``"friction"`` (minimise squared friction forces) or ``"norm"`` (squared forces).
        tol: Feasibility tolerance on the unilateral and cone constraints [N].

    Returns:
        A :class:`ContactForces`: forces (k, 3) [N] in the world frame, normal components and friction magnitudes
        (k,) [N], friction use (k,), the equilibrium residual [N, N m] and the method used.

    Raises:
        InputError: Bad shapes, mu <= 0, unknown objective.
        ConstraintError: No forces satisfy equilibrium, unilateral contact and the cones (the robot would tip or
            slide); the message names the worst contact.
    """
    P = np.atleast_2d(np.asarray(points, float))
    N = np.atleast_2d(np.asarray(normals, float))
    k = len(P)
    if P.shape != (k, 3) or N.shape != (k, 3) or k == 0:
        raise InputError(f"contact points {P.shape} and normals {N.shape}; expected two (k, 3) arrays, k >= 1")
    if not (np.isfinite(mu) and mu > 0):
        raise InputError(f"friction coefficient mu = {mu}; expected a positive number")
    if objective not in ("friction", "norm"):
        raise InputError(f"objective {objective!r}; expected 'friction' or 'norm'")
    N = N / np.linalg.norm(N, axis=1)[:, None]
    origin = np.asarray(origin, float)
    b = np.concatenate([np.asarray(force, float), np.asarray(moment, float)])
    G = equilibrium_matrix(P, origin)
    H = np.zeros((3 * k, 3 * k))
    for i, n in enumerate(N):
        H[3 * i: 3 * i + 3, 3 * i: 3 * i + 3] = np.eye(3) - (np.outer(n, n) if objective == "friction" else 0.0)
    # closed-form equality-constrained minimum: [H G^T; G 0][F; lam] = [0; b]
    K = np.block([[H, G.T], [G, np.zeros((6, 6))]])
    sol = np.linalg.lstsq(K, np.concatenate([np.zeros(3 * k), b]), rcond=None)[0]
    x = sol[: 3 * k]
    method = "kkt"

    def split(x):
        F = x.reshape(k, 3)
        fn = np.einsum("ij,ij->i", F, N)
        ft = F - fn[:, None] * N
        return F, fn, np.linalg.norm(ft, axis=1)

    F, fn, ft = split(x)
    if np.any(fn < -tol) or np.any(ft > mu * fn + tol) or np.linalg.norm(G @ x - b) > 1e-8 * max(1.0, np.abs(b).max()):
        method = "slsqp"
        cons = [
            {"type": "eq", "fun": lambda x: G @ x - b, "jac": lambda x: G},
            {"type": "ineq", "fun": lambda x: np.einsum("ij,ij->i", x.reshape(k, 3), N)},
            {"type": "ineq", "fun": lambda x: (mu * split(x)[1]) ** 2 - split(x)[2] ** 2},
        ]
        from scipy.optimize import minimize

        res = minimize(lambda x: 0.5 * x @ H @ x, x, jac=lambda x: H @ x, constraints=cons, method="SLSQP",
                       options={"ftol": 1e-14, "maxiter": 500})
        x = res.x
        F, fn, ft = split(x)
        worst = int(np.argmax(ft - mu * fn))
        if np.linalg.norm(G @ x - b) > 1e-6 * max(1.0, np.abs(b).max()) or fn.min() < -tol or np.any(
            ft > mu * fn + 1e-6 * max(1.0, np.abs(b).max())
        ):
            raise ConstraintError(
                f"no contact forces balance the load inside the friction cones (mu = {mu:g}); contact {worst} "
                f"needs friction {ft[worst]:.4g} N with normal force {fn[worst]:.4g} N"
            )
    ratio = np.where(fn > 0, ft / (mu * np.maximum(fn, 1e-300)), np.inf)
    return ContactForces(F, fn, ft, ratio, float(np.linalg.norm(G @ x - b)), method)

"""Derivatives of the forward dynamics with slipping wheels (:mod:`robotdyn.contact.sliding`).

With slipping wheels the accelerations and the kept constraint rows' forces solve together
(:func:`robotdyn.contact.sliding.forward`):

.. math:: \\Phi = \\mathrm{RNEA}(q, v, a) - B\\tau - G\\lambda = 0,\\quad
          G = A_R^T - \\sum_i J_{t,i}^T c_i(s_i)\\, e_{n_i}^T,\\quad a = S\\dot\\nu + w,\\; s_i = J_{t,i} v,

so with :math:`K_s = [MS,\\; -G]`, :math:`K_s\\, d(\\dot\\nu, \\lambda) = -\\partial\\Phi` where

.. math:: \\partial\\Phi = \\partial_q\\mathrm{RNEA}\\,dq + \\partial_v\\mathrm{RNEA}\\,dv + M\\,da|_{\\dot\\nu}
          - d(B\\tau) - \\partial_q(A_R^T\\lambda)\\,dq + \\sum_i \\lambda_{n_i}\\big(\\partial_q(J_{t,i}^T c_i)\\,dq
          + J_{t,i}^T c_i'(s_i)\\, ds_i\\big),\\quad ds_i = \\partial_q(J_{t,i}v)\\,dq + J_{t,i}\\,dv.

The transposed-row terms :math:`\\partial_q(A^T\\lambda)` need every column of :math:`\\partial A/\\partial q`: one
frame pass per velocity (:class:`~robotdyn.constraints.row_derivatives.FramePass` at each unit vector). The law's
:math:`c'(s)` is analytic for :class:`~robotdyn.contact.friction.RegularisedCoulomb` and
:class:`~robotdyn.contact.friction.LinearTyre` (in its linear and in its saturated range; at the kink it has none
and the linear side is taken); another smooth law's by central differences, reported as numerical. Exact
(set-valued) Coulomb friction and stick-slip wheels have no derivative and are refused in one line
(:func:`smooth_sliding`). The rest is :mod:`robotdyn.reduction.dynamics_derivatives`. The compiled twin is
``robotdyn/kernels/sliding_derivatives.hpp`` (:mod:`robotdyn.fast.compiled_derivatives`), which
:meth:`robotdyn.robot.Robot.dynamics_derivatives` takes where the compiled model simulates the slipping wheels.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ..constraints.row_derivatives import FramePass, velocity_dq, wheel_velocity_dq
from ..errors import InputError
from ..reduction.dynamics_derivatives import DynamicsDerivatives, motor_rows, pieces, result
from ..reduction.joint_springs import spring_terms
from .friction import ExactCoulomb, LinearTyre, RegularisedCoulomb
from . import painleve
from .sliding import PAINLEVE_CONDITION, SlippingWheel, painleve_error, sliding_now, tangential

TANGENT = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
"""The tangential rows (t1, t2) of a wheel's contact frame."""


def law_jacobian(wheel: SlippingWheel, s: np.ndarray, numerical: set[str]) -> np.ndarray:
    """:math:`\\partial c/\\partial s` (2, 2) of a slipping wheel's friction coefficient
    :meth:`~robotdyn.contact.sliding.SlippingWheel.friction_coefficient` at slip s (free directions only).

    Args:
        wheel: The slipping wheel (its friction law and its free slip directions).
        s: The slip velocity (2,) [m/s] of the contact point along the contact frame's (t1, t2).
        numerical: A set to which a note naming the wheel is added when the law's derivative is taken by central
            differences (a law other than :class:`~robotdyn.contact.friction.RegularisedCoulomb` and
            :class:`~robotdyn.contact.friction.LinearTyre`).

    Returns:
        The Jacobian (2, 2) [s/m], rows and columns along (t1, t2), zero in the wheel's blocked directions.
    """
    f = wheel._free
    x = s * f
    law = wheel.law
    if type(law) is RegularisedCoulomb:
        rho = math.sqrt(float(x @ x) + law.slip_velocity ** 2)
        J = law.mu * (np.eye(2) / rho - np.outer(x, x) / rho ** 3)
    elif type(law) is LinearTyre:
        speed = math.sqrt(float(x @ x))
        if speed * law.stiffness <= law.mu:
            J = law.stiffness * np.eye(2)
        else:
            J = law.mu * (np.eye(2) / speed - np.outer(x, x) / speed ** 3)
    else:
        h = 1e-6 * max(1.0, float(np.abs(x).max()))
        J = np.column_stack([(law.coefficient(x + h * e) - law.coefficient(x - h * e)) / (2 * h) for e in np.eye(2)])
        numerical.add(f"{wheel.name}: friction law derivative (central differences)")
    return f[:, None] * J * f[None, :]


def smooth_sliding(robot) -> list:
    """The wheels sliding now (:func:`~robotdyn.contact.sliding.sliding_now`), each checked to have a derivative:
    the one-line refusal of stick-slip wheels and exact Coulomb friction, on the Python and the compiled path.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The sliding wheels (:class:`~robotdyn.contact.sliding.SlippingWheel`), in the robot's order.

    Raises:
        InputError: A stick-slip wheel, or a law without a derivative (exact Coulomb friction).
    """
    wheels = sliding_now(robot)
    for wheel in wheels:
        if not isinstance(wheel, SlippingWheel):
            raise InputError(f"dynamics derivatives: wheel {wheel.name!r} switches between sticking and slipping "
                             "(stick-slip), which has no derivative; expected rolling or smoothly slipping wheels")
        if isinstance(wheel.law, ExactCoulomb):
            raise InputError(f"dynamics derivatives: wheel {wheel.name!r} has exact (set-valued) Coulomb friction, "
                             "which has no derivative; expected friction = 'coulomb' (regularised) or 'linear'")
    return wheels


def sliding_derivatives(robot, q, nu, tau, pc=None) -> DynamicsDerivatives:
    """:math:`\\dot\\nu` and its derivatives in q, :math:`\\nu`, :math:`\\tau` for a robot with slipping wheels
    (Python path; the same contents as :func:`robotdyn.reduction.dynamics_derivatives.dynamics_derivatives`).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` whose slipping wheels (those sliding now) have a smooth friction
            law (regularised Coulomb, linear tyre, or another smooth law by finite differences).
        q: Natural coordinates (n,) [m, rad], in the order of ``robot.coordinates``.
        nu: Independent velocities (k,) in the order of ``robot.velocity_names`` [m/s, rad/s].
        tau: Motor torques/forces (n_motors,) [N m or N] in the order of ``robot.motors``.
        pc: The derivative :class:`~robotdyn.reduction.dynamics_derivatives.Pieces` at (q, nu) when the caller
            has them already (default None: computed here).

    Returns:
        A :class:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives`.

    Raises:
        InputError: A stick-slip wheel or a law without a derivative (exact Coulomb friction).
        SingularConstraintError: The coupled system is singular (Painlevé), as in the forward dynamics.
        ConstraintError: A slipping wheel's normal row is redundant here (its load undetermined).
        NonFiniteError: A non-finite result.
    """
    q, nu, tau = robot.check_q(q), robot.check_nu(nu), robot.check_tau(tau)
    wheels = smooth_sliding(robot)
    pc = pieces(robot, q, nu) if pc is None else pc
    model, tree, n, k = pc.model, pc.tree, pc.n, pc.k
    S, M, v, w, B, kin0 = pc.S, pc.M, pc.v, pc.w, pc.B, pc.kin0
    rows = pc.rows0
    kept = np.asarray(pc.P.rows, int)
    G = rows.A[kept].T.copy()
    Jt, slip, coef, pos = [], [], [], []
    for wheel in wheels:
        row = rows.labels.index(f"{wheel.name}.normal")
        hit = np.flatnonzero(kept == row)
        if not hit.size:  # a statically indeterminate chassis: its loads are the rigid limit's (coupled solve)
            raise InputError(f"dynamics derivatives: slipping wheel {wheel.name!r} has a redundant normal row (a "
                             "statically indeterminate chassis, whose loads forward dynamics takes from the rigid "
                             "limit of compliance solved with the friction): that coupled solve has no derivative "
                             "rule yet; expected slipping wheels whose loads rigid-body dynamics determine")
        J, s = tangential(wheel, pc.kin)
        c = wheel.friction_coefficient(s)
        G[:, hit[0]] -= J.T @ c
        Jt.append(J)
        slip.append(s)
        coef.append(c)
        pos.append(int(hit[0]))
    Ks = np.hstack([M @ S, -G])
    cond = np.linalg.cond(Ks)
    if not np.isfinite(cond) or cond > PAINLEVE_CONDITION:
        raise painleve_error(wheels, cond)
    if wheels:  # no derivative where forward dynamics refuses: the Painleve check (robotdyn.contact.painleve)
        AR, sel = rows.A[kept], np.zeros((len(kept), len(wheels)))
        sel[pos, np.arange(len(wheels))] = 1.0
        painleve.check(Ks, k + np.array(pos), M @ (AR.T @ np.linalg.solve(AR @ AR.T, sel)), wheels, np.array(slip),
                       np.column_stack([J.T @ c for J, c in zip(Jt, coef)]))
    Q, dQ_dq, dQ_dv = spring_terms(getattr(robot, "springs", ()), q, v)  # joint springs and dampers (zeros: none)
    sol = np.linalg.solve(Ks, B @ tau - pin.rnea(model, tree, q, v, w) + Q)
    nudot, lam = sol[:k], sol[k:]
    a = S @ nudot + w
    dtau_dq, dtau_dv, _ = (x.copy() for x in pin.computeRNEADerivatives(model, tree, q, v, a))
    dtau_dq -= dQ_dq  # Phi's derivatives: the tree's less the springs' (stiffness) and dampers' (damping)
    dtau_dv -= dQ_dv
    # every column of dA/dq: T[i, j, p] = d A_ij / d q_p (and the slipping wheels' tangential rows likewise)
    units = [FramePass(kin0, e) for e in np.eye(n)]
    T = np.stack([velocity_dq(pc.constraints, fp) for fp in units], axis=1)
    Tt = [np.stack([wheel_velocity_dq(wh, fp, TANGENT) for fp in units], axis=1) for wh in wheels]
    dGlam_q = np.einsum("i,ijp->jp", lam, T[kept]) if kept.size else np.zeros((n, n))
    dGlam_nu = np.zeros((n, k))
    for i, wheel in enumerate(wheels):
        C = law_jacobian(wheel, slip[i], pc.numerical)
        ds_q = np.einsum("j,rjp->rp", v, Tt[i]) + Jt[i] @ pc.Vq
        dGlam_q -= lam[pos[i]] * (np.einsum("r,rjp->jp", coef[i], Tt[i]) + Jt[i].T @ C @ ds_q)
        dGlam_nu -= lam[pos[i]] * (Jt[i].T @ C @ Jt[i] @ S)
    Bq = motor_rows(robot, kin0, units, tau)
    R_q = dtau_dq + dtau_dv @ pc.Vq + M @ pc.Aq(nudot) - Bq - dGlam_q
    R_nu = dtau_dv @ S + M @ pc.Wnu - dGlam_nu
    X = np.linalg.solve(Ks, -np.hstack([R_q, R_nu, -B]))[:k]
    return result(robot, pc, nudot, X[:, :n], X[:, n:n + k], X[:, n + k:])


__all__ = ["sliding_derivatives", "law_jacobian", "smooth_sliding"]

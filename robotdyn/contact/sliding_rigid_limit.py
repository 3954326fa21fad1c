"""Slipping wheels whose normal loads rigid-body dynamics leave open (a rigid chassis on four wheels): the
accelerations, every constraint multiplier and the friction solved together, closed by the rigid limit of the
wheels' normal compliance (:mod:`robotdyn.contact.rigid_limit`; notes: indeterminate loads and compliance).

:func:`robotdyn.contact.sliding.forward` calls :func:`coupled` where the projection drops rows. The compiled twin is
robotdyn/kernels/sliding_rigid_limit.hpp (the same steps in the same order; the simulation's right-hand side on the
compiled engine).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..constraints.rolling_contact import RollingWheel
from ..reduction.actuation import input_matrix
from .applied_forces import applied, has_applied
from .compliance import wheel_stiffness
from .rigid_limit import PULL_TOL, RANK_TOL, normal_map
from . import painleve


def coupled(robot, q: np.ndarray, red, kin, wheels: list, tau: np.ndarray):
    """Accelerations, loads and friction of slipping wheels solved together where rigid-body dynamics leave wheel
    loads open (:mod:`robotdyn.contact.rigid_limit`): :func:`robotdyn.contact.sliding.forward`'s system on every row
    (redundant ones included), closed by the compatibility of the rigid limit of normal compliance.

    Unknowns :math:`(\\dot\\nu, \\lambda)` (k + m) and, for wheels held at zero load, their no-pull multipliers
    :math:`\\mu_U`; equations

    .. math::
        M S\\dot\\nu - \\Big(A^T - \\sum_i J_{t,i}^T c_i e_{n_i}^T\\Big)\\lambda = B\\tau - \\mathrm{RNEA}(q, v, w),
        \\qquad (C N V_n)^T (K^{-1} C\\lambda - \\mu) = 0,\\qquad (N V_o)^T\\lambda = 0,\\qquad C_U\\lambda = 0,

    the second being the compatibility of the wheels' deflections :math:`K^{-1}n` with a rigid motion of the
    chassis along the undetermined directions that move loads (:math:`V_n`; the stationarity of :func:`robotdyn.contact.rigid_limit.split`'s
    complementary energy, friction or not), the third the minimum-norm choice along those that move none. The set
    U of unloaded wheels is found by an active-set loop (with friction the problem is no longer a QP, so not
    :func:`robotdyn.contact.rigid_limit.split`'s solver): a loaded wheel whose load comes out negative is unloaded,
    an unloaded one whose multiplier :math:`\\mu` comes out negative is loaded again (at most 2W + 2 solves).
    Where a wheel to unload cannot be held at zero by the load-moving directions left (its row of
    :math:`C N V_n` depends on those of U: a whole axle of a rigid car would pull, it lifts off), no split avoids
    pulling: the compatible loads are returned, some negative (as :func:`robotdyn.contact.rigid_limit.split` does),
    for a lift-off event to locate the zero; holding that wheel as well would make the system singular, which is no
    Painleve paradox.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Coordinates (n,).
        red: Its :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu).
        kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).
        wheels: The sliding wheels (:func:`robotdyn.contact.sliding.sliding_now`).
        tau: Motor torques [N m or N].

    Returns:
        The :class:`~robotdyn.contact.sliding.SlidingState` (with every row's multiplier ``lam``), or ``None``
        where the redundant rows move no wheel load (the projection's rows then decide, as without a split).

    Raises:
        SingularConstraintError: The coupled system is singular (Painlevé), or no set of unloaded wheels solves it.
    """
    from .sliding import PAINLEVE_CONDITION, SlidingState, painleve_error, tangential  # (sliding imports this module)

    rows = red.jacobian_rows
    A, labels = rows.A, list(rows.labels)
    m, n = A.shape
    _, s, Vt = np.linalg.svd(A.T, full_matrices=True)
    tol = s.max(initial=0.0) * max(A.shape) * np.finfo(float).eps
    rank = int(np.sum(s > tol))
    N = Vt[rank:].T
    every = [c for c in robot.constraints if isinstance(c, RollingWheel)]
    index = {lab: i for i, lab in enumerate(labels)}
    C = normal_map([np.array([index[lab] for lab in c._labels()], int) for c in every],
                   [c._directions for c in every], m)
    P = C @ N
    _, sp, Vpt = np.linalg.svd(P, full_matrices=True)
    p = int(np.sum(sp > RANK_TOL))
    if p == 0:
        return None
    Vn, Vo = Vpt[:p].T, Vpt[p:].T
    k = wheel_stiffness(robot, [c.name for c in every])
    kinv = float(np.mean(k)) / k  # only the ratios matter (rows of order one)
    model, data = robot.model, robot.data
    G = A.T.copy()
    slip = np.zeros((len(wheels), 2))
    coef = np.zeros((len(wheels), 2))
    where = np.zeros(len(wheels), int)
    U = np.zeros((n, len(wheels)))  # each wheel's friction column J_t^T c (robotdyn.contact.painleve)
    for i, wheel in enumerate(wheels):
        Jt, slip[i] = tangential(wheel, kin)
        coef[i] = wheel.friction_coefficient(slip[i])
        U[:, i] = Jt.T @ coef[i]
        G[:, index[f"{wheel.name}.normal"]] -= U[:, i]
        where[i] = every.index(wheel)
    S = red.S
    kk = S.shape[1]
    M = pin.crba(model, data, q)
    MS = M @ S
    rhs = input_matrix(robot.motors, kin) @ tau - pin.rnea(model, data, q, red.v, red.w)
    app = applied(robot, q, red.v, kin) if has_applied(robot) else None
    if app is not None:  # joint springs, compliant wheels: known at the state (robotdyn.contact.applied_forces)
        rhs += app.Q
    PV = P @ Vn  # (W, p)
    compat = PV.T @ (kinv[:, None] * C)  # (p, m)
    opened = (N @ Vo).T  # (d - p, m)
    unloaded: list[int] = []
    compatible = None  # the solution holding no wheel at zero load (returned where no split avoids pulling)
    for _ in range(2 * len(every) + 2):
        u = len(unloaded)
        top = np.hstack([MS, -G, np.zeros((n, u))])
        mid = np.hstack([np.zeros((p, kk)), compat, -PV[unloaded].T])
        low = np.hstack([np.zeros((opened.shape[0], kk)), opened, np.zeros((opened.shape[0], u))])
        held = np.hstack([np.zeros((u, kk)), C[unloaded], np.zeros((u, u))])
        K = np.vstack([top, mid, low, held])
        b = np.concatenate([rhs, np.zeros(K.shape[0] - n)])
        cond = np.linalg.cond(K)
        if not np.isfinite(cond) or cond > PAINLEVE_CONDITION:
            raise painleve_error(wheels, cond)
        sol = np.linalg.solve(K, b)
        lam, mu = sol[kk:kk + m], sol[kk + m:]
        loads = C @ lam
        scale = max(float(np.max(np.abs(loads), initial=0.0)), 1e-300)
        free = [j for j in range(len(every)) if j not in unloaded]
        worst = min(free, key=lambda j: loads[j]) if free else None
        if u == 0:
            compatible = sol, lam, loads, K
        if worst is not None and loads[worst] < -PULL_TOL * scale:
            if np.linalg.matrix_rank(PV[unloaded + [worst]], tol=RANK_TOL) <= u:
                # the open loads cannot hold this wheel at zero too (a whole axle would pull: it lifts off), so no
                # split pulls on no wheel: the compatible loads, some negative, as rigid_limit.split gives them (the
                # lift-off event then finds where the load reaches zero; holding both wheels was singular)
                (sol, lam, loads, K), unloaded = compatible, []
                break
            unloaded.append(worst)
            continue
        if u and np.min(mu) < -PULL_TOL * float(np.max(np.abs(mu))):
            unloaded.pop(int(np.argmin(mu)))
            continue
        break
    else:
        raise painleve_error(wheels, float("inf"))
    live = [i for i in range(len(wheels)) if where[i] not in unloaded]
    if live:  # a unique, consistent solution: the Painleve check on the separations the rigid rows allow
        sel = np.array([index[f"{wheels[i].name}.normal"] for i in live], int)
        E = np.zeros((m, len(live)))
        E[sel, np.arange(len(live))] = 1.0
        _, sn, snt = np.linalg.svd(N.T @ E)
        basis = snt[int(np.sum(sn > RANK_TOL)):].T if np.any(sn > RANK_TOL) else None
        if basis is None or basis.shape[1]:
            pad = np.zeros((K.shape[0] - n, len(live)))
            MZ = np.vstack([M @ np.linalg.lstsq(A, E, rcond=None)[0], pad])
            painleve.check(K, kk + sel, MZ, [wheels[i] for i in live], slip[live], np.vstack([U[:, live], pad]),
                           basis)
    normal = loads[where]
    force = -normal[:, None] * coef
    power = float(np.sum(force * slip)) + (app.friction_power if app is not None else 0.0)
    return SlidingState(sol[:kk], red, normal, slip, force, power, lam, tuple(every[j].name for j in unloaded),
                        damper_power=app.damper_power if app is not None else 0.0)


__all__ = ["coupled"]

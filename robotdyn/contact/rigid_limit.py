"""Loads that rigid-body dynamics leave open, fixed by the rigid limit of the wheels' normal compliance.

With the constraint rows :math:`A` (m rows, rank r < m) the multipliers of :math:`M a + h = B\\tau + A^T\\lambda`
are :math:`\\lambda = \\lambda_0 + N z` for any z (N: the null space of :math:`A^T`, m x d): a rigid chassis on
four wheels is statically indeterminate. Each wheel i has a normal (radial) stiffness :math:`k_i`
(:mod:`robotdyn.contact.compliance`); the loads a stiff elastic chassis actually carries are the compatible ones,
which minimise the complementary energy (Menabrea, Castigliano: of all statically admissible loads, the
compatible ones make the complementary energy stationary, a minimum for linear springs)

.. math:: \\min_z \\sum_i \\frac{n_i(z)^2}{2 k_i} \\quad\\text{subject to}\\quad n_i(z) \\ge 0,

with :math:`n(z) = C(\\lambda_0 + N z)` the wheels' normal loads [N] (C picks each wheel's normal component from its
rows). Without the no-pull condition the minimiser is :math:`n = K J (J^T K J)^{-1} W` (compatible loads
:math:`n = K J u`); it depends only on the ratios :math:`k_i / k_j`, not on the stiffness scale, and is what a
compliant model converges to as the stiffnesses grow. With it (a wheel that would pull carries zero: the chassis
rests on the others) it is a least-distance program, solved exactly as Lawson & Hanson's LDP through their NNLS
(*Solving Least Squares Problems*, 1974, ch. 23; :func:`scipy.optimize.nnls`).

References (the site's bibliography, ``docs/bibliography.md``): L. F. Menabrea, *Nouveau principe sur la
distribution des tensions dans les systèmes élastiques*, Comptes rendus hebdomadaires des séances de l'Académie des
sciences, 1858 (volume and pages not confirmed); A. Castigliano, *Théorie de l'équilibre des systèmes élastiques et
ses applications*, Turin: A. F. Negro, 1879; C. L. Lawson, R. J. Hanson, *Solving Least Squares Problems*,
Englewood Cliffs, NJ: Prentice-Hall, 1974, ch. 23 (SIAM reprint, Classics in Applied Mathematics 15, 1995).

Every combination of rows that rigid-body dynamics determine (totals, axle and side sums, moments) keeps its value:
z moves only along N. Directions of N that move no normal load (e.g. two wheels of one axle pushing against each
other sideways) are not fixed by normal compliance: they stay open (:attr:`RigidLimit.open`), and the values shown
there are the minimum-norm choice among the loads of the rigid limit.

With slipping wheels the friction forces depend on the loads, so the split belongs inside the coupled solve of
accelerations and loads (:func:`robotdyn.contact.sliding_rigid_limit.coupled`, used by :func:`robotdyn.contact.sliding.forward`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MODEL = "rigid limit of compliance"
"""How loads that rigid-body dynamics leave open are reported (which model produced them)."""

RANK_TOL = 1e-9
"""Singular value (the null space being orthonormal and C's entries of magnitude <= 1) below which a direction of
the undetermined combinations counts as moving no normal load."""

PULL_TOL = 1e-9
"""Relative tolerance (of the largest load) within which a load counts as not pulling."""


@dataclass
class RigidLimit:
    """The multipliers of the rigid limit of normal compliance at one state.

    Attributes:
        lam: (m,) multipliers: the given ones on every row rigid-body dynamics determine, the rigid limit's on the
            others (minimum-norm along :attr:`open`).
        fixed: (m,) rows that rigid-body dynamics leave open and the rigid limit fixes.
        open: (m, d') orthonormal directions that stay open (they move no normal load).
        unloaded: Indices (into the wheels of C) of wheels carrying zero because they would pull.
        feasible: False when no split of the loads pulls on no wheel (the loads shown are then the rigid limit
            without the no-pull condition, some of them negative).
    """

    lam: np.ndarray
    fixed: np.ndarray
    open: np.ndarray
    unloaded: list[int]
    feasible: bool = True


def normal_map(rows: list[np.ndarray], directions: list[np.ndarray], m: int) -> np.ndarray:
    """C (W, m): row w picks wheel w's normal load :math:`(D^T\\lambda)_n` from the multipliers.

    Args:
        rows: Per wheel the indices of its rows among the m rows.
        directions: Per wheel D (rows, 3): row i acts along D[i] of (t1, t2, n).
        m: Number of rows.

    Returns:
        The matrix C (W, m), one row per wheel in wheel order, one column per multiplier in row order.
    """
    C = np.zeros((len(rows), m))
    for w, (idx, D) in enumerate(zip(rows, directions)):
        C[w, idx] = np.asarray(D, float)[:, 2]
    return C


def split(lam: np.ndarray, N: np.ndarray, C: np.ndarray, k: np.ndarray, determined: np.ndarray | None = None,
          offset: np.ndarray | None = None) -> RigidLimit:
    """The rigid limit of normal compliance on the family :math:`\\lambda + N z` (see the module).

    Args:
        lam: (m,) one solution of :math:`A^T\\lambda = e` [N, N m].
        N: (m, d) orthonormal null space of :math:`A^T`.
        C: (W, m) the wheels' normal maps (:func:`normal_map`).
        k: (W,) the wheels' normal stiffnesses [N/m] (> 0; only their ratios matter).
        determined: (m,) rows rigid-body dynamics determine (default: those with no weight in N); their values are
            kept bit for bit.
        offset: (W,) how far each wheel is raised against the chassis' rigid fit [m] (a prestress: a wheel on a
            block of height h_i is compressed by h_i more); the complementary energy is then
            :math:`\\sum_i n_i^2 / (2k_i) - n_i h_i` (the loads of finite stiffnesses, no longer a rigid limit).
            Default: none.

    Returns:
        The :class:`RigidLimit`.
    """
    lam = np.asarray(lam, float)
    m, d = N.shape
    if determined is None:
        determined = np.linalg.norm(N, axis=1) <= 1e-8 if d else np.ones(m, bool)
    if d == 0 or C.shape[0] == 0:
        return RigidLimit(lam.copy(), np.zeros(m, bool), N[:, :0] if d else np.zeros((m, 0)), [])
    P = C @ N  # (W, d): how each direction moves the normal loads
    _, s, Vt = np.linalg.svd(P, full_matrices=True)
    p = int(np.sum(s > RANK_TOL))
    Vn, Vo = Vt[:p].T, Vt[p:].T
    opened = N @ Vo
    if p == 0:
        return RigidLimit(lam.copy(), np.zeros(m, bool), opened, [])
    k = np.asarray(k, float)
    shift = np.zeros(len(k)) if offset is None else k * np.asarray(offset, float)
    y, unloaded, feasible = _loads(C @ lam - shift, P @ Vn, k, -shift)
    out = lam + N @ (Vn @ y)
    if opened.shape[1]:
        out -= opened @ (opened.T @ out)  # minimum-norm along what stays open (moves no normal load)
    out[determined] = lam[determined]
    fixed = ~determined & (np.linalg.norm(opened, axis=1) <= 1e-8)
    return RigidLimit(out, fixed, opened, unloaded, feasible)


def _loads(n0: np.ndarray, G: np.ndarray, k: np.ndarray, low: np.ndarray | None = None
           ) -> tuple[np.ndarray, list[int], bool]:
    """``(y, unloaded, feasible)``: y minimising :math:`\\sum_i (n_0 + G y)_i^2 / k_i` subject to
    :math:`n_0 + G y \\ge l` (G full column rank p; l = ``low``, default 0): the equality solution where it
    holds, else Lawson & Hanson's least-distance program by NNLS (see the module)."""
    low = np.zeros(len(n0)) if low is None else low
    r = 1.0 / np.sqrt(k)
    Wm, w0 = G * r[:, None], n0 * r
    Q, R = np.linalg.qr(Wm)  # Wm = Q R, R (p, p) invertible
    c = Q.T @ w0
    y = -np.linalg.solve(R, c)  # the compatible loads n = K J (J^T K J)^-1 W
    n = n0 + G @ y
    scale = max(float(np.max(np.abs(n0), initial=0.0)), float(np.max(np.abs(n), initial=0.0)), 1e-300)
    if np.all(n - low >= -PULL_TOL * scale):
        return y, [], True
    from scipy.optimize import nnls

    # x = R y + c (so that |Wm y + w0|^2 = |x|^2 + const); n >= 0  <=>  E x >= h
    E = np.linalg.solve(R.T, G.T).T  # G R^-1
    h = E @ c - n0 + low
    p = G.shape[1]
    Ematrix = np.vstack([E.T, h[None, :]])  # (p + 1, W)
    target = np.zeros(p + 1)
    target[p] = 1.0
    u, _ = nnls(Ematrix, target, maxiter=50 * (len(n0) + p + 1))
    res = Ematrix @ u - target
    if abs(res[p]) <= 1e-12 or np.linalg.norm(res) <= 1e-12:  # no x with E x >= h: every split pulls somewhere
        return y, [int(i) for i in np.flatnonzero(n < low)], False
    x = -res[:p] / res[p]
    y = np.linalg.solve(R, x - c)
    n = n0 + G @ y
    return y, [int(i) for i in np.flatnonzero(n - low <= PULL_TOL * scale)], True


def split_many(lam: np.ndarray, N: np.ndarray, C: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                                                        np.ndarray, np.ndarray]:
    """:func:`split` of G samples with the same number d of undetermined combinations, vectorised where the
    compatible loads pull on no wheel (the common case), sample by sample elsewhere.

    Args:
        lam: (G, m) multipliers (the minimum-norm ones).
        N: (G, m, d) orthonormal null spaces of :math:`A^T`.
        C: (W, m) the wheels' normal maps.
        k: (W,) the normal stiffnesses [N/m].

    Returns:
        ``(lam, open, fixed, count)``: (G, m) the rigid limit's multipliers, (G, m, d) the open directions (the
        first ``count`` columns; zero columns after them) and (G, m) the rows it fixes, (G,) how many stay open.
    """
    G, m, d = N.shape
    lam = np.array(lam, float)
    opened = np.zeros_like(N)
    fixed = np.zeros((G, m), bool)
    count = np.full(G, d, int)
    if d == 0 or C.shape[0] == 0 or G == 0:
        return lam, N.copy(), fixed, count
    determined = np.linalg.norm(N, axis=2) <= 1e-8
    P = np.einsum("wm,gmd->gwd", C, N)
    _, s, Vt = np.linalg.svd(P, full_matrices=True)
    p = np.sum(s > RANK_TOL, axis=1)
    r = 1.0 / np.sqrt(np.asarray(k, float))
    slow = []
    for pv in np.unique(p):
        sel = np.flatnonzero(p == pv)
        Vn = np.swapaxes(Vt[sel, :pv, :], 1, 2)  # (S, d, p)
        Vo = np.swapaxes(Vt[sel, pv:, :], 1, 2)
        op = np.einsum("gmd,gde->gme", N[sel], Vo)
        opened[sel, :, :d - pv] = op
        count[sel] = d - pv
        if pv == 0:
            continue
        Gm = np.einsum("gwd,gdp->gwp", P[sel], Vn)
        n0 = np.einsum("wm,gm->gw", C, lam[sel])
        Wm, w0 = Gm * r[None, :, None], n0 * r[None, :]
        with np.errstate(all="ignore"):
            y = -np.linalg.solve(np.einsum("gwp,gwq->gpq", Wm, Wm), np.einsum("gwp,gw->gp", Wm, w0)[:, :, None])[
                :, :, 0]
            n = n0 + np.einsum("gwp,gp->gw", Gm, y)
            scale = np.maximum(np.max(np.abs(n0), axis=1), np.max(np.abs(n), axis=1))
            good = np.all(n >= -PULL_TOL * scale[:, None], axis=1) & np.all(np.isfinite(y), axis=1)
        out = lam[sel] + np.einsum("gmd,gdp,gp->gm", N[sel], Vn, y)
        out -= np.einsum("gme,gje,gj->gm", op, op, out)
        det = determined[sel]
        out[det] = lam[sel][det]
        fixed[sel] = ~det & (np.linalg.norm(op, axis=2) <= 1e-8)
        lam[sel[good]] = out[good]
        slow += list(sel[~good])
    for g in slow:  # a wheel would pull: the least-distance program, one sample at a time
        res = split(lam[g], N[g], C, k, determined[g])
        lam[g], fixed[g] = res.lam, res.fixed
        opened[g] = 0.0
        opened[g, :, :res.open.shape[1]] = res.open
        count[g] = res.open.shape[1]
    return lam, opened, fixed, count


__all__ = ["RigidLimit", "split", "split_many", "normal_map", "MODEL"]


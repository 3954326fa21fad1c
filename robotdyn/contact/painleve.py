"""The Painlevé check of sliding wheels: is the contact problem's solution unique and consistent at this state?

With the friction of a sliding wheel following :math:`-\\mu N \\hat s` (the friction law's :math:`c(s)`, fixed by the
current slip), the separation accelerations :math:`a_n` of the sliding wheels' contacts depend on their normal loads
N through the effective normal matrix (the Delassus matrix of the normal rows with friction included):

.. math:: a_n = a_{n,0} + D N, \\qquad D = A_n W \\Big(A_n^T - \\sum_i J_{t,i}^T c_i e_i^T\\Big),

W the inverse inertia constrained by every other row (Pfeiffer and Glocker, *Multibody Dynamics with Unilateral
Contacts*, 1996, ch. 7; Stewart, SIAM Review 42, 2000, sec. 3). The contact complementarity problem
(:math:`a_n \\ge 0, N \\ge 0, a_n^T N = 0`) has one solution for every :math:`a_{n,0}` iff D is a P-matrix (all
principal minors positive); otherwise, at the same state, it has none or two: the Painlevé paradox (a single
wheel: :math:`D \\le 0`, its friction presses it into the ground more than its load lifts it).
:func:`robotdyn.contact.sliding.forward` solves the equality system (every wheel loaded); where D is no P-matrix it
refuses here instead of returning one of the answers.

Computed without W, from the coupled system K already factorised (:func:`robotdyn.contact.sliding.forward`'s
:math:`K x = b`, x = (nudot, lambda)): imposing separation accelerations :math:`\\epsilon` on the sliding wheels'
normal rows moves the accelerations by :math:`Z\\epsilon` (any Z with :math:`A_R Z = E`, E selecting those rows),
so the loads by :math:`E^{-1}\\epsilon` with

.. math:: D^{-1} = -\\big[K^{-1} M Z\\big]_{\\lambda_n}

(rows of the sliding wheels' loads in x), and D by inverting that W x W matrix. The principal minor of D on a set
J of wheels is the contact problem with the other sliding wheels' loads at zero; a single wheel's :math:`D_{jj}`
is its effective normal coefficient then. An applied force f moves the loads by :math:`-D^{-1} A_n W f`, so the
friction columns :math:`f = J_{t,j}^T c_j` give the friction's part of D, :math:`F = -D\\,[K^{-1} U]_{\\lambda_n}`
(U those columns), and :math:`D = D^0 - F` with :math:`D^0` the frictionless (positive definite) matrix. Column j of
F scales with wheel j's mu (where its law is proportional to mu), so :math:`D_{jj}` vanishes at the threshold
:math:`\\mu_P = \\mu_j D^0_{jj}/F_{jj}`.

On a statically indeterminate chassis (:func:`robotdyn.contact.sliding_rigid_limit.coupled`) the sliding wheels' separations
are restricted to those the rigid rows allow (an orthonormal basis V): the check holds for :math:`V^T D^{-1} V`,
and where one direction fails, the threshold is where :math:`\\det K` vanishes as the wheels' mu scale together:
:math:`\\det(I - (1 - t) Q)`, :math:`Q = [K^{-1} U]_{\\lambda_n}` (Sherman and Morrison).

The compiled twin is robotdyn/kernels/painleve.hpp (the same steps, the same order; the same verdict and message).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SingularConstraintError


def first_violation(E: np.ndarray) -> tuple[int, ...] | None:
    """The first principal minor of E that is not positive, or ``None`` where E is a P-matrix (all are positive).

    A positive definite symmetric part settles it at once (then every principal minor is positive); otherwise the
    minors are tried by size, and within a size in increasing order of their bit mask (bit i: index i), the order
    of the compiled twin.

    Args:
        E: A square matrix (W, W) (the effective normal matrix D).

    Returns:
        The indices of the first minor <= 0 (sorted), or ``None``.
    """
    w = E.shape[0]
    try:
        np.linalg.cholesky(0.5 * (E + E.T))
        return None
    except np.linalg.LinAlgError:
        pass
    masks = sorted(range(1, 1 << w), key=lambda m: (bin(m).count("1"), m))
    for mask in masks:
        idx = [i for i in range(w) if mask >> i & 1]
        if not np.linalg.det(E[np.ix_(idx, idx)]) > 0.0:  # NaN too
            return tuple(idx)
    return None


def friction_mu(wheel) -> float | None:
    """A sliding wheel's friction coefficient mu (its law's, or a stick-slip wheel's own), ``None`` without one.

    Args:
        wheel: The sliding wheel.

    Returns:
        mu [-] or ``None``.
    """
    law = getattr(wheel, "law", None)
    mu = getattr(law, "mu", None) if law is not None else getattr(wheel, "mu", None)
    return None if mu is None else float(mu)


def scales_with_mu(wheel, slip: np.ndarray) -> float | None:
    """A sliding wheel's friction coefficient mu where its law's :math:`c(s)` is proportional to it at this slip
    (Coulomb, regularised or exact; a linear tyre once saturated), else ``None`` (no threshold in mu exists).

    Args:
        wheel: The sliding wheel (a slipping wheel with a ``law``, or a stick-slip wheel with ``mu``).
        slip: Its slip velocity (2,) [m/s] in (t1, t2).

    Returns:
        mu [-] or ``None``.
    """
    law = getattr(wheel, "law", None)
    mu = friction_mu(wheel)
    if mu is None or not math.isfinite(mu):
        return None
    stiffness = getattr(law, "stiffness", None)
    if stiffness is not None:  # a linear tyre: proportional to mu only in its saturated regime
        s = np.asarray(slip, float) * getattr(wheel, "_free", np.ones(2))
        if float(np.hypot(s[0], s[1])) * stiffness <= mu:
            return None
    return float(mu)


def threshold(d0: float, f: float, mu: float | None) -> float | None:
    """The Painlevé threshold of one wheel j, :math:`\\mu_P = \\mu_j t^*`: its coefficient
    :math:`D_{jj}(t) = D^0_{jj} - t F_{jj}` vanishes at :math:`t^* = D^0_{jj}/F_{jj}` (see the module), where that lies
    in (0, 1).

    Args:
        d0: :math:`D^0_{jj}`, its coefficient without its friction.
        f: :math:`F_{jj}`, its friction's part at the current mu.
        mu: The wheel's friction coefficient (:func:`scales_with_mu`) or ``None``.

    Returns:
        mu_P [-], or ``None``.
    """
    if mu is None or not f != 0.0:
        return None
    t = d0 / f
    return mu * t if math.isfinite(t) and 0.0 < t < 1.0 else None


def check(K: np.ndarray, rows: np.ndarray, MZ: np.ndarray, wheels: list, slip: np.ndarray, U: np.ndarray,
          basis: np.ndarray | None = None) -> None:
    """Refuse a state whose sliding wheels make the contact problem a Painlevé case (see the module).

    Args:
        K: The coupled system's matrix (square), regular.
        rows: Positions in K's unknowns of the sliding wheels' normal loads (W,).
        MZ: :math:`M Z` stacked with zeros to K's size (K.shape[0], W): the generalised forces of unit separation
            accelerations of the sliding wheels' normal rows.
        wheels: The sliding wheels (W).
        slip: Their slip velocities (W, 2) [m/s].
        U: Their friction columns :math:`J_{t,j}^T c_j` stacked with zeros to K's size (K.shape[0], W).
        basis: Where the sliding wheels' normal rows are redundant among the rows (a statically indeterminate
            chassis), an orthonormal basis (W, r) of the separation accelerations the rigid rows allow; the check
            then holds on that subspace (default ``None``: every direction).

    Raises:
        SingularConstraintError: D is no P-matrix: one line naming the wheel(s) of its first minor that is not
            positive, their mu and, for one wheel (or one direction), the threshold mu_P.
    """
    E = -np.linalg.solve(K, MZ)[rows]
    if basis is not None:
        E = basis.T @ E @ basis
    try:
        D = np.linalg.inv(E)
    except np.linalg.LinAlgError:
        D = np.full_like(E, np.nan)
    bad = first_violation(D)
    if bad is None:
        return
    mu_p = None
    if basis is None:
        involved = list(bad)
        if len(bad) == 1:
            j = bad[0]
            F = -D @ np.linalg.solve(K, U)[rows]  # the friction's part of D (its columns scale with each mu)
            mu_p = threshold(float(D[j, j] + F[j, j]), float(F[j, j]), scales_with_mu(wheels[j], slip[j]))
    else:  # a subspace of the loads: the joint threshold of its wheels where one direction fails (Sherman-Morrison)
        involved = sorted({i for j in bad for i in np.flatnonzero(np.abs(basis[:, j]) > 1e-9)})
        mus = [scales_with_mu(wheels[i], slip[i]) for i in involved]
        if len(bad) == 1 and all(m is not None and m == mus[0] for m in mus):
            Q = np.linalg.solve(K, U[:, involved])[rows[involved]]
            roots = [1.0 - 1.0 / e.real for e in np.linalg.eigvals(Q) if abs(e.imag) <= 1e-9 * abs(e) and e != 0]
            inside = [t for t in roots if math.isfinite(t) and 0.0 < t < 1.0]
            mu_p = mus[0] * inside[0] if len(inside) == 1 else None
    lifted = [w for i, w in enumerate(wheels) if i not in involved] if basis is None else []
    raise painleve_sign_error([wheels[i] for i in involved], mu_p, lifted)


def painleve_sign_error(wheels: list, mu_p: float | None, lifted: list = ()) -> SingularConstraintError:
    """The error of a Painlevé case (D no P-matrix), the same on every engine.

    Args:
        wheels: The sliding wheels of the first minor of D that is not positive.
        mu_p: The threshold mu_P (one wheel or one direction), or ``None``.
        lifted: The other sliding wheels (that minor is the contact problem with their loads at zero).

    Returns:
        The :class:`~robotdyn.errors.SingularConstraintError` to raise (not raised here).
    """
    names = ", ".join(w.name for w in wheels)
    mus = [friction_mu(w) for w in wheels]
    mu = ", ".join("-" if m is None else f"{m:g}" for m in (mus[:1] if len(set(mus)) == 1 else mus))
    one = len(wheels) == 1
    limit = f"; mu_P = {mu_p:.6g} for this sliding direction" if mu_p is not None else ""
    mode = f" with the loads of {', '.join(w.name for w in lifted)} at zero" if lifted else ""
    what = "its friction presses it into the ground more than its load lifts it" if one else \
        "their friction presses them into the ground more than their loads lift them"
    return SingularConstraintError(
        f"sliding wheel{'' if one else 's'} {names} (mu = {mu}): Painleve paradox{mode}, {what} (effective normal "
        f"coefficient not positive: the accelerations and loads have no or two solutions){limit}; expected a "
        "smaller mu, another friction law or compliant wheels", float("nan"))

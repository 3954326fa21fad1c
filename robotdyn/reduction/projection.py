"""Projection of the constraint system onto independent velocities.

Given stacked rows :math:`A(q) v = 0` (m x n, possibly rank-deficient) and a choice of independent velocities
:math:`\\nu = v_{\\text{ind}}`, build :math:`S(q)` with :math:`v = S\\nu` and :math:`AS = 0`:
:math:`S = P\\,[I;\\; -A_d^{-1} A_i]` after removing redundant rows with a rank-revealing QR (never inverting a
singular block). The mobility is :math:`n - \\operatorname{rank} A`.

Time derivative: from :math:`\\dot A S + A \\dot S = 0` with a zero independent block,
:math:`\\dot S_d = -A_d^{-1} \\dot A S`, so :math:`w = \\dot S \\nu` solves :math:`A w = -\\dot A v`
(the acceleration offset :math:`a = S\\dot\\nu + w`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import SingularConstraintError

_LAPACK = None


def _lapack():
    """scipy's LAPACK wrappers (``dgeqp3``, ``dgesv``), loaded on first use: the very functions of
    ``scipy.linalg.lapack``, so the same numbers and the same pivots.

    ``import scipy.linalg.lapack`` costs about 0.3 s (the whole of ``scipy.linalg`` and scipy's array-API layer, a
    large part of ``robotdyn dump``'s start-up); the compiled module behind it, ``scipy.linalg._flapack`` (an f2py
    extension needing only numpy), loads from its file in ~5 ms. It is not left in ``sys.modules`` (its package is
    not imported): a later ``import scipy.linalg`` gets its own module object holding the same functions. Where it
    cannot be loaded alone (another scipy layout, a platform whose DLLs scipy's ``__init__`` locates first),
    ``scipy.linalg.lapack`` is imported as before.
    """
    global _LAPACK
    if _LAPACK is None:
        _LAPACK = _flapack()
    return _LAPACK


def _flapack():
    """``scipy.linalg._flapack`` without importing the ``scipy`` and ``scipy.linalg`` packages (see
    :func:`_lapack`); ``scipy.linalg.lapack`` if that fails."""
    import sys

    mod = sys.modules.get("scipy.linalg._flapack")
    if mod is None:
        try:
            import os
            from importlib.machinery import EXTENSION_SUFFIXES
            from importlib.util import find_spec, module_from_spec, spec_from_file_location

            spec = find_spec("scipy")  # locates the package without importing it
            folder = os.path.join(spec.submodule_search_locations[0], "linalg")
            path = next(p for p in (os.path.join(folder, "_flapack" + s) for s in EXTENSION_SUFFIXES)
                        if os.path.isfile(p))
            spec = spec_from_file_location("scipy.linalg._flapack", path)
            mod = module_from_spec(spec)
            spec.loader.exec_module(mod)
            if sys.modules.get(spec.name) is mod:  # Python registers it (single-phase init) without its package:
                del sys.modules[spec.name]  # a later import of scipy.linalg loads it anew (the same functions)
        except (ImportError, OSError, AttributeError, TypeError, IndexError, StopIteration):
            mod = None
    if mod is None or not all(hasattr(mod, f) for f in ("dgeqp3", "dgesv")):
        import scipy.linalg.lapack

        mod = scipy.linalg.lapack
    return mod


RANK_TOL = 1e-9
"""Relative tolerance on QR diagonal entries below which rows are counted as redundant."""
MAX_CONDITION = 1e10
"""Condition number of the dependent block above which the choice of independent velocities is refused."""


_LWORK: dict[tuple[int, int], int] = {}


def _pivoted_qr(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Diagonal of R and the column permutation of the QR decomposition with column pivoting of ``a``.

    The LAPACK call ``scipy.linalg.qr(a, pivoting=True)`` makes (``?geqp3`` with the optimal workspace, queried
    once per shape here), without its wrapper's overhead: the same numbers."""
    if a.size == 0 or not np.all(np.isfinite(a)):  # scipy's own checks and messages
        import scipy.linalg

        _, R, piv = scipy.linalg.qr(a, mode="economic", pivoting=True)
        return np.diag(R), piv
    a = np.asarray(a, dtype=float)
    lwork = _LWORK.get(a.shape)
    if lwork is None:
        lwork = _LWORK[a.shape] = int(_lapack().dgeqp3(a, lwork=-1)[-2][0].real)
    qr, jpvt, _, _, info = _lapack().dgeqp3(a, lwork=lwork)
    if info < 0:
        raise ValueError(f"illegal value in {-info}th argument of internal geqp3")
    return np.diag(qr).copy(), jpvt - 1


def solve(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """:math:`A^{-1}B` for a small square A by LAPACK ``dgesv``: the routine ``numpy.linalg.solve`` and
    ``numpy.linalg.inv`` (B = I) call, with the same numbers, without their wrapper's overhead.

    Args:
        A: A small square matrix (m, m).
        B: The right-hand side (m,) or (m, p).

    Returns:
        :math:`X = A^{-1}B`, shaped like B.

    Raises:
        numpy.linalg.LinAlgError: A is exactly singular.
    """
    _, _, X, info = (_LAPACK or _lapack()).dgesv(A, B)
    if info != 0:
        raise np.linalg.LinAlgError("Singular matrix" if info > 0 else f"illegal value in argument {-info} of dgesv")
    return X


def inverse_and_condition(A: np.ndarray) -> tuple[np.ndarray | None, float]:
    """:math:`A^{-1}` (``None`` if A is exactly singular) and the 1-norm condition number
    :math:`\\|A\\|_1 \\|A^{-1}\\|_1` (``inf`` if singular) of a small square matrix.

    Args:
        A: A small square matrix.

    Returns:
        ``(inverse, condition)``: :math:`A^{-1}` or ``None``, and the condition number (``inf`` if singular).
    """
    try:
        inv = solve(A, np.eye(len(A)))
    except np.linalg.LinAlgError:
        return None, float("inf")
    return inv, float(abs(A).sum(axis=0).max() * abs(inv).sum(axis=0).max())


def independent_rows(A: np.ndarray, tol: float = RANK_TOL) -> np.ndarray:
    """Indices of a maximal set of linearly independent rows of ``A`` (rank-revealing QR with pivoting).

    Args:
        A: The constraint Jacobian (m, n).
        tol: Relative rank tolerance: a pivot counts when above ``tol`` times the largest (at least 1).

    Returns:
        The row indices, sorted (int array, possibly empty).
    """
    if A.shape[0] == 0:
        return np.zeros(0, dtype=int)
    R_diag, piv = _pivoted_qr(A.T)
    diag = np.abs(R_diag)
    if diag.size == 0 or diag[0] == 0.0:
        return np.zeros(0, dtype=int)
    rank = int(np.sum(diag > tol * max(diag[0], 1.0)))
    return np.sort(piv[:rank])


def auto_independent(A: np.ndarray, tol: float = RANK_TOL) -> np.ndarray:
    """A well-conditioned choice of independent velocity indices (the columns QR pivoting chooses last).

    Args:
        A: The constraint Jacobian (m, n).
        tol: Relative rank tolerance (:func:`independent_rows`).

    Returns:
        The independent velocity indices (k,), sorted (int array).
    """
    n = A.shape[1]
    rows = independent_rows(A, tol)
    if rows.size == 0:
        return np.arange(n)
    _, piv = _pivoted_qr(A[rows])
    return np.sort(piv[rows.size :])


@dataclass
class Projection:
    """:math:`S(q)` and the data to differentiate it.

    Attributes:
        S: (n, k) with :math:`v = S\\nu`.
        independent: Indices of :math:`\\nu` in :math:`v` (k,).
        dependent: The other indices.
        rows: Indices of the independent constraint rows used.
        condition: 1-norm condition number of the dependent block :math:`A_d` (1 without constraints).
        Ad_inv: :math:`A_d^{-1}` (rows used x dependent), ``None`` without constraints.
    """

    S: np.ndarray
    independent: np.ndarray
    dependent: np.ndarray
    rows: np.ndarray
    condition: float
    Ad_inv: np.ndarray | None = None
    _layout: tuple | None = field(default=None, repr=False, compare=False)

    @property
    def mobility(self) -> int:
        """Number of independent velocities :math:`k = n - \\operatorname{rank} A`."""
        return int(self.S.shape[1])

    def Sdot(self, Adot: np.ndarray) -> np.ndarray:
        """:math:`\\dot S` (n, k) given :math:`\\dot A` (all rows) along the motion.

        Args:
            Adot: dA/dt of all rows (m, n) along the motion.

        Returns:
            :math:`\\dot S` (n, k).
        """
        out = np.zeros_like(self.S)
        if self.rows.size:
            out[self.dependent] = -self.Ad_inv @ (Adot[self.rows] @ self.S)
        return out

    def offset(self, drift: np.ndarray) -> np.ndarray:
        """:math:`w` with :math:`A w = -\\text{drift}` and zero independent part (drift = :math:`\\dot A v`).

        Args:
            drift: dA/dt v of all rows (m,) [m/s^2 or rad/s^2].

        Returns:
            w (n,), in the model's velocity order.
        """
        w = np.zeros(self.S.shape[0])
        if self.rows.size:
            w[self.dependent] = -self.Ad_inv @ drift[self.rows]
        return w


def _others(n: int, indices: np.ndarray) -> np.ndarray:
    """``np.setdiff1d(np.arange(n), indices)`` (the indices below n that ``indices`` does not name, ascending),
    without ``np.unique``, whose first call imports ``numpy.ma`` (~50 ms of a command's start-up)."""
    keep = np.ones(n, dtype=bool)
    keep[indices[(indices >= 0) & (indices < n)]] = False
    return np.flatnonzero(keep)


def _layout(n: int, independent: np.ndarray, dependent: np.ndarray, rows: np.ndarray) -> tuple:
    """Index helpers of a choice of independent velocities and rows (reused by projections built from a hint):
    S with its identity block set, and the index tuples of the dependent and independent blocks of A."""
    S0 = np.zeros((n, n - rows.size))
    S0[independent, np.arange(independent.size)] = 1.0
    return S0, np.ix_(rows, dependent), np.ix_(rows, independent)


def _build(A, independent, dependent, rows, names, layout: tuple | None = None) -> Projection:
    n = A.shape[1]
    if layout is None:
        layout = _layout(n, independent, dependent, rows)
    S0, ix_dep, ix_ind = layout
    S = S0.copy()
    if rows.size == 0:
        return Projection(S, independent, dependent, rows, 1.0, None, layout)
    Ad_inv, cond = inverse_and_condition(A[ix_dep])
    if not np.isfinite(cond) or cond > MAX_CONDITION:
        raise SingularConstraintError(
            f"the dependent velocities ({', '.join(names[i] for i in dependent)}) cannot be solved from the "
            f"independent ones here: constraint block singular (condition number {cond:.3g}); choose other "
            "independent velocities or move away from this singular configuration",
            condition=cond,
        )
    S[dependent] = -Ad_inv @ A[ix_ind]
    return Projection(S, independent, dependent, rows, cond, Ad_inv, layout)


def project(
    A: np.ndarray,
    independent: np.ndarray | None = None,
    names: list[str] | None = None,
    hint: Projection | None = None,
) -> Projection:
    """Build :math:`S` for the constraint rows ``A`` and the given independent velocity indices.

    Args:
        A: Stacked constraint Jacobian (m, n).
        independent: Indices of the independent velocities; ``None`` chooses a well-conditioned set.
        names: Velocity names, used in error messages.
        hint: A projection at a nearby state: its choice of independent rows is reused when it still spans the
            row space (checked: :math:`\\|A S\\|` must vanish), which skips the rank-revealing QR.

    Returns:
        The :class:`Projection`.

    Raises:
        SingularConstraintError: The number of independent velocities does not match the mobility, or the
            dependent block is singular / ill-conditioned at this configuration.
    """
    n = A.shape[1]
    names = names or [f"v{i}" for i in range(n)]
    if hint is not None and (
        independent is None or independent is hint.independent or np.array_equal(hint.independent, independent)
    ):
        try:
            proj = _build(A, hint.independent, hint.dependent, hint.rows, names, hint._layout)
        except SingularConstraintError:
            proj = None
        scale = max(1.0, float(abs(A).max())) if A.size else 1.0
        # no independent velocity (S has no columns, e.g. every wheel of a vehicle at rest sticking): A S is empty,
        # and the hint's rows, n of them with a regular block, span every row
        if proj is not None and (A.size == 0 or proj.S.shape[1] == 0 or abs(A @ proj.S).max() <= 1e-10 * scale):
            return proj
    rows = independent_rows(A)
    if independent is None:
        independent = auto_independent(A)
    independent = np.asarray(independent, dtype=int)
    dependent = _others(n, independent)
    if dependent.size != rows.size:
        exc = SingularConstraintError(
            f"{independent.size} independent velocities chosen ({', '.join(names[i] for i in independent)}) but the "
            f"constraints leave {n - rows.size} (n = {n}, rank A = {rows.size}); expected exactly the mobility"
        )
        exc.mobility = n - rows.size  # (a run that reaches here has changed mobility: simulation.compiled_engine.at_time)
        raise exc
    return _build(A, independent, dependent, rows, names)

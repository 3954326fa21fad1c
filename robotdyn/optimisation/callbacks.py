"""Python functions as CasADi constraint functions with a sparse analytic Jacobian (the plumbing of every NLP here).

IPOPT (through CasADi's ``nlpsol``) sees the robot's model as one CasADi ``Callback`` computing all constraint
values g(z) at once, whose Jacobian is another ``Callback`` with a declared sparsity pattern, filled by the
caller's own derivatives (analytic, or finite differences for comparison): CasADi's automatic differentiation is
never used through Pinocchio. Used by :mod:`robotdyn.optimisation.trajectory` (collocation defects) and
:mod:`robotdyn.optimisation.posture` (contact forces at a posture).

Exact zeros: the Jacobian is declared in dense blocks, and many of its entries are zero in exact arithmetic but come
out of the derivative kernels as rounding residues (1e-20 to 1e-13 of their row's largest entry on the linkage
rover). IPOPT's linear solver MUMPS chooses a weighted matching and scaling of the KKT matrix from the entries'
magnitudes (MC64, IPOPT's default ``mumps_permuting_scaling`` 5 and ``mumps_scaling`` 77): a residue taken into
the matching is scaled up like a genuine entry and the factorization loses its digits. Measured on the rover's
traction-limited solve (:mod:`robotdyn.robots.linkage_suspension.traction_path`, started from the minimum-effort
motion with its torques perturbed): with the Jacobian dense to CasADi, residual ratios of 1e52, least-squares
multipliers (IPOPT's ``recalc_y`` in its limited-memory mode) of 1e22, and 16 of 32 starts at 1e-8 ended in
``Invalid_Number_Detected``; with the pattern declared, a residual ratio of 1e6 at the first step from a start
at 1e-2, and 0 of 16 such starts converged (14 of 16 at 1e-4). So every entry at most :data:`ROUNDING` times its
row's largest is passed as an exact zero (the derivatives are computed no better than that: the compiled and the
Python kernels agree to 1e-12); then 32 of 32 at 1e-8 and 1e-6 and 16 of 16 at 1e-4 and 1e-2 converge to the same
cost (bench/traction_path_starts.py); the largest residual ratio before refinement, from a start at 1e-8,
fell from 0.3 to 5e-8.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

ROUNDING = 1e-12
"""Jacobian entries at most this fraction of their row's largest magnitude are passed to IPOPT as exact zeros (the
module docstring: rounding residues of exact zeros mislead MUMPS's scaling)."""


def _casadi():
    from ..errors import InputError

    try:
        import casadi
    except ImportError as exc:  # pragma: no cover - the test extra installs it
        raise InputError("optimisation needs CasADi (pip install casadi, or the `test` extra)") from exc
    return casadi


def sparse_callback(name: str, nz: int, ng: int, values: Callable[[np.ndarray], np.ndarray],
                    jacobian_values: Callable[[np.ndarray], np.ndarray], rows: np.ndarray, cols: np.ndarray,
                    keep: list):
    """A CasADi function z -> g(z) whose Jacobian is ``jacobian_values`` on the pattern (rows, cols).

    Args:
        name: The function's name (in CasADi's messages).
        nz: Number of decision variables.
        ng: Number of constraint values.
        values: z (nz,) -> g(z) (ng,).
        jacobian_values: z (nz,) -> the Jacobian's values (nnz,) at (rows[i], cols[i]), in that order.
        rows: Row indices (nnz,) of the structural nonzeros.
        cols: Column indices (nnz,).
        keep: A list that keeps the callback objects alive while the solver uses them (CasADi holds no Python
            reference to them): the caller keeps it as long as the solver.

    Returns:
        The CasADi ``Callback`` (call it on an ``MX`` symbol to build the NLP's constraints).
    """
    ca = _casadi()
    rows, cols = np.asarray(rows, int), np.asarray(cols, int)
    order = np.lexsort((rows, cols))  # column-major: CasADi's compressed-column storage
    colind = np.searchsorted(cols[order], np.arange(nz + 1))
    sparsity = ca.Sparsity(ng, nz, colind.tolist(), rows[order].tolist())

    class Jac(ca.Callback):
        def __init__(self, name, opts):
            ca.Callback.__init__(self)
            self.construct(name, opts)

        def get_n_in(self):
            return 2

        def get_n_out(self):
            return 1

        def get_sparsity_in(self, i):
            return ca.Sparsity.dense(nz, 1) if i == 0 else ca.Sparsity.dense(ng, 1)

        def get_sparsity_out(self, i):
            return sparsity

        def has_eval_buffer(self):  # the raw nonzero buffers: no DM built per call
            return True

        def eval_buffer(self, arg, res):
            z = np.frombuffer(arg[0], dtype=np.float64).copy()
            try:
                vals = exact_zeros(jacobian_values(z), rows, ng)
            except Exception as exc:  # noqa: BLE001 - see _refused
                vals = _refused(keep, exc, len(order))
            np.frombuffer(res[0], dtype=np.float64)[:] = vals[order]  # compressed-column order
            return 0

    class Values(ca.Callback):
        def __init__(self, name, opts):
            ca.Callback.__init__(self)
            self.construct(name, opts)

        def get_n_in(self):
            return 1

        def get_n_out(self):
            return 1

        def get_sparsity_in(self, i):
            return ca.Sparsity.dense(nz, 1)

        def get_sparsity_out(self, i):
            return ca.Sparsity.dense(ng, 1)

        def has_eval_buffer(self):
            return True

        def eval_buffer(self, arg, res):
            z = np.frombuffer(arg[0], dtype=np.float64).copy()
            try:
                g = values(z)
            except Exception as exc:  # noqa: BLE001 - see _refused
                g = _refused(keep, exc, ng)
            np.frombuffer(res[0], dtype=np.float64)[:] = g
            return 0

        def has_jac_sparsity(self, oind, iind):  # IPOPT sees the pattern (without it: a dense Jacobian and KKT)
            return True

        def get_jac_sparsity(self, oind, iind, symmetric):
            return sparsity

        def has_jacobian(self):
            return True

        def get_jacobian(self, name, inames, onames, opts):
            keep.append(Jac(name, opts))
            return keep[-1]

    keep.append(Values(name, {"enable_fd": False}))
    return keep[-1]


def exact_zeros(values: np.ndarray, rows: np.ndarray, ng: int) -> np.ndarray:
    """A sparse Jacobian's values with every entry of magnitude at most :data:`ROUNDING` times its row's largest
    set to exactly zero (rounding residues of exact zeros; the module docstring says why). NaN stays NaN.

    Args:
        values: The Jacobian's values (nnz,) at its structural nonzeros.
        rows: Their row indices (nnz,), in 0 .. ng - 1.
        ng: Number of rows.

    Returns:
        A new array (nnz,).
    """
    values = np.asarray(values, float)
    size = np.abs(values)
    largest = np.zeros(ng)
    np.maximum.at(largest, rows, size)
    out = values.copy()
    out[size <= ROUNDING * largest[rows]] = 0.0
    return out


class Refusal:
    """The first error a callback raised at a point IPOPT tried (kept in the callbacks' ``keep`` list).

    Args:
        exc: The exception the model raised.
    """

    def __init__(self, exc: Exception):
        self.exc = exc


def _refused(keep: list, exc: Exception, size: int) -> np.ndarray:
    """NaN values for a point where the model raised (e.g. a trial point beyond the joint ranges, or where the
    constraints are singular): IPOPT backtracks from NaN constraint values, or stops with Invalid_Number_Detected,
    instead of CasADi printing the Python traceback and its own dump of the point. The first error is kept in
    ``keep`` (see :func:`refusal`)."""
    if refusal(keep) is None:
        keep.append(Refusal(exc))
    return np.full(size, np.nan)


def refusal(keep: list) -> str | None:
    """The first error a callback of ``keep`` raised during the solve, as one line (None: none raised).

    Args:
        keep: The list given to :func:`sparse_callback`.

    Returns:
        ``"ErrorType: message"`` (its first line), or None.
    """
    for item in keep:
        if isinstance(item, Refusal):
            return f"{type(item.exc).__name__}: {str(item.exc).splitlines()[0] if str(item.exc) else ''}"
    return None


__all__ = ["ROUNDING", "Refusal", "exact_zeros", "refusal", "sparse_callback"]

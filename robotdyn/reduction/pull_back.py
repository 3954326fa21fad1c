"""Pulling holonomic position residuals back onto the constraint manifold during a simulation.

The velocity constraints hold exactly along a simulation (v = S nu), but the position residuals
:math:`\\phi(q)` of holonomic rows (a wheel's normal row, loop closures, joint couplings) drift by the integrator's
error. :func:`robotdyn.simulation.engine.simulate` adds :math:`-\\alpha\\,\\delta q` to :math:`\\dot q`, with
:math:`\\delta q` the minimum-norm solution of :math:`A_h\\,\\delta q = \\phi`
(the concepts page ``docs/concepts.md``, "The projection"), so that :math:`\\dot\\phi = -\\alpha\\phi`
on every residual the model's coordinates can change.

Rows whose Jacobian has no rank relative to its scale cannot be corrected by any coordinate. The textbook case is
a wheel's normal row under a planar root (x, y, psi): the model has no vertical motion, so the row's entries are
round-off (~1e-24), and a wheel centre at r + 1e-7, or an axle at ``rpy="-1.57 0 0"`` instead of pi/2, leaves a
residual ~1e-7 that a plain least-squares solve turns into corrections ~1e16 (and the integrator stops at t = 0).
:func:`correction` therefore solves by a truncated SVD: singular values below :data:`RANK_TOL` times
:math:`\\max(\\sigma_{max}, 1)` count as zero (the rule of :func:`robotdyn.reduction.projection.independent_rows`), and
:func:`offsets` names the residuals left in their directions: constant offsets of the model, reported once rather
than chased. The compiled path gives the same minimum-norm solution in C++ (``robotdyn/kernels/pull_back.hpp``, by a complete
orthogonal decomposition, pivots below the same relative tolerance counting as zero).
"""

from __future__ import annotations

import sys

import numpy as np

from ..errors import ConstraintError, RobotDynError
from .projection import RANK_TOL

STABILISATION = 10.0
"""Default gain :math:`\\alpha` [1/s] of the pull-back (every simulation engine's ``stabilisation``)."""
OFFSET_TOL = 1e-12
"""Residuals [m or rad] in directions no coordinate can change are reported as offsets above this size."""


def _svd(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Thin SVD of A and its numerical rank (:data:`RANK_TOL` relative to :math:`\\max(\\sigma_{max}, 1)`)."""
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    rank = int(np.sum(s > RANK_TOL * max(s.max(initial=0.0), 1.0)))
    return U, s, Vt, rank


def correction(A_h: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """:math:`\\delta q = A_h^{+}\\phi` with :math:`A_h^{+}` the pseudo-inverse truncated at the rows' rank.

    Args:
        A_h: Holonomic constraint rows (m, n) at q.
        phi: Their residuals (m,) [m or rad].

    Returns:
        (n,) the smallest coordinate change that removes the correctable part of phi (to first order).
    """
    if A_h.size == 0 or not phi.any():
        return np.zeros(A_h.shape[1])
    U, s, Vt, rank = _svd(A_h)
    return Vt[:rank].T @ ((U[:, :rank].T @ phi) / s[:rank])


def position_rate(red, stabilisation: float) -> np.ndarray:
    """:math:`\\dot q = v - \\alpha A_h^+\\phi` (n,) [m/s or rad/s]: the velocity of a
    :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` ``red`` with its holonomic residuals pulled back
    at the gain ``stabilisation`` [1/s] (0: none).

    Args:
        red: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu).
        stabilisation: Gain alpha [1/s] of the pull-back of the holonomic residuals (0: none).

    Returns:
        :math:`\\dot q` (n,) [m/s or rad/s].
    """
    qdot = red.v
    rows = red.jacobian_rows
    hol = rows.holonomic
    if stabilisation and hol.any() and rows.residual[hol].any():  # a zero residual needs no correction
        qdot = qdot - stabilisation * correction(rows.A[hol], rows.residual[hol])
    return qdot


def offsets(A_h: np.ndarray, phi: np.ndarray, labels) -> dict[str, float]:
    """The residuals that no coordinate of the model can change: the part of phi outside the range of
    :math:`A_h`'s rank-r part, by row label, where it exceeds :data:`OFFSET_TOL` (empty when every residual is
    correctable).

    Args:
        A_h: Holonomic constraint rows (m, n).
        phi: Their residuals (m,).
        labels: Their names (m,).

    Returns:
        A dict of row label to residual [m or rad] (only those above the tolerance; empty if none).
    """
    if A_h.size == 0 or not phi.any():
        return {}
    U, _, _, rank = _svd(A_h)
    left = phi - U[:, :rank] @ (U[:, :rank].T @ phi)
    return {lab: float(x) for lab, x in zip(labels, left) if abs(x) > OFFSET_TOL}


def describe_offsets(found: dict[str, float]) -> str:
    """One line naming the offsets of :func:`offsets`.

    Args:
        found: Residual [m or rad] by row label (:func:`offsets`).

    Returns:
        The one-line description.
    """
    parts = ", ".join(f"{lab} {x:.3g}" for lab, x in found.items())
    return (f"holonomic residuals that no coordinate of this model can change, kept as constant offsets (not "
            f"pulled back): {parts} (m or rad; e.g. a wheel's height or axle tilt under a planar root)")


MAX_CORRECTION = 1e-3
"""Largest coordinate change [m or rad] the pull-back may ask for at the start of a simulation: above it, the
residual is correctable only through a nearly rank-deficient direction of the rows, and chasing it would drag the
model (see :func:`check_start`)."""


def check_start(A_h: np.ndarray, phi: np.ndarray, labels, stabilisation: float) -> dict[str, float]:
    """The offsets (:func:`offsets`) at the start of a simulation, after checking that the pull-back can work.

    Args:
        A_h: The holonomic rows of A (h, n).
        phi: Their residuals (h,) [m or rad].
        labels: Their labels.
        stabilisation: Gain alpha [1/s] of the pull-back of the holonomic residuals (0: none).

    Returns:
        The offsets at q0 by row label [m or rad] (empty if none).

    Raises:
        ConstraintError: With ``stabilisation`` on, removing the correctable residual would move a coordinate by
            more than :data:`MAX_CORRECTION` (rows with a tiny but nonzero rank, e.g. a planar root on a very gentle
            slope): the one-line error names the rows and what to do.
    """
    found = offsets(A_h, phi, labels)
    if stabilisation and A_h.size and phi.any():
        dq = correction(A_h, phi)
        if np.max(np.abs(dq)) > MAX_CORRECTION:
            s, rows = weakest(A_h, labels)
            raise ConstraintError(
                f"the holonomic pull-back cannot work here: rows {rows} change only through a nearly rank-deficient "
                f"direction (relative singular value {s:.3g}), so removing their residual "
                f"{np.max(np.abs(phi)):.3g} would move the coordinates by {np.max(np.abs(dq)):.3g} (m or rad); "
                "expected a q0 that satisfies them (e.g. robotdyn.constraints.posture.solve_posture), or stabilisation = 0")
    return found


def weakest(A_h: np.ndarray, labels) -> tuple[float, str]:
    """The smallest nonzero-rank singular value of :math:`A_h` relative to its scale, and the rows that weigh
    most in its direction (for the error where the pull-back cannot work: nearly rank-deficient rows).

    Args:
        A_h: The holonomic rows of A (h, n).
        labels: Their labels.

    Returns:
        ``(value, rows)``: the relative singular value (``inf`` without holonomic rows), and the heaviest rows' labels
        joined by commas.
    """
    if A_h.size == 0:
        return float("inf"), ""
    U, s, _, rank = _svd(A_h)
    if rank == 0:
        return float("inf"), ""
    u = U[:, rank - 1]
    heavy = [lab for lab, c in zip(labels, u) if abs(c) >= 0.3 * np.abs(u).max()]
    return float(s[rank - 1] / max(s[0], 1.0)), ", ".join(heavy)


def start_offsets(robot, q0: np.ndarray, stabilisation: float, rows=None) -> dict[str, float]:
    """The holonomic residuals at q0 that no coordinate can change (reported once on stderr, kept as constant
    offsets); raises where the pull-back cannot work (:func:`robotdyn.reduction.pull_back.check_start`).
    ``rows``: ``robot.rows_at(q0)``, when the caller has them.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q0: The initial configuration (n,) [m, rad].
        stabilisation: Gain alpha [1/s] of the pull-back of the holonomic residuals (0: none).
        rows: ``robot.rows_at(q0)``, when the caller has them (default ``None``: computed).

    Returns:
        The offsets by row label [m or rad] (empty if none).
    """
    rows = robot.rows_at(q0) if rows is None else rows
    hol = rows.holonomic
    found = check_start(rows.A[hol], rows.residual[hol], [lab for lab, h in zip(rows.labels, hol) if h],
                        stabilisation)
    if found:
        print(f"simulate: {describe_offsets(found)}", file=sys.stderr, flush=True)
    return found


def failure_note(robot, q: np.ndarray, stabilisation: float) -> str:
    """Where an integration failed with the pull-back on and nearly rank-deficient holonomic rows: the rows and
    their relative singular value (else empty).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: The configuration where the integration failed (n,) [m, rad].
        stabilisation: Gain alpha [1/s] of the pull-back of the holonomic residuals (0: none).

    Returns:
        The note (starting with a space), or ``""`` where it does not apply.
    """
    if not stabilisation or not np.all(np.isfinite(q)):
        return ""
    try:
        rows = robot.rows_at(q)
    except RobotDynError:  # the state is beyond the model (the integration's own error says why)
        return ""
    hol = rows.holonomic
    s, names = weakest(rows.A[hol], [lab for lab, h in zip(rows.labels, hol) if h])
    if s > 1e-6:
        return ""
    return (f" (the holonomic pull-back is ill-conditioned there: rows {names} have a relative singular value "
            f"{s:.3g}; stabilisation = 0 turns it off)")


__all__ = ["correction", "offsets", "check_start", "start_offsets", "failure_note", "MAX_CORRECTION", "describe_offsets", "weakest", "RANK_TOL", "OFFSET_TOL",
           "STABILISATION"]

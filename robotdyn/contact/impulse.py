"""Impulsive contact with a fixed, frictionless surface in minimal (e.g. operational) coordinates, and the plastic
impact that stops several velocity rows at once (:func:`plastic_impact`: wheels touching down while rolling).

With the reduced inertia :math:`M` (k x k) in velocities :math:`\\nu`, an impulse :math:`\\hat F n` along a
direction :math:`n` of generalised force (the surface normal expressed in the same coordinates, e.g.
:math:`J_c^T n_{world}` for a contact point, or a unit force through the platform centre in operational space)
changes the velocity by :math:`\\Delta\\nu = M^{-1} n \\hat F` (finite forces and velocity products do not
integrate to anything over the vanishing impact time). Newton's restitution law on the normal velocity,
:math:`n^T\\nu^+ = -e\\, n^T\\nu^-`, then gives

.. math:: \\hat F = \\frac{-(1 + e)\\, n^T \\nu^-}{n^T M^{-1} n}

(Chung, Yi, Kim, Han, eq 60, where M is the operational-space inertia I_uu*). Units: N s for a force direction
in m/s velocities.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError


@dataclass
class Impulse:
    """Result of one impact.

    Attributes:
        magnitude: :math:`\\hat F` [N s] (> 0 for an approaching motion with n pointing out of the surface).
        direction: The unit direction n used.
        delta_nu: Velocity jump :math:`M^{-1} n \\hat F`.
        nu_after: :math:`\\nu^+ = \\nu^- + \\Delta\\nu`.
        normal_before, normal_after: :math:`n^T\\nu^-` and :math:`n^T\\nu^+` (= :math:`-e\\,n^T\\nu^-`).
        effective_mass: :math:`1 / (n^T M^{-1} n)` [kg], the mass the surface feels along n.
    """

    magnitude: float
    direction: np.ndarray
    delta_nu: np.ndarray
    nu_after: np.ndarray
    normal_before: float
    normal_after: float
    effective_mass: float


def _check(M, n, e: float) -> tuple[np.ndarray, np.ndarray]:
    M = np.asarray(M, float)
    n = np.asarray(n, float)
    k = M.shape[0] if M.ndim == 2 else -1
    if M.ndim != 2 or M.shape[1] != k or not np.all(np.isfinite(M)):
        raise InputError(f"inertia matrix of shape {M.shape}; expected a finite square matrix")
    try:
        np.linalg.cholesky(0.5 * (M + M.T))
    except np.linalg.LinAlgError:
        raise InputError("inertia matrix is not positive definite (massless mechanism?); no impulse defined") from None
    if n.shape != (k,) or not np.all(np.isfinite(n)):
        raise InputError(f"impact direction has {n.size} values; expected {k} finite numbers")
    norm = float(np.linalg.norm(n))
    if norm == 0.0:
        raise InputError("impact direction is zero; expected a non-zero surface normal")
    if not (np.isfinite(e) and 0.0 <= e <= 1.0):
        raise InputError(f"coefficient of restitution e = {e}; expected 0 <= e <= 1")
    return M, n / norm


def effective_mass(M, n) -> float:
    """:math:`1/(n^T M^{-1} n)` for the unit direction :math:`n/\\|n\\|` [kg for a force direction].

    Args:
        M: Reduced inertia (k, k), symmetric positive definite.
        n: A direction of generalised force (k,) (normalised here).

    Returns:
        The effective mass [kg for a force direction in m/s velocities].
    """
    M, n = _check(M, n, 0.0)
    return float(1.0 / (n @ np.linalg.solve(M, n)))


def impact(M, n, nu, e: float) -> Impulse:
    """Impulse and velocity jump for a frictionless impact along n (normalised) with restitution e (eq 60).

    Args:
        M: Reduced inertia (k, k), symmetric positive definite.
        n: Surface normal in the coordinates of M's forces, pointing from the surface towards the robot.
        nu: Velocity just before impact (k,); it must approach the surface (n^T nu < 0).
        e: Coefficient of restitution, 0 (plastic) to 1 (elastic).

    Returns:
        An :class:`Impulse`: magnitude [N s], direction, velocity jump, velocities after, normal velocities before and
        after, effective mass [kg].

    Raises:
        InputError: Bad shapes, non-finite values, e outside [0, 1], or a velocity that does not approach.
    """
    M, n = _check(M, n, e)
    nu = np.asarray(nu, float)
    if nu.shape != n.shape or not np.all(np.isfinite(nu)):
        raise InputError(f"velocity has {nu.size} values; expected {n.size} finite numbers")
    vn = float(n @ nu)
    if vn >= 0.0:
        raise InputError(f"the velocity does not approach the surface (n . v = {vn:.6g} >= 0); no impact")
    Minv_n = np.linalg.solve(M, n)
    F = -(1.0 + e) * vn / float(n @ Minv_n)
    dnu = Minv_n * F
    after = nu + dnu
    return Impulse(F, n, dnu, after, vn, float(n @ after), float(1.0 / (n @ Minv_n)))


@dataclass
class PlasticImpulse:
    """Result of a plastic impact on several velocity rows at once (:func:`plastic_impact`).

    Attributes:
        impulse: :math:`\\hat\\Lambda` (m,) [N s for rows of point velocities], one per row (minimum-norm on
            redundant rows).
        delta_nu: Velocity jump :math:`M^{-1} G^T \\hat\\Lambda` (k,).
        nu_after: :math:`\\nu^+` (k,), with :math:`G\\nu^+ = 0`.
        rows_before: :math:`G\\nu^-` (m,).
        energy_lost: :math:`\\tfrac12\\nu^{-T} M\\nu^- - \\tfrac12\\nu^{+T} M\\nu^+ \\ge 0` [J].
        rank: The rank of :math:`G M^{-1} G^T` used.
    """

    impulse: np.ndarray
    delta_nu: np.ndarray
    nu_after: np.ndarray
    rows_before: np.ndarray
    energy_lost: float
    rank: int


def plastic_impact(M, G, nu, rcond: float = 1e-10) -> PlasticImpulse:
    """The plastic impact that stops the velocity rows :math:`G\\nu` (e.g. the slip of wheels touching down while
    rolling without slipping): the impulse :math:`G^T\\hat\\Lambda` with :math:`G\\nu^+ = 0`,

    .. math:: (G M^{-1} G^T)\\,\\hat\\Lambda = -G\\nu^-,\\qquad \\nu^+ = \\nu^- + M^{-1}G^T\\hat\\Lambda,

    the multi-row form of :func:`impact` with e = 0 (for one row along n it is that impact exactly). By
    Kelvin's theorem the energy lost is :math:`\\tfrac12 (G\\nu^-)^T (G M^{-1} G^T)^{-1} G\\nu^-` (the kinetic energy of
    the relative motion the impulse stops). Redundant rows (a rank-deficient :math:`G M^{-1} G^T`, eigenvalues below
    ``rcond`` times the largest) get the minimum-norm impulse; rows that cannot all vanish are refused.

    Args:
        M: Reduced inertia (k, k), symmetric positive definite.
        G: Rows (m, k) in the coordinates of M's velocities (m may be 0).
        nu: Velocity just before impact (k,).
        rcond: Relative eigenvalue cut for redundant rows.

    Returns:
        The :class:`PlasticImpulse`.

    Raises:
        InputError: Bad shapes, non-finite values, or rows that no impulse can bring to zero together.
    """
    M, _ = _check(M, np.ones(np.asarray(M).shape[0]), 0.0)
    k = M.shape[0]
    G = np.asarray(G, float).reshape(-1, k) if np.size(G) else np.zeros((0, k))
    nu = np.asarray(nu, float)
    if nu.shape != (k,) or not (np.all(np.isfinite(nu)) and np.all(np.isfinite(G))):
        raise InputError(f"velocity has {nu.size} values and rows {G.shape}; expected {k} finite numbers and (m, {k})")
    before = G @ nu
    if G.shape[0] == 0:
        return PlasticImpulse(np.zeros(0), np.zeros(k), nu.copy(), before, 0.0, 0)
    MinvGT = np.linalg.solve(M, G.T)
    W = G @ MinvGT
    W = 0.5 * (W + W.T)
    vals, vecs = np.linalg.eigh(W)
    keep = vals > rcond * max(vals.max(initial=0.0), np.finfo(float).tiny)
    Lam = -vecs[:, keep] @ ((vecs[:, keep].T @ before) / vals[keep])
    dnu = MinvGT @ Lam
    after = nu + dnu
    left = np.abs(G @ after).max(initial=0.0)
    if left > 1e-8 * np.abs(before).max(initial=0.0) + 1e-12:  # [m/s] for rows of point velocities
        raise InputError(f"the rows cannot all be stopped by one impulse (|G nu+| = {left:.3g}); expected "
                         "consistent rows")
    lost = 0.5 * float(-before @ Lam)  # = 1/2 before^T W^+ before >= 0
    return PlasticImpulse(Lam, dnu, after, before, lost, int(keep.sum()))


def impulse_curve(M, e: float, speed: float = 1.0, plane: tuple[int, int] = (0, 1), samples: int = 361
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Impulse against a wall hit head-on at ``speed`` in every direction of a plane of velocity components.

    For each angle a, the motion is ``speed * d`` with d = cos(a) e_i + sin(a) e_j (i, j = ``plane``) and the
    wall normal is n = -d. The curve :math:`a \\mapsto |F(a)|\\,d` is what Chung, Yi, Kim, Han call the impulse ellipse
    (Figs. 16-19); it is a circle when the plane block of M^{-1} is isotropic.

    Args:
        M: Reduced inertia (k, k), symmetric positive definite.
        e: Coefficient of restitution, 0 (plastic) to 1 (elastic).
        speed: Approach speed [m/s] (> 0) in every direction.
        plane: The two velocity components (indices into nu) spanning the plane of directions.
        samples: Number of angles over [0, 2 pi].

    Returns:
        (angles [rad] (samples,), magnitudes [N s] (samples,)).
    """
    M, _ = _check(M, np.ones(np.asarray(M).shape[0]), e)
    if not (np.isfinite(speed) and speed > 0):
        raise InputError(f"impact speed {speed}; expected a positive speed")
    i, j = plane
    angles = np.linspace(0.0, 2 * np.pi, samples)
    Minv = np.linalg.inv(M)
    quad = Minv[i, i] * np.cos(angles) ** 2 + 2 * Minv[i, j] * np.cos(angles) * np.sin(angles) \
        + Minv[j, j] * np.sin(angles) ** 2
    return angles, (1.0 + e) * speed / quad


__all__ = ["Impulse", "impact", "effective_mass", "impulse_curve", "PlasticImpulse", "plastic_impact"]

"""Conditioning of a reduced model: which part of the solve makes a result (accelerations, forces, loads) huge.

Forward dynamics solves :math:`M_r \\dot\\nu = B_r\\tau - h` with :math:`M_r = S^T M S` (eq. of
:mod:`robotdyn.reduction.reduced_dynamics`), after the projection solved the dependent velocities from the
dependent block :math:`A_d` of the constraint Jacobian (:mod:`robotdyn.reduction.projection`). Two parts can make
the result blow up near a singular configuration, and only one of them is the projection's condition number
that ``dump`` has always printed:

* the **projection** (:math:`A_d`, 1-norm condition number): the dependent velocities become huge for a bounded
  :math:`\\nu` (a mechanism near a change of mobility), so do :math:`S`, :math:`w = \\dot S\\nu` and the bias;
* the **reduced mass matrix** :math:`S^T M S` (2-norm condition number, largest over smallest eigenvalue): an
  independent velocity that moves almost no mass at this state (e.g. a massless linkage at its dead point, where
  the coordinate it drives stops moving anything), so a bounded torque gives an unbounded acceleration.

A result is **beyond what the state can produce** when an acceleration exceeds :data:`PLAUSIBLE_ACCELERATION`
(1e6 m/s^2 or rad/s^2: 1e5 g; no motor and no rigid structure gets there) or a part's condition number exceeds
:data:`SEVERE_CONDITION` (1e10: ten of double precision's sixteen digits lost, whatever the result). Rigid bodies
with ideal joints idealise away what would bound such a result; :func:`ill_conditioned` names the parts that
explain it (condition number above :data:`NAME_CONDITION`; none: the inputs, not the state, are extreme) and
:func:`message` says it in one line, with each part's condition number and, for the mass matrix, the velocities of
its softest direction.

Scale: the five built-in robots and the examples (TIAGo, its arm, the skid-steer, QuasiMoRo) stay below 6e4
(:math:`S^TMS`, MMR12-EOD with its 0.2 kg slider beside a 99 kg robot) and 7e5 (:math:`A_d`, the adaptable wheel
near its equal-front-radii singularity) at regular states, with accelerations below 1e3 for unit torques;
:data:`NAME_CONDITION` = 1e6 lies above both, so that extreme torques on a regular state are not blamed on it,
and below the conditioning of every near-limit state of the adaptable wheel whose accelerations exceed 1e8 for unit
torques (``tests/test_conditioning.py``, 200 states, both evaluation paths).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PLAUSIBLE_ACCELERATION = 1e6
"""Largest independent acceleration [m/s^2 or rad/s^2] a real mechanism can produce (see the module text)."""
SEVERE_CONDITION = 1e10
"""Condition number above which a part is reported whatever the result (the projection refuses above 1e10 too)."""
NAME_CONDITION = 1e6
"""Condition number above which a part is named as a cause of an implausible result."""
WARN_CONDITION = SEVERE_CONDITION  # the force system's threshold (its own, a condition of A's rank-r part)


@dataclass
class IllConditioned:
    """One ill-conditioned part of a reduced solve.

    Attributes:
        part: ``"projection"`` (the dependent block :math:`A_d` of the constraint Jacobian),
            ``"mass matrix"`` (the reduced mass matrix :math:`S^T M S`) or ``"force system"`` (the rows'
            transpose :math:`A^T\\lambda = e` that gives the constraint forces, 2-norm condition of its rank-r part).
        condition: Its condition number (1-norm for :math:`A_d`, 2-norm for :math:`S^TMS`).
        velocities: For the mass matrix, the independent velocities of its softest direction (eigenvector of the
            smallest eigenvalue, entries above 0.3 of its largest); empty for the projection.
    """

    part: str
    condition: float
    velocities: tuple[str, ...] = ()


def mass_condition(M: np.ndarray) -> tuple[float, np.ndarray]:
    """2-norm condition number of a symmetric positive (semi-)definite matrix and the eigenvector of its smallest
    eigenvalue (``inf`` where that eigenvalue is not positive).

    Args:
        M: A symmetric positive (semi-)definite matrix (k, k), e.g. the reduced mass matrix :math:`S^TMS`.

    Returns:
        ``(condition, vector)``: the 2-norm condition number (1.0 for an empty matrix) and the unit eigenvector
        (k,) of the smallest eigenvalue (its softest direction).
    """
    if M.size == 0:
        return 1.0, np.zeros(0)
    w, V = np.linalg.eigh(M)
    cond = float(w[-1] / w[0]) if w[0] > 0 else float("inf")
    return cond, V[:, 0]


def _mass_below(M: np.ndarray, bound: float = SEVERE_CONDITION) -> bool:
    """Whether the reduced mass matrix's condition number (:func:`mass_condition`'s) is surely at most ``bound``:
    its eigenvalues alone (``eigvalsh``, no eigenvectors) give at most half of it. Their rounding differs from
    ``eigh``'s by about the machine precision times the condition number, far below that factor 2; ``False``
    leaves the decision to :func:`mass_condition`."""
    if M.size == 0:
        return True
    if not np.isfinite(M).all():
        return False
    w = np.linalg.eigvalsh(M)
    return bool(w[0] > 0 and w[-1] / w[0] <= 0.5 * bound)


def _parts(red, names) -> list[IllConditioned]:
    proj = IllConditioned("projection", float(red.projection.condition))
    cond, vec = mass_condition(np.asarray(red.M, float))
    names = names or [f"nu{i}" for i in range(len(vec))]
    big = np.abs(vec) >= 0.3 * np.abs(vec).max() if vec.size else np.zeros(0, bool)
    return [proj, IllConditioned("mass matrix", cond, tuple(n for n, b in zip(names, big) if b))]


def ill_conditioned(red, names: list[str] | None = None, nudot=None, forward: bool = True) -> list[IllConditioned]:
    """The parts of a reduced model's solve that make its results beyond what the state can produce.

    Args:
        red: A :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` (either evaluation path: it uses only
            ``M`` and ``projection.condition``).
        names: The independent velocities' names (k,), for the mass matrix's softest direction.
        nudot: The independent accelerations computed at this state (k,), if any.
        forward: Whether the results come from solving with the mass matrix (forward dynamics); inverse dynamics
            (accelerations given) multiplies by it instead, so its conditioning does not matter there.

    Returns:
        A list of :class:`IllConditioned`, the projection first: every part above :data:`SEVERE_CONDITION`, and
        where ``nudot`` exceeds :data:`PLAUSIBLE_ACCELERATION` every part above :data:`NAME_CONDITION`. Empty where
        the results are within what the state can produce, or where they are large only because the torques or
        velocities given are (every part well conditioned: the inputs, not the state, are extreme).
    """
    implausible = nudot is not None and not np.abs(np.asarray(nudot, float)).max(initial=0.0) <= PLAUSIBLE_ACCELERATION
    if not implausible and red.projection.condition <= SEVERE_CONDITION and (not forward or _mass_below(red.M)):
        return []  # (only parts above SEVERE_CONDITION could be named, and none is)
    parts = _parts(red, names)
    if not forward:
        parts = [p for p in parts if p.part != "mass matrix"]
    out = [p for p in parts if not p.condition <= SEVERE_CONDITION]
    if nudot is not None and not np.abs(np.asarray(nudot, float)).max(initial=0.0) <= PLAUSIBLE_ACCELERATION:
        out = [p for p in parts if p in out or not p.condition <= NAME_CONDITION]
    return out


WHAT = "the accelerations, forces and loads"
"""What an ill-conditioned solve makes unreliable (one wording for every door, so the CLI prints it once)."""


def message(found: list[IllConditioned], what: str = WHAT) -> str:
    """One line for :func:`ill_conditioned`'s list: which part, its condition number, and what it means.

    Args:
        found: The ill-conditioned parts (:class:`IllConditioned`), in the order to name them.
        what: What is implausible, the sentence's subject (default :data:`WHAT`).

    Returns:
        The warning's text, one line.
    """
    parts = []
    for f in found:
        if f.part == "projection":
            parts.append(f"the projection's dependent block of the constraint Jacobian (A_d) has condition number "
                         f"{f.condition:.3g} (the dependent velocities are nearly undetermined: a singular "
                         "configuration)")
        elif f.part == "force system":
            parts.append(f"the force system (the constraint rows' transpose, A^T lambda = ...) has condition number "
                         f"{f.condition:.3g} (nearly redundant rows: the forces are nearly undetermined)")
        else:
            parts.append(f"the reduced mass matrix S^T M S has condition number {f.condition:.3g} (its softest "
                         f"direction, {', '.join(f.velocities)}, moves almost no mass here)")
    return (f"{what} at this state are beyond what it can produce physically: " + "; ".join(parts)
            + "; move away from this configuration (or give the mechanism the inertia it has)")

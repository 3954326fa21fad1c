"""The minimum-mu column of the per-sample traction pass, solved for all samples at once.

Where :func:`robotdyn.contact.traction.traction` computes the loads sample by sample
(:func:`~robotdyn.contact.contact_forces.constraint_forces`: compliant wheels, stick-slip runs, robots without a
compiled model), its minimum-mu column was :meth:`~robotdyn.contact.contact_forces.ConstraintForces.minimum_mu` at
every sample: a bounded scalar search (scipy's ``minimize_scalar``) per sample where one combination of the forces is
open (e.g. the side force of two wheels on one axle), most of such a pass's time. Here each sample gives only its
problem (:func:`cone_problem`: the same wheels, loads and maps :math:`f_{t,i}(z) = b_i + T_i z` as ``minimum_mu``),
and :func:`minimum_mu_many` solves them together: exactly and vectorised where the tangential forces move along one
direction (:func:`robotdyn.contact.traction_fast._cone_minimum`, as the fast pass), by the reference's own solver
(:func:`~robotdyn.contact.contact_forces.cone_minimum`) where they move along more.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .traction_fast import _cone_minimum


@dataclass
class ConeProblem:
    """One sample's :math:`\\min_z \\max_i \\|b_i + T_i z\\| / f_{n,i}`.

    Attributes:
        fn: (W,) the normal loads [N] of the wheels that count (a compliant wheel in the air does not).
        b: (W, 2) their tangential forces (t1, t2) at z = 0 [N].
        T: (W, 2, d) how those change with the open combinations z.
    """

    fn: np.ndarray
    b: np.ndarray
    T: np.ndarray


def cone_problem(forces) -> ConeProblem | float | None:
    """A sample's minimum-mu problem, or its value where no search is needed, exactly as
    :meth:`~robotdyn.contact.contact_forces.ConstraintForces.minimum_mu` sets it up.

    Args:
        forces: The sample's :class:`~robotdyn.contact.contact_forces.ConstraintForces`.

    Returns:
        ``None`` where a normal load has no value, ``0.0`` where no wheel counts (all compliant ones in the air),
        ``inf`` where a counted wheel is not pressed on the ground, else the :class:`ConeProblem`.
    """
    if not forces.wheels or not all(w.known[2] for w in forces.wheels):
        return None
    pairs = [(t, w) for t, w in zip(forces._tangential, forces.wheels)
             if not (w.kind == "compliant" and w.normal <= 0)]
    if not pairs:
        return 0.0
    fn = np.array([w.normal for _, w in pairs], float)
    if np.any(fn <= 0):
        return float("inf")
    space = forces.open
    d = space.shape[1]
    b, T = np.zeros((len(pairs), 2)), np.zeros((len(pairs), 2, d))
    for i, ((idx, D, friction), _) in enumerate(pairs):
        if friction is not None:
            b[i] = np.asarray(friction, float)
        else:
            b[i], T[i] = D.T[:2] @ forces.lam[idx], D.T[:2] @ space[idx]
    return ConeProblem(fn, b, T)


def minimum_mu_many(problems: list) -> list:
    """The minimum friction coefficient of each sample, from its :func:`cone_problem` answer.

    Args:
        problems: Per sample a :class:`ConeProblem`, or the value (``None``, ``0.0``, ``inf``) that needs no search.

    Returns:
        Per sample the smallest :math:`\\max_i \\|b_i + T_i z\\| / f_{n,i}` over z (as ``minimum_mu``: exact
        where the maps move along one direction, the reference's solver elsewhere), or the value given.
    """
    out = list(problems)
    groups: dict[tuple, list[int]] = {}
    for i, p in enumerate(problems):
        if isinstance(p, ConeProblem):
            groups.setdefault(p.T.shape, []).append(i)
    for idx in groups.values():
        fn = np.stack([problems[i].fn for i in idx])
        b = np.stack([problems[i].b for i in idx])
        T = np.stack([problems[i].T for i in idx])
        for i, value in zip(idx, _cone_minimum(fn, b, T)):
            out[i] = float(value)
    return out


__all__ = ["ConeProblem", "cone_problem", "minimum_mu_many"]

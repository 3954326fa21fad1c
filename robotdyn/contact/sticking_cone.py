"""Whether exact stick-slip wheels can keep sticking, where rigid-body dynamics leave some of their forces open.

A sticking wheel i (:class:`~robotdyn.contact.stick_slip_wheel.StickSlipWheel` in its ``stick`` phase) holds while
its tangential force lies in its friction cone, :math:`\\|f_{t,i}\\| \\le \\mu_i f_{n,i}`. On a statically
indeterminate chassis (a rigid car or skid steer on four wheels) part of the multipliers is open,
:math:`\\lambda + N z` (:mod:`robotdyn.contact.contact_forces`), and the decision is made thus:

- **normal loads**: those of the rigid limit of the wheels' normal compliance (:mod:`robotdyn.contact.rigid_limit`;
  with sliding wheels, of the coupled solve :func:`robotdyn.contact.sliding_rigid_limit.coupled`). They come from the whole
  multiplier vector, so they include the load transfer by the moments of the tangential forces (a driven car's
  rear wheels carry :math:`m a_x h / L` more), and they do not depend on the rest of the choice: the directions
  that stay open (:attr:`~robotdyn.contact.contact_forces.ConstraintForces.open`) move no normal load;
- **tangential forces**: along what stays open (e.g. the lateral squeeze between two wheels of one axle) static
  friction takes whatever split keeps the wheels sticking, if there is one: the rigid Coulomb contact's
  complementarity (a sticking solution exists iff some admissible force lies in every cone; the concepts page
  ``docs/concepts.md``). The group of sticking wheels whose tangential forces move along those directions holds iff

  .. math:: \\rho = \\min_z \\max_i \\frac{\\|b_i + T_i z\\|}{\\mu_i f_{n,i}} \\le 1,

  a convex problem (:func:`robotdyn.contact.contact_forces.cone_split`). Its margin :math:`1 - \\rho` is the stick-slip
  engine's event (:mod:`robotdyn.simulation.stick_slip`); where it reaches zero, the wheels at the edge of their cone
  at the minimising split start sliding, opposite to their force there. Wheels whose tangential forces rigid-body
  dynamics determine keep the per-wheel test :math:`\\mu_i f_{n,i} - \\|f_{t,i}\\|` (this minimum over z is then
  just their own ratio).

This is the rule of :meth:`~robotdyn.contact.contact_forces.ConstraintForces.minimum_mu` (the smallest mu some
admissible split needs), with each wheel's own mu.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import RobotDynError
from .contact_forces import DETERMINED_TOL, ConstraintForces, cone_split

EDGE = 1e-8
"""Relative tolerance within which a wheel's force counts as on the edge of its cone (it starts sliding)."""


@dataclass
class ConeCheck:
    """The friction cones of sticking wheels at one state.

    Attributes:
        wheels: The sticking wheels checked, in the order given.
        ratio: (W,) :math:`\\|f_{t,i}\\| / (\\mu_i f_{n,i})` at the split chosen (``inf`` where the cone is empty).
        force: (W, 2) their tangential forces (t1, t2) of the contact frame [N] at that split.
        normal: (W,) their normal loads [N].
        coupled: (W,) whose tangential force moves along what stays open (they are decided together).
    """

    wheels: list
    ratio: np.ndarray
    force: np.ndarray
    normal: np.ndarray
    coupled: np.ndarray

    @property
    def margin(self) -> float:
        """:math:`1 - \\max_i` ratio [-] (>= 0: every wheel can stick; ``inf`` without wheels)."""
        return 1.0 - float(np.max(self.ratio)) if len(self.ratio) else np.inf

    @property
    def group_margin(self) -> float:
        """:math:`1 - \\rho` of the coupled wheels [-] (``inf`` where none is coupled): the joint event."""
        return 1.0 - float(np.max(self.ratio[self.coupled])) if self.coupled.any() else np.inf

    def breaking(self) -> list[tuple[object, np.ndarray]]:
        """The wheels at or beyond the edge of their cone and the slip direction (2,) each starts sliding in
        (opposite to its force at the split chosen).

        Returns:
            ``[(wheel, direction), ...]`` (empty where every force lies strictly inside its cone).
        """
        return [(w, -f) for w, r, f in zip(self.wheels, self.ratio, self.force) if r >= 1.0 - EDGE]


def check(forces: ConstraintForces, wheels: list) -> ConeCheck:
    """The friction cones of the sticking ``wheels`` at the state of ``forces`` (see the module).

    Args:
        forces: The :class:`~robotdyn.contact.contact_forces.ConstraintForces` at the state (rigid limit applied).
        wheels: The sticking :class:`~robotdyn.contact.stick_slip_wheel.StickSlipWheel` objects.

    Returns:
        The :class:`ConeCheck`.

    Raises:
        RobotDynError: A sticking wheel's normal load has no value (no model fixes it), in one line.
    """
    position = {w.name: i for i, w in enumerate(forces.wheels)}
    fn = np.zeros(len(wheels))
    maps = []
    space = forces.open
    for j, wheel in enumerate(wheels):
        i = position[wheel.name]
        wf = forces.wheels[i]
        if not wf.known[2]:
            raise RobotDynError(
                f"the normal load of sticking wheel {wheel.name} is not determined (no compliance model fixes it), "
                "so its friction cone cannot decide sticking; expected a chassis whose loads rigid-body dynamics or "
                "the rigid limit of the wheels' normal compliance give")
        idx, D, friction = forces._tangential[i]
        fn[j] = wf.normal
        if friction is not None or space.shape[1] == 0:
            maps.append((np.asarray(wf.force[:2], float), np.zeros((2, space.shape[1]))))
        else:
            T = np.asarray(D, float).T[:2] @ space[idx]
            T[np.abs(T) <= DETERMINED_TOL] = 0.0
            maps.append((np.asarray(D, float).T[:2] @ forces.lam[idx], T))
    coupled = np.array([bool(np.any(T)) for _, T in maps], bool)
    scale = np.array([w.mu for w in wheels], float) * fn
    ratio = np.array([np.hypot(*b) / s if s > 0 else (np.inf if np.hypot(*b) > 0 or s < 0 else 0.0)
                      for (b, _), s in zip(maps, scale)])
    force = np.array([b for b, _ in maps], float).reshape(len(wheels), 2)
    if coupled.any():
        group = np.flatnonzero(coupled)
        if np.any(scale[group] <= 0):
            ratio[group] = np.inf
        else:
            _, z = cone_split([maps[g] for g in group], scale[group], space.shape[1])
            for g in group:
                b, T = maps[g]
                force[g] = b + T @ z
                ratio[g] = float(np.linalg.norm(force[g])) / scale[g]
    return ConeCheck(list(wheels), ratio, force, fn, coupled)


__all__ = ["ConeCheck", "check", "EDGE"]

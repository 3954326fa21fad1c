"""Finite-difference steps in the natural coordinates that stay on the holonomic constraints' level set.

A central difference of the dynamics or of the contact forces in q perturbs one coordinate at a time. Where the
holonomic rows (loop closures, wheels on a terrain) are redundant on their manifold -- a closed linkage whose rows
are independent only off it -- a step along a dependent coordinate opens the loops, the rows' rank jumps and the
reduced dynamics refuse the state (:class:`~robotdyn.errors.SingularConstraintError`: fewer independent velocities
than the mobility). Here the step is taken along the level set :math:`\\phi(q') = \\phi(q)` of the independent
holonomic residuals instead: only an independent position coordinate i is stepped, by :math:`\\pm h`, and the
dependent coordinates d are corrected by Newton's method on :math:`\\phi(q') - \\phi(q) = 0` (Jacobian
:math:`A_h[:, d]`, square and invertible where the independent positions were chosen). The difference quotient is
then the derivative along that tangent direction; the dependent coordinates' columns are zero. Such a Jacobian
differs from the full one only by rows in the row space of :math:`A_h` (it agrees on every tangent vector), which
changes the holonomic rows' multipliers in an optimisation, not its optimum.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import ConstraintError

NEWTON_TOL = 1e-14
"""Newton's tolerance [m or rad] on the change of the holonomic residuals over a step."""
NEWTON_ITERATIONS = 20


class ManifoldSteps:
    """Steps of the natural coordinates along the holonomic level set (see the module docstring).

    Args:
        holonomic: ``q -> (phi (mh,), A_h (mh, n))``, the independent holonomic residuals [m or rad] and their
            Jacobian.
        positions: Indices of the independent position coordinates (n - mh,), the ones stepped.
        n: Number of natural coordinates.
    """

    def __init__(self, holonomic: Callable, positions, n: int) -> None:
        self.holonomic = holonomic
        self.positions = np.asarray(positions, int)
        self.dependent = np.setdiff1d(np.arange(n), self.positions)
        self.n = n
        self.held = set()  # coordinates held at their value (robotdyn.optimisation.held_coordinates): never stepped

    def pair(self, q: np.ndarray, i: int, step: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The configurations ``(q+, q-)`` a central difference in coordinate i uses, or ``None`` for a dependent
        coordinate or one in :attr:`held` (its column is zero).

        Args:
            q: Natural coordinates (n,) [m, rad].
            i: The coordinate stepped.
            step: The step h [m or rad].

        Returns:
            ``(q+, q-)``: q with coordinate i at :math:`q_i \\pm h` and the dependent coordinates on the level set
            of q's holonomic residuals.

        Raises:
            ConstraintError: Newton's method does not reach the level set (a singular :math:`A_h[:, d]`).
        """
        if i not in self.positions or i in self.held:
            return None
        phi0 = self.holonomic(q)[0]
        out = []
        for sign in (1.0, -1.0):
            qs = np.array(q, float)
            qs[i] += sign * step
            for _ in range(NEWTON_ITERATIONS):
                phi, A = self.holonomic(qs)
                e = phi - phi0
                if np.max(np.abs(e), initial=0.0) < NEWTON_TOL:
                    break
                qs[self.dependent] -= np.linalg.solve(A[:, self.dependent], e)
            else:
                raise ConstraintError(f"a finite-difference step of coordinate {i} does not return to the holonomic "
                                      f"level set (residual {np.max(np.abs(e)):.3g}); expected Newton to converge")
            out.append(qs)
        return out[0], out[1]

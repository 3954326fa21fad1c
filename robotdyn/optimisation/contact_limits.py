"""Traction limits as path constraints of a trajectory optimisation: wheel loads and the friction cone at the nodes.

At every collocation node (state :math:`x = (q, \\nu)`, motor torques :math:`\\tau`) the ground's force on wheel i,
in its contact frame (t1 longitudinal, t2 lateral, n normal) [N], is the one
:meth:`robotdyn.robot.Robot.contact_forces` reports: :math:`(f_{t1}, f_{t2}, f_n)_i(q, \\nu, \\tau)`. The
constraints, each scaled by the mean wheel load :math:`\\bar f = m g / n_w` (the robot's weight shared by its wheels,
so that they are numbers of order one):

- loads: :math:`f_{n,i} / \\bar f \\ge f_{min} / \\bar f` (a wheel kept on the ground with at least ``min_load``);
- friction cone: :math:`(f_{t1,i}^2 + f_{t2,i}^2 - \\mu_{max}^2 f_{n,i}^2) / \\bar f^2 \\le 0`, that is a required
  friction coefficient :math:`\\|f_t\\|/f_n \\le \\mu_{max}` where :math:`f_n \\ge 0` (no division: smooth where a
  wheel is unloaded, and the load constraint keeps :math:`f_n > 0`);
- peak required mu (cost ``peak-mu``): :math:`(f_{t1,i}^2 + f_{t2,i}^2 - s\\,f_{n,i}^2) / \\bar f^2 \\le 0` with
  one decision variable s, the square of the largest required mu over wheels and nodes (its epigraph), minimised.

Their Jacobian in :math:`(x, \\tau, s)` comes from the derivatives of the forces: analytic
(``Robot.contact_force_derivatives``, where the robot has it) or central finite differences of the forces
(``finite-difference``, the reference). Where every wheel slips under a friction law in both directions (a skid
steer), the forces of one state come from the same coupled solve as the forward dynamics
(:func:`robotdyn.contact.sliding.forward`), else from :meth:`~robotdyn.robot.Robot.contact_forces`; the two are the
same numbers (tested).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError, NonFiniteError
from ..fast.dispatch import ThreadModel


class ContactLimits:
    """The wheel-load and friction-cone constraints of one robot at one node (see the module docstring).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q0: A configuration on the constraint manifold (n,) [m, rad], at which the wheels are found.
        min_load: Least normal load of every wheel [N] (``None``: 0 where a cone or the peak cost is asked, else no
            load constraint).
        mu_max: Largest required friction coefficient :math:`\\|f_t\\|/f_n` of every wheel (``None``: no cone).
        peak: Add the peak-mu rows (``ratio - s <= 0``) for the ``peak-mu`` cost.
        derivatives: ``analytic`` or ``finite-difference``, the source of the forces' Jacobian.

    Raises:
        InputError: A robot without wheels, a non-finite or negative bound.
    """

    _compiled = ThreadModel()  # the compiled model for the calling thread (None: the Python path)

    def __init__(self, robot, q0: np.ndarray, min_load: float | None = None, mu_max: float | None = None,
                 peak: bool = False, derivatives: str = "finite-difference") -> None:
        self.robot = robot
        self.n, self.k, self.m = len(robot.coordinates), len(robot.velocity_names), len(robot.motors)
        for name, value in (("min_load", min_load), ("mu_max", mu_max)):
            if value is not None and not (np.isfinite(value) and value >= 0):
                raise InputError(f"{name} = {value!r}; expected a finite number >= 0")
        rest = robot.contact_forces(q0, np.zeros(self.k), tau=np.zeros(self.m))
        self.wheels = [w.name for w in rest.wheels]
        if not self.wheels:
            raise InputError(f"robot {robot.spec.name!r} has no wheels on the ground: no wheel loads to constrain")
        import pinocchio as pin

        weight = pin.computeTotalMass(robot.model) * float(np.linalg.norm(robot.model.gravity.linear))
        self.scale = weight / len(self.wheels) if weight > 0 else 1.0
        if min_load is None and (mu_max is not None or peak):
            min_load = 0.0
        self.min_load, self.mu_max, self.peak = min_load, mu_max, bool(peak)
        self.derivatives = derivatives
        self.steps = None  # a ManifoldSteps: finite differences in q along the holonomic level set
        from ..contact.sliding import sliding_now

        sliding = sliding_now(robot)
        self._coupled = bool(sliding) and ([w.name for w in sliding] == self.wheels
                                           and all(getattr(w, "slip_directions", None) == "both" for w in sliding))
        self._compiled = None
        if not sliding and not self._coupled:
            from ..fast.dispatch import compiled_model

            fast = compiled_model(robot)
            nu, tau = np.linspace(0.1, 0.2, self.k), np.linspace(-1.0, 1.0, self.m)  # a moving, driven state
            if fast is not None:
                from ..fast.compiled import Fallback

                reference = [w.force for w in robot.contact_forces(q0, nu, tau=tau).wheels]
                try:
                    same = np.allclose(self._compiled_forces(fast, q0, nu, tau), reference, rtol=1e-9,
                                       atol=1e-9 * self.scale)
                except Fallback:
                    same = False
                self._compiled = fast if same else None
        self.calls = 0

    @property
    def rows_per_node(self) -> int:
        """Constraint rows per node: loads, then cones, then peak rows, one per wheel each where asked."""
        return len(self.wheels) * ((self.min_load is not None) + (self.mu_max is not None) + self.peak)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of one node's rows (in their scaled units), in the order of :meth:`values`.

        Returns:
            ``(lower, upper)``, each (:attr:`rows_per_node`,).
        """
        nw, lo, hi = len(self.wheels), [], []
        if self.min_load is not None:
            lo.append(np.full(nw, self.min_load / self.scale))
            hi.append(np.full(nw, np.inf))
        for _ in range((self.mu_max is not None) + self.peak):
            lo.append(np.full(nw, -np.inf))
            hi.append(np.zeros(nw))
        return np.concatenate(lo), np.concatenate(hi)

    def forces(self, q: np.ndarray, nu: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """The ground's force on each wheel (nw, 3) [N], columns (t1, t2, n) of its contact frame, as
        :meth:`robotdyn.robot.Robot.contact_forces` gives it.

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            tau: Motor torques (motors,) [N m or N].

        Returns:
            The forces (nw, 3) [N], wheels in the order of :attr:`wheels`.
        """
        self.calls += 1
        if self._coupled:
            from ..contact.sliding import forward

            st = forward(self.robot, q, nu, tau)
            return np.column_stack([st.force, st.normal])
        fast = self._compiled
        if fast is not None:
            from ..fast.compiled import Fallback

            try:
                return self._compiled_forces(fast, q, nu, tau)
            except Fallback:
                pass
        cf = self.robot.contact_forces(q, nu, tau=tau)
        return np.array([w.force for w in cf.wheels])

    @staticmethod
    def _compiled_forces(fast, q, nu, tau) -> np.ndarray:
        """The wheel forces (nw, 3) of the compiled model's one-call forward dynamics and forces (a copy)."""
        return np.array(fast.forces(np.asarray(q, float), np.asarray(nu, float), np.asarray(tau, float))[3])

    def _rows(self, F: np.ndarray, s: float) -> np.ndarray:
        ft2, fn = F[:, 0] ** 2 + F[:, 1] ** 2, F[:, 2]
        out = []
        if self.min_load is not None:
            out.append(fn / self.scale)
        if self.mu_max is not None:
            out.append((ft2 - self.mu_max ** 2 * fn ** 2) / self.scale ** 2)
        if self.peak:
            out.append((ft2 - s * fn ** 2) / self.scale ** 2)
        return np.concatenate(out)

    def values(self, q: np.ndarray, nu: np.ndarray, tau: np.ndarray, s: float = 0.0) -> np.ndarray:
        """One node's rows (:attr:`rows_per_node`,), scaled (see the module docstring).

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            tau: Motor torques (motors,) [N m or N].
            s: The peak variable (the square of the peak required mu), used by the peak rows.

        Returns:
            The rows: loads, cones, peak rows, each one per wheel.
        """
        out = self._rows(self.forces(q, nu, tau), s)
        if not np.all(np.isfinite(out)):
            raise NonFiniteError("trajectory optimisation: the contact forces are not finite at an iterate")
        return out

    def force_jacobian(self, q: np.ndarray, nu: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The forces (nw, 3) and their Jacobian (nw, 3, n + k + motors) in (q, nu, tau).

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            tau: Motor torques (motors,) [N m or N].

        Returns:
            ``(F, dF)``.
        """
        if self.derivatives == "analytic":
            return self._analytic(q, nu, tau)
        y = np.concatenate([q, nu, tau])
        n, k = self.n, self.k
        F0 = self.forces(q, nu, tau).copy()
        dF = np.empty(F0.shape + (y.size,))
        for i in range(y.size):
            step = np.cbrt(np.finfo(float).eps) * (1.0 + abs(y[i]))
            yp, ym = y.copy(), y.copy()
            yp[i] += step
            ym[i] -= step
            if self.steps is not None and i < n:
                pair = self.steps.pair(q, i, step)
                if pair is None:
                    dF[:, :, i] = 0.0
                    continue
                yp[:n], ym[:n] = pair
            Fp = self.forces(yp[:n], yp[n:n + k], yp[n + k:]).copy()
            Fm = self.forces(ym[:n], ym[n:n + k], ym[n + k:])
            dF[:, :, i] = (Fp - Fm) / (2 * step)
        return F0, dF

    def _analytic(self, q, nu, tau):
        self.calls += 1
        d = self.robot.contact_force_derivatives(q, nu, tau)
        return _forces_and_jacobian(d, self.wheels, self.n, self.k, self.m)

    def jacobian(self, q: np.ndarray, nu: np.ndarray, tau: np.ndarray, s: float = 0.0
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One node's rows' Jacobian in the state x = (q, nu), the torques and s.

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            tau: Motor torques (motors,) [N m or N].
            s: The peak variable.

        Returns:
            ``(d/dx (rows, n + k), d/dtau (rows, motors), d/ds (rows, 1))``.
        """
        F, dF = self.force_jacobian(q, nu, tau)
        ft1, ft2, fn = F[:, 0:1], F[:, 1:2], F[:, 2:3]
        dt = 2 * (ft1 * dF[:, 0] + ft2 * dF[:, 1])
        blocks, ds = [], []
        nw = len(self.wheels)
        if self.min_load is not None:
            blocks.append(dF[:, 2] / self.scale)
            ds.append(np.zeros(nw))
        if self.mu_max is not None:
            blocks.append((dt - 2 * self.mu_max ** 2 * fn * dF[:, 2]) / self.scale ** 2)
            ds.append(np.zeros(nw))
        if self.peak:
            blocks.append((dt - 2 * s * fn * dF[:, 2]) / self.scale ** 2)
            ds.append(-fn[:, 0] ** 2 / self.scale ** 2)
        J = np.vstack(blocks)
        if not np.all(np.isfinite(J)):
            raise NonFiniteError("trajectory optimisation: the contact forces' derivatives are not finite at an "
                                 "iterate")
        nx = self.n + self.k
        return J[:, :nx], J[:, nx:], np.concatenate(ds)[:, None]

    def required_mu(self, q: np.ndarray, nu: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Each wheel's required friction coefficient :math:`\\|f_t\\|/f_n` (inf where :math:`f_n \\le 0`).

        Args:
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            tau: Motor torques (motors,) [N m or N].

        Returns:
            (nw,) in the order of :attr:`wheels`.
        """
        return required_mu(self.forces(q, nu, tau))


def required_mu(F: np.ndarray) -> np.ndarray:
    """:math:`\\|(f_{t1}, f_{t2})\\|/f_n` per row of ``F`` (..., 3) [N] (inf where :math:`f_n \\le 0`).

    Args:
        F: Forces (..., 3), last axis (t1, t2, n) [N].

    Returns:
        The ratios (...,).
    """
    F = np.asarray(F, float)
    ft = np.hypot(F[..., 0], F[..., 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(F[..., 2] > 0, ft / F[..., 2], np.inf)


def _forces_and_jacobian(d, wheels: list[str], n: int, k: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Forces (nw, 3) and their Jacobian (nw, 3, n + k + m) from ``Robot.contact_force_derivatives``' result
    (a :class:`~robotdyn.contact.force_derivatives.ContactForceDerivatives`), wheels in the order ``wheels``."""
    order = [list(d.wheels).index(w) for w in wheels]
    dF = np.concatenate([d.dforce_dq, d.dforce_dnu, d.dforce_dtau], axis=2)
    return np.asarray(d.force, float)[order], dF[order]


__all__ = ["ContactLimits", "required_mu"]

"""The linearised state-space model of the reduced dynamics about any state, and LQR gains for it.

State :math:`x = (q_P, \\nu)`: the independent position coordinates :math:`q_P` (a subset of the natural
coordinates; the others follow the holonomic constraints, :func:`robotdyn.reduction.dynamics_derivatives.position_coordinates`)
and the independent velocities. The reduced ODE :math:`\\dot q_P = [S(q)\\nu]_P`,
:math:`\\dot\\nu = \\dot\\nu(q, \\nu, \\tau)` (what :mod:`robotdyn.simulation.engine` integrates, on the manifold)
linearised at :math:`(x_0, \\tau_0)`:

.. math:: \\delta\\dot x = A\\,\\delta x + B\\,\\delta\\tau,\\qquad
          A = \\begin{bmatrix} [\\partial(S\\nu)/\\partial q\\; T]_P & S_P \\\\
          \\partial\\dot\\nu/\\partial q\\; T & \\partial\\dot\\nu/\\partial\\nu \\end{bmatrix},\\quad
          B = \\begin{bmatrix} 0 \\\\ M_r^{-1} B_r \\end{bmatrix},

with :math:`T = \\partial q/\\partial q_P`. About a state that is not an equilibrium (a steady motion) the model
describes deviations from the motion through it; :attr:`LinearModel.xdot0` is :math:`\\dot x` there.

Position coordinates the dynamics does not depend on (a base's x, y and heading on flat ground, wheel angles) give
zero eigenvalues and make the model unstabilisable for LQR; :meth:`LinearModel.restrict` keeps a subset of states
(exact when the kept states' equations do not involve the dropped ones). LQR gains are from scipy's
``solve_continuous_are`` (a well-kept Riccati solver, not hand-written).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError


@dataclass
class LinearModel:
    """:math:`\\delta\\dot x = A\\,\\delta x + B\\,\\delta\\tau` about :math:`(x_0, \\tau_0)`.

    Attributes:
        A: (n_x, n_x), rows and columns in the order of ``states``: blocks [1/s] (positions by positions),
            [-] (positions by velocities), [1/s^2] (velocities by positions), [1/s] (velocities by velocities).
        B: (n_x, n_motors), columns in the order of ``inputs``: zero position rows, then
            :math:`M_r^{-1}B_r` (each velocity's acceleration per unit input, e.g. [rad/s^2 per N m]).
        states: Names of the states (position coordinates, then velocities).
        inputs: Motor names, in the order of ``robot.motors``.
        x0: The operating state (n_x,) [m, rad, m/s, rad/s].
        tau0: The operating torques (n_motors,) [N m or N].
        xdot0: :math:`\\dot x` at the operating point (n_x,) [m/s, rad/s, m/s^2, rad/s^2] (zero at an equilibrium).
        q0: The full natural coordinates of the operating point (n,) [m, rad].
        position_index: For each position state, its index in q.
        numerical: Pieces of the derivatives computed by finite differences (see
            :class:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives`).
        velocities: Names of all the robot's independent velocities (to read the velocity states from nu).
    """

    A: np.ndarray
    B: np.ndarray
    states: list[str]
    inputs: list[str]
    x0: np.ndarray
    tau0: np.ndarray
    xdot0: np.ndarray
    q0: np.ndarray
    position_index: np.ndarray
    numerical: tuple[str, ...] = ()
    velocities: list[str] = field(default_factory=list)

    @property
    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of A [1/s], sorted by real part then imaginary part."""
        ev = np.linalg.eigvals(self.A)
        return ev[np.lexsort((ev.imag, ev.real))]

    def restrict(self, keep: list[str]) -> LinearModel:
        """The model on the states named in ``keep`` (in the model's order), the others dropped.

        Args:
            keep: Names of the states to keep (any order; the result keeps the model's order).

        Returns:
            A new :class:`LinearModel` (the inputs, ``tau0`` and ``q0`` unchanged).

        Raises:
            InputError: An unknown state name, or one listed twice.
        """
        bad = [s for s in keep if s not in self.states]
        if bad:
            raise InputError(f"unknown state {bad[0]!r}; expected some of {', '.join(self.states)}")
        twice = [s for s in dict.fromkeys(keep) if list(keep).count(s) > 1]
        if twice:
            raise InputError(f"state {twice[0]!r} listed twice; expected distinct states of {', '.join(self.states)}")
        idx = np.array([i for i, s in enumerate(self.states) if s in keep], dtype=int)
        npos = len(self.position_index)
        pos = [i for i in idx if i < npos]
        return LinearModel(self.A[np.ix_(idx, idx)], self.B[idx], [self.states[i] for i in idx], list(self.inputs),
                           self.x0[idx], self.tau0, self.xdot0[idx], self.q0, self.position_index[pos],
                           self.numerical, self.velocities)

    def state(self, q, nu) -> np.ndarray:
        """The model's state vector x (n_x,) of a robot state (q, nu).

        Args:
            q: Natural coordinates (n,) [m, rad] in the order of ``robot.coordinates``.
            nu: Independent velocities (k,) [m/s, rad/s] in the order of :attr:`velocities`.

        Returns:
            x (n_x,): the kept position coordinates then the kept velocities, in the order of :attr:`states`.
        """
        q, nu = np.asarray(q, float), np.asarray(nu, float)
        return np.concatenate([q[self.position_index], nu[self._velocity_index()]])

    def _velocity_index(self) -> np.ndarray:
        names = self.states[len(self.position_index):]
        return np.array([self.velocities.index(s) for s in names], dtype=int)


def linearize(robot, q, nu, tau) -> LinearModel:
    """The linearised model of ``robot``'s reduced dynamics about (q, nu, tau).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` (rolling and slipping wheels, loop closures, couplings, operational
            velocities): its :meth:`~robotdyn.robot.Robot.dynamics_derivatives`.
        q: Natural coordinates (n,) [m, rad] in the order of ``robot.coordinates``, on the holonomic manifold.
        nu: Independent velocities (k,) [m/s, rad/s] in the order of ``robot.velocity_names``.
        tau: Motor torques/forces (n_motors,) [N m or N] in the order of ``robot.motors``.

    Returns:
        A :class:`LinearModel` in the state (independent positions, independent velocities).

    Raises:
        InputError: Wrong sizes, or a constraint without derivatives (e.g. stick-slip or exact Coulomb friction).
        NonFiniteError: A non-finite derivative at this state.
    """
    D = robot.dynamics_derivatives(q, nu, tau)
    P, T = D.positions, D.tangent
    p, n_x = len(P), len(P) + D.dnu.shape[0]
    A = np.empty((n_x, n_x))  # the four blocks written in place (np.block's checks cost more than the copies)
    A[:p, :p], A[:p, p:], A[p:, :p], A[p:, p:] = (D.dqdot_dq @ T)[P], D.S[P], D.dq_manifold, D.dnu
    B = np.zeros((n_x, D.dtau.shape[1]))
    B[p:] = D.dtau
    q = np.asarray(q, float)
    nu = np.asarray(nu, float)
    states = [robot.coordinates[i] for i in P] + list(robot.velocity_names)
    out = LinearModel(A, B, states, [m.name for m in robot.motors], np.concatenate([q[P], nu]),
                      np.asarray(tau, float), np.concatenate([D.qdot[P], D.nudot]), q, np.asarray(P), D.numerical, list(robot.velocity_names))
    return out


def lqr(model: LinearModel, Q, R) -> tuple[np.ndarray, np.ndarray]:
    """The LQR gain K (u = -K dx minimises :math:`\\int dx^TQdx + du^TRdu`) and the closed-loop eigenvalues.

    Args:
        model: The linear model (e.g. restricted with :meth:`LinearModel.restrict`).
        Q: The state weights (n_x, n_x), or its diagonal (n_x,), positive semidefinite, in the order of
            ``model.states``.
        R: The input weights (n_u, n_u), or its diagonal (n_u,), positive definite, in the order of
            ``model.inputs``.

    Returns:
        ``(K, closed)``: the gain K (n_u, n_x) [N m or N per unit of each state] and the closed-loop eigenvalues
        of :math:`A - BK` (n_x,) [1/s], sorted by real part then imaginary part.

    Raises:
        InputError: Wrong shapes, or no stabilising solution (an unstabilisable mode: restrict the model to the
            states the inputs can reach, :meth:`LinearModel.restrict`).
    """
    import scipy.linalg

    nx, nu_ = model.B.shape
    Q = np.diag(np.asarray(Q, float)) if np.ndim(Q) == 1 else np.asarray(Q, float)
    R = np.diag(np.asarray(R, float)) if np.ndim(R) == 1 else np.asarray(R, float)
    if Q.shape != (nx, nx) or R.shape != (nu_, nu_):
        raise InputError(f"LQR weights Q {Q.shape}, R {R.shape}; expected Q ({nx}, {nx}) and R ({nu_}, {nu_})")
    try:
        X = scipy.linalg.solve_continuous_are(model.A, model.B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise InputError(f"no stabilising LQR solution for states {', '.join(model.states)} ({exc}); expected a "
                         "stabilisable model: keep only the states the motors reach (LinearModel.restrict)") from None
    K = np.linalg.solve(R, model.B.T @ X)
    closed = np.linalg.eigvals(model.A - model.B @ K)
    if not np.all(closed.real < 0):
        raise InputError(f"the LQR closed loop is not stable (largest real part {closed.real.max():.3g} 1/s) for "
                         f"states {', '.join(model.states)}; expected a stabilisable model (LinearModel.restrict)")
    return K, closed[np.lexsort((closed.imag, closed.real))]


def lqr_torque(model: LinearModel, K: np.ndarray):
    """A torque law ``tau(t, q, nu) = tau0 - K (x(q, nu) - x0)`` for :func:`robotdyn.simulation.engine.simulate`.

    Args:
        model: The linear model the gain was computed for (its ``x0``, ``tau0`` and :meth:`LinearModel.state`).
        K: The gain (n_motors, n_x), e.g. from :func:`lqr`.

    Returns:
        The callable ``torque(t, q, nu)`` -> (n_motors,) [N m or N] (t [s], q (n,), nu (k,)).
    """
    x0, tau0 = model.x0.copy(), model.tau0.copy()

    def torque(t: float, q: np.ndarray, nu: np.ndarray) -> np.ndarray:
        return tau0 - K @ (model.state(q, nu) - x0)

    return torque


__all__ = ["LinearModel", "linearize", "lqr", "lqr_torque"]

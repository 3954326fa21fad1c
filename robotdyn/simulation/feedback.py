"""Feedback laws as data: closed loops that the compiled integrator evaluates without returning to Python.

A :class:`FeedbackLaw` is the torque law

.. math:: \\tau = f(t) + K_q\\,(q_d(t) - q) + K_\\nu\\,(\\nu_d(t) - \\nu) + B_r^+\\,(M_r\\,a(t) + h)

on the natural coordinates q (n) and the independent velocities :math:`\\nu` (k), with :math:`f` (motors),
:math:`q_d` (n), :math:`\\nu_d` (k) and :math:`a` (k) profiles of time
(:class:`~robotdyn.simulation.torque_profile.TorqueProfile` terms: constants, windowed sines, tables, windowed
polynomials; their "motors" is here the width of the vector), :math:`K_q` (motors, n) and :math:`K_\\nu`
(motors, k) constant gains, and in the last term the reduced model at the state (:math:`M_r\\dot\\nu + h =
B_r\\tau`, :mod:`robotdyn.reduction.reduced_dynamics`) with :math:`B_r^+` its minimum-norm least-squares inverse
(``numpy.linalg.lstsq``): the computed torque (inverse dynamics) that gives the accelerations :math:`a(t)` where the
motors can. Every term is optional. It covers PD tracking of coordinates and velocities, an LQR
:math:`\\tau_0 - K(x - x_0)` (:func:`lqr_law`, the data form of
:func:`robotdyn.reduction.linearization.lqr_torque`) and computed-torque feed-forward.

The law is a Python callable ``tau(t, q, nu)`` (the scipy engine's reference, :meth:`FeedbackLaw.__call__`) and
encodes itself for the C++ twin ``robotdyn/_controller.hpp`` (:meth:`FeedbackLaw.native`), which the compiled
engine (:mod:`robotdyn.simulation.compiled_engine`) evaluates at every step on the reduced model it has just
computed. The same torques to rounding (``tests/test_feedback.py``: 1e-12 at random states). Model-based laws that are
not of this form (:class:`~robotdyn.simulation.control.LinearisingController`'s task-space feedback, any Python
function) stay Python callables on the scipy engine.

Units: SI (m, rad, s, N, N m).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .torque_profile import TorqueProfile


def native_profile(p: TorqueProfile):
    """The C++ object of a profile (``robotdyn._compiled.TorqueProfile``), as
    :func:`robotdyn.simulation.compiled_engine.native_profile`.

    Args:
        p: The :class:`~robotdyn.simulation.torque_profile.TorqueProfile` (any width).

    Returns:
        The ``robotdyn._compiled.TorqueProfile`` with the same terms.
    """
    from .._compiled import TorqueProfile as Native

    kinds, coefs, pars = p.encode()
    return Native(p.motors, kinds, [np.atleast_2d(c) for c in coefs], [q.tolist() for q in pars])


def _gain(K, what: str) -> np.ndarray | None:
    if K is None:
        return None
    K = np.asarray(K, dtype=float)
    if K.ndim != 2 or K.size == 0 or not np.all(np.isfinite(K)):
        raise InputError(f"feedback law: {what} of shape {K.shape}; expected a finite (motors, columns) matrix")
    return K


def _profile(p, what: str) -> TorqueProfile | None:
    if p is not None and not isinstance(p, TorqueProfile):
        raise InputError(f"feedback law: {what} must be a TorqueProfile (constant, sine, table, polynomial terms)")
    return p


class FeedbackLaw:
    """The torque law of the module docstring. Its dimensions (motors, n, k) are checked against a robot by
    :meth:`check` (the simulation does); ``robot`` is only needed for calling a law with ``acceleration`` from
    Python (its reduced model).

    Args:
        feedforward: f(t), (motors,) [N m or N] (default none).
        Kq: K_q (motors, n) [N m / m or N m / rad] (default none).
        q_ref: q_d(t), (n,) [m, rad] (default zero; needs ``Kq``).
        Knu: K_nu (motors, k) [N m s / rad, ...] (default none).
        nu_ref: nu_d(t), (k,) [m/s, rad/s] (default zero; needs ``Knu``).
        acceleration: a(t), (k,) [m/s^2, rad/s^2]: computed torque B_r^+ (M_r a + h) (default none).
        robot: The :class:`~robotdyn.robot.Robot` whose reduced model ``__call__`` uses (default none; the
            simulation binds the robot it runs, :meth:`bound`).

    Raises:
        InputError: A gain or a profile of inconsistent shape, or a reference without its gain.
    """

    def __init__(self, feedforward: TorqueProfile | None = None, Kq=None, q_ref: TorqueProfile | None = None,
                 Knu=None, nu_ref: TorqueProfile | None = None, acceleration: TorqueProfile | None = None,
                 robot=None) -> None:
        self.feedforward = _profile(feedforward, "the feed-forward torque")
        self.Kq, self.Knu = _gain(Kq, "K_q"), _gain(Knu, "K_nu")
        self.q_ref = _profile(q_ref, "the coordinate reference")
        self.nu_ref = _profile(nu_ref, "the velocity reference")
        self.acceleration = _profile(acceleration, "the reference acceleration")
        self.robot = robot
        if self.q_ref is not None and self.Kq is None:
            raise InputError("feedback law: a coordinate reference q_ref without its gain Kq")
        if self.nu_ref is not None and self.Knu is None:
            raise InputError("feedback law: a velocity reference nu_ref without its gain Knu")
        rows = {what: m for what, m in (("the feed-forward torque", self.feedforward and self.feedforward.motors),
                                        ("K_q", None if self.Kq is None else self.Kq.shape[0]),
                                        ("K_nu", None if self.Knu is None else self.Knu.shape[0])) if m}
        if len(set(rows.values())) > 1:
            raise InputError(f"feedback law: motors differ between terms ({rows})")
        for ref, K, what in ((self.q_ref, self.Kq, "q_ref"), (self.nu_ref, self.Knu, "nu_ref")):
            if ref is not None and ref.motors != K.shape[1]:
                raise InputError(f"feedback law: {what} has {ref.motors} values; its gain has {K.shape[1]} columns")

    def check(self, robot) -> None:
        """Raise a one-line :class:`~robotdyn.errors.InputError` unless the law fits ``robot`` (motors, n, k).

        Args:
            robot: The :class:`~robotdyn.robot.Robot`.
        """
        m, n, k = len(robot.motors), robot.nq, robot.mobility
        for what, got, want in (("feed-forward torques", self.feedforward and self.feedforward.motors, m),
                                ("K_q", None if self.Kq is None else self.Kq.shape, (m, n)),
                                ("K_nu", None if self.Knu is None else self.Knu.shape, (m, k)),
                                ("reference accelerations", self.acceleration and self.acceleration.motors, k)):
            if got is not None and got != want:
                raise InputError(f"feedback law: {what} of size {got}; the robot {robot.spec.name!r} expects {want} "
                                 f"({m} motors, {n} coordinates, {k} independent velocities)")

    def bound(self, robot) -> FeedbackLaw:
        """This law (checked) with ``robot`` as the model of its computed-torque term.

        Args:
            robot: The :class:`~robotdyn.robot.Robot`.

        Returns:
            This law if its robot is ``robot``, else a shallow copy bound to ``robot``.
        """
        self.check(robot)
        if self.robot is robot:
            return self
        import copy

        out = copy.copy(self)
        out.robot = robot
        return out

    def torque(self, t: float, q: np.ndarray, nu: np.ndarray, M: np.ndarray | None = None,
               h: np.ndarray | None = None, B: np.ndarray | None = None) -> np.ndarray:
        """The motor torques at (t, q, nu) given the reduced model there (M_r, h, B_r; only needed with
        ``acceleration``), in the C++ twin's order of operations.

        Args:
            t: Time [s].
            q: Natural coordinates (n,) [m, rad].
            nu: Independent velocities (k,) [m/s, rad/s].
            M, h, B: M_r (k, k), h (k,), B_r (k, motors) at (q, nu).

        Returns:
            (motors,) [N m or N].
        """
        motors = (self.feedforward.motors if self.feedforward is not None else self.Kq.shape[0] if self.Kq is not None
                  else self.Knu.shape[0] if self.Knu is not None else B.shape[1])
        out = np.zeros(motors)
        if self.feedforward is not None:
            out = out + self.feedforward(t)
        if self.Kq is not None:
            e = (self.q_ref(t) if self.q_ref is not None else np.zeros(self.Kq.shape[1])) - q
            out = out + self.Kq @ e
        if self.Knu is not None:
            e = (self.nu_ref(t) if self.nu_ref is not None else np.zeros(self.Knu.shape[1])) - nu
            out = out + self.Knu @ e
        if self.acceleration is not None:
            out = out + np.linalg.lstsq(B, M @ self.acceleration(t) + h, rcond=None)[0]
        return out

    def __call__(self, t: float, q: np.ndarray, nu: np.ndarray) -> np.ndarray:
        """tau(t, q, nu) [N m or N] (the scipy engine's signature; the reduced model from the robot)."""
        if self.acceleration is None:
            return self.torque(t, q, nu)
        if self.robot is None:
            raise InputError("feedback law: the computed-torque term needs a robot (FeedbackLaw(..., robot=) or .bound)")
        red = self.robot.reduced(q, nu)
        return self.torque(t, q, nu, red.M, red.h, red.B)

    def breakpoints(self) -> np.ndarray:
        """Sorted times [s] where a profile of the law is not smooth (both engines restart there).

        Returns:
            The breakpoint times (b,) [s], ascending, those a few doubles apart merged into one.
        """
        points = set()
        for p in (self.feedforward, self.q_ref, self.nu_ref, self.acceleration):
            if p is not None:
                points.update(map(float, p.breakpoints()))
        out = []
        for b in sorted(points):  # one breakpoint for windows that meet a few doubles apart (no 1-ulp steps)
            if not out or b - out[-1] > 16 * np.finfo(float).eps * max(1.0, abs(b)):
                out.append(b)
        return np.array(out, float)

    def native(self, robot):
        """The C++ twin (``robotdyn._compiled.Controller``, ``robotdyn/_controller.hpp``) for ``robot``.

        Args:
            robot: The :class:`~robotdyn.robot.Robot` (its dimensions; checked).

        Returns:
            The ``robotdyn._compiled.Controller`` of this law.
        """
        self.check(robot)
        from .._compiled import Controller

        nat = lambda p: None if p is None else native_profile(p)  # noqa: E731
        empty = np.zeros((0, 0))
        return Controller(len(robot.motors), robot.nq, robot.mobility, nat(self.feedforward),
                          empty if self.Kq is None else self.Kq, nat(self.q_ref),
                          empty if self.Knu is None else self.Knu, nat(self.nu_ref), nat(self.acceleration))

    def native_controller(self, robot, fast=None):
        """:meth:`native` (the compiled engine's entry point for every law given as data).

        Args:
            robot: The :class:`~robotdyn.robot.Robot`.
            fast: Its compiled model (unused).

        Returns:
            The ``robotdyn._compiled.Controller`` of this law (:meth:`native`).
        """
        return self.native(robot)

    def compiled_form(self) -> bool:
        """Whether the compiled engine can run this law.

        Returns:
            Always True: every feedback law runs on the compiled engine.
        """
        return True

    def __repr__(self) -> str:
        parts = [name for name, v in (("feedforward", self.feedforward), ("Kq", self.Kq), ("Knu", self.Knu),
                                      ("acceleration", self.acceleration)) if v is not None]
        return f"FeedbackLaw({', '.join(parts) or 'zero'})"


def lqr_law(model, K) -> FeedbackLaw:
    """The LQR torque law ``tau(t, q, nu) = tau0 - K (x(q, nu) - x0)`` of
    :func:`robotdyn.reduction.linearization.lqr_torque` as a :class:`FeedbackLaw` (it runs on the compiled engine):
    the gain's columns placed on the coordinates and velocities that the model's states are, its operating state
    as the references, its operating torques as the feed-forward.

    Args:
        model: The :class:`~robotdyn.reduction.linearization.LinearModel` (states, operating point and torques).
        K: The gain (n_motors, n_x) (e.g. from :func:`robotdyn.reduction.linearization.lqr`).

    Returns:
        The :class:`FeedbackLaw` (motor torques [N m or N] from the state).

    Raises:
        InputError: A gain of another shape.
    """
    from .torque_profile import Constant

    K = np.asarray(K, float)
    m, npos = len(model.tau0), len(model.position_index)
    if K.shape != (m, len(model.x0)) or not np.all(np.isfinite(K)):
        raise InputError(f"LQR gain of shape {K.shape}; expected finite ({m}, {len(model.x0)}) (motors, states)")
    n, k = len(model.q0), len(model.velocities)
    vel = np.array([model.velocities.index(s) for s in model.states[npos:]], dtype=int)
    Kq, Knu = np.zeros((m, n)), np.zeros((m, k))
    q_ref, nu_ref = np.zeros(n), np.zeros(k)
    Kq[:, model.position_index], q_ref[model.position_index] = K[:, :npos], model.x0[:npos]
    Knu[:, vel], nu_ref[vel] = K[:, npos:], model.x0[npos:]
    return FeedbackLaw(feedforward=Constant(model.tau0), Kq=Kq, q_ref=Constant(q_ref), Knu=Knu,
                       nu_ref=Constant(nu_ref))


__all__ = ["FeedbackLaw", "lqr_law"]

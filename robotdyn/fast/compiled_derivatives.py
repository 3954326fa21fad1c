"""Derivatives of the reduced forward dynamics on the compiled path: the fast twin of
:func:`robotdyn.reduction.dynamics_derivatives.dynamics_derivatives`.

The C++ kernels (``robotdyn/kernels/*_derivatives.hpp``: one per constraint kind, and
``reduced_dynamics_derivatives.hpp`` for the projection's chain rule and the reduced solve) evaluate the same
formulas as the Python reference on Pinocchio's own C++ derivative algorithms (``computeRNEADerivatives``,
``getFrameJacobianTimeVariation``, ``getFrameVelocityDerivatives``, and the steps of
``computeForwardKinematicsDerivatives`` and of the joint velocity and acceleration derivatives, taken on the compiled
evaluation's own kinematics where it already holds them) and on the compiled model's configuration pass
(:class:`~robotdyn.fast.compiled.CompiledModel`): one call gives :math:`\\dot\\nu`, :math:`\\partial\\dot\\nu/\\partial q`
(natural coordinates), :math:`\\partial\\dot\\nu/\\partial\\nu`, :math:`\\partial\\dot\\nu/\\partial\\tau`,
:math:`\\dot q = S\\nu`, :math:`\\partial(S\\nu)/\\partial q`, S and the constraint rows A (from which the independent
position coordinates and the tangent of the holonomic manifold are chosen here, as the Python path does).

It serves what the compiled model serves (:func:`robotdyn.fast.compiled.why_not`): rolling wheels on the compiled
terrains (whose third derivatives are closed forms, so every piece is analytic), loop closures and cosine-law joint
couplings, with independent velocities that are a selection of v or a frame's twist (operational-space velocities,
``kernels/operational_space_derivatives.hpp``), joint springs and dampers (their joint-diagonal terms in the tree's
residual and the reduced solve, ``kernels/joint_springs_derivatives.hpp``, as
:func:`~robotdyn.reduction.joint_springs.spring_terms` enters the Python reference), and wheels slipping under the
compiled friction laws (regularised Coulomb, the linear tyre: ``kernels/sliding_derivatives.hpp``, the twin of
:func:`robotdyn.contact.sliding_derivatives.sliding_derivatives`). The Python path answers (:func:`compiled_derivatives`
returns ``None``) where the compiled model does not serve, where it simulates the slipping wheels on the Python path
(its ``slip_refusal``: e.g. statically indeterminate loads, or joint springs beside them), and at any state where
the compiled evaluation falls back (a projection that must be re-chosen, a wheel lying flat, a singular slipping contact problem: the Python path
raises its error there). ``tests/test_compiled_derivatives.py`` checks every output against the Python path on every
built-in robot, ``tests/test_compiled_opspace_slip_derivatives.py`` the operational and slipping ones.
"""

from __future__ import annotations

import threading

import numpy as np

from ..errors import NonFiniteError
from ..reduction.dynamics_derivatives import DynamicsDerivatives, position_coordinates
from .compiled import Fallback
from .dispatch import compiled_model

_NAMES = ("nudot", "dq", "dnu", "dtau", "qdot", "dqdot_dq")  # the outputs of Evaluator.derivatives_checked, in order
_CHECKED = 0b101111  # the bits of the outputs compiled_derivatives tests (all but qdot)


_MANIFOLD_LOCK = threading.Lock()
"""Held while a :class:`_CompiledDerivatives` chooses its manifold coordinates (see there)."""


class _CompiledDerivatives(DynamicsDerivatives):
    """A :class:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives` whose manifold coordinates
    (``positions``, ``tangent``, ``dq_manifold``: a pivoted QR of the holonomic rows) are chosen on first access, as
    the Python path chooses them: a trajectory optimiser or a linearisation in natural coordinates never pays for
    them. One result may be read from several threads at once: the three are chosen under a lock and stored
    together before the inputs are dropped (before, a thread reading one of them while another was choosing them
    got an AttributeError: ``tests/test_threads_derivatives.py``)."""

    def __getattr__(self, name: str):
        if name in ("positions", "tangent", "dq_manifold"):
            with _MANIFOLD_LOCK:
                found = self.__dict__
                if name not in found and "_manifold" in found:
                    A, holonomic, prefer = found["_manifold"]  # (the holonomic rows picked here, on demand)
                    positions, T = position_coordinates(A[np.asarray(holonomic, bool)], prefer)
                    found.update(positions=positions, tangent=T, dq_manifold=self.dq @ T)
                    del found["_manifold"]
                if name in found:
                    return found[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


def compiled_derivatives(robot, q: np.ndarray, nu: np.ndarray, tau: np.ndarray) -> DynamicsDerivatives | None:
    """:math:`\\dot\\nu` and its derivatives at one state by the robot's compiled model, or ``None`` where the
    Python path must answer (no compiled model, slipping wheels it does not simulate, a compiled fallback).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], already checked (``robot.check_q``).
        nu: Independent velocities (k,) [m/s, rad/s] in the order of ``robot.velocity_names``, already checked.
        tau: Motor torques/forces (n_motors,) [N m or N] in the order of ``robot.motors``, already checked.

    Returns:
        The :class:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives` (the same contents as the Python
        path's, ``numerical`` empty), or ``None``.

    Raises:
        NonFiniteError: A non-finite result (as the Python path).
    """
    fast = compiled_model(robot)
    if fast is None or fast.slip_refusal is not None \
            or not hasattr(fast.ev, "derivatives_checked"):  # (an extension built before it)
        return None
    if not fast.ready:
        fast._choose(q, nu)
    try:  # (the finiteness tested in C++ where the outputs were just written: bit i for output i)
        nudot, dq, dnu, dtau, v, Vq, S, A, bad = fast.ev.derivatives_checked(q, nu, tau)
    except Fallback:
        return None
    bad &= _CHECKED  # (qdot = S nu is not among the tested outputs)
    if bad:
        name = _NAMES[(bad & -bad).bit_length() - 1]  # the first one
        raise NonFiniteError(f"dynamics derivatives: {name} is not finite at this state (|q| up to "
                             f"{np.max(np.abs(q)):.3g}, |nu| up to {np.max(np.abs(nu), initial=0):.3g})")
    out = _CompiledDerivatives.__new__(_CompiledDerivatives)
    out.__dict__.update(nudot=nudot, dq=dq, dnu=dnu, dtau=dtau, qdot=v, dqdot_dq=Vq, S=S, numerical=(),
                        coordinates=list(robot.coordinates), velocities=list(robot.velocity_names),
                        motors=[m.name for m in robot.motors],
                        _manifold=(A, fast.holonomic,
                                   None if fast.operational is not None else fast._hint.dependent))
    return out


def raw_derivatives(fast, q: np.ndarray, nu: np.ndarray, tau: np.ndarray) -> tuple | None:
    """The compiled derivative set at one state without the API's checks and wrapping, for a caller that evaluates
    many states of one robot (a trajectory optimiser's Jacobian): ``(nudot, dq, dnu, dtau, qdot, dqdot_dq, S, A)``
    as in :func:`compiled_derivatives`, or ``None`` where the Python path must answer (including a non-finite
    result, whose error that path raises).

    Args:
        fast: The robot's :class:`~robotdyn.fast.compiled.CompiledModel` (:func:`robotdyn.fast.dispatch.compiled_model`),
            its projection chosen (``fast.ready``).
        q: Natural coordinates (n,) [m, rad], valid (unchecked here).
        nu: Independent velocities (k,) [m/s, rad/s], valid.
        tau: Motor torques/forces (n_motors,) [N m or N], valid.

    Returns:
        The tuple of arrays, or ``None``.
    """
    if fast.slip_refusal is not None or not hasattr(fast.ev, "derivatives_checked") or not fast.ready:
        return None
    try:
        out = fast.ev.derivatives_checked(q, nu, tau)
    except Fallback:
        return None
    return None if out[8] else out[:8]  # (out[8]: the bits of the non-finite outputs)


__all__ = ["compiled_derivatives", "raw_derivatives"]

"""Derivatives of the wheel contact forces and of the required mu on the compiled path: the fast twin of
:func:`robotdyn.contact.force_derivatives.contact_force_derivatives`.

The C++ kernel ``robotdyn/kernels/contact_forces_derivatives.hpp`` evaluates the Python reference's layer 1 (the
multipliers at known motion and their partial derivatives: the KKT system of the force model with the rigid limit
of compliance and its active set, the projector onto what stays open and its derivative) with the same formulas,
on Pinocchio's ``computeRNEADerivatives`` and ``computeForwardKinematicsDerivatives`` (one frame pass per
coordinate for :math:`\\partial A/\\partial q`), and hands over, with the compiled dynamics derivatives
(``reduced_dynamics_derivatives.hpp``), the projection's two chain pieces (:math:`\\partial a/\\partial q` at fixed
:math:`\\dot\\nu` and :math:`\\partial w/\\partial\\nu`). The structure the derivatives follow (the reported forces,
the rigid limit's unloaded wheels, a planar model's floating twin) and layer 2 (the chain along the motion, the
wheel forces, the required mu) are the Python reference's own functions
(:func:`~robotdyn.contact.force_derivatives.structure`, :func:`~robotdyn.contact.force_derivatives.along_motion`),
so both paths report the same numbers through the same code where it is cheap.

It serves where the compiled dynamics derivatives serve (:mod:`robotdyn.fast.compiled_derivatives`: rolling wheels,
loop closures, couplings; for a planar model also its floating twin's compiled model); operational-space
velocities, slipping wheels and any compiled fallback return ``None`` and the Python path answers.
``tests/test_compiled_force_derivatives.py`` holds both paths equal.
"""

from __future__ import annotations

import weakref

import numpy as np

from ..fast.compiled import Fallback
from ..fast.compiled_derivatives import _CompiledDerivatives
from ..fast.dispatch import compiled_model

_LAYOUT: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
"""Per robot (or floating twin): its row labels, wheel entries (rows, directions) and normal stiffnesses."""


def _serves(fast) -> bool:
    """Whether the compiled model ``fast`` can give force derivatives (built with them, no operational velocities,
    no slipping wheels)."""
    return fast is not None and fast.operational is None and not getattr(fast.ev, "slipping", 0) \
        and hasattr(fast.ev, "force_layer")


def _layout(target, fast, stiffness_robot) -> tuple:
    """``(labels, wheels, k)`` of ``target``'s compiled rows: the row labels (the compiled model's, in the Python
    path's order), per wheel the :func:`~robotdyn.contact.force_derivatives.layer` entry (name, rows, directions,
    no friction) in the compiled wheel order, and the wheels' normal stiffnesses from ``stiffness_robot`` [N/m]."""
    key = (id(fast), id(stiffness_robot))
    cached = _LAYOUT.get(target)
    if cached is not None and cached[0] == key:
        return cached[1]
    from .compliance import wheel_stiffness

    labels = list(fast.labels)
    index = {lab: i for i, lab in enumerate(labels)}
    wheels = [{"name": c.name, "rows": np.array([index[lab] for lab in c._labels()], int),
               "D": np.asarray(c._directions, float), "fr": None} for c in fast.wheels]
    k = np.asarray(wheel_stiffness(stiffness_robot, [w["name"] for w in wheels]), float)
    out = (labels, wheels, k)
    _LAYOUT[target] = (key, out)
    return out


def compiled_force_derivatives(robot, q: np.ndarray, nu: np.ndarray, tau: np.ndarray
                               ) -> object | None:
    """The wheel contact forces, the required mu and their derivatives by the robot's compiled model, or ``None``
    where the Python path must answer (no compiled model, operational-space velocities, slipping wheels, a compiled
    fallback).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], already checked
            (:func:`robotdyn.contact.force_derivatives.checked`).
        nu: Independent velocities (k,) [m/s, rad/s] in the order of ``robot.velocity_names``, already checked.
        tau: Motor torques/forces (n_motors,) [N m or N] in the order of ``robot.motors``, already checked.

    Returns:
        The :class:`~robotdyn.contact.force_derivatives.ContactForceDerivatives` (the same contents as the Python
        path's, ``numerical`` empty), or ``None``.

    Raises:
        InputError: The multipliers differentiated are not those of the reported forces (as the Python path).
        NonFiniteError: A non-finite result (as the Python path).
    """
    from .contact_forces import floating_twin  # (the contact layer above: imported at call time)
    from .force_derivatives import _Layer, along_motion, structure
    from .sliding import sliding_now

    fast = compiled_model(robot)
    if not _serves(fast) or sliding_now(robot):
        return None
    if not fast.ready:
        fast._choose(q, nu)
    forces, unloaded, twin = structure(robot, q, nu, tau)
    if twin:
        target, index = floating_twin(robot)
        tfast = compiled_model(target)
        if not _serves(tfast):
            return None
    else:
        target, tfast = robot, fast
    try:
        (nudot, dq, dnu, dtau, v, Vq, S, A, a, Aq, Wnu) = fast.ev.force_chain(q, nu, tau)
        labels, wheels, k = _layout(target, tfast, robot)
        names = [w["name"] for w in wheels]
        drop = [names.index(u) for u in unloaded]
        if twin:
            def lift(x):
                out = np.zeros(target.nq)
                out[index] = x
                return out

            at = (lift(q), lift(v), lift(a))
        else:
            at = (q, v, a)
        if not tfast.ready:
            tfast._choose(at[0], np.zeros(target.mobility))
        lam, Lq, Lv, La, Lt, residual = tfast.ev.force_layer(*at, tau, k, drop, True)
    except Fallback:
        return None
    if not all(np.all(np.isfinite(x)) for x in (nudot, dq, dnu, dtau, Vq, Aq, Wnu)):
        return None  # (the Python path raises its own error)
    D = _CompiledDerivatives.__new__(_CompiledDerivatives)
    D.__dict__.update(nudot=nudot, dq=dq, dnu=dnu, dtau=dtau, qdot=v, dqdot_dq=Vq, S=S, numerical=(),
                      coordinates=list(robot.coordinates), velocities=list(robot.velocity_names),
                      motors=[m.name for m in robot.motors],
                      _manifold=(A, fast.holonomic, fast._hint.dependent))
    lay = _Layer(labels, lam, Lq, Lv, La, Lt, wheels, float(residual), set())
    return along_motion(robot, q, nu, tau, forces, unloaded, twin, lay, D, Vq, S, Aq + S @ dq, Wnu + S @ dnu,
                        S @ dtau)


__all__ = ["compiled_force_derivatives"]

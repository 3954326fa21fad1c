"""Full-coordinate rigid-body dynamics from Pinocchio.

For the unconstrained tree in natural coordinates: :math:`M(q)\\dot v + C(q, v) v + g(q) = \\tau`, with
M from CRBA, C from Pinocchio's Coriolis matrix (Christoffel-consistent, so :math:`\\dot M - 2C` is
skew-symmetric) and g the generalised gravity. Units: SI, generalised forces in N or N m.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin


def mass_matrix(model: pin.Model, data: pin.Data, q: np.ndarray) -> np.ndarray:
    """:math:`M(q)` (nv x nv, symmetric) by CRBA.

    Args:
        model: The Pinocchio model (natural coordinates: nq == nv).
        data: Its Pinocchio data (overwritten).
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.

    Returns:
        M (nv, nv), a copy, in the model's velocity order.
    """
    return pin.crba(model, data, q).copy()


def coriolis_matrix(model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """:math:`C(q, v)` with :math:`C v` the Coriolis and centrifugal forces.

    Args:
        model: The Pinocchio model (natural coordinates: nq == nv).
        data: Its Pinocchio data (overwritten).
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        v: Full velocities (n,) [m/s, rad/s].

    Returns:
        C (nv, nv), a copy.
    """
    return pin.computeCoriolisMatrix(model, data, q, v).copy()


def gravity(model: pin.Model, data: pin.Data, q: np.ndarray) -> np.ndarray:
    """:math:`g(q)`, the generalised gravity forces (positive opposes lifting).

    Args:
        model: The Pinocchio model (natural coordinates: nq == nv).
        data: Its Pinocchio data (overwritten).
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.

    Returns:
        g (nv,) [N or N m], a copy.
    """
    return pin.computeGeneralizedGravity(model, data, q).copy()


def inverse_dynamics(model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """:math:`\\tau = M a + C v + g` by RNEA.

    Args:
        model: The Pinocchio model (natural coordinates: nq == nv).
        data: Its Pinocchio data (overwritten).
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        v: Full velocities (n,) [m/s, rad/s].
        a: Full accelerations (n,) [m/s^2, rad/s^2].

    Returns:
        :math:`\\tau` (nv,) [N or N m], a copy.
    """
    return pin.rnea(model, data, q, v, a).copy()


def energy(model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """Kinetic and potential energy [J] (potential relative to z = 0, gravity of the model).

    Args:
        model: The Pinocchio model (natural coordinates: nq == nv).
        data: Its Pinocchio data (overwritten).
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        v: Full velocities (n,) [m/s, rad/s].

    Returns:
        ``(kinetic, potential)`` [J], two floats.
    """
    kinetic = pin.computeKineticEnergy(model, data, q, v)
    potential = pin.computePotentialEnergy(model, data, q)
    return float(kinetic), float(potential)

"""Rolling without slipping of a wheel on a terrain z = f(x, y).

A wheel is a thin disc of radius R whose centre is the origin of a frame of the model and whose axle is a unit
vector ``axis`` in that frame. With terrain normal n at the contact point p and axle a (world):

- :math:`u = (n - (n\\cdot a)a) / \\|n - (n\\cdot a)a\\|` points from p to the centre c, :math:`p = c - R u`,
  with n taken at p itself (a fixed point on curved terrain);
- the material point of the wheel at p has zero velocity:
  :math:`A_w v = v_c + \\omega \\times (p - c) - u \\dot R = 0` (world rows),
  expressed in the contact frame (t1 = rolling direction :math:`a \\times n` normalised, t2 = :math:`n \\times t_1`,
  n): the t1 and t2 rows are nonholonomic, the n row is the derivative of the holonomic contact condition
  :math:`\\phi = (p_z - f(p_x, p_y)) / \\|(-f_x, -f_y, 1)\\|`;
- the time derivative follows the contact point as it moves around the rim (not a body-fixed point):
  :math:`\\dot A_w v = a_c^0 + \\dot\\omega^0 \\times r + \\omega \\times \\dot r - \\dot u \\dot R`,
  :math:`r = p - c`, :math:`\\dot r = -(R\\dot u + \\dot R u)`, with :math:`\\dot u` from a 3x3 implicit solve on
  curved terrain (see the concepts page, ``docs/concepts.md``).

An omni (Swedish) wheel keeps the normal row and one tangential row along its rollers' axis, at ``roller_angle``
from t1 towards t2 (0 for a 90-degree omni wheel whose rollers leave the lateral motion free).
"""

from __future__ import annotations

import math

import numpy as np

from .constraint import Constraint, ConstraintRows, KinematicState, cross, skew
from ..errors import ConstraintError, DescriptionError
from .terrain import FlatTerrain, Terrain


class RollingWheel(Constraint):
    """A standard wheel rolling without slipping (three rows: longitudinal, lateral, normal).

    Args:
        description: The robot's :class:`~robotdyn.description.urdf.Description`.
        frame: Frame (link) whose origin is the wheel centre.
        radius: Wheel radius R [m] (> 0); with ``radius_joint`` the radius is ``radius + q[radius_joint]``.
        axis: Axle direction in the wheel frame (normalised here).
        terrain: The ground (default: the plane z = 0).
        radius_joint: Optional prismatic joint whose coordinate adds to the radius (adaptable wheels).
        name: Name used in row labels and messages (default: the frame name).
    """

    _directions = np.eye(3)
    _row_names = ("longitudinal", "lateral", "normal")

    def __init__(
        self,
        description,
        frame: str,
        radius: float,
        axis=(0.0, 1.0, 0.0),
        terrain: Terrain | None = None,
        radius_joint: str | None = None,
        name: str | None = None,
    ) -> None:
        self.frame = frame
        self.fid = description.frame_id(frame)
        self.nv = description.model.nv
        radius = float(radius)
        if not np.isfinite(radius) or (radius <= 0 and radius_joint is None):
            raise DescriptionError(f"wheel {frame!r}: radius {radius} is not > 0; expected a positive radius in m")
        self.radius = radius
        axis = np.asarray(axis, dtype=float)
        if axis.shape != (3,) or not np.all(np.isfinite(axis)) or np.linalg.norm(axis) < 1e-12:
            raise DescriptionError(f"wheel {frame!r}: axle axis {axis.tolist()} has zero length; expected a 3-vector")
        self.axis = axis / np.linalg.norm(axis)
        self.terrain = terrain if terrain is not None else FlatTerrain()
        self.radius_index = None if radius_joint is None else description.q_index(radius_joint)
        self.name = name or frame

    def __repr__(self) -> str:
        return f"{type(self).__name__}(frame={self.frame!r}, radius={self.radius}, terrain={self.terrain!r})"

    def _geometry(self, kin: KinematicState) -> tuple:
        """Configuration-level contact geometry (cached in ``kin.geometry``): c, a, R, n, u, p, |w|, phi, N."""
        key = (id(self), "geometry")
        if key in kin.geometry:
            return kin.geometry[key]
        placement, _ = kin.pose(self.fid)
        c = placement.translation
        a = placement.rotation @ self.axis
        R = self.radius
        if self.radius_index is not None:
            R += kin.q[self.radius_index]
            if R <= 0:
                raise ConstraintError(f"wheel {self.name!r}: radius {R:.6g} m is not positive at this configuration")
        terrain = self.terrain
        flat = terrain.is_flat
        # the fixed-point iteration on 3-vectors in Python floats (cheaper than numpy calls on 3-vectors)
        a0, a1, a2 = a.tolist()
        c0, c1_, c2 = c.tolist()
        Rf = float(R)
        n0, n1, n2 = terrain.normal(c0, c1_).tolist()
        for _ in range(100):
            na = n0 * a0 + n1 * a1 + n2 * a2
            w0, w1, w2 = n0 - na * a0, n1 - na * a1, n2 - na * a2
            nw = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
            if nw < 1e-9:
                raise ConstraintError(
                    f"wheel {self.name!r}: the axle is parallel to the ground normal (wheel lying flat); "
                    "expected a wheel standing on the terrain"
                )
            u0, u1, u2 = w0 / nw, w1 / nw, w2 / nw
            p0, p1, p2 = c0 - Rf * u0, c1_ - Rf * u1, c2 - Rf * u2
            if flat:
                break
            m0, m1, m2 = terrain.normal(p0, p1).tolist()
            d0, d1, d2 = m0 - n0, m1 - n1, m2 - n2
            n0, n1, n2 = m0, m1, m2
            if d0 * d0 + d1 * d1 + d2 * d2 < 1e-30:
                na = n0 * a0 + n1 * a1 + n2 * a2
                w0, w1, w2 = n0 - na * a0, n1 - na * a1, n2 - na * a2
                nw = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
                u0, u1, u2 = w0 / nw, w1 / nw, w2 / nw
                p0, p1, p2 = c0 - Rf * u0, c1_ - Rf * u1, c2 - Rf * u2
                break
        else:
            raise ConstraintError(
                f"wheel {self.name!r}: the contact point did not converge; the terrain is curved more sharply "
                "than the wheel (expected terrain curvature radius > wheel radius)"
            )
        n, u, p = np.array([n0, n1, n2]), np.array([u0, u1, u2]), np.array([p0, p1, p2])
        grad = terrain.gradient(p[0], p[1])
        phi = (p[2] - terrain.height(p[0], p[1])) / np.sqrt(1.0 + grad @ grad)
        N = None if terrain.is_flat else terrain.normal_derivative(p[0], p[1])
        k0, k1, k2 = a1 * n2 - a2 * n1, a2 * n0 - a0 * n2, a0 * n1 - a1 * n0  # a x n
        nc1 = math.sqrt(k0 * k0 + k1 * k1 + k2 * k2)
        t0, t1, t2 = k0 / nc1, k1 / nc1, k2 / nc1
        E = np.array([[t0, n1 * t2 - n2 * t1, n0], [t1, n2 * t0 - n0 * t2, n1], [t2, n0 * t1 - n1 * t0, n2]])
        out = (c, a, R, n, u, p, nw, phi, N, E, nc1)
        kin.geometry[key] = out
        return out

    def contact(self, kin: KinematicState) -> dict:
        """Contact geometry and its rates at the state of ``kin`` (world frame).

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            dict with ``p`` (contact point), ``n`` (normal), ``u`` (unit vector contact -> centre), ``R``,
            ``E`` (3x3, columns t1, t2, n), ``Edot``, ``r`` (p - c), ``rdot``, ``udot``, ``a`` (axle),
            ``phi`` (holonomic residual [m]), and the frame Jacobian ``J`` and ``dJ``.

        Raises:
            ConstraintError: The axle is parallel to the ground normal, the contact point does not converge on a
                curved terrain, or an adaptable radius is not positive.
        """
        c, a, R, n, u, p, nw, phi, N, E, nc1 = self._geometry(kin)
        _, jac, djac = kin.frame(self.fid)
        v = kin.v
        cdot = jac[:3] @ v
        omega = jac[3:] @ v
        adot = cross(omega, a)
        Rdot = 0.0 if self.radius_index is None else v[self.radius_index]
        P = (np.eye(3) - np.outer(u, u)) / nw
        rhs_const = -(n @ adot) * a - (n @ a) * adot
        if N is None:
            udot = P @ rhs_const
            ndot = np.zeros(3)
        else:
            Qa = np.eye(3) - np.outer(a, a)
            K = np.eye(3) + R * P @ Qa @ N
            udot = np.linalg.solve(K, P @ (Qa @ N @ (cdot - Rdot * u) + rhs_const))
            ndot = N @ (cdot - R * udot - Rdot * u)
        r = -R * u
        rdot = -R * udot - Rdot * u
        t1 = E[:, 0]
        c1dot = cross(adot, n) + cross(a, ndot)
        t1dot = (c1dot - t1 * (t1 @ c1dot)) / nc1
        t2dot = cross(ndot, t1) + cross(n, t1dot)
        Edot = np.array([t1dot, t2dot, ndot]).T
        return dict(p=p, n=n, u=u, R=R, E=E, Edot=Edot, r=r, rdot=rdot, udot=udot, a=a, phi=phi, J=jac, dJ=djac)

    def _world_jacobian(self, kin: KinematicState) -> tuple[np.ndarray, tuple]:
        """:math:`A_w = J_c - [r]_\\times J_\\omega - u\\,\\partial R/\\partial q` (3 x nv, world rows), cached."""
        key = (id(self), "Aw")
        if key not in kin.geometry:
            geo = self._geometry(kin)
            _, jac = kin.pose(self.fid)
            r = -geo[2] * geo[4]
            Aw = jac[:3] - skew(r) @ jac[3:]
            if self.radius_index is not None:
                Aw[:, self.radius_index] -= geo[4]
            kin.geometry[key] = (Aw, geo)
        return kin.geometry[key]

    def _labels(self) -> list[str]:
        return [f"{self.name}.{s}" for s in self._row_names]

    def jacobian(self, kin: KinematicState) -> ConstraintRows:
        """The wheel's rows :math:`D E^T A_w` (in its contact frame t1, t2, n) and the normal row's residual,
        without :math:`\\dot A`.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The :class:`~robotdyn.constraints.constraint.ConstraintRows`.
        """
        Aw, geo = self._world_jacobian(kin)
        D = self._directions
        holonomic = D[:, 2] != 0
        return ConstraintRows(D @ (geo[9].T @ Aw), None, np.where(holonomic, geo[7], 0.0), holonomic, self._labels())

    def drift(self, kin: KinematicState) -> np.ndarray:
        """:math:`\\dot A v = D(\\dot E^T s + E^T(a_c^0 + \\dot\\omega^0 \\times r + \\omega \\times \\dot r
        - \\dot u \\dot R))` with :math:`s = A_w v` the velocity of the wheel's material point at the contact.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            One value per row [m/s^2].
        """
        g = self.contact(kin)
        Aw, _ = self._world_jacobian(kin)
        jac, djac, v = g["J"], g["dJ"], kin.v
        s = Aw @ v
        acc = djac[:3] @ v + cross(djac[3:] @ v, g["r"]) + cross(jac[3:] @ v, g["rdot"])
        if self.radius_index is not None:
            acc = acc - g["udot"] * v[self.radius_index]
        return self._directions @ (g["Edot"].T @ s + g["E"].T @ acc)

    def rows(self, kin: KinematicState) -> ConstraintRows:
        """The wheel's rows with their time derivative: longitudinal, lateral and normal for a standard wheel
        (fewer for the subclasses), labelled ``<name>.<row>``.

        Args:
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v) (placements, Jacobians and
                their time variation of the robot's model).

        Returns:
            The :class:`~robotdyn.constraints.constraint.ConstraintRows`.
        """
        g = self.contact(kin)
        jac, djac = g["J"], g["dJ"]
        Aw, _ = self._world_jacobian(kin)
        Awdot = djac[:3] - skew(g["rdot"]) @ jac[3:] - skew(g["r"]) @ djac[3:]
        if self.radius_index is not None:
            Awdot[:, self.radius_index] -= g["udot"]
        D = self._directions  # rows: coefficients of (t1, t2, n)
        W = D @ g["E"].T
        Wdot = D @ g["Edot"].T
        A = W @ Aw
        Adot = Wdot @ Aw + W @ Awdot
        holonomic = D[:, 2] != 0
        residual = np.where(holonomic, g["phi"], 0.0)
        return ConstraintRows(A, Adot, residual, holonomic, self._labels())


class OmniWheel(RollingWheel):
    """An omni/Swedish wheel: rolls without slipping along its rollers' axis only, and touches the ground.

    Args:
        description: The robot's :class:`~robotdyn.description.urdf.Description`.
        frame: Frame (link) whose origin is the wheel centre.
        radius: Wheel radius R [m] (> 0).
        roller_angle: Angle [rad] of the constrained direction from the rolling direction t1 towards t2
            (0: a 90-degree omni wheel, lateral motion free; pi/4: a 45-degree mecanum wheel).
        **kwargs: ``axis``, ``terrain``, ``radius_joint``, ``name`` as for :class:`RollingWheel`.
    """

    _row_names = ("driving", "normal")

    def __init__(self, description, frame: str, radius: float, roller_angle: float = 0.0, **kwargs) -> None:
        super().__init__(description, frame, radius, **kwargs)
        self.roller_angle = float(roller_angle)
        ca, sa = np.cos(self.roller_angle), np.sin(self.roller_angle)
        self._directions = np.array([[ca, sa, 0.0], [0.0, 0.0, 1.0]])

    def __repr__(self) -> str:  # (the roller angle too: a mecanum base's info shows each wheel's handedness)
        return (f"{type(self).__name__}(frame={self.frame!r}, radius={self.radius}, roller_angle="
                f"{np.degrees(self.roller_angle):.6g} deg, terrain={self.terrain!r})")


FLAT_TILT = math.pi / 4
"""Axle tilts from the ground normal [rad] below which :func:`lying_flat` names a wheel (an upright wheel's is
pi/2; the contact geometry refuses only an axle exactly along the normal)."""


def lying_flat(constraints, kin: KinematicState, limit: float = FLAT_TILT) -> list[str]:
    """One line for each wheel whose axle is within ``limit`` of the terrain's normal under its centre: a wheel
    lying (almost) flat, whose contact point sits up to a radius to the side of its centre instead of below it, as
    when ``axis`` is given in the world's axes for a frame that its URDF joint turns (a ROS ``rpy="-1.57 0 0"``).

    Args:
        constraints: The robot's constraints (its :class:`RollingWheel` and subclasses are checked).
        kin: The kinematic state (a configuration; its velocity is not used).
        limit: The tilt [rad] below which a wheel is named (default :data:`FLAT_TILT`).

    Returns:
        The lines (empty where every wheel stands up).
    """
    out = []
    for c in constraints:
        if not isinstance(c, RollingWheel):
            continue
        placement, _ = kin.pose(c.fid)
        a = placement.rotation @ c.axis
        centre = placement.translation
        n = np.asarray(c.terrain.normal(centre[0], centre[1]), float)
        tilt = math.acos(min(1.0, abs(float(n @ a)) / float(np.linalg.norm(n))))
        if tilt < limit:
            out.append(f"wheel {c.name!r}: its axle {np.round(c.axis, 6).tolist()} (in the axes of frame {c.frame!r}) "
                       f"is {tilt:.2g} rad from the ground normal (a wheel lying flat: its contact point is "
                       f"{c.radius * math.cos(tilt):.3g} m to the side of its centre, not below it); expected the "
                       "wheel's spin axis in that frame's own axes, horizontal in the world (any horizontal axis for "
                       "a support)")
    return out


class SupportWheel(RollingWheel):
    """A wheel that only touches the ground: the holonomic normal row, no tangential rows (a frictionless
    support, e.g. a free castor or a skid whose friction is neglected). Arguments as :class:`RollingWheel`."""

    _row_names = ("normal",)
    _directions = np.array([[0.0, 0.0, 1.0]])

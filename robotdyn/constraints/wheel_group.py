"""Several rolling wheels evaluated together: the fast path of :mod:`robotdyn.constraints.rolling_contact`.

:class:`WheelGroup` gives exactly the rows of each wheel's :meth:`~robotdyn.constraints.rolling_contact.RollingWheel.jacobian`
and :meth:`~robotdyn.constraints.rolling_contact.RollingWheel.drift` (same formulas; the module docstring of
:mod:`robotdyn.constraints.rolling_contact` states them), stacked, with far fewer Python-level operations; the robot's
constraint set (:class:`robotdyn.reduction.reduced_dynamics.ConstraintSet`) uses it on the Python path.
``tests/test_fast_paths.py`` checks it against the per-wheel rows on every robot.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from .constraint import LWA, ConstraintRows, KinematicState, skew
from .constraint import skews as _skews
from .constraint import vcross as _vcross
from .constraint import vdot as _vdot
from ..errors import ConstraintError
from .rolling_contact import RollingWheel

_I3 = np.eye(3)


def groupable(constraint) -> bool:
    """Whether :class:`WheelGroup` reproduces ``constraint``'s rows (a wheel class that does not override the
    contact model)."""
    cls = type(constraint)
    return (
        isinstance(constraint, RollingWheel)
        and cls.jacobian is RollingWheel.jacobian
        and cls.drift is RollingWheel.drift
        and cls._geometry is RollingWheel._geometry
        and cls._world_jacobian is RollingWheel._world_jacobian
    )


class WheelGroup:
    """Several rolling wheels evaluated together (arrays of shape (m, 3), (m, 3, nv)).

    Gives the same rows as the wheels' own :meth:`RollingWheel.jacobian` and :meth:`RollingWheel.drift`
    (same formulas, see the module docstring), stacked in the order of ``wheels``, with a few dozen numpy calls
    for the whole group instead of ~80 per wheel. On a plane (``terrain.is_flat``, a
    :class:`~robotdyn.constraints.terrain.RampTerrain`) without radius joints the 3-vector geometry and drift of one state are
    computed wheel by wheel in Python floats (cheaper than numpy calls on 3-vectors) and only the (3, nv) rows
    in numpy; with radius joints the same formulas run vectorised over wheels; on other terrains the contact
    point of each wheel is found by :meth:`RollingWheel._geometry` (an iteration on the terrain) and the rest is
    vectorised.

    Args:
        wheels: The wheels (instances for which :func:`groupable` holds).
    """

    def __init__(self, wheels: list[RollingWheel]) -> None:
        from .terrain import RampTerrain

        self.wheels = list(wheels)
        m = len(self.wheels)
        self.fids = [w.fid for w in self.wheels]
        self.axis = np.array([w.axis for w in self.wheels])
        self.R0 = np.array([w.radius for w in self.wheels])[:, None]
        self.radial = np.array([i for i, w in enumerate(self.wheels) if w.radius_index is not None], dtype=int)
        self.radial_index = np.array([self.wheels[i].radius_index for i in self.radial], dtype=int)
        terrains = {id(w.terrain) for w in self.wheels}
        first = self.wheels[0].terrain
        self.plane = len(terrains) == 1 and isinstance(first, RampTerrain) and first.is_flat
        if self.plane:
            self.terrain = first
            self.n0 = first.normal(0.0, 0.0)
            self.n = np.tile(self.n0, (m, 1))
            self.Kn = skew(self.n0)
            grad = first.gradient(0.0, 0.0)
            self.height_row = np.array([-grad[0], -grad[1], 1.0])  # p_z - (f(p) - h) = height_row . p
            self.slope_norm = np.sqrt(1.0 + grad @ grad)
        self.curved = not all(w.terrain.is_flat for w in self.wheels)
        self.Dpad = np.zeros((m, 3, 3))
        keep, labels, holonomic = [], [], []
        for i, w in enumerate(self.wheels):
            D = w._directions
            self.Dpad[i, : D.shape[0]] = D
            keep += [3 * i + j for j in range(D.shape[0])]
            labels += w._labels()
            holonomic += list(D[:, 2] != 0)
        self.keep = np.array(keep, dtype=int)
        self.row_wheel = self.keep // 3
        self._built = [(w.terrain, w.radius, w.axis, w._directions) for w in self.wheels]
        self._axes = [tuple(w.axis.tolist()) for w in self.wheels]  # Python floats for the scalar path
        self._radii = [float(w.radius) for w in self.wheels]
        self._D = [None if w._directions.shape == (3, 3) and np.array_equal(w._directions, _I3)
                   else w._directions.tolist() for w in self.wheels]
        if self.plane:
            self._n0 = tuple(self.n0.tolist())
            self._height_row = tuple(self.height_row.tolist())
            self._slope_norm = float(self.slope_norm)
        self.all_rows = bool(np.array_equal(self.Dpad, np.broadcast_to(_I3, self.Dpad.shape)))
        self.row_counts = [w._directions.shape[0] for w in self.wheels]
        self.labels = labels
        self.holonomic = np.array(holonomic, dtype=bool)

    def __repr__(self) -> str:
        return f"WheelGroup({[w.name for w in self.wheels]})"

    def current(self) -> bool:
        """Whether the wheels still have the terrain, radius, axle and rows this group was built with."""
        return all(
            w.terrain is t and w.radius == r and w.axis is ax and w._directions is D
            for w, (t, r, ax, D) in zip(self.wheels, self._built)
        )

    def _geometry(self, kin: KinematicState) -> dict:
        """Configuration-level geometry of all wheels (cached in ``kin.geometry``)."""
        key = (id(self), "geometry")
        if key in kin.geometry:
            return kin.geometry[key]
        m, nv = len(self.fids), kin.model.nv
        J = np.empty((m, 6, nv))
        if self.plane and not self.radial.size:
            geo = self._plane_contact_scalar(kin, J)
        elif self.plane:
            rot = np.empty((m, 3, 3))
            c = np.empty((m, 3))
            model, data = kin.model, kin.data
            for i, f in enumerate(self.fids):  # straight from Pinocchio's data (kin is its latest pass)
                J[i] = pin.getFrameJacobian(model, data, f, LWA)
                placement = data.oMf[f]
                rot[i] = placement.rotation
                c[i] = placement.translation
            R = self.R0.copy()
            if self.radial.size:
                R[self.radial, 0] += kin.q[self.radial_index]
            geo = self._plane_contact(rot, c, R)
        else:
            geos = [w._geometry(kin) for w in self.wheels]  # (c, a, R, n, u, p, nw, phi, N, E, nc1)
            for i, f in enumerate(self.fids):
                J[i] = kin.pose(f)[1]
            a, n, u = (np.array([g[i] for g in geos]) for i in (1, 3, 4))
            E = np.array([g[9] for g in geos])
            geo = dict(
                a=a, n=n, u=u, na=None, E=E, ET=E.transpose(0, 2, 1),
                R=np.array([[g[2]] for g in geos]),
                nw=np.array([[g[6]] for g in geos]),
                phi=np.array([g[7] for g in geos]),
                N=None if not self.curved else np.array([np.zeros((3, 3)) if g[8] is None else g[8] for g in geos]),
                nc1=np.array([[g[10]] for g in geos]),
            )
        out = self._rows(geo, J)
        kin.geometry[key] = out
        return out

    def _plane_contact_scalar(self, kin: KinematicState, J: np.ndarray) -> dict:
        """:meth:`_plane_contact` for one state, wheel by wheel in Python floats (3-vectors are cheaper as floats
        than as numpy arrays); fills the frame Jacobians ``J`` (m, 6, nv) from Pinocchio's data."""
        model, data = kin.model, kin.data
        n0 = self._n0
        hr0, hr1, hr2 = self._height_row
        h, sn = float(self.terrain.h), self._slope_norm
        wheels = []
        for i, (f, (x0, x1, x2), R) in enumerate(zip(self.fids, self._axes, self._radii)):
            J[i] = pin.getFrameJacobian(model, data, f, LWA)  # kin is the latest pass on its data
            placement = data.oMf[f]
            (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = placement.rotation.tolist()
            c0, c1_, c2 = placement.translation.tolist()
            a = (r00 * x0 + r01 * x1 + r02 * x2, r10 * x0 + r11 * x1 + r12 * x2, r20 * x0 + r21 * x1 + r22 * x2)
            na = a[0] * n0[0] + a[1] * n0[1] + a[2] * n0[2]
            w0, w1, w2 = n0[0] - na * a[0], n0[1] - na * a[1], n0[2] - na * a[2]
            nw = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
            if nw < 1e-9:
                raise ConstraintError(
                    f"wheel {self.wheels[i].name!r}: the axle is parallel to the ground normal (wheel lying "
                    "flat); expected a wheel standing on the terrain"
                )
            u = (w0 / nw, w1 / nw, w2 / nw)
            p0, p1, p2 = c0 - R * u[0], c1_ - R * u[1], c2 - R * u[2]
            phi = (p0 * hr0 + p1 * hr1 + p2 * hr2 - h) / sn
            k0, k1, k2 = a[1] * n0[2] - a[2] * n0[1], a[2] * n0[0] - a[0] * n0[2], a[0] * n0[1] - a[1] * n0[0]
            nc1 = math.sqrt(k0 * k0 + k1 * k1 + k2 * k2)
            t1 = (k0 / nc1, k1 / nc1, k2 / nc1)
            t2 = (n0[1] * t1[2] - n0[2] * t1[1], n0[2] * t1[0] - n0[0] * t1[2], n0[0] * t1[1] - n0[1] * t1[0])
            wheels.append((a, na, nw, u, phi, nc1, t1, t2, R))
        ET = np.array([(w[6], w[7], n0) for w in wheels])
        return dict(
            scalar=wheels, a=None, R=self.R0, n=self.n, na=None, u=np.array([w[3] for w in wheels]), nw=None, N=None,
            E=ET.transpose(0, 2, 1), ET=ET, nc1=None, phi=np.array([w[4] for w in wheels]),
        )

    def _drift_scalar(self, geo: dict, Jv: np.ndarray, dJv: np.ndarray, s: np.ndarray) -> np.ndarray:
        """:meth:`_drift` for one state of plane wheels without radius joints, wheel by wheel in Python floats."""
        n0 = self._n0
        out = []
        for (a, na, nw, u, _, nc1, t1, t2, R), jv, djv, sv, D in zip(
            geo["scalar"], Jv.tolist(), dJv.tolist(), s.tolist(), self._D
        ):
            o0, o1, o2 = jv[3], jv[4], jv[5]
            ad0, ad1, ad2 = o1 * a[2] - o2 * a[1], o2 * a[0] - o0 * a[2], o0 * a[1] - o1 * a[0]  # a' = w x a
            nad = ad0 * n0[0] + ad1 * n0[1] + ad2 * n0[2]
            q0, q1, q2 = -nad * a[0] - na * ad0, -nad * a[1] - na * ad1, -nad * a[2] - na * ad2
            uq = u[0] * q0 + u[1] * q1 + u[2] * q2
            ud0, ud1, ud2 = (q0 - u[0] * uq) / nw, (q1 - u[1] * uq) / nw, (q2 - u[2] * uq) / nw  # u' = P q
            rd0, rd1, rd2 = -R * ud0, -R * ud1, -R * ud2  # r' = -R u'
            r0, r1, r2 = -R * u[0], -R * u[1], -R * u[2]
            k0, k1, k2 = ad1 * n0[2] - ad2 * n0[1], ad2 * n0[0] - ad0 * n0[2], ad0 * n0[1] - ad1 * n0[0]  # a' x n
            tk = t1[0] * k0 + t1[1] * k1 + t1[2] * k2
            e0, e1, e2 = (k0 - t1[0] * tk) / nc1, (k1 - t1[1] * tk) / nc1, (k2 - t1[2] * tk) / nc1  # t1'
            f0, f1, f2 = n0[1] * e2 - n0[2] * e1, n0[2] * e0 - n0[0] * e2, n0[0] * e1 - n0[1] * e0  # t2' = n x t1'
            b0, b1, b2 = djv[3], djv[4], djv[5]
            acc0 = djv[0] + (b1 * r2 - b2 * r1) + (o1 * rd2 - o2 * rd1)
            acc1 = djv[1] + (b2 * r0 - b0 * r2) + (o2 * rd0 - o0 * rd2)
            acc2 = djv[2] + (b0 * r1 - b1 * r0) + (o0 * rd1 - o1 * rd0)
            s0, s1, s2 = sv
            d = (
                (e0 * s0 + e1 * s1 + e2 * s2) + (t1[0] * acc0 + t1[1] * acc1 + t1[2] * acc2),
                (f0 * s0 + f1 * s1 + f2 * s2) + (t2[0] * acc0 + t2[1] * acc1 + t2[2] * acc2),
                n0[0] * acc0 + n0[1] * acc1 + n0[2] * acc2,
            )
            if D is None:
                out.extend(d)
            else:
                out.extend(row[0] * d[0] + row[1] * d[1] + row[2] * d[2] for row in D)
        return np.array(out)

    def _plane_contact(self, rot: np.ndarray, c: np.ndarray, R: np.ndarray) -> dict:
        """Contact geometry on the plane from the wheel frames' rotations (m, 3, 3), centres (m, 3) and radii
        (m, 1)."""
        m = len(c)
        bad = np.flatnonzero(R[:, 0] <= 0) if self.radial.size else ()
        if len(bad):
            raise ConstraintError(
                f"wheel {self.wheels[bad[0]].name!r}: radius {R[bad[0], 0]:.6g} m is not positive at this "
                "configuration"
            )
        a = (rot @ self.axis[:, :, None])[:, :, 0]
        na = a @ self.n0  # the normal is constant: products with it are matrix products
        wv = self.n0 - na[:, None] * a
        nw = np.sqrt(_vdot(wv, wv))
        if nw.min() < 1e-9:
            flat = np.flatnonzero(nw[:, 0] < 1e-9)
            raise ConstraintError(
                f"wheel {self.wheels[flat[0]].name!r}: the axle is parallel to the ground normal (wheel lying "
                "flat); expected a wheel standing on the terrain"
            )
        u = wv / nw
        p = c - R * u
        phi = (p @ self.height_row - self.terrain.h) / self.slope_norm
        c1 = a @ self.Kn  # a x n
        nc1 = np.sqrt(_vdot(c1, c1))
        t1 = c1 / nc1
        ET = np.empty((m, 3, 3))
        ET[:, 0] = t1
        ET[:, 1] = t1 @ self.Kn.T  # n x t1
        ET[:, 2] = self.n0
        n = self.n if m == len(self.n) else np.broadcast_to(self.n0, (m, 3))
        return dict(a=a, R=R, n=n, na=na, u=u, nw=nw, N=None, E=ET.transpose(0, 2, 1), ET=ET, nc1=nc1, phi=phi)

    def _rows(self, geo: dict, J: np.ndarray) -> dict:
        """Adds the world rows ``Aw`` (m, 3, nv), the stacked rows ``A`` and their ``residual`` to ``geo``."""
        u = geo["u"]
        r = -geo["R"] * u
        Aw = J[:, :3] - _skews(r) @ J[:, 3:]
        if self.radial.size:
            Aw[self.radial, :, self.radial_index] -= u[self.radial]
        if self.all_rows:  # three rows per wheel: D = I
            A = (geo["ET"] @ Aw).reshape(-1, Aw.shape[2])
        else:
            A = ((self.Dpad @ geo["ET"]) @ Aw).reshape(-1, Aw.shape[2])[self.keep]
        residual = np.where(self.holonomic, geo["phi"][self.row_wheel], 0.0)
        geo.update(J=J, r=r, Aw=Aw, A=A, residual=residual)
        return geo

    def jacobian(self, kin: KinematicState) -> ConstraintRows:
        """The stacked rows of all wheels (as :meth:`RollingWheel.jacobian`, ``Adot`` is ``None``)."""
        geo = self._geometry(kin)
        return ConstraintRows(geo["A"], None, geo["residual"], self.holonomic, self.labels)

    def drift(self, kin: KinematicState) -> np.ndarray:
        """The stacked drift terms :math:`\\dot A v` of all wheels (as :meth:`RollingWheel.drift`)."""
        geo = self._geometry(kin)
        v = kin.v
        if not kin._moving:
            return np.zeros(self.keep.size)
        J = geo["J"]
        dJ = np.empty_like(J)
        for i, f in enumerate(self.fids):  # kin is the latest pass on its data (as for KinematicState.frame)
            dJ[i] = pin.getFrameJacobianTimeVariation(kin.model, kin.data, f, LWA)
        if "scalar" in geo:
            return self._drift_scalar(geo, J @ v, dJ @ v, geo["Aw"] @ v)
        Rdot = np.zeros_like(geo["R"])
        if self.radial.size:
            Rdot[self.radial, 0] = v[self.radial_index]
        return self._drift(geo, J @ v, dJ @ v, geo["Aw"] @ v, Rdot)

    def _drift(self, geo: dict, Jv: np.ndarray, dJv: np.ndarray, s: np.ndarray, Rdot: np.ndarray) -> np.ndarray:
        """The drift terms from the frames' twists ``Jv`` (m, 6), ``dJv`` (m, 6), the contact points' velocities
        ``s`` = Aw v (m, 3) and the radius rates (m, 1)."""
        a, R, n, u, nw, E, ET = (geo[k] for k in ("a", "R", "n", "u", "nw", "E", "ET"))
        cdot, omega = Jv[:, :3], Jv[:, 3:]
        adot = _vcross(omega, a)
        if geo["na"] is None:
            rhs_const = -_vdot(n, adot) * a - _vdot(n, a) * adot
        else:
            rhs_const = -(adot @ self.n0)[:, None] * a - geo["na"][:, None] * adot
        if self.curved:
            P = (_I3 - u[:, :, None] * u[:, None, :]) / nw[:, :, None]
            N = geo["N"]
            Qa = _I3 - a[:, :, None] * a[:, None, :]
            QaN = Qa @ N
            K = _I3 + R[:, :, None] * (P @ QaN)
            rhs = (P @ ((QaN @ (cdot - Rdot * u)[:, :, None])[:, :, 0] + rhs_const)[:, :, None])
            udot = np.linalg.solve(K, rhs)[:, :, 0]
            ndot = (N @ (cdot - R * udot - Rdot * u)[:, :, None])[:, :, 0]
        else:  # plane: P = (I - u u^T) / |w| applied to a vector, the normal is constant
            udot = (rhs_const - u * _vdot(u, rhs_const)) / nw
            ndot = None
        r = geo["r"]
        rdot = -R * udot - Rdot * u if self.radial.size else -R * udot
        t1 = E[:, :, 0]
        plane = geo["na"] is not None
        if ndot is None:
            c1dot = adot @ self.Kn if plane else _vcross(adot, n)
        else:
            c1dot = _vcross(adot, n) + _vcross(a, ndot)
        t1dot = (c1dot - t1 * _vdot(t1, c1dot)) / geo["nc1"]
        if ndot is None:
            EdotT = np.zeros((len(a), 3, 3))
            EdotT[:, 0] = t1dot
            EdotT[:, 1] = t1dot @ self.Kn.T if plane else _vcross(n, t1dot)
        else:
            EdotT = np.stack([t1dot, _vcross(ndot, t1) + _vcross(n, t1dot), ndot], axis=1)
        acc = dJv[:, :3] + _vcross(dJv[:, 3:], r) + _vcross(omega, rdot)
        if self.radial.size:
            acc = acc - udot * Rdot
        d3 = (EdotT @ s[:, :, None] + ET @ acc[:, :, None])
        if self.all_rows:
            return d3.reshape(-1)
        return (self.Dpad @ d3).reshape(-1)[self.keep]

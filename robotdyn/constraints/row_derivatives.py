"""Configuration derivatives of the constraint rows: :math:`\\partial(A(q)x)/\\partial q` and
:math:`\\partial\\gamma/\\partial q`, :math:`\\partial\\gamma/\\partial v` of the drift :math:`\\gamma = \\dot A v`.

These are the constraint-side pieces of the chain rule through the projection
(:mod:`robotdyn.reduction.dynamics_derivatives`). All act on natural coordinates (:math:`\\dot q = v`), so that
:math:`\\dot A = \\sum_i \\partial A/\\partial q_i\\, v_i` and hence, for the drift,

.. math:: \\frac{\\partial \\gamma}{\\partial v} = \\dot A + \\frac{\\partial (A v)}{\\partial q}\\Big|_{v},

which needs no second-order geometry (the rolling contact's drift: the concepts page ``docs/concepts.md``).

Frame kinematics derivatives come from Pinocchio's own algorithms (``computeForwardKinematicsDerivatives`` and
``getFrameVelocityDerivatives`` / ``getFrameAccelerationDerivatives`` in LOCAL axes, rotated to world axes here:
Pinocchio 4.1's LOCAL_WORLD_ALIGNED velocity derivative is not the derivative of the LOCAL_WORLD_ALIGNED Jacobian
times a fixed velocity, which is what the rows need). Per constraint kind:

- rolling wheels (standard, omni, support, and the normal row of slipping ones; flat or curved terrain, constant
  or joint-driven radius): both analytic. The contact geometry's configuration derivatives are the rate formulas
  of :meth:`~robotdyn.constraints.rolling_contact.RollingWheel.contact` with the velocity replaced by the identity
  (every rate there is linear in v); the drift's q-derivative differentiates those rates once more, which on
  curved terrain needs the terrain's third derivatives (:attr:`~robotdyn.constraints.terrain.Terrain.third`; a
  terrain without them: central differences of its Hessian, reported as numerical);
- loop closures: :math:`\\partial(Ax)/\\partial q` and :math:`\\partial\\gamma/\\partial q` analytic;
- joint couplings: both analytic (a :class:`~robotdyn.constraints.joint_coupling.CosineLaw` gives
  :math:`f'''`; another law's :math:`f'''` is a central difference of its :math:`f''`, reported as numerical).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .constraint import KinematicState, skew
from .joint_coupling import CosineLaw, JointCoupling
from .loop_closure import LoopClosure
from .rolling_contact import RollingWheel

LOCAL = pin.ReferenceFrame.LOCAL


def _rot_dq(R: np.ndarray, y: np.ndarray, Jw: np.ndarray) -> np.ndarray:
    """:math:`\\partial(R(q) y)/\\partial q` at fixed y for a frame rotation R with world angular Jacobian Jw:
    :math:`-[Ry]_\\times J_\\omega`."""
    return -skew(R @ y) @ Jw


def _cross_d(x: np.ndarray, dx: np.ndarray, y: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Derivative of :math:`x \\times y` from those of x and y (3 x n each)."""
    return -skew(y) @ dx + skew(x) @ dy


class FramePass:
    """Frame velocities (and accelerations at :math:`\\dot v = 0`) at one state (q, x) with their derivatives.

    One ``computeForwardKinematicsDerivatives(q, x, 0)`` on a data of its own; results per frame are cached.

    Args:
        kin0: Kinematics at q (for frame rotations and LOCAL_WORLD_ALIGNED Jacobians).
        x: The velocity (n,) at which frame velocities are differentiated.
    """

    def __init__(self, kin0: KinematicState, x: np.ndarray) -> None:
        self.kin0 = kin0
        self.model = kin0.model
        self.data = kin0.model.createData()
        self.x = np.asarray(x, float)
        n = self.model.nv
        pin.computeForwardKinematicsDerivatives(self.model, self.data, kin0.q, self.x, np.zeros(n))
        pin.updateFramePlacements(self.model, self.data)
        self._vel: dict[int, tuple] = {}
        self._acc: dict[int, tuple] = {}

    def velocity(self, fid: int) -> tuple[np.ndarray, np.ndarray]:
        """World-axes (LOCAL_WORLD_ALIGNED) frame velocity :math:`V = J x` (6,) and :math:`\\partial V/\\partial q`
        at fixed x (6 x n): linear rows the frame origin's velocity, angular rows the angular velocity.

        Args:
            fid: The Pinocchio frame id (``model.getFrameId(name)``).

        Returns:
            ``(V, dV)``: V (6,) [m/s, rad/s] in world axes (linear first, then angular) and its q-derivative
            (6 x n) at fixed x, both cached per frame.
        """
        if fid not in self._vel:
            dq, _ = pin.getFrameVelocityDerivatives(self.model, self.data, fid, LOCAL)[:2]
            local = pin.getFrameVelocity(self.model, self.data, fid, LOCAL).vector
            placement, jac = self.kin0.pose(fid)
            R, Jw = placement.rotation, jac[3:]
            V = np.concatenate([R @ local[:3], R @ local[3:]])
            dV = np.vstack([R @ dq[:3] + _rot_dq(R, local[:3], Jw), R @ dq[3:] + _rot_dq(R, local[3:], Jw)])
            self._vel[fid] = (V, dV)
        return self._vel[fid]

    def local_velocity(self, fid: int) -> tuple[np.ndarray, np.ndarray]:
        """Body-axes (LOCAL) frame velocity (6,) and its q-derivative at fixed x (6 x n).

        Args:
            fid: The Pinocchio frame id (``model.getFrameId(name)``).

        Returns:
            ``(V, dV)``: the twist (6,) [m/s, rad/s] in the frame's own axes (linear first, then angular) and its
            q-derivative (6 x n) at fixed x.
        """
        dq = pin.getFrameVelocityDerivatives(self.model, self.data, fid, LOCAL)[0]
        return pin.getFrameVelocity(self.model, self.data, fid, LOCAL).vector.copy(), dq

    def local_acceleration(self, fid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Body-axes spatial acceleration at :math:`\\dot v = 0` (6,: the time derivative of the body twist, i.e.
        :math:`\\dot J_{\\text{LOCAL}} x`) and its derivatives in q and in x (6 x n each).

        Args:
            fid: The Pinocchio frame id (``model.getFrameId(name)``).

        Returns:
            ``(a, da_dq, da_dx)``: the spatial acceleration (6,) [m/s^2, rad/s^2] in the frame's own axes (linear
            first, then angular) and its derivatives in q and in x (6 x n each).
        """
        _, a_dq, a_dv, _ = pin.getFrameAccelerationDerivatives(self.model, self.data, fid, LOCAL)
        return pin.getFrameAcceleration(self.model, self.data, fid, LOCAL).vector.copy(), a_dq, a_dv

    def acceleration(self, fid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World-axes classical acceleration at :math:`\\dot v = 0` (6,: origin's linear acceleration and angular
        acceleration, :math:`\\dot J x` of the LOCAL_WORLD_ALIGNED Jacobian) and its derivatives in q and in x.

        Args:
            fid: The Pinocchio frame id (``model.getFrameId(name)``).

        Returns:
            ``(a, da_dq, da_dx)``: the classical acceleration (6,) [m/s^2, rad/s^2] in world axes (linear first,
            then angular) and its derivatives in q and in x (6 x n each), cached per frame.
        """
        if fid not in self._acc:
            vdq, vdv = pin.getFrameVelocityDerivatives(self.model, self.data, fid, LOCAL)[:2]
            vl = pin.getFrameVelocity(self.model, self.data, fid, LOCAL).vector
            al, a_dq, a_dv = self.local_acceleration(fid)
            placement, jac = self.kin0.pose(fid)
            R, Jw = placement.rotation, jac[3:]
            v, w = vl[:3], vl[3:]
            lin = al[:3] + np.cross(w, v)
            lin_dq = a_dq[:3] + _cross_d(w, vdq[3:], v, vdq[:3])
            lin_dv = a_dv[:3] + _cross_d(w, vdv[3:], v, vdv[:3])
            out = np.concatenate([R @ lin, R @ al[3:]])
            dq = np.vstack([R @ lin_dq + _rot_dq(R, lin, Jw), R @ a_dq[3:] + _rot_dq(R, al[3:], Jw)])
            dv = np.vstack([R @ lin_dv, R @ a_dv[3:]])
            self._acc[fid] = (out, dq, dv)
        return self._acc[fid]


# ------------------------------------------------------------------------------------------- rolling wheels
def wheel_geometry_dq(wheel: RollingWheel, kin0: KinematicState) -> dict:
    """Configuration derivatives (3 x n each) of a wheel's contact geometry: axle ``a``, unit vector ``u`` from the
    contact point to the centre, normal ``n``, contact frame columns ``t1``, ``t2``, the vector ``r = p - c``,
    and the radius row ``R`` (n,). The rate formulas of
    :meth:`~robotdyn.constraints.rolling_contact.RollingWheel.contact` with :math:`v` replaced by the identity
    (every rate there is linear in v).

    Args:
        wheel: The rolling wheel.
        kin0: Kinematics at the configuration q (its ``geometry`` cache holds the result, keyed by the wheel).

    Returns:
        A dict of derivatives with respect to the natural coordinates, all vectors in world axes: ``a``, ``u``,
        ``n``, ``t1``, ``t2`` (3 x n, unit vectors' rates per unit of each coordinate), ``r`` (3 x n, [m] per unit
        of each coordinate), ``R``
        (n,: 1 at the joint-driven radius coordinate, else zeros) and ``E``, the tuple (``t1``, ``t2``, ``n``) of
        the contact frame's columns.
    """
    key = (id(wheel), "geometry_dq")
    if key in kin0.geometry:
        return kin0.geometry[key]
    c, a, R, n, u, p, nw, phi, N, E, nc1 = wheel._geometry(kin0)
    _, jac = kin0.pose(wheel.fid)
    nv = jac.shape[1]
    Jc, Jw = jac[:3], jac[3:]
    eR = np.zeros(nv)
    if wheel.radius_index is not None:
        eR[wheel.radius_index] = 1.0
    Ad = -skew(a) @ Jw
    P = (np.eye(3) - np.outer(u, u)) / nw
    rhs = -np.outer(a, n @ Ad) - (n @ a) * Ad
    if N is None:
        U = P @ rhs
        Nq = np.zeros((3, nv))
    else:
        Qa = np.eye(3) - np.outer(a, a)
        K = np.eye(3) + R * P @ Qa @ N
        U = np.linalg.solve(K, P @ (Qa @ N @ (Jc - np.outer(u, eR)) + rhs))
        Nq = N @ (Jc - R * U - np.outer(u, eR))
    t1 = E[:, 0]
    C1 = -skew(n) @ Ad + skew(a) @ Nq
    T1 = (C1 - np.outer(t1, t1 @ C1)) / nc1
    T2 = -skew(t1) @ Nq + skew(n) @ T1
    out = dict(a=Ad, u=U, n=Nq, t1=T1, t2=T2, r=-R * U - np.outer(u, eR), R=eR, E=(T1, T2, Nq))
    kin0.geometry[key] = out
    return out


def wheel_velocity_dq(wheel: RollingWheel, fpass: FramePass, directions: np.ndarray | None = None) -> np.ndarray:
    """:math:`\\partial(A x)/\\partial q` (rows x n) of a rolling wheel at fixed x = ``fpass.x``:
    :math:`A x = D E^T s`, :math:`s = v_c(x) + \\omega(x)\\times r - u\\,x_R` (``directions``: D, default the
    wheel's own rows; e.g. the tangential rows (t1, t2) of a slipping wheel).

    Args:
        wheel: The rolling wheel.
        fpass: The frame pass at (q, x); x (n,) [m/s, rad/s] is held fixed.
        directions: D (rows x 3), the rows' coefficients of the contact frame's columns (t1, t2, n); default
            None: the wheel's own rows.

    Returns:
        The derivative (rows x n) of the rows' contact-frame velocity components [m/s] per unit of each
        coordinate (m or rad).
    """
    kin0 = fpass.kin0
    geo = wheel._geometry(kin0)
    E, R, u = geo[9], geo[2], geo[4]
    r = -R * u
    g = wheel_geometry_dq(wheel, kin0)
    V, dV = fpass.velocity(wheel.fid)
    xR = 0.0 if wheel.radius_index is None else fpass.x[wheel.radius_index]
    s = V[:3] + np.cross(V[3:], r) - u * xR
    ds = dV[:3] + _cross_d(V[3:], dV[3:], r, g["r"]) - xR * g["u"]
    dEs = np.vstack([E[:, i] @ ds + s @ g["E"][i] for i in range(3)])
    return (wheel._directions if directions is None else directions) @ dEs


def terrain_normal_dp(terrain, p: np.ndarray, numerical: set[str] | None = None, name: str = "") -> np.ndarray:
    """:math:`\\partial N/\\partial p_x`, :math:`\\partial N/\\partial p_y` (2, 3, 3) of the terrain normal's
    derivative :math:`N = \\partial n/\\partial p = (I - nn^T)D/\\|m\\|` (:math:`m = (-f_x, -f_y, 1)`,
    :math:`D = \\partial m/\\partial p`) at the ground point p, from the terrain's third derivatives
    (:attr:`~robotdyn.constraints.terrain.Terrain.third`):
    :math:`\\partial_\\alpha N = [-(N_\\alpha n^T + nN_\\alpha^T)D + (I - nn^T)\\partial_\\alpha D]/\\|m\\| -
    N\\,(n^TD_\\alpha)/\\|m\\|`; a terrain without them: Richardson-extrapolated central differences of its
    ``normal_derivative`` (reported in ``numerical``).

    Args:
        terrain: The :class:`~robotdyn.constraints.terrain.Terrain` (with or without ``third``).
        p: The ground point (3,) in world coordinates [m]; only its x and y are used.
        numerical: A set to which a note is added when the derivatives are finite differences (default None: no
            note).
        name: The constraint's name, for that note.

    Returns:
        The array (2, 3, 3) [1/m^2]: index 0 the derivative along world x, index 1 along world y.
    """
    x, y = float(p[0]), float(p[1])
    if terrain.third is not None:
        fx, fy = terrain.gradient(x, y)
        H = terrain.hessian(x, y)
        F3 = np.asarray(terrain.third(x, y), float)
        m = np.array([-fx, -fy, 1.0])
        norm = np.linalg.norm(m)
        n = m / norm
        D = np.zeros((3, 3))
        D[:2, :2] = -H
        Pn = np.eye(3) - np.outer(n, n)
        N = Pn @ D / norm
        out = np.zeros((2, 3, 3))
        for al in range(2):
            dD = np.zeros((3, 3))
            dD[:2, :2] = -F3[:, :, al]
            Na = N[:, al]
            out[al] = (-(np.outer(Na, n) + np.outer(n, Na)) @ D + Pn @ dD) / norm - N * (n @ D[:, al]) / norm
        return out
    if numerical is not None:
        numerical.add(f"{name}: the terrain's third derivatives (Richardson central differences of its Hessian)")
    out = np.zeros((2, 3, 3))
    for i in range(2):
        h = 1e-4 * max(1.0, abs(p[i]))
        e = np.zeros(2)
        e[i] = h
        f = lambda d: terrain.normal_derivative(x + d[0], y + d[1])  # noqa: E731
        d1 = (f(e) - f(-e)) / (2 * h)
        d2 = (f(e / 2) - f(-e / 2)) / h
        out[i] = (4 * d2 - d1) / 3
    return out


def wheel_drift_dq(wheel: RollingWheel, fpass: FramePass, numerical: set[str] | None = None) -> np.ndarray:
    """:math:`\\partial\\gamma/\\partial q` at fixed v = ``fpass.x`` of a rolling wheel, analytic: the drift of
    :meth:`~robotdyn.constraints.rolling_contact.RollingWheel.drift`,
    :math:`D(\\dot E^T s + E^T(a_c^0 + \\dot\\omega^0\\times r + \\omega\\times\\dot r - \\dot u\\dot R))`,
    differentiated term by term: the geometry through :func:`wheel_geometry_dq`, the frame's velocity and classical
    acceleration through Pinocchio's derivatives, and the rates of
    :meth:`~robotdyn.constraints.rolling_contact.RollingWheel.contact` (:math:`K\\dot u = P(Q_aN(\\dot c - \\dot R u)
    + r_c)`, :math:`K = I + RPQ_aN`, :math:`\\dot n = N(\\dot c - R\\dot u - \\dot R u)`, :math:`\\dot t_1`,
    :math:`\\dot t_2`) by the product rule. On curved terrain :math:`\\partial N/\\partial q` needs the terrain's
    third derivatives (:func:`terrain_normal_dp`); on planes N = 0.

    Args:
        wheel: The rolling wheel.
        fpass: The frame pass at (q, v); v = ``fpass.x`` (n,) [m/s, rad/s] is held fixed.
        numerical: A set to which a note is added if the terrain has no third derivatives (default None: no note).

    Returns:
        The derivative (rows x n) of the wheel's drift rows [m/s^2] per unit of each coordinate (m or rad).
    """
    kin0 = fpass.kin0
    c, a, R, n, u, p, nw, phi, N, E, nc1 = wheel._geometry(kin0)
    g = wheel_geometry_dq(wheel, kin0)
    nv = kin0.model.nv
    _, jac = kin0.pose(wheel.fid)
    v = fpass.x
    V, dV = fpass.velocity(wheel.fid)
    al, dal, _ = fpass.acceleration(wheel.fid)
    w, dw = V[3:], dV[3:]
    Rd = 0.0 if wheel.radius_index is None else v[wheel.radius_index]
    eR = g["R"]
    r, dr, du, da, dn = -R * u, g["r"], g["u"], g["a"], g["n"]
    curved = N is not None
    if curved:
        dNdp = terrain_normal_dp(wheel.terrain, p, numerical, wheel.name)
        dp = jac[:3] - np.outer(u, eR) - R * du  # p = c - R u
        dN = np.einsum("aij,ap->ijp", dNdp, dp[:2])  # (3, 3, n)
    else:
        N = np.zeros((3, 3))
        dN = np.zeros((3, 3, nv))

    def dN_times(y):  # d(N y)/dq at fixed y
        return np.einsum("ijp,j->ip", dN, y)

    def dP_times(y):  # d(P y)/dq at fixed y, P = (I - u u^T)/nw
        return -(np.outer(u, y @ du) + du * (u @ y)) / nw - np.outer(P @ y, dnw) / nw

    def dQ_times(y):  # d(Qa y)/dq at fixed y, Qa = I - a a^T
        return -(da * (a @ y) + np.outer(a, y @ da))

    P = (np.eye(3) - np.outer(u, u)) / nw
    Qa = np.eye(3) - np.outer(a, a)
    na = n @ a
    dna = a @ dn + n @ da
    dnw = -na * dna / nw
    # rates at (q, v)
    cd, dcd = V[:3], dV[:3]
    adot = np.cross(w, a)
    dadot = _cross_d(w, dw, a, da)
    nad = n @ adot
    rc = -nad * a - na * adot
    drc = -np.outer(a, adot @ dn + n @ dadot) - nad * da - np.outer(adot, dna) - na * dadot
    e = cd - Rd * u
    de = dcd - Rd * du
    m1 = N @ e
    dm1 = dN_times(e) + N @ de
    m2 = Qa @ m1 + rc
    dm2 = dQ_times(m1) + Qa @ dm1 + drc
    z = P @ m2
    dz = dP_times(m2) + P @ dm2
    K = np.eye(3) + R * P @ Qa @ N
    udot = np.linalg.solve(K, z)
    x1 = N @ udot
    x2 = Qa @ x1
    dK_udot = np.outer(P @ x2, eR) + R * (dP_times(x2) + P @ (dQ_times(x1) + Qa @ dN_times(udot)))
    dudot = np.linalg.solve(K, dz - dK_udot)
    hh = cd - R * udot - Rd * u
    dhh = dcd - np.outer(udot, eR) - R * dudot - Rd * du
    ndot = N @ hh
    dndot = dN_times(hh) + N @ dhh
    rdot = -R * udot - Rd * u
    drdot = -np.outer(udot, eR) - R * dudot - Rd * du
    t1, dt1 = E[:, 0], g["t1"]
    c1d = np.cross(adot, n) + np.cross(a, ndot)
    dc1d = _cross_d(adot, dadot, n, dn) + _cross_d(a, da, ndot, dndot)
    dnc1 = t1 @ _cross_d(a, da, n, dn)
    y = c1d - t1 * (t1 @ c1d)
    dy = dc1d - dt1 * (t1 @ c1d) - np.outer(t1, c1d @ dt1 + t1 @ dc1d)
    t1d = y / nc1
    dt1d = dy / nc1 - np.outer(y, dnc1) / nc1 ** 2
    t2d = np.cross(ndot, t1) + np.cross(n, t1d)
    dt2d = _cross_d(ndot, dndot, t1, dt1) + _cross_d(n, dn, t1d, dt1d)
    # s and acc
    s = V[:3] + np.cross(w, r) - u * Rd
    ds = dV[:3] + _cross_d(w, dw, r, dr) - Rd * du
    acc = al[:3] + np.cross(al[3:], r) + np.cross(w, rdot) - udot * Rd
    dacc = dal[:3] + _cross_d(al[3:], dal[3:], r, dr) + _cross_d(w, dw, rdot, drdot) - Rd * dudot
    Ed = (t1d, t2d, ndot)
    dEd = (dt1d, dt2d, dndot)
    rows = [Ed[i] @ ds + s @ dEd[i] + E[:, i] @ dacc + acc @ g["E"][i] for i in range(3)]
    return wheel._directions @ np.vstack(rows)


# -------------------------------------------------------------------------------------------- loop closures
def closure_velocity_dq(closure: LoopClosure, fpass: FramePass) -> np.ndarray:
    """:math:`\\partial(A x)/\\partial q` of a loop closure at fixed x (see the formulas of
    :mod:`robotdyn.constraints.loop_closure`; :math:`\\partial(R_1^T y)/\\partial q = R_1^T[y]_\\times J_{1,\\omega}`).

    Args:
        closure: The loop closure.
        fpass: The frame pass at (q, x); x (n,) [m/s, rad/s] is held fixed.

    Returns:
        The derivative (rows x n) of the closed components' rows (in frame1's axes, in the order of the
        closure's ``components``).
    """
    M1, J1, M2, J2, V1, dV1, V2, dV2 = _closure_frames(closure, fpass)
    R1T = M1.rotation.T
    d = M2.translation - M1.translation
    dd = J2[:3] - J1[:3]
    yt = V2[:3] - V1[:3] + np.cross(d, V1[3:])
    yr = V2[3:] - V1[3:]
    dyt = dV2[:3] - dV1[:3] + _cross_d(d, dd, V1[3:], dV1[3:])
    dyr = dV2[3:] - dV1[3:]
    out = np.vstack([R1T @ (skew(yt) @ J1[3:] + dyt), R1T @ (skew(yr) @ J1[3:] + dyr)])
    return out[closure._sel]


def _closure_frames(closure: LoopClosure, fpass: FramePass) -> tuple:
    """The closure's two frames at the pass: their placements and Jacobians, velocities and velocity derivatives
    ``(M1, J1, M2, J2, V1, dV1, V2, dV2)`` (as :meth:`FramePass.velocity` gives them)."""
    M1, J1 = fpass.kin0.pose(closure.f1)
    M2, J2 = fpass.kin0.pose(closure.f2)
    V1, dV1 = fpass.velocity(closure.f1)
    V2, dV2 = fpass.velocity(closure.f2)
    return M1, J1, M2, J2, V1, dV1, V2, dV2


def closure_drift_dq(closure: LoopClosure, fpass: FramePass) -> np.ndarray:
    """:math:`\\partial\\gamma/\\partial q` at fixed v = ``fpass.x`` of a loop closure, analytic: the drift of
    :meth:`~robotdyn.constraints.loop_closure.LoopClosure.drift` differentiated through the frames' velocities and
    classical accelerations (Pinocchio's velocity and acceleration derivatives).

    Args:
        closure: The loop closure.
        fpass: The frame pass at (q, v); v = ``fpass.x`` (n,) [m/s, rad/s] is held fixed.

    Returns:
        The derivative (rows x n) of the closed components' drift rows (in frame1's axes, in the order of the
        closure's ``components``).
    """
    M1, J1, M2, J2, V1, dV1, V2, dV2 = _closure_frames(closure, fpass)
    R1T = M1.rotation.T
    a1, da1, _ = fpass.acceleration(closure.f1)
    a2, da2, _ = fpass.acceleration(closure.f2)
    d = M2.translation - M1.translation
    dd = J2[:3] - J1[:3]
    w1, dw1 = V1[3:], dV1[3:]
    ddot, dddot = V2[:3] - V1[:3], dV2[:3] - dV1[:3]
    kt = ddot + np.cross(d, w1)
    dkt_q = dddot + _cross_d(d, dd, w1, dw1)
    jt = a2[:3] - a1[:3] + np.cross(ddot, w1) + np.cross(d, a1[3:])
    djt = da2[:3] - da1[:3] + _cross_d(ddot, dddot, w1, dw1) + _cross_d(d, dd, a1[3:], da1[3:])
    kr, dkr = V2[3:] - V1[3:], dV2[3:] - dV1[3:]
    jr, djr = a2[3:] - a1[3:], da2[3:] - da1[3:]
    yt = jt - np.cross(w1, kt)
    yr = jr - np.cross(w1, kr)
    dyt = djt - _cross_d(w1, dw1, kt, dkt_q)
    dyr = djr - _cross_d(w1, dw1, kr, dkr)
    out = np.vstack([R1T @ (skew(yt) @ J1[3:] + dyt), R1T @ (skew(yr) @ J1[3:] + dyr)])
    return out[closure._sel]


# ------------------------------------------------------------------------------------------ joint couplings
def _third(coupling: JointCoupling, qr: float) -> tuple[float, bool]:
    """:math:`f'''(q_r)` and whether it is exact (a CosineLaw) rather than a central difference of f''."""
    law = coupling.law
    if isinstance(law, CosineLaw):
        return law.amplitude * law.rate ** 3 * np.sin(law.rate * qr + law.phase), True
    h = 1e-4 * max(1.0, abs(qr))
    d1 = (coupling.ddlaw(qr + h) - coupling.ddlaw(qr - h)) / (2 * h)
    d2 = (coupling.ddlaw(qr + h / 2) - coupling.ddlaw(qr - h / 2)) / h
    return (4 * d2 - d1) / 3, False


def coupling_velocity_dq(coupling: JointCoupling, kin0: KinematicState, x: np.ndarray) -> np.ndarray:
    """:math:`\\partial(A x)/\\partial q = -f''(q_r)\\,x_r\\,e_r^T` of a joint coupling (its one row).

    Args:
        coupling: The joint coupling.
        kin0: Kinematics at the configuration q (q_r read from ``kin0.q``).
        x: The velocity (n,) [m/s, rad/s] held fixed.

    Returns:
        The derivative (1 x n), non-zero only in the reference coordinate's column.
    """
    out = np.zeros((1, kin0.model.nv))
    out[0, coupling.j] = -float(coupling.ddlaw(float(kin0.q[coupling.j]))) * x[coupling.j]
    return out


# ----------------------------------------------------------------- constraint forces at fixed multipliers
def world_jacobians(kin0: KinematicState) -> np.ndarray:
    """The joints' world Jacobian columns at the world origin (6 x n, linear rows first; Pinocchio's ``data.J`` after
    ``computeJointJacobians``) at ``kin0.q``: what :func:`force_jacobian_dq` differentiates.

    Args:
        kin0: Kinematics at the configuration q.

    Returns:
        The columns (6 x n) [m/s, rad/s per unit of each velocity coordinate], each joint's on its own columns.
    """
    data = kin0.model.createData()
    return np.array(pin.computeJointJacobians(kin0.model, data, kin0.q))


def force_jacobian_dq(model, J: np.ndarray, jid: int, phi: np.ndarray, T: np.ndarray, sign: float = 1.0) -> None:
    """Add ``sign`` times :math:`\\partial(J^T\\phi)/\\partial q` at fixed :math:`\\phi` into T (n x n): the
    generalized force of a spatial force :math:`\\phi = (f, m)` fixed in the world (force f, moment m about the
    world origin, world axes) on the body of joint ``jid``, J its world Jacobian columns at the origin. In
    Pinocchio's tangent, :math:`\\partial J_j/\\partial q_c = J_c \\times J_j` (motion cross product) where c's
    joint supports j's (itself included), else zero (the rule ``getJointVelocityDerivatives`` sums), so
    :math:`\\partial Q_j/\\partial q_c = J_j\\cdot(f\\times\\omega_c,\\ f\\times v_c + m\\times\\omega_c)`.

    Args:
        model: The Pinocchio model.
        J: World Jacobian columns at the origin (6 x n), e.g. :func:`world_jacobians`.
        jid: The joint whose body the force acts on.
        phi: The spatial force (6,): force [N] then moment about the world origin [N m], world axes.
        T: The (n x n) matrix added into, rows the generalized force's components, columns the coordinates.
        sign: Factor of the added term (-1: the force's reaction).
    """
    f, m = phi[:3], phi[3:]
    sup = [s for s in model.supports[jid] if s != 0]
    cols = [list(range(model.joints[s].idx_v, model.joints[s].idx_v + model.joints[s].nv)) for s in sup]
    for a, ca in enumerate(cols):
        later = [j for cb in cols[a:] for j in cb]
        for c in ca:
            v, w = J[:3, c], J[3:, c]
            psi = sign * np.concatenate([np.cross(f, w), np.cross(f, v) + np.cross(m, w)])
            T[later, c] += J[:, later].T @ psi


def wheel_force_dq(wheel: RollingWheel, kin0: KinematicState, mu: np.ndarray, J: np.ndarray) -> np.ndarray:
    """:math:`\\partial(A^T\\mu)/\\partial q` at fixed :math:`\\mu` (n x n) of a rolling wheel's rows
    :math:`A = D E^T A_c`, :math:`A_c = J_c - [r]_\\times J_\\omega - u\\,e_R` (the contact point p = c + r): with
    :math:`f = E D^T\\mu` (the force at p, world axes), :math:`A^T\\mu = J_O^T(f, p\\times f) - e_R (u\\cdot f)`, so

    .. math:: \\frac{\\partial(A^T\\mu)}{\\partial q} = \\frac{\\partial J_O^T}{\\partial q}\\Big|_{(f, p\\times f)}
              + A_c^T \\frac{\\partial f}{\\partial q} - J_\\omega^T [f]_\\times \\frac{\\partial p}{\\partial q}
              - e_R\\, f^T \\frac{\\partial u}{\\partial q},

    :math:`\\partial p/\\partial q = J_c + \\partial r/\\partial q`. Row l of :math:`S^T` times it is
    :math:`\\mu^T\\partial(A S_l)/\\partial q`, the multiplier term of the reduced dynamics' derivative, without a
    frame pass per column of S (twin of ``kernels/rolling_contact_derivatives.hpp``'s ``wheel_force_dq``).

    Args:
        wheel: The rolling wheel.
        kin0: Kinematics at the configuration q.
        mu: The rows' multipliers (rows,) [N], held fixed.
        J: World Jacobian columns at the origin (6 x n), :func:`world_jacobians`.

    Returns:
        The derivative (n x n) [N or N m per unit of each coordinate].
    """
    model = kin0.model
    D = wheel._directions
    _, _, R, _, u, p, _, _, _, E, _ = wheel._geometry(kin0)
    g = wheel_geometry_dq(wheel, kin0)
    _, jac = kin0.pose(wheel.fid)
    Jc, Jw = jac[:3], jac[3:]
    lam = D.T @ mu
    f = E @ lam
    T = np.zeros((model.nv, model.nv))
    force_jacobian_dq(model, J, model.frames[wheel.fid].parentJoint, np.concatenate([f, np.cross(p, f)]), T)
    Ac = Jc - skew(-R * u) @ Jw - np.outer(u, g["R"])
    df = sum(lam[i] * g["E"][i] for i in range(3))
    T += Ac.T @ df - Jw.T @ skew(f) @ (Jc + g["r"])
    T -= np.outer(g["R"], f @ g["u"])
    return T


def closure_force_dq(closure: LoopClosure, kin0: KinematicState, mu: np.ndarray, J: np.ndarray) -> np.ndarray:
    """:math:`\\partial(A^T\\mu)/\\partial q` at fixed :math:`\\mu` (n x n) of a loop closure's rows: with
    :math:`g = R_1\\mu` (mu on the closed components, translation half :math:`g_t`, rotation half :math:`g_r`, world
    axes), :math:`A^T\\mu = (J_{2,O} - J_{1,O})^T\\Phi`, :math:`\\Phi = (g_t, p_2\\times g_t + g_r)`; its derivative
    is that of the Jacobians at fixed :math:`\\Phi` (:func:`force_jacobian_dq`) plus
    :math:`(J_{2,O} - J_{1,O})^T\\partial\\Phi/\\partial q`, :math:`\\partial g = -[g]_\\times J_{1,\\omega}`
    (twin of ``kernels/loop_closure_derivatives.hpp``'s ``closure_force_dq``).

    Args:
        closure: The loop closure.
        kin0: Kinematics at the configuration q.
        mu: The closed components' multipliers (rows,) [N, N m], held fixed.
        J: World Jacobian columns at the origin (6 x n), :func:`world_jacobians`.

    Returns:
        The derivative (n x n) [N or N m per unit of each coordinate].
    """
    model = kin0.model
    M1, J1 = kin0.pose(closure.f1)
    M2, J2 = kin0.pose(closure.f2)
    m6 = np.zeros(6)
    np.add.at(m6, closure._sel, mu)
    gt, gr = M1.rotation @ m6[:3], M1.rotation @ m6[3:]
    p1, p2 = M1.translation, M2.translation
    phi = np.concatenate([gt, np.cross(p2, gt) + gr])
    T = np.zeros((model.nv, model.nv))
    force_jacobian_dq(model, J, model.frames[closure.f2].parentJoint, phi, T)
    force_jacobian_dq(model, J, model.frames[closure.f1].parentJoint, phi, T, -1.0)
    dJ = np.vstack([J2[:3] + skew(p2) @ J2[3:] - J1[:3] - skew(p1) @ J1[3:], J2[3:] - J1[3:]])
    dgt = -skew(gt) @ J1[3:]
    dphi = np.vstack([dgt, -skew(gr) @ J1[3:] - skew(gt) @ J2[:3] + skew(p2) @ dgt])
    return T + dJ.T @ dphi


def coupling_force_dq(coupling: JointCoupling, kin0: KinematicState, mu: float) -> np.ndarray:
    """:math:`\\partial(A^T\\mu)/\\partial q` (n x n) of a joint coupling's row: :math:`-f''(q_r)\\,\\mu` at
    (r, r) (twin of ``kernels/joint_coupling_derivatives.hpp``'s ``coupling_force_dq``).

    Args:
        coupling: The joint coupling.
        kin0: Kinematics at the configuration q.
        mu: The row's multiplier, held fixed.

    Returns:
        The derivative (n x n).
    """
    T = np.zeros((kin0.model.nv, kin0.model.nv))
    T[coupling.j, coupling.j] = -float(coupling.ddlaw(float(kin0.q[coupling.j]))) * mu
    return T


def force_dq(constraints, kin0: KinematicState, mu: np.ndarray) -> np.ndarray:
    """:math:`\\partial(A(q)^T\\mu)/\\partial q` at fixed :math:`\\mu` (n x n) of all rows, in constraint order
    (rolling wheels, loop closures, joint couplings): the compiled derivatives' multiplier term
    (``ReducedDerivatives::force_dq``), :math:`S^T` times it being :math:`\\sum_r\\mu_r\\,\\partial(A_r S_l)/\\partial q`.

    Args:
        constraints: The constraints, in the order of the rows of A.
        kin0: Kinematics at the configuration q.
        mu: The multipliers (m,), one per row of A, held fixed.

    Returns:
        The derivative (n x n).

    Raises:
        InputError: A constraint without a derivative rule (see :func:`kind`).
    """
    n = kin0.model.nv
    J = world_jacobians(kin0)
    T = np.zeros((n, n))
    row = 0
    for c in constraints:
        k = kind(c, sliding=True)
        if k == "wheel":
            nr = len(c._directions)
            T += wheel_force_dq(c, kin0, mu[row:row + nr], J)
        elif k == "closure":
            nr = len(c._sel)
            T += closure_force_dq(c, kin0, mu[row:row + nr], J)
        else:
            nr = 1
            T += coupling_force_dq(c, kin0, float(mu[row]))
        row += nr
    return T


# ------------------------------------------------------------------------------------------------ dispatch
def kind(constraint, sliding: bool = False) -> str:
    """The derivative rule that serves a constraint: ``wheel``, ``closure`` or ``coupling``.

    Args:
        constraint: One constraint of the robot.
        sliding: Accept wheels under a friction law (their rows are the normal row only; the caller adds the
            friction, :mod:`robotdyn.contact.sliding_derivatives`).

    Returns:
        ``"wheel"``, ``"closure"`` or ``"coupling"``.

    Raises:
        InputError: A constraint without derivatives here (a wheel under a friction law unless ``sliding``, a
            compliant wheel, a user's own constraint class): one line naming it.
    """
    if hasattr(constraint, "sliding") and not sliding:
        raise InputError(f"dynamics derivatives: constraint {constraint.name!r} is a wheel under a friction law; "
                         "expected rolling wheels, loop closures and joint couplings here (smoothly slipping wheels: "
                         "Robot.dynamics_derivatives; exact stick-slip friction has no derivative)")
    if getattr(constraint, "compliant", False):  # robotdyn.contact.compliant_contact.CompliantWheel
        raise InputError(f"dynamics derivatives: wheel {constraint.name!r} is a compliant wheel (contact = "
                         "'compliant': its normal force is a force law of penetration, with touch-down and lift-off "
                         "events) and has no derivative rule; expected rigid rolling or slipping wheels, loop "
                         "closures and joint couplings")
    if isinstance(constraint, RollingWheel):
        return "wheel"
    if isinstance(constraint, LoopClosure):
        return "closure"
    if isinstance(constraint, JointCoupling):
        return "coupling"
    raise InputError(f"dynamics derivatives: constraint {constraint.name!r} ({type(constraint).__name__}) has no "
                     "derivative rule; expected rolling wheels, loop closures and joint couplings")


def velocity_dq(constraints, fpass: FramePass) -> np.ndarray:
    """All rows' :math:`\\partial(A x)/\\partial q` (m x n) at fixed x = ``fpass.x``, stacked in constraint order.

    Args:
        constraints: The constraints (rolling wheels, also under a friction law, loop closures, joint couplings),
            in the order of the rows of A.
        fpass: The frame pass at (q, x).

    Returns:
        The derivative (m x n); (0 x n) for no constraints.

    Raises:
        InputError: A constraint without a derivative rule (see :func:`kind`).
    """
    parts = []
    for c in constraints:
        k = kind(c, sliding=True)
        if k == "wheel":
            parts.append(wheel_velocity_dq(c, fpass))
        elif k == "closure":
            parts.append(closure_velocity_dq(c, fpass))
        else:
            parts.append(coupling_velocity_dq(c, fpass.kin0, fpass.x))
    n = fpass.model.nv
    return np.vstack(parts) if parts else np.zeros((0, n))


def drift_dq(constraints, fpass: FramePass, numerical: set[str]) -> np.ndarray:
    """All rows' :math:`\\partial\\gamma/\\partial q` (m x n) at fixed v = ``fpass.x``, stacked in constraint order,
    analytic (the pieces that are not, a terrain without third derivatives or a coupling law other than a
    :class:`~robotdyn.constraints.joint_coupling.CosineLaw`, are named in ``numerical``).

    Args:
        constraints: The constraints (rolling wheels, also under a friction law, loop closures, joint couplings),
            in the order of the rows of A.
        fpass: The frame pass at (q, v).
        numerical: A set to which a note is added, naming the constraint, for each piece taken by finite
            differences.

    Returns:
        The derivative (m x n); (0 x n) for no constraints.

    Raises:
        InputError: A constraint without a derivative rule (see :func:`kind`).
    """
    q, v = fpass.kin0.q, fpass.x
    n = fpass.model.nv
    parts = []
    for c in constraints:
        k = kind(c, sliding=True)
        if k == "closure":
            parts.append(closure_drift_dq(c, fpass))
        elif k == "coupling":
            f3, exact = _third(c, float(q[c.j]))
            row = np.zeros((1, n))
            row[0, c.j] = -f3 * v[c.j] ** 2
            if not exact:
                numerical.add(f"{c.name}: f''' (central difference of the law's f'')")
            parts.append(row)
        else:
            parts.append(wheel_drift_dq(c, fpass, numerical))
    return np.vstack(parts) if parts else np.zeros((0, n))


__all__ = ["FramePass", "wheel_geometry_dq", "wheel_velocity_dq", "wheel_drift_dq", "terrain_normal_dp",
           "closure_velocity_dq", "closure_drift_dq", "coupling_velocity_dq", "velocity_dq", "drift_dq", "kind"]

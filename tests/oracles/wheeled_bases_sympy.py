"""Independent symbolic oracles for three wheeled bases, derived with sympy from first principles (no dependency on
``robotdyn`` or Pinocchio): a differential drive in its unicycle velocities, a mecanum base in its body twist, and
a synchro drive.

Method (the same for all three; Lagrange-d'Alembert on the admissible velocities):

1. generalised coordinates q of the unconstrained planar system (x, y, psi of the base, wheel and steering
   angles) and its kinetic energy T(q, q') written body by body (translation of each mass centre, rotation of
   each body: chassis and steering links about the vertical, wheels about the vertical and about their axle);
2. the admissible velocities q' = S(q) nu, written by hand from rolling without slipping (the material point of a
   wheel at its contact has no velocity along the constrained directions);
3. the Euler-Lagrange expressions E = d/dt dT/dq' - dT/dq (d/dt by the chain rule) projected on S:
   S^T E(q, S nu, S nu' + S' nu) = M_r nu' + h_r(q, nu). Constraint forces do no work on admissible motions, so
   they drop out.

Conventions: body axes x forward, y left, z up; a wheel's axle is its body y axis and a positive spin rolls it
forward (the contact point of a wheel spinning at phi' about +y moves at -r phi' x relative to its centre).
Gravity does no work in planar motion (g_r = 0).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import sympy as sp

__all__ = ["Body", "Wheel", "Coordinates", "unicycle", "mecanum", "mecanum_ik", "synchro", "reduced_lagrange"]

@dataclass(frozen=True)
class Body:
    """A rigid body fixed to the base: mass [kg], mass centre (x, y) in body axes [m], yaw inertia about its own
    mass centre [kg m^2]."""

    m: float
    x: float
    y: float
    izz: float


@dataclass(frozen=True)
class Wheel:
    """A wheel: centre (x, y) in body axes [m], mass [kg], spin inertia about its axle and inertia about the
    vertical through its centre [kg m^2], radius [m]; for a mecanum wheel the angle [rad] of its constrained
    direction (along the rollers' axes) from the rolling direction towards the left."""

    x: float
    y: float
    m: float
    spin: float
    vertical: float
    r: float
    roller: float = 0.0


class Coordinates:
    """Generalised coordinates q, their rates q' and accelerations q'' as plain symbols, with the total time
    derivative of expressions in (q, q') by the chain rule."""

    def __init__(self, names) -> None:
        self.q = sp.symbols(" ".join(names), real=True)
        self.qd = sp.symbols(" ".join(f"{n}_d" for n in names), real=True)
        self.qdd = sp.symbols(" ".join(f"{n}_dd" for n in names), real=True)

    def dt(self, expr):
        """d/dt of an expression in q and q'."""
        return sum(sp.diff(expr, a) * b for a, b in zip(self.q + self.qd, self.qd + self.qdd))


def reduced_lagrange(T, c: Coordinates, S: sp.Matrix, nu, nudot):
    """(M_r, h_r) of S^T (d/dt dT/dq' - dT/dq) with q' = S(q) nu and q'' = S nu' + S' nu."""
    E = sp.Matrix([c.dt(sp.diff(T, qd)) - sp.diff(T, q) for q, qd in zip(c.q, c.qd)])
    qd_adm = S * sp.Matrix(nu)
    qdd_adm = S * sp.Matrix(nudot) + sum((sp.diff(qd_adm, q) * qd for q, qd in zip(c.q, qd_adm)),
                                         sp.zeros(len(c.q), 1))
    E = E.xreplace(dict(zip(c.qdd, qdd_adm))).xreplace(dict(zip(c.qd, qd_adm)))
    red = sp.expand(S.T * E)
    M = red.jacobian(sp.Matrix(nudot))
    h = red.xreplace({nd: 0 for nd in nudot})
    return M, h


def _exact(obj):
    """A Body or Wheel with exact sympy numbers (decimals as rationals, angles as multiples of pi): sympy derives
    exact expressions several times faster than float-laden ones, and the values are the same."""
    values = {}
    for key, value in vars(obj).items():
        values[key] = sp.nsimplify(value, [sp.pi]) if key == "roller" else sp.Rational(repr(float(value)))
    return type(obj)(**values)


def _planar_T(c: Coordinates, bodies, wheels, spins, extra=0):
    """Kinetic energy of bodies fixed to the base (x, y, psi = c.q[:3]) and wheels on it (spin angles ``spins``,
    indices into c.q)."""
    x, y, psi = c.q[:3]
    cs, sn = sp.cos(psi), sp.sin(psi)
    psid = c.qd[2]
    T = extra
    for b in list(bodies) + list(wheels):
        vx, vy = c.dt(x + cs * b.x - sn * b.y), c.dt(y + sn * b.x + cs * b.y)
        T += b.m * (vx**2 + vy**2) / 2
    for b in bodies:
        T += b.izz * psid**2 / 2
    for w, i in zip(wheels, spins):
        T += w.vertical * psid**2 / 2 + w.spin * c.qd[i] ** 2 / 2
    return T


def mecanum_ik(wheels) -> sp.Matrix:
    """Wheel spin rates per body twist (vx, vy, wz), derived from each wheel's no-slip condition along its rollers'
    axis d = (cos a, sin a) (body axes): d . (v_centre - r phi' e_x) = 0 with v_centre = (vx - wz y, vy + wz x)."""
    vx, vy, wz, phid = sp.symbols("vx vy wz phid", real=True)
    rows = []
    for w in wheels:
        d = sp.Matrix([sp.cos(w.roller), sp.sin(w.roller)])
        slip = sp.Matrix([vx - wz * w.y - w.r * phid, vy + wz * w.x])
        rate = sp.solve(sp.Eq(d.dot(slip), 0), phid)[0]
        rows.append([sp.diff(rate, v) for v in (vx, vy, wz)])
    return sp.Matrix(rows)


def _planar_base(bodies, wheels, names: str, base, wheel_rows):
    """(M_r(psi, nu), h_r(psi, nu)) lambdified, for a base whose admissible velocities are
    (x', y', psi') = base(psi) nu and wheel spin rates wheel_rows nu (constant rows)."""
    c = Coordinates(["x", "y", "psi"] + [f"phi{i}" for i in range(len(wheels))])
    psi = c.q[2]
    nu = sp.symbols(names, real=True)
    nudot = sp.symbols(" ".join(f"{n}_dot" for n in names.split()), real=True)
    S = sp.Matrix([*base(psi), *wheel_rows])
    M, h = reduced_lagrange(_planar_T(c, bodies, wheels, range(3, 3 + len(wheels))), c, S, nu, nudot)
    return sp.lambdify((psi, nu), M), sp.lambdify((psi, nu), h)


@functools.lru_cache(maxsize=None)
def _mecanum(bodies: tuple, wheels: tuple):
    J = mecanum_ik(wheels)
    fM, fh = _planar_base(bodies, wheels, "vx vy wz",
                          lambda psi: [[sp.cos(psi), -sp.sin(psi), 0], [sp.sin(psi), sp.cos(psi), 0], [0, 0, 1]],
                          J.tolist())
    return fM, fh, J


def mecanum(bodies, wheels, psi: float, nu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M_r, h_r, J) of a mecanum base in its body twist nu = (vx, vy, wz) at heading psi: J the wheel rates per
    twist (inverse kinematics)."""
    fM, fh, J = _mecanum(tuple(map(_exact, bodies)), tuple(map(_exact, wheels)))
    return np.array(fM(psi, nu), float), np.array(fh(psi, nu), float).ravel(), np.array(J, float)


@functools.lru_cache(maxsize=None)
def _unicycle(bodies: tuple, wheels: tuple):
    # standard wheels on the axle (x = 0): the centre moves at v - w y forward, so r phi' = v - w y
    return _planar_base(bodies, wheels, "v w", lambda psi: [[sp.cos(psi), 0], [sp.sin(psi), 0], [0, 1]],
                        [[1 / w.r, -w.y / w.r] for w in wheels])


def unicycle(bodies, wheels, psi: float, nu) -> tuple[np.ndarray, np.ndarray]:
    """(M_r, h_r) of a differential drive (wheels on the axle x = 0) in its unicycle velocities nu = (v, w): the
    forward speed of the axle midpoint [m/s] and the yaw rate [rad/s]."""
    fM, fh = _unicycle(tuple(map(_exact, bodies)), tuple(map(_exact, wheels)))
    return np.array(fM(psi, nu), float), np.array(fh(psi, nu), float).ravel()


@functools.lru_cache(maxsize=None)
def _synchro(bodies: tuple, wheels: tuple, steer_izz):
    c = Coordinates(["x", "y", "psi", "s"] + [f"phi{i}" for i in range(len(wheels))])
    psi, st = c.q[2], c.q[3]
    nu = sp.symbols("phid sd", real=True)
    nudot = sp.symbols("phidd sdd", real=True)
    r = wheels[0].r
    # all wheels steered to one angle s: parallel, so the base cannot yaw (psi' = 0) and moves along psi + s at r phi'
    S = sp.Matrix([[r * sp.cos(psi + st), 0], [r * sp.sin(psi + st), 0], [0, 0], [0, 1], *[[1, 0] for _ in wheels]])
    # steering links and wheels turn with psi' + s' about the vertical (centred steering: their centres stay put)
    steer = sum((steer_izz + w.vertical) * (c.qd[2] + c.qd[3]) ** 2 / 2 for w in wheels)
    flat = [Wheel(w.x, w.y, w.m, w.spin, 0, w.r) for w in wheels]
    T = _planar_T(c, bodies, flat, range(4, 4 + len(wheels)), extra=steer)
    M, h = reduced_lagrange(T, c, S, nu, nudot)
    return sp.lambdify((psi, st, nu), M), sp.lambdify((psi, st, nu), h)


def synchro(bodies, wheels, steer_izz: float, psi: float, s: float, nu) -> tuple[np.ndarray, np.ndarray]:
    """(M_r, h_r) of a synchro drive (every wheel steered to the same angle s about a vertical axis through its
    centre; steering links of yaw inertia ``steer_izz``) in nu = (phi', s'): a wheel's spin rate and the steering
    rate."""
    fM, fh = _synchro(tuple(map(_exact, bodies)), tuple(map(_exact, wheels)), sp.Rational(repr(float(steer_izz))))
    return np.array(fM(psi, s, nu), float), np.array(fh(psi, s, nu), float).ravel()

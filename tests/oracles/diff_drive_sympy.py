"""Independent symbolic oracle: the classical differential-drive robot with its mass centre off the wheel axle.

Derived with sympy from first principles (no dependency on ``robotdyn`` or Pinocchio).

Model
-----
* A rigid chassis carrying two coaxial driven wheels of radius ``r`` whose centres are at distance ``b`` either
  side of the axle midpoint A. Planar motion on flat ground: A at (x, y), heading psi. Body axes: x forward,
  y along the axle towards the LEFT wheel, z up.
* ``m``: total mass (chassis + wheels); ``(d, e)``: the mass centre G in body axes relative to A (d forward, e
  left; the textbook case is e = 0); ``I_A``: yaw inertia of the whole robot (wheels included, not spinning)
  about the vertical axis through A; ``I_w``: spin inertia of each wheel about its axle (axisymmetric wheels,
  mass centre on the axle).
* th_R, th_L: wheel angles relative to the chassis, positive = rolling forward. Rolling without slipping:
  v = r (th_R' + th_L')/2 along the heading, no lateral velocity, omega = psi' = r (th_R' - th_L')/(2 b).
* Motor torques tau_R, tau_L between chassis and wheels.

Reduced equations in nu = (th_R', th_L'):  M_r nu' + h_r(nu) = (tau_R, tau_L),  M_r constant.

Two routes, checked against each other in :func:`self_test`:

(a) Lagrange-d'Alembert: kinetic energy T(q, q') of the unconstrained system (x, y, psi, th_R, th_L), its
    Euler-Lagrange expressions E(q, q', q''), projected on the admissible velocities q' = S(q) nu:
    S^T E(q, S nu, S nu' + S' nu);
(b) the textbook Newton-Euler form: body-axis Newton equation along the heading and Euler equation about the
    moving point A, plus each wheel's spin equation:
        m (v' - e w' - d w^2) = F_R + F_L,
        I_A w' + m d w v - m e v' = b (F_R - F_L),
        tau_i = I_w th_i'' + r F_i.
"""

from __future__ import annotations

import functools
from types import SimpleNamespace

import numpy as np
import sympy as sp

__all__ = ["SYMBOLS", "lagrange_reduced", "textbook_reduced", "numeric", "self_test"]

m, I_A, I_w, d, e, r, b = sp.symbols("m I_A I_w d e r b", real=True)
SYMBOLS = SimpleNamespace(m=m, I_A=I_A, I_w=I_w, d=d, e=e, r=r, b=b)
_nu = sp.symbols("nu_R nu_L", real=True)
_nudot = sp.symbols("nudot_R nudot_L", real=True)


@functools.lru_cache(maxsize=None)
def lagrange_reduced() -> tuple[sp.Matrix, sp.Matrix]:
    """Route (a): (M_r, h_r(nu)) from the projected Euler-Lagrange equations."""
    t = sp.symbols("t", real=True)
    x, y, psi, thR, thL = (sp.Function(n)(t) for n in ("x", "y", "psi", "thR", "thL"))
    q = sp.Matrix([x, y, psi, thR, thL])
    qd = q.diff(t)
    c, s = sp.cos(psi), sp.sin(psi)
    pG = sp.Matrix([x + c * d - s * e, y + s * d + c * e])
    vG = pG.diff(t)
    I_G = I_A - m * (d**2 + e**2)
    T = (m * (vG.dot(vG)) + I_G * psi.diff(t) ** 2 + I_w * (thR.diff(t) ** 2 + thL.diff(t) ** 2)) / 2
    E = sp.Matrix([sp.diff(sp.diff(T, qdi), t) - sp.diff(T, qi) for qi, qdi in zip(q, qd)])
    # admissible velocities q' = S(q) nu
    nR, nL = _nu
    v = r * (nR + nL) / 2
    w = r * (nR - nL) / (2 * b)
    Sq = sp.Matrix([[c * r / 2, c * r / 2], [s * r / 2, s * r / 2], [r / (2 * b), -r / (2 * b)], [1, 0], [0, 1]])
    nu_t = [sp.Function("nR")(t), sp.Function("nL")(t)]
    qd_adm = Sq * sp.Matrix(nu_t)
    qdd_adm = qd_adm.diff(t)
    subs = {}
    for i in range(5):
        subs[q[i].diff(t, 2)] = qdd_adm[i]
    for i in range(5):
        subs[q[i].diff(t)] = qd_adm[i]
    Ered = E.subs(subs)
    Ered = Ered.subs({nu_t[0].diff(t): _nudot[0], nu_t[1].diff(t): _nudot[1]})
    Ered = Ered.subs({nu_t[0]: nR, nu_t[1]: nL, sp.Derivative(psi, t): w})
    Ered = Ered.subs({x.diff(t): v * c, y.diff(t): v * s, psi.diff(t): w})
    red = sp.simplify(Sq.T * Ered)
    red = red.subs({psi: sp.Symbol("psi")})
    Mr = sp.simplify(red.jacobian(sp.Matrix(_nudot)))
    hr = sp.simplify(red.subs({_nudot[0]: 0, _nudot[1]: 0}))
    assert not (Mr.free_symbols | hr.free_symbols) & {sp.Symbol("psi")}, "psi must drop out"
    return Mr, hr


@functools.lru_cache(maxsize=None)
def textbook_reduced() -> tuple[sp.Matrix, sp.Matrix]:
    """Route (b): (M_r, h_r(nu)) from the Newton-Euler form of the module docstring."""
    nR, nL = _nu
    aR, aL = _nudot
    v, w = r * (nR + nL) / 2, r * (nR - nL) / (2 * b)
    vd, wd = r * (aR + aL) / 2, r * (aR - aL) / (2 * b)
    Fx = m * (vd - e * wd - d * w**2)
    N = I_A * wd + m * d * w * v - m * e * vd
    F_R, F_L = (Fx + N / b) / 2, (Fx - N / b) / 2
    tau = sp.Matrix([I_w * aR + r * F_R, I_w * aL + r * F_L])
    Mr = sp.simplify(tau.jacobian(sp.Matrix(_nudot)))
    hr = sp.simplify(tau.subs({aR: 0, aL: 0}))
    return Mr, hr


@functools.lru_cache(maxsize=None)
def _lambdified():
    Mr, hr = textbook_reduced()
    args = (m, I_A, I_w, d, e, r, b)
    return sp.lambdify(args, Mr, "numpy"), sp.lambdify(args + _nu, hr, "numpy")


def numeric(p: dict, nu) -> tuple[np.ndarray, np.ndarray]:
    """(M_r, h_r(nu)) for constants ``p`` with keys m, I_A, I_w, d, e, r, b (SI units)."""
    fM, fh = _lambdified()
    args = [float(p[k]) for k in ("m", "I_A", "I_w", "d", "e", "r", "b")]
    return np.array(fM(*args), float), np.array(fh(*args, *map(float, nu)), float).ravel()


def self_test() -> None:
    """Routes (a) and (b) agree symbolically; M_r is symmetric."""
    Ma, ha = lagrange_reduced()
    Mb, hb = textbook_reduced()
    assert sp.simplify(Ma - Mb) == sp.zeros(2, 2), (Ma, Mb)
    assert sp.simplify(ha - hb) == sp.zeros(2, 1), (ha, hb)
    assert sp.simplify(Ma - Ma.T) == sp.zeros(2, 2)

"""Independent symbolic oracle for the reduced dynamics of Angeles's Quasimoro.

Derived from first principles with sympy (no dependency on the ``robotdyn``
package), following the model conventions below.  Reference: St. Staicu,
"Dynamics of Angeles's Quasimoro mobile robot using principle of virtual
powers" (eqs. 1-31).

Conventions
-----------
* World frame N: z up, gravity ``g`` along -z, flat ground z = 0.
* q = (x, y, psi, th1, th2, th3), v = qdot in the same order.
  (x, y) is the world position of C2 (axle midpoint, at height r); psi is the
  yaw of platform frame 1 (x1 forward, y1 along the axle towards wheel A
  (left), z1 up).
* Wheel A centre = C2 + (l/2) y1, wheel B centre = C2 - (l/2) y1, l = r/rho.
* th1 (th2): rotation of wheel A (B) relative to frame 1 about +y1.  Rolling
  without slipping gives  xdot_C2 = r (th1dot + th2dot)/2 (along x1),
  psidot = rho (th2dot - th1dot), no lateral velocity.
* Wheels: mass m, central inertia m r^2/4 (diameters), m r^2/2 (axle).
* Intermediate body: rotates relative to frame 1 about -y1 by th3.  Body frame
  C: x_C from C2 towards the mass centre G (x_C = -z1 at th3 = 0), z_C = -y1,
  y_C = z_C x x_C.  G = C2 + d (sin th3 x1 - cos th3 z1).  Mass M.  Inertia
  diag(J1, J2, J2) in frame C, either about C2 (``inertia_about="axle"``,
  default) or about G (``inertia_about="com"``).
* Motor torque m1 acts on wheel A about +y1 with its reaction on the body;
  m2 likewise on wheel B.  Generalized forces (0, 0, 0, m1, m2, m1 + m2).
* Independent speeds nu = (th1dot, th2dot, th3dot), v = S(q) nu, A(q) S(q) = 0.

Two routes are derived and cross-checked (see :func:`self_test`):

(a) ``KanesMethod`` with the three rolling constraints as (nonholonomic)
    velocity constraints, dependent speeds (xdot, ydot, psidot)
    -> reduced mass matrix and forcing in nu;
(b) Lagrangian of the unconstrained tree (planar base + 3 revolute joints)
    built from explicit rotation matrices: M(q), Christoffel C(q, v), g(q);
    S(q) from the contact-point velocities; Sdot;
    C_r = S^T (M Sdot + C S), g_r = S^T g, B_r = S^T B.

Reduced equations:  M_r(q) nudot + C_r(q, nu) nu + g_r(q) = B_r(q) (m1, m2).
"""

from __future__ import annotations

import functools
from types import SimpleNamespace

import numpy as np
import sympy as sp

__all__ = [
    "paper_defaults",
    "quasimoro_reduced",
    "symbolic_reduced",
    "paper_coefficients",
    "self_test",
]

# ----------------------------------------------------------------------------
# symbols
# ----------------------------------------------------------------------------
m, M, J1, J2, r, d, rho, g = sp.symbols("m M J1 J2 r d rho g", positive=True)
PARAM_SYMS = (m, M, J1, J2, r, d, rho, g)
PARAM_KEYS = ("m", "M", "J1", "J2", "r", "d", "rho", "g")

x, y, psi, th1, th2, th3 = sp.symbols("x y psi theta1 theta2 theta3", real=True)
Q = (x, y, psi, th1, th2, th3)
V = sp.symbols("xd yd psid theta1d theta2d theta3d", real=True)  # full velocity
NU = V[3:]  # independent speeds (th1dot, th2dot, th3dot)
TAU = sp.symbols("m1 m2", real=True)  # motor torques

_INERTIA_READINGS = ("axle", "com")


def paper_defaults() -> dict:
    """Numerical values used in the paper's simulations (plus g)."""
    return dict(m=0.5, M=5.0, J1=0.2, J2=0.4, r=0.3, d=0.2, rho=0.5, g=9.81)


def _check_reading(inertia_about: str) -> str:
    if inertia_about not in _INERTIA_READINGS:
        raise ValueError(f"inertia_about must be one of {_INERTIA_READINGS}, got {inertia_about!r}")
    return inertia_about


_ANGLES = (psi, th1, th2, th3)
_SC = {a: (sp.Dummy(f"s_{a}"), sp.Dummy(f"c_{a}")) for a in _ANGLES}
_TO_SC = {f(a): sc[i] for a, sc in _SC.items() for i, f in enumerate((sp.sin, sp.cos))}
_FROM_SC = {v: k for k, v in _TO_SC.items()}


def _trig_reduce(e):
    """Cheap exact canonical form: expand, then sin(a)**k -> sin(a)**(k%2) *
    (1 - cos(a)**2)**(k//2) for every angle a.  Two expressions that are equal
    as trigonometric polynomials of the angles give identical results."""
    e = sp.expand(sp.expand_trig(sp.sympify(e)))
    e = e.xreplace(_TO_SC)
    for s_, c_ in _SC.values():
        if not e.has(s_):
            continue
        poly = sp.Poly(e, s_)
        e = sp.Add(*[coef * s_ ** (k % 2) * (1 - c_**2) ** (k // 2)
                     for (k,), coef in poly.terms()])
        e = sp.expand(e)
    return e.xreplace(_FROM_SC)


def _is_zero_trig(e) -> bool:
    """Exact test that a (matrix of) trigonometric expression(s) vanishes."""
    e = sp.sympify(e)
    if getattr(e, "is_Matrix", False):
        return all(_is_zero_trig(ei) for ei in e)
    num, _ = sp.fraction(sp.together(e))
    return _trig_reduce(num) == 0


def _simp(e):
    """Moderate simplification for the (small) final expressions."""
    return sp.trigsimp(sp.factor_terms(_trig_reduce(e)))


# ----------------------------------------------------------------------------
# route (b): Lagrangian of the unconstrained tree, explicit rotation matrices
# ----------------------------------------------------------------------------
def _Rz(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _Ry(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _tdiff(expr):
    """Time derivative of an expression in Q along the full velocity V."""
    return sum((sp.diff(expr, qi) * vi for qi, vi in zip(Q, V)), sp.S.Zero)


def _unskew(W):
    return sp.Matrix([W[2, 1], W[0, 2], W[1, 0]])


@functools.lru_cache(maxsize=None)
def _route_b(inertia_about: str = "axle"):
    _check_reading(inertia_about)
    l = r / rho
    ez = sp.Matrix([0, 0, 1])

    R1 = _Rz(psi)
    x1, y1 = R1[:, 0], R1[:, 1]
    RA = R1 * _Ry(th1)
    RB = R1 * _Ry(th2)
    # body frame C: columns x_C, y_C, z_C; at th3=0: x_C=-z1, y_C=x1, z_C=-y1
    P = sp.Matrix([[0, 1, 0], [0, 0, -1], [-1, 0, 0]])
    RC = R1 * _Ry(-th3) * P

    pC2 = sp.Matrix([x, y, r])
    pA = pC2 + (l / 2) * y1
    pB = pC2 - (l / 2) * y1
    pG = pC2 + RC * sp.Matrix([d, 0, 0])

    def omega(R):
        Rd = R.applyfunc(_tdiff)
        return _unskew(Rd * R.T).applyfunc(_trig_reduce)

    def vel(p):
        return p.applyfunc(_tdiff)

    wA, wB, wC = omega(RA), omega(RB), omega(RC)
    vA, vB, vG = vel(pA), vel(pB), vel(pG)

    Iw = sp.diag(m * r**2 / 4, m * r**2 / 2, m * r**2 / 4)  # wheel: body y = axle
    if inertia_about == "axle":
        # diag(J1,J2,J2) about C2; C2 lies on x_C at distance d from G
        IC_G = sp.diag(J1, J2 - M * d**2, J2 - M * d**2)
    else:
        IC_G = sp.diag(J1, J2, J2)

    def ke(mass, v, w, R, Ib):
        return (mass * (v.T * v)[0] + (w.T * R * Ib * R.T * w)[0]) / 2

    T = ke(m, vA, wA, RA, Iw) + ke(m, vB, wB, RB, Iw) + ke(M, vG, wC, RC, IC_G)
    T = _trig_reduce(T)
    Vpot = g * (m * pA[2] + m * pB[2] + M * pG[2])

    Mfull = sp.hessian(T, V).applyfunc(_trig_reduce)
    n = 6
    # Christoffel symbols of the first kind -> C(q, v)
    dM = [Mfull.diff(qk) for qk in Q]
    Cfull = sp.zeros(n, n)
    for i in range(n):
        for j in range(n):
            Cfull[i, j] = sp.expand(sum(
                (dM[k][i, j] + dM[j][i, k] - dM[i][j, k]) / 2 * V[k] for k in range(n)))
    gfull = sp.Matrix([sp.diff(Vpot, qi) for qi in Q]).applyfunc(_trig_reduce)

    # generalized forces by virtual power of the two motors (action-reaction)
    power = TAU[0] * (wA - wC).dot(y1) + TAU[1] * (wB - wC).dot(y1)
    power = _trig_reduce(power)
    Bfull = sp.Matrix([[sp.diff(power, vi, tj) for tj in TAU] for vi in V]).applyfunc(_trig_reduce)

    # rolling constraints: zero velocity of the wheel material point at contact
    vPA = vA + wA.cross(-r * ez)
    vPB = vB + wB.cross(-r * ez)
    cons = sp.Matrix([vPA[0], vPA[1], vPB[0], vPB[1]]).applyfunc(sp.expand)
    Afull = cons.jacobian(V).applyfunc(_trig_reduce)
    # solve the constraints for the dependent velocities (xd, yd, psid)
    sol = sp.solve(list(cons), V[:3], dict=True)
    assert len(sol) == 1
    sol = sol[0]
    vdep = sp.Matrix([sol[vi] for vi in V[:3]]).applyfunc(_simp)
    S = sp.Matrix.vstack(vdep.jacobian(NU), sp.eye(3)).applyfunc(_simp)

    v_of_nu = S * sp.Matrix(NU)
    Sdot = sp.zeros(6, 3)
    for k in range(6):
        Sdot += S.diff(Q[k]) * v_of_nu[k]
    Sdot = Sdot.applyfunc(_trig_reduce)
    C_at = Cfull.subs(dict(zip(V, v_of_nu)), simultaneous=True)

    M_r = (S.T * Mfull * S).applyfunc(_simp)
    C_r = (S.T * (Mfull * Sdot + C_at * S)).applyfunc(_simp)
    g_r = (S.T * gfull).applyfunc(_simp)
    B_r = (S.T * Bfull).applyfunc(_simp)

    return dict(M=Mfull, C=Cfull, g=gfull, B=Bfull, A=Afull, S=S, Sdot=Sdot,
                M_r=M_r, C_r=C_r, g_r=g_r, B_r=B_r, T=T, V=sp.expand(Vpot),
                pG=pG.applyfunc(_trig_reduce), wC=wC)


# ----------------------------------------------------------------------------
# route (a): KanesMethod with nonholonomic velocity constraints
# ----------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def _route_a(inertia_about: str = "axle"):
    _check_reading(inertia_about)
    import sympy.physics.mechanics as me

    l = r / rho
    qs = me.dynamicsymbols("x y psi theta1 theta2 theta3")
    us = me.dynamicsymbols("u1:7")
    qx, qy, qpsi, q1, q2, q3 = qs
    u1, u2, u3, u4, u5, u6 = us
    tau1, tau2 = TAU

    N = me.ReferenceFrame("N")
    F1 = N.orientnew("F1", "Axis", (qpsi, N.z))
    WA = F1.orientnew("WA", "Axis", (q1, F1.y))
    WB = F1.orientnew("WB", "Axis", (q2, F1.y))
    CB = F1.orientnew("CB", "Axis", (q3, -F1.y))  # rotation about -y1 by th3
    F1.set_ang_vel(N, u3 * N.z)
    WA.set_ang_vel(F1, u4 * F1.y)
    WB.set_ang_vel(F1, u5 * F1.y)
    CB.set_ang_vel(F1, -u6 * F1.y)

    O = me.Point("O")
    O.set_vel(N, 0)
    C2 = O.locatenew("C2", qx * N.x + qy * N.y + r * N.z)
    # generalized speeds: u1, u2 = velocity of C2 along x1, y1; u3 = psidot;
    # u4..u6 = (th1dot, th2dot, th3dot) = nu (independent)
    C2.set_vel(N, u1 * F1.x + u2 * F1.y)
    C2.set_vel(F1, 0)
    A = C2.locatenew("A", (l / 2) * F1.y)
    B = C2.locatenew("B", -(l / 2) * F1.y)
    A.v2pt_theory(C2, N, F1)
    B.v2pt_theory(C2, N, F1)
    # body frame C: x_C = -CB.z (towards G), z_C = -CB.y, y_C = CB.x
    G = C2.locatenew("G", -d * CB.z)
    G.v2pt_theory(C2, N, CB)
    PA = A.locatenew("PA", -r * N.z)
    PB = B.locatenew("PB", -r * N.z)
    PA.v2pt_theory(A, N, WA)
    PB.v2pt_theory(B, N, WB)

    Iw = me.inertia(WA, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4)
    IwB = me.inertia(WB, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4)
    xC, yC, zC = -CB.z, CB.x, -CB.y
    IC = J1 * (xC | xC) + J2 * (yC | yC) + J2 * (zC | zC)
    ref = C2 if inertia_about == "axle" else G
    bodyA = me.RigidBody("wheelA", A, WA, m, (Iw, A))
    bodyB = me.RigidBody("wheelB", B, WB, m, (IwB, B))
    bodyC = me.RigidBody("body", G, CB, M, (IC, ref))

    loads = [
        (A, -m * g * N.z), (B, -m * g * N.z), (G, -M * g * N.z),
        (WA, tau1 * F1.y), (CB, -tau1 * F1.y),
        (WB, tau2 * F1.y), (CB, -tau2 * F1.y),
    ]
    t = me.dynamicsymbols._t
    cp, sp_ = sp.cos(qpsi), sp.sin(qpsi)
    kd = [qx.diff(t) - (u1 * cp - u2 * sp_), qy.diff(t) - (u1 * sp_ + u2 * cp),
          qpsi.diff(t) - u3, q1.diff(t) - u4, q2.diff(t) - u5, q3.diff(t) - u6]
    vcons = [PA.vel(N).dot(F1.x), PB.vel(N).dot(F1.x), PA.vel(N).dot(F1.y)]
    kane = me.KanesMethod(N, q_ind=qs, u_ind=[u4, u5, u6], u_dependent=[u1, u2, u3],
                          kd_eqs=kd, velocity_constraints=vcons)
    kane.kanes_equations([bodyA, bodyB, bodyC], loads)
    # kane.mass_matrix is 6x6: rows = 3 dynamical equations (Fr + Fr* = 0,
    # coefficients of all udots, columns ordered u_ind + u_dep) stacked on the
    # 3 differentiated velocity constraints.  Eliminate the dependent udots.
    MMk = kane.mass_matrix
    Fk = kane.forcing
    p = 3
    MM_ti, MM_td = MMk[:p, :p], MMk[:p, p:]
    K_i, K_d = MMk[p:, :p], MMk[p:, p:]
    F_t, F_b = Fk[:p, :], Fk[p:, :]
    K_d_inv = K_d.inv()
    Mk = MM_ti - MM_td * K_d_inv * K_i
    Fk = F_t - MM_td * K_d_inv * F_b

    # dependent speeds from the constraints, then dynamicsymbols -> plain symbols
    dep = sp.solve(vcons, [u1, u2, u3], dict=True)[0]
    Fk = me.msubs(Fk, dep)
    Mk = me.msubs(Mk, dep)
    to_plain = dict(zip(qs, Q))
    to_plain.update(dict(zip([u4, u5, u6], NU)))
    # (no trigsimp here: it dominates the cost; comparisons are done exactly
    # with the tangent half-angle substitution, see _is_zero_trig)
    Mk = me.msubs(Mk, to_plain).applyfunc(sp.expand)
    Fk = me.msubs(Fk, to_plain).applyfunc(sp.expand)
    Bk = Fk.jacobian(sp.Matrix(TAU)).applyfunc(sp.expand)
    hk = (-Fk.subs({TAU[0]: 0, TAU[1]: 0})).applyfunc(sp.expand)  # = C_r nu + g_r
    return dict(M_r=Mk, h=hk, B_r=Bk)


# ----------------------------------------------------------------------------
# public API
# ----------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def symbolic_reduced(inertia_about: str = "axle") -> dict:
    """Simplified symbolic reduced model (route (b)).

    Returns a dict with sympy matrices ``M_r`` (3x3), ``C_r`` (3x3, linear in
    nu), ``g_r`` (3x1), ``B_r`` (3x2), ``h = C_r nu`` (3x1), and the full-model
    ``M``, ``C``, ``g``, ``B``, ``S``, ``Sdot``; plus the symbol tuples
    ``q``, ``v``, ``nu``, ``tau``, ``params``.
    """
    b = _route_b(inertia_about)
    h = (b["C_r"] * sp.Matrix(NU)).applyfunc(_simp)
    out = dict(b)
    out.update(h=h, q=Q, v=V, nu=NU, tau=TAU, params=PARAM_SYMS)
    return out


def paper_coefficients(inertia_about: str = "axle") -> list[dict]:
    """Rows of the reduced equations in the paper's form (eqs. 23, 25, 28).

    Row i:  sum_j Mr[i,j] th_j'' + sum_{products} coeff * (product) + g_r[i]
            = B_r[i,:] . (m1, m2).
    Returns one dict per row with keys 'dd1','dd2','dd3' (accelerations),
    '12','23','31','11','22','33' (velocity products th1d*th2d, th2d*th3d,
    th3d*th1d, th1d^2, th2d^2, th3d^2), 'grav' and 'B'.
    """
    s = symbolic_reduced(inertia_about)
    n1, n2, n3 = NU
    prods = {"12": n1 * n2, "23": n2 * n3, "31": n3 * n1, "11": n1**2, "22": n2**2, "33": n3**2}
    rows = []
    for i in range(3):
        poly = sp.Poly(sp.expand(s["h"][i]), *NU)
        row = {f"dd{j + 1}": s["M_r"][i, j] for j in range(3)}
        for k, mono in prods.items():
            row[k] = sp.trigsimp(sp.factor(poly.coeff_monomial(mono)))
        row["grav"] = s["g_r"][i]
        row["B"] = tuple(s["B_r"][i, :])
        rows.append(row)
    return rows


@functools.lru_cache(maxsize=None)
def _lambdified(inertia_about: str):
    s = symbolic_reduced(inertia_about)
    P = PARAM_SYMS
    lam = lambda args, e: sp.lambdify(args, e, modules="numpy")  # noqa: E731
    Vpot = s["V"]
    # M_r differentiated along the motion (for the skew-symmetry check)
    vq = s["S"] * sp.Matrix(NU)
    Mrdot = sp.zeros(3, 3)
    for k in range(6):
        Mrdot += s["M_r"].diff(Q[k]) * vq[k]
    return dict(
        M_r=lam((Q, P), s["M_r"]),
        C_r=lam((Q, NU, P), s["C_r"]),
        g_r=lam((Q, P), s["g_r"]),
        B_r=lam((Q, P), s["B_r"]),
        h_r=lam((Q, NU, P), s["h"]),
        Mdot_r=lam((Q, NU, P), Mrdot),
        M=lam((Q, P), s["M"]),
        C=lam((Q, V, P), s["C"]),
        g=lam((Q, P), s["g"]),
        B=lam((Q, P), s["B"]),
        S=lam((Q, P), s["S"]),
        Sdot=lam((Q, NU, P), s["Sdot"]),
        A=lam((Q, P), s["A"]),
        V=lam((Q, P), Vpot),
        T=lam((Q, V, P), s["T"]),
    )


def _bind(f, nargs, pvals):
    if nargs == 1:
        def wrapped(q):
            return np.asarray(f(tuple(np.asarray(q, float)), pvals), dtype=float)
    else:
        def wrapped(q, w):
            return np.asarray(f(tuple(np.asarray(q, float)), tuple(np.asarray(w, float)), pvals),
                              dtype=float)
    return wrapped


def quasimoro_reduced(params: dict | None = None, inertia_about: str = "axle") -> SimpleNamespace:
    """Numeric (numpy) callables of the Quasimoro model.

    Reduced (nu = (th1dot, th2dot, th3dot)):
      ``M_r(q)`` 3x3, ``C_r(q, nu)`` 3x3, ``g_r(q)`` (3,), ``B_r(q)`` 3x2,
      ``h_r(q, nu) = C_r nu`` (3,), ``Mdot_r(q, nu)`` 3x3.
    Full (v = qdot, 6-vector):
      ``M(q)`` 6x6, ``C(q, v)`` 6x6 (Christoffel), ``g(q)`` (6,), ``B(q)`` 6x2,
      ``S(q)`` 6x3, ``Sdot(q, nu)`` 6x3, ``A(q)`` 4x6 (contact-point velocity
      constraints, rank 3), ``V(q)`` potential energy, ``T(q, v)`` kinetic.
    Also ``rhs(t, state, tau=None)``: state = (q, nu) -> (qdot, nudot).

    ``q`` is the 6-vector (x, y, psi, th1, th2, th3).  params keys: m, M, J1,
    J2, r, d, rho, g (missing keys taken from :func:`paper_defaults`).
    """
    _check_reading(inertia_about)
    p = paper_defaults()
    if params:
        unknown = set(params) - set(PARAM_KEYS)
        if unknown:
            raise KeyError(f"unknown parameter(s) {sorted(unknown)}")
        p.update(params)
    pvals = tuple(float(p[k]) for k in PARAM_KEYS)
    L = _lambdified(inertia_about)
    ns = SimpleNamespace(params=dict(p), inertia_about=inertia_about)
    for name in ("M_r", "g_r", "B_r", "M", "g", "B", "S", "A"):
        setattr(ns, name, _bind(L[name], 1, pvals))
    for name in ("C_r", "h_r", "Mdot_r", "C", "Sdot", "T"):
        setattr(ns, name, _bind(L[name], 2, pvals))
    # vectors as flat 1-D arrays
    ns.g_r = (lambda f: (lambda q: f(q).ravel()))(ns.g_r)
    ns.g = (lambda f: (lambda q: f(q).ravel()))(ns.g)
    ns.h_r = (lambda f: (lambda q, w: f(q, w).ravel()))(ns.h_r)
    ns.V = lambda q: float(L["V"](tuple(np.asarray(q, float)), pvals))
    ns.T = (lambda f: (lambda q, v: float(f(q, v))))(ns.T)

    def rhs(t, state, tau=None):
        q, nu = state[:6], state[6:]
        force = -ns.h_r(q, nu).ravel() - ns.g_r(q).ravel()
        if tau is not None:
            tq = tau(t, state) if callable(tau) else tau
            force = force + ns.B_r(q) @ np.asarray(tq, float)
        nudot = np.linalg.solve(ns.M_r(q), force)
        return np.concatenate([ns.S(q) @ nu, nudot])

    def energy(q, nu):
        q = np.asarray(q, float)
        nu = np.asarray(nu, float)
        return 0.5 * nu @ ns.M_r(q) @ nu + ns.V(q)

    ns.rhs = rhs
    ns.energy = energy
    return ns


# ----------------------------------------------------------------------------
# self test: route (a) == route (b), plus structural checks
# ----------------------------------------------------------------------------
def _kane_numeric(inertia_about: str):
    a = _route_a(inertia_about)
    P = PARAM_SYMS
    return dict(
        M_r=sp.lambdify((Q, P), a["M_r"], modules="numpy"),
        h=sp.lambdify((Q, NU, P), a["h"], modules="numpy"),
        B_r=sp.lambdify((Q, P), a["B_r"], modules="numpy"),
    )


def self_test(n: int = 50, seed: int = 0, tol: float = 1e-10, verbose: bool = False) -> None:
    """Cross-check the two derivation routes and the conventions; raise on failure."""
    rng = np.random.default_rng(seed)
    for reading in _INERTIA_READINGS:
        b = _route_b(reading)
        a = _route_a(reading)
        # exact symbolic checks
        assert _is_zero_trig(a["M_r"] - b["M_r"]), reading
        assert _is_zero_trig(a["B_r"] - b["B_r"]), reading
        h_b = b["C_r"] * sp.Matrix(NU) + b["g_r"]
        assert _is_zero_trig(a["h"] - h_b), reading
        # conventions
        S_expected = sp.Matrix([
            [r / 2 * sp.cos(psi), r / 2 * sp.cos(psi), 0],
            [r / 2 * sp.sin(psi), r / 2 * sp.sin(psi), 0],
            [-rho, rho, 0],
            [1, 0, 0], [0, 1, 0], [0, 0, 1]])
        assert _is_zero_trig(b["S"] - S_expected)
        assert _is_zero_trig(b["A"] * b["S"])
        assert b["B"] == sp.Matrix([[0, 0], [0, 0], [0, 0], [1, 0], [0, 1], [1, 1]])
        G_expected = sp.Matrix([x, y, r]) + d * (sp.sin(th3) * sp.Matrix([sp.cos(psi), sp.sin(psi), 0])
                                                 - sp.cos(th3) * sp.Matrix([0, 0, 1]))
        assert _is_zero_trig(b["pG"] - G_expected)
        # numeric checks
        kn = _kane_numeric(reading)
        for _ in range(n):
            pd = paper_defaults()
            pr = {k: pd[k] * rng.uniform(0.5, 2.0) for k in PARAM_KEYS}
            if reading == "axle":  # keep the central inertia physical
                pr["J2"] = max(pr["J2"], pr["M"] * pr["d"] ** 2 + 0.05)
            model = quasimoro_reduced(pr, reading)
            pv = tuple(pr[k] for k in PARAM_KEYS)
            q = rng.uniform(-np.pi, np.pi, 6)
            nu = rng.normal(size=3) * 3
            Mr = model.M_r(q)
            np.testing.assert_allclose(Mr, np.asarray(kn["M_r"](tuple(q), pv), float),
                                       rtol=tol, atol=tol)
            hb = model.C_r(q, nu) @ nu + model.g_r(q).ravel()
            np.testing.assert_allclose(hb, np.asarray(kn["h"](tuple(q), tuple(nu), pv), float).ravel(),
                                       rtol=tol, atol=tol)
            np.testing.assert_allclose(model.B_r(q), np.asarray(kn["B_r"](tuple(q), pv), float),
                                       rtol=tol, atol=tol)
            # reduced = projection of the full model
            S = model.S(q)
            v = S @ nu
            np.testing.assert_allclose(S.T @ model.M(q) @ S, Mr, rtol=tol, atol=tol)
            Cr_full = S.T @ (model.M(q) @ model.Sdot(q, nu) + model.C(q, v) @ S)
            np.testing.assert_allclose(Cr_full, model.C_r(q, nu), rtol=tol, atol=tol)
            np.testing.assert_allclose(model.A(q) @ S, 0.0, atol=tol)
        if verbose:
            print(f"[{reading}] route (a) == route (b): OK")


if __name__ == "__main__":  # pragma: no cover
    import time

    t0 = time.perf_counter()
    for reading in _INERTIA_READINGS:
        s = symbolic_reduced(reading)
        print(f"=== inertia_about = {reading!r} ===")
        print("M_r =");  sp.pprint(s["M_r"])
        print("C_r nu ="); sp.pprint(s["h"])
        print("g_r ="); sp.pprint(s["g_r"])
        print("B_r ="); sp.pprint(s["B_r"])
        for i, row in enumerate(paper_coefficients(reading)):
            print(f"row {i + 1}:", row)
    print(f"derivation: {time.perf_counter() - t0:.2f} s")
    self_test(verbose=True)
    print(f"total: {time.perf_counter() - t0:.2f} s")

"""Independent symbolic oracle: Denavit-Hartenberg link transforms in both orders, with sympy.

No dependency on ``robotdyn`` or Pinocchio. Used by the errata checks of two papers that print D-H tables:

* Paul's (standard, distal) order, the one Zuniga-Aviles et al. cite and the one Chen et al.'s Table 1 follows:
  :math:`A = R_z(\\theta)\\,T_z(\\lambda)\\,T_x(l)\\,R_x(\\alpha)`;
* the modified (proximal, Craig 1986) order, the row's twist and length first:
  :math:`A = R_x(\\alpha)\\,T_x(l)\\,R_z(\\theta)\\,T_z(\\lambda)`.

:func:`linkage_r03` gives Chen et al.'s right-rear wheel centre in the body frame R from Table 1's rows D, B2, A3
(Paul's order), so that eq (10)'s joint terms can be checked against its exact time derivative and against the
paper's own eqs (5)-(8).
"""

from __future__ import annotations

import sympy as sp


def rot_x(a) -> sp.Matrix:
    """4x4 rotation by ``a`` about x."""
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]])


def rot_z(a) -> sp.Matrix:
    """4x4 rotation by ``a`` about z."""
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])


def trans(x, y, z) -> sp.Matrix:
    """4x4 translation."""
    T = sp.eye(4)
    T[0, 3], T[1, 3], T[2, 3] = x, y, z
    return T


def paul(theta, lam, l, alpha) -> sp.Matrix:
    """Paul's order: Rot(z, theta) Trans(0, 0, lambda) Trans(l, 0, 0) Rot(x, alpha)."""
    return rot_z(theta) * trans(0, 0, lam) * trans(l, 0, 0) * rot_x(alpha)


def modified(theta, lam, l, alpha) -> sp.Matrix:
    """Modified (Craig) order: Rot(x, alpha) Trans(l, 0, 0) Rot(z, theta) Trans(0, 0, lambda)."""
    return rot_x(alpha) * trans(l, 0, 0) * rot_z(theta) * trans(0, 0, lam)


def chain(rows, order) -> sp.Matrix:
    """Product of ``order(theta, lambda, l, alpha)`` over ``rows``."""
    T = sp.eye(4)
    for row in rows:
        T = T * order(*row)
    return T


# ------------------------------------------------------------------------- Chen et al., linkage suspension
A1, D1, A5, D5, A7, THETA1, BETA1 = sp.symbols("a1 d1 a5 d5 a7 theta1 beta1", real=True)


def linkage_r03() -> sp.Matrix:
    """Right-rear wheel centre in R from Table 1's rows D (pi/2, a1, -d1, 0), B2 (0, a5, d5, 3pi/2 - theta1),
    A3 (-pi/2, -a7, 0, beta1), the table's columns being (alpha, a, d, theta) in Paul's order."""
    rows = [(0, -D1, A1, sp.pi / 2), (3 * sp.pi / 2 - THETA1, D5, A5, 0), (BETA1, 0, -A7, -sp.pi / 2)]
    return sp.simplify(chain(rows, paul)[:3, 3])


def cross_matrix_eq6(r) -> sp.Matrix:
    """The matrix D of eqs (6)-(8) as printed: D w = w x r."""
    return sp.Matrix([[0, r[2], -r[1]], [-r[2], 0, r[0]], [r[1], -r[0], 0]])


def linkage_eqs5_8_joint_columns(r03: sp.Matrix, i: int = 3) -> tuple[sp.Matrix, sp.Matrix]:
    """The columns multiplying theta1' and beta1' in eq (5), evaluated with the paper's own eqs (6)-(8).

    omega1 = (0, (-1)^i theta1', 0), omega2 = (0, (-1)^i beta1', 0) (section 2), r13 = r03 with a1 = d1 = 0 and
    r23 = r13 with a5 = d5 = 0 (the text's recipe "if r01 equals 0 then a1 = 0, d1 = 0 ...").
    """
    r13 = r03.subs({A1: 0, D1: 0})
    r23 = r13.subs({A5: 0, D5: 0})
    w = sp.Matrix([0, (-1) ** i, 0])
    return sp.simplify(cross_matrix_eq6(r13) * w), sp.simplify(cross_matrix_eq6(r23) * w)

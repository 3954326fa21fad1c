"""Adaptable-wheel tricycle: the paper's closed forms and printed values, transcribed (no robotdyn model here).

Paper: A. Mardani, S. Ebrahimi, "A Novel Multimode Mobile Robot with Adaptable Wheel Geometry for Maneuverability
Improvement" (Mardani & Ebrahimi 2016, ``docs/bibliography.md``): the radius law of eq 1 and its
derivative (eq 33), the wheel offsets of eq 8, the inverse kinematics of eqs 3-17 and 24 (:func:`solve_ik`, eq 24's
Newton-Raphson replaced by scipy's hybrid root finder), the yaw update of eqs 18-23, the statics of eqs 25-34
(:func:`static_torques`; the free contact-force components of eqs 28-30 are chosen by the generic
:func:`robotdyn.contact.statics.solve_contact_forces`), the torque estimate of eq 35 and Table 2. How each garbled
equation was read: ``docs/errata/adaptable_wheel.md``. Parameters are a plain dict (Table 1 names of
:data:`.model.SPEC`), the surface any :class:`robotdyn.constraints.terrain.Terrain`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ...errors import ConstraintError, InputError
from ...contact.statics import solve_contact_forces
from ...constraints.terrain import Terrain

_WHEELS = ("fr", "fl", "r")
"""The paper's wheels (eq 8): front right, front left, rear."""
_COS30 = float(np.cos(np.pi / 6))
_Q0 = 2 * np.pi / 3
"""Default initial guess of the adjustment angles [rad] (120 deg)."""
IK_TOL = 1e-10
"""Convergence criterion ||C|| of the inverse kinematics (the paper used 1e-5, Table 1)."""


def radius_law(q: float, w: float) -> float:
    """Eq 1: close-loop pattern radius :math:`R_{ch} = w\\cos(q/2)\\cos(\\pi/6)` [m] for adjustment angle q [rad].

    Args:
        q: Adjustment angle q [rad] (0 to pi).
        w: The pattern width w [m].

    Returns:
        R_ch [m].
    """
    return w * np.cos(0.5 * q) * _COS30


def radius_law_d(q: float, w: float) -> float:
    """Eq 33: :math:`dR_{ch}/dq = -\\tfrac12 w\\sin(q/2)\\cos(\\pi/6)` [m/rad].

    Args:
        q: Adjustment angle q [rad] (0 to pi).
        w: The pattern width w [m].

    Returns:
        :math:`dR_{ch}/dq` [m/rad].
    """
    return -0.5 * w * np.sin(0.5 * q) * _COS30


def radius_law_dd(q: float, w: float) -> float:
    """:math:`d^2R_{ch}/dq^2 = -\\tfrac14 w\\cos(q/2)\\cos(\\pi/6)` [m/rad^2].

    Args:
        q: Adjustment angle q [rad] (0 to pi).
        w: The pattern width w [m].

    Returns:
        :math:`d^2R_{ch}/dq^2` [m/rad^2].
    """
    return -0.25 * w * np.cos(0.5 * q) * _COS30


def offsets(p: dict) -> dict[str, np.ndarray]:
    """Eq 8: wheel centres in the body frame X_CG Y_CG Z_CG [m] (Lx, Ly read per ``L_reading``).

    Args:
        p: The parameters as a plain dict (Table 1 names of :data:`.model.SPEC`: w, Lx, Ly, L_reading, R_ru [m], m
            [kg], g [m/s^2], mu).

    Returns:
        Wheel centre (3,) [m] by wheel (fr, fl, r).
    """
    s = 1.0 if p["L_reading"] == "half" else 0.5
    lx, ly = s * p["Lx"], s * p["Ly"]
    return {"fr": np.array([lx, -ly, 0.0]), "fl": np.array([lx, ly, 0.0]), "r": np.array([-lx, 0.0, 0.0])}


def q_range_radius(p: dict) -> tuple[float, float]:
    """Smallest and largest total radius R_T [m] over the adjustment range q in [0, pi] (eq 1).

    Args:
        p: The parameters as a plain dict (Table 1 names of :data:`.model.SPEC`: w, Lx, Ly, L_reading, R_ru [m], m
            [kg], g [m/s^2], mu).

    Returns:
        ``(smallest, largest)`` R_T [m].
    """
    return p["R_ru"], p["R_ru"] + p["w"] * _COS30


# ------------------------------------------------------------------------------------ eqs 4-24 (transcribed)
def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


_R2 = {"fr": _rx(np.pi / 2), "r": _rx(np.pi / 2), "fl": _rx(-np.pi / 2)}  # eq 9
_SIGN = {"fr": -1.0, "r": -1.0, "fl": 1.0}  # eq 11: translation (0, -+R_T, 0) in frame b


def paper_normal(terrain: Terrain, x: float, y: float) -> np.ndarray:
    """Eq 3 (read as :math:`N = (-f_x, -f_y, 1)`, not normalised).

    Args:
        terrain: The surface (a :class:`~robotdyn.constraints.terrain.Terrain`).
        x: World x [m].
        y: World y [m].

    Returns:
        N (3,), not normalised.
    """
    fx, fy = terrain.gradient(x, y)
    return np.array([-fx, -fy, 1.0])


@dataclass
class Commands:
    """The six commands of section 3 at one instant: path point (x_d, y_d) [m], height h_CG [m] along the normal,
    and the body angles q_xd, q_yd, q_zd [rad] of eq 4 (rotations about fixed Y, then X, then Z).

    Attributes:
        xd: Path point x_d [m].
        yd: Path point y_d [m].
        h: Height h_CG [m] of the CG along the surface normal.
        qx: Body angle q_xd [rad] (about fixed X).
        qy: Body angle q_yd [rad] (about fixed Y).
        qz: Body angle q_zd [rad] (about Z).
    """

    xd: float
    yd: float
    h: float
    qx: float = 0.0
    qy: float = 0.0
    qz: float = 0.0


def body_pose(cmd: Commands, terrain: Terrain) -> tuple[np.ndarray, np.ndarray]:
    """Eqs 4-6: rotation :math:`R_{CG}^0 = R_y(q_{yd}) R_x(q_{xd}) R_z(q_{zd})` and CG position
    :math:`d_{CG}^0 = [x_d, y_d, f(x_d, y_d)] + h_{CG}\\,n(x_d, y_d)` (world frame, m).

    Args:
        cmd: The six :class:`~robotdyn.robots.adaptable_wheel.paper.Commands`.
        terrain: The surface (a :class:`~robotdyn.constraints.terrain.Terrain`).

    Returns:
        ``(R_CG^0, d_CG^0)``.
    """
    R = _ry(cmd.qy) @ _rx(cmd.qx) @ _rz(cmd.qz)
    n = terrain.normal(cmd.xd, cmd.yd)
    d = np.array([cmd.xd, cmd.yd, terrain.height(cmd.xd, cmd.yd)]) + cmd.h * n
    return R, d


def contact_frame(R_cg: np.ndarray, d_cg: np.ndarray, offset: np.ndarray, tag: str, beta: float,
                  RT: float) -> tuple[np.ndarray, np.ndarray]:
    """Eqs 7-11: rotation :math:`R_{3i}^0` and origin :math:`d_{3i}^0` of the contact frame of wheel ``tag``.

    Args:
        R_cg: The body rotation R_CG^0 (3, 3) (eq 4).
        d_cg: The CG position d_CG^0 (3,) [m], world frame (eqs 5-6).
        offset: The wheel centre in the body frame (3,) [m] (eq 8).
        tag: The wheel: ``fr``, ``fl`` or ``r``.
        beta: The wheel's contact angle beta_i [rad].
        RT: The wheel's total radius R_T [m].

    Returns:
        ``(R_3i^0, d_3i^0)`` (3x3, 3 [m]).
    """
    R3 = R_cg @ _R2[tag] @ _rz(beta)
    d3 = d_cg + R_cg @ offset + R3 @ np.array([0.0, _SIGN[tag] * RT, 0.0])
    return R3, d3


def wheel_constraints(R_cg, d_cg, offset, tag, beta, RT, terrain) -> np.ndarray:
    """Eqs 12 and 14 of one wheel: :math:`C_i = d_{3i}(3) - f(d_{3i}(1), d_{3i}(2))` and
    :math:`CC_i = [1\\,0\\,0] (R_{3i}^0)^T N` at the contact point.

    Args:
        R_cg: The body rotation R_CG^0 (3, 3) (eq 4).
        d_cg: The CG position d_CG^0 (3,) [m], world frame (eqs 5-6).
        offset: The wheel centre in the body frame (3,) [m] (eq 8).
        tag: The wheel: ``fr``, ``fl`` or ``r``.
        beta: The wheel's contact angle beta_i [rad].
        RT: The wheel's total radius R_T [m].
        terrain: The surface (a :class:`~robotdyn.constraints.terrain.Terrain`).

    Returns:
        ``(C_i [m], CC_i)``.
    """
    R3, d3 = contact_frame(R_cg, d_cg, offset, tag, beta, RT)
    return np.array([d3[2] - terrain.height(d3[0], d3[1]), R3[:, 0] @ paper_normal(terrain, d3[0], d3[1])])


def ik_residual(x: np.ndarray, R_cg, d_cg, p: dict, terrain: Terrain) -> np.ndarray:
    """Eq 15: :math:`C = [C_{fr}, C_{fl}, C_r, CC_{fr}, CC_{fl}, CC_r]` for the unknowns of eq 16,
    :math:`x = [\\beta_{fr}, \\beta_{fl}, \\beta_r, q_{fr}, q_{fl}, q_r]` (rad).

    Args:
        x: An IK solution (beta_fr, beta_fl, beta_r, q_fr, q_fl, q_r) [rad] (eq 16).
        R_cg: The body rotation R_CG^0 (3, 3) (eq 4).
        d_cg: The CG position d_CG^0 (3,) [m], world frame (eqs 5-6).
        p: The parameters as a plain dict (Table 1 names of :data:`.model.SPEC`: w, Lx, Ly, L_reading, R_ru [m], m
            [kg], g [m/s^2], mu).
        terrain: The surface (a :class:`~robotdyn.constraints.terrain.Terrain`).

    Returns:
        C (6,).
    """
    off = offsets(p)
    out = np.empty(6)
    for k, tag in enumerate(_WHEELS):
        RT = p["R_ru"] + radius_law(x[3 + k], p["w"])
        out[[k, 3 + k]] = wheel_constraints(R_cg, d_cg, off[tag], tag, x[k], RT, terrain)
    return out


class MechanismRangeError(InputError):
    """A command needs an adjustment angle outside the mechanism's range 0-180 deg."""


def _needed_radius(R_cg, d_cg, p, terrain, tag, beta0: float) -> float:
    """The radius R_T [m] wheel ``tag`` would need (eqs 12, 14 solved for (beta, R_T): always well posed)."""
    off = offsets(p)[tag]
    RT0 = float(d_cg[2] - terrain.height(*(d_cg + R_cg @ off)[:2]))
    fun = partial(_wheel_rt, R_cg=R_cg, d_cg=d_cg, offset=off, tag=tag, terrain=terrain)
    from scipy.optimize import root

    sol = root(fun, [beta0, RT0], method="hybr", options={"xtol": 1e-14})
    if np.linalg.norm(fun(sol.x)) > 1e-8:
        raise ConstraintError(f"wheel {tag}: cannot touch the surface with any radius at these commands")
    return float(sol.x[1])


def _wheel_rt(z, R_cg, d_cg, offset, tag, terrain):
    return wheel_constraints(R_cg, d_cg, offset, tag, z[0], z[1], terrain)


def solve_ik(cmd: Commands, p: dict, terrain: Terrain, guess: np.ndarray | None = None,
             tol: float = IK_TOL) -> tuple[np.ndarray, float, int]:
    """Solve eq 15 for eq 16's unknowns by scipy's root finder (eq 24's Newton-Raphson, hybrid variant).

    Args:
        cmd: The six commands.
        p: Parameters (w, Lx, Ly, L_reading, R_ru).
        terrain: The surface of eq 2.
        guess: Initial (beta_fr, beta_fl, beta_r, q_fr, q_fl, q_r) [rad]; default zeros and 120 deg.
        tol: Required ||C|| (eq 24's error).

    Returns:
        ``(x, error, nfev)``: the solution (q in [0, pi]), ||C|| and the number of residual evaluations.

    Raises:
        MechanismRangeError: a wheel needs q outside 0-180 deg (names the wheel, the radius and the limit).
        ConstraintError: no solution found.
    """
    R_cg, d_cg = body_pose(cmd, terrain)
    x0 = np.array([0.0, 0.0, 0.0, _Q0, _Q0, _Q0]) if guess is None else np.array(guess, float)
    f = partial(ik_residual, R_cg=R_cg, d_cg=d_cg, p=p, terrain=terrain)
    from scipy.optimize import root

    sol = root(f, x0, method="hybr", options={"xtol": 1e-15})
    x = sol.x.copy()
    x[3:] = np.abs(x[3:])  # eq 1 is even in q: -q and q give the same radius
    err = float(np.linalg.norm(f(x)))
    lo, hi = q_range_radius(p)
    for k, tag in enumerate(_WHEELS):
        if err > tol or not (0.0 <= x[3 + k] <= np.pi):
            RT = _needed_radius(R_cg, d_cg, p, terrain, tag, x[k] if np.isfinite(x[k]) else 0.0)
            if RT > hi + 1e-12:
                raise MechanismRangeError(
                    f"wheel {tag}: the commands need radius R_T = {RT:.4f} m, more than the {hi:.4f} m the mechanism "
                    "gives at its limit q = 0 deg (adjustment range 0-180 deg)")
            if RT < lo - 1e-12:
                raise MechanismRangeError(
                    f"wheel {tag}: the commands need radius R_T = {RT:.4f} m, less than the {lo:.4f} m the mechanism "
                    "gives at its limit q = 180 deg (adjustment range 0-180 deg)")
    if err > tol:
        raise ConstraintError(f"inverse kinematics did not converge: ||C|| = {err:.3g} > {tol:g} ({sol.message})")
    off = offsets(p)
    for k, tag in enumerate(_WHEELS):  # eq 14 also holds at the top of the rim: keep the contact below the centre
        R3, d3 = contact_frame(R_cg, d_cg, off[tag], tag, x[k], p["R_ru"] + radius_law(x[3 + k], p["w"]))
        if (d_cg + R_cg @ off[tag] - d3) @ terrain.normal(d3[0], d3[1]) <= 0:
            raise ConstraintError(f"wheel {tag}: the solution found touches the surface with the top of the rim "
                                  f"(beta = {np.degrees(x[k]):.1f} deg); expected a wheel standing on the surface")
    return x, err, int(sol.nfev)


def yaw_update(qz: float, path_angle_change: float, R_cg: np.ndarray, dqx: float, dqy: float) -> float:
    """Eqs 18-23 over one step: :math:`\\Delta q_{zd} = (\\Delta q_{path} - R_{CG}^0(3,1{:}2)[\\Delta q_{xd},
    \\Delta q_{yd}]) / R_{CG}^0(3,3)` (eq 22 times dt; q_path is the path tangent's direction, eq 18).

    Args:
        qz: The current q_zd [rad].
        path_angle_change: Change of the path tangent's direction over the step [rad].
        R_cg: The body rotation R_CG^0 (3, 3) (eq 4).
        dqx: Change of q_xd over the step [rad].
        dqy: Change of q_yd over the step [rad].

    Returns:
        The new q_zd [rad].
    """
    return qz + (path_angle_change - R_cg[2, :2] @ np.array([dqx, dqy])) / R_cg[2, 2]


# ------------------------------------------------------------------------------------------ statics (sec 5)
def paper_torque_eq35(q, p: dict):
    """Eq 35 as printed: :math:`t_i = -0.5\\,m g w \\sin(q_i/2)\\cos(\\pi/6) / 3` [N m] (flat-ground worst case).

    Args:
        q: Adjustment angle(s) q_i [rad].
        p: The parameters as a plain dict (Table 1 names of :data:`.model.SPEC`: w, Lx, Ly, L_reading, R_ru [m], m
            [kg], g [m/s^2], mu).

    Returns:
        The torque t_i [N m], shaped like ``q`` (a NumPy array or scalar).
    """
    return -0.5 * p["m"] * p["g"] * p["w"] * np.sin(0.5 * np.asarray(q)) * _COS30 / 3.0


@dataclass
class StaticResult:
    """Statics of one configuration by eqs 25-34.

    Attributes:
        torque: (3,) adjustment-motor torques t_i of eq 34 [N m] (fr, fl, r; the model's sign: q_i positive
            shrinks the wheel, so holding the weight needs t_i < 0 like eq 35).
        forces: (3, 3) contact forces on the robot, world frame [N] (eq 25).
        along_u: (3,) :math:`F_i^{3i}(2)`, read as the component along the contact-to-centre line [N].
        normal, friction, ratio: eq 27-30 quantities per wheel [N, N, -].
        contacts, normals: (3, 3) contact points [m] and unit normals.
        equilibrium: Residual of eq 25.
        method: How the forces were found (``kkt`` closed form or ``slsqp``).
    """

    torque: np.ndarray
    forces: np.ndarray
    along_u: np.ndarray
    normal: np.ndarray
    friction: np.ndarray
    ratio: np.ndarray
    contacts: np.ndarray
    normals: np.ndarray
    equilibrium: float
    method: str


def static_torques(cmd: Commands, x: np.ndarray, p: dict, terrain: Terrain,
                   extra_force=None, extra_moment=None, objective: str = "friction") -> StaticResult:
    """Eqs 25-34 at an IK solution: contact forces by constrained optimisation, then virtual work.

    The contacts must carry the weight m g acting at the CG (eq 25, read with the forces acting on the robot:
    :math:`\\sum F_i = (0, 0, mg)`, :math:`\\sum V_{CG}^i \\times F_i = 0`), plus an optional extra wrench about
    the CG (kinetostatics: minus the inertial forces). The free components are fixed by minimising the friction
    forces subject to :math:`F_i\\cdot n_i \\ge 0` (eq 28) and :math:`|F_t| \\le \\mu F_n` (eq 30); then
    eq 31 and eq 34, :math:`t_i = -0.5 F_i^{3i}(2)\\, w \\sin(q_i/2)\\cos(\\pi/6)`.

    Args:
        cmd: The six :class:`~robotdyn.robots.adaptable_wheel.paper.Commands`.
        x: An IK solution (beta_fr, beta_fl, beta_r, q_fr, q_fl, q_r) [rad] (eq 16).
        p: The parameters as a plain dict (Table 1 names of :data:`.model.SPEC`: w, Lx, Ly, L_reading, R_ru [m], m
            [kg], g [m/s^2], mu).
        terrain: The surface (a :class:`~robotdyn.constraints.terrain.Terrain`).
        extra_force: An extra force on the body at the CG (3,) [N], world frame (default ``None``: none).
        extra_moment: An extra moment about the CG (3,) [N m] (default ``None``: none).
        objective: What the free contact-force components minimise
            (:func:`robotdyn.contact.statics.solve_contact_forces`; default ``friction``).

    Returns:
        The :class:`StaticResult`.
    """
    R_cg, d_cg = body_pose(cmd, terrain)
    off = offsets(p)
    pts, nrm, us = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    for k, tag in enumerate(_WHEELS):
        RT = p["R_ru"] + radius_law(x[3 + k], p["w"])
        R3, d3 = contact_frame(R_cg, d_cg, off[tag], tag, x[k], RT)
        pts[k], nrm[k] = d3, terrain.normal(d3[0], d3[1])
        us[k] = -_SIGN[tag] * R3[:, 1]  # eq 11: the centre is at -/+ R_T Y_3 from the contact point
    force = np.array([0.0, 0.0, p["m"] * p["g"]])
    moment = np.zeros(3)
    if extra_force is not None:
        force = force + np.asarray(extra_force, float)
    if extra_moment is not None:
        moment = moment + np.asarray(extra_moment, float)
    cf = solve_contact_forces(pts, nrm, force, moment, d_cg, p["mu"], objective)
    along = np.einsum("ij,ij->i", cf.forces, us)  # eq 31, second component (contact -> centre)
    torque = along * radius_law_d(x[3:], p["w"])  # eq 34 (= eq 32 with eq 33)
    return StaticResult(torque, cf.forces, along, cf.normal, cf.friction, cf.ratio, pts, nrm, cf.equilibrium,
                        cf.method)


TABLE2 = {"r": (3.9, 115.0), "fl": (1.7, 55.0), "fr": (3.4, 160.0)}
"""Table 2 (mission 2): torque [N m] and angle [deg] of each adjustment motor."""


EQ35_LOAD_SHARE = 1.0 / 3.0
"""Sec 5, before eq 35: "the contact forces exerted to each wheel are equal to the one-third of the robot weight"
(the paper's flat-ground "worst case"), as a fraction of m g per wheel."""


def paper_flat_loads(p: dict) -> np.ndarray:
    """The wheel loads sec 5 assumes on flat ground: m g / 3 on each wheel [N] (fr, fl, r).

    Args:
        p: The parameters as a plain dict (Table 1 names of :data:`.model.SPEC`: m [kg], g [m/s^2], ...).

    Returns:
        (3,) loads [N] in the order fr, fl, r.
    """
    return np.full(3, EQ35_LOAD_SHARE * p["m"] * p["g"])

"""Derivatives of the reduced forward dynamics :math:`\\dot\\nu(q, \\nu, \\tau)` (Python reference).

The reduced equations (:mod:`robotdyn.reduction.reduced_dynamics`) say that the full-coordinate inverse dynamics,
less the motor forces, has no component along the admissible motions:

.. math:: F = S(q)^T\\,\\rho = 0,\\qquad \\rho = \\mathrm{RNEA}(q, v, a) - B(q)\\tau,\\quad v = S\\nu,\\quad
          a = S\\dot\\nu + w(q, \\nu).

Every projection here is :math:`K S = [0; I]`, :math:`K w = -[\\gamma_r; \\dot J_o v]` with
:math:`K = [A_r; J_o]` (the independent constraint rows and the rows defining :math:`\\nu`: a constant selection of
v, or a frame twist for operational-space robots, :mod:`robotdyn.reduction.operational_space`). Differentiating
(:math:`dS = -K^{-1} dK\\, S`, :math:`dw = -K^{-1}(dK\\,w + d[\\gamma_r; \\dot J_o v])`):

.. math:: M_r\\,d\\dot\\nu = -\\big[dS^T\\rho + S^T(\\partial_q\\mathrm{RNEA}\\,dq + \\partial_v\\mathrm{RNEA}\\,dv
          + M\\,da - dB\\,\\tau)\\big],\\qquad dS^T\\rho = -S^T dK^T \\mu,\\; \\mu = K^{-T}\\rho,

with :math:`dv = dS\\,\\nu + S\\,d\\nu` and :math:`da = -K^{-1}(dK\\,a + d[\\gamma_r; \\dot J_o v]) + S\\,d\\dot\\nu`.
The tree terms are Pinocchio's ``computeRNEADerivatives``; :math:`dK` enters only as
:math:`\\partial(Kx)/\\partial q` for x in {columns of S, w, v} (frame velocity derivatives,
:mod:`robotdyn.constraints.row_derivatives`), :math:`\\partial\\gamma/\\partial v = \\dot A + \\partial(Av)/\\partial q`
and likewise for :math:`\\dot J_o v`. Motors reacting on a body make B depend on q: their term is differentiated
through the same frame velocity derivatives.

Position coordinates: ``dq`` is the derivative with respect to the natural coordinates q that the simulation
integrates (:math:`\\dot q = S\\nu`, :mod:`robotdyn.simulation.engine`). Along the holonomic constraint manifold
only tangent directions are admissible: :attr:`DynamicsDerivatives.positions` names independent position
coordinates (a subset of q, the others being solved from the holonomic rows, chosen among the dependent
velocities where possible), :attr:`~DynamicsDerivatives.tangent` is :math:`\\partial q/\\partial q_P` and
``dq_manifold = dq @ tangent`` the derivative in those coordinates.

What is analytic: everything, except on a terrain that does not give its third derivatives
(:attr:`~robotdyn.constraints.terrain.Terrain.third`: a user's ``FunctionTerrain``; the built-in terrains give
them) and for a coupling law that is not a :class:`~robotdyn.constraints.joint_coupling.CosineLaw` (its
:math:`f'''`), where central differences are taken; :attr:`DynamicsDerivatives.numerical` lists the pieces so
computed at each call. Slipping wheels (friction laws) are refused here in one line: their derivatives are
:mod:`robotdyn.contact.sliding_derivatives` (a later stage), which reuses :func:`pieces`;
:meth:`robotdyn.robot.Robot.dynamics_derivatives` chooses.

Reference for the tree's derivatives (``computeRNEADerivatives``, the frame velocity and acceleration derivatives):
J. Carpentier, N. Mansard, *Analytical derivatives of rigid body dynamics algorithms*, Robotics: Science and
Systems XIV (RSS 2018), paper 38.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
import pinocchio as pin

from ..constraints.constraint import KinematicState, skew
from ..constraints.row_derivatives import FramePass, drift_dq, force_jacobian_dq, kind, velocity_dq, world_jacobians
from ..errors import InputError, NonFiniteError
from .actuation import input_matrix
from .operational_space import project_operational
from .projection import _pivoted_qr, independent_rows, project
from .joint_springs import spring_terms
from .reduced_dynamics import constraint_set, solve_mass


@dataclass
class DynamicsDerivatives:
    """The reduced forward dynamics and its derivatives at one state (SI units).

    Attributes:
        nudot: :math:`\\dot\\nu` (k,) [rad/s^2 or m/s^2].
        dq: :math:`\\partial\\dot\\nu/\\partial q` (k, n), natural coordinates (valid along tangent directions of
            the holonomic manifold; see ``dq_manifold``).
        dnu: :math:`\\partial\\dot\\nu/\\partial\\nu` (k, k).
        dtau: :math:`\\partial\\dot\\nu/\\partial\\tau` (k, n_motors) = :math:`M_r^{-1}B_r`.
        qdot: :math:`\\dot q = S\\nu` (n,).
        dqdot_dq: :math:`\\partial(S\\nu)/\\partial q` (n, n); :math:`\\partial\\dot q/\\partial\\nu = S`.
        S: (n, k).
        positions: Indices into q of independent position coordinates (p,).
        tangent: :math:`\\partial q/\\partial q_P` (n, p): identity on ``positions``, the dependent coordinates
            following the holonomic rows to first order.
        dq_manifold: ``dq @ tangent`` (k, p).
        numerical: The pieces computed by finite differences (empty: everything analytic).
        coordinates, velocities, motors: Names of q, nu and tau.
    """

    nudot: np.ndarray
    dq: np.ndarray
    dnu: np.ndarray
    dtau: np.ndarray
    qdot: np.ndarray
    dqdot_dq: np.ndarray
    S: np.ndarray
    positions: np.ndarray
    tangent: np.ndarray
    dq_manifold: np.ndarray
    numerical: tuple[str, ...] = ()
    coordinates: list[str] = field(default_factory=list)
    velocities: list[str] = field(default_factory=list)
    motors: list[str] = field(default_factory=list)

    @property
    def position_names(self) -> list[str]:
        """Names of the independent position coordinates."""
        return [self.coordinates[i] for i in self.positions]


def position_coordinates(A_h: np.ndarray, prefer: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Independent position coordinates for holonomic rows ``A_h`` (m_h, n) and :math:`\\partial q/\\partial q_P`.

    The dependent coordinates (one per independent row) are chosen by QR with column pivoting among ``prefer``
    (e.g. the projection's dependent velocities) when those span the rows, else among all columns.

    Args:
        A_h: The holonomic constraint rows (m_h, n) at q, columns in the order of the natural coordinates
            (redundant rows allowed).
        prefer: Indices into q (any order) among which to choose the dependent coordinates first, or None
            (default: all columns).

    Returns:
        ``(positions, tangent)``: indices (p,) and T (n, p) with :math:`A_h T = 0`, identity on ``positions``.
    """
    n = A_h.shape[1]
    rows = independent_rows(A_h) if A_h.size else np.zeros(0, int)
    if rows.size == 0:
        return np.arange(n), np.eye(n)
    Ar = A_h[rows]
    dep = None
    for cand in ([np.asarray(prefer, int)] if prefer is not None and len(prefer) >= rows.size else []) + [np.arange(n)]:
        _, piv = _pivoted_qr(Ar[:, cand])
        trial = np.sort(cand[piv[:rows.size]])
        if np.linalg.matrix_rank(Ar[:, trial]) == rows.size:
            dep = trial
            break
    ind = np.setdiff1d(np.arange(n), dep)
    T = np.zeros((n, ind.size))
    T[ind, np.arange(ind.size)] = 1.0
    T[dep] = -np.linalg.solve(Ar[:, dep], Ar[:, ind])
    return ind, T


class _Projection:
    """K = [A_r; J_o] of one reduction: S, w's solve and the multiplier :math:`\\mu = K^{-T}\\rho`."""

    def __init__(self, robot, kin0: KinematicState, A: np.ndarray) -> None:
        self.op = getattr(robot, "operational", None)
        n = A.shape[1]
        self.n = n
        if self.op is None:
            # the row choice of the robot's own reduction (its hint: the last projection's rows while they still
            # span the row space), so that S, and hence every number, is the one reduce() gives
            proj = project(A, robot.independent_indices, robot.velocity_labels, hint=robot._projection_hint)
            robot._projection_hint = proj
            self.rows, self.dep, self.Ad_inv = proj.rows, proj.dependent, proj.Ad_inv
            self.S = proj.S
            self.twist = None
        else:
            self.twist = self.op.twist
            J = self.twist.jacobian(kin0)
            proj = project_operational(A, J, self.twist.names)
            self.rows, self.Kinv, self.S = proj.rows, proj._inv, proj.S

    def solve_neg(self, dA: np.ndarray, dJ: np.ndarray | None) -> np.ndarray:
        """:math:`-K^{-1}[dA_r; dJ]` (n, cols); ``dA`` holds all constraint rows."""
        if self.twist is None:
            out = np.zeros((self.n, dA.shape[1]))
            if self.rows.size:
                out[self.dep] = -self.Ad_inv @ dA[self.rows]
            return out
        return -self.Kinv @ np.vstack([dA[self.rows], dJ])

    def multiplier(self, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """:math:`\\mu = K^{-T}\\rho`, split into the constraint rows' part and the twist rows' part."""
        if self.twist is None:
            return (self.Ad_inv.T @ rho[self.dep] if self.rows.size else np.zeros(0)), None
        mu = self.Kinv.T @ rho
        return mu[:self.rows.size], mu[self.rows.size:]

    def twist_velocity_dq(self, fpass: FramePass) -> np.ndarray | None:
        """:math:`\\partial(J_o x)/\\partial q` at fixed x (k, n) (None without a twist)."""
        if self.twist is None:
            return None
        t = self.twist
        dV = fpass.local_velocity(t.fid)[1] if t.axes == "local" else fpass.velocity(t.fid)[1]
        return dV[t.select]

    def twist_drift_dq(self, fpass: FramePass) -> np.ndarray | None:
        """:math:`\\partial(\\dot J_o v)/\\partial q` at fixed v = ``fpass.x`` (LOCAL: the body-axes spatial
        acceleration; world axes: the classical acceleration)."""
        if self.twist is None:
            return None
        t = self.twist
        dA = fpass.local_acceleration(t.fid)[1] if t.axes == "local" else fpass.acceleration(t.fid)[1]
        return dA[t.select]


def motor_rows(robot, kin0: KinematicState, passes: list[FramePass], tau: np.ndarray) -> np.ndarray:
    """:math:`S^T\\,\\partial(B(q)\\tau)/\\partial q` at fixed S (k, n): row l is the q-derivative of
    :math:`s_l^T B\\tau = \\sum_j \\tau_j(\\omega_{\\text{child}}(s_l) - \\omega_{\\text{reaction}}(s_l))\\cdot\\hat a_j`
    (:mod:`robotdyn.reduction.actuation`), :math:`\\partial\\hat a/\\partial q = -[\\hat a]_\\times J_\\omega`.
    Motors without a reaction body have constant columns (no term).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (its model and motors).
        kin0: Kinematics at q (joint axes in world axes).
        passes: Frame passes at the velocities :math:`s_l` (n,) [m/s, rad/s], e.g. the columns of S (then the
            result is :math:`S^T\\,\\partial(B\\tau)/\\partial q`), or the unit vectors (then
            :math:`\\partial(B\\tau)/\\partial q` itself).
        tau: Motor torques/forces (n_motors,) [N m or N] in the order of ``robot.motors``.

    Returns:
        The derivative (len(passes), n) [N m or N per unit of each coordinate].
    """
    model = robot.model
    out = np.zeros((len(passes), model.nv))
    for j, m in enumerate(robot.motors):
        if m.rid is None or tau[j] == 0.0:
            continue
        cf = model.getFrameId(m.joint)
        _, jac_c = kin0.pose(cf)
        axis = jac_c[3:, m.index]
        daxis = -np.cross(axis[:, None], jac_c[3:], axis=0)  # -[a]x Jw
        for l, fp in enumerate(passes):
            Vc, dVc = fp.velocity(cf)
            Vr, dVr = fp.velocity(m.rid)
            out[l] += tau[j] * (axis @ (dVc[3:] - dVr[3:]) + (Vc[3:] - Vr[3:]) @ daxis)
    return out


def motor_force_dq(robot, kin0: KinematicState, tau: np.ndarray) -> np.ndarray:
    """:math:`\\partial(B(q)\\tau)/\\partial q` (n, n) of the motors reacting on a body, without frame passes:
    :math:`B\\tau = \\sum_j \\tau_j (J_{\\omega,\\text{child}} - J_{\\omega,\\text{reaction}})^T\\hat a_j`, a pure
    moment :math:`\\tau_j\\hat a_j` on the joint's body and its opposite on the reaction body, differentiated at
    fixed moment (:func:`~robotdyn.constraints.row_derivatives.force_jacobian_dq`) plus
    :math:`(J_{\\omega,c} - J_{\\omega,r})^T\\tau_j\\,\\partial\\hat a/\\partial q` (twin of the compiled
    ``ReducedDerivatives::motor_force_dq``; :func:`motor_rows` at the unit velocities gives the same matrix).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (its model and motors).
        kin0: Kinematics at q (joint axes in world axes).
        tau: Motor torques/forces (n_motors,) [N m or N] in the order of ``robot.motors``.

    Returns:
        The derivative (n, n) [N m or N per unit of each coordinate].
    """
    model = robot.model
    out = np.zeros((model.nv, model.nv))
    J = None
    for j, m in enumerate(robot.motors):
        if m.rid is None or tau[j] == 0.0:
            continue
        if J is None:
            J = world_jacobians(kin0)
        cf = model.getFrameId(m.joint)
        _, jac_c = kin0.pose(cf)
        _, jac_r = kin0.pose(m.rid)
        axis = jac_c[3:, m.index]
        daxis = -np.cross(axis[:, None], jac_c[3:], axis=0)  # -[a]x Jw
        phi = np.concatenate([np.zeros(3), tau[j] * axis])
        force_jacobian_dq(model, J, model.frames[cf].parentJoint, phi, out)
        force_jacobian_dq(model, J, model.frames[m.rid].parentJoint, phi, out, -1.0)
        out += tau[j] * (jac_c[3:] - jac_r[3:]).T @ daxis
    return out


def twist_force_dq(twist, kin0: KinematicState, mu: np.ndarray) -> np.ndarray:
    """:math:`\\partial(J_o^T\\mu_o)/\\partial q` at fixed :math:`\\mu_o` (n, n) of the operational twist's rows: a
    wrench at the frame's origin p (mu on the selected components, force then moment; in the frame's own axes if
    LOCAL, else world axes), :math:`\\Phi = (f, p\\times f + m)` at the world origin in world axes; its derivative is
    that of the Jacobian at fixed :math:`\\Phi` (:func:`~robotdyn.constraints.row_derivatives.force_jacobian_dq`)
    plus :math:`J_O^T\\partial\\Phi/\\partial q`, :math:`\\partial f = -[f]_\\times J_\\omega`,
    :math:`\\partial m = -[m]_\\times J_\\omega` if LOCAL (else zero) and
    :math:`\\partial(p\\times f) = -[f]_\\times J_v + [p]_\\times\\partial f` (twin of the compiled
    ``twist_force_dq``; :meth:`_Projection.twist_velocity_dq` at the unit velocities gives the same matrix).

    Args:
        twist: The operational frame twist (its ``fid``, ``axes`` and ``select``).
        kin0: Kinematics at q.
        mu: The twist rows' multipliers (len(select),), held fixed.

    Returns:
        The derivative (n, n).
    """
    model = kin0.model
    J = world_jacobians(kin0)
    w6 = np.zeros(6)
    np.add.at(w6, np.asarray(twist.select), mu)
    placement, jac = kin0.pose(twist.fid)
    R, p = placement.rotation, placement.translation
    local = twist.axes == "local"
    f, m = (R @ w6[:3], R @ w6[3:]) if local else (w6[:3], w6[3:])
    out = np.zeros((model.nv, model.nv))
    force_jacobian_dq(model, J, model.frames[twist.fid].parentJoint, np.concatenate([f, np.cross(p, f) + m]), out)
    Jv, Jw = jac[:3], jac[3:]
    df = -skew(f) @ Jw if local else np.zeros_like(Jw)
    dm = -skew(m) @ Jw if local else np.zeros_like(Jw)
    dphi = np.vstack([df, -skew(f) @ Jv + skew(p) @ df + dm])
    JO = np.vstack([Jv + skew(p) @ Jw, Jw])
    return out + JO.T @ dphi


class Pieces(SimpleNamespace):
    """The derivative pieces shared by every reduction at one state (q, nu), before the dynamics is solved:
    kinematics (``kin0``, ``kin``), the projection ``P`` (``S``, ``v``, ``w``), the full rows ``full`` (with
    Adot) and ``rows0``, the input matrix ``B``, the mass matrix ``M``, the frame passes at the columns of S, w and v
    with the rows' derivatives (``dA_cols``, ``dA_w``, ``dA_v``; ``dJ_*`` for a twist), ``Vq`` =
    :math:`\\partial(S\\nu)/\\partial q`, the drift's total q-derivative ``dgA`` (``dgJ``), ``Wnu`` =
    :math:`\\partial w/\\partial\\nu`, and ``numerical``."""

    def Aq(self, nudot: np.ndarray) -> np.ndarray:
        """:math:`\\partial a/\\partial q` at fixed :math:`\\dot\\nu`, :math:`a = S\\dot\\nu + w`:
        :math:`-K^{-1}(\\partial(Ka)/\\partial q + dg)` (n, n).

        Args:
            nudot: :math:`\\dot\\nu` (k,) [m/s^2, rad/s^2], held fixed.

        Returns:
            The derivative (n, n) of the full accelerations [m/s^2, rad/s^2] per unit of each coordinate.
        """
        k = len(nudot)
        dKa_A = self.dA_w + sum(nudot[l] * self.dA_cols[l] for l in range(k))
        if self.P.twist is None:
            return self.P.solve_neg(dKa_A + self.dgA, None)
        dKa_J = self.dJ_w + sum(nudot[l] * self.dJ_cols[l] for l in range(k))
        return self.P.solve_neg(dKa_A + self.dgA, dKa_J + self.dgJ)


def pieces(robot, q: np.ndarray, nu: np.ndarray) -> Pieces:
    """The :class:`Pieces` at (q, nu) (q, nu already validated; slipping wheels' normal rows are ordinary rows
    here: :mod:`robotdyn.contact.sliding_derivatives` adds their friction).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], already checked (``robot.check_q``).
        nu: Independent velocities (k,) [m/s, rad/s] in the order of ``robot.velocity_names``, already checked.

    Returns:
        The :class:`Pieces`.

    Raises:
        InputError: A constraint without a derivative rule
            (:func:`~robotdyn.constraints.row_derivatives.kind`).
    """
    model = robot.model
    n = model.nv
    constraints = list(robot.constraints)
    for c in constraints:
        kind(c, sliding=True)
    data = model.createData()
    kin0 = KinematicState(model, data, q, np.zeros(n))
    rows0 = constraint_set(robot).jacobian(kin0)
    P = _Projection(robot, kin0, rows0.A)
    S = P.S
    k = S.shape[1]
    v = S @ nu
    kin = kin0.with_velocity(v)
    Jodot = None
    if P.twist is not None:
        _, Jodot = P.twist.rows(kin)
    full = robot.constraint_rows(kin)
    gamma = full.Adot @ v if full.A.size else np.zeros(0)
    B = input_matrix(robot.motors, kin)
    if P.twist is None:
        w = P.solve_neg(gamma[:, None] if gamma.size else np.zeros((0, 1)), None)[:, 0]
    else:
        w = P.solve_neg(gamma[:, None], (Jodot @ v)[:, None])[:, 0]
    tree = model.createData()  # kept alive: Pinocchio returns views into its data
    M = pin.crba(model, tree, q).copy()
    M = np.triu(M) + np.triu(M, 1).T

    numerical: set[str] = set()
    cols = [FramePass(kin0, S[:, l]) for l in range(k)]
    fw = FramePass(kin0, w)
    fv = FramePass(kin0, v)
    dA_cols = [velocity_dq(constraints, fp) for fp in cols]
    dJ_cols = [P.twist_velocity_dq(fp) for fp in cols]
    dA_w, dJ_w = velocity_dq(constraints, fw), P.twist_velocity_dq(fw)
    dA_v, dJ_v = velocity_dq(constraints, fv), P.twist_velocity_dq(fv)
    dgam_q = drift_dq(constraints, fv, numerical)
    dgam_v = (full.Adot + dA_v) if full.A.size else np.zeros((0, n))
    if P.twist is not None:
        dJd_q = P.twist_drift_dq(fv)
        dJd_v = Jodot + dJ_v
    else:
        dJd_q = dJd_v = None
    # v = S(q) nu: dv/dq = -K^{-1} d(K v)/dq
    Vq = P.solve_neg(dA_v, dJ_v)
    # the drift terms along the motion: d g / dq with v = S(q) nu
    dgA = dgam_q + dgam_v @ Vq
    dgJ = None if dJd_q is None else dJd_q + dJd_v @ Vq
    # nu-derivative of w: dv = S dnu, dw/dnu = -K^{-1} dg/dv S
    Wnu = P.solve_neg(dgam_v @ S, None if dJd_v is None else dJd_v @ S)
    return Pieces(model=model, n=n, k=k, q=q, nu=nu, kin0=kin0, kin=kin, rows0=rows0, P=P, S=S, v=v, w=w,
                  full=full, B=B, M=M, tree=tree, cols=cols, fv=fv, dA_cols=dA_cols, dJ_cols=dJ_cols, dA_w=dA_w,
                  dJ_w=dJ_w, dA_v=dA_v, dJ_v=dJ_v, Vq=Vq, dgA=dgA, dgJ=dgJ, Wnu=Wnu, numerical=numerical,
                  constraints=constraints)


def result(robot, pc: Pieces, nudot, dq, dnu, dtau) -> DynamicsDerivatives:
    """Assemble a :class:`DynamicsDerivatives` (independent position coordinates, the tangent, finiteness).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (names of coordinates, velocities, motors).
        pc: The :class:`Pieces` at the state.
        nudot: :math:`\\dot\\nu` (k,) [m/s^2, rad/s^2].
        dq: :math:`\\partial\\dot\\nu/\\partial q` (k, n).
        dnu: :math:`\\partial\\dot\\nu/\\partial\\nu` (k, k) [1/s].
        dtau: :math:`\\partial\\dot\\nu/\\partial\\tau` (k, n_motors).

    Returns:
        The :class:`DynamicsDerivatives`.

    Raises:
        NonFiniteError: ``nudot``, ``dq``, ``dnu``, ``dtau`` or :math:`\\partial\\dot q/\\partial q` not finite.
    """
    hol = pc.rows0.holonomic
    prefer = pc.P.dep if pc.P.twist is None else None
    positions, T = position_coordinates(pc.rows0.A[hol], prefer)
    out = DynamicsDerivatives(nudot, dq, dnu, dtau, pc.v, pc.Vq, pc.S, positions, T, dq @ T,
                              tuple(sorted(pc.numerical)), list(robot.coordinates), list(robot.velocity_names),
                              [m.name for m in robot.motors])
    for name in ("nudot", "dq", "dnu", "dtau", "dqdot_dq"):
        if not np.all(np.isfinite(getattr(out, name))):
            raise NonFiniteError(f"dynamics derivatives: {name} is not finite at this state (|q| up to "
                                 f"{np.max(np.abs(pc.q)):.3g}, |nu| up to {np.max(np.abs(pc.nu), initial=0):.3g})")
    return out


def dynamics_derivatives(robot, q, nu, tau, pc: Pieces | None = None) -> DynamicsDerivatives:
    """:math:`\\dot\\nu` and its derivatives in q, :math:`\\nu` and :math:`\\tau` at one state (Python path).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` whose constraints are rolling wheels (standard, omni, support),
            loop closures and joint couplings; operational-space velocities are supported (slipping wheels:
            :func:`robotdyn.contact.sliding_derivatives.sliding_derivatives`, which
            :meth:`robotdyn.robot.Robot.dynamics_derivatives` chooses).
        q: Natural coordinates (n,) [m, rad] in the order of ``robot.coordinates``, on the holonomic constraint
            manifold for ``dq_manifold`` to be the derivative along it.
        nu: Independent velocities (k,) [m/s, rad/s] in the order of ``robot.velocity_names``.
        tau: Motor torques/forces (n_motors,) [N m or N] in the order of ``robot.motors``.
        pc: The derivative :class:`~robotdyn.reduction.dynamics_derivatives.Pieces` at (q, nu) when the caller
            has them already (default None: computed here).

    Returns:
        A :class:`DynamicsDerivatives`.

    Raises:
        InputError: A constraint without derivatives here (slipping wheels), or wrong sizes.
        NonFiniteError: A non-finite result.
    """
    q, nu, tau = robot.check_q(q), robot.check_nu(nu), robot.check_tau(tau)
    for c in robot.constraints:
        kind(c)
    pc = pieces(robot, q, nu) if pc is None else pc
    S, M, k, n = pc.S, pc.M, pc.k, pc.n
    model, tree, v, w, B = pc.model, pc.tree, pc.v, pc.w, pc.B
    Mr = S.T @ M @ S
    Br = S.T @ B
    Q, dQ_dq, dQ_dv = spring_terms(getattr(robot, "springs", ()), q, v)  # joint springs and dampers (zeros: none)
    nudot = solve_mass(Mr, Br @ tau - S.T @ (pin.rnea(model, tree, q, v, w) - Q))
    a = S @ nudot + w
    rho = pin.rnea(model, tree, q, v, a) - B @ tau - Q
    dtau_dq, dtau_dv, _ = (x.copy() for x in pin.computeRNEADerivatives(model, tree, q, v, a))
    dtau_dq -= dQ_dq  # rho's derivatives: the tree's less the springs' (stiffness) and dampers' (damping)
    dtau_dv -= dQ_dv
    # dS^T rho = -S^T dK^T mu
    P = pc.P
    muA, muJ = P.multiplier(rho)
    L = np.zeros((k, n))
    for l in range(k):
        if muA.size:
            L[l] += muA @ pc.dA_cols[l][P.rows]
        if muJ is not None:
            L[l] += muJ @ pc.dJ_cols[l]
    G = -L + S.T @ (dtau_dq + dtau_dv @ pc.Vq + M @ pc.Aq(nudot)) - motor_rows(robot, pc.kin0, pc.cols, tau)
    Mr_inv = solve_mass(Mr, np.eye(k))
    dq = -Mr_inv @ G
    dnu = -Mr_inv @ (S.T @ (dtau_dv @ S + M @ pc.Wnu))
    dtau = Mr_inv @ Br
    return result(robot, pc, nudot, dq, dnu, dtau)


__all__ = ["DynamicsDerivatives", "dynamics_derivatives", "position_coordinates", "pieces", "Pieces", "result",
           "motor_rows"]

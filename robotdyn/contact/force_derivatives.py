"""Derivatives of the wheel contact forces and of each wheel's required mu (Python path).

The forces are those :func:`robotdyn.contact.contact_forces.constraint_forces` reports for given motor torques
(forward dynamics), differentiated in q, :math:`\\nu` and :math:`\\tau`. Two layers:

1. **Forces at known motion** :math:`\\lambda(q, v, a, \\tau)`. The multipliers of :math:`M a + h = B\\tau +
   A^T\\lambda` (with slipping wheels :math:`G\\lambda = e`, :math:`G = A^T - \\sum_i J_{t,i}^T c_i(s_i)
   e_{n_i}^T`, their friction force being :math:`-\\lambda_{n_i} c_i`: :mod:`robotdyn.contact.sliding`) are the
   unique solution of the KKT system

   .. math:: \\begin{bmatrix} W + P_o & A & C_U^T \\\\ G & 0 & 0 \\\\ C_U & 0 & 0\\end{bmatrix}
             \\begin{bmatrix}\\lambda \\\\ u \\\\ \\mu\\end{bmatrix} = \\begin{bmatrix} 0 \\\\ e \\\\ 0
             \\end{bmatrix},\\qquad e = \\mathrm{RNEA}(q, v, a) - B(q)\\tau,

   which says everything the force model says: :math:`G\\lambda = e` (the equations of motion); where rigid-body
   dynamics leave loads open (rows redundant, null space N of :math:`A^T`), the rigid limit of the wheels' normal
   compliance (:mod:`robotdyn.contact.rigid_limit`): :math:`\\lambda` minimises the complementary energy
   :math:`\\tfrac12\\lambda^T W\\lambda`, :math:`W = C^T K^{-1} C` (C picks the wheels' normal loads, K their
   stiffnesses) over :math:`\\lambda + Nz`, with the wheels it leaves unloaded held at zero (:math:`C_U\\lambda =
   0`), and the minimum-norm choice along what stays open (:math:`P_o`: the orthogonal projector onto
   :math:`\\mathrm{null}(A^T)\\cap\\mathrm{null}(C)`; without a split, W = 0 and :math:`P_o = NN^T`: the
   minimum-norm multipliers). Differentiating (C and K constant, u any solution: the result does not depend on
   which),

   .. math:: H\\,d(\\lambda, u, \\mu) = \\big(-dP_o\\,\\lambda - dA\\,u,\\; de - dG\\,\\lambda,\\; 0\\big),\\qquad
             dP_o = -Z^+dZ\\,P_o - (Z^+dZ\\,P_o)^T,\\; Z = [A^T; C]

   (the derivative of a projector onto a null space of constant dimension). :math:`\\partial_q e` is Pinocchio's
   ``computeRNEADerivatives`` less the motors' :math:`\\partial_q(B\\tau)`
   (:func:`robotdyn.reduction.dynamics_derivatives.motor_rows`), :math:`\\partial_a e = M`, and
   :math:`\\partial_q(A^T\\lambda)` takes every column of :math:`\\partial A/\\partial q` from the constraint rows'
   derivatives (:mod:`robotdyn.constraints.row_derivatives`, one frame pass per velocity), as
   :mod:`robotdyn.contact.sliding_derivatives` does; a slipping wheel's :math:`\\partial_q(J_t^T c)` and its law's
   :math:`c'(s)` (:func:`robotdyn.contact.sliding_derivatives.law_jacobian`) likewise.

2. **Along the motion**: :math:`v = S(q)\\nu` and :math:`a = S\\dot\\nu + w` with :math:`\\dot\\nu(q, \\nu,
   \\tau)` the forward dynamics, chained through :meth:`robotdyn.robot.Robot.dynamics_derivatives` and the
   derivative pieces of the projection (:func:`robotdyn.reduction.dynamics_derivatives.pieces`:
   :math:`\\partial v/\\partial q`, :math:`\\partial a/\\partial q` at fixed :math:`\\dot\\nu`,
   :math:`\\partial w/\\partial\\nu`). A planar-root robot's loads come from its floating twin
   (:func:`robotdyn.contact.contact_forces.floating_twin`), as in the forces themselves: layer 1 runs on the twin
   at the lifted state and the chain maps its coordinates back.

Where it holds. The forces are smooth, and these are their derivatives, wherever the structure of the solution
is fixed: the rank of the rows, the number of open directions, and the rigid limit's **active set** (the wheels
it leaves unloaded because they would pull). Where a wheel's load reaches zero (it unloads) or an unloaded one's
multiplier does (it reloads), the forces are continuous but have a kink: the derivatives given are those of the
current active set's branch (one-sided there), and :attr:`ContactForceDerivatives.unloaded` names the set. The
required mu :math:`\\mu_i = \\|F_{t,i}\\|/F_{n,i}` is differentiable where :math:`F_{n,i} > 0` and
:math:`F_{t,i} \\ne 0`; elsewhere its derivative is reported as zero and the wheel is listed in
:attr:`ContactForceDerivatives.not_smooth` (a frictionless support wheel's mu is identically zero: exact).
Joint springs and dampers (:mod:`robotdyn.reduction.joint_springs`) enter e as :math:`-Q(q, v)` and its
derivatives as :math:`-\\partial Q/\\partial q`, :math:`-\\partial Q/\\partial v` (diagonal: the stiffnesses and
dampings); robots with compliant wheels are refused in one line.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..constraints.constraint import KinematicState
from ..constraints.rolling_contact import RollingWheel
from ..constraints.row_derivatives import FramePass, velocity_dq, wheel_velocity_dq
from ..errors import InputError, NonFiniteError
from ..reduction.actuation import input_matrix
from ..reduction.dynamics_derivatives import motor_rows, pieces
from ..reduction.joint_springs import spring_terms
from . import rigid_limit
from .compliant_contact import compliant_wheels
from .compliance import wheel_stiffness
from .contact_forces import DETERMINED_TOL, constraint_forces, floating_twin
from .sliding import sliding_now, tangential
from .sliding_derivatives import TANGENT, law_jacobian

CONSISTENT = 1e-7
"""Relative gap above which the differentiated multipliers are not those of the reported forces (refused)."""

TWIN_NOTE = "normal loads from the out-of-plane equilibrium"
"""How :func:`~robotdyn.contact.contact_forces.constraint_forces` notes that a planar model's loads come from its
floating twin (the derivatives then follow the same path)."""


@dataclass
class ContactForceDerivatives:
    """The wheel contact forces, the required mu and their derivatives at one state (q, nu, tau) (SI units).

    Wheels are in the order of ``wheels`` (the robot's wheel constraints, as in
    :attr:`~robotdyn.contact.contact_forces.ConstraintForces.wheels`); force components along (t1 longitudinal,
    t2 lateral, n normal) of each wheel's contact frame, the force of the ground on the wheel [N].

    Attributes:
        wheels: Wheel names (W,).
        force: (W, 3) contact forces [N].
        dforce_dq: (W, 3, n) :math:`\\partial F/\\partial q` in natural coordinates [N/m or N/rad] (valid along the
            holonomic manifold's tangent directions: see ``dforce_dq_manifold``).
        dforce_dnu: (W, 3, k) :math:`\\partial F/\\partial\\nu` [N per m/s or per rad/s].
        dforce_dtau: (W, 3, n_motors) :math:`\\partial F/\\partial\\tau` [N per N m or per N].
        required_mu: (W,) :math:`\\|(F_{t1}, F_{t2})\\|/F_n` [-] (``inf`` where :math:`F_n \\le 0`).
        dmu_dq, dmu_dnu, dmu_dtau: (W, n), (W, k), (W, n_motors) its derivatives (zero for the wheels in
            ``not_smooth``).
        not_smooth: Wheels whose required mu has no derivative here (not pressed on the ground, or a zero
            tangential force that can change: a kink of the norm).
        known: (W, 3) components with a value (rigid-body dynamics, or the rigid limit of compliance); the others
            are the minimum-norm choice, flagged as open (their derivatives are those of that choice).
        unloaded: Wheels the rigid limit holds at zero load (its active set; see the module).
        labels: Constraint rows (of the model that produced the forces: a planar robot's floating twin).
        lam: (m,) their multipliers [N, N m].
        dlam_dq, dlam_dnu, dlam_dtau: (m, n), (m, k), (m, n_motors) their derivatives.
        positions: Indices into q of independent position coordinates (p,), as
            :attr:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives.positions`.
        tangent: (n, p) :math:`\\partial q/\\partial q_P` along the holonomic manifold.
        coordinates, velocities, motors: Names of q, nu and tau.
        source: ``model`` or ``floating twin`` (where the planar model's loads come from).
        numerical: The pieces computed by finite differences (empty: everything analytic), as
            :attr:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives.numerical`, with a friction law
            without an analytic derivative (:func:`robotdyn.contact.sliding_derivatives.law_jacobian`).
        dynamics: The :class:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives` at the state (the
            accelerations and their derivatives, computed on the way).
    """

    wheels: list[str]
    force: np.ndarray
    dforce_dq: np.ndarray
    dforce_dnu: np.ndarray
    dforce_dtau: np.ndarray
    required_mu: np.ndarray
    dmu_dq: np.ndarray
    dmu_dnu: np.ndarray
    dmu_dtau: np.ndarray
    not_smooth: list[str]
    known: np.ndarray
    unloaded: list[str]
    labels: list[str]
    lam: np.ndarray
    dlam_dq: np.ndarray
    dlam_dnu: np.ndarray
    dlam_dtau: np.ndarray
    positions: np.ndarray
    tangent: np.ndarray
    coordinates: list[str] = field(default_factory=list)
    velocities: list[str] = field(default_factory=list)
    motors: list[str] = field(default_factory=list)
    source: str = "model"
    numerical: tuple[str, ...] = ()
    dynamics: object = field(default=None, repr=False)

    @property
    def dforce_dq_manifold(self) -> np.ndarray:
        """(W, 3, p) :math:`\\partial F/\\partial q_P` in the independent position coordinates ``positions``."""
        return self.dforce_dq @ self.tangent

    @property
    def dmu_dq_manifold(self) -> np.ndarray:
        """(W, p) the required mu's derivative in the independent position coordinates ``positions``."""
        return self.dmu_dq @ self.tangent

    @property
    def position_names(self) -> list[str]:
        """Names of the independent position coordinates."""
        return [self.coordinates[i] for i in self.positions]

    def wheel(self, name: str) -> int:
        """Index of the wheel called ``name`` in ``wheels``.

        Args:
            name: The wheel's name.

        Returns:
            Its index (into the first axis of ``force``, ``required_mu`` and their derivatives).
        """
        if name not in self.wheels:
            raise InputError(f"unknown wheel {name!r}; expected one of {', '.join(self.wheels)}")
        return self.wheels.index(name)

    def __repr__(self) -> str:
        mu = ", ".join(f"{w}={m:.4g}" for w, m in zip(self.wheels, self.required_mu))
        extra = (f", not smooth: {self.not_smooth}" if self.not_smooth else "") + \
            (f", unloaded: {self.unloaded}" if self.unloaded else "")
        return (f"ContactForceDerivatives({len(self.wheels)} wheels, q: {len(self.coordinates)} "
                f"(manifold {len(self.positions)}), nu: {len(self.velocities)}, tau: {len(self.motors)}; "
                f"required mu {mu}; source {self.source}{extra})")


@dataclass
class _Layer:
    """Layer 1 at (q, v, a, tau): the multipliers and their partial derivatives (m x n, m x n, m x n, m x n_motors),
    and per wheel its rows, directions and friction (``fr``: force and its partials, or None)."""

    labels: list
    lam: np.ndarray
    dq: np.ndarray
    dv: np.ndarray
    da: np.ndarray
    dtau: np.ndarray
    wheels: list
    residual: float
    numerical: set


def _projector_derivative(Zp: np.ndarray, dZ: np.ndarray, Po: np.ndarray) -> np.ndarray:
    """:math:`dP_o = -Z^+dZ\\,P_o - (Z^+dZ\\,P_o)^T` for one direction (m x m)."""
    X = Zp @ dZ @ Po
    return -X - X.T


def layer(robot, q: np.ndarray, v: np.ndarray, a: np.ndarray, tau: np.ndarray, stiffness_robot=None,
          unloaded: tuple = (), split: bool = True) -> _Layer:
    """The multipliers :math:`\\lambda(q, v, a, \\tau)` and their partial derivatives (layer 1 of the module).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` whose rows carry the forces (a planar robot's floating twin).
        q: Natural coordinates (n,) [m, rad].
        v: Full velocities (n,) [m/s, rad/s], consistent with the constraints.
        a: Full accelerations (n,) [m/s^2, rad/s^2], consistent with the motion (the forward dynamics').
        tau: Motor torques (n_motors,) [N m or N].
        stiffness_robot: The robot whose wheels' normal stiffnesses split open loads (default: ``robot``).
        unloaded: Names of the wheels the rigid limit holds at zero load.
        split: Whether open loads are split by the rigid limit (False: minimum-norm).

    Returns:
        The :class:`_Layer`.
    """
    model = robot.model
    n = model.nv
    kin0 = KinematicState(model, model.createData(), q, np.zeros(n))
    kin = KinematicState(model, model.createData(), q, v)
    rows = robot.constraint_rows(kin)
    A = rows.A
    m = A.shape[0]
    labels = list(rows.labels)
    index = {lab: i for i, lab in enumerate(labels)}
    B = input_matrix(robot.motors, kin)
    tree = model.createData()
    dR_q, dR_v, M = (x.copy() for x in pin.computeRNEADerivatives(model, tree, q, v, a))
    M = np.triu(M) + np.triu(M, 1).T
    e = pin.rnea(model, model.createData(), q, v, a) - B @ tau
    Q, dQ_dq, dQ_dv = spring_terms(getattr(robot, "springs", ()), q, v)  # joint springs and dampers (zeros: none)
    e -= Q
    dR_q -= dQ_dq
    dR_v -= dQ_dv
    units = [FramePass(kin0, col) for col in np.eye(n)]
    T = np.stack([velocity_dq(robot.constraints, fp) for fp in units], axis=1) if m else np.zeros((0, n, n))
    de_q = dR_q - motor_rows(robot, kin0, units, tau)
    # wheels: rows, directions; slipping ones: their friction
    wheels = []
    sliding = {id(c) for c in sliding_now(robot)}
    G = A.T.copy()
    numerical: set[str] = set()
    for c in robot.constraints:
        if not isinstance(c, RollingWheel):
            continue
        idx = np.array([index[lab] for lab in c._labels()], int)
        entry = {"name": c.name, "rows": idx, "D": np.asarray(c._directions, float), "fr": None}
        if id(c) in sliding:
            Jt, s = tangential(c, kin)
            coef = c.friction_coefficient(s)
            Cs = law_jacobian(c, s, numerical)
            Tt = np.stack([wheel_velocity_dq(c, fp, TANGENT) for fp in units], axis=1)  # (2, n, n)
            nrow = index[f"{c.name}.normal"]
            G[:, nrow] -= Jt.T @ coef
            # d(Jt^T c)/dq at fixed v and d/dv: the friction's generalised-force direction
            ds_q = np.einsum("j,rjp->rp", v, Tt)
            dJc_q = np.einsum("r,rjp->jp", coef, Tt) + Jt.T @ Cs @ ds_q
            dJc_v = Jt.T @ Cs @ Jt
            entry["fr"] = dict(nrow=nrow, coef=coef, Cs=Cs, Jt=Jt, ds_q=ds_q, dJc_q=dJc_q, dJc_v=dJc_v)
        wheels.append(entry)
    # the structure: null space of A^T, open directions, the split's W and C_U
    if m:
        _, s_, Vt = np.linalg.svd(A.T, full_matrices=True)
        tol = s_.max(initial=0.0) * max(A.shape) * np.finfo(float).eps
        rank = int(np.sum(s_ > tol))
    else:
        rank, Vt = 0, np.zeros((0, 0))
    N = Vt[rank:].T if m else np.zeros((0, 0))
    d = m - rank
    C = rigid_limit.normal_map([w["rows"] for w in wheels], [w["D"] for w in wheels], m)
    W = np.zeros((m, m))
    CU = np.zeros((0, m))
    opened = N
    if d and wheels and split:
        normal_open = [np.linalg.norm(w["D"].T[2] @ N[w["rows"]]) > DETERMINED_TOL for w in wheels]
        scale = max(np.abs(A).max(initial=0.0), 1.0)
        inert = bool(np.any(np.abs(A).max(axis=1, initial=0.0) <= 1e-12 * scale))
        if any(normal_open) and not inert:
            P = C @ N
            _, sp, Vpt = np.linalg.svd(P, full_matrices=True)
            p = int(np.sum(sp > rigid_limit.RANK_TOL))
            if p:
                opened = N @ Vpt[p:].T
                k = wheel_stiffness(stiffness_robot or robot, [w["name"] for w in wheels])
                kinv = float(np.mean(k)) / k  # only the ratios matter
                W = C.T @ (kinv[:, None] * C)
                names = [w["name"] for w in wheels]
                CU = C[[names.index(u) for u in unloaded]] if unloaded else np.zeros((0, m))
    Po = opened @ opened.T
    u_n = CU.shape[0]
    Z = np.vstack([A.T, C]) if W.any() else A.T
    # Z^+ on the rank that leaves exactly the open directions
    zr = m - opened.shape[1]
    if m:
        Uz, sz, Vzt = np.linalg.svd(Z, full_matrices=False)
        Zp = (Vzt[:zr].T / sz[:zr]) @ Uz[:, :zr].T
    else:
        Zp = np.zeros((0, Z.shape[0]))
    H = np.block([[W + Po, A, CU.T], [G, np.zeros((n, n)), np.zeros((n, u_n))],
                  [CU, np.zeros((u_n, n)), np.zeros((u_n, u_n))]])
    Uh, sh, Vht = np.linalg.svd(H)
    hr = m + rank + u_n  # u is determined up to null(A)
    Hp = (Vht[:hr].T / sh[:hr]) @ Uh[:, :hr].T
    rhs = np.concatenate([np.zeros(m), e, np.zeros(u_n)])
    X = Hp @ rhs
    lam, u = X[:m], X[m:m + n]
    residual = float(np.linalg.norm(H @ X - rhs) / max(np.linalg.norm(e), 1.0))

    def solve(r1, r2):  # dlambda for right-hand sides (m, c) and (n, c)
        r = np.vstack([r1, r2, np.zeros((u_n, r1.shape[1]))])
        return (Hp @ r)[:m]

    # q: -dPo lam - dA u ; de - dG lam
    r1 = np.zeros((m, n))
    r2 = de_q.copy()
    for p in range(n):
        dA = T[:, :, p]
        dZ = np.vstack([dA.T, np.zeros((Z.shape[0] - n, m))])
        r1[:, p] = -_projector_derivative(Zp, dZ, Po) @ lam - dA @ u
    if m:
        r2 -= np.einsum("i,ijp->jp", lam, T)
    r2v = dR_v.copy()
    for w in wheels:
        f = w["fr"]
        if f is not None:  # G's column of the wheel's normal row: -Jt^T c (depends on q and v)
            r2 += lam[f["nrow"]] * f["dJc_q"]
            r2v += lam[f["nrow"]] * f["dJc_v"]
    dq, dv = solve(r1, r2), solve(np.zeros((m, n)), r2v)
    da = solve(np.zeros((m, n)), M)
    dtau = solve(np.zeros((m, B.shape[1])), -B)
    return _Layer(labels, lam, dq, dv, da, dtau, wheels, residual, numerical)


def _wheel_forces(lay: _Layer, Vq: np.ndarray, S: np.ndarray, Dq: np.ndarray, Dnu: np.ndarray, Dtau: np.ndarray
                 ) -> tuple[list, list, list, list]:
    """Per wheel: its force (3,) and total derivatives (3 x n, 3 x k, 3 x n_motors) from the multipliers' total
    derivatives ``Dq``, ``Dnu``, ``Dtau``; a slipping wheel's friction :math:`-\\lambda_n c(s)`, :math:`s = J_t(q)
    S(q)\\nu`, by the chain rule (``Vq`` = :math:`\\partial v/\\partial q`)."""
    F, FQ, FV, FT = [], [], [], []
    for w in lay.wheels:
        idx, D = w["rows"], w["D"]
        f = D.T @ lay.lam[idx]
        fq, fv, ft = D.T @ Dq[idx], D.T @ Dnu[idx], D.T @ Dtau[idx]
        fr = w["fr"]
        if fr is not None:
            ln, coef, CJ = lay.lam[fr["nrow"]], fr["coef"], fr["Cs"] @ fr["Jt"]
            f[:2] += -ln * coef
            fq[:2] += -np.outer(coef, Dq[fr["nrow"]]) - ln * (fr["Cs"] @ fr["ds_q"] + CJ @ Vq)
            fv[:2] += -np.outer(coef, Dnu[fr["nrow"]]) - ln * CJ @ S
            ft[:2] += -np.outer(coef, Dtau[fr["nrow"]])
        F.append(f)
        FQ.append(fq)
        FV.append(fv)
        FT.append(ft)
    return F, FQ, FV, FT


def checked(robot, q, nu, tau) -> tuple:
    """The state's arrays checked for :func:`contact_force_derivatives` (and its compiled twin), with its one-line
    refusal of compliant wheels.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad].
        nu: Independent velocities (k,) [m/s, rad/s].
        tau: Motor torques/forces (n_motors,) [N m or N].

    Returns:
        ``(q, nu, tau)`` as float arrays.

    Raises:
        InputError: Wrong sizes; compliant wheels.
    """
    q, nu, tau = robot.check_q(q), robot.check_nu(nu), robot.check_tau(tau)
    if compliant_wheels(robot):
        raise InputError(f"contact force derivatives: robot {robot.spec.name!r} has compliant wheels, whose forces "
                         "have no derivatives here; expected rigid and slipping wheels, loop closures and joint "
                         "couplings")
    return q, nu, tau


def structure(robot, q, nu, tau) -> tuple:
    """The reported forces at the state and the structure the derivatives follow: ``(forces, unloaded, twin)``,
    the :class:`~robotdyn.contact.contact_forces.ConstraintForces`, the names of the wheels the rigid limit holds
    unloaded (its active set; none where no split avoids pulling) and whether the loads come from the floating
    twin.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], checked.
        nu: Independent velocities (k,) [m/s, rad/s], checked.
        tau: Motor torques/forces (n_motors,) [N m or N], checked.

    Returns:
        ``(forces, unloaded (tuple of names), twin (bool))``.
    """
    forces = constraint_forces(robot, q, nu, tau=tau)
    infeasible = any(note.startswith("no split of the loads pulls") for note in forces.notes)
    unloaded = () if infeasible else tuple(forces.unloaded)
    twin = any(note.startswith(TWIN_NOTE) for note in forces.notes)
    return forces, unloaded, twin


def contact_force_derivatives(robot, q, nu, tau) -> ContactForceDerivatives:
    """The wheel contact forces and required mu at (q, nu) under motor torques tau, with their derivatives.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` (rolling, omni and support wheels, smoothly slipping wheels, loop
            closures, joint couplings, operational-space velocities, joint springs and dampers; no compliant
            wheels).
        q: Natural coordinates (n,) [m, rad] in the order of ``robot.coordinates``, on the holonomic manifold
            for ``dforce_dq_manifold`` to be the derivative along it.
        nu: Independent velocities (k,) [m/s, rad/s] in the order of ``robot.velocity_names``.
        tau: Motor torques/forces (n_motors,) [N m or N] in the order of ``robot.motors``.

    Returns:
        A :class:`ContactForceDerivatives`.

    Raises:
        InputError: Wrong sizes; compliant wheels; a constraint without derivatives (see
            :meth:`robotdyn.robot.Robot.dynamics_derivatives`).
        NonFiniteError: A non-finite result.
    """
    q, nu, tau = checked(robot, q, nu, tau)
    forces, unloaded, twin = structure(robot, q, nu, tau)
    pc = pieces(robot, q, nu)  # shared with the dynamics derivatives (Robot.dynamics_derivatives' choice)
    if sliding_now(robot):
        from .sliding_derivatives import sliding_derivatives

        D = sliding_derivatives(robot, q, nu, tau, pc)
    else:
        from ..reduction.dynamics_derivatives import dynamics_derivatives

        D = dynamics_derivatives(robot, q, nu, tau, pc)
    S, v = pc.S, pc.v
    a = S @ D.nudot + pc.w
    a_q = pc.Aq(D.nudot) + S @ D.dq  # total da/dq
    a_nu = pc.Wnu + S @ D.dnu
    a_tau = S @ D.dtau
    if twin:
        target, index = floating_twin(robot)
        nt = target.nq

        def lift(x):
            out = np.zeros(nt)
            out[index] = x
            return out

        lay = layer(target, lift(q), lift(v), lift(a), tau, robot, unloaded)
    else:
        lay = layer(robot, q, v, a, tau, robot, unloaded)
    return along_motion(robot, q, nu, tau, forces, unloaded, twin, lay, D, pc.Vq, S, a_q, a_nu, a_tau)


def along_motion(robot, q, nu, tau, forces, unloaded: tuple, twin: bool, lay: _Layer, D, Vq: np.ndarray,
                 S: np.ndarray, a_q: np.ndarray, a_nu: np.ndarray, a_tau: np.ndarray) -> ContactForceDerivatives:
    """Layer 2 of the module: the multipliers' partial derivatives ``lay`` chained along the motion, the wheel
    forces, the required mu and their derivatives (shared by the Python path and its compiled twin,
    :mod:`robotdyn.fast.compiled_force_derivatives`).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], checked.
        nu: Independent velocities (k,) [m/s, rad/s], checked.
        tau: Motor torques/forces (n_motors,) [N m or N], checked.
        forces: The reported forces (:func:`structure`).
        unloaded: Names of the wheels the rigid limit holds unloaded.
        twin: Whether ``lay`` is the floating twin's (its coordinates are mapped back).
        lay: Layer 1 at (q, v, a, tau) (:func:`layer` or the compiled twin's).
        D: The :class:`~robotdyn.reduction.dynamics_derivatives.DynamicsDerivatives` at the state.
        Vq: (n, n) :math:`\\partial v/\\partial q`, v = S(q) nu.
        S: (n, k) the projection.
        a_q, a_nu, a_tau: (n, n), (n, k), (n, n_motors) total derivatives of the accelerations a.

    Returns:
        A :class:`ContactForceDerivatives`.

    Raises:
        InputError: The multipliers differentiated are not those of the reported forces.
        NonFiniteError: A non-finite result.
    """
    if twin:
        _, index = floating_twin(robot)
        Lq, Lv, La = lay.dq[:, index], lay.dv[:, index], lay.da[:, index]
    else:
        Lq, Lv, La = lay.dq, lay.dv, lay.da
    dlam_dq = Lq + Lv @ Vq + La @ a_q
    dlam_dnu = Lv @ S + La @ a_nu
    dlam_dtau = lay.dtau + La @ a_tau
    F, FQ, FV, FT = _wheel_forces(lay, Vq, S, dlam_dq, dlam_dnu, dlam_dtau)
    # one story: the multipliers differentiated are those of the forces reported (else a structure not mirrored)
    reported = np.array([w.force for w in forces.wheels]).reshape(-1, 3)
    scale = max(1.0, float(np.abs(reported).max(initial=0.0)))
    gap = float(np.abs(np.array(F).reshape(-1, 3) - reported).max(initial=0.0)) if len(F) == len(reported) else np.inf
    if gap > CONSISTENT * scale or lay.residual > CONSISTENT:
        raise InputError(f"contact force derivatives: the forces at this state come from a structure not "
                         f"differentiated here (gap {gap:.3g} N to the reported ones); expected rigid or "
                         "smoothly slipping wheels, loads from rigid-body dynamics or the rigid limit of compliance")
    names = [w["name"] for w in lay.wheels]
    W = len(names)
    n, k, nm = len(q), len(nu), len(tau)
    force = np.array(F).reshape(W, 3)
    dF_q = np.array(FQ).reshape(W, 3, n)
    dF_nu = np.array(FV).reshape(W, 3, -1)
    dF_tau = np.array(FT).reshape(W, 3, nm)
    mu = np.full(W, np.inf)
    dmu = [np.zeros((W, n)), np.zeros((W, k)), np.zeros((W, nm))]
    rough = []
    for i in range(W):
        ft, fn = force[i, :2], force[i, 2]
        t = float(np.hypot(*ft))
        if names[i] in unloaded:  # held at zero load by the rigid limit: not pressed on the ground
            fn = 0.0
        if fn > 0:
            mu[i] = t / fn
        derivs = (dF_q[i], dF_nu[i], dF_tau[i])
        if fn > 0 and t > 0:
            for j, dd in enumerate(derivs):
                dmu[j][i] = (ft @ dd[:2]) / (t * fn) - t * dd[2] / fn ** 2
        elif fn > 0 and all(np.abs(dd[:2]).max(initial=0.0) == 0.0 for dd in derivs):
            pass  # a frictionless wheel: mu stays zero
        else:
            rough.append(names[i])
    known = np.array([w.known for w in forces.wheels]).reshape(W, 3) if forces.wheels else np.zeros((0, 3), bool)
    out = ContactForceDerivatives(names, force, dF_q, dF_nu, dF_tau, mu, *dmu, rough, known, list(unloaded),
                                  lay.labels, lay.lam, dlam_dq, dlam_dnu, dlam_dtau, D.positions, D.tangent,
                                  list(robot.coordinates), list(robot.velocity_names),
                                  [mo.name for mo in robot.motors], "floating twin" if twin else "model",
                                  tuple(sorted(set(D.numerical) | lay.numerical)), D)
    for name in ("force", "dforce_dq", "dforce_dnu", "dforce_dtau", "dmu_dq", "dmu_dnu", "dmu_dtau", "dlam_dq",
                 "dlam_dnu", "dlam_dtau"):
        if not np.all(np.isfinite(getattr(out, name))):
            raise NonFiniteError(f"contact force derivatives: {name} is not finite at this state")
    return out


__all__ = ["ContactForceDerivatives", "along_motion", "checked", "contact_force_derivatives", "layer", "structure"]

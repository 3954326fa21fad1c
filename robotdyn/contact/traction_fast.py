"""The wheel loads of many states at once: the fast pass of :func:`robotdyn.contact.traction.traction`.

:func:`robotdyn.contact.contact_forces.constraint_forces` answers one state with a full
:class:`~robotdyn.contact.contact_forces.ConstraintForces` (labels, null space, reasons, one object per wheel; for a
planar root the same again on its floating twin): about a millisecond of Python per state. Along a trajectory
:func:`wheel_loads` computes the same numbers with the same formulas, block by block (:data:`BLOCK` samples):

1. the reduced model of every sample in one compiled call (:meth:`robotdyn.fast.compiled.CompiledModel.
   evaluate_many`), the forward dynamics :math:`\\dot\\nu = M_r^{-1}(B_r\\tau - h)` by stacked Cholesky solves
   (:func:`robotdyn.reduction.reduced_dynamics.solve_mass`'s), :math:`v = S\\nu`, :math:`a = S\\dot\\nu + w`;
2. per sample one compiled call (:meth:`~robotdyn.fast.compiled.CompiledModel.forces_at`: :math:`\\lambda` on the
   projection's rows, :math:`e`, the rows A), and for a planar root whose normal loads the planar model leaves
   undetermined a second one on its floating twin (:func:`robotdyn.contact.contact_forces.floating_twin`), kept
   where the twin's residual is at most :data:`~robotdyn.contact.contact_forces.TWIN_RESIDUAL`, as the reference;
3. stacked SVDs of :math:`A^T` for the minimum-norm :math:`\\lambda` and the null space
   (:func:`robotdyn.contact.contact_forces._from_basic`'s formulas, grouped by rank), and from them each wheel's
   force along (t1, t2, n) of its contact frame [N] and whether each component is determined;
4. the smallest friction coefficient over the undetermined splits (``minimum_mu``) only where the trajectory
   reports it (every sample has a wheel whose load is not all determined, and every normal load is determined):
   exactly, vectorised, where the tangential forces vary along one direction of undetermined combinations
   (:func:`_cone_minimum_1d`), else by the reference's solver per sample
   (:func:`robotdyn.contact.contact_forces.cone_minimum`).

Where it cannot serve the whole robot (no compiled model, slipping wheels whose friction forces only the Python
path computes, a planar root whose twin is not compiled) :func:`wheel_loads` returns ``None``; a sample it cannot
serve (a compiled fallback, a reduced mass matrix that is not positive definite, non-finite or out-of-range numbers)
is computed by :func:`~robotdyn.contact.contact_forces.constraint_forces` itself, which also raises the reference's
errors there. Nothing per sample is kept but the loads: memory grows with 8 numbers per wheel and sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..constraints.rolling_contact import RollingWheel
from ..fast.compiled import Fallback
from ..fast.dispatch import compiled_model
from ..inputs import MAX_FORCE, MAX_POSITION, MAX_VELOCITY
from ..reduction.joint_springs import spring_forces
from .contact_forces import DETERMINED_TOL, TWIN_RESIDUAL, cone_minimum, constraint_forces, floating_twin
from .sliding import sliding_now
from .compliance import wheel_stiffness
from .rigid_limit import normal_map, split_many

BLOCK = 512
"""Samples evaluated together: bounds the working set of the stacked rows and SVDs (~2 MB on Quasimoro; larger
blocks are no faster)."""

DIRECTION_TOL = 1e-12
"""Singular value (relative to 1, the null space being orthonormal) below which a direction of the undetermined
combinations is taken to move no wheel's tangential force (:func:`_cone_minimum`)."""


@dataclass
class WheelLoads:
    """The ground's force on each wheel at every sample of a trajectory (contact frames: t1 longitudinal, t2
    lateral, n normal, as :class:`~robotdyn.contact.contact_forces.WheelForce`).

    Attributes:
        names: The wheels' names (W), in the robot's constraint order.
        normal: (N, W) normal loads :math:`f_n` [N] (positive: pressed on the ground).
        tangential: (N, W) friction force magnitudes :math:`\\|(f_{t1}, f_{t2})\\|` [N] (the minimum-norm choice
            where not determined).
        normal_determined: (N, W) whether the normal load has a value: rigid-body dynamics determine it, or the
            rigid limit of the wheels' normal compliance does (:mod:`robotdyn.contact.rigid_limit`).
        load_determined: (N, W) whether all three components have one.
        compliance: (N, W) whether the normal load is the rigid limit of compliance (rigid-body dynamics leave it
            open).
        minimum_mu: (N,) the smallest friction coefficient over the undetermined splits
            (:meth:`~robotdyn.contact.contact_forces.ConstraintForces.minimum_mu`), or ``None`` where the trajectory
            has none: some sample whose loads are all determined or some normal load that is not.
        fallback: How many samples were computed by the per-sample reference.
    """

    names: list[str]
    normal: np.ndarray
    tangential: np.ndarray
    normal_determined: np.ndarray
    load_determined: np.ndarray
    minimum_mu: np.ndarray | None = None
    fallback: int = 0
    compliance: np.ndarray | None = None


def sample_loads(forces) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """One sample's ``(names, normal [N], tangential [N], known (W, 3))`` from a
    :class:`~robotdyn.contact.contact_forces.ConstraintForces` (the reference's values, as
    :attr:`~robotdyn.contact.contact_forces.WheelForce.normal` and ``.tangential``).

    Args:
        forces: One sample's :class:`~robotdyn.contact.contact_forces.ConstraintForces`.

    Returns:
        ``(names, normal, tangential, known)``: wheel names (W,), normal loads (W,) [N], tangential load magnitudes
        (W,) [N] and the boolean mask (W, 3) of the determined components.
    """
    wheels = forces.wheels
    return ([w.name for w in wheels], np.array([w.normal for w in wheels], float),
            np.array([w.tangential for w in wheels], float),
            np.array([w.known for w in wheels], bool).reshape(len(wheels), 3))


def torques(torque, t: np.ndarray, Q: np.ndarray, NU: np.ndarray, motors: int) -> list | np.ndarray:
    """The motor torques of every sample [N m or N]: zeros without ``torque``, a torque profile's vectorised
    ``at(times)`` (:class:`robotdyn.simulation.torque_profile.TorqueProfile`: the same formulas, q and nu
    ignored), else ``torque(t, q, nu)`` sample by sample (a list of what it returned: checked by
    :func:`_checked_torques`).

    Args:
        torque: ``None``, a torque profile, or a callable ``tau(t, q, nu)``.
        t: Sample times (N,) [s].
        Q: Coordinates (N, n) [m, rad].
        NU: Independent velocities (N, k).
        motors: The robot's number of motors.

    Returns:
        The torques (N, motors) as an array, or a list of N per-sample torque vectors for a torque function.
    """
    if torque is None:
        return np.zeros((len(t), motors))
    kind = type(torque)
    if all(callable(getattr(kind, m, None)) for m in ("at", "encode", "breakpoints")):  # a TorqueProfile (duck typed:
        return np.asarray(torque.at(t), float)  # robotdyn.simulation is a later stage than contact)
    return [torque(ti, Q[i], NU[i]) for i, ti in enumerate(t)]


def _checked_torques(tau, n: int, motors: int) -> tuple[np.ndarray, np.ndarray]:
    """``(TAU (n, motors), ok (n,))``: the torques as one array and where they pass ``Robot.check_tau`` (length,
    finite, at most MAX_FORCE); the others are left to the reference, which raises its error there."""
    if isinstance(tau, np.ndarray) and tau.shape == (n, motors):
        TAU = tau
    else:
        TAU = np.full((n, motors), np.nan)
        for i, x in enumerate(tau):
            try:
                x = np.asarray(x, float)
            except (TypeError, ValueError):  # (the reference's one-line error)
                continue
            if x.shape == (motors,) or (x.shape == () and motors == 1):  # (as_vector takes a number for one)
                TAU[i] = x
    with np.errstate(invalid="ignore"):
        ok = np.all(np.isfinite(TAU) & (np.abs(TAU) <= MAX_FORCE), axis=1)
    return TAU, ok


def wheel_loads(robot, t, Q, NU, torque=None) -> WheelLoads | None:
    """The wheel loads at every sample of a trajectory, as
    :func:`~robotdyn.contact.contact_forces.constraint_forces` (forward dynamics from the motor torques, a planar
    root's loads from its floating twin) gives them sample by sample.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` the trajectory was simulated with.
        t: (N,) sample times [s].
        Q: (N, n) coordinates [m, rad].
        NU: (N, k) independent velocities.
        torque: The motor torques ``tau(t, q, nu)`` [N m or N] (``None``: zero).

    Returns:
        The :class:`WheelLoads`, or ``None`` where this pass does not serve the robot (use the per-sample
        reference): no compiled model, slipping wheels, a planar root whose floating twin is not compiled, no
        sample.

    Raises:
        RobotDynError: As the reference, at a sample where it raises (bad numbers, a singular configuration).
    """
    t = np.asarray(t, float)
    Q, NU = np.asarray(Q, float), np.asarray(NU, float)
    N = len(t)
    fast = None if N == 0 or sliding_now(robot) else compiled_model(robot)
    if fast is None or Q.shape != (N, robot.nq) or NU.shape != (N, robot.mobility):
        return None
    models = [_Model(robot, fast), None]  # (the floating twin: built where a sample needs it, as the reference)
    motors = len(robot.motors)
    TAU, tau_ok = _checked_torques(torques(torque, t, Q, NU, motors), N, motors)
    ok = tau_ok.copy()
    lo, hi = robot.description.lower, robot.description.upper
    with np.errstate(invalid="ignore"):
        ok &= np.all(np.isfinite(Q) & (np.abs(Q) <= MAX_POSITION) & (Q >= lo - 1e-12) & (Q <= hi + 1e-12), axis=1)
        ok &= np.all(np.isfinite(NU) & (np.abs(NU) <= MAX_VELOCITY), axis=1)
    W = len(models[0].wheels)
    out = WheelLoads([w.name for w in models[0].wheels], np.zeros((N, W)), np.zeros((N, W)), np.zeros((N, W), bool),
                     np.zeros((N, W), bool), compliance=np.zeros((N, W), bool))
    if not ok[0]:  # the reference raises there, or the compiled model may have no projection chosen yet
        return None
    robot.reduced(Q[0], NU[0])  # the reference's first step (it chooses the rows the compiled model uses)
    minimum = _Minimum(N)
    for start in range(0, N, BLOCK):
        part = slice(start, min(start + BLOCK, N))
        block = _block(robot, models, Q[part], NU[part], TAU[part], ok[part])
        served = block["served"]
        out.normal[part] = block["force"][:, :, 2]
        out.tangential[part] = np.hypot(block["force"][:, :, 0], block["force"][:, :, 1])
        out.normal_determined[part] = block["known"][:, :, 2]
        out.load_determined[part] = block["known"].all(axis=2)
        out.compliance[part] = block["known"][:, :, 2] & ~block["determined"][:, :, 2]
        references = {}
        for j in np.flatnonzero(~served):  # the reference, sample by sample (it raises where it must)
            i = start + j
            tau = TAU[i] if tau_ok[i] else _torque_at(torque, t, Q, NU, i)  # (evaluated again: its error)
            forces = constraint_forces(robot, Q[i], NU[i], tau=tau)
            names, fn, ft, det = sample_loads(forces)
            if names != out.names:
                raise RuntimeError(f"wheels {names} at sample {i}, {out.names} at the others")  # (never: one robot)
            out.normal[i], out.tangential[i], out.normal_determined[i], out.load_determined[i] = (
                fn, ft, det[:, 2], det.all(axis=1))
            out.compliance[i] = [w.compliance[2] for w in forces.wheels]
            references[j] = forces
            out.fallback += 1
        minimum.add(part, block, references, out)
    out.minimum_mu = minimum.result()
    return out


def _torque_at(torque, t, Q, NU, i: int):
    """The torque of sample i as the reference evaluates it (``None``: zero)."""
    return None if torque is None else np.asarray(torque(t[i], Q[i], NU[i]), float)


class _Model:
    """A robot (or a planar robot's floating twin) as the fast pass evaluates it: its compiled model, its wheels'
    rows (indices in the compiled rows and the directions D, row i along D[i] of (t1, t2, n)) and, for a twin, where
    the planar coordinates go in its own (``index``)."""

    def __init__(self, robot, fast, index: list[int] | None = None) -> None:
        self.robot, self.fast, self.index = robot, fast, index
        self.wheels = [c for c in robot.constraints if isinstance(c, RollingWheel)]
        rows = {lab: i for i, lab in enumerate(fast.labels)}
        self.rows = [np.array([rows[lab] for lab in c._labels()], int) for c in self.wheels]
        self.directions = [np.asarray(c._directions, float) for c in self.wheels]
        self.m = len(fast.labels)
        self.C = normal_map(self.rows, self.directions, self.m)
        self.k = wheel_stiffness(robot, [c.name for c in self.wheels])
        # a planar root's own loads are never split (as constraint_forces: they come from its floating twin where
        # it holds the out-of-plane equilibrium, and stay undetermined where it does not)
        self.split = index is not None or robot.spec.root != "planar"

    def lift(self, X: np.ndarray) -> np.ndarray:
        """Planar coordinates (or velocities) (B, n) into the twin's (B, n_twin), zero elsewhere."""
        out = np.zeros((len(X), self.robot.nq))
        out[:, self.index] = X
        return out

    def forces(self, Q, V, A, TAU, todo: np.ndarray) -> dict:
        """The compiled :math:`\\lambda` (basic), e and A at the samples ``todo`` (indices), then the minimum-norm
        solution and each wheel's force (:meth:`_solve`); ``ok`` is False where the compiled call fell back."""
        B, n = len(Q), Q.shape[1]
        lam = np.zeros((B, self.m))
        e = np.zeros((B, n))
        rows = np.zeros((B, self.m, n))
        ok = np.zeros(B, bool)
        call = self.fast.forces_at
        for j in todo:
            try:
                lam[j], e[j], _, rows[j] = call(Q[j], V[j], A[j], TAU[j])
            except Fallback:  # the Python path decides this sample
                continue
            ok[j] = True
        return self._solve(rows, e, lam, ok)

    def _solve(self, rows: np.ndarray, e: np.ndarray, lam: np.ndarray, ok: np.ndarray) -> dict:
        """:func:`robotdyn.contact.contact_forces._from_basic` on a stack of samples (those with ``ok``): the SVD
        of :math:`A^T`, its rank (numpy's ``matrix_rank`` tolerance), the null space N, the minimum-norm
        :math:`\\lambda - NN^T\\lambda`, the relative residual, then per wheel :math:`D^T\\lambda` and whether each
        component is determined (:math:`\\|D^T N\\| \\le` DETERMINED_TOL), and the wheels' tangential maps for the
        minimum friction coefficient (:func:`_cone_minimum`). Samples whose numbers are not finite lose ``ok``."""
        B, W = len(rows), len(self.wheels)
        force = np.zeros((B, W, 3))
        determined = np.zeros((B, W, 3), bool)
        known = np.zeros((B, W, 3), bool)
        residual = np.full(B, np.inf)
        groups = []  # (sample indices, b (G, W, 2), T (G, W, 2, d)) per rank
        with np.errstate(all="ignore"):
            ok = ok & np.all(np.isfinite(rows), axis=(1, 2)) & np.all(np.isfinite(e), axis=1) & np.all(
                np.isfinite(lam), axis=1)
            idx = np.flatnonzero(ok)
            if idx.size and self.m:
                At = np.swapaxes(rows[idx], 1, 2)  # (G, n, m)
                # V of A^T = U S V^T is square (m, m) without full_matrices where n >= m (U is not used)
                _, s, Vt = np.linalg.svd(At, full_matrices=At.shape[1] < At.shape[2])
                tol = s.max(axis=1, initial=0.0) * max(At.shape[1:]) * np.finfo(float).eps
                rank = np.sum(s > tol[:, None], axis=1)
                for r in np.unique(rank):
                    sel = idx[rank == r]
                    g = rank == r
                    Ns = np.swapaxes(Vt[g, r:, :], 1, 2)  # (G, m, d)
                    lb = lam[sel]
                    lm = lb - np.einsum("gij,gj->gi", Ns, np.einsum("gji,gj->gi", Ns, lb))
                    lam[sel] = lm
                    res = np.einsum("gij,gi->gj", rows[sel], lm) - e[sel]
                    residual[sel] = np.linalg.norm(res, axis=1) / np.maximum(np.linalg.norm(e[sel], axis=1), 1.0)
                    for w, (ri, D) in enumerate(zip(self.rows, self.directions)):  # rigid-body dynamics' own
                        ND = np.einsum("rk,grd->gkd", D, Ns[:, ri, :])  # (G, 3, d): D^T N
                        determined[sel, w] = np.linalg.norm(ND, axis=2) <= DETERMINED_TOL
                    # the open loads by the rigid limit of compliance (as constraint_forces: not where some row acts
                    # on no coordinate, a planar root's normal rows, nor where every normal load is determined)
                    scale = np.maximum(np.max(np.abs(rows[sel]), axis=(1, 2)), 1.0)
                    inert = np.any(np.max(np.abs(rows[sel]), axis=2) <= 1e-12 * scale[:, None], axis=1)
                    split = (r < self.m) & ~inert & ~determined[sel, :, 2].all(axis=1) & self.split
                    Os, count = Ns, np.full(len(sel), Ns.shape[2])
                    if split.any():
                        lr, op, _, cnt = split_many(lm[split], Ns[split], self.C, self.k)
                        lm, Os, count = lm.copy(), Ns.copy(), count.copy()
                        lm[split], Os[split], count[split] = lr, op, cnt
                        lam[sel] = lm
                    for c in np.unique(count):
                        g = count == c
                        Og = Os[g][:, :, :c]
                        b = np.zeros((int(g.sum()), W, 2))
                        T = np.zeros((int(g.sum()), W, 2, c))
                        for w, (ri, D) in enumerate(zip(self.rows, self.directions)):
                            f = lm[g][:, ri] @ D  # (G, 3): D^T lambda
                            force[sel[g], w] = f
                            ND = np.einsum("rk,grd->gkd", D, Og[:, ri, :])  # (G, 3, c): D^T (open directions)
                            known[sel[g], w] = np.linalg.norm(ND, axis=2) <= DETERMINED_TOL
                            b[:, w], T[:, w] = f[:, :2], ND[:, :2, :]
                        groups.append((sel[g], b, T))
            elif idx.size:  # no rows: nothing to solve
                residual[idx] = np.linalg.norm(e[idx], axis=1) / np.maximum(np.linalg.norm(e[idx], axis=1), 1.0)
                determined[idx] = True
                known[idx] = True
            ok &= np.isfinite(residual) & np.all(np.isfinite(lam), axis=1)
        return {"ok": ok, "force": force, "determined": determined, "known": known, "residual": residual,
                "groups": groups}


def _block(robot, models: list, Q, NU, TAU, ok) -> dict:
    """One block of samples: forward dynamics, the robot's forces and, for a planar root, its twin's where the
    reference takes them (the planar normal loads undetermined, the twin's residual within TWIN_RESIDUAL).
    ``served`` says which samples it computed (the others: the reference)."""
    B = len(Q)
    fast = models[0].fast
    ok = ok.copy()
    V = np.zeros_like(Q)
    A = np.zeros_like(Q)
    with np.errstate(all="ignore"):
        M, h, _, S, w, Br, failed = fast.evaluate_many(Q, NU)
        ok[failed] = False
        ok &= np.all(np.isfinite(M), axis=(1, 2)) & np.all(np.isfinite(h), axis=1) & np.all(np.isfinite(w), axis=1)
        ok &= np.all(np.isfinite(S), axis=(1, 2))
        idx = np.flatnonzero(ok)
        L = np.zeros_like(M)
        try:  # solve_mass: M = L L^T, nudot = L^-T L^-1 (B tau - h)
            L[idx] = np.linalg.cholesky(M[idx])
        except np.linalg.LinAlgError:  # some not positive definite: those are the reference's (its error)
            for i in idx:
                try:
                    L[i] = np.linalg.cholesky(M[i])
                except np.linalg.LinAlgError:
                    ok[i] = False
            idx = np.flatnonzero(ok)
        if idx.size:
            rhs = np.einsum("gij,gj->gi", Br[idx], TAU[idx]) - h[idx]
            V[idx] = np.einsum("gij,gj->gi", S[idx], NU[idx])
            springs = getattr(robot, "springs", None)
            if springs:  # joint springs and dampers: + S^T Q (the compiled forces_at takes e - Q)
                rhs += np.einsum("gij,gi->gj", S[idx], spring_forces(springs, Q[idx], V[idx]))
            Li = L[idx]
            nudot = np.linalg.solve(np.swapaxes(Li, 1, 2), np.linalg.solve(Li, rhs[:, :, None]))[:, :, 0]
            A[idx] = np.einsum("gij,gj->gi", S[idx], nudot) + w[idx]
            ok[idx] &= np.all(np.isfinite(A[idx]), axis=1)
    own = models[0].forces(Q, V, A, TAU, np.flatnonzero(ok))
    ok &= own["ok"]
    force, determined, known, groups = own["force"], own["determined"], own["known"], own["groups"]
    need = ok & ~determined[:, :, 2].all(axis=1)
    if robot.spec.root == "planar" and need.any():  # the loads from the floating twin where the planar ones are
        if models[1] is None:  # undetermined (built at the first such sample, as the reference builds it)
            models[1] = _twin(robot, models[0])
        twin = models[1]
    else:
        twin = None
    if twin is False:  # its compiled model does not serve: the reference's samples
        ok &= ~need
    elif twin is not None:
        held = twin.forces(twin.lift(Q), twin.lift(V), twin.lift(A), TAU, np.flatnonzero(need))
        ok &= ~need | held["ok"]
        use = need & held["ok"] & (held["residual"] <= TWIN_RESIDUAL)
        force = np.where(use[:, None, None], held["force"], force)
        determined = np.where(use[:, None, None], held["determined"], determined)
        known = np.where(use[:, None, None], held["known"], known)
        groups = [(sel[~use[sel]], b[~use[sel]], T[~use[sel]]) for sel, b, T in groups] + [
            (sel[use[sel]], b[use[sel]], T[use[sel]]) for sel, b, T in held["groups"]]
    groups = [(sel[ok[sel]], b[ok[sel]], T[ok[sel]]) for sel, b, T in groups]
    return {"served": ok, "force": force, "determined": determined, "known": known,
            "groups": [g for g in groups if len(g[0])]}


def _twin(robot, own: _Model) -> _Model | bool:
    """A planar robot's floating twin as a :class:`_Model` (built as the reference builds it), or ``False`` where
    its compiled model does not serve or its wheels differ."""
    twin, index = floating_twin(robot)
    fast = compiled_model(twin)
    if fast is None:
        return False
    out = _Model(twin, fast, index)
    return out if [w.name for w in out.wheels] == [w.name for w in own.wheels] else False


class _Minimum:
    """The trajectory's ``minimum_mu``, block by block, as long as the trajectory has one: the reference reports it
    only when every sample has a wheel whose load is not all determined and every normal load is determined
    (:meth:`~robotdyn.contact.contact_forces.ConstraintForces.minimum_mu` is ``None`` otherwise), so once a sample
    says otherwise nothing more is computed."""

    def __init__(self, N: int) -> None:
        self.values = np.full(N, np.nan)
        self.wanted = True

    def add(self, part: slice, block: dict, references: dict, out: WheelLoads) -> None:
        """The minimum friction coefficient of one block's samples (fast ones from their tangential maps, the
        reference's own from its :class:`~robotdyn.contact.contact_forces.ConstraintForces`)."""
        if not self.wanted:
            return
        if out.load_determined[part].all(axis=1).any() or not out.normal_determined[part].all():
            self.wanted = False
            return
        values = self.values[part]
        fn = out.normal[part]
        for sel, b, T in block["groups"]:
            values[sel] = _cone_minimum(fn[sel], b, T)
        for j, forces in references.items():
            values[j] = forces.minimum_mu()

    def result(self) -> np.ndarray | None:
        return self.values if self.wanted else None


def _cone_minimum(fn: np.ndarray, b: np.ndarray, T: np.ndarray) -> np.ndarray:
    """:func:`robotdyn.contact.contact_forces.cone_minimum` of G samples at once: :math:`\\min_z \\max_i
    \\|b_i + T_i z\\| / f_{n,i}` with fn (G, W) [N] (all determined), b (G, W, 2) [N], T (G, W, 2, d).

    ``inf`` where a load is not positive; the ratio at z = 0 where no T_i moves (d = 0); exact where the stacked
    T_i have rank one (:func:`_cone_minimum_1d` along that direction: e.g. the lateral split of two wheels on one
    axle); else the reference's solver sample by sample."""
    G, W, _, d = T.shape
    out = np.full(G, np.inf)
    pressed = np.all(fn > 0, axis=1)
    with np.errstate(all="ignore"):
        ratio0 = np.max(np.linalg.norm(b, axis=2) / fn, axis=1)
    if d == 0:
        out[pressed] = ratio0[pressed]
        return out
    stacked = T.reshape(G, 2 * W, d)
    _, s, Vt = np.linalg.svd(stacked, full_matrices=False)
    rank = np.sum(s > DIRECTION_TOL, axis=1)
    flat = pressed & (rank == 0)
    out[flat] = ratio0[flat]
    line = np.flatnonzero(pressed & (rank == 1))
    if line.size:
        u = Vt[line, 0, :]  # the one direction that moves a tangential force
        t = np.einsum("gwkd,gd->gwk", T[line], u)
        # the reference searches z in [-scale, scale] for d = 1 (SLSQP, unbounded, for more)
        scale = 10.0 * (1.0 + np.max(np.linalg.norm(b[line], axis=2), axis=1)) if d == 1 else np.full(line.size,
                                                                                                    np.inf)
        out[line] = np.minimum(_cone_minimum_1d(fn[line], b[line], t, scale), ratio0[line])
    for g in np.flatnonzero(pressed & (rank > 1)):
        out[g] = cone_minimum([(b[g, w], T[g, w]) for w in range(W)], fn[g], d)
    return out


def _cone_minimum_1d(fn: np.ndarray, b: np.ndarray, t: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """:math:`\\min_{|y| \\le s} \\max_i \\|b_i + t_i y\\| / f_{n,i}` exactly, for G samples at once: fn (G, W) [N]
    (positive), b, t (G, W, 2) [N], s = ``scale`` (G,) (inf: unbounded).

    Each :math:`\\phi_i(y) = \\|b_i + t_i y\\| / f_{n,i}` is convex, so their maximum is smallest where one of them
    is at its own minimum (:math:`y = -b_i \\cdot t_i / \\|t_i\\|^2`), where two of them cross
    (:math:`\\phi_i^2 = \\phi_j^2`, a quadratic in y, solved without cancellation) or at a bound: the maximum is
    evaluated at every such candidate (and at y = 0) and the smallest value kept."""
    G, W, _ = b.shape
    with np.errstate(all="ignore"):
        alpha = np.sum(t * t, axis=2) / fn**2  # phi_i^2 = alpha_i y^2 + 2 beta_i y + gamma_i
        beta = np.sum(b * t, axis=2) / fn**2
        gamma = np.sum(b * b, axis=2) / fn**2
        cands = [np.zeros((G, 1)), np.where(alpha > 0, -beta / alpha, 0.0)]
        if W > 1:
            i, j = np.triu_indices(W, 1)
            qa, qb, qc = alpha[:, i] - alpha[:, j], beta[:, i] - beta[:, j], gamma[:, i] - gamma[:, j]
            root = np.sqrt(np.maximum(qb * qb - qa * qc, 0.0))
            qq = -(qb + np.where(qb >= 0, root, -root))  # qa y^2 + 2 qb y + qc = 0: y = qq / qa = qc / qq
            cands += [qq / qa, qc / qq]
        finite = np.isfinite(scale)
        bounds = np.where(finite, scale, 0.0)[:, None]
        cands.append(np.hstack([-bounds, bounds]))
        y = np.hstack(cands)
        y = np.where(np.isfinite(y), y, 0.0)
        y = np.clip(y, np.where(finite, -scale, -np.inf)[:, None], np.where(finite, scale, np.inf)[:, None])
        values = np.linalg.norm(b[:, None] + t[:, None] * y[:, :, None, None], axis=3) / fn[:, None]  # (G, C, W)
        return np.min(np.max(values, axis=2), axis=1)


__all__ = ["WheelLoads", "wheel_loads", "sample_loads", "torques", "BLOCK"]

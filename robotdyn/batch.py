"""Batch evaluation of the reduced model at many states (design sweeps, learning data sets).

:func:`evaluate` returns stacked arrays, ``M`` (N, k, k), ``h`` (N, k), ``g`` (N, k), ``B`` (N, k, m) and ``S``
(N, n, k), for N states, optionally spread over worker processes (one robot copy per process, inherited by
fork): by the robot's compiled model (:mod:`robotdyn.compiled`) where it serves the robot, else vectorised in
numpy (wheels on a plane and loop closures) or one by one. A state where the constraints are singular raises :class:`~robotdyn.errors.SingularConstraintError`
naming its index.
"""

from __future__ import annotations

import multiprocessing as mp
import os
from dataclasses import dataclass

import numpy as np

import pinocchio as pin

from .actuation import input_matrix
from .compiled import compiled_model
from .constraint import LWA, KinematicState
from .errors import RobotDynError, SingularConstraintError
from .projection import MAX_CONDITION, project
from .reduced_dynamics import constraint_set
from .wheel_group import WheelGroup

_WORKER_ROBOT = None


@dataclass
class Batch:
    """Reduced models at N states (arrays stacked along the first axis)."""

    M: np.ndarray
    h: np.ndarray
    g: np.ndarray
    B: np.ndarray
    S: np.ndarray

    def __len__(self) -> int:
        return self.M.shape[0]

    def __repr__(self) -> str:
        return f"Batch(N={len(self)}, k={self.M.shape[1]})"


def _vectorisable(robot) -> bool:
    """Whether the states can be evaluated together: every constraint in a wheel group on a plane (without
    radius joints) or a loop-closure group, and joint-selected independent velocities."""
    if getattr(robot, "operational", None) is not None:
        return False
    cset = constraint_set(robot)
    if cset.others or not cset.groups:
        return False
    return all(not isinstance(g, WheelGroup) or (g.plane and not g.radial.size) for g, _ in cset.groups)


def _evaluate_vectorised(robot, Q: np.ndarray, NU: np.ndarray, offset: int) -> tuple[np.ndarray, ...]:
    """All states at once: three Python loops of Pinocchio calls per state (kinematics, CRBA and gravity at q;
    Jacobian time variation at (q, v); RNEA), the constraint geometry, projection and drift vectorised over
    states with the group formulas of :class:`~robotdyn.wheel_group.WheelGroup` and
    :class:`~robotdyn.loop_closure.LoopGroup`. States where the projection of the first state does not apply
    (other independent rows needed, or singular) are evaluated one by one by :meth:`Robot.reduced`."""
    model, data = robot.model, robot.data
    N, n = Q.shape
    k = robot.mobility
    cset = constraint_set(robot)
    groups = [(g.tile(N), g) for g, _ in cset.groups]
    reacting = [(j, m) for j, m in enumerate(robot.motors) if m.rid is not None]
    Jjoint = np.empty((N, len(reacting), 6, n))  # Jacobians of the reacting motors' joints and reaction bodies
    Jreact = np.empty((N, len(reacting), 6, n))
    Ms, G = np.empty((N, n, n)), np.empty((N, n))
    B = np.empty((N, n, len(robot.motors)))
    frames = []  # per group: arrays of Jacobians, rotations, origins for all states
    for _, g in groups:
        fids = g.fids if isinstance(g, WheelGroup) else [f for pair in zip(g.f1, g.f2) for f in pair]
        frames.append((fids, np.empty((N, len(fids), 6, n)), np.empty((N, len(fids), 3, 3)), np.empty((N, len(fids), 3))))
    zero = np.zeros(n)
    B0 = input_matrix(robot.motors, KinematicState(model, data, Q[0], zero))  # reacting columns: set below
    for i in range(N):  # pass 1: configuration-level kinematics and dynamics
        q = Q[i]
        pin.computeJointJacobians(model, data, q)  # what KinematicState(q, 0) runs
        pin.updateFramePlacements(model, data)
        for fids, J, rot, pos in frames:
            Ji, roti, posi = J[i], rot[i], pos[i]
            for j, f in enumerate(fids):
                Ji[j] = pin.getFrameJacobian(model, data, f, LWA)
                placement = data.oMf[f]
                roti[j] = placement.rotation
                posi[j] = placement.translation
        for r, (_, m) in enumerate(reacting):
            Jjoint[i, r] = pin.getJointJacobian(model, data, m.jid, LWA)
            Jreact[i, r] = pin.getFrameJacobian(model, data, m.rid, LWA)
        Ms[i] = pin.crba(model, data, q)
        G[i] = pin.computeGeneralizedGravity(model, data, q)
    B[:] = B0
    for r, (j, m) in enumerate(reacting):  # Motor.column for all states: (J_w,child - J_w,reaction)^T axis
        ang, lin = Jjoint[:, r, 3:, m.index], Jjoint[:, r, :3, m.index]
        axis = np.where((np.einsum("ni,ni->n", ang, ang) > 0.25)[:, None], ang, lin)
        B[:, :, j] = ((Jjoint[:, r, 3:] - Jreact[:, r, 3:]).transpose(0, 2, 1) @ axis[:, :, None])[:, :, 0]
    A_parts, geos = [], []
    for (tiled, g), (fids, J, rot, pos) in zip(groups, frames):
        nf = len(fids)
        J, rot, pos = J.reshape(N * nf, 6, n), rot.reshape(N * nf, 3, 3), pos.reshape(N * nf, 3)
        if isinstance(g, WheelGroup):
            geo = tiled._rows(tiled._plane_contact(rot, pos, tiled.R0), J)
            A_parts.append(geo["A"].reshape(N, -1, n))
        else:
            geo = (J[0::2], J[1::2], rot[0::2], rot[1::2], pos[0::2], pos[1::2])
            A_parts.append(tiled._rows(*geo).A.reshape(N, -1, n))
        geos.append(geo)
    A = np.concatenate(A_parts, axis=1)
    perm = cset._permutation(())
    if perm is not None:
        A = A[:, perm]
    try:
        proj0 = project(A[0], robot.independent_indices, robot.velocity_labels, hint=robot._projection_hint)
    except SingularConstraintError:  # the first state is singular: one by one (names the state)
        return _evaluate_loop(robot, Q, NU, offset)
    rows, dep, ind = proj0.rows, proj0.dependent, proj0.independent
    Ar = A[:, rows]
    Ad = Ar[:, :, dep]
    bad = np.zeros(N, bool)
    with np.errstate(all="ignore"):
        try:
            Ad_inv = np.linalg.inv(Ad)
        except np.linalg.LinAlgError:  # a singular block: invert state by state, mark the singular ones
            Ad_inv = np.zeros_like(Ad)
            for i in range(N):
                try:
                    Ad_inv[i] = np.linalg.inv(Ad[i])
                except np.linalg.LinAlgError:
                    bad[i] = True
        cond = np.abs(Ad).sum(axis=1).max(axis=1) * np.abs(Ad_inv).sum(axis=1).max(axis=1)
        S = np.zeros((N, n, k))
        S[:, ind, np.arange(k)] = 1.0
        S[:, dep] = -Ad_inv @ Ar[:, :, ind]
        scale = np.maximum(1.0, np.abs(A).max(axis=(1, 2)))
        bad |= ~np.isfinite(cond) | (cond > MAX_CONDITION) | ~(np.abs(A @ S).max(axis=(1, 2)) <= 1e-10 * scale)
    S[bad] = 0.0  # evaluated one by one below; keep non-finite numbers away from Pinocchio
    Ad_inv[bad] = 0.0
    V = (S @ NU[:, :, None])[:, :, 0]
    dframes = [np.empty((N, len(fids), 6, n)) for fids, *_ in frames]
    for i in range(N):  # pass 2: Jacobian time variation along v = S nu
        pin.computeJointJacobiansTimeVariation(model, data, Q[i], V[i])
        for (fids, *_), dJ in zip(frames, dframes):
            dJi = dJ[i]
            for j, f in enumerate(fids):
                dJi[j] = pin.getFrameJacobianTimeVariation(model, data, f, LWA)
    drift_parts = []
    for (tiled, g), (fids, J, *_), dJ, geo in zip(groups, frames, dframes, geos):
        nf = len(fids)
        Vs = V[:, None, :, None]
        Jv = (J @ Vs)[..., 0].reshape(N * nf, 6)
        dJv = (dJ @ Vs)[..., 0].reshape(N * nf, 6)
        if isinstance(g, WheelGroup):
            s = (geo["Aw"].reshape(N, nf, 3, n) @ Vs)[..., 0].reshape(N * nf, 3)
            d = tiled._drift(geo, Jv, dJv, s, np.zeros((N * nf, 1)))
        else:
            d = tiled._drift(geo[2], geo[4], geo[5], Jv[0::2], Jv[1::2], dJv[0::2], dJv[1::2])
        drift_parts.append(d.reshape(N, -1))
    drift = np.concatenate(drift_parts, axis=1)
    if perm is not None:
        drift = drift[:, perm]
    W = np.zeros((N, n))
    W[:, dep] = -(Ad_inv @ drift[:, rows, None])[:, :, 0]
    H = np.empty((N, n))
    for i in range(N):  # pass 3: the bias RNEA(q, v, w)
        H[i] = pin.rnea(model, data, Q[i], V[i], W[i])
    St = S.transpose(0, 2, 1)
    M, h, g, Br = St @ Ms @ S, (St @ H[:, :, None])[:, :, 0], (St @ G[:, :, None])[:, :, 0], St @ B
    for i in np.flatnonzero(bad):  # another choice of rows, or singular (raises, naming the state)
        red = _reduced_named(robot, Q[i], NU[i], offset + i)
        M[i], h[i], g[i], Br[i], S[i] = red.M, red.h, red.g, red.B, red.S
    return M, h, g, Br, S


def _reduced_named(robot, q: np.ndarray, nu: np.ndarray, index: int):
    """``robot.reduced(q, nu)``, with a singular state's index in the error message."""
    try:
        return robot.reduced(q, nu)
    except SingularConstraintError as exc:
        raise SingularConstraintError(f"state {index}: {exc}", exc.condition) from None


def _evaluate_compiled(robot, fast, Q: np.ndarray, NU: np.ndarray, offset: int) -> tuple[np.ndarray, ...]:
    """All states in one call of the robot's compiled model (:mod:`robotdyn.compiled`); states where its row
    choice does not apply are evaluated one by one by :meth:`Robot.reduced`."""
    if not fast.ready:  # the Python path chooses the projection's rows at the first state
        _reduced_named(robot, Q[0], NU[0], offset)
    M, h, g, S, _, B, failed = fast.evaluate_many(Q, NU)
    for i in failed:
        red = _reduced_named(robot, Q[i], NU[i], offset + i)
        M[i], h[i], g[i], B[i], S[i] = red.M, red.h, red.g, red.B, red.S
    return M, h, g, B, S


def _evaluate_chunk(robot, Q: np.ndarray, NU: np.ndarray, offset: int) -> tuple[np.ndarray, ...]:
    fast = compiled_model(robot)
    if len(Q) and fast is not None:
        return _evaluate_compiled(robot, fast, Q, NU, offset)
    if len(Q) and _vectorisable(robot):
        return _evaluate_vectorised(robot, Q, NU, offset)
    return _evaluate_loop(robot, Q, NU, offset)


def _evaluate_loop(robot, Q: np.ndarray, NU: np.ndarray, offset: int) -> tuple[np.ndarray, ...]:
    N, k = len(Q), robot.mobility
    M = np.empty((N, k, k))
    h = np.empty((N, k))
    g = np.empty((N, k))
    B = np.empty((N, k, len(robot.motors)))
    S = np.empty((N, robot.nq, k))
    for i in range(N):
        red = _reduced_named(robot, Q[i], NU[i], offset + i)
        M[i], h[i], g[i], B[i], S[i] = red.M, red.h, red.g, red.B, red.S
    return M, h, g, B, S


def _worker(args):
    Q, NU, offset = args
    return _evaluate_chunk(_WORKER_ROBOT, Q, NU, offset)


def evaluate(robot, Q, NU, processes: int | None = 1) -> Batch:
    """The reduced model of ``robot`` at the states (Q[i], NU[i]).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        Q: Natural coordinates, shape (N, n).
        NU: Independent velocities, shape (N, k).
        processes: Worker processes (``None``: one per CPU; 1: in this process).

    Raises:
        RobotDynError: Wrong shapes or non-finite entries.
        SingularConstraintError: At a singular state (its index is named).
    """
    Q, NU = np.asarray(Q, dtype=float), np.asarray(NU, dtype=float)
    if Q.ndim != 2 or Q.shape[1] != robot.nq:
        raise RobotDynError(f"Q has shape {Q.shape}; expected (N, {robot.nq}) ({', '.join(robot.coordinates)})")
    if NU.shape != (len(Q), robot.mobility):
        raise RobotDynError(f"NU has shape {NU.shape}; expected ({len(Q)}, {robot.mobility})")
    if not (np.all(np.isfinite(Q)) and np.all(np.isfinite(NU))):
        raise RobotDynError("Q and NU must be finite (found NaN or inf)")
    processes = (os.cpu_count() or 1) if processes is None else int(processes)
    if processes <= 1 or len(Q) < 2 * processes or "fork" not in mp.get_all_start_methods():
        return Batch(*_evaluate_chunk(robot, Q, NU, 0))
    global _WORKER_ROBOT
    _WORKER_ROBOT = robot
    bounds = np.linspace(0, len(Q), processes + 1).astype(int)
    chunks = [(Q[a:b], NU[a:b], a) for a, b in zip(bounds[:-1], bounds[1:])]
    try:
        with mp.get_context("fork").Pool(processes) as pool:
            parts = pool.map(_worker, chunks)
    finally:
        _WORKER_ROBOT = None
    return Batch(*(np.concatenate([p[j] for p in parts]) for j in range(5)))

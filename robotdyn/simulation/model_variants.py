"""Variants of one robot that differ only in numbers: masses, inertias, lengths, radii, gravity.

A compiled model (:mod:`robotdyn.fast.compiled`) is built from a vector of numbers, its *model vector*: per joint its
placement and body inertia (mass, centre of mass, inertia about it), per frame its placement, per wheel its radius
and axle, per joint coupling its law, and the gravity (``robotdyn/_compiled.cpp``, ``model_vector``). Robots built
from one description with different parameter values share everything else (joints, frames, constraints, motors),
so one compiled model can simulate all of them by swapping that vector: no Xacro expansion, URDF parsing or model
build per run (:func:`robotdyn.simulation.batch.simulate_many`).

:class:`ParameterModel` gives the model vector as a function of chosen robot parameters, without knowing how the
description uses them: it builds the robot at probe points of a box of parameter values and fits each entry of the
vector, in the parameters it depends on, by a polynomial of total degree <= 3 -- with the body inertias in
Pinocchio's dynamic parameters :math:`\\pi = (m, m c, I_O)` (Atkeson et al. 1986; ``Inertia.toDynamicParameters``),
in which masses, first moments and inertias are linear, and a merged body is a sum. The fit must reproduce every
probe to 1e-11 (relative): masses, inertias, lengths and radii that enter as products of at most three of them
(e.g. a wheel's :math:`m r^2/2`) pass; a parameter that enters otherwise (a ratio such as ``rho = r / l``, an angle
inside a rotation) is refused in one line naming it, with the alternative of passing built robots.
:func:`variant` builds the :class:`~robotdyn.robot.Robot` of a model vector, so that any run of a batch can be
repeated alone with :func:`robotdyn.simulation.engine.simulate` (bit for bit).
"""

from __future__ import annotations

import copy
import itertools
import threading

import numpy as np
import pinocchio as pin

from ..fast.dispatch import compiled_model
from ..fast.compiled import why_not
from ..errors import DescriptionError, InputError

JOINT, FRAME, WHEEL, COUPLING, GRAVITY = 22, 12, 4, 4, 3
"""Entries per joint, frame, wheel and coupling, and of the gravity, in a model vector."""

FIT_TOL = 1e-11
"""Largest relative error of the polynomial fit at the probes (round-off is ~1e-15)."""


def _fast(robot):
    fast = compiled_model(robot)
    if fast is None:
        raise InputError(f"robot {robot.spec.name!r} has no compiled model ({why_not(robot)}); many simulations in "
                         "one call need it")
    return fast


def model_vector(robot) -> np.ndarray:
    """The robot's model vector (as its compiled model reads it).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` with a compiled model.

    Returns:
        The model vector (L,).
    """
    return np.array(_fast(robot).ev.model_vector())


def structure(robot) -> tuple:
    """Everything of the compiled model that a model vector does not hold: joint kinds and parents, the frames'
    joints, the constraints' kinds, rows and joints, the motors, the terrain. Robots with equal structures can share
    one compiled model.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` with a compiled model.

    Returns:
        The tuple ``(joints, frames, rows, motors, terrains, velocity names)`` (equal for robots that can share a
        compiled model).
    """
    fast = _fast(robot)
    model = robot.model
    joints = tuple((model.joints[i].shortname(), int(model.parents[i])) for i in range(1, model.njoints))
    frames = tuple(int(model.frames[f].parentJoint) for f in fast.frame_ids)
    rows = (tuple(fast.labels), tuple(bool(h) for h in fast.holonomic))
    motors = tuple((m.index, m.jid, m.rid) for m in robot.motors)
    terrains = tuple(repr(getattr(c, "terrain", None)) for c in robot.constraints)
    return joints, frames, rows, motors, terrains, tuple(robot.velocity_names)


def variant(robot, vector: np.ndarray):
    """A copy of ``robot`` whose model vector is ``vector`` (the same description, constraints and motors).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` with a compiled model.
        vector: A model vector of its layout (:func:`model_vector`).

    Returns:
        The new :class:`~robotdyn.robot.Robot` (``robot`` is not changed).
    """
    fast = _fast(robot)
    vector = np.asarray(vector, float)
    if vector.shape != (fast.ev.model_vector().size,):
        raise InputError(f"model vector of shape {vector.shape}; expected ({fast.ev.model_vector().size},)")
    out = copy.copy(robot)
    for key in ("_constraint_set", "_compiled_model", "_floating_twin"):
        out.__dict__.pop(key, None)
    out._local = threading.local()
    out._projection_hint = robot._projection_hint
    model = out.model = robot.model.copy()
    out.description = copy.copy(robot.description)
    out.description.model = model
    i = 0

    def se3() -> pin.SE3:
        nonlocal i
        R, p = vector[i:i + 9].reshape(3, 3), vector[i + 9:i + 12]
        i += 12
        return pin.SE3(R.copy(), p.copy())

    for j in range(1, model.njoints):
        model.jointPlacements[j] = se3()
        m, c, I = vector[i], vector[i + 1:i + 4], vector[i + 4:i + 10]
        model.inertias[j] = pin.Inertia(float(m), c.copy(), np.array([[I[0], I[1], I[2]], [I[1], I[3], I[4]],
                                                                       [I[2], I[4], I[5]]]))
        i += 10
    for f in fast.frame_ids:
        model.frames[f].placement = se3()
    replaced = {}
    for w in fast.wheels:
        new = copy.copy(w)
        new.radius, new.axis = float(vector[i]), vector[i + 1:i + 4].copy()
        replaced[id(w)] = new
        i += WHEEL
    for c in fast.couplings:
        new = copy.copy(c)
        new.law = type(c.law)(*(float(x) for x in vector[i:i + 4]))
        new.dlaw, new.ddlaw = new.law.d, new.law.dd
        replaced[id(c)] = new
        i += COUPLING
    model.gravity.linear = vector[i:i + 3].copy()
    out.constraints = [replaced.get(id(c), c) for c in robot.constraints]
    return out


def _inertia_slots(njoints: int) -> np.ndarray:
    """Start index of each joint's inertia block (mass, lever, I) in a model vector."""
    return np.array([JOINT * j + 12 for j in range(njoints - 1)], dtype=int)


def to_dynamic(V: np.ndarray, slots: np.ndarray) -> np.ndarray:
    """Model vectors (N, L) with each inertia block as :math:`\\pi = (m, mc, I_O)` (inertia about the joint frame's
    origin: :math:`I_O = I_C + m(|c|^2 1 - cc^T)`, entries xx xy xz yy yz zz).

    Args:
        V: Model vectors (N, L), inertia blocks as (m, c, I_C).
        slots: Start index of each inertia block in a model vector.

    Returns:
        The converted model vectors (N, L).
    """
    V = np.array(V, float)
    for s in slots:
        m, c, I = V[:, s], V[:, s + 1:s + 4], V[:, s + 4:s + 10]
        cx, cy, cz = c.T
        shift = np.stack([cy**2 + cz**2, -cx * cy, -cx * cz, cx**2 + cz**2, -cy * cz, cx**2 + cy**2], axis=1)
        V[:, s + 4:s + 10] = I + m[:, None] * shift
        V[:, s + 1:s + 4] = m[:, None] * c
    return V


def from_dynamic(V: np.ndarray, slots: np.ndarray) -> np.ndarray:
    """The inverse of :func:`to_dynamic` (a massless body keeps a zero centre of mass).

    Args:
        V: Model vectors (N, L), inertia blocks as (m, mc, I_O).
        slots: Start index of each inertia block in a model vector.

    Returns:
        The model vectors (N, L) in the model vector's own form.
    """
    V = np.array(V, float)
    for s in slots:
        m = V[:, s]
        c = np.divide(V[:, s + 1:s + 4], m[:, None], out=np.zeros((len(m), 3)), where=m[:, None] != 0)
        cx, cy, cz = c.T
        shift = np.stack([cy**2 + cz**2, -cx * cy, -cx * cz, cx**2 + cz**2, -cy * cz, cx**2 + cy**2], axis=1)
        V[:, s + 4:s + 10] = V[:, s + 4:s + 10] - m[:, None] * shift
        V[:, s + 1:s + 4] = c
    return V


def physical(V: np.ndarray, robot) -> list[str]:
    """Per model vector (N, L): '' where every body is physical, else why not (a negative mass, an inertia that is
    not positive semi-definite or breaks the triangle inequality of principal moments, as
    :func:`robotdyn.description.urdf.validate_urdf` refuses in a description).

    Args:
        V: Model vectors (N, L) (or one (L,)).
        robot: The :class:`~robotdyn.robot.Robot` they are variants of (its joint names for the messages).

    Returns:
        One string per model vector, in order (``''``: physical).
    """
    V = np.atleast_2d(V)
    out = [""] * len(V)
    names = robot.model.names
    for j, s in enumerate(_inertia_slots(robot.model.njoints)):
        m, I = V[:, s], V[:, s + 4:s + 10]
        mats = np.stack([I[:, [0, 1, 2]], I[:, [1, 3, 4]], I[:, [2, 4, 5]]], axis=1)
        eig = np.linalg.eigvalsh(mats)  # ascending
        tol = 1e-9 * np.maximum(np.abs(eig).max(axis=1), 1e-300)
        bad = (m < 0) | (eig[:, 0] < -tol) | (eig[:, 0] + eig[:, 1] < eig[:, 2] - tol)
        for i in np.flatnonzero(bad):
            if not out[i]:
                out[i] = (f"the body of joint {names[j + 1]} is not physical (mass {m[i]:.6g} kg, principal inertias "
                          f"{', '.join(f'{x:.6g}' for x in eig[i])} kg m^2)")
    return out


def _monomials(X: np.ndarray, degree: int) -> tuple[np.ndarray, list[tuple[int, ...]]]:
    """All monomials of total degree <= ``degree`` in the columns of X (N, d): values (N, B) and exponents."""
    d = X.shape[1]
    exps = [e for total in range(degree + 1) for e in itertools.product(range(total + 1), repeat=d) if sum(e) == total]
    return np.stack([np.prod(X ** np.array(e), axis=1) for e in exps], axis=1), exps


class ParameterModel:
    """The model vector of ``robot`` as a polynomial of some of its parameters, fitted at probes and verified.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` with a compiled model (its other parameters stay as they are).
        bounds: Parameter name -> (low, high), the box the runs' values lie in.
        degree: Total degree of the fit (3: products of up to three parameters).
        seed: Seed of the random probe points (the fit is reproducible).
        points: Candidate probe points (P, len(bounds)), e.g. the runs' values (default: uniform in the box); a
            point whose robot is not physical (an inertia off its triangle inequality) is skipped.

    Raises:
        InputError: An unknown or non-numeric parameter, a parameter that changes the robot's structure (joints,
            frames, constraints) or enters the model vector other than polynomially.
    """

    def __init__(self, robot, bounds: dict[str, tuple[float, float]], degree: int = 3, seed: int = 0,
                 points=None) -> None:
        from ..robot import Robot

        self.robot, self.names, self.degree = robot, list(bounds), degree
        lo = np.array([float(bounds[n][0]) for n in self.names])
        hi = np.array([float(bounds[n][1]) for n in self.names])
        for n, a, b in zip(self.names, lo, hi):
            p = robot.spec.parameter(n)
            if p.choices is not None:
                raise InputError(f"parameter {n} is a choice ({', '.join(p.choices)}); only numbers can vary per run")
            if not (np.isfinite(a) and np.isfinite(b) and a <= b):
                raise InputError(f"bounds of {n}: [{a}, {b}]; expected finite low <= high")
            p.convert(a), p.convert(b)  # physical limits (e.g. masses >= 0), one line
        span = np.maximum(hi - lo, 1e-6 * np.maximum(1.0, np.abs(lo)))
        self.low, self.high, self.centre, self.span = lo, hi, 0.5 * (lo + hi), span
        base = structure(robot)
        nominal = model_vector(robot)
        self.slots = _inertia_slots(robot.model.njoints)

        def build(values: np.ndarray) -> np.ndarray:
            params = {**robot.params, **dict(zip(self.names, (float(v) for v in values)))}
            probe = Robot(robot.spec, params, terrain=robot.terrain)
            probe.reduced(probe.neutral(), np.zeros(probe.mobility))  # chooses the projection (compiled layout)
            if structure(probe) != base:
                raise InputError(f"parameters {', '.join(self.names)} change the robot's structure (joints, frames, "
                                 "constraints or terrain), not only its numbers; expected masses, inertias, lengths")
            return model_vector(probe)

        rng = np.random.default_rng(seed)
        m = len(self.names)
        box = self.centre + rng.uniform(-0.5, 0.5, (1000, m)) * span
        if points is None:
            candidates = box
        else:  # the runs' own values first: physical robots where the box's corners may not be
            runs = np.unique(np.atleast_2d(np.asarray(points, float)), axis=0)
            candidates = np.vstack([runs[rng.permutation(len(runs))], box])
        tried, failures = iter(candidates), []

        def next_probe() -> tuple[np.ndarray, np.ndarray]:
            for point in tried:
                try:
                    return point, build(point)
                except DescriptionError as exc:  # an unphysical combination (e.g. an inertia's triangle inequality)
                    failures.append(str(exc))
                    if len(failures) > 50:
                        break
            raise InputError(f"too few valid robots among the probe points of {', '.join(self.names)} (e.g. "
                             f"{failures[-1] if failures else 'none left'}); expected a box of physical parameter "
                             "values")

        anchor, centre = next_probe()
        # dependence: one small step per parameter from the anchor (a valid robot nearby)
        steps = 0.01 * span * np.where(anchor + 0.01 * span <= self.high, 1.0, -1.0)
        single = [build(anchor + steps[j] * np.eye(m)[j]) for j in range(m)]
        Pc, Ps = to_dynamic(centre[None], self.slots)[0], to_dynamic(np.array(single), self.slots)
        depends = np.abs(Ps - Pc) > 1e-15 * np.maximum(1.0, np.abs(Pc))  # (m, L)
        groups: dict[tuple[int, ...], list[int]] = {}
        for e in range(Pc.size):
            key = tuple(np.flatnonzero(depends[:, e]))
            if key:
                groups.setdefault(key, []).append(e)
        need = max([len(_monomials(np.zeros((1, len(k))), degree)[1]) for k in groups] or [1])
        probes = [next_probe() for _ in range(need + 6)] if groups else []
        points = np.array([p for p, _ in probes]).reshape(-1, m)
        values = to_dynamic(np.array([v for _, v in probes]).reshape(-1, Pc.size), self.slots)
        X = np.vstack([(anchor - self.centre) / span, (anchor - self.centre) / span + np.diag(steps / span),
                       (points - self.centre) / span])
        Y = np.vstack([Pc, Ps, values])
        fixed = ~np.any(depends, axis=0)
        moved = fixed & np.any(np.abs(values - Pc) > FIT_TOL * np.maximum(1.0, np.abs(Pc)), axis=0)
        if moved.any():  # a pure cross term that no single-parameter probe revealed: fit it in all parameters
            groups.setdefault(tuple(range(m)), []).extend(np.flatnonzero(moved).tolist())
            fixed &= ~moved
        self.base = np.where(fixed, to_dynamic(nominal[None], self.slots)[0], 0.0)
        self.fixed = fixed
        self.fits = []
        for key, entries in groups.items():
            A, exps = _monomials(X[:, key], degree)
            coef, *_ = np.linalg.lstsq(A, Y[:, entries], rcond=None)
            err = np.abs(A @ coef - Y[:, entries])
            scale = np.maximum(1.0, np.abs(Y[:, entries]).max(axis=0))
            bad = np.flatnonzero(err.max(axis=0) > FIT_TOL * scale)
            if bad.size:
                names = ", ".join(self.names[k] for k in key)
                raise InputError(f"parameter(s) {names} enter the model other than as a polynomial of degree <= "
                                 f"{degree} ({self._entry(entries[bad[0]])} misses by {err[:, bad[0]].max():.3g}): "
                                 "they cannot vary without rebuilding the model; pass built robots instead "
                                 "(simulate_many(..., robots=[...]))")
            self.fits.append((list(key), exps, coef, entries))

    def _entry(self, e: int) -> str:
        """A readable name of model-vector entry e."""
        model = self.robot.model
        nj = model.njoints - 1
        if e < JOINT * nj:
            j, k = divmod(e, JOINT)
            return f"the {'placement' if k < 12 else 'body inertia'} of joint {model.names[j + 1]}"
        return "a frame placement, wheel radius or axle, or coupling law"

    def __repr__(self) -> str:
        box = ", ".join(f"{n} in [{a:g}, {b:g}]" for n, a, b in zip(self.names, self.low, self.high))
        return f"ParameterModel({self.robot.spec.name!r}: {box}; {len(self.fits)} fitted groups)"

    def vectors(self, values: np.ndarray) -> np.ndarray:
        """Model vectors (N, L) at parameter values (N, len(names)) inside the box.

        Args:
            values: Parameter values (N, len(names)) in the parameters' units (or one row).

        Returns:
            The model vectors (N, L).

        Raises:
            InputError: A value outside the box (the fit is verified only inside it).
        """
        values = np.atleast_2d(np.asarray(values, float))
        tol = 1e-9 * self.span
        outside = (values < self.low - tol) | (values > self.high + tol) | ~np.isfinite(values)
        if outside.any():
            i, j = np.argwhere(outside)[0]
            raise InputError(f"run {i}: {self.names[j]} = {values[i, j]:g} lies outside the fitted range "
                             f"[{self.low[j]:g}, {self.high[j]:g}]; give bounds that contain every run's value")
        X = (values - self.centre) / self.span
        V = np.tile(self.base, (len(values), 1))
        for key, exps, coef, entries in self.fits:
            A = np.stack([np.prod(X[:, key] ** np.array(e), axis=1) for e in exps], axis=1)
            V[:, entries] = A @ coef
        varied = np.zeros(V.shape[1], bool)
        for _, _, _, entries in self.fits:
            varied[entries] = True
        out = from_dynamic(V, self.slots)
        nominal = model_vector(self.robot)
        for s in self.slots:  # an inertia block that no parameter moves keeps its exact nominal numbers
            if not varied[s:s + 10].any():
                out[:, s:s + 10] = nominal[s:s + 10]
        keep = self.fixed.copy()
        for s in self.slots:
            keep[s:s + 10] = False
        out[:, keep] = nominal[keep]
        return out


__all__ = ["ParameterModel", "model_vector", "structure", "variant", "physical", "to_dynamic", "from_dynamic"]

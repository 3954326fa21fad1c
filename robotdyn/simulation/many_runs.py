"""Many simulations of one robot's variants in one call: :func:`simulate_many` (also ``robotdyn.simulation.batch.simulate_many``).

N runs -- differing in initial states, torque profiles (:mod:`robotdyn.simulation.torque_profile`), and parameters that change
only numbers of the model (masses, inertias, lengths, radii, g: :mod:`robotdyn.simulation.model_variants`) or in built robots
of one description -- are simulated by the compiled engine (:mod:`robotdyn.simulation.compiled_engine`) on C++ threads
(``Evaluator.simulate_many`` in ``robotdyn/_compiled.cpp``: the GIL released, one model copy per thread, the runs
handed out one at a time). Every run's numbers are those of the same run alone, whatever the number of threads.
Results come back as arrays per run (:class:`ManyRuns`); a failing run is flagged with its message, not raised.
"""

from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from ..fast.dispatch import compiled_model
from ..errors import InputError, RobotDynError
from ..reduction.pull_back import STABILISATION


@dataclass
class ManyRuns:
    """N simulations sampled at the same times.

    Attributes:
        t: Sample times (S,) [s].
        q: Natural coordinates (N, S, n), named by ``coordinates``.
        nu: Independent velocities (N, S, k), named by ``velocity_names``.
        energy: Total mechanical energy (N, S) [J].
        residual: Largest holonomic residual (N, S) [m or rad].
        ok: (N,) whether run i reached t_end.
        samples: (N,) samples run i computed (S when ok; the rest of its rows are NaN).
        messages: Why run i failed ('' when ok).
        nfev: (N,) right-hand-side evaluations per run.
        models: (N, L) the model vector of each run (:mod:`robotdyn.simulation.model_variants`; ``None`` when the runs share
            the robot's): ``simulate(variant(robot, models[i]), ...)`` repeats run i alone, bit for bit.
        walls: (N,) wall-clock time of each run's integration [s] (0 for runs not started).
        stats: Wall time [s], threads, integrator, runs per second, ``partial`` after an interruption.
        coordinates: Names of the n coordinates.
        velocity_names: Names of the k independent velocities.
    """

    t: np.ndarray
    q: np.ndarray
    nu: np.ndarray
    energy: np.ndarray
    residual: np.ndarray
    ok: np.ndarray
    samples: np.ndarray
    messages: list[str]
    nfev: np.ndarray
    coordinates: list[str]
    velocity_names: list[str]
    models: np.ndarray | None = None
    walls: np.ndarray | None = None
    stats: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.ok)

    def __repr__(self) -> str:
        return (f"ManyRuns(N={len(self)}, samples={len(self.t)}, ok={int(self.ok.sum())}, "
                f"wall={self.stats.get('wall', 0):.3g} s, threads={self.stats.get('threads')})")


def _per_run(x, N: int | None, width: int, what: str, names) -> tuple[np.ndarray, int | None]:
    """``x`` as (N, width): one row for all runs or one per run (N fixed by the first per-run input)."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 1:
        if a.shape != (width,):
            raise RobotDynError(f"{what} has {a.size} entries; expected {width} ({', '.join(names)}) or one row per run")
        return a, N
    if a.ndim != 2 or a.shape[1] != width or (N is not None and a.shape[0] != N):
        raise RobotDynError(f"{what} has shape {a.shape}; expected ({N if N is not None else 'N'}, {width})")
    return a, a.shape[0]


def simulate_many(robot, t_end: float, q0=None, nu0=None, torque=None, params: dict | None = None,
                  robots: list | None = None, bounds: dict | None = None, n_out: int = 101, rtol: float = 1e-10,
                  atol: float = 1e-12, method: str = "adams", stabilisation: float = STABILISATION,
                  threads: int | None = None, progress: bool = False, *, models=None,
                  time_limit: float | None = None) -> ManyRuns:
    """N simulations of one robot's variants in one call, spread over threads (compiled engine only).

    Every run is what :func:`robotdyn.simulation.engine.simulate` would compute alone on the compiled engine with the
    same arguments (bit for bit, on any number of threads; a parameter-varied run on the robot
    :func:`robotdyn.simulation.model_variants.variant` gives); the runs differ in any of:

    - ``q0`` (N, n) / ``nu0`` (N, k): initial states (or one row for all);
    - ``torque``: one :class:`~robotdyn.simulation.torque_profile.TorqueProfile` for all, or a list of N;
    - ``params``: parameter name -> (N,) values, for parameters that change only numbers of the model (masses,
      inertias, lengths, radii, g): the model vector comes from a :class:`~robotdyn.simulation.model_variants.ParameterModel`
      fitted once over ``bounds`` (default: the values' range) and cached, so a sweep split in chunks should pass
      the whole sweep's ``bounds`` to share one fit;
    - ``robots``: N built robots of the same structure as ``robot`` (any parameters, at the cost of a build each);
    - ``models``: N model vectors (N, L) of ``robot``'s layout, e.g. from one
      :class:`~robotdyn.simulation.model_variants.ParameterModel` fitted for a whole sweep and sent in chunks (a
      sweep's worker computes no fit and its runs do not depend on which chunk holds them).

    All inputs are plain data that pickle (a Dask worker may call this per chunk).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` or a registered robot name.
        t_end: Duration of every run [s].
        q0, nu0: Initial states (default: the neutral configuration at rest).
        torque: None (no actuation), a profile, or a list of N profiles.
        params, bounds: Per-run parameter values, and the box they lie in.
        robots: Per-run robots (instead of ``params``).
        n_out: Samples per run (at ``linspace(0, t_end, n_out)``).
        rtol, atol, method, stabilisation: As :func:`~robotdyn.simulation.engine.simulate` (compiled methods).
        threads: Worker threads (default: one per CPU).
        progress: Print the runs done to stderr (about once a second).
        models: Per-run model vectors (instead of ``params`` or ``robots``).
        time_limit: Wall-clock limit of each run [s] (None: none): a run past it is flagged failed with a message
            saying so (the others go on).

    Returns:
        The :class:`ManyRuns` (failed runs are flagged with their message, never raised; Ctrl-C keeps the finished
        runs, ``stats["partial"]`` says so).
    """
    import robotdyn

    from .compiled_engine import METHODS, native_profile, rechooser
    from .model_variants import model_vector, physical, structure, variant
    from .engine import MAX_SAMPLES
    from .torque_profile import TorqueProfile, as_profile

    if isinstance(robot, str):
        robot = robotdyn.load(robot)
    if not (np.isfinite(t_end) and t_end > 0):
        raise RobotDynError(f"t_end = {t_end} s; expected a positive duration")
    if method not in METHODS:
        raise RobotDynError(f"method {method!r}; expected one of {', '.join(METHODS)}")
    q0 = robot.neutral() if q0 is None else q0
    nu0 = np.zeros(robot.mobility) if nu0 is None else nu0
    Q0, N = _per_run(q0, None, robot.nq, "q0", robot.coordinates)
    NU0, N = _per_run(nu0, N, robot.mobility, "nu0", robot.velocity_names)
    if torque is not None and not isinstance(torque, TorqueProfile):
        torque = list(torque)
        if N is not None and len(torque) != N:
            raise RobotDynError(f"{len(torque)} torque profiles for {N} runs; expected one per run or one for all")
        N = len(torque)
    if sum((bool(params), robots is not None, models is not None)) > 1:
        raise RobotDynError("give per-run params, robots or models, not more than one of them")
    if time_limit is not None and not (np.isfinite(time_limit) and time_limit > 0):
        raise RobotDynError(f"time_limit = {time_limit} s; expected a positive wall-clock duration or None")
    if models is not None:
        models = np.asarray(models, float)
        width = model_vector(robot).size
        if models.ndim != 2 or models.shape[1] != width or (N is not None and models.shape[0] != N):
            raise RobotDynError(f"models has shape {models.shape}; expected ({N if N is not None else 'N'}, {width}) "
                                "(one model vector of the robot's layout per run)")
        if not np.all(np.isfinite(models)):
            raise RobotDynError("models must be finite (found NaN or inf)")
        N = models.shape[0]
    if params:
        values = {}
        for k, v in params.items():
            p = robot.spec.parameter(k)  # an unknown name: one line listing the known ones
            if p.choices is not None:
                raise InputError(f"parameter {k} is a choice ({', '.join(p.choices)}); only numbers can vary per run")
            try:
                values[k] = np.atleast_1d(np.asarray(v, float))
            except (TypeError, ValueError):
                raise InputError(f"parameter {k}: expected numbers per run [{p.unit}]") from None
        lengths = {len(v) for v in values.values()}
        if len(lengths) != 1 or (N is not None and lengths != {N}):
            raise RobotDynError(f"per-run parameters of lengths {sorted(lengths)} for {N} runs; expected one length")
        N = lengths.pop()
    if robots is not None:
        robots = list(robots)
        if N is not None and len(robots) != N:
            raise RobotDynError(f"{len(robots)} robots for {N} runs; expected one per run")
        N = len(robots)
    N = 1 if N is None else N
    Q0 = np.ascontiguousarray(np.broadcast_to(Q0, (N, robot.nq)), float)
    NU0 = np.ascontiguousarray(np.broadcast_to(NU0, (N, robot.mobility)), float)
    if not (np.all(np.isfinite(Q0)) and np.all(np.isfinite(NU0))):
        raise RobotDynError("q0 and nu0 must be finite (found NaN or inf)")
    if not 2 <= n_out <= MAX_SAMPLES // max(N, 1):
        raise RobotDynError(f"{n_out} samples per run for {N} runs; expected 2 to {MAX_SAMPLES // max(N, 1)}")
    profiles = torque if isinstance(torque, list) else [torque] * N
    natives, cache = [], {}
    for p in profiles:
        if id(p) not in cache:
            cache[id(p)] = native_profile(as_profile(p, len(robot.motors)) if p is None or
                                          isinstance(p, TorqueProfile) else _refuse_callable(p))
        natives.append(cache[id(p)])
    breaks = [[float(b) for b in (p.breakpoints() if p is not None else []) if 0.0 < b < t_end] for p in profiles]

    fast = compiled_model(robot)
    if fast is None:
        from ..fast.compiled import why_not

        raise RobotDynError(f"simulate_many needs the compiled model: {why_not(robot)}")
    if getattr(robot, "springs", None):  # (its runs carry no damper work: simulate runs them, compiled, one by one)
        from ..reduction.joint_springs import urdf_damping_hint

        raise RobotDynError("simulate_many does not run robots with joint springs or dampers; expected "
                            "robotdyn.simulation.simulate per run" + urdf_damping_hint(robot.springs))
    if fast.ev.slipping or fast.slip_refusal is not None:  # (refused: slipping wheels whose friction is not
        raise RobotDynError("simulate_many does not run robots with slipping wheels (their friction and lift-off "
                            "are on robotdyn.simulation.simulate); expected wheels that roll without slipping")
    robot.reduced(Q0[0], NU0[0])  # the projection's rows (the Python path chooses them)
    variants: dict[int, object] = {}
    if models is None and params:
        names = list(values)
        box = {n: tuple(bounds[n]) if bounds and n in bounds else (float(values[n].min()), float(values[n].max()))
               for n in names}
        points = np.column_stack([values[n] for n in names])
        models = _parameter_model(robot, box, points).vectors(points)
    elif models is None and robots is not None:
        base = structure(robot)
        rows = []
        for i, r in enumerate(robots):
            if structure(r) != base:
                raise RobotDynError(f"robots[{i}] differs from robot in its joints, frames, constraints or terrain; "
                                    "expected variants of one description")
            rows.append(model_vector(r))
        models = np.array(rows)
    models = np.ascontiguousarray(np.zeros((0, 0)) if models is None else models, float)
    refused = physical(models, robot) if models.size else [""] * N
    run = np.array([not r for r in refused])  # the runs whose model is physical

    def rechoose(i, q, nu):  # the Python path's rows for run i at (q, nu), on that run's model
        if i not in variants:
            variants[i] = variant(robot, models[i]) if models.size else robot
        return rechooser(variants[i])(q, nu)

    samples = np.linspace(0.0, t_end, n_out)
    threads = (os.cpu_count() or 1) if threads is None else int(threads)
    if threads < 1:
        raise RobotDynError(f"threads = {threads}; expected at least 1")
    report = _Report(N) if progress else None
    start = time.perf_counter()
    idx = np.flatnonzero(run)
    sub = idx.tolist()
    out = fast.ev.simulate_many(Q0[idx], NU0[idx], models[idx] if models.size else models, [natives[i] for i in sub],
                                [breaks[i] for i in sub], float(t_end), samples, rtol, atol, stabilisation, method,
                                threads, report, lambda i, q, nu: rechoose(sub[i], q, nu),
                                float(time_limit) if time_limit is not None else 0.0)
    wall = time.perf_counter() - start
    if len(idx) < N:  # the refused runs: no samples, their reason
        full = {"y": np.zeros((N,) + out["y"].shape[1:]), "energy": np.zeros((N, n_out)),
                "residual": np.zeros((N, n_out)), "emitted": np.zeros(N, int), "nfev": np.zeros(N, int),
                "status": np.full(N, 3), "messages": list(refused), "walls": np.zeros(N)}
        for key in ("y", "energy", "residual", "emitted", "nfev", "status", "walls"):
            full[key][idx] = out[key]
        for j, i in enumerate(sub):
            full["messages"][i] = out["messages"][j]
        out = {**out, **full}
    emitted = out["emitted"]
    Y = out["y"]
    for i in np.flatnonzero(emitted < n_out):
        Y[i, emitted[i]:] = np.nan
        out["energy"][i, emitted[i]:] = np.nan
        out["residual"][i, emitted[i]:] = np.nan
    status = out["status"]
    labels = [lab for lab, h in zip(fast.labels, fast.holonomic)]
    messages = [m if st != 0 else "" for m, st in zip(out["messages"], status)]
    messages = [_named_rows(m, labels) for m in messages]
    messages = [m or ("not run (interrupted)" if st == -1 else "") for m, st in zip(messages, status)]
    stats = {"wall": wall, "threads": threads, "method": method, "runs_per_s": N / wall if wall else float("inf"),
             "engine": f"compiled ({method})"}
    if out["interrupted"]:
        stats["partial"] = f"interrupted: {int(np.sum(status == 0))} of {N} runs finished"
    n = robot.nq
    return ManyRuns(samples, Y[:, :, :n], Y[:, :, n:], out["energy"], out["residual"], status == 0, emitted,
                    messages, out["nfev"], list(robot.coordinates), list(robot.velocity_names),
                    models if models.size else None, out["walls"], stats)


def _refuse_callable(p):
    raise RobotDynError(f"torque {p!r} is a Python function; simulate_many takes robotdyn.simulation.torque_profile "
                        "profiles (constant, sine, table, sums)")


def _named_rows(message: str, labels: list[str]) -> str:
    """The C++ side's 'holonomic row #r' with the row's label."""
    import re

    return re.sub(r"holonomic row #(\d+)", lambda m: f"constraint {labels[int(m.group(1))]}", message)


_FITS: dict = {}
_FITS_LOCK = threading.Lock()


def _parameter_model(robot, box: dict, points: np.ndarray):
    """The :class:`~robotdyn.simulation.model_variants.ParameterModel` of ``robot`` over ``box`` (cached per robot, box and
    other parameter values: a sweep in chunks fits once)."""
    from .model_variants import ParameterModel

    from .model_variants import model_vector

    # keyed by what the fit depends on, not by object: robots unpickled in a worker share one fit
    key = (robot.spec.name, tuple(sorted((k, tuple(v)) for k, v in box.items())),
           tuple(sorted((k, str(v)) for k, v in robot.params.items())), repr(robot.terrain),
           model_vector(robot).tobytes())
    with _FITS_LOCK:
        fit = _FITS.get(key)
        if fit is None:
            fit = _FITS[key] = ParameterModel(robot, box, points=points[:200])
            while len(_FITS) > 16:
                _FITS.pop(next(iter(_FITS)))
    return fit


class _Report:
    """Runs done, on stderr, at most once a second."""

    def __init__(self, total: int) -> None:
        self.total, self.last = total, time.perf_counter()

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        if now - self.last >= 1.0:
            self.last = now
            import sys

            print(f"simulate_many: {done} / {total} runs", file=sys.stderr, flush=True)


__all__ = ["ManyRuns", "simulate_many"]

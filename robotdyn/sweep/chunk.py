"""One chunk of a sweep's runs, computed where it is sent (a Dask worker, or this process): :func:`run_chunk`.

Runs that come with a model vector are simulated together as variants of one compiled model
(:mod:`robotdyn.sweep.batched`). Every other run builds its robot afresh (parameters, terrain), takes its scenario's
initial state and torque law (times the run's torque scale) and integrates them with
:func:`robotdyn.simulation.engine.simulate`. Each run gives one summary row (and optionally the trajectory). A
run that raises, or whose numbers are not finite, gives an error row naming why; the other runs of the chunk go on.
Nothing depends on which process computes a run or what it computed before, so a run's numbers are the same bits
on one worker, on two, or in this process.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import RobotDynError
from ..simulation.scenario import Scenario
from .spec import RunInput
from ..simulation.torque_profile import TorqueProfile


@dataclass(frozen=True)
class RunContext:
    """What every run of a sweep shares, sent with each chunk.

    Attributes:
        source: ``{"robot": name}`` or ``{"constraints": path, "urdf": path | None, "xacro_args": {...},
            "digest": sha256 of the file}`` (workers read the file by its path: on a cluster, a shared one).
        fixed: Parameter values held for every run (name -> value text).
        terrains: Terrain definitions by label: ``("named", name)`` (the robot module's ``TERRAINS``) or
            ``("kind", kind, {arg: value})`` (:data:`robotdyn.interfaces.constraint_file.TERRAINS`).
        t_end, n_out: Duration [s] and output samples (``None``: the scenario's).
        tolerances: The integrator's options ``rtol``/``atol``/``method``, passed to
            :func:`~robotdyn.simulation.engine.simulate` (absent: the scenario's own choice).
        columns: Columns whose maximum and minimum are summarised.
        trajectories: Also return each run's trajectory.
        compiled: Whether the compiled fast path is on (as in the process that planned the sweep).
        time_limit: Wall-clock limit [s] of one run (``None``: none), ``simulate(..., time_limit=...)`` (not in
            scenarios that build their own torque law): a run that crawls (a stiff or blown-up state) becomes an
            error row instead of stalling the sweep.
    """

    source: dict
    fixed: dict = field(default_factory=dict)
    terrains: dict = field(default_factory=dict)
    t_end: float | None = None
    n_out: int | None = None
    tolerances: dict = field(default_factory=dict)
    columns: tuple[str, ...] = ()
    trajectories: bool = False
    compiled: bool = True
    time_limit: float | None = None


@functools.lru_cache(maxsize=8)
def _load(source_key: tuple):
    """The robot module or constraint file of a source (cached per process; a constraint file's source holds
    the digest of its bytes, so an edited file is read again)."""
    source = dict(source_key)
    if "robot" in source:
        from ..robots import module

        return module(source["robot"])
    from ..interfaces.constraint_file import read

    return read(source["constraints"], source.get("urdf"), dict(source.get("xacro_args") or ()))


def load_source(source: dict):
    """The module-like object (``SPEC``, ``SCENARIOS``, optionally ``TERRAINS``) of a sweep's robot.

    Args:
        source: The :attr:`RunContext.source`.

    Returns:
        The robot module, or the :class:`~robotdyn.interfaces.constraint_file.ConstraintFile`.
    """
    key = tuple(sorted((k, tuple(sorted(v.items())) if isinstance(v, dict) else v) for k, v in source.items()))
    return _load(key)


def build_terrain(mod, definition: tuple):
    """A terrain from its definition (see :class:`RunContext`).

    Args:
        mod: The robot's module-like object (``SPEC``, ``SCENARIOS``, optionally ``TERRAINS``; a robot module or a
            :class:`~robotdyn.interfaces.constraint_file.ConstraintFile`).
        definition: ``("named", name)`` or ``("kind", kind, {arg: value})``.

    Returns:
        The terrain object.
    """
    if definition[0] == "named":
        return mod.TERRAINS[definition[1]]()
    from ..interfaces.constraint_file import TERRAINS

    return TERRAINS[definition[1]](**definition[2])


def overrides_run(scenario) -> bool:
    """Whether a scenario builds its own torque law in its ``run`` (a controller, feed-forward torques): then
    its torques cannot be scaled from outside.

    Args:
        scenario: The :class:`~robotdyn.simulation.scenario.Scenario`.

    Returns:
        ``True`` if the scenario's class overrides :meth:`~robotdyn.simulation.scenario.Scenario.run`.
    """
    return type(scenario).run is not Scenario.run


def prepare(ctx: RunContext, run: RunInput):
    """The robot, scenario (a copy, on the run's terrain), duration and sample count of one run.

    Args:
        ctx: The sweep's :class:`~robotdyn.sweep.chunk.RunContext`.
        run: The :class:`~robotdyn.sweep.spec.RunInput`.

    Returns:
        ``(robot, scenario, t_end, n_out)``: the :class:`~robotdyn.robot.Robot`, the scenario copy, the duration [s] and
        the number of output samples.
    """
    mod = load_source(ctx.source)
    params = {**ctx.fixed, **{k: v for k, v in run.params if k != "torque_scale"}}
    terrain = build_terrain(mod, ctx.terrains[run.terrain]) if run.terrain is not None else None
    robot = build_robot(mod, params, terrain)
    scenario = scenario_of(ctx, mod, run)
    t_end, n_out = scenario.span(ctx.t_end, ctx.n_out)
    return robot, scenario, t_end, n_out


def scenario_of(ctx: RunContext, mod, run: RunInput):
    """A copy of the run's scenario, on the run's terrain (a scenario that picks its terrain by name gets it).

    Args:
        ctx: The sweep's :class:`~robotdyn.sweep.chunk.RunContext`.
        mod: The robot's module-like object (``SPEC``, ``SCENARIOS``, optionally ``TERRAINS``; a robot module or a
            :class:`~robotdyn.interfaces.constraint_file.ConstraintFile`).
        run: The :class:`~robotdyn.sweep.spec.RunInput`.

    Returns:
        The scenario copy.
    """
    scenario = copy.copy(mod.SCENARIOS[run.scenario])
    if run.terrain is not None and dataclasses.is_dataclass(scenario) and hasattr(scenario, "terrain"):
        scenario = dataclasses.replace(scenario, terrain=ctx.terrains[run.terrain][1])
    return scenario


def build_robot(mod, params: dict, terrain):
    """A robot module's robot, or a constraint file's (which also checks its scenarios against the robot).

    Args:
        mod: The robot's module-like object (``SPEC``, ``SCENARIOS``, optionally ``TERRAINS``; a robot module or a
            :class:`~robotdyn.interfaces.constraint_file.ConstraintFile`).
        params: Parameter values by name.
        terrain: A :class:`~robotdyn.constraints.terrain.Terrain` (``None``: the robot's own).

    Returns:
        The :class:`~robotdyn.robot.Robot`.
    """
    from ..interfaces.constraint_file import ConstraintFile
    from ..robot import Robot

    return mod.robot(params, terrain) if isinstance(mod, ConstraintFile) else Robot(mod.SPEC, params, terrain)


def scaled_torque(torque, scale: float):
    """The torques times the run's scale: a profile stays a profile (the compiled engine runs it).

    Args:
        torque: The scenario's torques (``None``, a profile, or a callable ``tau(t, q, nu)``).
        scale: The run's torque scale (dimensionless).

    Returns:
        ``torque`` itself when it is ``None`` or ``scale`` is 1; else a scaled profile for a profile, or a callable
        ``tau(t, q, nu)`` returning the scaled torques.
    """
    if torque is None or scale == 1.0:
        return torque
    if isinstance(torque, TorqueProfile):
        return torque.scaled(scale)
    return lambda t, q, nu: scale * np.asarray(torque(t, q, nu), float)


SCENARIO_LAW = "the scenario's own torque law"
"""The torque law a :func:`simulate_run` reports for scenarios that build theirs inside their ``run``."""


def simulate_run(ctx: RunContext, run: RunInput):
    """Simulate one run: (robot, trajectory, torque law: a function, ``None`` without torques, or
    :data:`SCENARIO_LAW` when the scenario builds its own).

    Args:
        ctx: The sweep's :class:`~robotdyn.sweep.chunk.RunContext`.
        run: The :class:`~robotdyn.sweep.spec.RunInput`.

    Returns:
        ``(robot, trajectory, law)``: the :class:`~robotdyn.robot.Robot`, the
        :class:`~robotdyn.simulation.trajectory.Trajectory` and the torque law as above.
    """
    from ..simulation.engine import simulate

    robot, scenario, t_end, n_out = prepare(ctx, run)
    if overrides_run(scenario):
        traj = scenario.run(robot, t_end=t_end, n_out=n_out, progress=False, **ctx.tolerances)
        return robot, traj, SCENARIO_LAW
    q0, nu0 = scenario.initial_state(robot)  # may set the scenario's torque law (it is a copy)
    torque = scaled_torque(scenario.torque, run.torque_scale)
    traj = simulate(robot, t_end, q0, nu0, torque, n_out=n_out, progress=False, time_limit=ctx.time_limit,
                    **ctx.tolerances)
    return robot, traj, torque


def energy_drift(traj, torque) -> float | None:
    """Largest :math:`|E(t) - E(t_0)|` [J] over the output samples from the first one after which the motor
    torques are zero at every sample (the whole run without torques), with the friction work of slipping wheels
    and the work of dampers added back; ``None`` when the torques never stop or are built by the scenario itself.

    Args:
        traj: The run's :class:`~robotdyn.simulation.trajectory.Trajectory`.
        torque: Its torque law (``None``: none; :data:`SCENARIO_LAW`: built by the scenario).

    Returns:
        The drift [J], or ``None`` where it is not defined.
    """
    if torque is SCENARIO_LAW:
        return None
    if torque is None:
        start = 0
    else:
        if isinstance(torque, TorqueProfile):  # a function of time alone: all samples at once
            active = np.any(torque.at(traj.t) != 0.0, axis=1).tolist()
        else:
            active = [bool(np.any(np.asarray(torque(t, q, nu), float) != 0.0))
                      for t, q, nu in zip(traj.t, traj.q, traj.nu)]
        if active[-1]:
            return None
        start = len(active) - int(np.argmax(active[::-1])) if any(active) else 0
    if start >= len(traj.t) - 1:
        return None
    e = traj.energy[start:] - (traj.friction_work[start:] if traj.friction_work is not None else 0.0)
    damper = getattr(traj, "damper_work", None)  # joint dampers and compliant contacts' damping
    if damper is not None:
        e = e - damper[start:]
    impacts = getattr(traj, "impact_loss", None)  # touch-downs of rolling compliant wheels
    if impacts is not None:
        e = e + impacts[start:]
    return float(np.max(np.abs(e - e[0])))


def summary(mod, robot, traj, torque, columns) -> dict:
    """The summary outputs of one run (see :mod:`robotdyn.sweep.runner`).

    Args:
        mod: The robot's module-like object (``SPEC``, ``SCENARIOS``, optionally ``TERRAINS``; a robot module or a
            :class:`~robotdyn.interfaces.constraint_file.ConstraintFile`).
        robot: The :class:`~robotdyn.robot.Robot`.
        traj: The run's :class:`~robotdyn.simulation.trajectory.Trajectory`.
        torque: Its torque law (as :func:`energy_drift`).
        columns: Columns whose maximum and minimum are kept.

    Returns:
        The summary row: a dict of output column name to value.
    """
    names = traj.coordinates + traj.velocity_names
    data = np.column_stack([traj.q, traj.nu])
    row = {f"final.{c}": float(x) for c, x in zip(names, data[-1])}
    for c in columns:
        col = data[:, names.index(c)]
        row[f"max.{c}"], row[f"min.{c}"] = float(col.max()), float(col.min())
    row["t_reached"] = float(traj.t[-1])
    row["energy.start"], row["energy.end"] = float(traj.energy[0]), float(traj.energy[-1])
    row["energy.drift"] = energy_drift(traj, torque)
    row["residual.max"] = float(np.max(traj.residual)) if traj.residual.size else 0.0
    drift = getattr(mod, "drift", None)  # a robot module's own invariant (e.g. an integrated constraint)
    if callable(drift):
        row["drift"] = float(drift(robot, traj))
    row["nfev"] = int(traj.stats.get("nfev", 0))
    row["wall"] = float(traj.stats.get("wall", np.nan))
    return row


def trajectory_columns(traj) -> dict:
    """A run's trajectory as the columns a sweep stores (t, q, nu, energy, residual).

    Args:
        traj: The run's :class:`~robotdyn.simulation.trajectory.Trajectory`.

    Returns:
        A dict of column name to a (N,) array.
    """
    return {"t": traj.t, **{c: traj.q[:, i] for i, c in enumerate(traj.coordinates)},
            **{c: traj.nu[:, i] for i, c in enumerate(traj.velocity_names)},
            "energy": traj.energy, "residual": traj.residual}


def error_message(exc: Exception) -> str:
    """The error row's message of a failed run: the first line (with the exception's type unless it is one of
    robotdyn's), at most 1000 characters.

    Args:
        exc: The exception that ended the run.

    Returns:
        The message (at most 1000 characters).
    """
    message = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    if not isinstance(exc, RobotDynError):
        message = f"{type(exc).__name__}: {message}"
    return message[:1000]


def finished_row(ctx: RunContext, run: RunInput, robot, traj, torque) -> tuple[dict, dict | None]:
    """The row (``ok``, or ``stopped`` where an event ended the run) and trajectory columns (``None`` unless
    ``ctx.trajectories``) of a simulated run, whichever engine ran it; an error row where a summarised number is
    not finite or the summary fails. ``run_wall`` is the caller's to add.

    Args:
        ctx: The sweep's :class:`~robotdyn.sweep.chunk.RunContext`.
        run: The :class:`~robotdyn.sweep.spec.RunInput`.
        robot: The :class:`~robotdyn.robot.Robot`.
        traj: The run's :class:`~robotdyn.simulation.trajectory.Trajectory`.
        torque: Its torque law (as :func:`energy_drift`).

    Returns:
        ``(row, columns)``: the summary row dict, and the trajectory columns or ``None``.
    """
    try:
        row = {"run_id": run.run_id, "status": "ok", "error": None,
               **summary(load_source(ctx.source), robot, traj, torque, ctx.columns)}
        bad = [k for k, v in row.items() if isinstance(v, float) and not np.isfinite(v) and k != "wall"]
        if bad:
            raise RobotDynError(f"non-finite result ({', '.join(bad[:3])}): the dynamics blew up")
    except Exception as exc:  # one failed run is an error row, never the end of the sweep
        return {"run_id": run.run_id, "status": "error", "error": error_message(exc)}, None
    if "event" in traj.stats:  # e.g. a slipping wheel lifting off: the run ends there by the model's rules
        row["status"], row["error"] = "stopped", str(traj.stats["event"])
    return row, trajectory_columns(traj) if ctx.trajectories else None


def _one(ctx: RunContext, run: RunInput) -> tuple[dict, dict | None]:
    start = time.perf_counter()
    try:
        robot, traj, torque = simulate_run(ctx, run)
        if "partial" in traj.stats:  # simulate() kept what it had when interrupted: the sweep stops, not the run
            raise KeyboardInterrupt
        row, traj_out = finished_row(ctx, run, robot, traj, torque)
    except Exception as exc:  # one failed run is an error row, never the end of the sweep
        row, traj_out = {"run_id": run.run_id, "status": "error", "error": error_message(exc)}, None
    row["run_wall"] = time.perf_counter() - start
    return row, traj_out


def run_chunk(ctx: RunContext, runs: list[RunInput], vectors: dict | None = None) -> list[tuple[dict, dict | None]]:
    """Compute a chunk of runs: for each, its summary row (``status`` ok, stopped or error, with the message) and
    its trajectory columns (``None`` unless ``ctx.trajectories``). Runs with a model vector in ``vectors`` (run id
    -> vector, :func:`robotdyn.sweep.batched.model_vectors`) are simulated together as variants of one compiled
    model (:func:`robotdyn.sweep.batched.run_batched`), the others one after the other, each built afresh.

    Args:
        ctx: The sweep's :class:`~robotdyn.sweep.chunk.RunContext`.
        runs: The runs (:class:`~robotdyn.sweep.spec.RunInput`), in order.
        vectors: Model vectors by run id (default ``None``: every run built afresh).

    Returns:
        One ``(row, trajectory columns or None)`` pair per run, in run order.
    """
    from ..fast.dispatch import use_compiled

    vectors = vectors or {}
    batched = [i for i, r in enumerate(runs) if r.run_id in vectors]
    out: list = [None] * len(runs)
    with use_compiled(ctx.compiled), np.errstate(all="ignore"):
        if batched:
            from .batched import run_batched

            try:
                results = run_batched(ctx, [runs[i] for i in batched], [vectors[runs[i].run_id] for i in batched])
            except (KeyboardInterrupt, MemoryError):
                raise
            except Exception as exc:  # the batch itself failed (not one run): each of its runs says why
                message = error_message(exc)
                results = [({"run_id": runs[i].run_id, "status": "error", "error": message, "run_wall": 0.0}, None)
                           for i in batched]
            for i, result in zip(batched, results):
                out[i] = result
        for i, run in enumerate(runs):
            if out[i] is None:
                out[i] = _one(ctx, run)
    return out


__all__ = ["RunContext", "run_chunk", "simulate_run", "prepare", "load_source", "energy_drift", "overrides_run",
           "trajectory_columns", "error_message", "scenario_of", "build_robot", "scaled_torque", "build_terrain",
           "finished_row"]

"""A sweep's runs as variants of one compiled model: :func:`model_vectors` (planned once) and :func:`run_batched`.

Most sweeps vary numbers of the model -- masses, inertias, lengths, radii -- and the torque scale. Building each
run's robot (Xacro, URDF, Pinocchio model, compiled model) costs some 30 ms, ten times a short run's integration.
Instead, before any run is sent out, :func:`model_vectors` fits one
:class:`~robotdyn.simulation.model_variants.ParameterModel` over the whole sweep (its box: the smallest and largest
value of each varied parameter over all runs; its probes: the runs' own points) and gives every run its model vector;
a chunk then simulates its runs in one :func:`~robotdyn.simulation.many_runs.simulate_many` call on one base robot
(:func:`run_batched`). The vectors travel with the chunks, so a run's numbers do not depend on the chunk that holds
it, on the worker, on the number of workers or on an interruption and resumption: they are the numbers of
``simulate(variant(base, vector), ...)`` alone (bit for bit), and differ from a robot built from the run's
parameters only by the fit (verified to 1e-11 relative at the probes).

Runs that cannot go this way are built one at a time (:func:`robotdyn.sweep.chunk.run_chunk`), and the plan says
why: the compiled fast path off or unavailable for the robot, slipping wheels, a scenario that builds its own torque
law or whose torques are a Python function, a varied parameter that is a choice or that enters the model other than
polynomially (e.g. a ratio inside the coupling law).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ..errors import RobotDynError
from .chunk import (RunContext, build_robot, build_terrain, error_message, finished_row, load_source, overrides_run,
                    scaled_torque, scenario_of)
from .spec import RunInput
from ..reduction.pull_back import STABILISATION, start_offsets
from ..simulation.engine import simulate
from ..simulation.many_runs import simulate_many
from ..simulation.trajectory import Trajectory


@dataclasses.dataclass
class Batching:
    """Which runs of a sweep are simulated as model variants.

    Attributes:
        vectors: run id -> model vector (the runs that are batched).
        reasons: Why the other runs are built one at a time (one line per cause, empty when all are batched).
    """

    vectors: dict[str, np.ndarray]
    reasons: list[str]

    def __repr__(self) -> str:
        return f"Batching(batched={len(self.vectors)}, reasons={self.reasons})"


def _params(robot, values) -> dict[str, float]:
    """Run parameter values (name, value text or number) as the robot's numbers."""
    return {k: robot.spec.parameter(k).convert(v) for k, v in values}


_BASES: dict[tuple, object] = {}


def base_robot(ctx: RunContext, terrain: str | None):
    """The robot every batched run of ``terrain`` varies (the sweep's fixed parameters, that terrain); kept per
    process, so that the chunks a worker computes share it.

    Args:
        ctx: The sweep's :class:`~robotdyn.sweep.chunk.RunContext`.
        terrain: The terrain label of the runs (``None``: the robot's own terrain).

    Returns:
        The :class:`~robotdyn.robot.Robot`.
    """
    key = (repr(sorted(ctx.source.items())), repr(sorted(ctx.fixed.items())), terrain,
           repr(ctx.terrains.get(terrain)))
    robot = _BASES.get(key)
    if robot is None:
        mod = load_source(ctx.source)
        terrain_obj = build_terrain(mod, ctx.terrains[terrain]) if terrain is not None else None
        robot = build_robot(mod, dict(ctx.fixed), terrain_obj)
        while len(_BASES) >= 8:
            _BASES.pop(next(iter(_BASES)))
        _BASES[key] = robot
    return robot


MODES = ("auto", "always", "never")
"""When a sweep simulates its runs as model variants: ``auto`` where a group (a scenario and terrain) has at least
twice as many runs as the fit builds robots (fewer runs are cheaper to build one by one), ``always`` wherever it
can, ``never`` (every run built from its parameters)."""


def fit_builds(m: int, degree: int = 3) -> int:
    """At most how many robots a :class:`~robotdyn.simulation.model_variants.ParameterModel` of ``m`` parameters
    builds: an anchor, one step per parameter, and six more probes than the monomials of total degree <= 3.

    Args:
        m: Number of varied parameters.
        degree: Total degree of the fitted polynomial.

    Returns:
        The number of robots built (an upper bound).
    """
    return 1 + m + math.comb(m + degree, degree) + 6


def model_vectors(ctx: RunContext, runs: list[RunInput], mode: str = "auto") -> Batching:
    """The model vector of every run that can be simulated as a variant of the sweep's base robot (see the module
    docstring and :data:`MODES`); the others are listed by cause in ``reasons``.

    Args:
        ctx: The sweep's :class:`~robotdyn.sweep.chunk.RunContext`.
        runs: The runs (:class:`~robotdyn.sweep.spec.RunInput`), in order.
        mode: ``auto``, ``always`` or ``never`` (:data:`MODES`).

    Returns:
        A :class:`Batching`: the model vector of every batched run by run id, and why the others are not batched.
    """
    if mode not in MODES:
        raise RobotDynError(f"batch = {mode!r}; expected one of {', '.join(MODES)}")
    if mode == "never":
        return Batching({}, ["batch = never: every run is built from its parameters"])
    from ..simulation.compiled_engine import METHODS

    method = ctx.tolerances.get("method")
    if method is not None and method not in METHODS:  # (simulate_many runs Boost.Odeint's steppers only)
        return Batching({}, [f"method = {method!r}: every run is built and simulated on its own"])
    from ..fast.compiled import why_not
    from ..fast.dispatch import compiled_model, use_compiled
    from ..simulation.model_variants import ParameterModel, model_vector
    from ..simulation.torque_profile import TorqueProfile
    from ..errors import InputError

    vectors: dict[str, np.ndarray] = {}
    reasons: list[str] = []
    if not ctx.compiled:
        return Batching(vectors, ["the compiled fast path is off: every run is built and simulated on its own"])
    mod = load_source(ctx.source)
    with use_compiled(True):
        for terrain in dict.fromkeys(r.terrain for r in runs):
            group = [r for r in runs if r.terrain == terrain]
            where = f" (terrain {terrain})" if terrain is not None else ""
            try:
                base = base_robot(ctx, terrain)
                fast = compiled_model(base)
            except RobotDynError as exc:  # each run meets it again when built alone, and says so in its row
                reasons.append(f"runs{where} built one at a time: {error_message(exc)}")
                continue
            if fast is None or fast.ev.slipping or fast.slip_refusal is not None:  # (friction not compiled: the
                # model's slipping wheels would have none, e.g. on a statically indeterminate chassis)
                reasons.append(f"runs{where} built one at a time: "
                               + ("slipping wheels" if fast is not None else why_not(base)))
                continue
            if getattr(base, "springs", None):  # (simulate_many carries no damper work: each run on the compiled
                # simulation of its own robot, robotdyn.fast.applied_model)
                reasons.append(f"runs{where} built one at a time: joint springs and dampers are simulated run by run")
                continue
            ok = []
            for name in dict.fromkeys(r.scenario for r in group):
                scenario = scenario_of(ctx, mod, next(r for r in group if r.scenario == name))
                if overrides_run(scenario):
                    reasons.append(f"scenario {name}{where}: builds its own torque law, so its runs are built one "
                                   "at a time")
                    continue
                try:
                    scenario.initial_state(base)
                except RobotDynError as exc:
                    reasons.append(f"scenario {name}{where}: built one at a time ({error_message(exc)})")
                    continue
                if scenario.torque is not None and not isinstance(scenario.torque, TorqueProfile):
                    reasons.append(f"scenario {name}{where}: its torques are a Python function, so its runs are "
                                   "built one at a time")
                    continue
                ok.append(name)
            group = [r for r in group if r.scenario in ok]
            if not group:
                continue
            names = list(dict.fromkeys(k for r in group for k, _ in r.params))
            choices = [n for n in names if base.spec.parameter(n).choices is not None]
            if choices:
                reasons.append(f"runs{where} built one at a time: parameter {', '.join(choices)} is a choice")
                continue
            if not names:
                vector = model_vector(base)
                vectors.update({r.run_id: vector for r in group})
                continue
            if mode == "auto" and len(group) < 2 * fit_builds(len(names)):
                reasons.append(f"{len(group)} runs{where} built one at a time: fewer than twice the "
                               f"{fit_builds(len(names))} robots a fit of {', '.join(names)} builds (batch = always "
                               "fits anyway)")
                continue
            points = np.array([[_params(base, r.params)[n] for n in names] for r in group])
            box = {n: (float(points[:, j].min()), float(points[:, j].max())) for j, n in enumerate(names)}
            try:
                fit = ParameterModel(base, box, points=points)
            except InputError as exc:
                reasons.append(f"runs{where} built one at a time: {exc}")
                continue
            for r, v in zip(group, fit.vectors(points)):
                vectors[r.run_id] = v
    return Batching(vectors, reasons)


def _variant(base, vector: np.ndarray, params: dict):
    """The run's robot: the base robot with the run's model vector, its ``params`` the run's values."""
    from ..simulation.model_variants import variant

    robot = variant(base, vector)
    robot.params = {**base.params, **params}
    return robot


def run_batched(ctx: RunContext, runs: list[RunInput], vectors: list[np.ndarray]) -> list[tuple[dict, dict | None]]:
    """Simulate runs as variants of the base robot (one :func:`~robotdyn.simulation.many_runs.simulate_many` call
    per scenario and terrain, on one thread: the sweep's workers are the parallelism); returns the rows and
    trajectories of :func:`robotdyn.sweep.chunk.run_chunk`, in the order of ``runs``.

    Each run's start is checked as :func:`~robotdyn.simulation.engine.simulate` checks it (the same error rows); a
    run whose start holds residuals that no coordinate can change (constant offsets,
    :func:`robotdyn.reduction.pull_back.start_offsets`) is simulated alone by ``simulate`` on its variant.

    Args:
        ctx: The sweep's :class:`~robotdyn.sweep.chunk.RunContext`.
        runs: The runs (:class:`~robotdyn.sweep.spec.RunInput`), in order.
        vectors: The model vector (L,) of each run, in the same order.

    Returns:
        One ``(row, trajectory columns or None)`` pair per run, in the order of ``runs``.
    """
    mod = load_source(ctx.source)
    out: list = [None] * len(runs)
    groups: dict[tuple, list[int]] = {}
    for i, r in enumerate(runs):
        groups.setdefault((r.terrain, r.scenario), []).append(i)
    for (terrain, name), index in groups.items():
        base = base_robot(ctx, terrain)
        t_end, n_out = scenario_of(ctx, mod, runs[index[0]]).span(ctx.t_end, ctx.n_out)
        batch = []  # (i, robot, q0, nu0, torque, prep wall)
        for i in index:
            begin = time.perf_counter()
            run = runs[i]
            try:
                robot = _variant(base, vectors[i], _params(base, run.params))
                scenario = scenario_of(ctx, mod, run)
                q0, nu0 = scenario.initial_state(robot)
                torque = scaled_torque(scenario.torque, run.torque_scale)
                q0, nu0 = robot.check_q(q0), robot.check_nu(nu0)
                rows = robot.rows_at(q0)
                robot.check_constraints(q0, rows=rows)
                if start_offsets(robot, q0, STABILISATION, rows):  # simulate keeps them as constant offsets
                    traj = simulate(robot, t_end, q0, nu0, torque, n_out=n_out, progress=False,
                                    time_limit=ctx.time_limit, **ctx.tolerances)
                    if "partial" in traj.stats:  # interrupted (as run_chunk's per-run path): the sweep stops
                        raise KeyboardInterrupt
                    out[i] = _result(ctx, run, robot, traj, torque, time.perf_counter() - begin)
                    continue
            except Exception as exc:  # an error row, as the run built alone gives
                out[i] = ({"run_id": run.run_id, "status": "error", "error": error_message(exc),
                           "run_wall": time.perf_counter() - begin}, None)
                continue
            batch.append((i, robot, q0, nu0, torque, time.perf_counter() - begin))
        if not batch:
            continue
        many = simulate_many(base, t_end, np.array([b[2] for b in batch]), np.array([b[3] for b in batch]),
                             [b[4] for b in batch], models=np.array([vectors[b[0]] for b in batch]), n_out=n_out,
                             threads=1, time_limit=ctx.time_limit, **ctx.tolerances)
        if "partial" in many.stats:
            raise KeyboardInterrupt
        for pos, (i, robot, _, _, torque, prep) in enumerate(batch):
            run = runs[i]
            if not many.ok[pos]:
                out[i] = ({"run_id": run.run_id, "status": "error", "error": many.messages[pos][:1000],
                           "run_wall": prep + float(many.walls[pos])}, None)
                continue
            traj = Trajectory(many.t, many.q[pos], many.nu[pos], many.energy[pos], many.residual[pos],
                              many.coordinates, many.velocity_names,
                              {"nfev": int(many.nfev[pos]), "wall": float(many.walls[pos])}, base.units, None,
                              robot, torque)
            out[i] = _result(ctx, run, robot, traj, torque, prep + float(many.walls[pos]))
    return out


def _result(ctx: RunContext, run: RunInput, robot, traj, torque, wall: float) -> tuple[dict, dict | None]:
    """:func:`robotdyn.sweep.chunk.finished_row` with ``run_wall``: ``wall`` [s] plus the summary's own time."""
    begin = time.perf_counter()
    row, traj_out = finished_row(ctx, run, robot, traj, torque)
    row["run_wall"] = wall + time.perf_counter() - begin
    return row, traj_out


__all__ = ["Batching", "model_vectors", "run_batched", "base_robot"]

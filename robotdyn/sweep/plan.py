"""A sweep checked against its robot: the runs it makes, what they share, and the columns of their results.

:func:`plan` builds the robot once (with the fixed parameters), checks every name and value of the
:class:`~robotdyn.sweep.spec.SweepSpec` against it (parameters and their units, scenarios, terrains, columns,
durations, tolerances) and lists the runs in order: every parameter point (grid or sample), then every scenario,
then every terrain. Each run's id hashes everything its result depends on: the robot (its name, or the bytes of
its constraint file and description), the expanded description at the fixed parameters (the URDF text: the
content of every file the description includes, so a changed Xacro include is a new run), robotdyn's version, the
fixed and varied parameters, scenario, terrain, torque scale, duration, samples, tolerances, summarised columns,
whether trajectories are kept and whether the compiled fast path is on.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError, RobotDynError
from .chunk import RunContext, build_robot, build_terrain, load_source, overrides_run
from .spec import (MAX_RUNS, RESERVED, TORQUE_SCALE, Axis, RunInput, SweepSpec, SweepSpecError, points,
                         resolve_axis, run_id)

OUTPUT_UNITS = {"t_reached": "s", "energy.start": "J", "energy.end": "J", "energy.drift": "J",
                "residual.max": "m, rad", "drift": "", "nfev": "", "wall": "s", "run_wall": "s"}


@dataclass
class Plan:
    """A checked sweep: the runs, their shared :class:`~robotdyn.sweep.chunk.RunContext`, the resolved axes,
    the results' pyarrow schema, units by column and each scenario's (duration, samples).

    Attributes:
        spec: The :class:`~robotdyn.sweep.spec.SweepSpec`.
        robot: The robot's name.
        context: The :class:`~robotdyn.sweep.chunk.RunContext` every run shares.
        axes: The resolved axes (plain values in the parameters' units).
        runs: The runs (:class:`~robotdyn.sweep.spec.RunInput`), in order.
        schema: The results' pyarrow schema.
        units: Unit of each result column by name.
        spans: (duration [s], samples) of each scenario by name.
    """

    spec: SweepSpec
    robot: str
    context: RunContext
    axes: list[Axis]
    runs: list[RunInput]
    schema: object
    units: dict[str, str]
    spans: dict[str, tuple[float, int]]

    def __repr__(self) -> str:
        return f"Plan({self.robot!r}, runs={len(self.runs)}, axes={[a.name for a in self.axes]})"

    def inputs(self, run: RunInput) -> dict:
        """The input columns of a run's row.

        Args:
            run: The :class:`~robotdyn.sweep.spec.RunInput`.

        Returns:
            A dict of input column name to value.
        """
        return {"run_id": run.run_id, "run_index": run.index, "robot": self.robot, "scenario": run.scenario,
                "terrain": run.terrain, "torque_scale": run.torque_scale, "t_end": self.spans[run.scenario][0],
                **{k: v for k, v in run.params if k != TORQUE_SCALE}}


def _digest(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _source(spec: SweepSpec) -> tuple[dict, dict]:
    """The robot's source (what workers load) and its identity (what run ids hash)."""
    if spec.urdf is not None and spec.constraints is None and spec.robot is None:
        raise SweepSpecError(f"urdf = {spec.urdf!r} (--urdf) needs constraints = FILE (--constraints): the wheels, "
                             "closures and motors of the robot")
    if (spec.robot is None) == (spec.constraints is None):
        raise SweepSpecError("give either a robot name (robot = ...) or a constraint file (constraints = ...), "
                             "exactly one")
    if spec.robot is not None:
        if spec.urdf is not None:
            raise SweepSpecError("urdf = ... goes with constraints = FILE, not with a registered robot")
        if spec.xacro_args:
            raise SweepSpecError(f"xacro argument {next(iter(spec.xacro_args))!r} (--xacro-arg, xacro_args) is for "
                                 "your own robot's description (constraints = FILE); a built-in robot's numbers are "
                                 "its parameters: --param NAME=VALUE or --vary NAME=...")
        return {"robot": spec.robot}, {"robot": spec.robot}
    from ..input_files import resolved

    try:
        path = resolved(spec.constraints, "constraints")
    except InputError as exc:
        raise SweepSpecError(str(exc)) from None
    if not path.is_file():
        raise SweepSpecError(f"constraint file {spec.constraints!r} not found")
    source = {"constraints": str(path), "urdf": spec.urdf, "xacro_args": dict(spec.xacro_args),
              "digest": _digest(path)}
    description = load_source(source).SPEC.xacro
    return source, {"constraints": source["digest"], "description": _digest(description),
                    "xacro_args": dict(spec.xacro_args)}


def _terrain(mod, item, scenarios) -> tuple[str, tuple]:
    """(label, definition) of one terrain of the spec: a name of the robot module's ``TERRAINS``, a kind of
    :data:`robotdyn.interfaces.constraint_file.TERRAINS` (``ramp:slope=0.1,heading=0`` or ``{kind = "ramp", ...}``)."""
    from ..interfaces.constraint_file import TERRAINS as KINDS

    named = getattr(mod, "TERRAINS", {})
    if isinstance(item, str) and item in named:
        return item, ("named", item)
    if isinstance(item, str):
        kind, _, rest = item.partition(":")
        args = {}
        for part in filter(None, (s.strip() for s in rest.split(","))):
            key, eq, value = part.partition("=")
            if not eq:
                raise SweepSpecError(f"terrain {item!r}: {part!r} is not ARG=VALUE")
            args[key.strip()] = value.strip()
    else:
        args = dict(item)
        kind = args.pop("kind", "flat")
    if kind not in KINDS:
        names = [*named, *(k + (":ARG=VALUE,..." if k != "flat" else "") for k in KINDS if k not in named)]
        raise SweepSpecError(f"unknown terrain {item!r}; expected one of {', '.join(names)}")
    try:
        values = {k: float(v) for k, v in args.items()}
    except (TypeError, ValueError):
        raise SweepSpecError(f"terrain {item!r}: arguments must be numbers") from None
    from ..interfaces.constraint_schema import terrain_problem

    problem = terrain_problem({"kind": kind, **values})  # the constraint file's ranges: finite, widths > 0, ...
    if problem is not None:
        raise SweepSpecError(f"terrain {item!r}: {problem}")
    label = kind + ("(" + ", ".join(f"{k}={v!r}" for k, v in values.items()) + ")" if values else "")
    definition = ("kind", kind, values)
    try:
        build_terrain(mod, definition)
    except TypeError as exc:
        raise SweepSpecError(f"terrain {item!r}: {exc}") from None
    for name in scenarios:
        if hasattr(mod.SCENARIOS[name], "terrain"):
            raise SweepSpecError(f"scenario {name!r} picks its terrain by name; expected one of "
                                 f"{', '.join(named) or '(none)'}")
    return label, definition


def plan(spec: SweepSpec) -> Plan:
    """Check ``spec`` against its robot and list its runs (see the module docstring).

    Args:
        spec: The :class:`~robotdyn.sweep.spec.SweepSpec`.

    Returns:
        The :class:`Plan`.
    """
    from ..fast.dispatch import enabled

    import robotdyn

    source, identity = _source(spec)
    mod = load_source(source)
    if not spec.fixed.keys().isdisjoint(a.name for a in spec.axes):
        both = sorted(set(spec.fixed) & {a.name for a in spec.axes})
        raise SweepSpecError(f"parameter {both[0]!r} is both fixed and varied; expected one or the other")
    robot = build_robot(mod, dict(spec.fixed), None)
    axes = []
    for axis in spec.axes:
        if axis.name in RESERVED:
            raise SweepSpecError(f"parameters.{axis.name}: a name of the results' own columns; expected a parameter")
        parameter = None if axis.name == TORQUE_SCALE else mod.SPEC.parameter(axis.name)
        try:
            axes.append(resolve_axis(axis, parameter))
        except SweepSpecError:
            raise
        except InputError as exc:  # the parameter's own check (bounds, choices)
            raise SweepSpecError(f"parameters.{axis.name}: {exc}") from None
    scenarios = getattr(mod, "SCENARIOS", {})
    chosen = spec.scenarios or list(scenarios)[:1]
    if not chosen:
        raise SweepSpecError(f"robot {robot.spec.name!r} has no scenarios; expected a robot with scenarios")
    for name in chosen:
        if name not in scenarios:
            raise SweepSpecError(f"unknown scenario {name!r} for {robot.spec.name}; expected one of "
                                 f"{', '.join(scenarios)}")
        if any(a.name == TORQUE_SCALE for a in axes) and overrides_run(scenarios[name]):
            raise SweepSpecError(f"scenario {name!r} builds its own torque law (a controller or feed-forward "
                                 "torques): torque_scale applies to scenarios with a torque profile")
    terrains = {}
    if spec.terrains:
        if not any(hasattr(c, "terrain") for c in robot.constraints):
            raise SweepSpecError(f"robot {robot.spec.name!r} has no wheel on a terrain; expected no terrains")
        for item in spec.terrains:
            label, definition = _terrain(mod, item, chosen)
            if label in terrains:
                raise SweepSpecError(f"terrain {label!r} listed twice; expected distinct terrains")
            terrains[label] = definition
    names = robot.coordinates + robot.velocity_names
    columns = spec.columns or names
    for c in columns:
        if columns.count(c) > 1:  # (two columns of one name would make every results file of the sweep unreadable)
            raise SweepSpecError(f"column {c!r} listed {columns.count(c)} times; expected distinct columns")
        if c not in names:
            raise SweepSpecError(f"unknown column {c!r}; expected one of {', '.join(names)}")
    from ..simulation.compiled_engine import check_method
    from ..simulation.run_options import check_tolerance

    tolerances = {}  # the integrator's options, checked as simulate checks them (simulation.run_options)
    for key in ("rtol", "atol"):
        value = getattr(spec, key)
        if value is not None:
            try:
                check_tolerance(key, value)
            except RobotDynError as exc:
                raise SweepSpecError(str(exc)) from None
            tolerances[key] = float(value)
    if spec.method is not None:
        try:
            check_method(spec.method)
        except RobotDynError as exc:
            raise SweepSpecError(str(exc)) from None
        tolerances["method"] = spec.method
    limit = spec.time_limit or None
    if limit is not None and not (limit > 0 and limit < float("inf")):
        raise SweepSpecError(f"time_limit = {spec.time_limit}; expected a duration in s > 0 (0: no limit)")
    if spec.n_out is not None and spec.n_out < 2:
        raise SweepSpecError(f"n_out = {spec.n_out}; expected at least 2 output samples")
    spans = {}
    for name in chosen:
        try:
            spans[name] = scenarios[name].span(spec.t_end, spec.n_out)
        except RobotDynError as exc:
            raise SweepSpecError(f"t_end/n_out: {exc}") from None
    pts = points(spec, axes)
    total = len(pts) * len(chosen) * max(1, len(terrains))
    if total > MAX_RUNS:
        raise SweepSpecError(f"{total:,} runs; expected at most {MAX_RUNS:,}: fewer points or samples")
    ctx = RunContext(source, dict(spec.fixed), terrains, spec.t_end, spec.n_out, tolerances, tuple(columns),
                     bool(spec.trajectories), enabled(), limit)
    expanded = hashlib.sha256(robot.description.urdf.encode()).hexdigest()  # every included file's content
    base = {"robot": {**identity, "expanded": expanded}, "version": robotdyn.__version__, "fixed": dict(spec.fixed),
            "tolerances": tolerances,
            "columns": list(columns), "trajectories": bool(spec.trajectories), "compiled": ctx.compiled}
    runs = []
    for point in pts:
        scale = float(point.get(TORQUE_SCALE, 1.0))
        params = tuple((k, v) for k, v in point.items() if k != TORQUE_SCALE)
        for name in chosen:
            for label in list(terrains) or [None]:
                key = {**base, "params": dict(params), "torque_scale": scale, "scenario": name,
                       "terrain": terrains.get(label), "span": spans[name]}
                runs.append(RunInput(run_id(key), len(runs), name, label, scale, params))
    if len({r.run_id for r in runs}) < len(runs):
        raise SweepSpecError("the sweep lists the same run twice (repeated values on an axis); expected distinct "
                             "values")
    return _finish(spec, robot, ctx, axes, runs, columns, spans)


def _finish(spec, robot, ctx, axes, runs, columns, spans) -> Plan:
    from .store import schema

    units = {"torque_scale": "-", "t_end": "s"}
    fields = [("run_id", "str", ""), ("run_index", "int", ""), ("robot", "str", ""), ("scenario", "str", ""),
              ("terrain", "str", ""), ("torque_scale", "float", "-"), ("t_end", "float", "s")]
    for axis in axes:
        if axis.name != TORQUE_SCALE:
            parameter = robot.spec.parameter(axis.name)
            numeric = parameter.choices is None
            fields.append((axis.name, "float" if numeric else "str", parameter.unit))
            units[axis.name] = parameter.unit
    fields += [("status", "str", ""), ("error", "str", "")]
    robot_units = robot.units
    for c in robot.coordinates + robot.velocity_names:
        fields.append((f"final.{c}", "float", robot_units.get(c, "")))
    for c in columns:
        fields += [(f"max.{c}", "float", robot_units.get(c, "")), (f"min.{c}", "float", robot_units.get(c, ""))]
    mod = load_source(ctx.source)
    for name, unit in OUTPUT_UNITS.items():
        if name != "drift" or callable(getattr(mod, "drift", None)):
            fields.append((name, "int" if name == "nfev" else "float", unit))
    units.update({name: unit for name, _, unit in fields if unit})
    table_schema = schema(fields, {"robotdyn.sweep.runner": spec.to_dict()})
    numeric = [name for name, kind, _ in fields if kind != "str"]
    if spec.plot_column is not None and spec.plot_column not in numeric:
        raise SweepSpecError(f"plot_column = {spec.plot_column!r}; expected a numeric column of the results: "
                             f"{', '.join(n for n in numeric if '.' in n)}")
    return Plan(spec, robot.spec.name, ctx, axes, runs, table_schema, units, spans)


__all__ = ["Plan", "plan"]

"""What a sweep runs: the axes (robot parameters with their units, scenarios, terrains, a torque scale), how they
are combined (a grid, or a seeded random or Latin-hypercube sample) and the runs that come out, each with an id
derived from its inputs.

A spec comes from a TOML file and/or the ``robotdyn sweep`` flags (:func:`parse_axis` reads ``NAME=LO:HI[:N][:log]``
and ``NAME=V1,V2,...``); :func:`from_toml` reads::

    robot = "quasimoro"                 # or constraints = "robot.toml" (urdf = "...", xacro_args = {...})
    scenarios = ["rectilinear"]         # default: the robot's first scenario
    terrains = ["flat", { kind = "ramp", slope = 0.1 }]   # the robot module's TERRAINS names, or kinds with args
    sample = "lhs"                      # grid (default) | random | lhs
    n = 200                             # samples (random, lhs)
    seed = 1
    t_end = 10.0                        # [s] (default: each scenario's duration)
    time_limit = 600.0                  # wall-clock limit of one run [s] (0: none): beyond it, an error row
    method = "dopri5"                   # the integrator, as simulate --method takes it (cvode: stiff compliant
                                        # wheels and springs; default: simulate's); rtol, atol: its tolerances
    columns = ["theta3", "theta1_dot"]  # columns whose max and min are kept (default: every q and nu column)
    trajectories = false                # also keep each run's trajectory
    fixed = { inertia_about = "com" }   # parameters held at one value

    [parameters]                        # the varied parameters, in the robot's units
    M = [4.0, 5.0, 6.0]                 # values (crossed with everything else)
    d = { min = "0.15 m", max = "0.25 m", n = 3 }   # a range: n points on a grid, sampled otherwise
    torque_scale = { min = 0.5, max = 2.0, scale = "log" }  # the scenario's torques times this factor

Every mistake is a one-line :class:`SweepSpecError` naming the entry and what was expected.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import re
import tomllib
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from ..errors import InputError

TORQUE_SCALE = "torque_scale"
"""The pseudo-parameter scaling every motor torque of a scenario (dimensionless)."""
SAMPLERS = ("grid", "random", "lhs")
DEFAULT_TIME_LIMIT = 600.0
"""Wall-clock limit [s] of one run by default (0 or ``None``: none): a crawling run becomes an error row."""
MAX_RUNS = 1_000_000
"""Largest number of runs of one sweep (a larger one is refused before anything runs)."""
MAX_SPEC_BYTES = 1_000_000
"""Largest sweep file read [bytes] (a sweep file is a few lines; a larger file is refused before it is read)."""
MAX_TORQUE_SCALE = 1e9
"""Largest magnitude of the torque scale: :data:`robotdyn.inputs.MAX_FORCE` per N m of the scenario's torques
(beyond it a torque of 1 N m leaves the range any motor torque is accepted in)."""
MAX_SEED = 2**63 - 1
RESERVED = ("run_id", "run_index", "robot", "scenario", "terrain", "status", "error", "t_end", "t_reached", "drift",
            "nfev", "wall", "run_wall")
"""Column names of the results that no varied parameter may take."""
TOP_KEYS = ("robot", "constraints", "urdf", "xacro_args", "fixed", "parameters", "scenarios", "terrains", "sample",
            "n", "seed", "t_end", "n_out", "rtol", "atol", "method", "columns", "trajectories", "plot_column",
            "time_limit")
RANGE_KEYS = ("min", "max", "n", "scale")
"""The keys of a range of the ``[parameters]`` table."""
_VALUE = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*")


class SweepSpecError(InputError):
    """A sweep specification that cannot be run (one line naming the entry and what was expected)."""


@dataclass(frozen=True)
class Axis:
    """One varied quantity: explicit ``values`` (numbers or choices), or a range [``low``, ``high``] in the
    parameter's unit with ``n`` grid points (linear, or geometric with ``log``); sampled when the sweep samples.

    Attributes:
        name: The parameter's name (or ``torque_scale``).
        values: Explicit values (numbers, unit strings or choices); empty for a range.
        low: Lower end of a range (``None`` with values).
        high: Upper end of a range.
        n: Grid points of a range (``None``: sampled only).
        log: Geometric grid / log-uniform samples instead of linear.
    """

    name: str
    values: tuple = ()
    low: float | None = None
    high: float | None = None
    n: int | None = None
    log: bool = False

    @property
    def ranged(self) -> bool:
        return not self.values

    def grid(self) -> list:
        """The axis's points on a grid.

        Returns:
            The points (floats or the given values), in order.
        """
        if not self.ranged:
            return list(self.values)
        if self.n is None:
            raise SweepSpecError(f"parameters.{self.name}: a range on a grid needs its number of points "
                                 f"(LO:HI:N, or n = ...); or sample it (sample = 'lhs' or 'random')")
        return (np.geomspace if self.log else np.linspace)(self.low, self.high, self.n).tolist()

    def scale(self, u: np.ndarray) -> np.ndarray:
        """Map uniform samples u in [0, 1) onto the range (log-uniform with ``log``).

        Args:
            u: Uniform samples in [0, 1).

        Returns:
            The values, shaped like ``u``, in the parameter's unit.
        """
        if self.log:
            return np.exp(np.log(self.low) + u * (np.log(self.high) - np.log(self.low)))
        return self.low + u * (self.high - self.low)


@dataclass
class SweepSpec:
    """A sweep: the robot (a registered name, or a constraint file), the axes and how to combine them, and the
    settings of each run (duration, samples, tolerances, summarised columns). See the module docstring.

    Attributes:
        robot: A registered robot's name (or ``None`` with ``constraints``).
        constraints: A constraint file's path.
        urdf: The constraint file's description, overriding its ``urdf``.
        xacro_args: Xacro arguments by name.
        fixed: Parameters held at one value (name -> value text).
        axes: The varied :class:`Axis` objects.
        scenarios: Scenario names (default: the robot's first).
        terrains: Terrain names or tables (default: the robot's own).
        sample: ``grid``, ``random`` or ``lhs``.
        n: Number of samples (random, lhs).
        seed: Seed of the samples.
        t_end: Duration [s] of each run (``None``: the scenario's).
        n_out: Output samples of each run (``None``: the scenario's).
        rtol: Integrator relative tolerance (``None``: default).
        atol: Integrator absolute tolerance (``None``: default).
        method: The integrator, as :func:`~robotdyn.simulation.engine.simulate` takes it (``None``: its default).
        columns: Columns whose max and min are kept (default: every q and nu column).
        trajectories: Also keep every run's trajectory.
        plot_column: The column of ``summary.png`` (``None``: :func:`~robotdyn.sweep.plot.default_column`).
        time_limit: Wall-clock limit [s] of one run (0 or ``None``: none).
    """

    robot: str | None = None
    constraints: str | None = None
    urdf: str | None = None
    xacro_args: dict[str, str] = field(default_factory=dict)
    fixed: dict[str, str] = field(default_factory=dict)
    axes: list[Axis] = field(default_factory=list)
    scenarios: list[str] = field(default_factory=list)
    terrains: list = field(default_factory=list)  # names (str) or tables {kind = ..., args}
    sample: str = "grid"
    n: int | None = None
    seed: int = 0
    t_end: float | None = None
    n_out: int | None = None
    rtol: float | None = None
    atol: float | None = None
    method: str | None = None
    columns: list[str] = field(default_factory=list)
    trajectories: bool = False
    plot_column: str | None = None
    time_limit: float | None = DEFAULT_TIME_LIMIT

    def __repr__(self) -> str:
        what = self.robot or self.constraints
        return (f"SweepSpec({what!r}, axes={[a.name for a in self.axes]}, scenarios={self.scenarios}, "
                f"sample={self.sample!r}" + (f", n={self.n}, seed={self.seed}" if self.sample != "grid" else "") + ")")

    def merged(self, **changes) -> SweepSpec:
        """A copy with the non-empty ``changes`` applied; axes given replace the axes of the same name.

        Args:
            **changes: Fields to replace (empty values are ignored; ``axes`` replace the axes of the same name).

        Returns:
            The new :class:`SweepSpec`.
        """
        changes = {k: v for k, v in changes.items() if v not in (None, [], {}, ())}
        axes = changes.pop("axes", [])
        names = {a.name for a in axes}
        out = replace(self, **changes)
        out.axes = [a for a in self.axes if a.name not in names] + list(axes)
        return out

    def to_dict(self) -> dict:
        """Plain data (for the sweep's ``sweep.json``).

        Returns:
            A JSON-ready dict of the spec's fields.
        """
        return asdict(self)


@dataclass(frozen=True)
class RunInput:
    """One run: its position in the sweep, its id (a hash of everything that determines its result), the
    scenario, the terrain label, the torque scale and the varied parameter values (name, value) pairs.

    Attributes:
        run_id: 16 hex digits, a hash of the run's inputs (:func:`run_id`).
        index: Position in the sweep.
        scenario: The scenario's name.
        terrain: The terrain label (``None``: the robot's own).
        torque_scale: The factor on the scenario's torques.
        params: (name, value) pairs of the varied parameters.
    """

    run_id: str
    index: int
    scenario: str
    terrain: str | None
    torque_scale: float
    params: tuple[tuple[str, float | str], ...]


def parse_value(text, unit: str, where: str) -> float:
    """A number, optionally followed by its unit (which must be the parameter's; degrees are accepted for an
    angle in rad): ``0.3``, ``"0.3 m"``, ``"5 deg"``.

    Args:
        text: A number, or a string: a number optionally followed by a unit.
        unit: The parameter's unit.
        where: The entry's name, for messages.

    Returns:
        The value [unit].
    """
    if isinstance(text, bool):
        raise SweepSpecError(f"{where} = {text!r}; expected a number [{unit or '-'}]")
    if isinstance(text, (int, float)):
        value, given = float(text), ""
    else:
        m = _VALUE.fullmatch(str(text))
        if not m:
            raise SweepSpecError(f"{where} = {text!r}; expected a number [{unit or '-'}], e.g. '0.3' or '0.3 {unit}'")
        value, given = float(m.group(1)), m.group(2)
    if given and " ".join(given.split()) != " ".join(unit.split()):
        if given == "deg" and unit == "rad":
            value = float(np.radians(value))
        else:
            raise SweepSpecError(f"{where} = {text!r}: unit {given!r}; expected the parameter's unit "
                                 f"{unit or '(none)'!r}")
    if not np.isfinite(value):
        raise SweepSpecError(f"{where} = {text!r} is not finite; expected a number [{unit or '-'}]")
    return value


def parse_axis(text: str) -> Axis:
    """``NAME=LO:HI`` (a range), ``NAME=LO:HI:N`` (N grid points), ``...:log`` (geometric/log-uniform) or
    ``NAME=V1,V2,...`` (values); values keep their unit text until checked against the robot.

    Args:
        text: The ``--vary`` argument.

    Returns:
        The :class:`Axis` (values still as text).
    """
    if "=" not in text:
        raise SweepSpecError(f"--vary {text!r}; expected NAME=LO:HI[:N][:log] or NAME=V1,V2,...")
    name, rhs = (s.strip() for s in text.split("=", 1))
    parts = [p.strip() for p in rhs.split(":")]
    log = parts[-1] == "log"
    if log:
        parts = parts[:-1]
    if len(parts) == 1:
        if log:
            raise SweepSpecError(f"--vary {text!r}: ':log' applies to a range LO:HI; expected NAME=LO:HI:log")
        return Axis(name, tuple(v.strip() for v in rhs.split(",") if v.strip()))
    if len(parts) not in (2, 3):
        raise SweepSpecError(f"--vary {text!r}; expected NAME=LO:HI[:N][:log] or NAME=V1,V2,...")
    return Axis(name, (), parts[0], parts[1], _count(parts[2], f"--vary {text}") if len(parts) == 3 else None, log)


def _count(x, where: str) -> int:
    try:
        n = int(x)
    except (TypeError, ValueError):
        raise SweepSpecError(f"{where}: n = {x!r}; expected a whole number of points >= 1") from None
    if isinstance(x, float) and x != n or not 1 <= n <= MAX_RUNS:
        raise SweepSpecError(f"{where}: n = {x!r}; expected a whole number of points from 1 to {MAX_RUNS:,}")
    return n


def from_toml(path) -> SweepSpec:
    """Read and check the structure of a sweep file (names and values are checked against the robot by
    :func:`expand`). Relative ``constraints``/``urdf`` paths are taken from the file's directory.

    Args:
        path: The sweep TOML file.

    Returns:
        The :class:`SweepSpec`.
    """
    from ..input_files import read_text, resolved

    path = Path(path)
    try:  # a regular file of bounded size: a FIFO would block, /dev/zero would never end
        text = read_text(path, "sweep file", MAX_SPEC_BYTES)
    except InputError as exc:
        raise SweepSpecError(str(exc)) from None
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        raise SweepSpecError(f"{path}: not valid TOML ({exc})") from None
    for key in data:
        if key not in TOP_KEYS:
            raise SweepSpecError(f"{path}: unknown key {key!r}; expected one of {', '.join(TOP_KEYS)}")
    spec = SweepSpec()
    for key in ("robot", "constraints", "urdf", "plot_column"):
        if key in data:
            if not isinstance(data[key], str) or not data[key]:
                raise SweepSpecError(f"{path}: {key} = {data[key]!r}; expected a non-empty string")
            value = data[key]
            if key in ("constraints", "urdf") and not value.startswith("package://"):
                value = str(resolved(path.parent / value, key))
            setattr(spec, key, value)
    for key in ("xacro_args", "fixed"):
        table = data.get(key, {})
        if not isinstance(table, dict):
            raise SweepSpecError(f"{path}: {key} = {table!r}; expected a table NAME = VALUE")
        setattr(spec, key, {k: str(v) for k, v in table.items()})
    for key in ("scenarios", "columns"):
        items = data.get(key, [])
        if isinstance(items, str):
            items = [items]
        if not isinstance(items, list) or not all(isinstance(s, str) for s in items):
            raise SweepSpecError(f"{path}: {key} = {items!r}; expected a list of names")
        setattr(spec, key, list(items))
    terrains = data.get("terrains", [])
    if not isinstance(terrains, list) or not all(isinstance(t, (str, dict)) for t in terrains):
        raise SweepSpecError(f"{path}: terrains = {terrains!r}; expected a list of names or tables {{kind = ...}}")
    spec.terrains = terrains
    params = data.get("parameters", {})
    if not isinstance(params, dict):
        raise SweepSpecError(f"{path}: parameters: expected a table of NAME = [values] or {{min, max, n}}")
    spec.axes = [_toml_axis(path, name, v) for name, v in params.items()]
    for key, kind in (("sample", str), ("n", int), ("seed", int), ("t_end", float), ("n_out", int),
                      ("rtol", float), ("atol", float), ("method", str), ("trajectories", bool),
                      ("time_limit", float)):
        if key in data:
            v = data[key]
            ok = isinstance(v, kind) if kind is not float else isinstance(v, (int, float)) and not isinstance(v, bool)
            if not ok or (kind is int and isinstance(v, bool)):
                raise SweepSpecError(f"{path}: {key} = {v!r}; expected {'a ' + kind.__name__}")
            setattr(spec, key, float(v) if kind is float else v)
    return spec


def _toml_axis(path: Path, name: str, v) -> Axis:
    where = f"{path}: parameters.{name}"
    if isinstance(v, list):
        if not v:
            raise SweepSpecError(f"{where}: no values; expected at least one")
        return Axis(name, tuple(v))
    if not isinstance(v, dict):
        return Axis(name, (v,))
    allowed = RANGE_KEYS
    for k in v:
        if k not in allowed:
            raise SweepSpecError(f"{where}: unknown key {k!r}; expected {', '.join(allowed)}")
    if "min" not in v or "max" not in v:
        raise SweepSpecError(f"{where}: a range needs min and max")
    if v.get("scale", "linear") not in ("linear", "log"):
        raise SweepSpecError(f"{where}: scale = {v['scale']!r}; expected 'linear' or 'log'")
    return Axis(name, (), v["min"], v["max"], _count(v["n"], where) if "n" in v else None, v.get("scale") == "log")


def resolve_axis(axis: Axis, parameter) -> Axis:
    """Check an axis against the robot's :class:`~robotdyn.robot.Parameter` (``None`` for the torque scale):
    units, finiteness, the parameter's own bounds and choices; returns it with plain values.

    Args:
        axis: The :class:`Axis` as parsed.
        parameter: The robot's :class:`~robotdyn.robot.Parameter` (``None`` for the torque scale).

    Returns:
        The checked :class:`Axis`, values converted to the parameter's unit.
    """
    where = f"parameters.{axis.name}"
    unit = "-" if parameter is None else parameter.unit

    def convert(x):
        if parameter is not None and parameter.choices is not None:
            return parameter.convert(x)
        value = parse_value(x, unit if unit != "-" else "", where)
        if parameter is None and abs(value) > MAX_TORQUE_SCALE:
            raise SweepSpecError(f"{where} = {x!r}; expected a torque scale of magnitude <= {MAX_TORQUE_SCALE:g}")
        return value if parameter is None else parameter.convert(value)

    if parameter is not None and parameter.choices is not None and axis.ranged:
        raise SweepSpecError(f"{where}: a range for a parameter with choices; expected values among "
                             f"{', '.join(parameter.choices)}")
    if not axis.ranged:
        return replace(axis, values=tuple(convert(x) for x in axis.values))
    low, high = convert(axis.low), convert(axis.high)
    if not low < high:
        raise SweepSpecError(f"{where}: range [{low:g}, {high:g}]; expected min < max")
    if axis.log and low <= 0:
        raise SweepSpecError(f"{where}: a log scale needs min > 0 (got {low:g})")
    return replace(axis, low=low, high=high)


def points(spec: SweepSpec, axes: list[Axis]) -> list[dict]:
    """The parameter points of the sweep: the grid of every axis, or ``spec.n`` random/LHS samples of the ranged
    axes (seeded) crossed with the grid of the axes given as values.

    Args:
        spec: The :class:`SweepSpec` (its ``sample``, ``n`` and ``seed``).
        axes: The resolved axes.

    Returns:
        One dict of parameter name to value per point.
    """
    if spec.sample not in SAMPLERS:
        raise SweepSpecError(f"sample = {spec.sample!r}; expected one of {', '.join(SAMPLERS)}")
    if isinstance(spec.seed, bool) or not isinstance(spec.seed, int) or not 0 <= spec.seed <= MAX_SEED:
        raise SweepSpecError(f"seed = {spec.seed!r}; expected a whole number from 0 to {MAX_SEED}")
    if spec.sample == "grid":
        if spec.n is not None:
            raise SweepSpecError(f"n = {spec.n} samples with sample = 'grid'; expected sample = 'lhs' or 'random' "
                                 "(a grid's size is its axes' points)")
        total = 1
        for a in axes:
            total *= len(a.values) if not a.ranged else (a.n or 1)
        if total > MAX_RUNS:
            raise SweepSpecError(f"{total:,} runs on the grid; expected at most {MAX_RUNS:,}: fewer points")
        grids = [a.grid() for a in axes]
        return [dict(zip([a.name for a in axes], combo)) for combo in itertools.product(*grids)]
    ranged = [a for a in axes if a.ranged]
    listed = [a for a in axes if not a.ranged]
    if not ranged:
        raise SweepSpecError(f"sample = {spec.sample!r} needs at least one range to sample (NAME=LO:HI)")
    if spec.n is None or spec.n < 1:
        raise SweepSpecError(f"sample = {spec.sample!r}: n = {spec.n}; expected the number of samples >= 1")
    if spec.n * int(np.prod([len(a.values) for a in listed])) > MAX_RUNS:
        raise SweepSpecError(f"n = {spec.n:,} samples crossed with the listed values; expected at most {MAX_RUNS:,} "
                             "runs")
    rng = np.random.default_rng(spec.seed)
    if spec.sample == "random":
        u = rng.random((spec.n, len(ranged)))
    else:
        import inspect

        from scipy.stats import qmc

        kw = "rng" if "rng" in inspect.signature(qmc.LatinHypercube).parameters else "seed"
        u = qmc.LatinHypercube(d=len(ranged), **{kw: rng}).random(spec.n)
    samples = np.column_stack([a.scale(u[:, j]) for j, a in enumerate(ranged)])
    out = []
    for row in samples:
        for combo in itertools.product(*[a.values for a in listed]):
            point = {a.name: float(x) for a, x in zip(ranged, row)}
            point.update(zip([a.name for a in listed], combo))
            out.append({a.name: point[a.name] for a in axes})
    return out


def run_id(identity: dict) -> str:
    """A 16-hex-digit id of a run from the canonical JSON of its inputs (floats by their exact ``repr``).

    Args:
        identity: Everything that determines a run's result (JSON-serialisable).

    Returns:
        The id (16 hex digits).
    """
    text = json.dumps(identity, sort_keys=True, default=repr, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


__all__ = ["Axis", "SweepSpec", "RunInput", "SweepSpecError", "parse_axis", "parse_value", "from_toml",
           "resolve_axis", "points", "run_id", "TORQUE_SCALE"]

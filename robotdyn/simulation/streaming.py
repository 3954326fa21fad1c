"""Long runs streamed to a CSV file in segments: memory bounded whatever the duration.

:func:`stream` (reached through ``simulate(..., sink=CsvSink(path))`` or ``Scenario.run(..., sink=...)``) integrates
[0, t_end] in segments of at most ``CsvSink.segment`` output samples (default :data:`SEGMENT`). Each segment is one
:func:`~robotdyn.simulation.engine.simulate` call from the previous segment's last sample (q, nu and the absolute
time, so torque profiles continue unchanged); its rows, and the extra columns ``CsvSink.columns`` computes from
it (e.g. the wheel loads of :func:`robotdyn.contact.traction.traction`), are appended to ``<target>.partial``
(:func:`robotdyn.output.visible_output`: visible, on disk as computed, left with its rows by a run killed hard) that
replaces the target at the end, and then dropped. The output grid is the
in-memory run's (``np.linspace(0, t_end, n_out)``), each time written once.

**The integrator restarts at every segment boundary**, as both engines do at a torque profile's breakpoints: the
state is carried exactly, but the step-size and order history is not, so a streamed run and one in-memory run agree
to the integration tolerance (``tests/test_streaming.py``: 1e-9 on Quasimoro), not bit for bit.

A Ctrl-C or SIGTERM (the CLI turns it into ``KeyboardInterrupt``) keeps every row already written plus the
interrupted segment's rows up to the interruption, followed by the ``# partial: ...`` line of
:meth:`~robotdyn.simulation.engine.Trajectory.to_csv`: the rows are always a prefix of the full run's, and the
times the line states are read back from the last row on disk (whatever the interruption hit: the integration, the
extra columns or the formatting of a chunk), so the marker is true by construction.
"""

from __future__ import annotations

import io
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import RobotDynError, TimeLimitError

SEGMENT = 100_000
"""Default number of output samples per segment (memory: about 8 bytes x (2n + 3 + extra columns) each, plus the
integrator's own per-sample arrays)."""
CHUNK = 5_000
"""Rows formatted and written at a time (the text of a chunk is the only copy of the rows as text)."""


@dataclass
class CsvSink:
    """Where and how a streamed run is written.

    Attributes:
        path: The CSV file (written atomically: a failed run leaves an existing file as it was).
        columns: Extra columns of a segment by name, ``columns(trajectory) -> {name: (N,) array}`` (``None``: none).
            The names of the first segment make the header; a later segment's missing names are written as nan.
        segment: Output samples per segment (>= 2): bounds the memory of the run.
        stopped_by: Rewrites a partial run's note before it is written to the file, ``stopped_by(note) -> note``
            (e.g. the CLI's :meth:`robotdyn.cli.time_limit.Limit.reason`, which says that the time limit, not an
            interruption, stopped the run); ``None``: the note as it is.
    """

    path: str | Path
    columns: Callable | None = None
    segment: int = SEGMENT
    stopped_by: Callable | None = None


@dataclass
class StreamResult:
    """What is kept in memory of a streamed run: its ends and extremes.

    Attributes:
        path: The CSV file written.
        samples: Rows written.
        t: Time of the last row [s].
        coordinates, velocity_names: Column names of q and nu.
        q, nu: State at the last row.
        energy_start, energy_end: Total mechanical energy at the first and last rows [J].
        max_residual: Largest holonomic residual over the rows written.
        stats: ``nfev``, ``wall`` [s], ``engine``, ``segments``, and ``partial`` / ``event`` / ``offsets`` as in
            :attr:`~robotdyn.simulation.engine.Trajectory.stats`.
    """

    path: Path
    samples: int
    t: float
    coordinates: list[str]
    velocity_names: list[str]
    q: np.ndarray
    nu: np.ndarray
    energy_start: float
    energy_end: float
    max_residual: float
    stats: dict = field(default_factory=dict)


def _grid(a: int, b: int, n_out: int, t_end: float) -> np.ndarray:
    """Samples a..b (inclusive) of ``np.linspace(0, t_end, n_out)``, bit for bit."""
    times = np.arange(a, b + 1, dtype=float) * (t_end / (n_out - 1))
    if b == n_out - 1:
        times[-1] = t_end
    return times


def stream(robot, t_end: float, q0, nu0, torque, n_out: int, sink: CsvSink, progress: bool = True,
           time_limit: float | None = None, **kwargs) -> StreamResult:
    """Simulate [0, t_end] from (q0, nu0) and write the samples to ``sink.path`` segment by segment.

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        t_end: Final time [s] (> 0).
        q0, nu0: Initial state (q0 checked against the holonomic constraints).
        torque: As for :func:`~robotdyn.simulation.engine.simulate`.
        n_out: Number of output samples (>= 2; no upper bound: memory depends on ``sink.segment`` only).
        sink: The :class:`CsvSink`.
        progress: Print the simulated time to stderr after each segment (at most once a second).
        time_limit: Wall-clock limit of the whole run [s] (None: none).
        **kwargs: rtol, atol, method, stabilisation, engine: passed to every segment's ``simulate``.

    Returns:
        The :class:`StreamResult`; ``stats["partial"]`` says where an interrupted run stopped.

    Raises:
        RobotDynError: Bad arguments, or a segment's integration failed (the file is then not written).
    """
    from ..contact.stick_slip_wheel import stick_slip_wheels
    from ..output import check_target, visible_output
    from .engine import simulate

    segment = int(sink.segment)
    if segment < 2 or segment != sink.segment:
        raise RobotDynError(f"segment = {sink.segment}; expected a whole number of samples >= 2")
    if not (float(n_out) == int(n_out) and n_out >= 2):
        raise RobotDynError(f"n_out = {n_out}; expected a whole number of samples >= 2")
    n_out = int(n_out)
    if not (np.isfinite(t_end) and t_end > 0):
        raise RobotDynError(f"t_end = {t_end} s; expected a positive duration")
    if stick_slip_wheels(robot):
        raise RobotDynError("sink: a run with stick-slip wheels cannot be streamed (its phases switch over the whole "
                            "run); simulate it in memory")
    check_target(sink.path, "CSV file")
    q, nu = robot.check_q(q0), robot.check_nu(nu0)
    robot.check_constraints(q)
    names = ["t", *robot.coordinates, *robot.velocity_names]
    extra: list[str] | None = None
    written, a, t_last = 0, 0, 0.0
    stats: dict = {"nfev": 0, "wall": 0.0, "segments": 0}
    energy_start = energy_end = float("nan")
    max_residual = 0.0
    start = last_print = time.perf_counter()
    with visible_output(sink.path, "CSV file") as (_, f):
        try:
            while a < n_out - 1:
                b = min(a + segment - 1, n_out - 1)
                times = _grid(a, b, n_out, t_end)
                limit = None
                if time_limit is not None:
                    limit = time_limit - (time.perf_counter() - start)
                    if limit <= 0:
                        raise TimeLimitError(f"the run exceeded its time limit of {time_limit:g} s at t = {times[0]:.3g}"
                                             f" s of {t_end:g} s (a stiff or blown-up run; a longer time limit allows more)")
                traj = simulate(robot, float(times[-1]), q, nu, torque, t0=float(times[0]), times=times,
                                progress=False, time_limit=limit, **kwargs)
                stats["nfev"] += traj.stats["nfev"]
                stats["wall"] += traj.stats["wall"]
                stats["segments"] += 1
                for key in ("engine", "method", "rtol"):
                    stats.setdefault(key, traj.stats.get(key))
                if "offsets" in traj.stats:
                    stats.setdefault("offsets", traj.stats["offsets"])
                skip = 1 if a else 0  # a later segment's first sample is the previous segment's last row
                cols = {}
                if sink.columns is not None and len(traj.t) > skip:
                    try:
                        cols = sink.columns(traj)
                    except KeyboardInterrupt:
                        stats["partial"] = (f"interrupted while computing the extra columns from t = {times[0]:.6g}"
                                            f" s: samples up to t = {t_last:.6g} s of {t_end:g} s")
                        break
                if extra is None:
                    extra = list(cols)
                    f.write((",".join(names + extra) + "\n").encode())
                data = np.column_stack([traj.t, traj.q, traj.nu,
                                        *(cols.get(c, np.full(len(traj.t), np.nan)) for c in extra)])[skip:]
                kept = _write(f, data)
                if kept:
                    t_last, q, nu = float(data[kept - 1, 0]), traj.q[skip + kept - 1], traj.nu[skip + kept - 1]
                    if written == 0 and skip == 0:
                        energy_start = float(traj.energy[0])
                    energy_end = float(traj.energy[skip + kept - 1])
                    max_residual = max(max_residual, float(np.max(traj.residual[skip:skip + kept])))
                    written += kept
                if kept < len(data):
                    stats["partial"] = (f"interrupted while writing: samples up to t = {t_last:.6g} s of "
                                        f"{t_end:g} s")
                    break
                if "partial" in traj.stats:  # the segment's own message counts to its end: say the run's
                    stats["partial"] = f"interrupted: samples up to t = {t_last:.6g} s of {t_end:g} s"
                    break
                if "event" in traj.stats:  # a slipping wheel lifted off: the contact model ends there
                    stats["event"], stats["t_event"] = traj.stats["event"], traj.stats["t_event"]
                    break
                a = b
                now = time.perf_counter()
                if progress and now - last_print >= 1.0:
                    last_print = now
                    print(f"simulate: t = {t_last:.2f} / {t_end:g} s ({100 * t_last / t_end:.0f}%), {written:,} samples "
                          f"written to {sink.path}", file=sys.stderr, flush=True)
        except KeyboardInterrupt:  # anywhere else: between segments, in a set-up, in formatting a chunk
            stats["partial"] = "interrupted"
        if "partial" in stats:  # the rows on disk say where the run stopped (the marker must be true)
            row = _last_row(f, 1 + len(robot.coordinates) + len(robot.velocity_names))
            if row is not None and row[0] != t_last:
                t_last = float(row[0])
                q = row[1:1 + robot.nq]
                nu = row[1 + robot.nq:1 + robot.nq + robot.mobility]
                written = int(round(t_last / (t_end / (n_out - 1)))) + 1  # the rows are samples 0.. of the grid
                energy_end = float(robot.energy(q, robot.velocity(q, nu)))
                if written == 1:
                    energy_start = energy_end
            if row is None:
                written = 0
            reached = f"samples up to t = {t_last:.6g} s" if written else "no samples"
            stats["partial"] = f"{stats['partial'].split(':')[0]}: {reached} of {t_end:g} s"
            if sink.stopped_by is not None:
                stats["partial"] = sink.stopped_by(stats["partial"])
            f.write(f"# partial: {stats['partial']}\n".encode())
    return StreamResult(Path(sink.path), written, t_last, list(robot.coordinates), list(robot.velocity_names),
                        np.asarray(q, float), np.asarray(nu, float), energy_start, energy_end, max_residual, stats)


def _write(f, data: np.ndarray) -> int:
    """Append ``data``'s rows to the binary file ``f`` (numpy.savetxt's format), :data:`CHUNK` rows at a time.
    Returns how many rows were written completely: an interruption (KeyboardInterrupt) anywhere in a chunk, its
    formatting included, cuts the file back to the last whole chunk, so that no half line is left."""
    done = 0
    while done < len(data):
        pos, end = f.tell(), min(done + CHUNK, len(data))
        buf = io.BytesIO()
        try:
            np.savetxt(buf, data[done:end], delimiter=",")
            f.write(buf.getvalue())
            f.flush()
            done = end
        except KeyboardInterrupt:
            if done != end:  # the chunk is not counted: not on disk either
                f.seek(pos)
                f.truncate()
            return done
        finally:  # savetxt leaves buf in a reference cycle: free its text now, not at the next garbage collection
            buf.close()
    return done


def _last_row(f, width: int) -> np.ndarray | None:
    """The last complete data row of the CSV file ``f`` (open for reading and writing), its first ``width`` numbers,
    after cutting off an incomplete last line (``None``: no data row, only the header or nothing)."""
    f.flush()
    end = f.seek(0, io.SEEK_END)
    start = max(0, end - (1 << 20))
    f.seek(start)
    tail = f.read(end - start)
    cut = tail.rfind(b"\n") + 1
    if start + cut != end:  # a half-written line (e.g. a write cut short): not a row
        f.seek(start + cut)
        f.truncate()
        tail = tail[:cut]
    f.seek(0, io.SEEK_END)
    lines = tail[:-1].rsplit(b"\n", 1) if tail else []
    if not lines:
        return None
    last = lines[-1]
    if last.startswith(b"t,") or last.startswith(b"#"):  # the header (names start with "t"), or a comment
        return None
    try:
        return np.array([float(x) for x in last.split(b",")[:width]])
    except ValueError:
        return None


__all__ = ["stream", "CsvSink", "StreamResult", "SEGMENT"]

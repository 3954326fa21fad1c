"""A sweep's results on disk, in Parquet (pyarrow), written so that an interrupted sweep resumes.

Layout of a sweep directory::

    runs/part-<hash>.parquet            one file per finished chunk: one row per run (inputs and outputs)
    trajectories/run_id=<id>/part-0.parquet   each run's trajectory (optional; a Hive-partitioned dataset)
    results.parquet                     this sweep's rows, in run order (rewritten at the end of every session)
    sweep.json                          the specification last run, its run count and its run ids' digest
    sweep.lock                          locked (flock) while a sweep writes the directory: pid, host, start

A second sweep writing the same directory meanwhile is refused in one line naming the lock's holder
(:func:`lock`). A directory whose rows are not all runs of the sweep being started holds another sweep (or this
one with changed inputs: every run id hashes its inputs) and is refused unless replaced (:func:`foreign`,
:func:`clear`).

Every file is written to a temporary name and renamed (:func:`robotdyn.output.atomic_output`), trajectories before
the chunk's row file, so a row file on disk means its runs are complete. Rows are keyed by ``run_id``, a hash of
the run's inputs (:func:`robotdyn.sweep.spec.run_id`): rerunning a sweep skips the runs whose rows exist.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from ..errors import OutputError
from ..output import atomic_output, try_lock

RUNS = "runs"
TRAJECTORIES = "trajectories"
RESULTS = "results.parquet"


def schema(fields: list[tuple[str, str, str]], metadata: dict | None = None):
    """A pyarrow schema from (column, type, unit) triples, type one of ``float``, ``int``, ``str``; each field
    carries its unit in its metadata (``unit``).

    Args:
        fields: (column, type, unit) triples.
        metadata: Schema-level metadata (default ``None``).

    Returns:
        The ``pyarrow.Schema``.
    """
    import pyarrow as pa

    types = {"float": pa.float64(), "int": pa.int64(), "str": pa.string()}
    return pa.schema([pa.field(name, types[kind], metadata={"unit": unit}) for name, kind, unit in fields],
                     metadata={k: json.dumps(v) for k, v in (metadata or {}).items()})


def prepare(out) -> Path:
    """Create the sweep directory (and ``runs/``); an existing file in the way is a one-line error.

    Args:
        out: The sweep directory.

    Returns:
        The sweep directory.
    """
    out = Path(out)
    try:
        (out / RUNS).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create sweep directory {str(out)!r}: {exc.strerror or exc}") from None
    return out


LOCK = "sweep.lock"


class Lock:
    """The exclusive lock of a sweep directory (:func:`lock`); :meth:`release` gives it up.

    Args:
        fd: The open descriptor of ``sweep.lock`` that holds the ``flock`` (closing it releases the lock).
    """

    def __init__(self, fd: int) -> None:
        self.fd = fd

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)  # closing the descriptor releases the flock
            self.fd = None


def lock(out: Path) -> Lock:
    """Lock the sweep directory ``out`` for this process (``flock`` on ``out/sweep.lock``, released when the
    process ends, however it ends) and write who holds it into the file.

    Args:
        out: The sweep directory (existing).

    Returns:
        The held :class:`Lock`.

    Raises:
        OutputError: Another process holds the lock (naming its pid, host and start time).
    """
    import socket
    import time

    try:
        fd, held = try_lock(out / LOCK)
    except OSError as exc:
        raise OutputError(f"cannot lock sweep directory {str(out)!r}: {exc.strerror or exc}") from None
    if not held:
        try:
            holder = os.pread(fd, 300, 0).decode(errors="replace").strip() or "another process"
        finally:
            os.close(fd)
        raise OutputError(f"sweep directory {str(out)!r} is being written by {holder}; expected one sweep at a time "
                          "per directory (wait for it, or give another --out)") from None
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"pid {os.getpid()} on {socket.gethostname()} since "
                  f"{time.strftime('%Y-%m-%d %H:%M:%S', time.localtime())}\n".encode(), 0)
    return Lock(fd)


def foreign(out: Path, done: dict[str, str], ids: set[str], spec: dict) -> str | None:
    """Why the directory ``out`` holds another sweep than the one whose run ids are ``ids`` and specification
    ``spec`` (its rows on disk, ``done``, include runs that are not this sweep's), or ``None`` if it does not.

    Args:
        out: The sweep directory (its ``sweep.json`` says which specification wrote it).
        done: The runs with a row on disk, run_id -> status (:func:`finished`).
        ids: The run ids of this sweep.
        spec: This sweep's specification as a dict (``SweepSpec.to_dict()``).

    Returns:
        A one-line reason (how many finished runs are not this sweep's, and whether the specification is the
        same so an input changed), or None if every finished run is one of this sweep's.
    """
    others = [i for i in done if i not in ids]
    if not others:
        return None
    previous = None
    try:
        previous = json.loads((out / "sweep.json").read_text()).get("spec")
    except (OSError, ValueError, AttributeError):
        pass
    why = (": the same specification, so an input changed since it ran (a file the description includes, the "
           "constraint file, or robotdyn's version)") if previous == json.loads(json.dumps(spec, default=str)) else ""
    return f"{len(others)} of its {len(done)} finished runs are not runs of this sweep{why}"


def clear(out: Path) -> None:
    """Delete a sweep's results from ``out`` (row files, trajectories, results, plot, description); other files
    are left alone.

    Args:
        out: The sweep directory.
    """
    import shutil

    for path in _parts(out):
        path.unlink()
    shutil.rmtree(out / TRAJECTORIES, ignore_errors=True)
    for name in (RESULTS, "summary.png", "sweep.json"):
        (out / name).unlink(missing_ok=True)


def _write(table, path: Path, what: str) -> None:
    import pyarrow.parquet as pq

    with atomic_output(path, what) as tmp:
        pq.write_table(table, tmp)


def write_chunk(out: Path, rows: list[dict], trajectories: list[dict | None], schema) -> Path:
    """Write a finished chunk: its trajectories (if any), then its row file; returns the row file's path.

    Args:
        out: The sweep directory.
        rows: The chunk's result rows.
        trajectories: Each row's trajectory columns (``None``: not kept).
        schema: The results' pyarrow schema (:func:`schema`).

    Returns:
        The row file's path.
    """
    import pyarrow as pa

    for row, traj in zip(rows, trajectories):
        if traj is not None:
            folder = out / TRAJECTORIES / f"run_id={row['run_id']}"
            folder.mkdir(parents=True, exist_ok=True)
            _write(pa.table(traj), folder / "part-0.parquet", "trajectory file")
    table = pa.Table.from_pylist([{k: row.get(k) for k in schema.names} for row in rows], schema=schema)
    name = hashlib.sha256(",".join(sorted(r["run_id"] for r in rows)).encode()).hexdigest()[:16]
    path = out / RUNS / f"part-{name}.parquet"
    _write(table, path, "results file")
    return path


_WARNED: set[Path] = set()


def _parts(out: Path) -> list[Path]:
    """The chunk files of a sweep directory that can be read back: a file with two columns of one name (written by a
    sweep that listed a column twice, before that was refused) cannot, and is left out with a warning (its runs are
    computed again) rather than failing every later sweep into the directory."""
    import warnings

    import pyarrow.parquet as pq

    from ..errors import RobotDynWarning

    parts = []
    for path in sorted((out / RUNS).glob("part-*.parquet")):
        try:
            names = pq.read_schema(path).names
        except Exception:  # unreadable: finished() names it in one line
            names = []
        if len(set(names)) < len(names):
            if path not in _WARNED:  # once per process
                _WARNED.add(path)
                warnings.warn(f"results file {str(path)!r} has repeated columns and cannot be read; ignored (its runs "
                              "are computed again): move it away", RobotDynWarning, stacklevel=2)
            continue
        parts.append(path)
    return parts


def finished(out: Path) -> dict[str, str]:
    """The runs with a row on disk: run_id -> status (``ok``, ``stopped`` or ``error``).

    Args:
        out: The sweep directory.

    Returns:
        A dict of run id to status.
    """
    import pyarrow.parquet as pq

    done: dict[str, str] = {}
    for path in _parts(out):
        try:
            table = pq.read_table(path, columns=["run_id", "status"])
        except Exception as exc:  # a foreign or damaged file: say which, never resume from it silently
            raise OutputError(f"cannot read sweep results {str(path)!r} ({exc}); expected a file written by "
                              "robotdyn sweep: move it away") from None
        done.update(zip(table.column("run_id").to_pylist(), table.column("status").to_pylist()))
    return done


def consolidate(out: Path, order: dict[str, int], schema):
    """Gather this sweep's rows (the run ids in ``order``) from the row files, sorted by run order, and write
    them to ``results.parquet``; returns the table.

    Args:
        out: The sweep directory.
        order: Run index by run id (the runs of this sweep).
        schema: The results' pyarrow schema (:func:`schema`).

    Returns:
        The consolidated ``pyarrow.Table``, in run order.
    """
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    tables, seen = [], set()
    for path in _parts(out):
        try:
            table = pq.read_table(path)
        except Exception as exc:  # a foreign or damaged file: say which, in one line
            raise OutputError(f"cannot read sweep results {str(path)!r} ({exc}); expected a file written by "
                              "robotdyn sweep: move it away") from None
        ids = table.column("run_id")
        mask = pc.is_in(ids, value_set=pa.array(sorted(set(order) - seen), pa.string()))
        table = table.filter(mask)
        if table.num_rows:
            seen.update(table.column("run_id").to_pylist())
            tables.append(table.select(schema.names).cast(schema))
    table = pa.concat_tables(tables) if tables else schema.empty_table()
    index = pa.array([order[i] for i in table.column("run_id").to_pylist()], pa.int64())
    table = table.take(pc.sort_indices(index))
    _write(table.replace_schema_metadata(schema.metadata), out / RESULTS, "results file")
    return table


def write_json(path: Path, data: dict) -> None:
    """Write ``data`` as indented JSON to ``path``, atomically.

    Args:
        path: The JSON file.
        data: The data (non-JSON values written as strings).
    """
    with atomic_output(path, "sweep description") as tmp:
        tmp.write_text(json.dumps(data, indent=2, default=str))


def load(out):
    """A sweep's results as a pandas DataFrame (one row per run, in run order).

    Args:
        out: A sweep directory written by ``robotdyn sweep`` (or :func:`robotdyn.sweep.runner.run`).

    Returns:
        A pandas DataFrame.
    """
    import pyarrow.parquet as pq

    path = Path(out) / RESULTS
    if not path.is_file():
        raise OutputError(f"no sweep results at {str(path)!r}; expected a directory written by robotdyn sweep")
    return pq.read_table(path).to_pandas()


def load_trajectory(out, run_id: str):
    """One run's trajectory (t, coordinates, velocities, energy, residual) as a pandas DataFrame.

    Args:
        out: A sweep directory run with ``--trajectories``.
        run_id: The run's id (``run_id`` column).

    Returns:
        The ``pandas.DataFrame`` of the run's trajectory, one row per sample.
    """
    import pyarrow.parquet as pq

    path = Path(out) / TRAJECTORIES / f"run_id={run_id}" / "part-0.parquet"
    if not path.is_file():
        raise OutputError(f"no trajectory for run {run_id!r} in {str(out)!r} (was the sweep run with "
                          "trajectories = true?)")
    return pq.read_table(path).to_pandas()


__all__ = ["schema", "prepare", "lock", "foreign", "clear", "write_chunk", "finished", "consolidate", "load",
           "load_trajectory"]

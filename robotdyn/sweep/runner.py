"""Parameter sweeps on Dask: :func:`run` (and ``robotdyn sweep``).

A sweep (:class:`~robotdyn.sweep.spec.SweepSpec`) crosses robot parameters (a grid, or a seeded random or Latin
hypercube sample, in the parameters' units), scenarios, terrains and a torque scale. :func:`plan` checks it
against the robot and lists the runs, each with an id derived from its inputs; :func:`run` sends them in chunks
(:func:`robotdyn.sweep.chunk.run_chunk`) to Dask: an in-process ``LocalCluster`` of ``workers`` single-threaded
worker processes by default, the cluster of a ``scheduler`` address, or a given ``client`` (``workers=0``: no
Dask, in this process). Finished runs are written to Parquet about once a second (:data:`FLUSH_EVERY`,
:mod:`robotdyn.sweep.store`) and at the end, also after Ctrl-C or SIGTERM, so a sweep that is interrupted and run
again computes only the runs it has not finished.

Results (``results.parquet``, :func:`load`): one row per run with its inputs (``run_id``, ``run_index``,
``robot``, ``scenario``, ``terrain``, ``torque_scale``, ``t_end`` and the varied parameters, units in each
field's metadata), ``status`` (``ok``; ``stopped`` when an event ended the run early; ``error``) and ``error``
(the message), and the outputs: the final state ``final.<column>``, ``max.<column>`` and ``min.<column>`` of the
chosen columns, ``t_reached`` [s], ``energy.start``/``energy.end`` [J], ``energy.drift`` [J] (the largest energy
change once the torques have stopped: :func:`robotdyn.sweep.chunk.energy_drift`), ``residual.max`` (the largest
holonomic residual), ``drift`` (the robot module's own invariant, where it defines ``drift``), ``nfev``, ``wall``
[s] (the integration) and ``run_wall`` [s] (the whole run). Error rows have no outputs (null), never NaN.
"""

from __future__ import annotations

import logging
import math
import sys
import time
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path

from . import store as sweep_store
from ..errors import OutputError, RobotDynError
from .batched import MODES, Batching, model_vectors
from .chunk import RunContext, load_source, run_chunk
from .plan import Plan, plan
from .spec import RunInput, SweepSpec, from_toml

FLUSH_EVERY = 1.0
"""Finished runs are written to ``OUT/runs/`` at most this often [s] (and at the end, after an interruption too):
one Parquet file per second rather than per chunk keeps the client's work small beside the workers; a process
killed outright (SIGKILL, power loss) loses at most this much of finished runs, which a rerun computes again."""
CONNECT_TIMEOUT = "20s"
"""How long to try reaching a Dask scheduler given by address."""
load = sweep_store.load
load_trajectory = sweep_store.load_trajectory


@dataclass
class SweepResult:
    """What a sweep did: its directory, the results table (pyarrow; :meth:`frame` for pandas), counts.

    Attributes:
        out: The sweep directory.
        table: The results (pyarrow table, one row per run in run order).
        total: Number of runs of the sweep.
        computed: Runs computed by this call.
        resumed: Runs found finished on disk.
        wall: Wall time [s].
        plot: The summary plot's path (``None``: not written).
        interrupted: Why the sweep stopped early (``None``: it finished).
        statuses: Number of runs by status (ok, stopped, error).
        batched: Runs simulated as variants of one compiled model.
        notes: Lines on which runs were built one at a time and why.
        phases: Wall time [s] of each phase (plan, compute, ...).
    """

    out: Path
    table: object
    total: int
    computed: int
    resumed: int
    wall: float
    plot: Path | None = None
    interrupted: str | None = None
    statuses: dict[str, int] = field(default_factory=dict)
    batched: int = 0
    notes: list[str] = field(default_factory=list)
    phases: dict[str, float] = field(default_factory=dict)

    def __repr__(self) -> str:
        return (f"SweepResult({str(self.out)!r}, runs={self.total}, computed={self.computed}, "
                f"resumed={self.resumed}, batched={self.batched}, {self.statuses}, wall={self.wall:.3g} s"
                + (", interrupted" if self.interrupted else "") + ")")

    def frame(self):
        """The results as a pandas DataFrame.

        Returns:
            The ``pandas.DataFrame`` of the result table, one row per run.
        """
        return self.table.to_pandas()


class _Progress:
    """One line on stderr at most every ``every`` seconds: runs done, errors, rate, time left."""

    def __init__(self, total: int, resumed: int, enabled: bool, every: float = 1.0) -> None:
        self.total, self.resumed, self.enabled, self.every = total, resumed, enabled, every
        self.done = self.errors = 0
        self.start = self.last = time.perf_counter()

    def __call__(self, rows: list[dict], final: bool = False) -> None:
        self.done += len(rows)
        self.errors += sum(r["status"] == "error" for r in rows)
        now = time.perf_counter()
        if not self.enabled or (now - self.last < self.every and not final):
            return
        self.last = now
        rate = self.done / max(now - self.start, 1e-9)
        left = (self.total - self.resumed - self.done) / rate if rate > 0 else float("inf")
        print(f"sweep: {self.resumed + self.done}/{self.total} runs"
              + (f" ({self.resumed} resumed)" if self.resumed else "")
              + (f", {self.errors} error(s)" if self.errors else "")
              + f", {rate:.3g} runs/s" + ("" if final else f", about {_duration(left)} left"),
              file=sys.stderr, flush=True)


def _duration(s: float) -> str:
    if not math.isfinite(s):
        return "?"
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.0f} min"


def _chunks(runs: list[RunInput], size: int, workers: int = 0) -> list[list[RunInput]]:
    """Runs in chunks of ``size``; with ``workers`` > 0, guided: each chunk a quarter of the runs left per worker
    (at most ``size``, at least 8), so that the first chunks are large and the last small and no worker waits long
    for another's last chunk."""
    if workers <= 0:
        return [runs[i:i + size] for i in range(0, len(runs), size)]
    out, i = [], 0
    while i < len(runs):
        step = min(size, max(8, math.ceil((len(runs) - i) / (4 * workers))))
        out.append(runs[i:i + step])
        i += step
    return out


def _worker_info() -> str:
    import robotdyn

    return robotdyn.__version__


WORKERS_PER_CPU = 4
"""Most local Dask worker processes per CPU (beyond it they only wait for each other; 100,000 hung the start)."""


def max_local_workers() -> int:
    """The largest number of worker processes of a local cluster: :data:`WORKERS_PER_CPU` per CPU here.

    Returns:
        The number of workers (>= 1).
    """
    import os

    return WORKERS_PER_CPU * (os.cpu_count() or 1)


SCHEMES = ("tcp", "tls", "ws", "wss", "ucx", "inproc")
"""Address schemes of a Dask scheduler (``inproc``: a cluster of threads in this process, from the API)."""


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 200 else text[:197] + "..."


def _probe(scheduler: str):
    """Check that ``scheduler`` is a Dask scheduler that answers, within :data:`CONNECT_TIMEOUT` in all (Dask's
    own connect waits for the handshake without a limit: a server that accepts and never answers hung it); returns
    the :class:`distributed.security.Security` to connect with.

    Raises:
        RobotDynError: One line naming the address: an unknown or unusable scheme (``ucx://`` without its backend,
            ``tls://`` without certificates), nothing listening, no answer in time, or an answer that is not a
            Dask scheduler's (an HTTP server, garbage).
    """
    import asyncio
    import importlib.util

    from dask.utils import parse_timedelta
    from distributed.comm import connect
    from distributed.comm.addressing import parse_address
    from distributed.security import Security

    def fail(why: str):
        raise RobotDynError(f"cannot reach the Dask scheduler at {scheduler!r} ({why}); expected an address like "
                            "tcp://HOST:8786 of a running scheduler")

    try:
        scheme, _ = parse_address(scheduler)
    except (ValueError, TypeError) as exc:
        fail(_short(exc))
    if scheme not in SCHEMES:
        fail(f"unknown address scheme {scheme!r}; expected one of {', '.join(s + '://' for s in SCHEMES)}")
    if scheme == "ucx" and not any(importlib.util.find_spec(m) for m in ("distributed_ucxx", "ucp")):
        fail("ucx:// needs Dask's UCX backend (distributed-ucxx), which is not installed")
    security = Security()
    if scheme == "inproc":  # this process's own cluster: nothing on the network to probe
        return security
    if scheme in ("tls", "wss") and security.tls_client_cert is None and security.tls_ca_file is None:
        fail(f"{scheme}:// needs TLS certificates, and Dask's configuration gives none (distributed.comm.tls: "
             "ca-file, client.cert, client.key)")
    seconds = parse_timedelta(CONNECT_TIMEOUT, default="seconds")

    async def identity():
        comm = await connect(scheduler, timeout=seconds, **security.get_connection_args("client"))
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        reply = asyncio.run(asyncio.wait_for(identity(), seconds))
    except (TimeoutError, asyncio.TimeoutError):
        fail(f"no answer within {CONNECT_TIMEOUT}")
    except MemoryError:  # garbage read as Dask's frame header announces exabytes
        fail("it answered, but not in Dask's protocol (an HTTP server or another service?)")
    except Exception as exc:  # noqa: BLE001 - refused, reset, garbage
        fail(f"{type(exc).__name__}: {_short(exc)}")
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        fail(f"it answered, but not as a Dask scheduler ({_short(repr(reply))})")
    return security


def _connect(stack: ExitStack, workers: int, scheduler: str | None):
    """A Dask client: on the cluster of ``scheduler``, or on a new LocalCluster of ``workers`` processes."""
    from dask.distributed import Client, LocalCluster

    import robotdyn

    if scheduler is not None:
        security = _probe(scheduler)
        try:
            client = stack.enter_context(Client(scheduler, timeout=CONNECT_TIMEOUT, security=security))
        except Exception as exc:  # noqa: BLE001 - whatever the address answered, one line naming it
            raise RobotDynError(f"cannot reach the Dask scheduler at {scheduler!r} ({type(exc).__name__}: "
                                f"{_short(exc)}); expected an address like tcp://HOST:8786 of a running "
                                "scheduler") from None
        try:
            versions = client.run(_worker_info)
        except Exception as exc:
            raise RobotDynError(f"the Dask workers at {scheduler!r} cannot run robotdyn ({type(exc).__name__}: "
                                f"{exc}); expected robotdyn {robotdyn.__version__} installed on every worker") from None
        if not versions:
            raise RobotDynError(f"the Dask scheduler at {scheduler!r} has no workers; expected at least one")
        other = {w: v for w, v in versions.items() if v != robotdyn.__version__}
        if other:
            raise RobotDynError(f"Dask workers run another robotdyn ({other}); expected {robotdyn.__version__}")
        return client
    if workers < 1:
        raise RobotDynError(f"workers = {workers}; expected at least 1 (or 0: in this process, without Dask)")
    cluster = stack.enter_context(LocalCluster(
        n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
        dashboard_address="127.0.0.1:0",  # the scheduler's HTTP server on a free local port, never a fixed one
        silence_logs=logging.ERROR, preload=["robotdyn.sweep.batched"]))  # each worker imports robotdyn once
    return stack.enter_context(Client(cluster))


def _execute(chunks, ctx: RunContext, vectors: dict, workers: int, scheduler: str | None, client,
             on_chunk, phases: dict) -> None:
    """Run the chunks (in this process, or on Dask) and hand each finished one to ``on_chunk(runs, results)``;
    each chunk carries the model vectors of its batched runs (``vectors``: run id -> vector). ``phases`` gets the
    wall times [s] of starting or reaching the cluster (``connect``) and of the runs (``runs``: first
    submission to last result)."""
    def mine(chunk):
        return {r.run_id: vectors[r.run_id] for r in chunk if r.run_id in vectors}

    if client is None and scheduler is None and workers == 0:
        begin = time.perf_counter()
        for chunk in chunks:
            on_chunk(chunk, run_chunk(ctx, chunk, mine(chunk)))
        phases["runs"] = time.perf_counter() - begin
        return
    from dask.distributed import as_completed
    from distributed.scheduler import KilledWorker

    with ExitStack() as stack:
        if client is None:
            begin = time.perf_counter()
            client = _connect(stack, workers, scheduler)
            phases["connect"] = time.perf_counter() - begin
        begin = time.perf_counter()
        futures = {}
        for chunk in chunks:
            futures[client.submit(run_chunk, ctx, chunk, mine(chunk), pure=False)] = chunk
        pending = as_completed(list(futures))
        try:
            for fut in pending:
                chunk = futures.pop(fut)
                try:
                    results = fut.result()
                except KilledWorker as exc:  # a run took its worker process down: isolate it
                    if len(chunk) > 1:
                        for run in chunk:
                            single = client.submit(run_chunk, ctx, [run], mine([run]), pure=False)
                            futures[single] = [run]
                            pending.add(single)
                        continue
                    results = [({"run_id": chunk[0].run_id, "status": "error",
                                 "error": f"the worker process died during this run ({exc})"}, None)]
                on_chunk(chunk, results)
        finally:
            phases["runs"] = time.perf_counter() - begin
            client.cancel(list(futures))


def run(spec: SweepSpec | str | Path, out="sweep", workers: int = 1, scheduler: str | None = None,
        chunk_size: int | None = None, progress: bool = True, retry_errors: bool = False, plot: bool = True,
        client=None, batch: str = "auto", replace: bool = False) -> SweepResult:
    """Run a sweep and write its results to the directory ``out`` (see the module docstring).

    Args:
        spec: A :class:`~robotdyn.sweep.spec.SweepSpec` or the path of a sweep TOML file.
        out: The sweep directory (created; a rerun there resumes: finished runs are not computed again).
        workers: Worker processes of the local Dask cluster (0: in this process, without Dask).
        scheduler: Address of a running Dask scheduler (e.g. ``tcp://host:8786``) instead of a local cluster.
        chunk_size: Runs per Dask task (default: about 32 tasks per worker, at most 32 runs each, so that the
            last tasks leave no worker idle for long; where most runs are batched, guided chunks of at most 256
            runs, each a quarter of the runs left per worker, at least 8).
        progress: Progress lines on stderr.
        retry_errors: Compute the runs again whose rows on disk are errors (others are kept).
        plot: Write ``summary.png`` (the plot column against each varied parameter).
        client: An existing ``dask.distributed.Client`` to use.
        batch: ``auto``, ``always`` or ``never``: whether runs that vary only numbers of the model are simulated
            together as variants of one compiled model (:mod:`robotdyn.sweep.batched`; ``never``: each run built
            from its parameters).
        replace: Delete the results of another sweep found in ``out`` (else that is an error: a directory whose
            rows are not all runs of this sweep, e.g. another specification, or this one after an input changed).

    Raises:
        OutputError: ``out`` is being written by another sweep (locked), or holds another sweep's results and
            ``replace`` is false.

    Returns:
        A :class:`SweepResult`; after an interruption (Ctrl-C) it holds what was finished, with ``interrupted``
        saying so: running the same sweep again resumes.

    Example:
        >>> from robotdyn.sweep import load, run
        >>> from robotdyn.sweep.spec import SweepSpec, parse_axis
        >>> spec = SweepSpec(robot="quasimoro", axes=[parse_axis("M=4:6:3")], t_end=0.2)
        >>> result = run(spec, "sweep_out", workers=0, progress=False, plot=False)
        >>> result.total, result.statuses
        (3, {'ok': 3, 'stopped': 0, 'error': 0})
        >>> load("sweep_out").sort_values("M")["M"].tolist()
        [4.0, 5.0, 6.0]
    """
    if batch not in MODES:
        raise RobotDynError(f"batch = {batch!r}; expected one of {', '.join(MODES)}")
    spec = from_toml(spec) if isinstance(spec, (str, Path)) else spec
    start = time.perf_counter()
    p = plan(spec)
    phases = {"plan": time.perf_counter() - start}
    if scheduler is not None and client is None:
        _probe(scheduler)  # a wrong address is one line before anything is written or shown
    elif client is None and workers > max_local_workers():
        raise RobotDynError(f"workers = {workers}: more local worker processes than this machine runs usefully; "
                            f"expected at most {max_local_workers()} ({WORKERS_PER_CPU} per CPU), or a scheduler")
    out = sweep_store.prepare(out)
    held = sweep_store.lock(out)  # one sweep at a time per directory
    try:
        return _run_locked(spec, p, out, start, phases, workers, scheduler, chunk_size, progress, retry_errors, plot,
                           client, batch, replace)
    finally:
        held.release()


def _run_locked(spec, p, out, start, phases, workers, scheduler, chunk_size, progress, retry_errors, plot, client,
                batch, replace) -> SweepResult:
    """:func:`run` once the sweep directory ``out`` is locked."""
    done = sweep_store.finished(out)
    other = sweep_store.foreign(out, done, {r.run_id for r in p.runs}, spec.to_dict())
    if other is not None:
        if not replace:
            raise OutputError(f"sweep directory {str(out)!r} holds another sweep ({other}); expected a new directory, "
                              "or --replace (run(..., replace=True)) to delete its results")
        sweep_store.clear(out)
        done = {}
    todo = [r for r in p.runs if r.run_id not in done or (retry_errors and done[r.run_id] == "error")]
    resumed = len(p.runs) - len(todo)
    sweep_store.write_json(out / "sweep.json", {"spec": spec.to_dict(), "runs": len(p.runs)})
    n_workers = workers
    if client is not None:
        n_workers = len(client.scheduler_info()["workers"]) or 1
    begin = time.perf_counter()
    batching = model_vectors(p.context, p.runs, batch) if todo else Batching({}, [])  # all runs: resumes fit alike
    phases["fit"] = time.perf_counter() - begin
    # batched runs cost a few ms each: bigger chunks, fewer tasks and Parquet files (still 8 tasks per worker)
    mostly_batched = 2 * sum(r.run_id in batching.vectors for r in todo) > len(todo)
    tasks, cap = (4, 256) if mostly_batched else (32, 32)
    size = chunk_size or max(1, min(cap, math.ceil(len(todo) / (tasks * max(n_workers, 1)))))
    guided = max(n_workers, 1) if mostly_batched and not chunk_size else 0
    if size < 1:
        raise RobotDynError(f"chunk_size = {chunk_size}; expected at least 1 run per chunk")
    report = _Progress(len(p.runs), resumed, progress)
    inputs = {r.run_id: p.inputs(r) for r in p.runs}

    pending: list = []  # finished runs not yet on disk: (row, trajectory)
    flushed = [-math.inf]  # the first finished chunk is written at once, later ones at most every FLUSH_EVERY

    def flush() -> None:
        if pending:
            sweep_store.write_chunk(out, [r for r, _ in pending], [t for _, t in pending], p.schema)
            pending.clear()
        flushed[0] = time.perf_counter()

    def on_chunk(chunk: list[RunInput], results) -> None:
        rows = [{**inputs[row["run_id"]], **row} for row, _ in results]
        pending.extend(zip(rows, [traj for _, traj in results]))
        if time.perf_counter() - flushed[0] >= FLUSH_EVERY:
            flush()
        report(rows)

    interrupted = None
    try:
        if todo:
            _execute(_chunks(todo, size, guided), p.context, batching.vectors, workers, scheduler, client,
                     on_chunk, phases)
    except KeyboardInterrupt:
        interrupted = (f"interrupted after {resumed + report.done} of {len(p.runs)} runs; run the same sweep again "
                       "to resume")
    finally:
        flush()  # also after Ctrl-C or SIGTERM: every finished run is kept
        if todo and progress:
            report([], final=True)
    table = sweep_store.consolidate(out, {r.run_id: r.index for r in p.runs}, p.schema)
    statuses = {s: table.column("status").to_pylist().count(s) for s in ("ok", "stopped", "error")}
    image = None
    if plot and table.num_rows:
        from .plot import plot_summary

        image = plot_summary(table, p, out / "summary.png")
    return SweepResult(out, table, len(p.runs), report.done, resumed, time.perf_counter() - start, image,
                       interrupted, statuses, sum(r.run_id in batching.vectors for r in todo), batching.reasons,
                       phases)


__all__ = ["run", "plan", "load", "load_trajectory", "SweepResult", "SweepSpec", "Plan", "load_source"]

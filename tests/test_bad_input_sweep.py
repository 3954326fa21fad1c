"""Bad inputs of ``robotdyn sweep`` (issue 24): scheduler addresses that are not a Dask scheduler, sweep files that
are FIFOs or devices, flags that were silently unused, out-of-range numbers, repeated columns, and a sweep directory
holding an unreadable results file. Each is one line naming the entry (exit status 2) in bounded time, before any
run is computed.

The test servers listen on 127.0.0.1 only, on a free port, and stop by themselves after a few seconds.
"""

from __future__ import annotations

import os
import socket
import threading
import time
from pathlib import Path

import pytest

import cli_run
from robotdyn.cli.commands import main
from robotdyn.sweep import runner

SECONDS = 20
SW = ["sweep", "quasimoro", "--vary", "M=4,5", "--t-end", "0.2", "--workers", "0", "--quiet", "--no-plot"]


def refused(argv, capsys, *needles) -> float:
    """``main(argv)`` ends with exit status 2 and one line holding every needle; returns its wall time [s]."""
    rc, err, wall = cli_run.run_cli(argv, capsys, SECONDS)
    lines = [line for line in err.splitlines() if not line.startswith("robotdyn: warning: ")]
    assert rc == 2, err
    assert len(lines) == 1 and lines[0].startswith("robotdyn: error: "), err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return wall


# ------------------------------------------------------------------------------------------------ schedulers
class Server:
    """A TCP server on 127.0.0.1 (a free port) that answers every connection by ``mode``: ``http`` (an HTTP
    response), ``garbage`` (random bytes) or ``silent`` (accepts, never answers); it stops after ``life`` s."""

    def __init__(self, mode: str, life: float = 8.0) -> None:
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.sock.settimeout(0.2)
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.mode, self.end, self.conns = mode, time.monotonic() + life, []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while time.monotonic() < self.end:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            self.conns.append(conn)
            try:
                if self.mode == "http":
                    conn.settimeout(1.0)
                    try:
                        conn.recv(4096)
                    except OSError:
                        pass
                    conn.sendall(b"HTTP/1.0 200 OK\r\nContent-Length: 5\r\n\r\nhello")
                elif self.mode == "garbage":
                    conn.sendall(b"\x00\xff not dask \x13\x37" * 64)
            except OSError:
                pass
        for conn in self.conns:
            conn.close()
        self.sock.close()


@pytest.fixture
def short_timeout(monkeypatch):
    monkeypatch.setattr(runner, "CONNECT_TIMEOUT", "1s")


@pytest.mark.parametrize("mode", ["http", "garbage", "silent"])
def test_scheduler_address_that_is_not_a_scheduler(mode, tmp_path, capsys, short_timeout):
    """An HTTP server and a server sending garbage traced back (a MemoryError: garbage read as a frame of
    exabytes); a server that accepts and never answers hung (Dask waits for its handshake without a limit)."""
    server = Server(mode)
    seconds = refused([*SW, "--out", tmp_path / "s", "--scheduler", server.address], capsys, server.address)
    assert seconds < 8
    assert not (tmp_path / "s" / "results.parquet").exists()


@pytest.mark.parametrize("address, needle", [("ucx://127.0.0.1:9", "UCX"), ("tls://127.0.0.1:9", "certificates"),
                                             ("http://127.0.0.1:9", "scheme")])
def test_scheduler_schemes_that_cannot_work(address, needle, tmp_path, capsys, short_timeout):
    """ucx:// without its backend and tls:// without certificates traced back (TypeError)."""
    refused([*SW, "--out", tmp_path / "s", "--scheduler", address], capsys, address, needle)


# ---------------------------------------------------------------------------------------------- sweep files
def test_spec_fifo_and_device(tmp_path, capsys):
    """A sweep file that is a FIFO hung (reading it blocks); /dev/zero ended in a MemoryError."""
    fifo = tmp_path / "spec.toml"
    os.mkfifo(fifo)
    refused(["sweep", "--spec", fifo, "--workers", "0", "--out", tmp_path / "s"], capsys, str(fifo), "named pipe")
    refused(["sweep", "--spec", "/dev/zero", "--workers", "0", "--out", tmp_path / "s"], capsys, "/dev/zero", "device")


def test_spec_too_large(tmp_path, capsys):
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * 1_100_000 + "\n")
    refused(["sweep", "--spec", big, "--workers", "0", "--out", tmp_path / "s"], capsys, "big.toml", "bytes")


def test_spec_terrain_nan_is_refused(tmp_path, capsys):
    """terrains = [{kind = "flat", height = nan}] gave rows marked ok."""
    spec = tmp_path / "spec.toml"
    spec.write_text('robot = "quasimoro"\nt_end = 0.2\nterrains = [{kind = "flat", height = nan}]\n'
                    "[parameters]\nM = [4.0, 5.0]\n")
    refused(["sweep", "--spec", spec, "--workers", "0", "--quiet", "--no-plot", "--out", tmp_path / "s"], capsys,
            "height = nan")
    assert not (tmp_path / "s" / "results.parquet").exists()


# --------------------------------------------------------------------------------------------------- flags
@pytest.mark.parametrize("extra, needles", [
    (["--workers", "100000"], ["--workers 100000", "at most"]),
    (["--sample", "random", "--n", "2", "--vary", "d=0.1:0.3", "--seed", "-1"], ["seed = -1"]),
    (["--terrain", "bump:width=0"], ["width"]),
    (["--terrain", "bump:height=0.05,width=0"], ["width = 0.0"]),
    (["--terrain", "ramp:slope=nan"], ["slope = nan"]),
    (["--terrain", "flat:height=inf"], ["height = inf"]),
    (["--vary", "torque_scale=1e308"], ["torque_scale", "1e308"]),
    (["--column", "theta1", "--column", "theta1"], ["column 'theta1' listed 2 times"]),
    (["--twist", "body"], ["--twist"]),
    (["--package", "/tmp"], ["--package"]),
    (["--xacro-arg", "r=0.2"], ["xacro argument 'r'", "--param"]),
])
def test_sweep_flags_refused_before_running(extra, needles, tmp_path, capsys, monkeypatch):
    """Each traced back, hung (--workers 100000), computed every run before crashing (a repeated --column) or
    was accepted and never used (--twist, --package, --xacro-arg with a built-in robot); now one line, nothing
    computed."""
    monkeypatch.setattr(runner, "run_chunk", lambda *a, **k: pytest.fail("a run was computed"))
    argv = [*SW, "--out", tmp_path / "s", *extra]
    if "--workers" in extra:
        argv[argv.index("--workers")] = "--chunk-size"  # (the base's --workers 0 replaced by a harmless flag)
        argv[argv.index("--chunk-size") + 1] = "4"
    refused(argv, capsys, *needles)
    assert not (tmp_path / "s" / "results.parquet").exists()


def test_directory_with_a_results_file_of_repeated_columns_still_works(tmp_path, capsys):
    """A chunk file with two columns of one name (what a repeated --column wrote before it was refused) made
    every later sweep into that directory crash in pyarrow; it is now ignored with a warning naming it, its runs
    computed again, and the sweep finishes."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = tmp_path / "s"
    (out / "runs").mkdir(parents=True)
    bad = out / "runs" / "part-0000000000000000.parquet"
    table = pa.Table.from_arrays([pa.array(["x"]), pa.array(["ok"]), pa.array([1.0]), pa.array([1.0])],
                                 names=["run_id", "status", "max.theta1", "max.theta1"])
    pq.write_table(table, bad)
    assert main([*SW, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert str(bad) in err and "repeated columns" in err
    assert pq.read_table(out / "results.parquet").num_rows == 2


def test_api_refuses_too_many_local_workers(tmp_path):
    """sweep.run(..., workers=100000) hung starting the processes; refused before anything is written."""
    from robotdyn.errors import RobotDynError
    from robotdyn.sweep.spec import SweepSpec, parse_axis

    spec = SweepSpec(robot="quasimoro", axes=[parse_axis("M=4,5")], t_end=0.2)
    with pytest.raises(RobotDynError, match="workers = 100000"):
        runner.run(spec, tmp_path / "s", workers=100_000, progress=False, plot=False)
    assert not (tmp_path / "s").exists()

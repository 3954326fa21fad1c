"""Streamed and atomic output files (issue 24): a streamed run's rows are on disk as they are computed, in the
visible ``<target>.partial`` (left with its rows by SIGKILL; the target replaced only by a finished or marked
file), the ``# partial`` marker states the time of the last row on disk whatever the interruption hit, and every
file keeps the user's umask (before: mode 0600 always, a replaced 0644 file became 0600)."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import robotdyn
import robotdyn.robots.quasimoro.model as qm
from robotdyn.errors import OutputError
from robotdyn.output import atomic_output
from robotdyn.simulation.streaming import CsvSink

SC = qm.SCENARIOS["pure_rotation"]


@pytest.fixture(scope="module")
def robot():
    return robotdyn.load("quasimoro")


def test_marker_states_the_last_row_when_formatting_is_interrupted(robot, tmp_path, monkeypatch):
    """SIGTERM (KeyboardInterrupt) while a chunk of rows is being formatted: before, the interruption escaped
    _write and the marker said "interrupted at t = 0 s: samples up to t = 0 s" below 1998.8 s of rows. Here chunks
    of 10 rows, the third chunk's formatting interrupted: 20 rows (t = 0 .. 0.95 s on the 0.05 s grid) on disk,
    and the marker, the result's t, samples and final state say exactly that."""
    monkeypatch.setattr("robotdyn.simulation.streaming.CHUNK", 10)
    real, calls = np.savetxt, []

    def savetxt(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(np, "savetxt", savetxt)
    path = tmp_path / "run.csv"
    res = SC.run(robot, t_end=5.0, n_out=101, progress=False, sink=CsvSink(path, segment=101))
    monkeypatch.undo()
    lines = path.read_text().splitlines()
    data = np.loadtxt(lines[1:-1], delimiter=",")
    assert len(data) == 20 and data[-1, 0] == pytest.approx(0.95, abs=1e-12)
    assert lines[-1] == "# partial: interrupted while writing: samples up to t = 0.95 s of 5 s"
    assert res.t == data[-1, 0] and res.samples == 20
    n, k = robot.nq, robot.mobility
    np.testing.assert_array_equal(res.q, data[-1, 1:1 + n])
    np.testing.assert_array_equal(res.nu, data[-1, 1 + n:1 + n + k])
    assert not (tmp_path / "run.csv.partial").exists()


def test_rows_are_in_a_visible_partial_file_during_the_run(robot, tmp_path):
    """During the run the finished segments' rows are in ``run.csv.partial`` (before: a hidden temporary file, no
    row visible) and the old target is untouched until the end, when the finished file replaces it."""
    path = tmp_path / "run.csv"
    path.write_text("old\n")
    seen = []

    def columns(traj):
        partial = tmp_path / "run.csv.partial"
        rows = partial.read_text().splitlines()[1:] if partial.exists() else None
        seen.append((float(traj.t[0]), None if rows is None else len(rows), path.read_text(),
                     sorted(p.name for p in tmp_path.iterdir())))
        return {}

    SC.run(robot, t_end=5.0, n_out=101, progress=False, sink=CsvSink(path, columns, segment=51))
    # segment 1 is samples 0..50, segment 2 samples 50..100: when segment 2's columns are computed, 51 rows are out
    assert seen[1][0] == pytest.approx(2.5) and seen[1][1] == 51
    assert seen[1][2] == "old\n" and seen[1][3] == ["run.csv", "run.csv.partial"]
    assert len(path.read_text().splitlines()) == 102 and sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]


def test_sigkill_leaves_the_visible_partial_file(tmp_path):
    """A run killed hard mid-run leaves ``run.csv.partial`` with whole rows of the grid, and the target as it was."""
    path = tmp_path / "run.csv"
    path.write_text("old\n")
    script = textwrap.dedent(f"""
        import os, signal
        import robotdyn, robotdyn.robots.quasimoro.model as qm
        from robotdyn.simulation.streaming import CsvSink
        def columns(traj):
            if traj.t[0] > 2.99:  # the fourth segment (samples 60..80): rows 0..60 are out
                os.kill(os.getpid(), signal.SIGKILL)
            return {{}}
        qm.SCENARIOS["pure_rotation"].run(robotdyn.load("quasimoro"), t_end=5.0, n_out=101, progress=False,
                                          sink=CsvSink({str(path)!r}, columns, segment=21))
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == -9, proc.stderr
    assert path.read_text() == "old\n"
    data = np.loadtxt(tmp_path / "run.csv.partial", delimiter=",", skiprows=1)
    assert len(data) == 61 and np.array_equal(data[:, 0], np.linspace(0.0, 5.0, 101)[:61])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv", "run.csv.partial"]


def test_a_second_writer_of_the_same_target_is_refused(tmp_path):
    from robotdyn.output import visible_output

    path = tmp_path / "run.csv"
    with visible_output(path, "CSV file") as (partial, f):
        f.write(b"t\n")
        f.flush()
        with pytest.raises(OutputError, match="another process is writing it") as err:
            with visible_output(path, "CSV file"):
                pass
        assert "\n" not in str(err.value)
        assert partial.read_bytes() == b"t\n"
    assert path.read_bytes() == b"t\n"


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_output_files_keep_the_umask(robot, tmp_path, umask, mode):
    """Before, every output file was created 0600 (tempfile.mkstemp), and replacing a 0644 file made it 0600."""
    old = os.umask(umask)
    try:
        for name in ("a.txt", "b.csv"):
            (tmp_path / name).write_text("x")
            os.chmod(tmp_path / name, 0o644)
        with atomic_output(tmp_path / "a.txt") as tmp:
            tmp.write_text("new")
        with atomic_output(tmp_path / "new.txt") as tmp:
            tmp.write_text("new")
        SC.run(robot, t_end=1.0, n_out=11, progress=False, sink=CsvSink(tmp_path / "b.csv", segment=6))
    finally:
        os.umask(old)
    for name in ("a.txt", "new.txt", "b.csv"):
        assert stat.S_IMODE(os.stat(tmp_path / name).st_mode) == mode, name

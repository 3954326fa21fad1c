"""Long runs streamed to CSV in segments (robotdyn.simulation.streaming, issue 15): the same samples as one
in-memory run up to the integrator's restart at the segment boundaries, checked against Quasimoro's closed-form
free rotation; memory bounded independently of the duration; an interrupted run leaves a partial-marked prefix;
the in-memory sample limit still refuses in one line where nothing can be streamed."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
import tracemalloc

import numpy as np
import pytest

import robotdyn
import robotdyn.robots.quasimoro.model as qm
from robotdyn.cli import main
from robotdyn.simulation import simulate
from robotdyn.simulation.streaming import CsvSink

SC = qm.SCENARIOS["pure_rotation"]  # m1 = -m2 = 0.1 sin(pi t) N m for t <= 1 s, then free
TOL = 1e-8
"""Streamed vs one run: both integrate at rtol 1e-10, atol 1e-12 over O(1) values, and each restart costs a fresh
error history of that size; 1e-8 leaves two orders for the accumulation over 40 restarts, while an off-by-one row
or a state not carried (the wheels restarting at rest) would be off by O(1)."""


@pytest.fixture(scope="module")
def robot():
    return robotdyn.load("quasimoro")


def _closed_form_errors(robot, t, q, nu) -> float:
    """Largest deviation from the free pure rotation after the pulse (t > 1 s): x, y and theta3 stay zero, the
    wheel rates stay at their value at the end of the pulse, theta1 grows linearly, theta2 = -theta1."""
    col = {n: q[:, i] for i, n in enumerate(robot.coordinates)}
    col |= {n: nu[:, i] for i, n in enumerate(robot.velocity_names)}
    free = t > 1.0
    rate = col["theta1_dot"][free]
    line = col["theta1"][free] - col["theta1"][free][0] - rate[0] * (t[free] - t[free][0])
    return max(np.max(np.abs(col["x"])), np.max(np.abs(col["y"])), np.max(np.abs(col["theta3"])),
               np.max(np.abs(rate - rate[0])), np.max(np.abs(line)),
               np.max(np.abs(col["theta1"] + col["theta2"])))


@pytest.mark.parametrize("engine", ["compiled", "scipy"])
def test_streamed_run_matches_one_run_and_the_closed_form(robot, tmp_path, engine):
    one = SC.run(robot, t_end=20.0, n_out=2001, progress=False, engine=engine)
    path = tmp_path / "s.csv"
    res = SC.run(robot, t_end=20.0, n_out=2001, progress=False, engine=engine, sink=CsvSink(path, segment=50))
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    n, k = robot.nq, robot.mobility
    assert res.stats["segments"] == 41 and res.samples == 2001 and "partial" not in res.stats
    assert np.array_equal(data[:, 0], np.linspace(0.0, 20.0, 2001))  # the in-memory grid, each time once
    assert np.max(np.abs(data[:, 1:] - np.column_stack([one.q, one.nu]))) < TOL
    # both against the closed form of the free rotation (theta1_dot about 0.3 rad/s: a state not carried fails)
    assert abs(one.column("theta1_dot")[-1]) > 0.1
    assert _closed_form_errors(robot, one.t, one.q, one.nu) < 1e-9
    assert _closed_form_errors(robot, data[:, 0], data[:, 1:1 + n], data[:, 1 + n:1 + n + k]) < 1e-9
    assert abs(res.energy_end - one.energy[-1]) < 1e-9 and res.t == 20.0


def test_one_segment_is_the_in_memory_file(robot, tmp_path):
    """With a segment as long as the run nothing restarts: byte for byte what Trajectory.to_csv writes."""
    SC.run(robot, t_end=5.0, n_out=101, progress=False).to_csv(tmp_path / "m.csv")
    SC.run(robot, t_end=5.0, n_out=101, progress=False, sink=CsvSink(tmp_path / "s.csv", segment=101))
    assert (tmp_path / "m.csv").read_bytes() == (tmp_path / "s.csv").read_bytes()


def test_cli_streams_with_traction_columns(tmp_path, monkeypatch, capsys):
    """Above a segment's worth of samples `simulate --csv` streams: the same header (traction columns included)
    and the same rows as the in-memory run of the same command."""
    assert main(["simulate", "quasimoro", "--scenario", "pure_rotation", "--t-end", "12", "--quiet", "--csv",
                 str(tmp_path / "m.csv")]) == 0
    monkeypatch.setattr("robotdyn.simulation.streaming.SEGMENT", 64)
    assert main(["simulate", "quasimoro", "--scenario", "pure_rotation", "--t-end", "12", "--quiet", "--csv",
                 str(tmp_path / "s.csv"), "--json"]) == 0
    assert '"streamed": true' in capsys.readouterr().out
    head_m, head_s = ((tmp_path / f).read_text().splitlines()[0] for f in ("m.csv", "s.csv"))
    assert head_m == head_s and "normal" in head_s
    m = np.loadtxt(tmp_path / "m.csv", delimiter=",", skiprows=1)
    s = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1)
    assert m.shape == s.shape == (240, len(head_s.split(",")))
    assert np.max(np.abs(m - s)) < 1e-6 * max(1.0, np.max(np.abs(m)))  # loads [N] ~ 50: relative


def test_memory_bounded_independently_of_duration(robot, tmp_path):
    """tracemalloc peak of a streamed run is that of one segment: 4x the duration (4x the segments) does not
    raise it, and it stays far below the in-memory run of the longer duration."""
    def peak(t_end: float, sink: bool) -> int:
        n_out = int(round(20 * t_end)) + 1
        tracemalloc.start()
        try:
            if sink:
                SC.run(robot, t_end=t_end, n_out=n_out, progress=False, sink=CsvSink(tmp_path / "p.csv", segment=2000))
            else:
                SC.run(robot, t_end=t_end, n_out=n_out, progress=False)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    short, long = peak(500.0, True), peak(2000.0, True)  # 5 and 20 segments of 2000 samples
    assert long < 1.2 * short + 200_000
    assert long < 4_000_000  # 2000 samples x 15 columns x 8 B = 0.24 MB per copy
    assert peak(2000.0, False) > 2 * long  # the in-memory run grows with the duration (the test can fail)


def test_sigterm_leaves_a_partial_prefix(robot, tmp_path):
    csv = tmp_path / "run.csv"
    script = textwrap.dedent(f"""
        import signal
        import robotdyn, robotdyn.robots.quasimoro.model as qm
        from robotdyn.simulation.streaming import CsvSink
        def stop(signum, frame):
            raise KeyboardInterrupt
        signal.signal(signal.SIGTERM, stop)
        res = qm.SCENARIOS["pure_rotation"].run(robotdyn.load("quasimoro"), t_end=5000.0, n_out=100001,
                                                sink=CsvSink({str(csv)!r}, segment=500))
        print(res.stats.get("partial"))
    """)
    env = {**os.environ, "ROBOTDYN_COMPILED": "0"}  # the Python path: slow enough to be stopped mid-run
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env)
    deadline = time.time() + 120
    for line in proc.stderr:  # a segment or more written
        if line.startswith("simulate: t =") or time.time() > deadline:
            break
    time.sleep(0.3)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert out.startswith("interrupted")
    lines = csv.read_text().splitlines()
    assert lines[0].startswith("t,") and lines[-1].startswith("# partial: interrupted")
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert 500 <= len(data) < 100001
    assert np.array_equal(data[:, 0], np.linspace(0.0, 5000.0, 100001)[:len(data)])  # a prefix of the grid
    ref = simulate(robot, data[-1, 0], *SC.initial_state(robot), SC.torque, times=data[:, 0], progress=False,
                   engine="scipy")
    assert np.max(np.abs(data[:, 1:] - np.column_stack([ref.q, ref.nu]))) < TOL


@pytest.mark.parametrize("extra", [[], ["--csv", "{d}/o.csv", "--plot", "{d}/o.png"]])
def test_in_memory_limit_still_refused_in_one_line(tmp_path, capsys, extra):
    """Without --csv (or with a plot, which needs every sample in memory) 10^6 s at 20 samples/s is refused."""
    argv = ["simulate", "quasimoro", "--scenario", "pure_rotation", "--t-end", "1e6", "--quiet"]
    assert main(argv + [a.replace("{d}", str(tmp_path)) for a in extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "expected 2 to 5,000,000 samples" in err[0] and "--csv" in err[0]
    assert not (tmp_path / "o.csv").exists()

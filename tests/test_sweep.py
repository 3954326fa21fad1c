"""Sweeps (issue 17): numbers against closed forms and direct simulations, bit-for-bit identity between the
in-process run and 1 or 2 Dask workers (with the cluster gone afterwards), resuming after an interruption, error
rows, seeded samples, and one-line errors for bad specifications."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import psutil
import pytest

import robotdyn
from robotdyn.sweep import runner as sweep, chunk as sweep_chunk
from robotdyn.cli.commands import main
from robotdyn.robots import module
from robotdyn.sweep.plan import plan
from robotdyn.sweep.spec import Axis, SweepSpec, SweepSpecError, from_toml, parse_axis, parse_value, points

QUASIMORO = module("quasimoro")
T_END = 1.5
TIMES = ("wall", "run_wall")  # wall-clock times: the only columns allowed to differ between two runs


def small_spec(**kw) -> SweepSpec:
    """2 masses x 2 torque scales x 2 scenarios = 8 runs of 1.5 s."""
    base = dict(robot="quasimoro", axes=[parse_axis("M=4,6"), parse_axis("torque_scale=0.5,1")],
                scenarios=["rectilinear", "pure_rotation"], t_end=T_END, columns=["theta3", "theta1_dot"])
    return SweepSpec(**{**base, **kw})


def numbers(table) -> dict:
    """Every column but the wall-clock times, as plain Python values (floats compared exactly)."""
    return {k: v for k, v in table.to_pydict().items() if k not in TIMES}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The small sweep computed in this process, without Dask."""
    return sweep.run(small_spec(), tmp_path_factory.mktemp("ref"), workers=0, progress=False)


def test_pure_rotation_rows_match_the_closed_form(reference):
    """Pure rotation (m1 = -m2): theta3 stays 0 and theta1'' = m1 / I with I = m r^2 (3/2 + rho^2) + 2 rho^2 J1
    (Lagrange, independent of the body mass M), so after the pulse theta1' = s 0.2 / (pi I) and the kinetic
    energy gained is I theta1'^2."""
    p = QUASIMORO.SPEC
    m, r, rho, J1 = (p.parameter(k).default for k in ("m", "r", "rho", "J1"))
    inertia = m * r**2 * (1.5 + rho**2) + 2 * rho**2 * J1
    df = reference.frame()
    rot = df[df.scenario == "pure_rotation"]
    assert len(rot) == 4 and set(rot.status) == {"ok"}
    for _, row in rot.iterrows():
        rate = row.torque_scale * 0.2 / (np.pi * inertia)
        assert row["final.theta1_dot"] == pytest.approx(rate, rel=1e-8)
        assert row["final.theta1"] == pytest.approx(row.torque_scale * 0.1 / (np.pi * inertia) + (T_END - 1) * rate,
                                                    rel=1e-8)
        assert row["energy.end"] - row["energy.start"] == pytest.approx(inertia * rate**2, rel=1e-7)
        assert abs(row["max.theta3"]) < 1e-12 and abs(row["min.theta3"]) < 1e-12
        assert row["energy.drift"] < 1e-9 and row["drift"] < 1e-9  # torque-free after t = 1 s; psi = rho (th2 - th1)


def test_rows_are_the_direct_simulation(reference):
    """Each rectilinear row holds the numbers of the same run through the public API (scenario with scaled
    torques), bit for bit; energy.drift is the energy change after the pulse."""
    df = reference.frame()
    sc = QUASIMORO.SCENARIOS["rectilinear"]
    for _, row in df[df.scenario == "rectilinear"].iterrows():
        s = row.torque_scale
        scaled = dataclasses.replace(sc, torque=sc.torque.scaled(s))  # a profile: the compiled engine, as the sweep
        traj = scaled.run(robotdyn.load("quasimoro", {"M": row.M}), t_end=T_END, progress=False)
        final = np.concatenate([traj.q[-1], traj.nu[-1]])
        assert [row[f"final.{c}"] for c in traj.coordinates + traj.velocity_names] == final.tolist()
        assert row["max.theta3"] == traj.column("theta3").max() and row["min.theta1_dot"] == traj.column(
            "theta1_dot").min()
        free = traj.t > 1.0
        assert row["energy.drift"] == pytest.approx(np.max(np.abs(traj.energy[free] - traj.energy[free][0])),
                                                    abs=1e-15)
        assert row["energy.drift"] < 1e-8 and row["nfev"] == traj.stats["nfev"]
        assert row.t_end == T_END and row["t_reached"] == T_END


def _listening(proc: psutil.Process) -> set:
    return {c.laddr for c in proc.net_connections(kind="inet") if c.status == psutil.CONN_LISTEN}


def _children(proc: psutil.Process) -> set:
    """Child processes, without multiprocessing's resource tracker (one per Python process, started with the
    first spawned child and ending with this process: Python's, not the cluster's)."""
    return {p.pid for p in proc.children(recursive=True) if "resource_tracker" not in " ".join(p.cmdline())}


@pytest.mark.parametrize("workers", [1, 2])
def test_dask_gives_the_same_bits_and_leaves_nothing_running(reference, tmp_path, workers):
    me = psutil.Process()
    children, ports = _children(me), _listening(me)
    res = sweep.run(small_spec(), tmp_path, workers=workers, progress=False, chunk_size=3)
    assert res.computed == 8 and res.statuses["ok"] == 8
    assert numbers(res.table) == numbers(reference.table)
    assert _children(me) - children == set()  # the cluster's processes are gone
    assert _listening(me) - ports == set()  # and so are its ports


def test_on_a_running_cluster_by_its_address(reference, tmp_path):
    """--scheduler ADDRESS: the sweep connects to a cluster it did not start (here one of threads in this
    process), checks that its workers run this robotdyn, and leaves the cluster running."""
    import logging

    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address="127.0.0.1:0",
                      silence_logs=logging.ERROR) as cluster:
        res = sweep.run(small_spec(), tmp_path, scheduler=cluster.scheduler_address, progress=False, plot=False)
        assert numbers(res.table) == numbers(reference.table)
        assert cluster.scheduler.status.name == "running" and len(cluster.workers) == 1


def test_interrupted_sweep_resumes_without_recomputing(reference, tmp_path, monkeypatch):
    calls = []

    def interrupting(ctx, runs, vectors=None):
        calls.append(len(runs))
        if len(calls) == 2:
            raise KeyboardInterrupt
        return sweep_chunk.run_chunk(ctx, runs, vectors)

    monkeypatch.setattr(sweep, "run_chunk", interrupting)
    first = sweep.run(small_spec(), tmp_path, workers=0, progress=False, chunk_size=3, plot=False)
    assert first.interrupted and first.table.num_rows == 3 and first.computed == 3
    assert not [p for p in tmp_path.rglob("*") if ".tmp" in p.name]  # no half-written file left
    calls.clear()
    monkeypatch.setattr(sweep, "run_chunk", sweep_chunk.run_chunk)
    again = sweep.run(small_spec(), tmp_path, workers=0, progress=False, chunk_size=3)
    assert (again.resumed, again.computed, again.interrupted) == (3, 5, None)
    assert numbers(again.table) == numbers(reference.table)
    # a larger sweep over the same directory computes only its new runs
    more = sweep.run(small_spec(axes=[parse_axis("M=4,5,6"), parse_axis("torque_scale=0.5,1")]), tmp_path,
                     workers=0, progress=False, plot=False)
    assert (more.resumed, more.computed, more.table.num_rows) == (8, 4, 12)
    assert (tmp_path / "summary.png").stat().st_size > 1000


def test_failed_runs_are_error_rows_and_the_others_go_on(tmp_path, monkeypatch):
    """An impossible body inertia (principal inertias J2 - M d^2, J2 - M d^2, J1 break the triangle inequality
    for d = 0.25 m), a run that crawls past the time limit (torques x 1e6: the error control takes tiny steps) and a result made non-finite each give
    an error row with its reason and null outputs; the other runs go on."""
    spec = SweepSpec(robot="quasimoro", axes=[parse_axis("d=0.15,0.2,0.25"), parse_axis("torque_scale=1,1e6")],
                     fixed={"M": "6"}, t_end=1.2, time_limit=1.0)
    real = sweep_chunk.summary

    def poisoned(mod, robot, traj, torque, columns):
        row = real(mod, robot, traj, torque, columns)
        if robot.params["d"] == 0.15:
            row["max.theta3"] = float("inf")
        return row

    monkeypatch.setattr(sweep_chunk, "summary", poisoned)
    res = sweep.run(spec, tmp_path, workers=0, progress=False)
    df = res.frame()
    assert list(df.status) == ["error", "error", "ok", "error", "error", "error"]
    assert df.error[0].startswith("non-finite result (max.theta3)")
    assert "exceeded its time limit of 1 s" in df.error[1] and "exceeded its time limit of 1 s" in df.error[3]
    assert "triangle inequality" in df.error[4] and "triangle inequality" in df.error[5]
    final_x, error = res.table.column("final.x").to_pylist(), res.table.column("error").to_pylist()
    assert [x is None for x in final_x] == [True, True, False, True, True, True]  # null (no output), not NaN
    assert np.isfinite(final_x[2]) and error[2] is None


def test_terrains(tmp_path):
    """Quasimoro's planar root keeps the axle at height r: on flat ground a run is the plain run, on a ramp its
    start puts the wheels below the ground, which is the error row's message."""
    spec = SweepSpec(robot="quasimoro", terrains=["flat", "ramp:slope=0.1"], t_end=0.5)
    df = sweep.run(spec, tmp_path, workers=0, progress=False, plot=False).frame()
    assert list(df.terrain) == ["flat", "ramp(slope=0.1)"] and list(df.status) == ["ok", "error"]
    traj = QUASIMORO.SCENARIOS["rectilinear"].run(robotdyn.load("quasimoro"), t_end=0.5, progress=False)
    assert df["final.x"][0] == traj.column("x")[-1]
    assert "every wheel is 0.00148884 m below the ground" in df.error[1]  # r (1 - cos atan 0.1), r = 0.3 m
    # a robot whose scenarios pick their terrain by name: names of its registry, not kinds
    p = plan(SweepSpec(robot="linkage_suspension", scenarios=["bump"], terrains=["flat", "bump"]))
    assert [r.terrain for r in p.runs] == ["flat", "bump"]
    with pytest.raises(SweepSpecError, match="picks its terrain by name"):
        plan(SweepSpec(robot="linkage_suspension", scenarios=["bump"], terrains=["ramp:slope=0.1"]))


def test_trajectories_are_kept_by_run(tmp_path):
    import pandas as pd

    spec = SweepSpec(robot="quasimoro", axes=[parse_axis("torque_scale=1,2")], t_end=0.5, trajectories=True)
    res = sweep.run(spec, tmp_path, workers=0, progress=False, plot=False)
    ids = res.frame().run_id.tolist()
    traj = QUASIMORO.SCENARIOS["rectilinear"].run(robotdyn.load("quasimoro"), t_end=0.5, progress=False)
    one = sweep.load_trajectory(tmp_path, ids[0])
    assert one["theta3"].tolist() == traj.column("theta3").tolist() and one["t"].tolist() == traj.t.tolist()
    every = pd.read_parquet(tmp_path / "trajectories")
    assert set(every.run_id) == set(ids) and len(every) == 2 * len(traj.t)


def test_samples_are_seeded_stratified_and_in_range():
    axes = [Axis("a", (), 1.0, 3.0), Axis("b", (), 0.1, 10.0, log=True), Axis("c", ("x", "y"))]
    lhs = points(SweepSpec(sample="lhs", n=16, seed=3), axes)
    assert len(lhs) == 32 and lhs == points(SweepSpec(sample="lhs", n=16, seed=3), axes)
    assert lhs != points(SweepSpec(sample="lhs", n=16, seed=4), axes)
    u_a = np.array([p["a"] for p in lhs[::2]]) / 2 - 0.5
    u_b = np.log(np.array([p["b"] for p in lhs[::2]]) / 0.1) / np.log(100)
    for u in (u_a, u_b):  # Latin hypercube: exactly one sample in each of the 16 strata of each dimension
        assert sorted(np.floor(u * 16).astype(int)) == list(range(16))
    rnd = points(SweepSpec(sample="random", n=50, seed=0), axes[:2])
    assert all(1 <= p["a"] <= 3 and 0.1 <= p["b"] <= 10 for p in rnd)
    grid = points(SweepSpec(), [Axis("a", (), 1.0, 100.0, 3, log=True), Axis("c", ("x", "y"))])
    assert [(p["a"], p["c"]) for p in grid] == [(1.0, "x"), (1.0, "y"), (10.0, "x"), (10.0, "y"), (100.0, "x"),
                                                (100.0, "y")]


def test_values_with_units():
    assert parse_value("0.3 m", "m", "r") == 0.3 and parse_value(0.3, "m", "r") == 0.3
    assert parse_value("0.4 kg m^2", "kg m^2", "J2") == 0.4
    assert parse_value("90 deg", "rad", "theta0") == pytest.approx(np.pi / 2, abs=1e-15)
    with pytest.raises(SweepSpecError, match="unit 'cm'; expected the parameter's unit 'm'"):
        parse_value("30 cm", "m", "r")
    p = plan(SweepSpec(robot="quasimoro", axes=[parse_axis("d=0.1 m:0.2 m:3")], t_end=1))
    assert [dict(r.params)["d"] for r in p.runs] == pytest.approx([0.1, 0.15, 0.2], abs=1e-15)
    assert p.units["d"] == "m" and p.schema.field("d").metadata[b"unit"] == b"m"


def test_toml_spec(tmp_path):
    f = tmp_path / "study.toml"
    f.write_text('robot = "quasimoro"\nscenarios = ["rectilinear"]\nsample = "lhs"\nn = 5\nseed = 2\nt_end = 2.0\n'
                 'fixed = { inertia_about = "com" }\n[parameters]\nM = { min = "4 kg", max = "6 kg" }\n'
                 'inertia_about = ["axle"]\n')
    with pytest.raises(SweepSpecError, match="both fixed and varied"):
        plan(from_toml(f))
    f.write_text(f.read_text().replace('inertia_about = ["axle"]\n', 'torque_scale = [1, 2]\n'))
    p = plan(from_toml(f))
    assert len(p.runs) == 10 and all(4 <= dict(r.params)["M"] <= 6 for r in p.runs)
    assert len({r.run_id for r in p.runs}) == 10 and p.context.fixed == {"inertia_about": "com"}
    f.write_text('robot = "quasimoro"\nsampel = "lhs"\n')
    with pytest.raises(SweepSpecError, match="unknown key 'sampel'"):
        from_toml(f)


@pytest.mark.parametrize("argv, message", [
    (["--vary", "Mass=4:6:3"], "unknown parameter 'Mass' for quasimoro; expected one of m, M"),
    (["--vary", "M=4 g:6 g:3"], "unit 'g'; expected the parameter's unit 'kg'"),
    (["--vary", "M=4:6"], "a range on a grid needs its number of points"),
    (["--vary", "M=-1,5"], "parameter M = -1 kg; expected a value > 0 kg"),
    (["--scenario", "wobble"], "unknown scenario 'wobble' for quasimoro; expected one of rectilinear"),
    (["--sample", "lhs", "--vary", "M=4,5"], "needs at least one range"),
    (["--column", "theta9"], "unknown column 'theta9'"),
    (["--vary", "torque_scale=1,1"], "the same run twice"),
    (["--workers", "-1"], "--workers -1; expected a whole number >= 0"),
    (["--plot-column", "final.theta9"], "plot_column = 'final.theta9'; expected a numeric column"),
])
def test_bad_specs_are_one_line_errors(tmp_path, capsys, argv, message):
    assert main(["sweep", "quasimoro", "--out", str(tmp_path / "s"), "--workers", "0", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and err.startswith("robotdyn: error: ")
    assert not (tmp_path / "s").exists()  # refused before anything is written


def test_unreachable_scheduler(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sweep, "CONNECT_TIMEOUT", "1s")
    assert main(["sweep", "quasimoro", "--t-end", "0.5", "--out", str(tmp_path), "--scheduler",
                 "tcp://127.0.0.1:9"]) == 2
    assert "cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'" in capsys.readouterr().err


def test_cli_end_to_end(tmp_path):
    out = tmp_path / "s"
    argv = [sys.executable, "-m", "robotdyn", "sweep", "quasimoro", "--vary", "M=4,6", "--t-end", "0.5",
            "--workers", "0", "--out", str(out), "--json", "--quiet"]
    first = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    data = json.loads(first.stdout)
    assert (data["runs"], data["computed"], data["statuses"]["ok"]) == (2, 2, 2)
    assert (out / "results.parquet").is_file() and (out / "summary.png").is_file()
    again = json.loads(subprocess.run(argv, capture_output=True, text=True, timeout=300).stdout)
    assert (again["computed"], again["resumed"]) == (0, 2)
    probe = ("import sys, io, contextlib, robotdyn.cli.commands as c\n"
             "with contextlib.redirect_stdout(io.StringIO()): c.main(['info', 'quasimoro'])\n"
             "print('dask' in sys.modules, 'pyarrow' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True).stdout.split() == [
        "False", "False"]  # the sweep command costs the other commands no start-up time


def test_sigterm_stops_the_sweep_and_keeps_what_finished(tmp_path):
    """SIGTERM (like Ctrl-C) during a run stops the sweep, not just that run (simulate() keeps partial results of
    an interruption: the sweep must not record them as a finished run); exit status 130, a rerun resumes."""
    import signal
    import time

    out = tmp_path / "s"
    argv = [sys.executable, "-m", "robotdyn", "sweep", "quasimoro", "--vary", "torque_scale=1,1e6,1e7",
            "--t-end", "0.5", "--workers", "0", "--chunk-size", "1", "--out", str(out), "--quiet", "--no-plot"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list((out / "runs").glob("part-*.parquet")) and time.monotonic() < deadline:
        time.sleep(0.2)  # the first run (torques x 1) is written; the second one crawls
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "interrupted after 1 of 3 runs; run the same sweep again to resume" in err
    assert sweep.load(out).status.tolist() == ["ok"]


def test_sweep_rows_are_the_in_process_batch_bit_for_bit(tmp_path):
    """The Dask sweep (2 workers) over torque scales gives the final states that one in-process batch call
    (robotdyn.simulation.batch.simulate_many, C++ threads) computes for the same scaled profiles: the same bits."""
    from robotdyn.simulation.batch import simulate_many

    scales = [0.25, 0.5, 1.0, 2.0]
    spec = SweepSpec(robot="quasimoro", axes=[Axis("torque_scale", scales)], scenarios=["rectilinear"], t_end=T_END)
    df = sweep.run(spec, tmp_path, workers=2, progress=False, plot=False).frame().sort_values("torque_scale")
    robot = robotdyn.load("quasimoro")
    sc = QUASIMORO.SCENARIOS["rectilinear"]
    q0, nu0 = sc.initial_state(robot)
    t_end, n_out = sc.span(T_END, None)
    batch = simulate_many(robot, t_end, q0, nu0, [sc.torque.scaled(s) for s in scales], n_out=n_out, threads=2)
    assert batch.ok.all()
    names = robot.coordinates + robot.velocity_names
    final = np.concatenate([batch.q[:, -1], batch.nu[:, -1]], axis=1)
    assert df[[f"final.{c}" for c in names]].to_numpy().tolist() == final.tolist()

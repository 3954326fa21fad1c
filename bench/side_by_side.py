"""make bench, side by side in one run (issue 17): Quasimoro's 'rectilinear' manoeuvre by robotdyn's scipy path,
by the compiled simulation (where ``robotdyn.simulation.engine.simulate`` offers it) and by MuJoCo, with the cost per
simulated second and the accuracy against robotdyn's exact trajectory; then the throughput of a 2,000-run sweep
on 1 and 2 Dask workers, with the identity of their results. Ratios matter here, not absolute times: the machine
has 2 cores and may be shared. This is a benchmark, not a test: it asserts nothing.

``ROBOTDYN_BENCH_SWEEP_RUNS`` sets the sweep's size (default 2000).
"""

from __future__ import annotations

import inspect
import os
import tempfile
import time

import numpy as np

import mujoco_quasimoro as mq
import robotdyn
from robotdyn.robots import module
from robotdyn.simulation.engine import simulate

SAMPLE = 0.05  # [s] output spacing: the scenario's own (1801 samples over 90 s)
REPEAT = 3  # each timed run is repeated; the fastest counts (the machine may be shared)


def compiled_engine() -> dict | None:
    """Keyword arguments of ``simulate`` choosing the compiled integrator, or ``None`` where this checkout's
    ``simulate`` has no such choice (an ``engine`` argument)."""
    return {"engine": "compiled"} if "engine" in inspect.signature(simulate).parameters else None


def scipy_engine() -> dict:
    """Keyword arguments of ``simulate`` choosing the scipy reference path (DOP853), whatever ``engine="auto"``
    would pick for a torque profile."""
    kw = {"method": "DOP853"}
    return {**kw, "engine": "scipy"} if "engine" in inspect.signature(simulate).parameters else kw


def _robotdyn_run(robot, sc, t_end: float, repeat: int = REPEAT, **kw) -> tuple[object, float]:
    """The trajectory and the fastest wall time [s] of ``repeat`` whole ``simulate`` calls."""
    q0, nu0 = sc.initial_state(robot)
    n = int(round(t_end / SAMPLE)) + 1
    walls = []
    for _ in range(repeat):
        start = time.perf_counter()
        traj = simulate(robot, t_end, q0, nu0, sc.torque, n_out=n, progress=False, **kw)
        walls.append(time.perf_counter() - start)
    return traj, min(walls)


def _as_run(traj, r: float) -> dict:
    return {"t": traj.t, "x": traj.column("x"), "z": np.full(len(traj.t), r), "theta1": traj.column("theta1"),
            "theta3": traj.column("theta3")}


def manoeuvre(t_ends=(20.0, 90.0)) -> None:
    """The table of the manoeuvre: cost per simulated second and accuracy of each engine."""
    robot = robotdyn.load("quasimoro")
    sc = module("quasimoro").SCENARIOS["rectilinear"]
    r = robot.params["r"]
    drift = module("quasimoro").drift
    _robotdyn_run(robot, sc, 1.0, repeat=1)  # builds the compiled model once, outside the timings
    version = mq.available()
    print("\nQuasimoro 'rectilinear' (m1 = m2 = 0.1 sin(pi t) N m for t <= 1 s, then free; from rest), side by side;"
          f"\ncost: the fastest of {REPEAT} runs (robotdyn: the whole simulate() call; MuJoCo: the stepping loop); "
          "accuracy against robotdyn's scipy trajectory (DOP853, rtol 1e-10) at the same 0.05 s samples")
    head = (f"{'engine':<34} {'t_end':>5} {'ms/sim s':>9} {'vs MuJoCo':>9} {'pitch ampl. err':>15} "
            f"{'max|x-x_ref|':>12} {'penetration':>11} {'|x-r th1|':>10} {'psi drift':>9}")
    print(head + "\n" + "-" * len(head))
    for t_end in t_ends:
        ref, wall_ref = _robotdyn_run(robot, sc, t_end, **scipy_engine())
        rows = [("robotdyn scipy DOP853 1e-10", wall_ref, _as_run(ref, r), drift(robot, ref))]
        kw = compiled_engine()
        if kw is None:
            rows.append(("robotdyn compiled simulation", None, "not available (simulate has no engine=)", None))
        else:
            fast, wall = _robotdyn_run(robot, sc, t_end, **kw)
            rows.append(("robotdyn compiled simulation", wall, _as_run(fast, r), drift(robot, fast)))
        if version is None:
            rows.append(("MuJoCo", None, "not installed (pip install -e .[bench])", None))
        else:
            for label, step, integrator in ((f"MuJoCo {version} default (2 ms)", 0.002, None),
                                            (f"MuJoCo {version} 1 ms implicitfast", 0.001, "implicitfast")):
                runs = [mq.simulate(robot, t_end, ref.t, step, integrator) for _ in range(REPEAT)]
                rows.append((label, min(run["wall"] for run in runs), runs[-1], None))
        mujoco_default = next((w for label, w, _, _ in rows if "default" in label), None)
        for label, wall, run, psi_drift in rows:
            if wall is None:
                print(f"{label:<34} {t_end:>5g}  {run}")
                continue
            acc = mq.accuracy(run, ref, r)
            ratio = f"{mujoco_default / wall:>8.2f}x" if mujoco_default else f"{'-':>9}"
            print(f"{label:<34} {t_end:>5g} {1e3 * wall / t_end:>9.2f} {ratio} {100 * acc['amplitude_error']:>14.3g}%"
                  f" {1e3 * acc['x_error']:>9.3g} mm {1e3 * acc['penetration']:>8.3g} mm"
                  f" {1e3 * acc['rolling_drift']:>7.2g} mm " + (f"{psi_drift:>9.1e}" if psi_drift is not None else
                                                                 f"{'-':>9}"))
    print("(vs MuJoCo: MuJoCo default's cost / this row's cost; penetration r - z(C2) and |x - r theta1| are zero "
          "by construction in robotdyn; psi drift: |psi - rho (theta2 - theta1)|, eq 11)")


def sweep_throughput(n: int | None = None, t_end: float = 2.0) -> None:
    """A Latin-hypercube sweep of n Quasimoro runs (M, d, J1, torque scale) on 1 and 2 Dask workers: runs per
    second of the whole ``robotdyn.sweep.runner.run`` call (cluster start included) and whether the results agree."""
    from robotdyn.sweep import runner as sweep
    from robotdyn.sweep.spec import SweepSpec, parse_axis

    n = n or int(os.environ.get("ROBOTDYN_BENCH_SWEEP_RUNS", 2000))
    spec = SweepSpec(robot="quasimoro", sample="lhs", n=n, seed=0, t_end=t_end, columns=["theta3"],
                     axes=[parse_axis(a) for a in ("M=4:6", "d=0.1:0.2", "J1=0.15:0.25", "torque_scale=0.5:2")])
    print(f"\nsweep throughput: {n} Quasimoro runs of {t_end:g} s (LHS over M, d, J1, torque scale), "
          f"robotdyn.sweep.runner.run on a local Dask cluster (cluster start included)")
    tables, rates = {}, {}
    for workers in (1, 2):
        before = os.times()
        with tempfile.TemporaryDirectory() as out, tempfile.TemporaryDirectory() as cache:
            # each measurement starts with an empty description cache (robotdyn.description.cache): every run of
            # this sweep is a new variant, and a cache the first measurement filled would favour the second
            saved, os.environ["ROBOTDYN_CACHE"] = os.environ.get("ROBOTDYN_CACHE"), cache
            try:
                res = sweep.run(spec, out, workers=workers, progress=False, plot=False)
            finally:
                os.environ.pop("ROBOTDYN_CACHE") if saved is None else os.environ.__setitem__("ROBOTDYN_CACHE", saved)
        after = os.times()  # the workers' CPU time: they are this process's (reaped) descendants
        cpu = after.children_user + after.children_system - before.children_user - before.children_system
        rates[workers] = res.computed / res.wall
        tables[workers] = {k: v for k, v in res.table.to_pydict().items() if k not in ("wall", "run_wall")}
        print(f"  {workers} worker(s): {res.wall:7.1f} s wall, {rates[workers]:7.1f} runs/s, workers' CPU {cpu:.1f} s "
              f"({cpu / res.wall:.2f} cores busy on average; {res.statuses})")
    same = tables[1] == tables[2]
    print(f"  2 workers / 1 worker: {rates[2] / rates[1]:.2f}x (target >= 1.8x); results bit-for-bit identical: "
          f"{'yes' if same else 'NO'}  (machine load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores: "
          "fewer cores busy than workers means other processes took them)")


def side_by_side() -> None:
    manoeuvre()
    sweep_throughput()


if __name__ == "__main__":
    side_by_side()

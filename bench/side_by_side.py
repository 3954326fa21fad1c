"""make bench, side by side in one run (issue 17): Quasimoro's 'rectilinear' manoeuvre by robotdyn's scipy path,
by the compiled simulation (where ``robotdyn.simulation.engine.simulate`` offers it) and by MuJoCo, with the cost per
simulated second and the accuracy against robotdyn's exact trajectory; then the throughput of a 2,000-run sweep
on 1 and 2 Dask workers (its runs as model variants, robotdyn.sweep.batched), with the identity of their results,
and the same sweep built run by run for scale. Ratios matter here, not absolute times: the machine
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
LOOSER = (1e-8, 1e-6)  # rtol of the compiled simulation's extra rows (its default is 1e-10)


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
            evaluations = {"rtol 1e-10 (default)": (fast.stats["nfev"], wall)}
            for rtol in LOOSER:  # the same engine at looser tolerances: accuracy against cost (stated per row)
                loose, wall_loose = _robotdyn_run(robot, sc, t_end, rtol=rtol, atol=rtol * 1e-2, **kw)
                rows.append((f"robotdyn compiled, rtol {rtol:g}", wall_loose, _as_run(loose, r), drift(robot, loose)))
                evaluations[f"rtol {rtol:g}"] = (loose.stats["nfev"], wall_loose)
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
        if kw is not None:
            print("  compiled simulation, whole call per evaluation (integrator, torque profile, output included): "
                  + ", ".join(f"{label}: {n} evaluations, {1e6 * w / n:.2f} us" for label, (n, w) in
                              evaluations.items()))
    print("(vs MuJoCo: MuJoCo default's cost / this row's cost; penetration r - z(C2) and |x - r theta1| are zero "
          "by construction in robotdyn; psi drift: |psi - rho (theta2 - theta1)|, eq 11; atol = rtol / 100 on the "
          "looser rows)")
    evaluation_cost(robot, sc)


def evaluation_cost(robot, sc) -> None:
    """One compiled evaluation of Quasimoro against its floor (issue 26): Evaluator.profile's C++ CPU time per call
    of the evaluation, of the simulation's right-hand side, of Pinocchio's CRBA + RNEA + frame Jacobians inside it
    and of Pinocchio's own CRBA + RNEA + computeJointJacobians as a user calls them, at the state 1 s into the
    manoeuvre (median of 5 profiles of 2000 calls each)."""
    from robotdyn.fast.dispatch import compiled_model

    fast = compiled_model(robot)
    if fast is None:
        return
    q0, nu0 = sc.initial_state(robot)
    traj = simulate(robot, 1.0, q0, nu0, sc.torque, n_out=3, progress=False)
    fast.compute(traj.q[-1], traj.nu[-1])
    runs = [fast.ev.profile(traj.q[-1], traj.nu[-1], 2000, 1.0) for _ in range(5)]
    t = {k: float(np.median([run[k] for run in runs])) for k in runs[0]}
    floor = t.get("pinocchio_jacobians", t["pinocchio"])
    print(f"  one compiled evaluation [us, C++ CPU time]: evaluation {1e6 * t['evaluation']:.2f}, right-hand side "
          f"{1e6 * t['rhs']:.2f}; Pinocchio inside it (CRBA + RNEA + frames) {1e6 * t['pinocchio']:.2f}; Pinocchio's "
          f"own CRBA + RNEA + computeJointJacobians {1e6 * floor:.2f} (evaluation / that floor "
          f"{t['evaluation'] / floor:.2f})")


def _sweep(spec, workers: int, batch: str):
    """One whole ``robotdyn.sweep.runner.run`` call on a new local cluster, with an empty description cache (every
    run of this sweep is a new variant, and a cache an earlier measurement filled would favour the later one)."""
    from robotdyn.sweep import runner as sweep

    before = os.times()
    with tempfile.TemporaryDirectory() as out, tempfile.TemporaryDirectory() as cache:
        saved, os.environ["ROBOTDYN_CACHE"] = os.environ.get("ROBOTDYN_CACHE"), cache
        try:
            res = sweep.run(spec, out, workers=workers, progress=False, plot=False, batch=batch)
        finally:
            os.environ.pop("ROBOTDYN_CACHE") if saved is None else os.environ.__setitem__("ROBOTDYN_CACHE", saved)
    after = os.times()  # the workers' CPU time: they are this process's (reaped) descendants
    cpu = after.children_user + after.children_system - before.children_user - before.children_system
    return res, cpu


def _ceiling(spec, t_end: float) -> float:
    """What this machine's two cores give right now on pure C++ threads: the same number of Quasimoro runs through
    ``simulate_many`` (no Python per run, no Dask) on 2 threads against 1 (best of 2 each)."""
    from robotdyn.simulation.batch import simulate_many

    robot = robotdyn.load("quasimoro")
    sc = module("quasimoro").SCENARIOS["rectilinear"]
    q0, nu0 = sc.initial_state(robot)
    torques = [sc.torque.scaled(s) for s in np.linspace(0.5, 2.0, spec.n // 4)]
    best = {}
    for threads in (1, 2, 1, 2):
        start = time.perf_counter()
        simulate_many(robot, t_end, q0, nu0, torques, n_out=41, threads=threads)
        best[threads] = min(best.get(threads, np.inf), time.perf_counter() - start)
    return best[1] / best[2]


def sweep_throughput(n: int | None = None, t_end: float = 2.0, built: bool = True) -> None:
    """A Latin-hypercube sweep of n Quasimoro runs (M, d, J1, torque scale) on 1 and 2 Dask workers, twice each,
    interleaved: the whole ``robotdyn.sweep.runner.run`` call (planning, the one-time fit of the model variants,
    cluster start, runs, Parquet) and its runs phase (first submission to last result), the faster of the two, and
    whether all four results agree bit for bit; then
    the same sweep with every run built from its parameters (``batch="never"``, the way before model variants) on 2
    workers, for scale."""
    from robotdyn.sweep.spec import SweepSpec, parse_axis

    n = n or int(os.environ.get("ROBOTDYN_BENCH_SWEEP_RUNS", 2000))
    spec = SweepSpec(robot="quasimoro", sample="lhs", n=n, seed=0, t_end=t_end, columns=["theta3"],
                     axes=[parse_axis(a) for a in ("M=4:6", "d=0.1:0.2", "J1=0.15:0.25", "torque_scale=0.5:2")])
    print(f"\nsweep throughput: {n} Quasimoro runs of {t_end:g} s (LHS over M, d, J1, torque scale), "
          f"robotdyn.sweep.runner.run on a new local Dask cluster each time")
    from robotdyn.sweep.plan import plan

    plan(spec)  # this process's imports (robot, scipy's sampler), once: not counted against the first measurement
    tables, whole, runs = {}, {}, {}
    for workers in (1, 2, 1, 2):  # interleaved, the faster of two each (this shared VM's speed drifts by ~20 %)
        res, cpu = _sweep(spec, workers, "auto")
        ph = res.phases
        whole[workers] = max(whole.get(workers, 0.0), res.computed / res.wall)
        runs[workers] = max(runs.get(workers, 0.0), res.computed / ph["runs"])
        table = {k: v for k, v in res.table.to_pydict().items() if k not in ("wall", "run_wall")}
        tables.setdefault(workers, table)
        if table != tables[workers]:
            tables[workers] = None  # two runs with the same workers differ: reported below
        print(f"  {workers} worker(s): {res.wall:6.1f} s whole call ({res.computed / res.wall:6.1f} runs/s): plan "
              f"{ph['plan']:.2f} s, fit {ph['fit']:.2f} s, cluster start {ph.get('connect', 0):.2f} s, runs "
              f"{ph['runs']:.2f} s ({res.computed / ph['runs']:6.1f} runs/s); {res.batched} batched; workers' CPU "
              f"{cpu:.1f} s; "
              f"{res.statuses}")
    same = tables[1] is not None and tables[1] == tables[2]
    print(f"  2 workers / 1 worker (the faster of two each): runs phase {runs[2] / runs[1]:.2f}x (target >= 1.8x), "
          f"whole call "
          f"{whole[2] / whole[1]:.2f}x (the plan, the fit and the cluster start do not shrink with workers); "
          f"results bit-for-bit identical: {'yes' if same else 'NO'}  (machine load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; the same cores on pure C++ threads now: 2 threads / "
          f"1 = {_ceiling(spec, t_end):.2f}x)")
    if not built:
        return
    res, cpu = _sweep(spec, 2, "never")
    print(f"  every run built from its parameters (batch = never), 2 workers: {res.wall:6.1f} s whole call "
          f"({res.computed / res.wall:6.1f} runs/s), runs {res.phases['runs']:.2f} s; batched sweep "
          f"{res.wall / (res.computed / whole[2]):.1f}x faster on the whole call")


def side_by_side() -> None:
    manoeuvre()
    sweep_throughput()
    sweep_throughput(t_end=10.0, built=False)  # the batch target's ten-second runs


if __name__ == "__main__":
    side_by_side()

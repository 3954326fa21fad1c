"""make bench: speed of robotdyn's reduced model next to raw Pinocchio, for every registered robot, in one run.

For each robot: the median time of one reduced-model evaluation (M_r, C_r nu + g_r, g_r, S, w = Sdot nu) -- by
the compiled model (robotdyn.fast.compiled, views of its buffers), by robot.reduced (the full ReducedDynamics object) and
by the Python path -- next to Pinocchio's CRBA + RNEA on the same model, their ratios; for Quasimoro also the sympy-derived model lambdified
with numpy (tests/oracles); and simulated seconds per wall-clock second of the robot's first scenario with the
constraint drift at the end (for Quasimoro also DOP853 at rtol 1e-8 and LSODA at rtol 1e-10, each with its
deviation from the default DOP853 rtol 1e-10 run); the batch API next to robot.reduced in a loop; Quasimoro's
'rectilinear' manoeuvre side by side with MuJoCo and sweep throughput on Dask (side_by_side.py). This is a
benchmark, not a test: it asserts nothing.
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import robotdyn  # noqa: E402
from robotdyn.fast.dispatch import available, compiled_model, use_compiled
from robotdyn.fast.compiled import why_not  # noqa: E402
from robotdyn.robots import module, names  # noqa: E402


def timeit(fn, repeat: int = 7, number: int = 200) -> float:
    """Median seconds per call over ``repeat`` batches of ``number`` calls."""
    fn()
    runs = []
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        runs.append((time.perf_counter() - start) / number)
    return statistics.median(runs)


def state(robot, seed: int = 0):
    rng = np.random.default_rng(seed)
    q = robot.neutral()
    nu = 0.3 * rng.normal(size=robot.mobility)
    return q, nu


def main() -> None:
    print(f"robotdyn {robotdyn.__version__}, pinocchio {pin.__version__}, numpy {np.__version__}, "
          f"compiled fast path: {'built' if available() else 'NOT built'}")
    print("times per evaluation of (M_r, C_r nu + g_r, g_r, S, Sdot nu) [us]; ratio = time / (CRBA + RNEA)")
    print(f"{'robot':<20} {'n':>3} {'k':>3} {'CRBA+RNEA':>10} {'compiled':>9} {'ratio':>6} {'reduced()':>10} "
          f"{'ratio':>6} {'Python path':>12} {'ratio':>6}")
    rows = []
    for name in names():
        try:
            robot = robotdyn.load(name)
            q, nu = state(robot)
            robot.reduced(q, nu)
        except Exception as exc:  # a robot that cannot be evaluated at its neutral state is reported, not fatal
            print(f"{name:<20} skipped: {exc}")
            continue
        v = np.zeros(robot.nq)
        t_pin = timeit(lambda: (pin.crba(robot.model, robot.data, q), pin.rnea(robot.model, robot.data, q, v, v)),
                       number=2000)
        fast = compiled_model(robot)
        t_fast = timeit(lambda: fast.compute(q, nu), number=2000) if fast is not None else float("nan")
        t_red = timeit(lambda: robot.reduced(q, nu), number=1000)
        with use_compiled(False):
            t_py = timeit(lambda: robot.reduced(q, nu))
        rows.append((name, robot, t_red))
        print(f"{name:<20} {robot.nq:>3} {robot.mobility:>3} {t_pin * 1e6:>10.2f} {t_fast * 1e6:>9.2f} "
              f"{t_fast / t_pin:>6.1f} {t_red * 1e6:>10.2f} {t_red / t_pin:>6.1f} {t_py * 1e6:>12.1f} {t_py / t_pin:>6.0f}"
              + ("" if fast is not None else f"   (not compiled: {why_not(robot)})"))

    from oracles.quasimoro_sympy import quasimoro_reduced

    robot = robotdyn.load("quasimoro")
    q, nu = state(robot)
    oracle = quasimoro_reduced({"g": robot.params["g"]})
    qo = np.array([q[robot.coordinate_index(c)] for c in ("x", "y", "psi", "theta1", "theta2", "theta3")])
    t_sym = timeit(lambda: (oracle.M_r(qo), oracle.h_r(qo, nu), oracle.g_r(qo), oracle.S(qo)))
    fast = compiled_model(robot)
    t_fast = timeit(lambda: fast.compute(q, nu), number=2000) if fast is not None else float("nan")
    t_red = timeit(lambda: robot.reduced(q, nu))
    print(f"\nquasimoro: sympy-lambdified model {t_sym * 1e6:.1f} us; robotdyn compiled {t_fast * 1e6:.2f} us "
          f"({t_sym / t_fast:.1f}x faster), robot.reduced {t_red * 1e6:.1f} us ({t_sym / t_red:.1f}x faster)")

    from robotdyn.simulation.batch import evaluate

    rng = np.random.default_rng(1)
    N = 2000
    Q = np.tile(q, (N, 1))
    Q[:, robot.coordinate_index("theta3")] = rng.uniform(-1, 1, N)
    NU = rng.normal(size=(N, robot.mobility))
    start = time.perf_counter()
    for i in range(N):
        robot.reduced(Q[i], NU[i])
    wall = time.perf_counter() - start
    print(f"quasimoro one by one (robot.reduced in a loop): {N} states: {N / wall:,.0f} states/s")
    for label, flag in (("compiled", True), ("Python path", False)):
        with use_compiled(flag):
            for processes in (1, 2):  # 2: workers start only where the first 256 states say they pay (batch.evaluate)
                start = time.perf_counter()
                evaluate(robot, Q, NU, processes=processes)
                wall = time.perf_counter() - start
                print(f"quasimoro batch API ({label}): {N} states, processes={processes}: {N / wall:,.0f} states/s")

    print(f"\n{'robot / scenario':<36} {'sim [s]':>8} {'wall [s]':>9} {'sim/wall':>9} {'evals':>7} {'drift':>9}")
    for name, robot, _ in rows:
        mod = module(name)
        scenarios = getattr(mod, "SCENARIOS", {})
        if not scenarios:
            continue
        sc_name, sc = next(iter(scenarios.items()))
        t_end = sc.t_end if name == "quasimoro" else min(sc.t_end, 2.0)
        try:
            traj = sc.run(robot, t_end=t_end, progress=False)
        except Exception as exc:
            print(f"{name + ' / ' + sc_name:<36} failed: {exc}")
            continue
        drift_fn = getattr(mod, "drift", None)
        drift = drift_fn(robot, traj) if drift_fn else float(np.max(traj.residual))
        wall = traj.stats["wall"]
        print(f"{name + ' / ' + sc_name:<36} {t_end:>8.1f} {wall:>9.2f} {t_end / wall:>9.1f} "
              f"{traj.stats['nfev']:>7d} {drift:>9.1e}")
        if name == "quasimoro":  # other integrator settings, and how far each strays from the default run
            start = time.perf_counter()
            sc.run(robot, t_end=t_end, progress=False)
            print(f"{'  whole simulate() call':<36} {t_end:>8.1f} {time.perf_counter() - start:>9.2f}")
            for label, kw, flag in (("DOP853 rtol 1e-8", dict(rtol=1e-8, atol=1e-10), True),
                                    ("LSODA rtol 1e-10", dict(method="LSODA"), True),
                                    ("DOP853, Python path", {}, False)):
                with use_compiled(flag):
                    other = sc.run(robot, t_end=t_end, progress=False, **kw)
                dev = float(np.max(np.abs(other.q - traj.q)))
                wall = other.stats["wall"]
                print(f"{'  ' + label:<36} {t_end:>8.1f} {wall:>9.2f} {t_end / wall:>9.1f} {other.stats['nfev']:>7d} "
                      f"{drift_fn(robot, other):>9.1e}  (max |q - q(default)| = {dev:.1e})")

    forces_bench()
    side_by_side_bench()
    startup_bench()
    compiled_engine_bench()
    evaluation_profile_bench()
    controller_bench()
    compiled_forces_bench()
    rigid_limit_bench()
    traction_bench()
    compliant_bench()
    from compliant_rolling_bench import compliant_rolling_bench  # bench/compliant_rolling_bench.py

    compliant_rolling_bench()
    simulate_many_bench()
    from derivatives_bench import derivatives_bench  # bench/derivatives_bench.py

    derivatives_bench()
    from force_derivatives_bench import force_derivatives_bench  # bench/force_derivatives_bench.py

    force_derivatives_bench()
    trajectory_optimisation_bench()


def side_by_side_bench() -> None:
    """Quasimoro's manoeuvre by robotdyn and by MuJoCo, and sweep throughput on 1 and 2 Dask workers (issue 17;
    bench/side_by_side.py, bench/mujoco_quasimoro.py)."""
    from side_by_side import side_by_side

    side_by_side()


def startup_bench() -> None:
    """Wall time of `robotdyn info quasimoro` and `robotdyn dump quasimoro` in fresh processes (median of 5)."""
    import subprocess

    # as a user's shell runs it: Python keeps its bytecode (PYTHONDONTWRITEBYTECODE would recompile every module of
    # every import on each start); the first run warms the bytecode and robotdyn's description caches
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    bare = [sys.executable, "-c", "import numpy, pinocchio"]
    for label, cmd in (("python -c 'import numpy, pinocchio' (the floor)", bare),
                       ("robotdyn info quasimoro", [sys.executable, "-m", "robotdyn", "info", "quasimoro"]),
                       ("robotdyn dump quasimoro", [sys.executable, "-m", "robotdyn", "dump", "quasimoro", "--q", "0",
                                                    "0", "0", "0", "0", "0.3", "--v", "1", "0.5", "0.2"])):
        walls = []
        for _ in range(6):
            start = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True, env=env)
            walls.append(time.perf_counter() - start)
        print(f"CLI start-up: {label}: {statistics.median(walls[1:]):.3f} s wall (median of 5 after a warm-up)")


def forces_bench() -> None:
    """Contact forces against a compiled evaluation, and a slipping against a rolling simulation (issue 13)."""
    from dataclasses import replace

    from robotdyn.interfaces.constraint_file import read
    from robotdyn.robot import Robot

    print(f"\n{'robot':<20} {'compiled [us]':>14} {'forces [us]':>12} {'forces / compiled':>18}")
    for name in ("quasimoro", "omni_caster", "adaptable_wheel", "linkage_suspension"):
        robot = robotdyn.load(name)
        q, nu = robot.neutral(), np.full(robot.mobility, 0.3)
        tau = np.full(len(robot.motors), 0.1)
        fast = compiled_model(robot)
        t_fast = timeit(lambda: fast.compute(q, nu)) if fast is not None else float("nan")
        t_forces = timeit(lambda: robot.contact_forces(q, nu, tau=tau), number=20)
        print(f"{name:<20} {t_fast * 1e6:>14.2f} {t_forces * 1e6:>12.1f} {t_forces / t_fast:>18.1f}")
    # the skid-steer rover: four slipping wheels (linear law) against the same rover with rolling wheels, on the
    # compiled engine (the default) and on scipy's (the Python reference); best of 3 whole simulate() calls after a
    # warm-up (imports, compiled model, projection)
    example = Path(__file__).resolve().parents[1] / "examples" / "skid_steer.toml"
    mod = read(example)
    slipping = mod.robot()
    sc = mod.SCENARIOS["straight"]
    rolling = Robot(replace(mod.SPEC, wheels=[replace(w, friction="rolling", stiffness=None)
                                              for w in mod.SPEC.wheels], independent=None))

    def best(robot, engine: str, repeats: int = 3):
        sc.run(robot, t_end=0.1, progress=False, engine=engine)
        walls = []
        for _ in range(repeats):
            start = time.perf_counter()
            traj = sc.run(robot, t_end=2.0, progress=False, engine=engine)
            walls.append(time.perf_counter() - start)
        return min(walls), traj

    print("skid-steer 'straight', 2 s, whole simulate() call (best of 3; scipy slipping: 1):")
    for engine in ("compiled", "scipy"):
        t_slip, traj = best(slipping, engine, 3 if engine == "compiled" else 1)
        t_roll, other = best(rolling, engine)
        print(f"  {engine:<9} slipping wheels {t_slip:.3f} s wall ({traj.stats['nfev']} evaluations), rolling wheels "
              f"{t_roll:.3f} s ({other.stats['nfev']}): ratio slipping / rolling {t_slip / t_roll:.1f}")
    # a rigid four-wheel skid steer (statically indeterminate loads: the coupled solve, kernels/sliding_rigid_limit.hpp)
    # turning in place under a Coulomb law, 0.2 s from rest
    # turning in place under a Coulomb law, 0.2 s from rest; then with its wheels damped (0.5 N m s/rad each, as a
    # URDF's <dynamics damping> is applied: the springs' Q in the same solve)
    from robotdyn.reduction.joint_springs import JointSpring

    mod = read(Path(__file__).resolve().parents[1] / "examples" / "husky_like.toml")
    husky, turn = mod.robot(), mod.SCENARIOS["turn_in_place"]
    damped = Robot(replace(mod.SPEC, springs=[JointSpring(m.joint, damping=0.5) for m in mod.SPEC.motors]))
    for label, robot in (("open loads", husky), ("open loads, damped wheels", damped)):
        walls = {}
        for engine in ("compiled", "scipy"):
            turn.run(robot, t_end=0.002, progress=False, engine=engine)
            start = time.perf_counter()
            traj = turn.run(robot, t_end=0.2, progress=False, engine=engine)
            walls[engine] = (time.perf_counter() - start) / 0.2
            print(f"husky_like 'turn_in_place' ({label}), {engine:<8}: {walls[engine]:.3f} s wall per simulated "
                  f"second ({traj.stats['nfev']} evaluations in 0.2 s)")
        print(f"  scipy / compiled: {walls['scipy'] / walls['compiled']:.0f}x")


# ------------------------------------------------------------------ compiled simulation engine (issue 17, items 1, 2)
def compiled_engine_bench() -> None:
    """The whole simulation in C++ (robotdyn.simulation.compiled_engine) against the scipy path on Quasimoro's rectilinear
    manoeuvre (90 s, default tolerances rtol 1e-10, atol 1e-12): cost per simulated second (best of 5 whole
    simulate() calls, 2 for scipy, after a warm-up), evaluations, deviation from the scipy trajectory, energy drift
    after the pulse."""
    robot = robotdyn.load("quasimoro")
    sc = module("quasimoro").SCENARIOS["rectilinear"]
    t_end = 90.0
    print(f"\nquasimoro rectilinear {t_end:g} s, whole simulate() call (best of 5; scipy: of 2), default tolerances:")
    print(f"{'engine':<28} {'ms / sim s':>11} {'evals':>7} {'max|q - q_scipy|':>17} {'max|nu - nu_scipy|':>19} "
          f"{'energy drift':>13}")
    ref = None
    for label, kw in (("scipy (DOP853)", dict(engine="scipy")), ("compiled (adams)", {}),
                      ("compiled (bulirsch_stoer)", dict(method="bulirsch_stoer")),
                      ("compiled (dopri5)", dict(method="dopri5"))):
        sc.run(robot, t_end=1.0, progress=False, **kw)  # warm: imports, the compiled model, the projection
        walls = []
        for _ in range(2 if ref is None else 5):
            start = time.perf_counter()
            traj = sc.run(robot, t_end=t_end, progress=False, **kw)
            walls.append(time.perf_counter() - start)
        ref = traj if ref is None else ref
        drift = float(np.ptp(traj.energy[traj.t > 1.0]))
        print(f"{label:<28} {1e3 * min(walls) / t_end:>11.3f} {traj.stats['nfev']:>7d} "
              f"{np.max(np.abs(traj.q - ref.q)):>17.2e} {np.max(np.abs(traj.nu - ref.nu)):>19.2e} {drift:>13.2e}")


def evaluation_profile_bench() -> None:
    """Where a compiled evaluation's time goes (Evaluator.profile: each part timed in C++, this thread's CPU time, no
    Python in the loop), next to Pinocchio's own C++ CRBA + RNEA + frame placements and Jacobians on the same model,
    at the state a second into each robot's first scenario (the holonomic residuals are then nonzero, so the
    simulation's right-hand side pays the pull-back). Parts: rows = constraint rows, residuals and B; projection = S
    (LU of A_d, condition estimate, span check); drift = the rows' drift and w after RNEA; reduce = M_r, h, g_r, B_r;
    rhs = the whole right-hand side of a compiled simulation with the pull-back at gain 1; gravity = g from CRBA's
    composite inertias; solve = the right-hand side's LLT of M_r and its solve; floor = Pinocchio's own CRBA + RNEA +
    computeJointJacobians as a user calls them (each redoing the kinematics); then the heap allocations per
    evaluation (bench/allocation_bench.py)."""
    parts = ("crba", "rnea", "frames", "gravity", "rows", "projection", "drift", "reduce", "solve", "pull_back")
    print("\nwhere a compiled evaluation's time goes [us, C++ CPU time per call] (issue 26: pinocchio = Pinocchio's own "
          "CRBA + RNEA + frame Jacobians on the same model)")
    print("(floor = Pinocchio's own CRBA + RNEA + computeJointJacobians as a user calls them; kinematics = "
          "forwardKinematics alone)")
    print(f"{'robot':<20} {'evaluation':>10} {'pinocchio':>9} {'ratio':>6} {'floor':>6} {'kinematics':>10} {'rhs':>7} "
          + " ".join(f"{p:>10}" for p in parts))
    for name in names():
        robot = robotdyn.load(name)
        fast = compiled_model(robot)
        scenarios = getattr(module(name), "SCENARIOS", {})
        if fast is None or not scenarios:
            continue
        try:
            traj = next(iter(scenarios.values())).run(robot, t_end=1.0, progress=False)
            fast.compute(traj.q[-1], traj.nu[-1])
            t = fast.ev.profile(traj.q[-1], traj.nu[-1], 2000 if robot.nq < 20 else 500, 1.0)
        except Exception as exc:  # a benchmark reports, it does not stop
            print(f"{name:<20} skipped: {exc}")
            continue
        print(f"{name:<20} {1e6 * t['evaluation']:>10.2f} {1e6 * t['pinocchio']:>9.2f} "
              f"{t['evaluation'] / t['pinocchio']:>6.2f} {1e6 * t.get('pinocchio_jacobians', np.nan):>6.2f} "
              f"{1e6 * t.get('kinematics', np.nan):>10.2f} {1e6 * t['rhs']:>7.2f} "
              + " ".join(f"{1e6 * t.get(p, np.nan):>10.2f}" for p in parts))
    from allocation_bench import allocation_bench  # bench/allocation_bench.py

    allocation_bench()


def _best_of(run, repeat: int) -> tuple[float, float, object]:
    """(wall [s], CPU [s], result) of the fastest of ``repeat`` calls of ``run()`` (the CPU time is this process's:
    on a shared machine it is the steadier measure)."""
    best = (np.inf, np.inf, None)
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        out = run()
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        best = (wall, cpu, out) if wall < best[0] else best
    return best


def controller_bench() -> None:
    """The built-in controller scenarios (robotdyn.simulation.feedback: feedback laws as data) on the compiled loop
    against the same law on the scipy loop, at each scenario's tolerances and samples: cost per simulated second
    (whole simulate() calls, best of 3 each, after a warm-up), speed-up in wall and in CPU time (the machine may be
    shared: CPU is the steadier ratio), the final states' difference, the evaluations of each; then the same with 11
    samples, with each engine's error against a tight reference (compiled dopri5 at rtol = atol = 1e-12, max abs. over
    q and nu at the 11 samples); then where each compiled run's CPU time goes: the Python set-up of the call
    (checks, start posture, model, law), the integration (evaluations, steps) and the samples (energy and residual of
    each, interpolation), from the same call with the default samples, with 2, and over 1 ms (CPU times)."""
    rows = [("linkage_suspension", "straight_line", None), ("linkage_suspension", "pivot_steering", None),
            ("linkage_suspension", "bump", None), ("omni_caster", "circle", 20.0), ("omni_caster", "ellipse", None),
            ("mmr12_eod", "orientation", 50.0),
            ("mmr12_eod", "sinusoid", 50.0), ("mmr12_eod", "manipulation", None), ("mmr12_eod", "lifting", None)]
    print("\ncontroller scenarios, compiled loop vs scipy loop (the same law), whole simulate() call (best of 3):")
    print(f"{'robot / scenario':<36} {'sim [s]':>8} {'scipy ms/s':>11} {'compiled ms/s':>14} {'speed-up':>9} "
          f"{'cpu speed-up':>13} {'max|dy(t_end)|':>15} {'evals scipy/compiled':>21} {'err scipy':>10} "
          f"{'err compiled':>13}")
    costs = []

    def line(label, t_end, scipy, compiled, dev=None, errors=None):
        (ws, cs, ref), (wc, cc, fast) = scipy, compiled
        dev = f"{dev:>15.2e}" if dev is not None else f"{'':>15}"
        errs = f" {errors[0]:>10.1e} {errors[1]:>13.1e}" if errors is not None else ""
        print(f"{label:<36} {t_end:>8.1f} {1e3 * ws / t_end:>11.2f} {1e3 * wc / t_end:>14.3f} {ws / wc:>8.1f}x "
              f"{cs / cc:>12.1f}x {dev} {ref.stats['nfev']:>10d}/{fast.stats['nfev']:<10d}{errs}")

    def compare(label, run, t_end, n_out, reference):
        runs = {engine: _best_of(lambda: run(engine, n_out), 3) for engine in ("scipy", "auto")}
        ref, fast = runs["scipy"][2], runs["auto"][2]
        assert fast.stats["engine"].startswith("compiled"), fast.stats["engine"]
        dev = max(np.abs(fast.q[-1] - ref.q[-1]).max(), np.abs(fast.nu[-1] - ref.nu[-1]).max())
        line(label, t_end, runs["scipy"], runs["auto"], dev)
        sparse = {engine: _best_of(lambda: run(engine, 11), 3) for engine in ("scipy", "auto")}
        try:
            tight = reference()
        except robotdyn.errors.RobotDynError:  # (dopri5 failed at windows meeting one double apart: fixed)
            tight = reference(method="adams")
        errors = [max(np.abs(sparse[e][2].q - tight.q).max(), np.abs(sparse[e][2].nu - tight.nu).max())
                  for e in ("scipy", "auto")]
        line("  the same, 11 samples", t_end, sparse["scipy"], sparse["auto"], errors=errors)
        for engine in ("auto", "scipy"):  # CPU times (steadier than wall on a shared machine)
            two, whole = _best_of(lambda: run(engine, 2), 3), runs[engine]
            short = _best_of(lambda: run(engine, 2, 1e-3), 3)  # 1 ms: the set-up and a few evaluations
            costs.append((label if engine == "auto" else "  scipy loop", whole[1], short[1], whole[1] - two[1],
                          whole[2]))

    for name, sc_name, t_end in rows:
        robot = robotdyn.load(name)
        sc = module(name).SCENARIOS[sc_name]
        t_end = sc.t_end if t_end is None else t_end
        sc.run(robot, t_end=0.1, progress=False)  # warm: imports, the compiled model, the projection
        n_out = sc.span(t_end)[1]
        compare(name + " / " + sc_name,
                lambda engine, n, t=t_end: sc.run(robot, t_end=t, n_out=n, progress=False, engine=engine), t_end, n_out,
                lambda method="dopri5": sc.run(robot, t_end=t_end, n_out=11, progress=False, method=method, rtol=1e-12,
                                               atol=1e-12))
    robot = robotdyn.load("quasimoro")  # the LQR of examples/quasimoro_lqr.py as data (lqr_law), 10 s
    from robotdyn.reduction.linearization import linearize, lqr
    from robotdyn.simulation.engine import simulate
    from robotdyn.simulation.feedback import lqr_law

    q0 = robot.neutral()
    model = linearize(robot, q0, np.zeros(3), np.zeros(2)).restrict(["theta3", "theta1_dot", "theta2_dot",
                                                                      "theta3_dot"])
    law = lqr_law(model, lqr(model, np.eye(4), np.eye(2))[0])
    start_q = q0.copy()
    start_q[robot.coordinate_index("theta3")] += 0.1
    compare("quasimoro / LQR (lqr_law)",
            lambda engine, n, t=10.0: simulate(robot, t, start_q, np.zeros(3), law, n_out=n, progress=False,
                                               engine=engine),
            10.0, 101, lambda method="dopri5": simulate(robot, 10.0, start_q, np.zeros(3), law, n_out=11,
                                                        progress=False, method=method, rtol=1e-12, atol=1e-12))
    print("\nwhere each run's time goes [ms of CPU, best of 3] (default samples; set-up: the same call over 1 ms of "
          "simulated time; samples: the default samples' cost over 2 samples; integration: the rest):")
    print(f"{'robot / scenario (compiled; scipy)':<36} {'total':>8} {'set-up':>8} {'integration':>12} {'samples':>8} "
          f"{'us / sample':>12} {'evals':>7} {'us / eval':>10}")
    for label, total, setup, samples, traj in costs:
        integration, nfev, count = total - setup - samples, traj.stats["nfev"], len(traj.t)
        print(f"{label:<36} {1e3 * total:>8.2f} {1e3 * setup:>8.2f} {1e3 * integration:>12.2f} {1e3 * samples:>8.2f} "
              f"{1e6 * samples / max(count - 2, 1):>12.1f} {nfev:>7d} {1e6 * integration / nfev:>10.1f}")
    print("a compiled sample's energy and residual [us, C++ CPU time per call, at each run's last state]: observe = the "
          "whole configuration pass (what every sample cost before), sample = the lean pass of a run that kept its row "
          "choice (no gravity torques, motor columns, condition or span checks; the same bits)")
    seen = set()
    for label, _, _, _, traj in costs:
        if label.startswith(" ") or traj.robot is None or traj.robot.spec.name in seen:
            continue
        seen.add(traj.robot.spec.name)
        t = compiled_model(traj.robot).ev.profile(traj.q[-1], traj.nu[-1], 500, 0.0)
        print(f"  {traj.robot.spec.name:<20} observe {1e6 * t['observe']:>6.2f}  sample {1e6 * t['sample']:>6.2f}  "
              f"({t['observe'] / t['sample']:.2f}x)")
    print("  the scipy loop evaluates the same compiled model (one Python call per evaluation around it) and computes "
          "each sample's v and residual with the compiled model and its energy with Pinocchio: its integration costs "
          "nfev_s (c + p) against the compiled loop's nfev_c c, c the compiled evaluation, p the Python around it. "
          "Where c is tens of us (the linkage: 25 coordinates, six wheels, the suspension's loop closures: c = 33-40 "
          "us, p = 4-7 us) the integrations' ratio is about nfev_s / nfev_c (1.9-2.8 with Adams up to order 10), "
          "and each of the 400-820 samples per second costs a configuration pass on both loops (~13-16 us compiled by the "
          "lean pass, 17-23 us before it, against ~53 us): the linkage's runs are bound at about 3x by its evaluation "
          "and its samples, not by the loop; with free samples and set-up they would reach nfev_s (c + p) + the scipy "
          "samples over nfev_c c, about 7x")


def compiled_forces_bench() -> None:
    """Constraint forces in the compiled evaluation (CompiledModel.forces: forward dynamics, lambda on the
    projection's rows by the LU factors of A_d, per-wheel contact-frame forces) against the compiled evaluation
    alone (CompiledModel.compute), both returning views: median of 7 batches of 5000 calls, interleaved."""
    print(f"\n{'robot':<20} {'compute [us]':>13} {'forces [us]':>12} {'added':>7}   robot.contact_forces [us]")
    for name in names():
        robot = robotdyn.load(name)
        rng = np.random.default_rng(3)
        q, nu = robot.neutral(), 0.3 * rng.normal(size=robot.mobility)
        tau = 0.1 * rng.normal(size=len(robot.motors))
        fast = compiled_model(robot)
        if fast is None:
            continue
        fast.forces(q, nu, tau)
        pairs = [(timeit(lambda: fast.compute(q, nu), repeat=1, number=5000),
                  timeit(lambda: fast.forces(q, nu, tau), repeat=1, number=5000)) for _ in range(7)]
        t_c = statistics.median(p[0] for p in pairs)
        t_f = statistics.median(p[1] for p in pairs)
        t_api = timeit(lambda: robot.contact_forces(q, nu, tau=tau), number=50)
        print(f"{name:<20} {t_c * 1e6:>13.2f} {t_f * 1e6:>12.2f} {100 * (t_f / t_c - 1):>6.0f}%   {t_api * 1e6:>8.0f}")


def rigid_limit_bench() -> None:
    """The rigid limit of the wheels' normal compliance in the compiled evaluation with forces
    (CompiledModel.forces: the split of the loads rigid-body dynamics leave open, robotdyn.contact.rigid_limit's
    formulas in C++) against the same call without it (rigid_limit(False): the basic solution), side by side:
    median of 7 batches of 5000 calls each, interleaved, on the rigid four-wheel bases of examples/ (wheels rolling)
    and every registered robot whose loads are open at its neutral configuration (issue 23: at most +25 %)."""
    from dataclasses import replace

    from robotdyn.interfaces.constraint_file import read
    from robotdyn.robot import Robot

    examples = Path(__file__).resolve().parents[1] / "examples"
    robots = []
    for name in ("husky_like", "jackal_like"):
        spec = read(examples / f"{name}.toml").SPEC
        wheels = [replace(w, friction="rolling", slip_velocity=None) for w in spec.wheels]
        robots.append((name + " (rolling)", Robot(replace(spec, wheels=wheels, independent=None))))
    for name in names():
        robot = robotdyn.load(name)
        f = robot.contact_forces(robot.neutral(), np.zeros(robot.mobility))
        if f.compliance is not None and f.compliance.any():
            robots.append((name, robot))
    print(f"\n{'robot (loads open)':<24} {'forces [us]':>12} {'+ rigid limit [us]':>19} {'added':>7}")
    for name, robot in robots:
        fast = compiled_model(robot)
        if fast is None:
            continue
        rng = np.random.default_rng(5)
        q, nu = robot.neutral(), 0.3 * rng.normal(size=robot.mobility)
        tau = 0.1 * rng.normal(size=len(robot.motors))
        fast.forces(q, nu, tau)

        def timed(on: bool) -> float:
            fast.rigid_limit(on)
            return timeit(lambda: fast.forces(q, nu, tau), repeat=1, number=5000)

        pairs = [(timed(False), timed(True)) for _ in range(7)]
        fast.rigid_limit(True)
        t_off = statistics.median(p[0] for p in pairs)
        t_on = statistics.median(p[1] for p in pairs)
        print(f"{name:<24} {t_off * 1e6:>12.2f} {t_on * 1e6:>19.2f} {100 * (t_on / t_off - 1):>6.0f}%")


def traction_bench() -> None:
    """The traction post-pass of ``robotdyn simulate`` (robotdyn.contact.traction.traction: per-sample wheel loads,
    required and minimum mu, events) on long runs, the fast pass (robotdyn.contact.traction_fast) next to the
    per-sample reference (constraint_forces at every sample): wall time of the traction() call alone (best of 3,
    reference: 1, after a warm-up), per sample, the ratio and the largest differences of the loads [N] and the
    minimum mu."""
    from robotdyn.contact.traction import traction

    print(f"\n{'traction post-pass':<40} {'samples':>8} {'fast [s]':>9} {'ref [s]':>8} {'us/sample':>10} "
          f"{'speed-up':>9} {'max|dN| [N]':>12} {'max|dmu_min|':>13}")
    for name, sc_name, t_end in (("quasimoro", "rectilinear", 200.0), ("linkage_suspension", "straight_line", 6.0),
                                 ("omni_caster", "circle", 20.0)):
        robot = robotdyn.load(name)
        sc = module(name).SCENARIOS[sc_name]
        traj = sc.run(robot, t_end=t_end, progress=False)
        traction(robot, traj, sc.torque)  # warm: imports, the floating twin, its compiled model
        walls = []
        for _ in range(3):
            start = time.perf_counter()
            fast = traction(robot, traj, sc.torque)
            walls.append(time.perf_counter() - start)
        start = time.perf_counter()
        ref = traction(robot, traj, sc.torque, method="reference")
        t_ref, t_fast = time.perf_counter() - start, min(walls)
        d_mu = (f"{float(np.max(np.abs(fast.minimum_mu - ref.minimum_mu))):>13.1e}" if ref.minimum_mu is not None
                else f"{'- (no column)':>13}")  # the robot's forces are determined: no minimum-mu column
        print(f"{name + ' / ' + sc_name + f' {t_end:g} s':<40} {len(traj.t):>8} {t_fast:>9.3f} {t_ref:>8.2f} "
              f"{1e6 * t_fast / len(traj.t):>10.1f} {t_ref / t_fast:>8.0f}x "
              f"{float(np.max(np.abs(fast.normal - ref.normal), initial=0.0)):>12.1e} {d_mu}"
              + ("" if fast.method == "fast" else f"   (fast pass not used: {fast.method})"))


def compliant_bench() -> None:
    """The linkage rover over its 5 cm bump, rigid contacts against compliant tyres (about 1 mm static deflection,
    robotdyn.robots.linkage_suspension.compliant), the same tolerances and samples: whole simulate() calls. Rigid:
    the scipy loop on the compiled model (the speed held by a Python function) and the compiled engine (the same law
    as data, adams); compliant: the compiled engine (its default dopri5, the stiff rosenbrock4, SUNDIALS CVODE's BDF
    at the same tolerance and at a 100x tighter one) and the Python path (LSODA). Issue 23's target: the compliant
    compiled run <= 10x the rigid compiled run."""
    from robotdyn.robot import Robot
    from robotdyn.robots.linkage_suspension.compliant import bump_run, compliant_spec
    from robotdyn.robots.linkage_suspension.model import PEAK_SPEED, SPEC

    rigid, soft = Robot(SPEC), Robot(compliant_spec())
    k = soft.constraints[0].normal_law.stiffness
    options = dict(rtol=1e-8, atol=1e-10, n_out=101)
    print(f"\nlinkage rover over the bump (5 cm step), rtol 1e-8, 101 samples; compliant tyres k = {k:.4g} N/m "
          "(1 mm static deflection) with a linear tyre law")
    print("each run's accuracy: max |q - q_ref| over the samples against the same model run at rtol 1e-11, atol "
          "1e-13 (compiled engine, dopri5)")
    print(f"{'run':<52} {'sim [s]':>8} {'wall [s]':>9} {'evals':>7} {'/ rigid':>8} {'/ rigid Py':>11} "
          f"{'|q - ref|':>9}  flight")
    runs = (("rigid, compiled model (scipy DOP853)", rigid, True, False, None),
            ("rigid, compiled engine (adams)", rigid, True, True, None),
            ("rigid, Python path", rigid, False, False, None),
            ("rigid, compiled engine (dopri5)", rigid, True, True, "dopri5"),
            ("compliant, compiled engine (dopri5)", soft, True, True, None),
            ("compliant, compiled engine (rosenbrock4)", soft, True, True, "rosenbrock4"),
            ("compliant, Python path (LSODA)", soft, False, False, None),
            ("compliant, compiled engine (cvode)", soft, True, True, "cvode"),
            ("compliant, compiled engine (cvode, rtol 1e-10)", soft, True, True, "cvode"))
    tighter = {runs[8][0]: dict(rtol=1e-10, atol=1e-12)}
    tight = dict(options, rtol=1e-11, atol=1e-13, method="dopri5")
    import sksundae.cvode  # noqa: F401 (cvode's import, once per process, is not timed: the models are warm too)

    for speed, t_end in ((PEAK_SPEED, 2.2), (25.0, 0.45)):
        walls, trajs = {}, {}
        refs = {id(robot): bump_run(robot, t_end, rigid, speed=speed, feedback=True, **tight) for robot in (rigid, soft)}
        for name, robot, compiled, feedback, method in runs:
            with use_compiled(compiled):
                start = time.perf_counter()
                traj = bump_run(robot, t_end, rigid, speed=speed, feedback=feedback, method=method,
                                **{**options, **tighter.get(name, {})})
                walls[name] = wall = time.perf_counter() - start
            trajs[name] = traj
            flight = traj.stats.get("flight")
            flights = "-" if flight is None else (f"{len(flight)} events" if flight else "none")
            ratio = wall / walls[runs[0][0]]
            ratio_py = wall / walls.get(runs[2][0], wall)
            error = float(np.max(np.abs(traj.q - refs[id(robot)].q)))
            print(f"{name + f' at {speed:.3g} rad/s':<52} {t_end:>8.3g} {wall:>9.3f} {traj.stats['nfev']:>7} "
                  f"{ratio:>8.1f} {ratio_py:>11.1f} {error:>9.1e}  {flights}")
        b = trajs[runs[6][0]]
        fastest = min(walls[runs[1][0]], walls[runs[3][0]])  # the rigid compiled engine, its better integrator
        for name in (runs[4][0], runs[5][0], runs[7][0], runs[8][0]):
            a = trajs[name]
            print(f"  {name}: {walls[name] / walls[runs[0][0]]:.1f}x the rigid scipy loop on the compiled model, "
                  f"{walls[name] / fastest:.1f}x the fastest rigid compiled engine run (issue 23 target <= 10x; "
                  f"evaluations {a.stats['nfev'] / trajs[runs[3][0]].stats['nfev']:.1f}x those of rigid dopri5); vs "
                  f"LSODA: max |q| difference {float(np.max(np.abs(a.q - b.q))):.1e}, flight events "
                  f"{len(a.stats['flight'])} vs {len(b.stats['flight'])}")


def simulate_many_bench(runs: int = 10_000) -> None:
    """robotdyn.simulation.batch.simulate_many: ten-second Quasimoro runs (the eq 19 pulse) with six parameters varied per run
    (M, m, d, r, J1, J2, uniform in physical ranges), 201 samples each, on 1 thread (a tenth of the runs) and 2."""
    from robotdyn.simulation.batch import simulate_many

    robot = robotdyn.load("quasimoro")
    pulse = module("quasimoro").SCENARIOS["rectilinear"].torque
    rng = np.random.default_rng(0)
    ranges = {"M": (4.5, 5.5), "m": (0.4, 0.6), "d": (0.15, 0.22), "r": (0.27, 0.33), "J1": (0.18, 0.22),
              "J2": (0.38, 0.42)}
    params = {k: rng.uniform(a, b, runs) for k, (a, b) in ranges.items()}
    simulate_many(robot, 10.0, torque=pulse, params={k: v[:50] for k, v in params.items()}, bounds=ranges)  # fit
    print(f"\nsimulate_many: {runs:,} ten-second Quasimoro runs, 6 parameters varied per run, 201 samples each")
    for threads, n in ((1, runs // 10), (2, runs)):
        start = time.perf_counter()
        out = simulate_many(robot, 10.0, torque=pulse, params={k: v[:n] for k, v in params.items()}, bounds=ranges,
                            n_out=201, threads=threads)
        wall = time.perf_counter() - start
        print(f"  {threads} thread(s): {n:,} runs in {wall:.2f} s ({n / wall:,.0f} runs/s; {int(out.ok.sum()):,} ok, "
              f"{out.nfev.mean():.0f} evaluations per run)")


def trajectory_optimisation_bench() -> None:
    """Quasimoro's minimum-effort rest-to-rest motion (1 m in 3 s, 21 nodes, abs(tau) <= 0.6 N m, abs(theta3) <= 0.06
    rad) on IPOPT, the defects' Jacobian from the analytic derivatives and from central finite differences, side by
    side (issue 26: target analytic >= 5x faster), with the nodes' dynamics batched (one compiled call per Jacobian,
    robotdyn.optimisation.node_batches) and node by node; 'jacobian' is the CPU time in the nodes' Jacobians, 'rest'
    the CPU time outside them (IPOPT, CasADi, the defects). The ceiling: with zero overhead the ratio tends to the
    Jacobians' own, 2 (n + k + m) evaluations over one derivative set, both timed in C++ without Python."""
    try:
        import casadi  # noqa: F401
    except ImportError:
        print("\ntrajectory optimisation: skipped (casadi not installed: pip install casadi)")
        return
    from robotdyn.optimisation import trajectory
    from robotdyn.robots.quasimoro.optimal_motion import rest_to_rest

    robot = robotdyn.load("quasimoro")
    q, nu = state(robot)
    tau = np.array([0.3, -0.2])
    t_an = timeit(lambda: robot.dynamics_derivatives(q, nu, tau), repeat=3, number=50)
    t_fw = timeit(lambda: robot.forward_dynamics(q, nu, tau, check=False), repeat=3, number=500)
    with use_compiled(False):
        t_fw_py = timeit(lambda: robot.forward_dynamics(q, nu, tau, check=False), repeat=3, number=200)
    n_in = robot.nq + robot.mobility + len(robot.motors)
    print(f"\nquasimoro per state: dynamics_derivatives {t_an * 1e3:.2f} ms (compiled); central differences "
          f"{2 * n_in} x forward_dynamics {t_fw * 1e3:.3f} ms (compiled) = {2 * n_in * t_fw * 1e3:.2f} ms "
          f"(Python path: {2 * n_in * t_fw_py * 1e3:.2f} ms)")
    ev = compiled_model(robot).ev
    if hasattr(ev, "derivatives_seconds"):
        t = ev.derivatives_seconds(q, nu, tau, 3000)
        d, e = t["derivatives"], t["rhs"]
        print(f"the same in C++ without Python (CPU): derivative set {d * 1e6:.1f} us = {d / e:.1f} evaluations of "
              f"{e * 1e6:.2f} us; central differences {2 * n_in} x {e * 1e6:.2f} = {2 * n_in * e * 1e6:.1f} us: the "
              f"ceiling of the optimisation's ratio (zero overhead) is {2 * n_in * e / d:.2f}x; 5x needs a derivative "
              f"set of <= {2 * n_in / 5:.1f} evaluations")

    def solve(derivatives: str) -> tuple:
        problem = rest_to_rest(nodes=21, robot=robot, derivatives=derivatives)
        spent, inner = [0.0], problem._jac_nodes

        def timed(X, U):
            start = time.process_time()
            out = inner(X, U)
            spent[0] += time.process_time() - start
            return out

        problem._jac_nodes = timed
        start = time.process_time()
        sol = problem.solve()
        return sol, time.process_time() - start, spent[0]

    batches = ("analytic_jacobians", "central_jacobians", "rhs_nodes")
    batched = {name: getattr(trajectory, name) for name in batches}
    print("quasimoro rest-to-rest 1 m in 3 s, 21 nodes, IPOPT (CasADi), best of 3:")
    print("(wall: IPOPT's call, TrajectorySolution.wall_time; cpu: this process's CPU time of the whole solve(), its "
          "set-up included (pattern, guess, nlpsol: about 8 ms); jacobian: the CPU time in the nodes' Jacobians; rest "
          "= cpu - jacobian: IPOPT, CasADi, the defects, the set-up)")
    print(f"{'nodes':<13} {'jacobian':<18} {'wall [s]':>9} {'cpu [s]':>8} {'jacobian [s]':>13} {'rest [s]':>9} "
          f"{'iterations':>11} {'cost [N^2 m^2 s]':>17} {'derivative calls':>17} {'dynamics calls':>15}")
    for mode in ("batched", "node by node"):
        for name in batches:
            setattr(trajectory, name, batched[name] if mode == "batched" else (lambda *args: None))
        runs: dict = {"analytic": [], "finite-difference": []}
        try:
            for _ in range(3):
                for derivatives in runs:
                    runs[derivatives].append(solve(derivatives))
        finally:
            for name in batches:
                setattr(trajectory, name, batched[name])
        best = {key: min(value, key=lambda r: r[1]) for key, value in runs.items()}  # least CPU time
        for derivatives, (sol, cpu, jac) in best.items():
            print(f"{mode:<13} {derivatives:<18} {sol.wall_time:>9.3f} {cpu:>8.3f} {jac:>13.3f} {cpu - jac:>9.3f} "
                  f"{sol.iterations:>11} {sol.cost:>17.9f} {sol.derivative_calls:>17} {sol.dynamics_calls:>15}")
        (a, a_cpu, _), (f, f_cpu, _) = best["analytic"], best["finite-difference"]
        print(f"{mode}: speed-up of analytic over finite differences {f.wall_time / a.wall_time:.2f}x wall, "
              f"{f_cpu / a_cpu:.2f}x CPU (target >= 5x; the derivatives and the forward dynamics compiled); "
              f"abs(cost difference) {abs(a.cost - f.cost):.1e}")

if __name__ == "__main__":
    if sys.argv[1:] == ["controllers"]:  # only this section: python bench/bench.py controllers
        controller_bench()
    elif sys.argv[1:] == ["profile"]:  # only this section: python bench/bench.py profile
        evaluation_profile_bench()
    elif sys.argv[1:] == ["trajectory"]:  # only this section: python bench/bench.py trajectory
        trajectory_optimisation_bench()
    elif sys.argv[1:] == ["compliant"]:  # only this section: python bench/bench.py compliant
        compliant_bench()
        from compliant_rolling_bench import compliant_rolling_bench

        compliant_rolling_bench()
    else:
        main()

"""The Python API's cost around the compiled calls, per call and per built-in robot (issue 26: a control or
trajectory-optimisation loop calls ``robot.dynamics_derivatives`` once per state): each public door next to the
raw binding it reaches (``Evaluator.derivatives``, ``evaluate``, ``forces``), at one admissible state per robot
(tests/test_dynamics_derivatives.py's ``admissible_state``). CPU time (``time.process_time``), best of several
rounds of many calls, every door measured in two passes (the first calls of a process run slower). With several
checkouts the rounds alternate between them (each in its own process, PYTHONPATH set to it), so the ratios are
side by side in one run. This is a benchmark, not a test: it asserts nothing.

Usage: python bench/api_overhead.py [--calls N] [--robots a,b] [CHECKOUT ...]   (default: this checkout)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ["quasimoro", "omni_caster", "linkage_suspension", "adaptable_wheel", "mmr12_eod"]


def cpu_us(f, calls: int, rounds: int = 5) -> float:
    """Best CPU time per call [us] of ``f`` over ``rounds`` rounds of ``calls`` calls."""
    best = float("inf")
    for _ in range(rounds):
        t = time.process_time()
        for _ in range(calls):
            f()
        best = min(best, (time.process_time() - t) / calls)
    return best * 1e6


def measure(names: list[str], calls: int) -> dict:
    """Per robot, per door: CPU microseconds per call (this process's robotdyn)."""
    import numpy as np

    sys.path.insert(0, str(Path(os.environ.get("PYTHONPATH", ROOT).split(os.pathsep)[0]) / "tests"))
    warnings.simplefilter("ignore")
    import robotdyn
    from robotdyn.fast.dispatch import compiled_model
    from robotdyn.reduction.linearization import linearize
    from test_dynamics_derivatives import START, admissible_state

    out = {}
    for name in names:
        r = robotdyn.load(name)
        q, nu, tau = admissible_state(r, START[name], np.random.default_rng(1))
        r.dynamics_derivatives(q, nu, tau)
        fast = compiled_model(r)
        doors = {
            "raw derivatives": (lambda: fast.ev.derivatives(q, nu, tau), calls),
            "dynamics_derivatives": (lambda: r.dynamics_derivatives(q, nu, tau), calls),
            "dynamics_derivatives(check=False)": (lambda: r.dynamics_derivatives(q, nu, tau, check=False), calls),
            "linearize": (lambda: linearize(r, q, nu, tau), calls // 2),
            "raw evaluate": (lambda: fast.ev.evaluate(q, nu), calls),
            "reduced": (lambda: r.reduced(q, nu), calls),
            "forward_dynamics": (lambda: r.forward_dynamics(q, nu, tau), calls // 4),
            "forward_dynamics(check=False)": (lambda: r.forward_dynamics(q, nu, tau, check=False), calls),
            "raw forces": (lambda: fast.ev.forces(q, nu, tau), calls),
            "contact_forces": (lambda: r.contact_forces(q, nu, tau), calls // 8),
            "contact_force_derivatives": (lambda: r.contact_force_derivatives(q, nu, tau),
                                          calls // 8 if name != "omni_caster" else 4),
        }
        row = {}
        for _ in range(2):
            for door, (f, n) in doors.items():
                row[door] = min(row.get(door, float("inf")), cpu_us(f, max(n, 1)))
        out[name] = row
    return out


def main() -> None:
    """Measure (``--child``: print JSON for the parent) or run each checkout and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkouts", nargs="*", default=[str(ROOT)])
    parser.add_argument("--calls", type=int, default=200)
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    names = args.robots.split(",")
    if args.child:
        print(json.dumps(measure(names, args.calls)))
        return
    results: dict[str, dict] = {}
    for _ in range(2):  # alternate the checkouts, keep each one's best
        for co in args.checkouts:
            env = {**os.environ, "PYTHONPATH": str(Path(co).resolve())}
            done = subprocess.run([sys.executable, __file__, "--child", "--calls", str(args.calls), "--robots",
                                   args.robots], env=env, cwd=co, capture_output=True, text=True, check=True)
            got = json.loads(done.stdout.strip().splitlines()[-1])
            mine = results.setdefault(co, {})
            for robot, row in got.items():
                for door, us in row.items():
                    mine.setdefault(robot, {})[door] = min(mine.get(robot, {}).get(door, float("inf")), us)
    print(f"CPU us per call, best of 2 x 2 x 5 rounds; load {os.getloadavg()[0]:.2f}")
    doors = list(next(iter(next(iter(results.values())).values())))
    for robot in names:
        print(f"\n{robot}")
        print(f"  {'door':36s}" + "".join(f"{Path(co).name:>14s}" for co in args.checkouts))
        for door in doors:
            print(f"  {door:36s}" + "".join(f"{results[co][robot][door]:14.1f}" for co in args.checkouts))


if __name__ == "__main__":
    main()

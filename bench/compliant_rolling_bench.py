"""Compliant wheels that roll while in contact (examples/bump_base_rolling.toml: the rigid four-wheel base on rolling
compliant tyres crossing its bump at 4 m/s, front and rear wheels flying and landing) on the compiled engine
(robotdyn.simulation.compiled_rolling, dopri5) and on the Python path (robotdyn.simulation.compliant_rolling, scipy
LSODA), the same tolerances and samples, side by side in one run: whole simulate() calls, their evaluations, the
contact switches, and the largest differences between the two runs. Run alone: ``python bench/compliant_rolling_bench.py``.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from robotdyn.interfaces.constraint_file import read

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "bump_base_rolling.toml"


def compliant_rolling_bench(t_end: float = 1.0) -> None:
    """Print the compiled and the Python run of the example's ``bump`` scenario (``t_end`` [s], rtol 1e-8)."""
    cf = read(EXAMPLE)
    robot, scenario = cf.robot(), cf.SCENARIOS["bump"]
    options = dict(t_end=t_end, rtol=1e-8, atol=1e-10, progress=False)
    print(f"\nbump_base_rolling (rolling compliant tyres) over the bump, {t_end:g} s, rtol 1e-8:")
    print(f"{'engine':<34} {'wall [s]':>9} {'evals':>7} {'switches':>9} {'touch-down loss [J]':>20}")
    runs = {}
    for engine in ("compiled", "scipy"):
        start = time.perf_counter()
        traj = scenario.run(robot, engine=engine, **options)
        wall = time.perf_counter() - start
        runs[engine] = (traj, wall)
        print(f"{traj.stats['engine']:<34} {wall:>9.3f} {traj.stats['nfev']:>7} {traj.stats['contact_switches']:>9} "
              f"{traj.stats['touchdown_loss']:>20.12g}")
    (a, wa), (b, wb) = runs["compiled"], runs["scipy"]
    ta = np.array([e["t"] for e in a.stats["flight"]])
    tb = np.array([e["t"] for e in b.stats["flight"]])
    same = len(ta) == len(tb)
    print(f"  compiled / Python wall: {wa / wb:.3f} ({wb / wa:.0f}x faster); max |q| difference "
          f"{float(np.max(np.abs(a.q - b.q))):.1e}; events {len(ta)} vs {len(tb)}"
          + (f", max |t| difference {float(np.max(np.abs(ta - tb))):.1e} s" if same and len(ta) else "")
          + f"; touch-down loss relative difference "
          f"{abs(a.stats['touchdown_loss'] - b.stats['touchdown_loss']) / max(b.stats['touchdown_loss'], 1e-300):.1e}")


if __name__ == "__main__":
    compliant_rolling_bench()

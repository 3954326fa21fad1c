"""Robustness of the rover's traction-limited trajectory optimisation (robotdyn.robots.linkage_suspension.
traction_path) against its start: IPOPT from the minimum-effort motion with its torques perturbed by a relative
``eps`` (seeds 0 .. starts - 1), as the notebook ``rover_path_traction.ipynb`` starts it with ``eps = 0``.

Prints, per start, IPOPT's status, the cost, its iterations and wall time, then how many converged and the spread
of their costs (relative). Measured (issue 26), before the Jacobian's rounding residues reached IPOPT as exact
zeros (robotdyn.optimisation.callbacks.exact_zeros): with the Jacobian dense to CasADi, 16 of 32 starts at 1e-8
and 1 of 32 at 1e-6 converged; with its pattern declared, 32/32, 32/32, 14/16 and 0/16 at 1e-8, 1e-6, 1e-4 and
1e-2. After: 32/32, 32/32, 16/16 and 16/16, costs equal to 2e-15, 12 to 17 iterations.

Run: ``python bench/traction_path_starts.py [starts [eps ...]]`` (default: 16 starts at 1e-8, 1e-6, 1e-4 and
1e-2; about 1 s per start on an idle machine).
"""

from __future__ import annotations

import contextlib
import io
import sys

import numpy as np


def starts(count: int, eps: float, robot, free) -> list:
    """Solve the traction-limited problem from ``count`` perturbed starts.

    Args:
        count: Number of starts (seeds 0 .. count - 1).
        eps: Relative perturbation of the start's torques (normal, standard deviation eps).
        robot: The linkage rover.
        free: The minimum-effort solution (no traction rows) whose motion is the start.

    Returns:
        ``[(success, cost, iterations, wall time [s]), ...]``, one per start.
    """
    from robotdyn.robots.linkage_suspension import traction_path as tp

    out = []
    for seed in range(count):
        rng = np.random.default_rng(seed)
        problem = tp.traction_path(mu_max=tp.MU_MAX, robot=robot)
        problem.guess = (free.q, free.nu, free.tau * (1 + eps * rng.normal(size=free.tau.shape)))
        with contextlib.redirect_stdout(io.StringIO()):
            s = problem.solve()
        print(f"  seed {seed:>2}: {s.status:<26} cost {s.cost:.12f}  {s.iterations:>3} iterations  "
              f"{s.wall_time:.2f} s", flush=True)
        out.append((s.success, s.cost, s.iterations, s.wall_time))
    return out


def main(argv: list[str]) -> None:
    """Command line: ``[starts [eps ...]]``.

    Args:
        argv: The arguments after the script's name.
    """
    import robotdyn
    from robotdyn.robots.linkage_suspension import traction_path as tp

    count = int(argv[0]) if argv else 16
    epsilons = [float(a) for a in argv[1:]] or [1e-8, 1e-6, 1e-4, 1e-2]
    robot = robotdyn.load("linkage_suspension")
    free = tp.traction_path(mu_max=None, min_load=None, robot=robot).solve()
    for eps in epsilons:
        print(f"traction-limited rover path from {count} starts, torques perturbed by {eps:g}:")
        runs = starts(count, eps, robot, free)
        costs = np.array([c for ok, c, _, _ in runs if ok])
        spread = (costs.max() - costs.min()) / costs.mean() if costs.size else float("nan")
        print(f"{costs.size}/{count} converged; cost spread {spread:.2g} (relative); iterations median "
              f"{np.median([r[2] for r in runs]):g}, wall median {np.median([r[3] for r in runs]):.2f} s")


if __name__ == "__main__":
    main(sys.argv[1:])

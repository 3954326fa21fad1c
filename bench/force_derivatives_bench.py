"""The compiled contact-force and required-mu derivatives (robotdyn.contact.compiled_force_derivatives) against the
Python path, per call on the robots the compiled path serves, and the linkage rover's traction-limited path
optimisation (robotdyn.robots.linkage_suspension.traction_path, analytic derivatives) with each, side by side in
one run. Run alone: ``python bench/force_derivatives_bench.py`` (``--no-optimisation``: the per-call lines only).
"""

from __future__ import annotations

import sys
from pathlib import Path
from unittest import mock

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from robotdyn.contact import force_derivatives  # noqa: E402
from robotdyn.contact import compiled_force_derivatives as fast_forces  # noqa: E402
from robotdyn.robot import Robot  # noqa: E402
from robotdyn.robots import module  # noqa: E402


from derivatives_bench import _best as _median  # noqa: E402 (bench/: the same median-of-batches timer)


def per_call() -> None:
    from test_dynamics_derivatives import START, admissible_state

    print("\ncontact-force and required-mu derivatives per state [ms]: Robot.contact_force_derivatives compiled "
          "against the Python path (largest difference relative to the largest entry of dforce/dq)")
    print(f"{'robot':<20} {'n':>3} {'m':>3} {'compiled':>9} {'Python':>9} {'ratio':>7} {'difference':>11}")
    for name in ("quasimoro", "mmr12_eod", "adaptable_wheel", "linkage_suspension"):
        robot = Robot(module(name).SPEC)
        q, nu, tau = admissible_state(robot, START[name], np.random.default_rng(0))
        fast = robot.contact_force_derivatives(q, nu, tau)
        ref = force_derivatives.contact_force_derivatives(robot, q, nu, tau)
        assert fast_forces.compiled_force_derivatives(robot, q, nu, tau) is not None
        err = np.abs(fast.dforce_dq - ref.dforce_dq).max() / max(1.0, np.abs(ref.dforce_dq).max())
        t_c = _median(lambda: robot.contact_force_derivatives(q, nu, tau), 20)
        t_p = _median(lambda: force_derivatives.contact_force_derivatives(robot, q, nu, tau), 2, 3)
        print(f"{name:<20} {robot.nq:>3} {len(fast.lam):>3} {t_c * 1e3:>9.3f} {t_p * 1e3:>9.2f} {t_p / t_c:>6.0f}x "
              f"{err:>11.1e}")


def optimisation() -> None:
    from robotdyn.robots.linkage_suspension.traction_path import traction_path

    print("\nlinkage rover, traction-limited path (mu <= 0.15, loads >= 10 N, 5 nodes), IPOPT with analytic "
          "derivatives: force derivatives compiled against the Python path")
    print(f"{'force derivatives':<18} {'wall [s]':>9} {'iterations':>11} {'cost':>17}")
    results = {}
    for label in ("compiled", "Python"):
        if label == "Python":  # the compiled twin declines: Robot.contact_force_derivatives takes the Python path
            with mock.patch.object(fast_forces, "compiled_force_derivatives", lambda *a: None):
                sol = traction_path().solve()
        else:
            sol = traction_path().solve()
        results[label] = sol
        print(f"{label:<18} {sol.wall_time:>9.2f} {sol.iterations:>11} {sol.cost:>17.9f}")
    c, p = results["compiled"], results["Python"]
    print(f"speed-up {p.wall_time / c.wall_time:.1f}x; costs differ by {abs(c.cost - p.cost):.1e}")


def force_derivatives_bench(with_optimisation: bool = True) -> None:
    per_call()
    if with_optimisation:
        optimisation()


if __name__ == "__main__":
    force_derivatives_bench("--no-optimisation" not in sys.argv[1:])

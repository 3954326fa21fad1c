"""The compiled derivatives of the reduced forward dynamics (robotdyn.fast.compiled_derivatives), per robot, in
units of one compiled evaluation, and against central finite differences of the compiled model (issue 26:
targets <= 5 evaluations, and >= 10x faster than finite differences on the six-wheel linkage rover).

One compiled evaluation is one forward-dynamics right-hand side of the compiled model (``Evaluator.rhs``:
configuration and state passes, the reduced solve): what a finite-difference Jacobian calls 2 (n + k + m) times.
The derivative set is (nudot, d/dq, d/dnu, d/dtau, dqdot/dq, S) in one C++ call; the API line adds the Python
wrapper (checks, the independent position coordinates). Run alone: ``python bench/derivatives_bench.py``.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from robotdyn.fast.compiled_derivatives import compiled_derivatives  # noqa: E402
from robotdyn.fast.dispatch import compiled_model  # noqa: E402
from robotdyn.reduction.dynamics_derivatives import dynamics_derivatives  # noqa: E402
from robotdyn.robot import Robot  # noqa: E402
from robotdyn.robots import module, names  # noqa: E402


def _best(fn, number: int, repeat: int = 5) -> float:
    """Median seconds per call over ``repeat`` batches of ``number`` calls (after one warm-up call)."""
    fn()
    runs = []
    for _ in range(repeat):
        t = time.perf_counter()
        for _ in range(number):
            fn()
        runs.append((time.perf_counter() - t) / number)
    return statistics.median(runs)


def _state(robot, name: str, rng):
    from test_dynamics_derivatives import START, admissible_state

    return admissible_state(robot, START.get(name), rng)


def central_differences(ev, q, nu, tau, T) -> np.ndarray:
    """The Jacobian of (qdot, nudot) in (q_P, nu, tau) by central differences of the compiled right-hand side, q
    moved along the holonomic manifold's tangent T (n, p) (off it the redundant closure rows stop spanning)."""
    n, k, p = len(q), len(nu), T.shape[1]
    y = np.concatenate([np.zeros(p), nu, tau])
    cols = []
    for i in range(y.size):
        h = np.cbrt(np.finfo(float).eps) * (1.0 + abs(y[i]))
        yp, ym = y.copy(), y.copy()
        yp[i] += h
        ym[i] -= h
        cols.append((ev.rhs(q + T @ yp[:p], yp[p:p + k], yp[p + k:], 0.0)
                     - ev.rhs(q + T @ ym[:p], ym[p:p + k], ym[p + k:], 0.0)) / (2 * h))
    return np.column_stack(cols)


def pinocchio_floor(robot, q, v) -> float:
    """Seconds per call of Pinocchio's own computeABADerivatives on the robot's tree at (q, v, tau = 0), no
    constraints: the floor of any derivative set of these dynamics on Pinocchio (its Python binding's call included)."""
    import pinocchio as pin

    model = robot.model
    data = model.createData()
    tau = np.zeros(model.nv)
    return _best(lambda: pin.computeABADerivatives(model, data, q, v, tau), 500)


def cpu_seconds(ev, q, nu, tau, repeat: int = 300) -> dict:
    """CPU seconds per call of the derivative set and of one evaluation, timed in C++ (Evaluator.derivatives_seconds),
    the median of 5 calls of ``repeat`` repetitions each.

    Args:
        ev: The compiled evaluator (``compiled_model(robot).ev``), its projection chosen at q.
        q: Natural coordinates (n,).
        nu: Independent velocities (k,).
        tau: Motor torques (motors,).
        repeat: Repetitions per timed call.
    """
    runs = [ev.derivatives_seconds(q, nu, tau, repeat) for _ in range(5)]
    return {key: statistics.median(r[key] for r in runs) for key in ("derivatives", "rhs")}


def derivatives_bench() -> None:
    print("\ncompiled derivatives of the reduced dynamics (nudot, d/dq, d/dnu, d/dtau, dqdot/dq, S) per state [us]; "
          "'evals' = time / one compiled evaluation (rhs); API: Robot.dynamics_derivatives, checked and with "
          "check=False; floor: Pinocchio's computeABADerivatives on the unconstrained tree; 'CPU evals': the same ratio "
          "in CPU time, both timed in C++ without Python (Evaluator.derivatives_seconds: robust under load)")
    print(f"{'robot':<20} {'n':>3} {'k':>3} {'eval':>7} {'derivs C++':>11} {'evals':>6} {'CPU evals':>9} {'API':>8} "
          f"{'evals':>6} {'unchecked':>10} {'evals':>6} {'floor':>7} {'evals':>6} {'Python path':>12} {'/ C++':>7}")
    rng = np.random.default_rng(0)
    for name in names():
        robot = Robot(module(name).SPEC)
        q, nu, tau = _state(robot, name, rng)
        fast = compiled_model(robot)
        if compiled_derivatives(robot, q, nu, tau) is None:
            print(f"{name:<20} {robot.nq:>3} {robot.mobility:>3}   Python path (the compiled model does not serve)")
            continue
        ev = fast.ev
        t_ev = _best(lambda: ev.rhs(q, nu, tau, 0.0), 500)
        t_c = _best(lambda: ev.derivatives(q, nu, tau), 100)
        t_api = _best(lambda: robot.dynamics_derivatives(q, nu, tau), 50)
        t_fast = _best(lambda: robot.dynamics_derivatives(q, nu, tau, check=False), 50)
        t_floor = pinocchio_floor(robot, q, fast.ev.derivatives(q, nu, tau)[4])
        t_py = _best(lambda: dynamics_derivatives(robot, q, nu, tau), 3, 3)
        cpu = cpu_seconds(ev, q, nu, tau)
        print(f"{name:<20} {robot.nq:>3} {robot.mobility:>3} {t_ev * 1e6:>7.1f} {t_c * 1e6:>11.1f} {t_c / t_ev:>6.1f} "
              f"{cpu['derivatives'] / cpu['rhs']:>9.2f} {t_api * 1e6:>8.1f} {t_api / t_ev:>6.1f} {t_fast * 1e6:>10.1f} {t_fast / t_ev:>6.1f} "
              f"{t_floor * 1e6:>7.1f} {t_floor / t_ev:>6.1f} {t_py * 1e6:>12.0f} {t_py / t_c:>6.0f}x")
        if name == "linkage_suspension":
            linkage = (robot, ev, q, nu, tau, t_ev, t_c, t_api, cpu)
    robot, ev, q, nu, tau, t_ev, t_c, t_api, cpu = linkage
    d = robot.dynamics_derivatives(q, nu, tau)
    T = d.tangent
    t_fd = _best(lambda: central_differences(ev, q, nu, tau, T), 3, 3)
    J = central_differences(ev, q, nu, tau, T)
    n, p = robot.nq, T.shape[1]
    exact = np.hstack([d.dq_manifold, d.dnu, d.dtau])
    err = np.abs(J[n:] - exact).max() / max(1.0, np.abs(exact).max())
    m = len(robot.motors)
    print(f"linkage rover (n = {n}: {p} independent positions, k = {robot.mobility}, {m} motors): central "
          f"differences of the compiled model along the manifold, {2 * (p + robot.mobility + m)} evaluations "
          f"{t_fd * 1e3:.2f} ms; compiled derivatives {t_c * 1e3:.3f} ms "
          f"({t_fd / t_c:.0f}x faster; API {t_fd / t_api:.0f}x), their largest difference {err:.1e} (relative; the "
          "differences' own error)")
    print(f"  the same in C++ CPU time without Python: {2 * (p + robot.mobility + m)} evaluations of "
          f"{cpu['rhs'] * 1e6:.1f} us against one derivative set of {cpu['derivatives'] * 1e6:.1f} us: "
          f"{2 * (p + robot.mobility + m) * cpu['rhs'] / cpu['derivatives']:.1f}x")

    operational_and_slipping_bench()


def operational_and_slipping_bench() -> None:
    """The compiled derivatives with operational-space velocities (TIAGo driven by its base twist) and with slipping
    wheels (the skid-steer example, linear tyre law), against their Python path, per state."""
    from dataclasses import replace

    from robotdyn.contact.sliding_derivatives import sliding_derivatives
    from robotdyn.interfaces.constraint_file import read
    from robotdyn.reduction.operational_space import OperationalVelocities

    examples = Path(__file__).resolve().parents[1] / "examples"
    spec = read(examples / "tiago.toml").SPEC
    tiago = Robot(replace(spec, independent=None, operational=OperationalVelocities(
        "base_footprint", ("vx", "wz"), "local", ["vx", "wz"])))
    skid = read(examples / "skid_steer.toml").robot()
    rng = np.random.default_rng(0)
    q = tiago.neutral()
    q[:5] = rng.uniform(-2, 2, 5)
    cases = [("tiago (twist)", tiago, (q, rng.normal(size=2), rng.normal(size=2)), dynamics_derivatives)]
    q = skid.neutral()
    for c in ("x", "y", "yaw", "front_left_spin", "rear_right_spin"):
        q[skid.coordinate_index(c)] = rng.uniform(-1, 1)
    cases.append(("skid_steer (slipping)", skid, (q, rng.normal(size=skid.mobility) * 0.5, rng.normal(size=4)),
                  sliding_derivatives))
    print(f"{'robot':<22} {'n':>3} {'k':>3} {'eval':>7} {'derivs C++':>11} {'evals':>6} {'API':>8} "
          f"{'Python path':>12} {'/ C++':>7}")
    for name, robot, (q, nu, tau), python_path in cases:
        ev = compiled_model(robot).ev
        assert compiled_derivatives(robot, q, nu, tau) is not None, name
        rhs = (lambda: ev.slip_rhs(q, nu, tau, 0.0)) if ev.slipping else (lambda: ev.rhs(q, nu, tau, 0.0))
        t_ev = _best(rhs, 500)
        t_c = _best(lambda: ev.derivatives(q, nu, tau), 100)
        t_api = _best(lambda: robot.dynamics_derivatives(q, nu, tau), 50)
        t_py = _best(lambda: python_path(robot, q, nu, tau), 3, 3)
        print(f"{name:<22} {robot.nq:>3} {robot.mobility:>3} {t_ev * 1e6:>7.1f} {t_c * 1e6:>11.1f} "
              f"{t_c / t_ev:>6.1f} {t_api * 1e6:>8.1f} {t_py * 1e6:>12.0f} {t_py / t_c:>6.0f}x")


if __name__ == "__main__":
    derivatives_bench()

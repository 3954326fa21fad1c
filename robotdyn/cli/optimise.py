"""``robotdyn optimise``: a minimum-effort motion between two states in a fixed time, by trajectory optimisation
(:mod:`robotdyn.optimisation.trajectory`: trapezoidal collocation on IPOPT through CasADi)."""

from __future__ import annotations

import numpy as np

from ..errors import RobotDynError
from ..inputs import MAX_POSITION, as_vector, parse_assignments


def _ranges(items, option: str) -> dict[str, tuple[float, float]]:
    """``NAME=LO:HI`` options as finite (lower, upper) pairs by name (one line naming the option otherwise)."""
    out = {}
    for name, value in parse_assignments(items, option).items():
        try:
            lo, hi = (float(x) for x in value.split(":"))
        except ValueError:
            raise RobotDynError(f"{option} {name}={value!r}: expected LOWER:UPPER, two numbers in SI units") from None
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
            raise RobotDynError(f"{option} {name}={value!r}: expected finite LOWER <= UPPER")
        out[name] = (lo, hi)
    return out


def cmd_optimise(args) -> int:
    """``robotdyn optimise ROBOT --t-end T [--nodes N] [--q0 ...] [--end NAME=VALUE ...] [--bound NAME=LO:HI ...]
    [--tau-max X] [--min-load N] [--mu-max MU] [--cost effort|peak-mu] [--derivatives analytic|finite-difference]
    [--csv FILE]``.

    Args:
        args: The parsed command line (argparse namespace of :func:`register`'s parser).

    Returns:
        The exit status (0; a problem IPOPT could not solve raises a one-line error and prints nothing else).
    """
    from ..optimisation.trajectory import TrajectoryProblem
    from ..output import atomic_output
    from .commands import _emit, _load, _numbers

    _, robot = _load(args)
    q0 = robot.neutral() if args.q0 is None else as_vector(args.q0, robot.nq, "--q0", robot.coordinates,
                                                              MAX_POSITION)
    end = _numbers(args.end, "--end", "a final coordinate value in m or rad")
    bounds = _ranges(args.bound, "--bound")
    tau = None if args.tau_max is None else (-args.tau_max, args.tau_max)
    problem = TrajectoryProblem(robot, args.t_end, args.nodes, q0, q_end=end, tau_bounds=tau, bounds=bounds,
                                derivatives=args.derivatives, min_load=args.min_load, mu_max=args.mu_max,
                                cost=args.cost)
    s = problem.solve()
    if not s.success:  # nothing printed or written: an unconverged iterate is not a result
        raise RobotDynError(f"the optimisation did not converge: IPOPT {s.status} after {s.iterations} iterations, "
                            f"largest defect {s.max_defect:.2g}: {s.diagnosis}"
                            + (f"; the model refused a point IPOPT tried: {problem.refused}"
                               if getattr(problem, "refused", None) else ""))
    if args.csv:
        header = ["t"] + s.coordinates + s.velocity_names + [f"tau_{m}" for m in s.motors]
        with atomic_output(args.csv, "CSV file") as tmp:
            np.savetxt(tmp, np.column_stack([s.t, s.q, s.nu, s.tau]), delimiter=",", header=",".join(header),
                       comments="", fmt="%.12g")
    out = {"robot": args.robot, "status": s.status, "success": s.success, "cost": s.cost,
           "iterations": s.iterations, "wall_time": s.wall_time, "max_defect": s.max_defect,
           "derivatives": s.derivatives, "t": s.t, "coordinates": s.coordinates, "q": s.q,
           "velocity_names": s.velocity_names, "nu": s.nu, "motors": s.motors, "tau": s.tau}
    if s.forces is not None:
        out.update({"wheels": s.wheels, "forces": s.forces, "required_mu": s.required_mu, "effort": s.effort})
    peak = ", ".join(f"{m} {np.max(np.abs(s.tau[:, i])):.6g}" for i, m in enumerate(s.motors))
    final = ", ".join(f"{c} {x:.6g}" for c, x in zip(s.coordinates, s.q[-1]))
    text = "\n".join([repr(problem), f"IPOPT: {s.status} after {s.iterations} iterations ({s.wall_time:.3g} s)",
                      (f"cost (integral of |tau|^2 dt) = {s.cost:.10g} N^2 m^2 s" if args.cost == "effort" else
                       f"cost (peak required mu squared + {problem.effort_weight:g} x effort) = {s.cost:.10g}")
                      + f"; largest defect {s.max_defect:.2g}",
                      f"peak |tau| [N m or N]: {peak}", f"final coordinates: {final}"]
                     + ([f"least wheel load [N]: {np.min(s.forces[..., 2]):.6g}; peak required mu: "
                         f"{np.max(s.required_mu):.6g}; effort {s.effort:.10g} N^2 m^2 s"] if s.forces is not None else [])
                     + ([f"node table written to {args.csv}"] if args.csv else []))
    _emit(args, out, text)
    return 0


def _positive(text: str) -> float:
    """An argparse type: a finite number > 0 (argparse names the option in its one-line error)."""
    import argparse

    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}; expected a finite number > 0 [N m or N]")
    return value


def _nonnegative(text: str) -> float:
    """An argparse type: a finite number >= 0 (argparse names the option in its one-line error)."""
    import argparse

    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text!r}; expected a finite number >= 0")
    return value


def register(sub, parents) -> None:
    """Add the ``optimise`` subcommand.

    Args:
        sub: The ``robotdyn`` parser's subparsers.
        parents: The parsers whose options every robot command shares (``--json``, ROBOT, ``--urdf`` ...).
    """
    from .commands import _duration

    p = sub.add_parser("optimise", parents=parents,
                       help="minimum-effort motion from rest to given final coordinates in a fixed time (IPOPT)")
    p.add_argument("--t-end", type=_duration, required=True, help="duration of the motion [s]")
    p.add_argument("--nodes", type=int, default=41, help="collocation nodes (default 41)")
    p.add_argument("--q0", nargs="+", help="initial natural coordinates (default: the neutral configuration); "
                                           "the robot starts and ends at rest")
    p.add_argument("--end", action="append", default=[], metavar="NAME=VALUE",
                   help="a final coordinate, e.g. --end x=1 (repeatable; the others are free)")
    p.add_argument("--bound", action="append", default=[], metavar="NAME=LO:HI",
                   help="bounds on a coordinate or velocity at every node, e.g. --bound theta3=-0.06:0.06")
    p.add_argument("--tau-max", type=_positive, default=None, help="bound on every motor torque |tau| [N m or N]")
    p.add_argument("--derivatives", choices=("analytic", "finite-difference"), default="analytic",
                   help="the constraint Jacobian from the analytic derivatives (default) or finite differences")
    p.add_argument("--min-load", type=_nonnegative, default=None,
                   help="least normal load of every wheel at every node [N]")
    p.add_argument("--mu-max", type=_nonnegative, default=None,
                   help="largest required friction coefficient |f_t|/f_n of every wheel at every node")
    p.add_argument("--cost", choices=("effort", "peak-mu"), default="effort",
                   help="minimise the effort (default) or the peak required mu over wheels and nodes")
    p.add_argument("--csv", help="write the node table (t, q, nu, tau columns) to this CSV file")
    p.set_defaults(func=cmd_optimise)


__all__ = ["cmd_optimise", "register"]

"""``robotdyn sweep``: the command line of :mod:`robotdyn.sweep.runner` (a sweep TOML file and/or flags; flags win).

Registering the subcommand imports nothing heavy: Dask, pyarrow and the robot load only when the command runs.
"""

from __future__ import annotations

import os
import sys

EXAMPLES = """examples:
  robotdyn sweep quasimoro --vary M=4:6:5 --vary d=0.1:0.3:5 --t-end 10 --out sweep_M_d
  robotdyn sweep quasimoro --vary "M=4 kg:6 kg" --vary torque_scale=0.5:2:log --sample lhs --n 200 --seed 1
  robotdyn sweep --spec study.toml --scheduler tcp://head-node:8786      # on a running Dask cluster
"""


def register(sub, parents) -> None:
    """Add ``sweep`` to the CLI's subparsers (``parents``: the common and robot arguments).

    Args:
        sub: The CLI's subparsers (``argparse`` action).
        parents: Parsers whose arguments it inherits (the common and robot arguments).
    """
    import argparse

    p = sub.add_parser("sweep", parents=parents, help="parameter sweep on Dask, results in Parquet",
                       epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Runs a grid or sample of parameters x scenarios x terrains x torque scale on "
                                   "Dask; writes DIR/results.parquet (one row per run) and DIR/summary.png; a "
                                   "rerun of the same sweep resumes. --param NAME=VALUE holds a parameter fixed.")
    p.add_argument("--spec", metavar="FILE", help="sweep TOML file (see robotdyn.sweep.spec); flags override it")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=RANGE",
                   help="a varied parameter: NAME=LO:HI[:N][:log] (a range, N grid points) or NAME=V1,V2,... "
                        "(values); in the parameter's unit (robotdyn info ROBOT), e.g. M=4:6:5, 'd=0.1 m:0.3 m:3'; "
                        "torque_scale multiplies the scenario's torques (repeatable)")
    p.add_argument("--scenario", action="append", default=[], help="scenario (repeatable; default: the first)")
    p.add_argument("--terrain", action="append", default=[],
                   help="terrain: a name of the robot's terrains or KIND[:ARG=VALUE,...], e.g. ramp:slope=0.1 "
                        "(repeatable; default: the robot's own)")
    p.add_argument("--sample", choices=("grid", "random", "lhs"), help="grid (default), random or Latin hypercube")
    p.add_argument("--n", type=int, help="number of samples (random, lhs)")
    p.add_argument("--seed", type=int, help="seed of the sample (default 0)")
    p.add_argument("--t-end", type=float, help="duration [s] of each run (default: the scenario's)")
    p.add_argument("--n-out", type=int, help="output samples per run (default: the scenario's rate)")
    p.add_argument("--rtol", type=float, help="relative tolerance of the integrator (default: the scenario's)")
    p.add_argument("--atol", type=float, help="absolute tolerance of the integrator (default: the scenario's)")
    p.add_argument("--method", help="integrator of every run, as simulate --method takes it (e.g. cvode for stiff "
                   "compliant wheels; default: simulate's)")
    p.add_argument("--column", action="append", default=[],
                   help="a column whose max and min are kept (repeatable; default: every coordinate and velocity)")
    p.add_argument("--trajectories", action="store_true", help="also keep every trajectory (DIR/trajectories/)")
    p.add_argument("--plot-column", help="output column of the summary plot (default: max of the first --column)")
    p.add_argument("--no-plot", action="store_true", help="no summary plot")
    p.add_argument("--out", default="sweep", metavar="DIR", help="sweep directory (default: ./sweep)")
    p.add_argument("--workers", type=int, default=None,
                   help="worker processes of the local Dask cluster (default: one per CPU; 0: in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler, e.g. tcp://host:8786")
    p.add_argument("--chunk-size", type=int, help="runs per Dask task (default: about 32 tasks per worker)")
    p.add_argument("--time-limit", type=float, metavar="SECONDS",
                   help="wall-clock limit of one run (default 600; 0: none): beyond it the run is an error row")
    p.add_argument("--retry-errors", action="store_true", help="compute again the runs that ended in an error")
    p.add_argument("--replace", action="store_true",
                   help="delete the results of another sweep found in --out (else refused: its runs are not this "
                        "sweep's, e.g. another specification or an input changed since)")
    p.add_argument("--batch", choices=("auto", "always", "never"), default="auto",
                   help="simulate runs that vary only masses, inertias, lengths as variants of one compiled model "
                        "(auto: where the sweep is large enough to pay for the fit; never: build every run)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_sweep)


def spec_from_args(args):
    """The sweep spec of the command line: the ``--spec`` file, then the flags on top.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The :class:`~robotdyn.sweep.spec.SweepSpec` of the ``--spec`` file (or the default spec) with the command line's
        flags merged on top.
    """
    from ..inputs import parse_assignments
    from ..sweep.spec import SweepSpec, from_toml, parse_axis

    spec = from_toml(args.spec) if args.spec else SweepSpec()
    if args.robot is not None or args.constraints is not None:
        spec.robot, spec.constraints = args.robot, args.constraints
    if args.urdf is not None:
        spec.urdf = args.urdf
    spec.xacro_args.update(parse_assignments(args.xacro_arg, "--xacro-arg"))
    spec.fixed.update(parse_assignments(args.param))
    return spec.merged(axes=[parse_axis(v) for v in args.vary], scenarios=args.scenario, terrains=args.terrain,
                       sample=args.sample, n=args.n, seed=args.seed, t_end=args.t_end, n_out=args.n_out,
                       rtol=args.rtol, atol=args.atol, method=args.method, columns=args.column,
                       trajectories=args.trajectories or None, plot_column=args.plot_column,
                       time_limit=args.time_limit)


def cmd_sweep(args) -> int:
    """``robotdyn sweep``: run a parameter sweep and print its summary.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status (0 on success; 130 after an interruption whose partial results were kept). Errors raise
        :class:`~robotdyn.errors.RobotDynError`, which :func:`~robotdyn.cli.commands.main` prints in one line with
        status 2.
    """
    import signal
    import threading

    from .commands import _emit
    from ..errors import InputError
    from ..sweep.runner import run

    for flag in ("workers", "chunk_size", "n", "n_out"):
        value = getattr(args, flag)
        if value is not None and value < (0 if flag == "workers" else 1):
            raise InputError(f"--{flag.replace('_', '-')} {value}; expected a whole number >= "
                             f"{0 if flag == 'workers' else 1}")
    from ..sweep.runner import WORKERS_PER_CPU, max_local_workers

    if args.workers is not None and args.workers > max_local_workers() and args.scheduler is None:
        raise InputError(f"--workers {args.workers}: more worker processes than this machine runs usefully; expected "
                         f"at most {max_local_workers()} ({WORKERS_PER_CPU} per CPU), or a cluster: --scheduler "
                         "ADDRESS")
    for flag, value, where in (("--twist", args.twist, "[twist] frame = ..."),
                               ("--package", args.package, "[packages] NAME = DIR or package_dirs = [DIR]")):
        if value:  # not carried to the runs: refused rather than silently ignored
            raise InputError(f"{flag}: a sweep does not take it (its runs would not see it); expected {where} in "
                             "the constraint file of the sweep (constraints = FILE)")
    spec = spec_from_args(args)
    if threading.current_thread() is threading.main_thread():  # SIGTERM stops the sweep like Ctrl-C: results kept
        signal.signal(signal.SIGTERM, _interrupt)
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    res = run(spec, args.out, workers=workers, scheduler=args.scheduler, chunk_size=args.chunk_size,
              progress=not args.quiet, retry_errors=args.retry_errors, plot=not args.no_plot, batch=args.batch,
              replace=args.replace)
    rows = res.table.to_pydict() if res.table.num_rows else {"run_id": [], "status": [], "error": []}
    varied = [a.name for a in spec.axes] + ["scenario"] + (["terrain"] if spec.terrains else [])
    errors = [{"run_id": rows["run_id"][i], "inputs": {k: rows[k][i] for k in varied if k in rows},
               "error": rows["error"][i]} for i, s in enumerate(rows["status"]) if s == "error"]
    where = f"on {args.scheduler}" if args.scheduler else (f"with {workers} Dask worker(s)" if workers else
                                                           "in this process")
    out = {"out": str(res.out), "results": str(res.out / "results.parquet"), "runs": res.total,
           "computed": res.computed, "resumed": res.resumed, "statuses": res.statuses, "wall_time_s": res.wall,
           "plot": str(res.plot) if res.plot else None, "errors": errors, "interrupted": res.interrupted,
           "batched": res.batched, "notes": res.notes}
    text = [f"sweep of {spec.robot or spec.constraints}: {res.total} run(s) "
            f"({res.computed} computed, {res.resumed} resumed) in {res.wall:.1f} s {where}: "
            + (", ".join(f"{n} {s}" for s, n in res.statuses.items() if n) or "nothing finished"),
            f"wrote {out['results']} ({res.table.num_rows} rows)" + (f" and {out['plot']}" if res.plot else "")]
    if res.computed:
        text.append(f"{res.batched} of {res.computed} computed run(s) simulated as variants of one compiled model "
                    "(robotdyn.sweep.batched)" + "".join(f"\n  {n}" for n in res.notes))
    text += [f"  error in run {e['run_id']} ({', '.join(f'{k}={v}' for k, v in e['inputs'].items())}): {e['error']}"
             for e in errors[:5]]
    if len(errors) > 5:
        text.append(f"  ... {len(errors) - 5} more (status/error columns of the results)")
    _emit(args, out, "\n".join(text))
    if res.interrupted:
        print(f"robotdyn: {res.interrupted}", file=sys.stderr)
        return 130
    return 0


def _interrupt(signum, frame):
    raise KeyboardInterrupt

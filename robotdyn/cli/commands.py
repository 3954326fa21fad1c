"""Command-line interface: ``robotdyn list | info | dump | simulate | compare | view | sweep | linearize | optimise`` plus robot-specific commands
(every command has ``--json``).

Robot modules may add their own subcommands by defining ``register_cli(subparsers, parents)``; each such
subcommand sets ``func(args) -> int``.

Bad input gives one line ``robotdyn: error: ...`` on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import json
import re
import sys

import numpy as np

from .. import __version__
from ..errors import RobotDynError
from ..inputs import MAX_ACCELERATION, MAX_FORCE, MAX_POSITION, MAX_VELOCITY, as_vector, parse_assignments
from ..reduction.reduced_dynamics import solve_mass
from ..constraints.rolling_contact import RollingWheel


def _load(args):
    from ..robot import Robot
    from ..robots import module

    urdf, constraints = getattr(args, "urdf", None), getattr(args, "constraints", None)
    if urdf is not None or constraints is not None:
        if args.robot is not None:
            raise RobotDynError(f"give either ROBOT ({args.robot!r}) or --urdf FILE --constraints FILE, not both")
        if constraints is None:
            raise RobotDynError("--urdf needs --constraints FILE (the wheels, closures and motors of the robot)")
        from ..interfaces.constraint_file import read

        named, dirs = _packages(getattr(args, "package", []))
        mod = read(constraints, urdf, parse_assignments(args.xacro_arg, "--xacro-arg"), dirs, named,
                   getattr(args, "twist", None))
        robot = mod.robot(parse_assignments(args.param))
        args.robot = robot.spec.name
        return mod, robot
    if args.robot is None:
        raise RobotDynError("no robot given: expected ROBOT (robotdyn list) or --urdf FILE --constraints FILE")
    if getattr(args, "package", []):
        raise RobotDynError("--package is for your own robot (--constraints FILE); the built-in robots need none")
    if getattr(args, "xacro_arg", []):
        raise RobotDynError("--xacro-arg is for your own robot's description (--constraints FILE); a built-in "
                            "robot's numbers are its parameters: --param NAME=VALUE (robotdyn info ROBOT lists them)")
    mod = module(args.robot)
    spec = mod.SPEC
    if getattr(args, "twist", None):
        from dataclasses import replace

        from ..reduction.operational_space import OperationalVelocities

        frame, _, comps = args.twist.partition(":")
        comps = tuple(comps.replace(",", " ").split()) or ("vx", "vy", "wz")
        spec = replace(spec, independent=None, operational=OperationalVelocities(frame, comps, "local", list(comps)))
    return mod, Robot(spec, parse_assignments(args.param))


def _packages(items) -> tuple[dict[str, str], list[str]]:
    """``--package NAME=DIR`` (a package by name) and ``--package DIR`` (a directory searched for packages)."""
    named, dirs = {}, []
    for item in items or []:
        if "=" in item:
            named.update(parse_assignments([item], "--package"))
        else:
            dirs.append(item)
    return named, dirs


def _emit(args, data: dict, text: str) -> None:
    if args.json:
        print(json.dumps(data, indent=2, default=_jsonable))
    else:
        print(text)


def _jsonable(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")


def _matrix_text(name: str, rows: list[str], cols: list[str], A: np.ndarray) -> str:
    if not rows or not cols:  # e.g. B of a robot without motors: said, not an empty grid
        return f"{name}: (none: {len(rows)} x {len(cols)})"
    w = max(14, *(len(c) + 2 for c in cols))  # a '-1.23457e-05' (12 characters) keeps a space on its left
    left = max(14, *(len(r) for r in rows)) if rows else 14  # long row names keep the columns aligned
    lines = [f"{name}:", " " * left + "".join(f"{c:>{w}}" for c in cols)]
    for r, row in zip(rows, np.atleast_2d(A)):
        lines.append(f"{r:>{left}}" + "".join(f"{x:>{w}.6g}" for x in row))
    return "\n".join(lines)


def _vector_text(name: str, rows: list[str], x: np.ndarray) -> str:
    left = max(14, *(len(r) for r in rows)) if rows else 14
    return f"{name}:\n" + "\n".join(f"{r:>{left}}  {v:.10g}" for r, v in zip(rows, x))


# --------------------------------------------------------------------------------------------- commands
def cmd_list(args) -> int:
    """``robotdyn list``: the registered robots and their titles.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status, 0. Errors raise :class:`~robotdyn.errors.RobotDynError`, which
        :func:`~robotdyn.cli.commands.main` prints in one line with status 2.
    """
    from ..robots import module, names

    data = {n: module(n).SPEC.title for n in names()}
    _emit(args, {"robots": data}, "\n".join(f"{n:<20} {t}" for n, t in data.items()))
    return 0


def cmd_info(args) -> int:
    """``robotdyn info ROBOT``: coordinates, independent velocities, mobility, parameters, actuators, constraints and scenarios.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status, 0. Errors raise :class:`~robotdyn.errors.RobotDynError`, which
        :func:`~robotdyn.cli.commands.main` prints in one line with status 2.
    """
    mod, robot = _load(args)
    info = robot.info()
    info["scenarios"] = {k: s.description for k, s in getattr(mod, "SCENARIOS", {}).items()}
    lines = [
        f"{info['robot']}: {info['title']}",
        *([f"paper: {info['paper']} (full reference: docs/bibliography.md)"] if info["paper"] else []),
        f"coordinates q ({len(info['coordinates'])}): {', '.join(info['coordinates'])}   [m, rad]",
        f"independent velocities ({info['mobility']}): {', '.join(info['independent_velocities'])}",
        f"mobility at the neutral configuration: {info['mobility_at_neutral']} (n - rank A)"
        + ("" if info["mobility_at_neutral"] == info["mobility"] else
           f"; the independent velocities listed are {info['mobility']}: expected as many as the mobility"),
        *(f"note: {n}" for n in info["mobility_notes"]),
        *(f"meshes: {w}" for w in info["visual_warnings"]),  # (the viewer warns of them too; not every command)
        *([f"root: {info['root']}, its link at {info['root_height']:.6g} m above the ground "
           f"({info['root_height_source']}; root_height in the constraint file)"]
          if info["root"] == "planar" and info["root_height"] else []),
        "parameters:",
        *(f"  {k:<14} = {v['value']!s:<10} {v['unit']:<8} {v['description']}" for k, v in info["parameters"].items()),
        "actuators:",
        *(f"  {a['name']}: on {a['joint']}" + (f", reacting on {a['reaction']}" if a["reaction"] else "")
          for a in info["actuators"]),
        "constraints:",
        *(f"  {c}" for c in info["constraints"]),
        *(["springs and dampers:", *(f"  {sp}" for sp in info["springs"])] if info.get("springs") else []),
        f"terrain: {info['terrain']}",
        "scenarios:",
        *(f"  {k}: {d}" for k, d in info["scenarios"].items()),
    ]
    _emit(args, info, "\n".join(lines))
    return 0


def cmd_dump(args) -> int:
    """``robotdyn dump ROBOT``: the reduced model (M_r, h, g_r, B_r, S) at a state, and with ``--a``/``--tau`` the inverse or forward dynamics and the constraint forces.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status, 0. Errors raise :class:`~robotdyn.errors.RobotDynError`, which
        :func:`~robotdyn.cli.commands.main` prints in one line with status 2.
    """
    from ..inputs import refuse_together

    refuse_together(args, "a", "tau_set")  # (--a and --tau: argparse's own group)
    if args.full and args.forces:
        raise RobotDynError("--forces and --full exclude each other: the contact forces are those of the constrained "
                            "robot; expected --forces without --full")
    _, robot = _load(args)
    q = robot.neutral() if args.q is None else as_vector(args.q, robot.nq, "q", robot.coordinates, MAX_POSITION)
    for name, x in _numbers(args.set, "--set", "a value in m or rad").items():
        q[robot.coordinate_index(name)] = x
    q = robot.check_q(q)
    if args.full:
        v = as_vector(args.v, robot.nq, "v", robot.velocity_labels, MAX_VELOCITY)
        M, C, g = robot.full(q, v)
        out = {"coordinates": robot.coordinates, "velocities": robot.velocity_labels, "M": M, "C": C, "g": g}
        text = [_matrix_text("M (full)", robot.coordinates, robot.coordinates, M),
                _matrix_text("C (full)", robot.coordinates, robot.coordinates, C),
                _vector_text("g (full)", robot.coordinates, g)]
        if args.a is not None:
            a = as_vector(args.a, robot.nq, "a", robot.velocity_labels, MAX_ACCELERATION)
            out["tau"] = M @ a + C @ v + g
            text.append(_vector_text("tau (full, M a + C v + g)", robot.coordinates, out["tau"]))
        elif args.tau is not None:
            tau = as_vector(args.tau, robot.nq, "tau", robot.coordinates, MAX_FORCE)
            out["a"] = np.linalg.solve(M, tau - C @ v - g)
            text.append(_vector_text("a (full)", robot.velocity_labels, out["a"]))
        _emit(args, out, "\n".join(text))
        return 0
    robot.check_constraints(q)
    nu = robot.check_nu(args.v, "v")
    red = robot.reduced(q, nu, coriolis=True)
    names = robot.velocity_names
    motors = [m.name for m in robot.motors]
    from ..reduction.conditioning import mass_condition

    mass_cond = mass_condition(red.M)[0]  # the other conditioning that matters (robotdyn.reduction.conditioning)
    out = {"coordinates": names, "q": q, "q_names": robot.coordinates, "M": red.M, "C": red.C, "g": red.g,
           "B": red.B, "motors": motors, "S": red.S, "condition": red.projection.condition,
           "mass_matrix_condition": mass_cond}
    text = [f"minimal coordinates: {', '.join(names)}  (constraint block condition {red.projection.condition:.3g}, "
            f"S^T M S condition {mass_cond:.3g})",
            _matrix_text("M", names, names, red.M), _matrix_text("C", names, names, red.C),
            _vector_text("g", names, red.g),
            _matrix_text("B", names, motors, red.B) if motors else "B: none (the robot has no motors)"]
    from ..contact.applied_forces import has_applied, reduced_applied

    if has_applied(robot):  # joint springs and dampers (a URDF's joint damping too), compliant wheels
        out["applied"] = reduced_applied(robot, red, q)[0]
        text.append(_vector_text("S^T Q (joint springs and dampers, compliant wheels: M a = B tau - C nu - g + S^T Q)",
                                 names, out["applied"]))
    from ..contact.sliding import sliding_now

    sliding = bool(sliding_now(robot))  # wheels under a friction law: their forces in every solve below
    if args.a is not None:
        nudot = robot.check_nu(args.a, "a")
        Q, tau, resid = robot.inverse_dynamics(q, nu, nudot)
        if sliding:  # the friction forces follow the loads: torques and loads solved together
            from ..contact.sliding import inverse as inverse_sliding

            inv = inverse_sliding(robot, q, red.v, red.S @ nudot + red.w)
            tau, resid = inv.tau, inv.residual
        out.update(tau=Q, motor_torques=dict(zip(motors, tau)), motor_residual=resid)
        from ..contact.applied_forces import has_applied

        applied = " - Q_springs/contacts" if has_applied(robot) else ""  # what inverse_dynamics takes off
        text += [_vector_text(f"tau (generalised forces M a + C v + g{applied})", names, Q),
                 _vector_text(f"motor torques (least squares, residual {resid:.3g})", motors, tau) if motors else
                 f"motor torques: none (the robot has no motors; residual {resid:.3g})"]
    elif args.tau is not None or args.tau_set:
        tau = _torques(robot, args.tau, args.tau_set)
        from ..contact.applied_forces import reduced_applied

        rolling = any(getattr(c, "rolling", False) for c in robot.constraints)  # contact.compliant_rolling
        nudot = robot.forward_dynamics(q, nu, tau, check=False) if sliding or rolling else \
            solve_mass(red.M, red.B @ tau - red.h + reduced_applied(robot, red, q)[0])  # springs, compliant wheels
        out["a"] = nudot
        out["ill_conditioned"] = [vars(f) for f in robot.warn_conditioning(red, nudot)]
        text.append(_vector_text("a (independent accelerations)", names, nudot))
    from ..constraints.redundancy import message, violations

    found = violations(red, nudot if (args.a is not None or args.tau is not None or args.tau_set) else None)
    out["dropped_row_violations"] = [vars(f) for f in found]
    if found and args.a is None:  # (inverse dynamics warns by itself)
        import warnings

        from ..errors import RobotDynWarning

        warnings.warn(message(found), RobotDynWarning, stacklevel=1)
    if args.forces:
        if args.a is None and args.tau is None and not args.tau_set:
            raise RobotDynError("--forces needs --tau (forward dynamics) or --a (inverse dynamics)")
        # with sliding wheels the forces follow from the torques (with --a: those that produce the accelerations)
        forward = sliding or (args.a is None and any(getattr(c, "rolling", False) for c in robot.constraints))
        forces = robot.contact_forces(q, nu, tau=tau) if forward else robot.contact_forces(q, nu, tau=tau, nudot=nudot)
        out["forces"] = forces.as_dict()
        text.append(forces.table())
    _emit(args, out, "\n".join(text))
    return 0


def _torques(robot, tau, assignments) -> np.ndarray:
    """Motor torques from ``--tau`` (all, in motor order; default zeros) and ``--tau-set MOTOR=VALUE`` by name."""
    motors = [m.name for m in robot.motors]
    out = robot.check_tau(tau) if tau is not None else np.zeros(len(motors))
    for name, x in _numbers(assignments, "--tau-set", "a torque in N m (or N)").items():
        if name not in motors:
            raise RobotDynError(f"--tau-set {name}: no motor named {name!r}; motors are {', '.join(motors) or '(none)'}")
        out[motors.index(name)] = x
    return out


def _numbers(items, option: str, expected: str) -> dict[str, float]:
    """``NAME=VALUE`` options as finite numbers by name (one line naming the option otherwise)."""
    out = {}
    for name, value in parse_assignments(items, option).items():
        try:
            x = float(value)
        except ValueError:
            raise RobotDynError(f"{option} {name}={value!r}: not a number; expected {expected}") from None
        if not np.isfinite(x):
            raise RobotDynError(f"{option} {name}={value!r}: not finite; expected {expected}")
        out[name] = x
    return out


def cmd_simulate(args) -> int:
    """``robotdyn simulate ROBOT --scenario NAME``: run a scenario; summary, CSV, plots and the traction check.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status (0 on success; 130 after an interruption, 124 past ``--time-limit``, whose partial results were kept). Errors raise
        :class:`~robotdyn.errors.RobotDynError`, which :func:`~robotdyn.cli.commands.main` prints in one line with
        status 2.
    """
    from .time_limit import wall_clock_limit

    with wall_clock_limit(getattr(args, "time_limit", None)) as limit:  # robotdyn.cli.time_limit: a partial run past it
        return _simulate(args, limit)


def _simulate(args, limit) -> int:
    """:func:`cmd_simulate` inside its wall-clock ``limit`` (:mod:`robotdyn.cli.time_limit`)."""
    from ..output import IMAGE_FORMATS, check_target

    # output paths checked before the run, so that a typo does not cost a simulation
    if args.csv:
        check_target(args.csv, "CSV file")
    for path in (args.plot, args.traction_plot):
        if path:
            check_target(path, "plot", IMAGE_FORMATS)
    mod, robot = _load(args)
    scenarios = getattr(mod, "SCENARIOS", {})
    if args.scenario not in scenarios:
        raise RobotDynError(
            f"unknown scenario {args.scenario!r} for {args.robot}; expected one of {', '.join(scenarios) or '(none)'}"
        )
    sc = scenarios[args.scenario]
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():  # SIGTERM stops the run like Ctrl-C: results kept
        signal.signal(signal.SIGTERM, _interrupt)
    extra = {} if args.stabilisation is None else {"stabilisation": args.stabilisation}
    if args.method is not None:  # checked by simulate (robotdyn.simulation.run_options): one line if unknown
        extra["method"] = args.method
    from ..contact.stick_slip_wheel import stick_slip_wheels
    from ..simulation.streaming import SEGMENT

    if args.csv and not (args.plot or args.traction_plot) and sc.span(args.t_end, None, streamed=True)[1] > SEGMENT \
            and not stick_slip_wheels(robot):
        return _simulate_streamed(args, robot, sc, extra, limit)  # more samples than a segment: to disk as they come
    from ..contact.stick_slip_traction import check_mu

    check_mu(robot, args.mu)  # a stick-slip wheel's mu is its law's: another --mu refused before the run
    limit.start()
    traj = sc.run(robot, t_end=args.t_end, progress=not args.quiet, **extra)
    partial = traj.stats.get("partial")
    tr = None
    switches = traj.stats.get("switches")  # exact stick-slip: the phases' switches, beside the traction summary
    if any(isinstance(c, RollingWheel) for c in robot.constraints):
        from ..interfaces.plotting import plot_traction
        from ..contact.traction import traction

        try:
            tr = traction(traj.robot or robot, traj, traj.torque, args.mu,  # the robot and torques simulated
                          progress=not args.quiet)
        except KeyboardInterrupt:  # the trajectory is kept; only its traction columns are lost
            partial = traj.stats["partial"] = (partial + "; " if partial else "") + "traction not computed (interrupted)"
            tr = None
        if tr is not None and args.traction_plot:
            plot_traction(tr, args.traction_plot, f"{args.robot}: {sc.name}, wheel loads and required friction",
                          traj.robot or robot)
    elif args.mu is not None or args.traction_plot:
        raise RobotDynError(f"--mu/--traction-plot: robot {args.robot!r} has no wheels")
    limit.stop()
    partial = limit.reason(partial)
    if partial:  # the CSV file's marker says why the run stopped
        traj.stats["partial"] = partial
    if args.csv:
        traj.to_csv(args.csv, tr.columns() if tr is not None else None)
    if args.plot:
        from ..interfaces.plotting import plot_trajectory, pose_columns

        plot_trajectory(traj, sc.plot or traj.velocity_names, args.plot, f"{args.robot}: {sc.name}", sc.zoom,
                        sc.references, pose_columns(traj.robot or robot, traj))
    drift = float(np.max(traj.residual)) if traj.residual.size else 0.0
    final = dict(zip(traj.coordinates + traj.velocity_names, np.concatenate([traj.q[-1], traj.nu[-1]])))
    out = {"scenario": sc.name, "t_end": float(traj.t[-1]), "samples": len(traj.t), "final": final,
           "energy_start": float(traj.energy[0]), "energy_end": float(traj.energy[-1]),
           "max_holonomic_residual": drift, "wall_time_s": traj.stats["wall"], "csv": args.csv, "plot": args.plot,
           "engine": traj.stats.get("engine")}
    if tr is not None:
        out["traction"] = {"summary": tr.summary(), "wheels": tr.wheels, "undetermined": list(tr.undetermined),
                           "events": [vars(e) for e in tr.events],
                           "max_required_mu": tr.max_required_mu(),  # (as the streamed run: no arbitrary
                                                                     # split's value; stick-slip: while sticking)
                           "min_normal_load": {w: float(np.min(tr.normal[:, j])) for j, w in enumerate(tr.wheels)}}
    text = [f"{args.robot} / {sc.name}: {sc.description}",
            f"simulated {traj.t[-1]:g} s in {traj.stats['wall']:.2f} s wall ({traj.stats['nfev']} evaluations, "
            f"{traj.stats.get('engine', 'scipy')} engine)",
            "final state:", *(f"  {k:<14} {v: .8g}" for k, v in final.items()),
            f"energy: {traj.energy[0]:.10g} J -> {traj.energy[-1]:.10g} J; max holonomic residual {drift:.2e}"]
    if str(out["engine"] or "scipy").startswith("scipy"):  # the Python path: say why (it can take 100x longer)
        from ..simulation.engine_reason import python_path_reason

        out["engine_reason"] = python_path_reason(traj.robot or robot, traj.torque)
        if out["engine_reason"]:
            text.insert(2, f"  (not on the compiled engine: {out['engine_reason']})")
    if tr is not None:
        text.append(tr.summary())
    if "flight" in traj.stats:  # compliant wheels: lift-off and touch-down times (robotdyn.simulation.flight)
        from ..simulation.flight import flight_summary

        out["flight"] = traj.stats["flight"]
        lines = flight_summary(traj.stats["flight"], traj.stats.get("airborne", []))
        text.append("flight phases: " + ("; ".join(lines) if lines else
                                         "none (every compliant wheel kept its contact)"))
    if traj.damper_work is not None or traj.friction_work is not None:
        fw = 0.0 if traj.friction_work is None else float(traj.friction_work[-1])
        dw = 0.0 if traj.damper_work is None else float(traj.damper_work[-1])
        out["friction_work"], out["damper_work"] = fw, dw
        lost = getattr(traj, "impact_loss", None)  # rolling compliant wheels' touch-downs (simulation.compliant_rolling)
        if lost is not None:
            out["touchdown_loss"] = float(lost[-1] - lost[0])
        text.append(f"work: friction {fw:.10g} J, dampers {dw:.10g} J" + (
            "" if lost is None else f", touch-down impacts {-(lost[-1] - lost[0]):.10g} J")
            + " (energy change = motor work + these)")
    if switches is not None:
        out["switches"] = switches
        text.append(f"stick-slip: {len(switches)} phase switch(es)" + "".join(
            f"; t = {s['t']:.6g} s {s['wheel']} -> {s['phase']}" for s in switches[:10])
            + ("; ..." if len(switches) > 10 else ""))
    return _finish_run(args, out, text, traj.stats, partial, [args.csv, args.plot, args.traction_plot], limit)


def _finish_run(args, out: dict, text: list[str], stats: dict, partial: str | None, written: list, limit) -> int:
    """The end of ``simulate``'s report, in memory or streamed: constant offsets, an event that stopped the run, the
    files written and a partial run's note (stderr, exit status 130; 124 past ``--time-limit``)."""
    if "offsets" in stats:  # holonomic residuals no coordinate can change (robotdyn.reduction.pull_back)
        out["constant_offsets"] = stats["offsets"]
    if "event" in stats:
        out["stopped"] = stats["event"]
        text.append(f"stopped early: {stats['event']}")
    written = [w for w in written if w]
    text += [f"wrote {w}" for w in written]
    if partial:
        out["partial"] = partial
        text.append(f"partial: {partial}")
    _emit(args, out, "\n".join(text))
    if partial:
        print(f"robotdyn: {partial}; wrote the partial results: {', '.join(written) or 'nothing'}", file=sys.stderr)
        return limit.status
    return 0


def _simulate_streamed(args, robot, sc, extra: dict, limit) -> int:
    """``simulate --csv`` of a run longer than one segment (robotdyn.simulation.streaming): the samples go to the
    CSV file segment by segment, with the wheel-load columns; only the ends and extremes stay in memory."""
    from ..simulation.streaming import SEGMENT, CsvSink

    has_wheels = any(isinstance(c, RollingWheel) for c in robot.constraints)
    if args.mu is not None and not has_wheels:
        raise RobotDynError(f"--mu/--traction-plot: robot {args.robot!r} has no wheels")
    peaks: dict[str, list[float]] = {}  # wheel -> [min normal load, max required mu]
    events: dict[tuple[str, str], object] = {}

    def columns(traj) -> dict:
        from ..contact.traction import traction

        tr = traction(traj.robot or robot, traj, traj.torque, args.mu)  # the segment's robot and torque law
        for j, w in enumerate(tr.wheels):
            lo, hi = peaks.setdefault(w, [np.inf, -np.inf])
            mus = tr.required_mu[:, j] if tr.friction_determined[j] else np.array([-np.inf])
            peaks[w] = [min(lo, float(np.min(tr.normal[:, j]))), max(hi, float(np.max(mus)))]
        for e in tr.events:
            events.setdefault((e.kind, e.wheel), e)
        return tr.columns()

    limit.start()
    res = sc.run(robot, t_end=args.t_end, progress=not args.quiet,
                 sink=CsvSink(args.csv, columns if has_wheels else None, SEGMENT, limit.reason), **extra)
    limit.stop()
    partial = limit.reason(res.stats.get("partial"))
    final = dict(zip(res.coordinates + res.velocity_names, np.concatenate([res.q, res.nu])))
    out = {"scenario": sc.name, "t_end": res.t, "samples": res.samples, "final": final, "streamed": True,
           "segments": res.stats["segments"], "energy_start": res.energy_start, "energy_end": res.energy_end,
           "max_holonomic_residual": res.max_residual, "wall_time_s": res.stats["wall"], "csv": args.csv,
           "plot": None, "engine": res.stats.get("engine")}
    text = [f"{args.robot} / {sc.name}: {sc.description}",
            f"simulated {res.t:g} s in {res.stats['wall']:.2f} s wall ({res.stats['nfev']} evaluations, "
            f"{res.stats.get('engine', 'scipy')} engine), streamed in {res.stats['segments']} segment(s)",
            "final state:", *(f"  {k:<14} {v: .8g}" for k, v in final.items()),
            f"energy: {res.energy_start:.10g} J -> {res.energy_end:.10g} J; max holonomic residual "
            f"{res.max_residual:.2e}"]
    if peaks:
        first = sorted(events.values(), key=lambda e: e.t)
        out["traction"] = {"min_normal_load": {w: p[0] for w, p in peaks.items()},
                           "max_required_mu": {w: p[1] for w, p in peaks.items() if np.isfinite(p[1])},
                           "events": [vars(e) for e in first]}
        text.append(f"loads {min(p[0] for p in peaks.values()):.4g} N minimum"
                    + (f"; first: {first[0]}" if first else "; no lift-off or slip"))
    return _finish_run(args, out, text, res.stats, partial, [args.csv], limit)


def _nonnegative(text: str) -> float:
    """An argparse type: a finite number >= 0 (argparse names the option in its one-line error)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number; expected a finite number >= 0") from None
    if not (np.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text!r}; expected a finite number >= 0")
    return value


def _duration(text: str) -> float:
    """An argparse type: a duration [s], finite and > 0 (argparse names the option in its one-line error)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number; expected a positive duration in s") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}; expected a positive duration in s")
    return value


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def cmd_compare(args) -> int:
    """``robotdyn compare ROBOT``: the paper comparison table of a built-in robot.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status, 0. Errors raise :class:`~robotdyn.errors.RobotDynError`, which
        :func:`~robotdyn.cli.commands.main` prints in one line with status 2.
    """
    mod, robot = _load(args)
    if not hasattr(mod, "compare"):
        raise RobotDynError(f"robot {args.robot!r} has no paper comparison")
    cmp = mod.compare(robot)
    _emit(args, {"title": cmp.title, "rows": cmp.as_dicts()}, cmp.table())
    return 0


def cmd_view(args) -> int:
    """The meshcat viewer: the robot (and a scenario's animation); a standalone HTML file or a live server.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status, 0 (also when Ctrl-C stops the live server). Errors raise
        :class:`~robotdyn.errors.RobotDynError`, which :func:`~robotdyn.cli.commands.main` prints in one line with
        status 2.
    """
    from ..interfaces.viewer import Viewer

    mod, robot = _load(args)
    traj = None
    if args.scenario is not None:
        scenarios = getattr(mod, "SCENARIOS", {})
        if args.scenario not in scenarios:
            raise RobotDynError(f"unknown scenario {args.scenario!r} for {args.robot}; "
                                f"expected one of {', '.join(scenarios) or '(none)'}")
        if args.t_end is not None and not (np.isfinite(args.t_end) and args.t_end > 0):
            raise RobotDynError(f"--t-end {args.t_end:g}; expected a positive duration in s")
        traj = scenarios[args.scenario].run(robot, t_end=args.t_end, progress=not args.quiet)
    viewer = Viewer(robot, live=args.html is None, frames=args.frames)
    viewer.display(robot.neutral() if traj is None else traj.q[0])
    if traj is not None:
        viewer.animate(traj)
    out = {"robot": args.robot, "scenario": args.scenario, "html": args.html, "url": viewer.url,
           "duration_s": None if traj is None else float(traj.t[-1] - traj.t[0])}
    if args.html:
        viewer.save(args.html)
        viewer.close()
        _emit(args, out, f"wrote {args.html}" + ("" if traj is None else f" ({out['duration_s']:g} s animation)"))
        return 0
    try:  # from the first line printed on, Ctrl-C stops the server cleanly
        _emit(args, out, f"meshcat viewer of {args.robot} at {viewer.url}  (Ctrl-C to stop)")
        if args.open:
            import webbrowser

            webbrowser.open(viewer.url)
        import time

        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        pass
    finally:
        viewer.close()
    return 0


# ------------------------------------------------------------------------------------------------ parser
class _Parser(argparse.ArgumentParser):
    """argparse with its errors as robotdyn's one line (``robotdyn: error: ...``, exit status 2), no usage block,
    and negative numbers in scientific notation (``--v 1e-5 -2e-5``) read as values, not options."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$|^-(inf|nan)$", re.I)

    def error(self, message: str):
        raise RobotDynError(f"{message} (see robotdyn {self.prog.split(' ', 1)[-1] + ' ' if ' ' in self.prog else ''}"
                            "--help)")


HELP_EPILOG = ("file formats (constraint TOML, sweep spec, simulate CSV, sweep Parquet): docs/reference/file-formats.md "
               "(the documentation site: make docs)")
"""The last line of ``robotdyn --help``: where the file formats are documented."""

BUILT_IN = ("list", "info", "dump", "simulate", "compare", "view", "sweep", "linearize", "optimise")
"""The built-in commands (robot modules add theirs, see :func:`_add_robot_commands`)."""


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The ``robotdyn`` parser; with ``only`` (one of :data:`BUILT_IN`), a parser holding that command alone (what
    :func:`main` needs to parse it: the others' parsers cost start-up time and change nothing of its parsing, help
    or errors).

    Args:
        only: One of :data:`BUILT_IN` (default ``None``: every command).

    Returns:
        The :class:`argparse.ArgumentParser` of every built-in command, or of ``only`` alone.
    """
    if only is not None and only not in BUILT_IN:
        raise ValueError(f"only = {only!r}; expected one of {', '.join(BUILT_IN)}")

    def wanted(name: str) -> bool:
        return only is None or only == name

    parser = _Parser(prog="robotdyn", description=__doc__.splitlines()[0], epilog=HELP_EPILOG)
    parser.add_argument("--version", action="version", version=f"robotdyn {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    common = _Parser(add_help=False)
    common.add_argument("--json", action="store_true", help="machine-readable output")
    robot_args = _Parser(add_help=False)
    robot_args.add_argument("robot", metavar="ROBOT", nargs="?", default=None,
                            help="robot name (robotdyn list); or describe your own with --urdf/--constraints")
    robot_args.add_argument("--urdf", metavar="FILE",
                            help="your robot's URDF/Xacro (a path or package://PKG/...; default: the file's urdf)")
    robot_args.add_argument("--xacro-arg", action="append", default=[], metavar="NAME=VALUE",
                            help="a xacro argument of --urdf (repeatable)")
    robot_args.add_argument("--constraints", metavar="FILE",
                            help="TOML constraint file: root, wheels, closures, motors (format: docs/reference/file-formats.md; "
                                 "examples/*.toml)")
    robot_args.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                            help="override a parameter (repeatable; robotdyn info ROBOT lists them)")
    robot_args.add_argument("--package", action="append", default=[], metavar="NAME=DIR|DIR",
                            help="a ROS package for $(find NAME) and package://NAME (NAME=DIR), or a directory "
                                 "searched for packages (DIR) (repeatable; ROS_PACKAGE_PATH is searched too)")
    robot_args.add_argument("--twist", metavar="FRAME[:vx,vy,wz]",
                            help="independent velocities that are FRAME's twist in its own axes (default components "
                                 "vx vy wz: a base's body twist) instead of joint velocities")

    plain = {"list": ([common], "list the robots", cmd_list),
             "info": ([common, robot_args], "coordinates, parameters, actuators", cmd_info),
             "compare": ([common, robot_args], "the paper comparison table", cmd_compare)}

    def _add_sweep(sub, parents) -> None:
        from .sweep import register  # the command imports Dask only when it runs

        register(sub, parents)

    def _add_linearize(sub, parents) -> None:
        from .linearize import register

        register(sub, parents)

    def _add_optimise(sub, parents) -> None:
        from .optimise import register

        register(sub, parents)

    added = {"dump": _add_dump, "simulate": _add_simulate, "view": _add_view, "sweep": _add_sweep,
             "linearize": _add_linearize, "optimise": _add_optimise}
    for name in BUILT_IN:  # the order of --help
        if not wanted(name):
            continue
        if name in plain:
            parents, text, func = plain[name]
            sub.add_parser(name, parents=parents, help=text).set_defaults(func=func)
        else:
            added[name](sub, [common, robot_args])
    parser.commands = sub.choices  # name -> subparser (the built-in ones until robot_commands() adds theirs)
    parser.robot_commands = lambda: _add_robot_commands(sub, [common, robot_args])
    return parser


def _add_dump(sub, parents) -> None:
    p = sub.add_parser("dump", parents=parents,
                       help="minimal-coordinate M, C, g and torques (or accelerations) at a state")
    p.add_argument("--q", nargs="+", help="natural coordinates, in the order info lists them (default: the neutral "
                                          "configuration)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="set one coordinate by name, e.g. --set theta3=0.3 (repeatable; applied after --q)")
    p.add_argument("--v", nargs="+", required=True, help="independent velocities (with --full: all velocities)")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--a", nargs="+", help="accelerations -> torques (inverse dynamics)")
    group.add_argument("--tau", nargs="+", help="motor torques -> accelerations (forward dynamics)")
    p.add_argument("--tau-set", action="append", default=[], metavar="MOTOR=VALUE",
                   help="one motor torque by name, e.g. --tau-set tau_R=0.5 (repeatable; the others from --tau or 0)")
    p.add_argument("--full", action="store_true", help="the unconstrained tree's M, C, g instead")
    p.add_argument("--forces", action="store_true",
                   help="also the wheel-ground contact forces and loop-closure forces (needs --tau or --a)")
    p.set_defaults(func=cmd_dump)


def _add_simulate(sub, parents) -> None:
    p = sub.add_parser("simulate", parents=parents, help="run a scenario")
    p.add_argument("--scenario", required=True, help="scenario name (robotdyn info ROBOT lists them)")
    p.add_argument("--t-end", type=_duration, default=None, help="duration [s] (default: the scenario's)")
    p.add_argument("--csv", help="write t, q columns, velocity columns to this CSV file (a run of more than "
                   "100,000 samples without --plot/--traction-plot streams to it in segments: any duration)")
    p.add_argument("--plot", help="save the paper's figures reproduced to this image file")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--stabilisation", type=_nonnegative, default=None, metavar="ALPHA",
                   help="gain [1/s] pulling holonomic residuals back (default 10; 0 turns the pull-back off)")
    p.add_argument("--method", default=None,
                   help="integrator: adams, bulirsch_stoer, dopri5, rosenbrock4 or cvode (SUNDIALS' BDF, for stiff "
                        "compliant wheels and springs) on the compiled engine, or a scipy solve_ivp method (default: "
                        "the scenario's; see robotdyn.simulation.engine.simulate)")
    p.add_argument("--mu", type=_nonnegative, default=None,
                   help="friction coefficient of every wheel for the slip check (default: each wheel's own mu)")
    p.add_argument("--traction-plot", metavar="FILE",
                   help="save the wheel loads and required friction against time to this image file")
    p.add_argument("--time-limit", type=_duration, default=None, metavar="SECONDS",
                   help="wall-clock limit of the run: past it the run stops, the samples so far are written as a "
                        "marked partial file, and the exit status is 124 (Ctrl-C/SIGTERM: 130)")
    p.set_defaults(func=cmd_simulate)


def _add_view(sub, parents) -> None:
    p = sub.add_parser("view", parents=parents,
                       help="meshcat viewer (live on localhost, or a standalone HTML file with --html)")
    p.add_argument("--scenario", help="animate this scenario (robotdyn info ROBOT lists them)")
    p.add_argument("--t-end", type=_duration, default=None,
                   help="duration [s] of the scenario (default: the scenario's)")
    p.add_argument("--html", help="write a standalone HTML file (opens offline) instead of starting a server")
    p.add_argument("--frames", action="store_true", help="show the link frames initially")
    p.add_argument("--open", action="store_true", help="open the live viewer in the default web browser")
    p.add_argument("--quiet", action="store_true", help="no simulation progress on stderr")
    p.set_defaults(func=cmd_view)


def _add_robot_commands(sub, parents) -> None:
    """The commands that robot modules add (``register_cli``): importing every robot module costs start-up time,
    so :func:`main` adds them only when the command is not a built-in one (or for ``--help``)."""
    from ..robots import module, names

    for name in names():
        try:
            mod = module(name)
        except Exception as exc:  # a broken robot module must not take the whole CLI down
            print(f"robotdyn: warning: robot module {name!r} failed to import: {exc}", file=sys.stderr)
            continue
        hook = getattr(mod, "register_cli", None)
        if hook is not None:
            hook(sub, parents)


def _one_line_warnings() -> None:
    """robotdyn's warnings (:class:`~robotdyn.errors.RobotDynWarning`) as ``robotdyn: warning: ...`` on stderr, each
    message once per run."""
    import warnings

    from ..errors import RobotDynWarning

    default = warnings.showwarning

    shown = set()

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, RobotDynWarning):
            if str(message) not in shown:  # once per run, wherever it was raised from (e.g. a robot built twice)
                shown.add(str(message))
                print(f"robotdyn: warning: {message}", file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)

    warnings.showwarning = show
    warnings.simplefilter("default", RobotDynWarning)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``robotdyn`` console script.

    Args:
        argv: The arguments after the program name (default ``None``: ``sys.argv[1:]``).

    Returns:
        The exit status: 0 on success, 2 on a one-line error, 130 after Ctrl-C.
    """
    _one_line_warnings()
    from . import sigterm

    handler = sigterm.current()  # simulate and sweep install their own SIGTERM handler: theirs only while they run
    try:
        argv = sys.argv[1:] if argv is None else list(argv)
        parser = build_parser(argv[0] if argv and argv[0] in BUILT_IN else None)  # `robotdyn CMD ...`: CMD alone
        command = next((a for a in argv if not a.startswith("-")), None)
        if command is None or command not in parser.commands:
            parser.robot_commands()  # a robot module's command, or --help listing them all
        args = parser.parse_args(argv)
        with np.errstate(all="ignore"):  # non-finite results are refused explicitly (NonFiniteError), in one line
            return int(args.func(args) or 0)
    except RobotDynError as exc:
        print(f"robotdyn: error: {exc}", file=sys.stderr)
        return 2
    except np.linalg.LinAlgError as exc:  # a solve the checks above did not foresee: still one line
        print(f"robotdyn: error: a linear solve failed ({exc}): the model is singular at this state (massless "
              "bodies, or redundant constraints)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("robotdyn: interrupted", file=sys.stderr)
        return 130
    except RuntimeError as exc:  # Path.resolve() of a loop of symbolic links (Python < 3.13) where no check caught it
        if "Symlink loop" not in str(exc):
            raise
        print(f"robotdyn: error: {exc}: a loop of symbolic links; expected a file or directory that exists",
              file=sys.stderr)
        return 2
    except RecursionError:  # a nesting deeper than any valid input (e.g. a hostile TOML or XML file)
        print("robotdyn: error: input nested too deeply; expected a robot description or constraint file of "
              "ordinary depth", file=sys.stderr)
        return 2
    except OSError as exc:  # a file the checks above did not foresee (read or write): still one line, naming it
        if isinstance(exc, BrokenPipeError):  # output piped into e.g. `head`, which closed early
            sys.stderr.close()
            return 0
        name = f" {exc.filename!r}" if getattr(exc, "filename", None) else ""
        print(f"robotdyn: error: cannot access file{name}: {exc.strerror or exc}; expected a readable input or a "
              "writable output in an existing directory", file=sys.stderr)
        return 2
    finally:
        sigterm.restore(handler)

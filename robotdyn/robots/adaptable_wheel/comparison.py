"""Adaptable-wheel tricycle: the model against the paper (:func:`compare`) and the functions that bring both together.

Model: :mod:`robotdyn.robots.adaptable_wheel.model` (Pinocchio, ``urdf/adaptable_wheel.urdf.xacro``). Paper: :mod:`robotdyn.robots.adaptable_wheel.paper` (eqs 1, 3-35, Table 2 of
Mardani & Ebrahimi 2016, ``docs/bibliography.md``) and its missions (:mod:`robotdyn.robots.adaptable_wheel.missions`, section 7).
:func:`model_configuration` puts an IK solution of the paper into the model's coordinates,
:func:`model_static_check` tests eqs 25-34 against the model's generalised equilibrium, :func:`compare` the printed
numbers of section 7 and Table 2, :func:`loads_comparison` sec 5's wheel loads against robotdyn's (:func:`hold_loads`).
The ``ik`` CLI subcommand shows the paper's IK and statics beside the model's coordinates. Verdicts and evidence:
``docs/errata/adaptable_wheel.md``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ...reduction.actuation import input_matrix
from ...interfaces.comparison import Comparison
from ...constraints.constraint import KinematicState
from ...errors import InputError
from ...constraints.joint_coupling import JointCoupling
from ...robot import Robot
from .missions import MISSIONS, run_mission
from .model import SPEC, WHEELS, _terrain
from .paper import (
    TABLE2,
    Commands,
    StaticResult,
    body_pose,
    offsets,
    paper_torque_eq35,
    radius_law,
    solve_ik,
    static_torques,
)

if TYPE_CHECKING:
    from ...contact.contact_forces import ConstraintForces


def euler_zyx(R: np.ndarray) -> tuple[float, float, float]:
    """(yaw, pitch, roll) [rad] with :math:`R = R_z(yaw) R_y(pitch) R_x(roll)` (the floating root's convention).

    Args:
        R: A rotation matrix (3, 3).

    Returns:
        ``(yaw, pitch, roll)`` [rad], three floats.
    """
    return float(np.arctan2(R[1, 0], R[0, 0])) + 0.0, float(np.arcsin(-np.clip(R[2, 0], -1, 1))) + 0.0, float(
        np.arctan2(R[2, 1], R[2, 2]))


def model_configuration(robot: Robot, cmd: Commands, x: np.ndarray, spins: np.ndarray | None = None) -> np.ndarray:
    """The model's natural coordinates for commands ``cmd`` and an IK solution ``x`` (eq 16).

    The body pose comes from eqs 4-6 (converted to the root's Z-Y-X Euler angles), q_i from x and the radius
    coordinates from the coupling law (eq 1). Wheel spin angles are ``spins`` (default 0; they do not change the
    contact geometry of a round wheel).

    Args:
        robot: The adaptable-wheel :class:`~robotdyn.robot.Robot`.
        cmd: The six :class:`~robotdyn.robots.adaptable_wheel.paper.Commands`.
        x: An IK solution (beta_fr, beta_fl, beta_r, q_fr, q_fl, q_r) [rad] (eq 16).
        spins: Wheel spin angles (3,) [rad] (default ``None``: zero).

    Returns:
        Natural coordinates (n,) [m, rad].
    """
    R, d = body_pose(cmd, robot.terrain)
    q = robot.neutral()
    for label, value in zip(("x", "y", "z"), d):
        q[robot.coordinate_index(label)] = value
    for label, value in zip(("yaw", "pitch", "roll"), euler_zyx(R)):
        q[robot.coordinate_index(label)] = value
    for k, tag in enumerate(WHEELS):
        q[robot.coordinate_index(f"q_{tag}")] = x[3 + k]
        q[robot.coordinate_index(f"Rch_{tag}")] = radius_law(x[3 + k], robot.params["w"])
        q[robot.coordinate_index(f"theta_{tag}")] = 0.0 if spins is None else spins[k]
    return q


def model_static_check(robot: Robot, cmd: Commands, x: np.ndarray, res: StaticResult) -> dict:
    """Check eqs 25-34 against the Pinocchio model at the same configuration (independent of eq 34).

    1. Generalised equilibrium of the whole model: :math:`g(q) = B\\tau + \\sum_i A_{w,i}^T F_i +
       A_{eq1}^T\\mu` solved for the six motor torques and the three coupling forces, with :math:`A_{w,i}` the
       world rows of wheel i's rolling contact (its material contact point's velocity, radius rate included).
       The residual tests the contact forces against the model's gravity; the adjustment torques must equal
       eq 34's.
    2. Virtual work by finite differences: :math:`t_i = -F_i\\cdot\\partial p_i/\\partial q_i`, where
       :math:`p_i(q_i)` is the material rim point at the contact (wheel-fixed direction), computed from the
       model's kinematics with the radius coordinate set by the coupling, at :math:`q_i \\pm \\varepsilon`.

    Args:
        robot: The adaptable-wheel :class:`~robotdyn.robot.Robot`.
        cmd: The six :class:`~robotdyn.robots.adaptable_wheel.paper.Commands`.
        x: An IK solution (beta_fr, beta_fl, beta_r, q_fr, q_fl, q_r) [rad] (eq 16).
        res: The :class:`~robotdyn.robots.adaptable_wheel.paper.StaticResult` of eqs 25-34 at that configuration.

    Returns:
        dict with ``tau`` (6, model order of motors), ``residual``, ``tau_fd`` (3,).
    """
    if robot.params["lateral"] != "rolling":
        raise InputError("model_static_check needs the rolling wheels (lateral=rolling)")
    q = model_configuration(robot, cmd, x)
    nv = robot.nq
    kin = KinematicState(robot.model, robot.data, q, np.zeros(nv))
    g = pin.computeGeneralizedGravity(robot.model, robot.data, q)
    load = np.zeros(nv)
    couplings, wheels = [], {}
    for c in robot.constraints:
        if isinstance(c, JointCoupling):
            couplings.append(c.rows(kin).A[0])
        else:
            geo = c.contact(kin)
            rows = c.rows(kin)
            Aw = geo["E"] @ rows.A  # world rows (E orthonormal: rows = E^T A_w)
            wheels[c.name] = (geo, Aw)
    for k, tag in enumerate(WHEELS):
        load += wheels[tag][1].T @ res.forces[k]
    B = input_matrix(robot.motors, kin)
    K = np.column_stack([B, np.array(couplings).T])
    sol, *_ = np.linalg.lstsq(K, g - load, rcond=None)
    residual = float(np.linalg.norm(K @ sol - (g - load)))
    tau = sol[: B.shape[1]]
    # virtual work by finite differences on the model's kinematics
    eps = 1e-6
    tau_fd = np.zeros(3)
    coupling = {c.driver: c for c in robot.constraints if isinstance(c, JointCoupling)}
    for k, tag in enumerate(WHEELS):
        geo = wheels[tag][0]
        u = geo["u"]
        c_join = coupling[f"adjust_{tag}_joint"]
        frame = robot.model.getFrameId(f"wheel_{tag}")

        def rim_point(dq):
            qq = q.copy()
            qq[robot.coordinate_index(f"q_{tag}")] += dq
            qq = c_join.solve_driven(qq)
            pin.forwardKinematics(robot.model, robot.data, qq)
            centre = pin.updateFramePlacement(robot.model, robot.data, frame).translation
            return centre - (robot.params["R_ru"] + qq[robot.coordinate_index(f"Rch_{tag}")]) * u

        tau_fd[k] = -res.forces[k] @ (rim_point(eps) - rim_point(-eps)) / (2 * eps)
    names = [m.name for m in robot.motors]
    return {"tau": dict(zip(names, tau)), "residual": residual, "tau_fd": tau_fd,
            "tau_adjust": np.array([tau[names.index(f"adjust_{t}")] for t in WHEELS])}


def compare(robot: Robot | None = None, runs: dict | None = None) -> Comparison:
    """The paper's printed numbers (section 7, Table 2) against the transcribed IK/statics and the model.

    Tolerances: angles read off the figures or printed to 5 deg: 2.5 deg; torques printed to 0.1 N m: 0.05 N m;
    the "4" N m of section 7: 0.5; convergence: the paper's criterion 1e-5.

    Args:
        robot: The robot (default ``None``: built with the default parameters).
        runs: Mission runs by name (:func:`~robotdyn.robots.adaptable_wheel.missions.run_mission`; default ``None``:
            run here).

    Returns:
        The :class:`~robotdyn.interfaces.comparison.Comparison`.
    """
    robot = robot or Robot(SPEC)
    params = {k: v for k, v in robot.params.items() if k != "terrain"}
    runs = runs or {name: run_mission(name, params) for name in MISSIONS}
    m1, m2 = runs["mission1"], runs["mission2"]
    reading = params["L_reading"]
    cmp = Comparison(f"Mardani & Ebrahimi 2016 vs robotdyn (L_reading={reading}: offsets {offsets(params)['fr'][:2]})")
    worst = max(m1.error.max(), m2.error.max())
    cmp.add("eq 24: max ||C|| over missions 1-2 (criterion 1e-5)", 1e-5, worst, 1e-5,
            note="our criterion is 1e-10; the paper's 1e-5 is met")
    qd = np.degrees(m1.q)
    cmp.add("Fig. 11 / sec 7: min adjustment angle, mission 1 [deg]", 20.0, qd.min(), 2.5)
    cmp.add("Fig. 11 / sec 7: max adjustment angle, mission 1 [deg]", 170.0, qd.max(), 2.5)
    cmp.add("sec 8: min adjustment angle (40-170 deg) [deg]", 40.0, qd.min(), 2.5)
    t35 = np.abs(paper_torque_eq35(m1.q, params))
    cmp.add("sec 7: min torque, mission 1, eq 35 [N m]", 1.4, t35.min(), 0.05)
    cmp.add("sec 7: max torque, mission 1, eq 35 [N m]", 4.0, t35.max(), 0.5)
    full = np.array([np.abs(static_torques(m1.commands[i], np.concatenate([m1.beta[i], m1.q[i]]), params,
                                           _terrain({**params, "terrain": "rough"})).torque)
                     for i in range(0, len(m1.t), 5)])
    cmp.add("sec 7: min torque, mission 1, eqs 25-34 [N m]", 1.4, full.min(), 0.05)
    cmp.add("sec 7: max torque, mission 1, eqs 25-34 [N m]", 4.0, full.max(), 0.5)
    ramp = _terrain({**params, "terrain": "ramp"})
    x2 = np.concatenate([m2.beta[0], m2.q[0]])
    st2 = static_torques(m2.commands[0], x2, params, ramp)
    for k, tag in enumerate(WHEELS):
        torque, angle = TABLE2[tag]
        cmp.add(f"Table 2: angle {tag} [deg]", angle, np.degrees(m2.q[0, k]), 2.5)
        cmp.add(f"Table 2: torque {tag}, eq 35 at our angle [N m]", torque,
                abs(paper_torque_eq35(m2.q[0, k], params)), 0.05)
        cmp.add(f"Table 2: torque {tag}, eqs 25-34 at our angle [N m]", torque, abs(st2.torque[k]), 0.05)
        cmp.add(f"Table 2: torque {tag}, eq 35 at Table 2's angle [N m]", torque,
                abs(paper_torque_eq35(np.radians(angle), params)), 0.05,
                note="internal consistency of Table 2 with eq 35")
    cmp.rows.extend(loads_comparison({k: v for k, v in params.items() if k != "lateral"}).rows)
    return cmp


# ------------------------------------------------------------------------------------------------------ CLI
def cmd_ik(args) -> int:
    """``robotdyn ik adaptable_wheel --commands x_d y_d h_CG q_xd q_yd q_zd``: eqs 4-24 and the static torques.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status 0 (the results are printed).
    """
    import json

    from ...cli.commands import _jsonable
    from ...inputs import as_vector, parse_assignments

    from ...inputs import MAX_ANGLE, MAX_POSITION, refuse_together

    for flag in ("urdf", "constraints", "xacro_arg", "package", "twist"):  # ik solves the built-in robot's eqs 4-24
        if getattr(args, flag, None):
            raise InputError(f"--{flag.replace('_', '-')}: ik solves {SPEC.name}'s own equations (eqs 4-24); "
                             "expected --param NAME=VALUE for its numbers")
    if args.robot != SPEC.name:
        raise InputError(f"ik is implemented for {SPEC.name} only, not {args.robot!r}")
    refuse_together(args, "mission", "commands")
    if args.csv and not args.mission:
        raise InputError("--csv writes a mission's steps; expected it with --mission")
    robot = Robot(SPEC, parse_assignments(args.param))
    p = robot.params
    if args.mission:
        run = run_mission(args.mission, {k: v for k, v in p.items() if k != "terrain"})
        data = {"mission": run.mission.name, "description": run.mission.description, "steps": len(run.t),
                "max_error": float(run.error.max()), "q_min_deg": np.degrees(run.q.min(0)),
                "q_max_deg": np.degrees(run.q.max(0))}
        if args.csv:
            cols = np.column_stack([run.t, run.cg, run.yaw, run.beta, run.q, run.RT, run.error])
            header = "t,x_cg,y_cg,z_cg,q_zd," + ",".join(
                [f"beta_{t}" for t in WHEELS] + [f"q_{t}" for t in WHEELS] + [f"RT_{t}" for t in WHEELS]) + ",error"
            np.savetxt(args.csv, cols, delimiter=",", header=header, comments="")
            data["csv"] = args.csv
        text = [f"{run.mission.name}: {run.mission.description}",
                f"{len(run.t)} steps, max ||C|| = {run.error.max():.3g}",
                *(f"  q_{t}: {np.degrees(run.q[:, k].min()):.3f} .. {np.degrees(run.q[:, k].max()):.3f} deg"
                  for k, t in enumerate(WHEELS))]
        if args.csv:
            text.append(f"wrote {args.csv}")
    else:
        if args.commands is None:
            raise InputError("ik needs --commands x_d y_d h_CG q_xd q_yd q_zd (m, m, m, rad, rad, rad) or --mission")
        c = as_vector(args.commands, 6, "commands", ["x_d", "y_d", "h_CG", "q_xd", "q_yd", "q_zd"], MAX_POSITION)
        for k, name in enumerate(("q_xd", "q_yd", "q_zd"), start=3):
            if abs(c[k]) > MAX_ANGLE:
                raise InputError(f"commands[{name}] = {c[k]:g} rad; expected an angle of magnitude <= {MAX_ANGLE:.6g} "
                                 "rad (one turn)")
        if c[2] <= 0:
            raise InputError(f"commands[h_CG] = {c[2]:g} m; expected a positive height above the surface")
        cmd = Commands(c[0], c[1], c[2], c[3], c[4], c[5])
        x, err, nfev = solve_ik(cmd, p, robot.terrain)
        res = static_torques(cmd, x, p, robot.terrain)
        q = model_configuration(robot, cmd, x)
        data = {"beta": dict(zip(WHEELS, x[:3])), "q_deg": dict(zip(WHEELS, np.degrees(x[3:]))),
                "q": dict(zip(WHEELS, x[3:])), "R_T": dict(zip(WHEELS, p["R_ru"] + radius_law(x[3:], p["w"]))),
                "error": err, "evaluations": nfev, "torque_eq35": dict(zip(WHEELS, paper_torque_eq35(x[3:], p))),
                "torque_eq34": dict(zip(WHEELS, res.torque)), "contact_forces": res.forces,
                "model_q": dict(zip(robot.coordinates, q))}
        text = [f"inverse kinematics (eqs 4-24) on {robot.terrain!r}: ||C|| = {err:.3g} ({nfev} evaluations)",
                f"{'wheel':>6} {'beta [deg]':>11} {'q [deg]':>9} {'R_T [m]':>9} {'t eq35':>9} {'t eq34':>9}"
                f" {'F_n [N]':>9}"]
        for k, t in enumerate(WHEELS):
            text.append(f"{t:>6} {np.degrees(x[k]):>11.5f} {np.degrees(x[3 + k]):>9.4f} "
                        f"{data['R_T'][t]:>9.5f} {data['torque_eq35'][t]:>9.4f} {res.torque[k]:>9.4f} "
                        f"{res.normal[k]:>9.4f}")
        text.append("model coordinates: " + " ".join(f"{v:.10g}" for v in q))
    if args.json:
        print(json.dumps(data, indent=2, default=_jsonable))
    else:
        print("\n".join(text))
    return 0


def register_cli(subparsers, parents) -> None:
    """Add ``robotdyn ik ROBOT --commands ...`` (or ``--mission NAME``).

    Args:
        subparsers: The CLI's subparsers (``argparse`` action).
        parents: Parsers whose arguments it inherits (the common and robot arguments).
    """
    name = "ik" if "ik" not in subparsers.choices else "wheel-ik"
    p = subparsers.add_parser(name, parents=parents,
                              help="adaptable_wheel: inverse kinematics (eqs 4-24) and static torques")
    p.add_argument("--commands", nargs="+", help="x_d y_d h_CG q_xd q_yd q_zd [m, m, m, rad, rad, rad]")
    p.add_argument("--mission", choices=sorted(MISSIONS), help="run a whole mission of section 7 instead")
    p.add_argument("--csv", help="with --mission: write the solution at every step to this CSV file")
    p.set_defaults(func=cmd_ik)


# ------------------------------------------------------------------------------------------- wheel loads (sec 5)
def hold_loads(terrain: str = "flat", lateral: str = "rolling",
               params: dict | None = None) -> tuple[Robot, np.ndarray, np.ndarray, ConstraintForces]:
    """robotdyn's wheel loads with the robot at rest on ``terrain`` (the ``hold`` scenario's pose: the paper's IK at
    the path origin, h_CG = 0.15 m, body level, and its least-squares holding torques).

    On flat ground the rolling model is singular (the two front wheels' lateral rows coincide, errata), so the
    loads there are taken with ``lateral="slip"``: at rest nothing pushes sideways, so dropping the lateral rows
    changes no force.

    Args:
        terrain: ``flat``, ``ramp`` (mission 2) or ``rough`` (Table 1).
        lateral: The ``lateral`` parameter of :data:`.model.SPEC` (``rolling`` or ``slip``).
        params: Further parameters of :data:`.model.SPEC` (default ``None``: the defaults).

    Returns:
        ``(robot, q, tau, forces)``: the robot, the configuration (n,), the holding torques (6,) [N m] (spin fr, fl,
        r, adjust fr, fl, r) and the :class:`~robotdyn.contact.contact_forces.ConstraintForces`.
    """
    from .model import HoldScenario

    robot = Robot(SPEC, {**(params or {}), "terrain": terrain, "lateral": lateral})
    hold = HoldScenario("hold", "at rest", 1.0)
    q, nu = hold.initial_state(robot)
    return robot, q, hold.holding, robot.contact_forces(q, nu, tau=hold.holding)


def loads_comparison(params: dict | None = None) -> Comparison:
    """Sec 5's equal share m g / 3 against robotdyn's loads at rest on flat ground, and eq 35's torques against
    robotdyn's holding torques at the same angles.

    Tolerance 0.05 N on loads and 0.005 N m on torques (both are closed forms on either side).

    Args:
        params: Parameters of :data:`.model.SPEC` (default ``None``: the defaults).

    Returns:
        The :class:`~robotdyn.interfaces.comparison.Comparison`.
    """
    from .paper import paper_flat_loads

    robot, q, tau, forces = hold_loads("flat", "slip", params)
    p = robot.params
    share = paper_flat_loads(p)
    cmp = Comparison("Mardani & Ebrahimi 2016, sec 5 (wheel loads on flat ground) vs robotdyn")
    for k, w in enumerate(forces.wheels):
        cmp.add(f"sec 5: load {w.name}, flat ground (m g / 3) [N]", share[k], w.normal, 0.05,
                note="robotdyn: Robot.contact_forces at rest; the lever rule gives m g/4 (front), m g/2 (rear)")
    angles = np.array([q[robot.coordinate_index(f"q_{t}")] for t in WHEELS])
    for k, t in enumerate(WHEELS):
        cmp.add(f"eq 35: holding torque {t}, flat ground [N m]", abs(paper_torque_eq35(angles[k], p)),
                abs(tau[3 + k]), 0.005, note="robotdyn: least-squares holding torques of the rolling model")
    return cmp

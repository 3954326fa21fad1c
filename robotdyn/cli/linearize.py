"""``robotdyn linearize``: the linearised state-space model (A, B, eigenvalues) of a robot's reduced dynamics about
a state, optionally restricted to some states and with an LQR gain (:mod:`robotdyn.reduction.linearization`)."""

from __future__ import annotations

import numpy as np

from ..errors import RobotDynError
from ..inputs import MAX_POSITION, as_vector


def cmd_linearize(args) -> int:
    """``robotdyn linearize ROBOT [--q ...] [--set NAME=VALUE] [--v ...] [--tau ...] [--states ...]
    [--lqr-q ... --lqr-r ...]``: the linearised reduced dynamics (A, B, eigenvalues of A; with ``--lqr-q``/``--lqr-r``
    an LQR gain and the closed-loop eigenvalues) about a state, printed as text or (``--json``) as JSON.

    Args:
        args: The parsed command line (``argparse.Namespace``): ``q`` natural coordinates in the order ``info``
            lists them [m, rad] (default: the neutral configuration), ``set`` NAME=VALUE overrides, ``v`` the
            independent velocities [m/s, rad/s] (default zeros), ``tau``/``tau_set`` the motor torques [N m or N]
            (default zeros), ``states`` the states to keep, ``lqr_q``/``lqr_r`` the LQR weights (one per kept state,
            >= 0; one per motor, > 0).

    Returns:
        The exit status, 0.

    Raises:
        RobotDynError: Bad input (a coordinate off the holonomic constraints, a wrong number of values, only one
            of ``--lqr-q``/``--lqr-r``, a negative state weight or a non-positive input weight), which
            :func:`~robotdyn.cli.commands.main` prints in one line with status 2.
    """
    from ..reduction.linearization import linearize, lqr
    from .commands import _emit, _load, _matrix_text, _numbers, _torques, _vector_text

    _, robot = _load(args)
    q = robot.neutral() if args.q is None else as_vector(args.q, robot.nq, "q", robot.coordinates, MAX_POSITION)
    for name, x in _numbers(args.set, "--set", "a value in m or rad").items():
        q[robot.coordinate_index(name)] = x
    q = robot.check_q(q)
    robot.check_constraints(q)
    nu = np.zeros(robot.mobility) if args.v is None else robot.check_nu(args.v, "v")
    tau = _torques(robot, args.tau, args.tau_set)
    model = linearize(robot, q, nu, tau)
    if args.states:
        model = model.restrict(args.states)
    ev = model.eigenvalues
    out = {"robot": args.robot, "states": model.states, "inputs": model.inputs, "x0": model.x0, "tau0": model.tau0,
           "xdot0": model.xdot0, "A": model.A, "B": model.B, "eigenvalues_real": ev.real, "eigenvalues_imag": ev.imag,
           "numerical_pieces": list(model.numerical)}
    text = [f"linearised reduced dynamics of {args.robot} about x0 (states: positions [m, rad], velocities "
            f"[m/s, rad/s]; inputs [N m or N])",
            _vector_text("x0", model.states, model.x0),
            _vector_text("xdot0 (zero at an equilibrium)", model.states, model.xdot0),
            _matrix_text("A", model.states, model.states, model.A),
            _matrix_text("B", model.states, model.inputs, model.B),
            "eigenvalues of A [1/s]:", *(f"  {z.real: .10g} {z.imag:+.10g}j" for z in ev)]
    if model.numerical:
        text.append("by finite differences: " + "; ".join(model.numerical))
    if (args.lqr_q is None) != (args.lqr_r is None):
        raise RobotDynError("--lqr-q and --lqr-r go together: the state weights (one per state) and the input "
                            "weights (one per motor)")
    if args.lqr_q is not None:
        Q = as_vector(args.lqr_q, len(model.states), "--lqr-q", model.states, 1e12, "")
        R = as_vector(args.lqr_r, len(model.inputs), "--lqr-r", model.inputs, 1e12, "")
        if np.any(Q < 0) or np.any(R <= 0):
            raise RobotDynError("--lqr-q weights must be >= 0 and --lqr-r weights > 0")
        K, closed = lqr(model, Q, R)
        out.update(K=K, closed_loop_real=closed.real, closed_loop_imag=closed.imag)
        text += [_matrix_text("LQR gain K (tau = tau0 - K (x - x0))", model.inputs, model.states, K),
                 "closed-loop eigenvalues [1/s]:", *(f"  {z.real: .10g} {z.imag:+.10g}j" for z in closed)]
    _emit(args, out, "\n".join(text))
    return 0


def register(sub, parents) -> None:
    """Add the ``linearize`` subcommand.

    Args:
        sub: The CLI's subparsers (``argparse`` action).
        parents: Parsers whose arguments it inherits (the common and robot arguments).
    """
    p = sub.add_parser("linearize", parents=parents,
                       help="linearised state-space model (A, B, eigenvalues; optional LQR gain) about a state")
    p.add_argument("--q", nargs="+", help="natural coordinates, in the order info lists them (default: the neutral "
                                          "configuration); must satisfy the holonomic constraints")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="set one coordinate by name, e.g. --set theta3=3.14159 (repeatable; applied after --q)")
    p.add_argument("--v", nargs="+", help="independent velocities (default zeros)")
    p.add_argument("--tau", nargs="+", help="motor torques (default zeros)")
    p.add_argument("--tau-set", action="append", default=[], metavar="MOTOR=VALUE",
                   help="one motor torque by name (repeatable; the others from --tau or 0)")
    p.add_argument("--states", nargs="+", help="keep only these states (names as printed), e.g. those the motors "
                                               "can reach")
    p.add_argument("--lqr-q", nargs="+", help="LQR state weights, one per state (after --states)")
    p.add_argument("--lqr-r", nargs="+", help="LQR input weights, one per motor")
    p.set_defaults(func=cmd_linearize)


__all__ = ["cmd_linearize", "register"]

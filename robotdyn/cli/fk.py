"""``robotdyn fk``: the pose of a frame (forward kinematics, :mod:`robotdyn.description.kinematics`), a subcommand
that robot modules register (``register_fk_cli``)."""

from __future__ import annotations

from ..description.kinematics import frame_pose, pose_text, relative_pose, rotation_defects


def cmd_fk(args) -> int:
    """``robotdyn fk ROBOT --q ... --frame NAME [--base NAME]``: print the 4x4 pose of a frame.

    Args:
        args: The parsed command line (``argparse.Namespace``).

    Returns:
        The exit status, 0. Errors raise :class:`~robotdyn.errors.RobotDynError`, which
        :func:`~robotdyn.cli.commands.main` prints in one line with status 2.
    """
    from .commands import _emit, _load

    _, robot = _load(args)
    if args.base:
        T = relative_pose(robot, args.q, args.frame, args.base)
        where = f"in frame {args.base!r}"
    else:
        T = frame_pose(robot, args.q, args.frame)
        where = "in the world frame"
    ortho, det = rotation_defects(T[:3, :3])
    data = {"robot": args.robot, "frame": args.frame, "base": args.base or "world", "T": T,
            "rotation_orthonormality_defect": ortho, "rotation_det_minus_1": det}
    text = pose_text(T, f"pose of {args.frame!r} {where} (rotation | position [m]):") + (
        f"\nrotation check: max|R^T R - I| = {ortho:.2e}, det R - 1 = {det:.2e}")
    _emit(args, data, text)
    return 0


def register_fk_cli(subparsers, parents) -> None:
    """Add the generic ``fk`` subcommand (once, whichever robot module registers it first).

    Args:
        subparsers: The CLI's subparsers (``argparse`` action).
        parents: Parsers whose arguments it inherits (the common and robot arguments).
    """
    if "fk" in subparsers.choices:
        return
    p = subparsers.add_parser("fk", parents=parents, help="4x4 pose of a frame (forward kinematics)")
    p.add_argument("--q", nargs="+", required=True, help="natural coordinates, in the order info lists them")
    p.add_argument("--frame", required=True, help="frame (link) name")
    p.add_argument("--base", default=None, help="express the pose in this frame instead of the world")
    p.set_defaults(func=cmd_fk)


__all__ = ["cmd_fk", "register_fk_cli"]

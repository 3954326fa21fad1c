"""Plots of trajectories and comparisons (matplotlib: the Agg backend, files and no window, unless ``MPLBACKEND``
names one, as a Jupyter kernel does for its inline figures)."""

from __future__ import annotations

import os
from collections.abc import Sequence

import matplotlib
import numpy as np

if not os.environ.get("MPLBACKEND"):  # keep a backend chosen by the user or a notebook kernel (inline figures)
    matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

def _unit(traj, name: str) -> str:
    """The column's unit as the trajectory records it (from the joint types), else a guess from the name."""
    if name in getattr(traj, "units", {}):
        return traj.units[name]
    base = name[:-4] if name.endswith("_dot") else name
    unit = "m" if base in ("x", "y", "z") else "rad"
    return unit + ("/s" if name.endswith("_dot") else "")


def plot_trajectory(
    traj,
    columns: Sequence[str],
    path=None,
    title: str = "",
    zoom: float | None = None,
    references: dict[str, list[tuple[float, str]]] | None = None,
    pose: tuple[str, str, str] | None = None,
):
    """Plot columns of a :class:`~robotdyn.simulation.trajectory.Trajectory` against time.

    Args:
        traj: The trajectory.
        columns: Coordinate or velocity names, one row of axes each.
        path: Where to save the figure (PNG/PDF/SVG by extension); ``None`` to only return it.
        title: Figure title.
        zoom: If given, a second column of axes shows only ``0 <= t <= zoom`` (the paper's transient windows).
        references: Horizontal reference lines per column, e.g. a paper's printed amplitude.
        pose: Names of the root's x [m], y [m] and heading [rad] coordinates (:func:`pose_columns`); if given, a
            first column of axes draws the root's path in the world x-y plane with its heading (:func:`plot_path`).

    Returns:
        The matplotlib figure.
    """
    ncol = 2 if zoom else 1
    extra = 1 if pose else 0
    rows = max(len(columns), 2 if pose else 1)
    fig, grid = plt.subplots(rows, ncol + extra, figsize=(5.5 * (ncol + extra), 2.3 * rows), squeeze=False)
    axes = grid[:, extra:]
    if pose:
        for ax in grid[:, 0]:
            ax.remove()
        plot_path(traj, *pose, fig.add_subplot(1, ncol + extra, 1))
    for ax in axes[len(columns):].ravel():
        ax.remove()
    for i, name in enumerate(columns):
        y = traj.column(name)
        for j in range(ncol):
            ax = axes[i, j]
            mask = slice(None) if j == 0 else traj.t <= zoom
            ax.plot(traj.t[mask], y[mask], lw=1.2, label="robotdyn")
            for value, label in (references or {}).get(name, []):
                ax.axhline(value, color="C3", ls="--", lw=1.0, label=label)
            ax.set_ylabel(f"{name} [{_unit(traj, name)}]")
            ax.grid(alpha=0.3)
            if i == len(columns) - 1:
                ax.set_xlabel("t [s]")
            if i == 0:
                ax.set_title("whole run" if j == 0 else f"first {zoom:g} s")
            if (references or {}).get(name) and j == ncol - 1:
                ax.legend(fontsize=7, loc="upper right")
    return finish(fig, path, title)


def pose_columns(robot, traj) -> tuple[str, str, str] | None:
    """The names of a planar or floating root's x, y and heading (psi, or yaw) coordinates in ``traj`` (the
    robot's labels of the root joints); ``None`` for a fixed root or a trajectory without them.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` simulated.
        traj: Its :class:`~robotdyn.simulation.trajectory.Trajectory`.

    Returns:
        The three column names ``(x, y, heading)``, or ``None`` where ``traj`` has no such root.
    """
    joints = robot.description.joint_names
    heading = "psi" if robot.spec.root == "planar" else "yaw" if robot.spec.root == "floating" else None
    if heading is None or not all(j in joints for j in ("x", "y", heading)):
        return None
    names = tuple(robot.coordinates[joints.index(j)] for j in ("x", "y", heading))
    return names if all(n in traj.coordinates for n in names) else None


def plot_path(traj, x: str, y: str, heading: str, ax=None):
    """Draw the root's path in the world x-y plane [m], equal axes, with its heading as arrows at about ten
    evenly spaced times, the start (circle) and the end (square).

    Args:
        traj: The :class:`~robotdyn.simulation.trajectory.Trajectory`.
        x, y: Names of the root's world x and y coordinates [m].
        heading: Name of its heading (yaw about the world z axis) [rad].
        ax: Axes to draw in (default: a new figure's).

    Returns:
        The axes.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(5.0, 5.0))
    px, py, psi = traj.column(x), traj.column(y), traj.column(heading)
    ax.plot(px, py, lw=1.4, color="C0", label="path")
    span = max(float(np.ptp(px)), float(np.ptp(py)), 1e-3)
    idx = np.unique(np.linspace(0, len(px) - 1, min(len(px), 11)).astype(int))
    ax.quiver(px[idx], py[idx], np.cos(psi[idx]), np.sin(psi[idx]), angles="xy", scale_units="xy",
              scale=1.0 / (0.08 * span), width=0.006, color="C1", label=f"heading ({heading})")
    ax.plot(px[0], py[0], "o", color="k", ms=5, label=f"start (t = {traj.t[0]:g} s)")
    ax.plot(px[-1], py[-1], "s", color="k", ms=5, label=f"end (t = {traj.t[-1]:g} s)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.15)
    ax.set_xlabel(f"{x} [m]")
    ax.set_ylabel(f"{y} [m]")
    ax.set_title("path in the world x-y plane")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return ax


def finish(fig, path=None, title: str = ""):
    """Title and lay out a figure, then save it atomically (:func:`robotdyn.output.save_figure`) and close it when
    ``path`` is given; returns the figure.

    Args:
        fig: The matplotlib figure.
        path: The image file (default ``None``: not saved, the figure stays open).
        title: The figure's title (default: none).

    Returns:
        The matplotlib figure ``fig`` (closed if it was saved).
    """
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if path is not None:
        from ..output import save_figure

        try:
            save_figure(fig, path)
        finally:
            plt.close(fig)
    return fig


def wheel_order(robot, wheels: Sequence[str]) -> tuple[list[str], set[str]]:
    """Wheels in the order a traction plot lists them, drive wheels first (a wheel whose spin joint a motor
    drives), then the others in the robot's order; and the support wheels among them (frictionless: they carry a
    load but cannot slip).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (``None``: the given order, no support wheels known).
        wheels: Wheel names (:attr:`robotdyn.contact.traction.Traction.wheels`).

    Returns:
        ``(ordered names, names of the support wheels)``.
    """
    if robot is None:
        return list(wheels), set()
    driven_links = set()
    joints = robot.description.joint_names
    for m in robot.spec.motors:
        joint = m.joint if m.joint in joints else next((j for j, label in robot.spec.labels.items()
                                                        if label == m.joint), m.joint)
        jid = robot.model.getJointId(joint) if robot.model.existJointName(joint) else None
        if jid is not None:
            driven_links.update(f.name for f in robot.model.frames if f.parentJoint == jid)
    spec = {(w.name or w.frame): w for w in robot.spec.wheels}
    drive = [w for w in wheels if w in spec and spec[w].frame in driven_links]
    rest = [w for w in wheels if w not in drive]
    supports = {w for w in wheels if w in spec and spec[w].kind == "support"}
    return drive + rest, supports


def _stick_slip_lines(ax, tr, j: int, color) -> None:
    """A stick-slip wheel's phases on the friction panel ``ax``: its required friction where it sticks and its
    friction force is determined (thin), its friction ratio mu where it slides (thick), its mu (dashed) and its
    sliding samples shaded in its colour."""
    name = tr.wheels[j]
    slides = tr.phases[:, j]
    known = tr.known[:, j] if tr.known is not None else np.full(len(tr.t), bool(tr.friction_determined[j]))
    mu = np.where(known & np.isfinite(tr.required_mu[:, j]), tr.required_mu[:, j], np.nan)
    sticks = ~slides & known
    ax.plot(tr.t, np.where(slides, np.nan, mu), lw=1.2, color=color,
            label=f"{name} sticking" + ("" if sticks.any() else ": friction not determined" if (~slides).any() else
                                         " (never)"))
    if slides.any():
        ax.plot(tr.t, np.where(slides, mu, np.nan), lw=3.0, alpha=0.5, color=color,
                label=f"{name} sliding (friction mu N), {100 * slides.mean():.3g} % of the samples")
        ax.fill_between(tr.t, 0, 1, where=slides, transform=ax.get_xaxis_transform(), color=color, alpha=0.08)
    if np.isfinite(tr.mu[j]):
        ax.axhline(tr.mu[j], color=color, ls="--", lw=1.0)


def plot_traction(tr, path=None, title: str = "", robot=None):
    """Plot a :class:`~robotdyn.contact.traction.Traction`: normal loads (top) and required friction (bottom)
    per wheel against time, shaded where a rigid wheel is unloaded (load <= 0: lifting off) or a rolling wheel needs
    more friction than its mu (drawn dashed): where the no-slip assumption breaks; and, in a band of its own, where
    a compliant wheel is in the air (:meth:`~robotdyn.contact.traction.Traction.in_air`: flight, which its model
    allows).

    A stick-slip wheel (:attr:`~robotdyn.contact.traction.Traction.phases`) shows its phases: its required friction
    drawn thin while it sticks, its friction ratio (mu) drawn thick and the band shaded in its colour while it slides.

    Drive wheels come first. Every wheel that can slip has its required friction ``|f_t|/f_n`` drawn where it is
    determined; where rigid-body dynamics split a force between wheels only as a sum (e.g. two wheels on one
    axle share a lateral force), the smallest mu with which some split lies inside every friction cone
    (:attr:`~robotdyn.contact.traction.Traction.minimum_mu`) is drawn for them instead. Support wheels
    (frictionless) appear only in the load panel.

    Args:
        tr: The traction (:func:`robotdyn.contact.traction.traction`).
        path: Where to save the figure (PNG/PDF/SVG by extension); ``None`` to only return it.
        title: Figure title.
        robot: The :class:`~robotdyn.robot.Robot` simulated, to order the wheels (drive wheels first) and tell
            the support wheels (default ``None``: the traction's order, every wheel treated alike).

    Returns:
        The matplotlib figure.
    """
    fig, (ax_n, ax_mu) = plt.subplots(2, 1, figsize=(7.0, 5.0), sharex=True)
    broken = tr.broken().any(axis=1) if tr.wheels else np.zeros(len(tr.t), bool)
    flying = tr.in_air().any(axis=1) if tr.wheels else np.zeros(len(tr.t), bool)
    order, supports = wheel_order(robot, tr.wheels)
    pending = []  # wheels that can slip but whose own friction force is not determined
    for name in order:
        j = tr.wheels.index(name)
        (line,) = ax_n.plot(tr.t, tr.normal[:, j], lw=1.2,
                            label=f"{name} (support, frictionless)" if name in supports else name)
        if name in supports:
            continue
        if name in getattr(tr, "stick_slip", ()):  # its phases: thin while it sticks, thick and shaded while it slides
            _stick_slip_lines(ax_mu, tr, j, line.get_color())
            continue
        if not tr.friction_determined[j]:
            pending.append(name)
            continue
        mu = np.where(np.isfinite(tr.required_mu[:, j]), tr.required_mu[:, j], np.nan)
        ax_mu.plot(tr.t, mu, lw=1.2, color=line.get_color(), label=name)
        if np.isfinite(tr.mu[j]):
            ax_mu.axhline(tr.mu[j], color=line.get_color(), ls="--", lw=1.0)
    if tr.minimum_mu is not None:  # every wheel's need, the open forces split at best
        minimum = np.where(np.isfinite(tr.minimum_mu), tr.minimum_mu, np.nan)
        peak = f"max {np.nanmax(minimum):.3g}" if np.isfinite(minimum).any() else "not determined"
        who = f"{', '.join(pending)}: smallest mu of the best split" if pending else "all wheels, best split (minimum mu)"
        ax_mu.plot(tr.t, minimum, lw=1.6, color="k", label=f"{who} ({peak})")
    elif pending:
        ax_mu.plot([], [], lw=0, label=f"{', '.join(pending)}: friction not determined")
    for ax in (ax_n, ax_mu):
        if broken.any():
            ax.fill_between(tr.t, 0, 1, where=broken, transform=ax.get_xaxis_transform(), color="C3", alpha=0.15,
                            label="a wheel unloaded or beyond its mu" if ax is ax_n else None)
        if flying.any():
            ax.fill_between(tr.t, 0, 1, where=flying, transform=ax.get_xaxis_transform(), color="C0", alpha=0.12,
                            hatch="//", label="a compliant wheel in the air (flight)" if ax is ax_n else None)
        ax.grid(alpha=0.3)
    ax_n.axhline(0.0, color="k", lw=0.8)
    drawn = [y for line in ax_mu.lines for y in np.asarray(line.get_ydata(), float).ravel() if np.isfinite(y)]
    top = max(ax_mu.get_ylim()[1], 1.1 * max(drawn)) if drawn else None
    ax_mu.set_ylim(bottom=0.0, top=top)  # (a constant line, e.g. a steady turn's mu, not hidden on the frame)
    ax_n.set_ylabel("normal load [N]")
    ax_mu.set_ylabel("required friction |f_t|/f_n")
    ax_mu.set_xlabel("t [s]")
    if tr.wheels:
        ax_n.legend(fontsize=7, loc="best")
        ax_mu.legend(fontsize=7, loc="best")
    if tr.undetermined:
        ax_n.set_title(f"loads of {', '.join(tr.undetermined)} not determined", fontsize=8)
    return finish(fig, path, title)

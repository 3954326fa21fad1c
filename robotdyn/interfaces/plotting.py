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
):
    """Plot columns of a :class:`~robotdyn.simulation.trajectory.Trajectory` against time.

    Args:
        traj: The trajectory.
        columns: Coordinate or velocity names, one row of axes each.
        path: Where to save the figure (PNG/PDF/SVG by extension); ``None`` to only return it.
        title: Figure title.
        zoom: If given, a second column of axes shows only ``0 <= t <= zoom`` (the paper's transient windows).
        references: Horizontal reference lines per column, e.g. a paper's printed amplitude.

    Returns:
        The matplotlib figure.
    """
    ncol = 2 if zoom else 1
    fig, axes = plt.subplots(len(columns), ncol, figsize=(5.5 * ncol, 2.3 * len(columns)), squeeze=False)
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


def finish(fig, path=None, title: str = ""):
    """Title and lay out a figure, then save it atomically (:func:`robotdyn.output.save_figure`) and close it when
    ``path`` is given; returns the figure."""
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


def plot_traction(tr, path=None, title: str = ""):
    """A :class:`~robotdyn.contact.traction.Traction`: normal loads and required friction per wheel against time, shaded where the no-slip assumption is broken
    (load <= 0, or required friction above the wheel's mu, drawn dashed)."""
    fig, (ax_n, ax_mu) = plt.subplots(2, 1, figsize=(7.0, 5.0), sharex=True)
    broken = tr.broken().any(axis=1) if tr.wheels else np.zeros(len(tr.t), bool)
    for j, name in enumerate(tr.wheels):
        ax_n.plot(tr.t, tr.normal[:, j], lw=1.2, label=name)
        if not tr.friction_determined[j]:
            ax_mu.plot([], [], lw=1.2, label=f"{name}: friction not determined")
            continue
        mu = np.where(np.isfinite(tr.required_mu[:, j]), tr.required_mu[:, j], np.nan)
        (line,) = ax_mu.plot(tr.t, mu, lw=1.2, label=name)
        if np.isfinite(tr.mu[j]):
            ax_mu.axhline(tr.mu[j], color=line.get_color(), ls="--", lw=1.0)
    if getattr(tr, "minimum_mu", None) is not None:  # every wheel's need, the open forces split at best
        ax_mu.plot(tr.t, np.where(np.isfinite(tr.minimum_mu), tr.minimum_mu, np.nan), color="k", lw=1.4,
                   label="all wheels, best split (minimum mu)")
    for ax in (ax_n, ax_mu):
        if broken.any():
            ax.fill_between(tr.t, 0, 1, where=broken, transform=ax.get_xaxis_transform(), color="C3", alpha=0.15,
                            label="no-slip broken" if ax is ax_n else None)
        ax.grid(alpha=0.3)
    ax_n.axhline(0.0, color="k", lw=0.8)
    ax_n.set_ylabel("normal load [N]")
    ax_mu.set_ylabel("required friction |f_t|/f_n")
    ax_mu.set_xlabel("t [s]")
    if tr.wheels:
        ax_n.legend(fontsize=7, loc="upper right")
        ax_mu.legend(fontsize=7, loc="upper right")
    if tr.undetermined:
        ax_n.set_title(f"loads of {', '.join(tr.undetermined)} not determined", fontsize=8)
    return finish(fig, path, title)

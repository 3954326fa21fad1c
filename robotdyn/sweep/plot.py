"""The summary plot of a sweep: one output column against each varied numeric parameter (matplotlib, Agg)."""

from __future__ import annotations

import math
from pathlib import Path

def default_column(plan) -> str:
    """The column plotted when the spec names none: the maximum of the first chosen column, else the final
    value of the first coordinate.

    Args:
        plan: The sweep's :class:`~robotdyn.sweep.plan.Plan`.

    Returns:
        The column name.
    """
    if plan.spec.plot_column:
        return plan.spec.plot_column
    if plan.spec.columns:
        return f"max.{plan.spec.columns[0]}"
    return f"final.{plan.context.columns[0]}"


def plot_summary(table, plan, path, column: str | None = None) -> Path:
    """Scatter ``column`` of the finished runs against each varied numeric parameter (the run index when none
    varies), one colour per scenario and terrain; error runs are counted in the title. Returns the path.

    Args:
        table: The results (pyarrow table).
        plan: The sweep's :class:`~robotdyn.sweep.plan.Plan`.
        path: The image file written (atomically).
        column: The plotted column (default ``None``: :func:`default_column`).

    Returns:
        The image's path.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..output import save_figure

    column = column or default_column(plan)
    data = table.to_pydict()
    ok = [i for i, s in enumerate(data["status"]) if s != "error" and data[column][i] is not None]
    errors = len(data["status"]) - sum(s != "error" for s in data["status"])
    xs = [a.name for a in plan.axes if a.ranged or all(isinstance(v, float) for v in a.values)]
    xs = xs or ["run_index"]
    cols = min(len(xs), 3)
    rows = math.ceil(len(xs) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    groups: dict[str, list[int]] = {}
    for i in ok:
        label = data["scenario"][i] + (f", {data['terrain'][i]}" if data["terrain"][i] else "")
        groups.setdefault(label, []).append(i)
    unit = plan.units.get(column, "")
    for k, name in enumerate(xs):
        ax = axes[k // cols][k % cols]
        for label, idx in groups.items():
            ax.plot([data[name][i] for i in idx], [data[column][i] for i in idx], "o", ms=3, alpha=0.7, label=label)
        xunit = plan.units.get(name, "")
        ax.set_xlabel(f"{name} [{xunit}]" if xunit and xunit != "-" else name)
        ax.set_ylabel(f"{column} [{unit}]" if unit else column)
        ax.grid(alpha=0.3)
    for k in range(len(xs), rows * cols):
        axes[k // cols][k % cols].set_visible(False)
    if len(groups) > 1:
        axes[0][0].legend(fontsize=7)
    fig.suptitle(f"{plan.robot}: {column} over {len(ok)} runs" + (f" ({errors} failed, not shown)" if errors else ""))
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
    return Path(path)


__all__ = ["plot_summary", "default_column"]

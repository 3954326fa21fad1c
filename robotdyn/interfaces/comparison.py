"""Comparison tables: a paper's printed values and closed forms next to the model's.

Each row holds a quantity, the paper's value (number or formula evaluated), the model's value, the deviation and
a verdict (``reproduced`` within the stated tolerance, or ``differs``). Verdicts are computed, never asserted.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np


@dataclass
class Row:
    """One compared quantity.

    Attributes:
        quantity: What is compared (with the paper's equation number).
        paper: The paper's value.
        model: The model's value.
        tol: Tolerance on ``|paper - model|`` for ``reproduced``.
        note: How the tolerance was chosen or what the difference means.
    """

    quantity: str
    paper: float
    model: float
    tol: float
    note: str = ""

    @property
    def deviation(self) -> float:
        return float(abs(self.paper - self.model))

    @property
    def verdict(self) -> str:
        return "reproduced" if self.deviation <= self.tol else "differs"


@dataclass
class Comparison:
    """A titled list of :class:`Row` s with text and JSON renderings.

    Attributes:
        title: The table's title.
        rows: The compared quantities (:class:`Row`).
    """

    title: str
    rows: list[Row] = field(default_factory=list)

    def add(self, quantity: str, paper: float, model: float, tol: float, note: str = "") -> Row:
        """Append a row comparing the paper's value with the model's.

        Args:
            quantity: What is compared (with the paper's equation number).
            paper: The paper's value (or its closed form evaluated).
            model: The model's value.
            tol: Tolerance on ``|paper - model|`` for ``reproduced``.
            note: How the tolerance was chosen or what a difference means.

        Returns:
            The new :class:`Row`.
        """
        row = Row(quantity, float(paper), float(model), float(tol), note)
        self.rows.append(row)
        return row

    def as_dicts(self) -> list[dict]:
        """The rows as plain data (for JSON).

        Returns:
            One dict per row, in row order: the row's fields plus ``deviation`` and ``verdict``.
        """
        return [dict(asdict(r), deviation=r.deviation, verdict=r.verdict) for r in self.rows]

    def table(self) -> str:
        """A fixed-width text table.

        Returns:
            The table as one string (lines joined with newlines).
        """
        w = max([len(r.quantity) for r in self.rows] + [8])
        lines = [self.title, f"{'quantity':<{w}}  {'paper':>13}  {'model':>13}  {'|diff|':>9}  verdict"]
        for r in self.rows:
            lines.append(f"{r.quantity:<{w}}  {r.paper:>13.6g}  {r.model:>13.6g}  {r.deviation:>9.2e}  {r.verdict}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        bad = sum(r.verdict == "differs" for r in self.rows)
        return f"Comparison({self.title!r}, rows={len(self.rows)}, differs={bad})"


def quadratic_coefficients(bias: Callable[[np.ndarray], np.ndarray], k: int) -> dict[tuple[int, int], np.ndarray]:
    """Coefficients of a vector function quadratic in nu (e.g. :math:`C_r(q,\\nu)\\nu`) by polarisation.

    Args:
        bias: A function of nu (k,) returning a vector, quadratic in nu.
        k: The length of nu.

    Returns:
        ``{(i, j): c}`` with i <= j such that ``bias(nu) = sum c_ij nu_i nu_j`` (c_ij a vector).
    """
    e = np.eye(k)
    f0 = bias(np.zeros(k))
    fi = [bias(e[i]) - f0 for i in range(k)]
    out = {}
    for i in range(k):
        out[(i, i)] = fi[i]
        for j in range(i + 1, k):
            out[(i, j)] = bias(e[i] + e[j]) - f0 - fi[i] - fi[j]
    return out

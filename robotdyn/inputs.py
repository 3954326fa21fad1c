"""Validation of user-supplied numbers: one clear line for each mistake."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from .errors import InputError


def as_vector(values, n: int, what: str, names: Sequence[str] | None = None) -> np.ndarray:
    """Convert ``values`` to a finite float vector of length ``n``.

    Args:
        values: A sequence of numbers (or strings of numbers).
        n: Expected length.
        what: What the vector is, for the message (e.g. ``"q"``).
        names: Names of the entries, listed in the message when the length is wrong.

    Raises:
        InputError: Wrong length, non-numeric or non-finite entries.
    """
    if isinstance(values, str):
        values = values.replace(",", " ").split()
    try:
        seq = list(values) if isinstance(values, Iterable) else [values]
    except TypeError:
        raise InputError(f"{what}: expected {n} numbers") from None
    expected = f"{n} values" + (f" ({', '.join(names)})" if names else "")
    if len(seq) != n:
        raise InputError(f"{what} has {len(seq)} values; expected {expected}")
    out = np.empty(n)
    for i, x in enumerate(seq):
        label = names[i] if names else str(i)
        try:
            out[i] = float(x)
        except (TypeError, ValueError):
            raise InputError(f"{what}[{label}] = {x!r} is not a number; expected {expected}") from None
        if not np.isfinite(out[i]):
            raise InputError(f"{what}[{label}] = {x!r} is not finite; expected finite numbers")
    return out


def parse_assignments(items: Iterable[str], what: str = "--param") -> dict[str, str]:
    """Parse ``NAME=VALUE`` strings into a dict (values kept as strings)."""
    out: dict[str, str] = {}
    for item in items or []:
        if "=" not in item:
            raise InputError(f"{what} {item!r} is not NAME=VALUE")
        name, value = item.split("=", 1)
        out[name.strip()] = value.strip()
    return out

"""Validation of user-supplied numbers: one clear line for each mistake."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from .errors import InputError

MAX_POSITION = 1e6
"""Largest magnitude of a coordinate [m or rad] accepted as input (beyond it sines and products lose every digit)."""
MAX_VELOCITY = 1e6
"""Largest magnitude of a velocity [m/s or rad/s] accepted as input (its squares stay far from overflow)."""
MAX_ACCELERATION = 1e9
"""Largest magnitude of an acceleration [m/s^2 or rad/s^2] accepted as input."""
MAX_FORCE = 1e9
"""Largest magnitude of a motor torque [N m] or force [N] accepted as input."""
MAX_ANGLE = 2 * np.pi
"""Largest magnitude of an angle given as a setting [rad] (an orientation, a roller or rocker angle, a heading):
one turn; beyond it a value is almost always a unit mistake (degrees) or garbage."""
MAX_FRICTION = 1e6
"""Largest friction coefficient accepted (as the constraint file's wheel ``mu``)."""


def refuse_together(args, *flags: str) -> None:
    """Refuse options that exclude each other when more than one was given (argparse names, e.g. ``"tau_set"``;
    given means neither None, False nor empty).

    Args:
        args: The parsed command line (``argparse.Namespace``).
        flags: The options' argparse names.

    Raises:
        InputError: ``--a and --tau-set exclude each other; expected one of them``.
    """
    given = [f for f in flags if getattr(args, f, None) not in (None, False, [], ())]
    if len(given) > 1:
        names = [f"--{f.replace('_', '-')}" for f in given]
        raise InputError(f"{' and '.join(names)} exclude each other; expected one of them")


def as_vector(values, n: int, what: str, names: Sequence[str] | None = None,
              limit: float | None = None, unit: str = "") -> np.ndarray:
    """Convert ``values`` to a finite float vector of length ``n``.

    Args:
        values: A sequence of numbers (or strings of numbers).
        n: Expected length.
        what: What the vector is, for the message (e.g. ``"q"``).
        names: Names of the entries, listed in the message when the length is wrong.
        limit: Largest magnitude accepted (None: any finite number), e.g. :data:`MAX_VELOCITY`.
        unit: Unit of the entries, for the message.

    Returns:
        A float array of shape (n,).

    Raises:
        InputError: Wrong length, non-numeric, non-finite or too large entries.
    """
    if isinstance(values, np.ndarray) and values.dtype == np.float64 and values.shape == (n,) and np.count_nonzero(
            np.abs(values) <= limit if limit is not None and limit < np.inf else np.isfinite(values)) == n:
        return values.copy()  # the common case in one vectorised check; any mistake takes the loop for its message
    if isinstance(values, str):
        values = values.replace(",", " ").split()
    if values is None:
        raise InputError(f"{what} is None; expected {n} values" + (f" ({', '.join(names)})" if names else ""))
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
        if limit is not None and abs(out[i]) > limit:
            raise InputError(f"{what}[{label}] = {out[i]:g}{' ' + unit if unit else ''} is beyond what a robot "
                             f"reaches; expected |{what}| <= {limit:g}{' ' + unit if unit else ''}")
    return out


def within(values: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> bool:
    """Whether every entry of ``values`` lies in [lower, upper] (a NaN never does): one vectorised test, for the hot
    path of a check whose one-line messages come from the entry-by-entry checks where it fails.

    Args:
        values: Float array.
        lower: Lower bounds, the shape of ``values`` (``-inf``: none).
        upper: Upper bounds, the shape of ``values`` (``inf``: none).

    Returns:
        ``True`` if ``lower <= values <= upper`` entry by entry.
    """
    return np.count_nonzero((values >= lower) & (values <= upper)) == values.size


def all_finite(arrays) -> bool:
    """Whether every entry of every array is finite: one test of their concatenation (``np.isfinite(x).all()`` per
    array costs several times more on the small arrays of one state; ``ravel("K")`` is a view of a column-major
    matrix).

    Args:
        arrays: Float arrays of any shapes (a sequence).

    Returns:
        ``True`` if no entry is NaN or infinite.
    """
    x = np.concatenate([a.ravel("K") for a in arrays])
    return np.count_nonzero(np.isfinite(x)) == x.size


def parse_assignments(items: Iterable[str], what: str = "--param") -> dict[str, str]:
    """Parse ``NAME=VALUE`` strings into a dict (values kept as strings).

    Args:
        items: ``NAME=VALUE`` strings (``None``: none).
        what: The option's name, for messages.

    Returns:
        A dict of NAME to VALUE (both stripped strings), in the given order; a repeated NAME keeps its last VALUE.

    Raises:
        InputError: An item without ``=``.
    """
    out: dict[str, str] = {}
    for item in items or []:
        if "=" not in item:
            raise InputError(f"{what} {item!r} is not NAME=VALUE")
        name, value = item.split("=", 1)
        out[name.strip()] = value.strip()
    return out

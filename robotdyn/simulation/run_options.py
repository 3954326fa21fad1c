"""Validation of a simulation's integrator options (output samples, tolerances, method): one line naming the option
and what was expected, before any engine starts (a NaN or negative tolerance would otherwise be taken silently by
Boost.Odeint, and an unknown method or a fractional sample count would end in numpy's or scipy's traceback)."""

from __future__ import annotations

import numbers

import numpy as np

from ..errors import RobotDynError

def check_run_options(n_out, rtol, atol, method) -> int:
    """Refuse integrator options no engine can honour.

    Args:
        n_out: Number of output samples (an integer; its range is checked by the caller).
        rtol: Relative tolerance, in (0, 1) (the rule of a sweep file's ``rtol``).
        atol: Absolute tolerance per component, in (0, 1).
        method: ``None`` or a method's name, as :func:`robotdyn.simulation.compiled_engine.check_method` takes it.

    Returns:
        ``n_out`` as an int.

    Raises:
        RobotDynError: One line naming the option, its value and what was expected.
    """
    from .compiled_engine import check_method

    if isinstance(n_out, bool) or not isinstance(n_out, numbers.Integral):
        raise RobotDynError(f"n_out = {n_out!r}; expected a whole number of output samples (>= 2)")
    for name, value in (("rtol", rtol), ("atol", atol)):
        check_tolerance(name, value)
    check_method(method)
    return int(n_out)


def check_tolerance(name: str, value) -> None:
    """Refuse an integrator tolerance outside (0, 1) (NaN, zero, negative, not a number), as every engine and a
    sweep file's ``rtol``/``atol`` need it.

    Args:
        name: ``rtol`` or ``atol`` (named in the message).
        value: The tolerance given.

    Raises:
        RobotDynError: One line naming the option, its value and what was expected.
    """
    try:
        ok = bool(np.ndim(value) == 0 and 0 < float(value) < 1)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise RobotDynError(f"{name} = {value!r}; expected a tolerance in (0, 1)")

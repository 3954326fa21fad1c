"""Validation of a simulation's integrator options (output samples, tolerances, method): one line naming the option
and what was expected, before any engine starts (a NaN or negative tolerance would otherwise be taken silently by
Boost.Odeint, and an unknown method or a fractional sample count would end in numpy's or scipy's traceback)."""

from __future__ import annotations

import numbers

import numpy as np

from ..errors import RobotDynError

SCIPY_METHODS = ("DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA")
"""``scipy.integrate.solve_ivp``'s methods by name (the scipy engine's)."""


def check_run_options(n_out, rtol, atol, method) -> int:
    """Refuse integrator options no engine can honour.

    Args:
        n_out: Number of output samples (an integer; its range is checked by the caller).
        rtol: Relative tolerance, in (0, 1) (the rule of a sweep file's ``rtol``).
        atol: Absolute tolerance per component, in (0, 1).
        method: ``None``, a compiled method (:data:`robotdyn.simulation.compiled_engine.METHODS` or
            :data:`robotdyn.simulation.compiled_engine.CVODE`), a scipy method
            name (:data:`SCIPY_METHODS`) or a ``scipy.integrate.OdeSolver`` subclass.

    Returns:
        ``n_out`` as an int.

    Raises:
        RobotDynError: One line naming the option, its value and what was expected.
    """
    from .compiled_engine import CVODE, METHODS

    if isinstance(n_out, bool) or not isinstance(n_out, numbers.Integral):
        raise RobotDynError(f"n_out = {n_out!r}; expected a whole number of output samples (>= 2)")
    for name, value in (("rtol", rtol), ("atol", atol)):
        try:
            ok = bool(np.ndim(value) == 0 and 0 < float(value) < 1)
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise RobotDynError(f"{name} = {value!r}; expected a tolerance in (0, 1)")
    if isinstance(method, str) and method not in (*METHODS, CVODE) and method not in SCIPY_METHODS:
        raise RobotDynError(f"method = {method!r}; expected one of {', '.join((*METHODS, CVODE))} (compiled) or "
                            f"{', '.join(SCIPY_METHODS)} (scipy)")
    if method is not None and not isinstance(method, (str, type)):
        raise RobotDynError(f"method = {method!r}; expected a method name or a scipy.integrate.OdeSolver subclass")
    return int(n_out)

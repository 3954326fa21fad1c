"""The one place that chooses between the compiled fast path and the Python reference.

Every evaluation that has a compiled form asks this module: :func:`reduce` (the reduced model, behind
:meth:`robotdyn.robot.Robot.reduced`) tries the robot's :class:`~robotdyn.fast.compiled.CompiledModel` and falls
back to the Python reference of :mod:`robotdyn.reduction` (which also chooses the projection's rows the compiled
model then uses); the simulation engines, the constraint forces and the many-run/batch evaluators ask
:func:`compiled_model` for the robot's compiled model (``None``: take the Python path). ``ROBOTDYN_COMPILED=0`` in
the environment turns the fast path off everywhere; :func:`use_compiled` ``(False)`` in a ``with`` block turns it off
for the calls made inside that block only: the switch is a :class:`contextvars.ContextVar`, so it belongs to the
calling thread (or asyncio task), and a block in one thread never changes what another thread evaluates.
"""

from __future__ import annotations

import os
import threading
from contextlib import contextmanager
from contextvars import ContextVar

import numpy as np

from ..reduction.reduced_dynamics import ReducedDynamics, reference
from .compiled import CompiledModel, available, why_not

_DEFAULT = os.environ.get("ROBOTDYN_COMPILED", "1") != "0"
"""Whether the fast path is on where no :func:`use_compiled` block says otherwise (``ROBOTDYN_COMPILED``)."""
_ENABLED: ContextVar[bool] = ContextVar("robotdyn_compiled", default=_DEFAULT)
"""The switch of :func:`use_compiled`: context-local (a new thread starts from :data:`_DEFAULT`)."""


def enabled() -> bool:
    """Whether the fast path is used where a robot allows it (built, and not turned off in this thread's context).

    Returns:
        ``True`` if the compiled path is built and enabled here.
    """
    return _ENABLED.get() and available()


@contextmanager
def use_compiled(flag: bool):
    """Turn the fast path on or off for the calls made inside a ``with`` block (e.g. to compare it with the Python
    path). Context-local: other threads, and code after the block, are unaffected.

    Args:
        flag: True: the compiled path where it serves; False: always the Python path.

    Yields:
        Nothing (``None``); the setting is restored on exit.
    """
    token = _ENABLED.set(bool(flag))
    try:
        yield
    finally:
        _ENABLED.reset(token)


def compiled_model(robot) -> CompiledModel | None:
    """The robot's :class:`CompiledModel` for the calling thread (built once per thread; rebuilt when its
    constraints, their terrain, radius or friction law, its joint springs' numbers or the model's gravity change),
    or ``None`` when the fast path is off or :func:`why_not` gives a reason. Each thread gets its own model, so one robot may be evaluated
    from several threads at once.

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.

    Returns:
        The :class:`~robotdyn.fast.compiled.CompiledModel`, or ``None`` where the robot cannot use the compiled path.
    """
    if not enabled():
        return None
    # one compiled model per thread: compute() returns views of its buffers, which another thread's call would
    # overwrite (the robot's Pinocchio data is per thread as well, see Robot.data)
    local = getattr(robot, "_local", None)
    cached = getattr(local, "compiled", None) if local is not None else getattr(robot, "_compiled_model", None)
    numbers = robot.model.gravity.linear.tobytes()  # (bit for bit: a cheaper test than np.array_equal)
    springs = getattr(robot, "springs", None)  # joint springs and dampers are compiled with their numbers
    if springs:  # (a tuple: a fifth of the cost of the repr this compared before, on every lookup)
        numbers = (numbers, tuple((s.index, s.stiffness, s.damping, s.rest) for s in springs))
    constraints = robot.constraints
    if cached is not None and (cached[3] is None or cached[3].owner == threading.get_ident()) \
            and cached[1] == numbers and cached[0] == constraints and all(
        getattr(c, "terrain", None) is t and getattr(c, "radius", None) == r and getattr(c, "law", None) is law
        for c, t, r, law in cached[2]  # (only the constraints that have any of the three: a closure has none)
    ):
        return cached[3]
    fast = CompiledModel(robot) if why_not(robot) is None else None
    state = [(c, getattr(c, "terrain", None), getattr(c, "radius", None), getattr(c, "law", None))
             for c in constraints]
    entry = (list(constraints), numbers, [s for s in state if s[1:] != (None, None, None)], fast)
    if local is not None:
        local.compiled = entry
    else:
        robot._compiled_model = entry
    return fast


def for_this_thread(robot, fast: CompiledModel | None) -> CompiledModel | None:
    """The compiled model an object holding ``fast`` (e.g. a trajectory problem) evaluates from the calling thread:
    ``fast`` itself in the thread that built it; in any other thread that thread's own model of ``robot``
    (:func:`compiled_model`), given ``fast``'s row choice, so that the object gives the same numbers, bit for bit,
    from whichever thread calls it (``None`` where ``fast`` is ``None`` or the fast path is off in this thread).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` ``fast`` was built for.
        fast: Its :class:`CompiledModel` (built in any thread), or ``None``.

    Returns:
        A :class:`CompiledModel` the calling thread owns, or ``None``.
    """
    if fast is None or fast.owner == threading.get_ident():
        return fast
    local = compiled_model(robot)
    if local is not None and fast._hint is not None:
        local.select(fast._hint)  # (the same rows as the owner's: nothing to do if they already are)
    return local


class ThreadModel:
    """A class attribute holding the compiled model an object (e.g. a trajectory problem) built for its ``robot``,
    which each thread reads as its own: assigned the model (or ``None``: the Python path) in the building thread,
    read as :func:`for_this_thread` of the object's ``robot`` and that model, so that the object gives the same
    numbers from whichever thread calls it."""

    def __set_name__(self, owner, name: str) -> None:
        self._slot = f"_{name.lstrip('_')}_model"  # (where the instance keeps the model it was given)

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        return for_this_thread(obj.robot, obj.__dict__.get(self._slot))

    def __set__(self, obj, fast: CompiledModel | None) -> None:
        obj.__dict__[self._slot] = fast


def reduce(robot, q: np.ndarray, nu: np.ndarray, coriolis: bool = False, independent=None) -> ReducedDynamics:
    """The reduced model of ``robot`` at (q, nu) (in its operational velocities if it has them): by the robot's
    compiled model where it serves, else (and to choose the projection's rows) by the Python reference
    (:func:`robotdyn.reduction.reduced_dynamics.reference`). ``coriolis`` (the matrix :math:`C_r`) is the Python
    path's; ``independent`` overrides the independent velocity indices (not with operational velocities).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
        nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.
        coriolis: Also compute the matrix C_r (k, k) and dS/dt (default: only the bias h = C_r nu + g_r).
        independent: Indices of the independent velocities in v (default ``None``: the robot's).

    Returns:
        The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu).
    """
    op = getattr(robot, "operational", None)
    fast = None if coriolis else compiled_model(robot)
    if fast is not None:
        if op is not None:
            op.check(nu)  # the Python path's InputError, before the compiled call
            out = fast.reduced(q, nu)
        else:
            out = fast.reduced(q, nu, robot.independent_indices if independent is None else independent)
        if out is not None:
            return out
    out = reference(robot, q, nu, coriolis, independent)
    if fast is not None:
        fast.select(out.projection)  # the compiled model uses the Python path's row choice from now on
    return out


__all__ = ["available", "enabled", "use_compiled", "compiled_model", "for_this_thread", "ThreadModel", "why_not",
           "reduce"]

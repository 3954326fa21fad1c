"""The registry of robots: one module or package per robot in this package, each exposing ``SPEC`` (a
:class:`~robotdyn.robot.RobotSpec`) and optionally ``SCENARIOS`` and ``compare``.

The five robots of the papers are packages that keep the model and the paper apart: ``<name>/model.py`` (the spec,
parameters, scenarios), ``<name>/paper.py`` (the paper's closed forms and printed values, transcribed) and
``<name>/comparison.py`` (``compare``, the model against the paper); their ``__init__`` re-exports all names, so
:func:`module` returns the package. :func:`names` lists packages and plain modules alike (``pkgutil.iter_modules``).
"""

from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType

from ..errors import UnknownRobotError


def names() -> list[str]:
    """Registered robot names, sorted.

    Returns:
        The names, sorted.
    """
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))


def module(name: str) -> ModuleType:
    """The module of a registered robot.

    Args:
        name: The robot's registry name (:func:`names`).

    Returns:
        The robot's module.

    Raises:
        UnknownRobotError: naming the known robots.
    """
    if name not in names():
        raise UnknownRobotError(f"unknown robot {name!r}; expected one of {', '.join(names())}")
    return importlib.import_module(f"{__name__}.{name}")

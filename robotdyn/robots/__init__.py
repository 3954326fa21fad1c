"""The registry of robots: one module per robot in this package, each exposing ``SPEC`` (a
:class:`~robotdyn.robot.RobotSpec`) and optionally ``SCENARIOS`` and ``compare``."""

from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType

from ..errors import UnknownRobotError


def names() -> list[str]:
    """Registered robot names, sorted."""
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))


def module(name: str) -> ModuleType:
    """The module of a registered robot.

    Raises:
        UnknownRobotError: naming the known robots.
    """
    if name not in names():
        raise UnknownRobotError(f"unknown robot {name!r}; expected one of {', '.join(names())}")
    return importlib.import_module(f"{__name__}.{name}")

"""Lazy re-exports for the pipeline packages: a package's ``__getattr__`` that imports a submodule on first use.

The subpackages named like former flat modules (``robotdyn.simulation``, ``robotdyn.sweep``, ``robotdyn.cli``,
``robotdyn.description``) keep their old public names importable (``robotdyn.simulation.simulate``) without
importing the submodules (and their dependencies: scipy, Dask) when the package itself is imported.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable


def lazy_exports(package: str, exports: dict[str, str]) -> Callable[[str], object]:
    """The module ``__getattr__`` of ``package`` serving ``exports`` (public name -> submodule defining it)."""

    def __getattr__(name: str):
        if name in exports:
            return getattr(importlib.import_module(f".{exports[name]}", package), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__

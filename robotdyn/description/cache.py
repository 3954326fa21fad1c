"""A cache of expanded descriptions, so that a command on a known robot starts without importing xacro.

Expanding a Xacro file costs about 0.1 s of every command (importing xacro and PyYAML, then the expansion). The
expansion is a pure function of the files it reads, the arguments, the packages it can find and the xacro
version, so its result is kept under :func:`cache_dir` and reused while all of these are unchanged:

- the key hashes the file's resolved path, the (already validated) argument values, the package index
  (:class:`~robotdyn.description.ros_packages.PackageIndex`'s ``repr``: explicit packages, search paths, prefixes) and a stamp
  of the installed xacro (its path, size and modification time);
- the entry lists every file xacro read (the file itself and each include or YAML file) with its SHA-256, and is
  used only while each of them still has that hash;
- descriptions that read environment variables (``$(env ...)``, ``$(optenv ...)``) are never cached.

Entries are written atomically, at most :data:`MAX_ENTRIES` are kept; a cache that cannot be read or written only
costs time. ``ROBOTDYN_CACHE`` moves
the cache (default ``~/.cache/robotdyn``); ``ROBOTDYN_CACHE=off`` switches it off.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from ..errors import RobotDynError

REVISION = 1
"""Revision of the entry format (raise it when the format or what a key covers changes)."""

MAX_ENTRIES = 256
"""Entries kept (the least recently written are removed beyond it: a parameter sweep expands a new variant per
run and must not fill the disk)."""


def cache_dir() -> Path | None:
    """robotdyn's cache directory: ``$ROBOTDYN_CACHE`` or ``~/.cache/robotdyn`` (None when ``off``).

    Returns:
        The cache directory (not necessarily existing), or ``None`` when caching is off.
    """
    root = os.environ.get("ROBOTDYN_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "robotdyn")
    return None if root == "off" else Path(root)


def package_stamp(name: str) -> str:
    """A cheap stamp of an installed Python package (path, size and mtime of its ``__init__``), without importing
    it or ``importlib.metadata`` (which alone costs ~50 ms).

    Args:
        name: The package's import name.

    Returns:
        The stamp string (``<name>-missing`` if the package is not installed).
    """
    from importlib.util import find_spec

    spec = find_spec(name)
    if spec is None or not spec.origin:
        return f"{name}-missing"
    st = os.stat(spec.origin)
    return f"{name}-{spec.origin}-{st.st_size}-{st.st_mtime_ns}"


def _digest(path: str | Path) -> str | None:
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def _entry(path: Path, mappings: dict[str, str], index) -> Path | None:
    root = cache_dir()
    if root is None:
        return None
    key = json.dumps([REVISION, str(path.resolve()), sorted(mappings.items()), repr(index), package_stamp("xacro")])
    return root / "xacro" / f"{hashlib.sha256(key.encode()).hexdigest()}.json"


def lookup(path: Path, mappings: dict[str, str], index) -> str | None:
    """The cached URDF text of an expansion, or None (no entry, or a file it read has changed). Restores the
    packages the expansion used into ``index.used``.

    Args:
        path: The description file expanded.
        mappings: The xacro arguments (name -> value text) of the expansion.
        index: The :class:`~robotdyn.description.ros_packages.PackageIndex` that answered ``$(find)``.

    Returns:
        The cached URDF text, or ``None``.
    """
    entry = _entry(path, mappings, index)
    if entry is None:
        return None
    try:
        data = json.loads(entry.read_text())
    except (OSError, ValueError):
        return None
    files = data.get("files")
    if not isinstance(files, dict) or not files or any(_digest(f) != h for f, h in files.items()):
        return None
    index.used.update({name: Path(d) for name, d in data.get("used", {}).items()})
    return data.get("urdf")


def store(path: Path, mappings: dict[str, str], index, files: list[str], urdf: str) -> None:
    """Remember an expansion (``files``: every file xacro read, the description first).

    Args:
        path: The description file expanded.
        mappings: The xacro arguments (name -> value text) of the expansion.
        index: The :class:`~robotdyn.description.ros_packages.PackageIndex` that answered ``$(find)``.
        files: Every file xacro read, the description first.
        urdf: The expanded URDF text.
    """
    entry = _entry(path, mappings, index)
    if entry is None:
        return
    digests = {}
    for f in dict.fromkeys([str(path), *files]):
        try:
            text = Path(f).read_bytes()
        except OSError:
            return
        if b"$(env " in text or b"$(optenv " in text:  # depends on the environment: never cached
            return
        digests[str(Path(f).resolve())] = hashlib.sha256(text).hexdigest()
    data = {"files": digests, "used": {k: str(v) for k, v in index.used.items()}, "urdf": urdf}
    try:
        from ..output import atomic_output

        entry.parent.mkdir(parents=True, exist_ok=True)
        with atomic_output(entry, "cache") as tmp:
            tmp.write_text(json.dumps(data))
        _prune(entry.parent)
    except (OSError, RobotDynError):
        pass


def _prune(folder: Path) -> None:
    """Remove the least recently written entries beyond :data:`MAX_ENTRIES` (another process may remove them
    first: a missing file is not an error)."""
    entries = list(folder.glob("*.json"))
    if len(entries) <= MAX_ENTRIES:
        return
    by_age = []
    for e in entries:
        try:
            by_age.append((e.stat().st_mtime_ns, e))
        except OSError:
            pass
    for _, e in sorted(by_age)[: len(by_age) - MAX_ENTRIES]:
        try:
            e.unlink()
        except OSError:
            pass


__all__ = ["cache_dir", "package_stamp", "lookup", "store"]

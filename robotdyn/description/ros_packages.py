"""ROS packages without ROS: where ``$(find PKG)`` and ``package://PKG/...`` point.

A description straight from a ROS repository names other files by package: Xacro includes
``$(find husky_description)/urdf/wheel.urdf.xacro`` and meshes ``package://husky_description/meshes/wheel.dae``.
ROS answers from its package index (ROS 1: ``rospkg`` crawling ``ROS_PACKAGE_PATH``; ROS 2: the ament index
under each prefix of ``AMENT_PREFIX_PATH``). :class:`PackageIndex` answers the same question from the same
sources, without ROS installed, in this order:

1. explicit packages, ``NAME -> DIR`` (``--package NAME=DIR``, the ``[packages]`` table of a constraint file);
2. search directories (``package_dirs`` of a constraint file, ``--package DIR``), then ``ROS_PACKAGE_PATH``: each
   is crawled like ``rospkg`` does (a directory holding a ``package.xml`` is a package named by its ``<name>``;
   crawling stops there and skips hidden directories and those marked ``CATKIN_IGNORE``/``COLCON_IGNORE``/
   ``AMENT_IGNORE``), and a direct subdirectory named ``NAME`` counts too (Pinocchio's convention);
3. ``AMENT_PREFIX_PATH``: ``<prefix>/share/NAME``;
4. pip-installed robot data (the ``cmeel.prefix/share`` directory of e.g. example-robot-data).

:func:`xacro_find` substitutes this lookup for xacro's own ``$(find)`` (xacro 2 resolves it through
``xacro.substitution_args._eval_find``, which imports ``ament_index_python``) while a file is expanded, recording
every package it could not find instead of stopping at the first.
"""

from __future__ import annotations

import os
import re
import stat
import sysconfig
import threading
import xml.etree.ElementTree as ET
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import DescriptionError
from ..input_files import resolved

MISSING_ROOT = "/nonexistent-ros-package"
"""What ``$(find NAME)`` of a package that was not found expands to (``MISSING_ROOT/NAME``), so that expansion can
go on (paths in Gazebo tags, say, are never read) and a later use of the path names the package."""
MAX_DEPTH = 6
"""How many directory levels below a search directory are crawled for ``package.xml`` files."""
_SKIP = {"build", "install", "log", "devel", "node_modules", "__pycache__", "site-packages"}
_IGNORE_MARKERS = ("CATKIN_IGNORE", "COLCON_IGNORE", "AMENT_IGNORE")
XACRO_LOCK = threading.RLock()
"""xacro keeps its state in module globals: one expansion at a time (every robotdyn expansion holds this)."""

HINT = "give them with --package NAME=DIR, [packages] in the constraint file, or ROS_PACKAGE_PATH"
"""How to supply packages that were not found (the end of every such message)."""


class MissingPackagesError(DescriptionError):
    """Packages a description needs that were not found (all of them, in one line).

    Attributes:
        names: The package names, sorted.
    """

    def __init__(self, names, context: str = "") -> None:
        self.names = sorted(set(names))
        super().__init__(f"{context}packages not found: {', '.join(self.names)}; {HINT}")


MAX_MANIFEST_BYTES = 1_000_000
"""Largest ``package.xml`` read (a manifest is a few kB; a larger file, a FIFO or a device is not a manifest)."""
MAX_CRAWL_DIRECTORIES = 20_000
"""Most directories crawled below one search directory (a ROS workspace has a few hundred): beyond it the search
directory is refused in one line rather than crawled for minutes."""


def package_name(directory: Path) -> str | None:
    """The ``<name>`` in ``directory/package.xml``, or None (no file, not a regular file of at most
    :data:`MAX_MANIFEST_BYTES`, or not a package manifest). A FIFO or a device named ``package.xml`` is never
    opened (reading it would block or never end).

    Args:
        directory: A directory that may hold a ``package.xml``.

    Returns:
        The package name, or ``None``.
    """
    manifest = directory / "package.xml"
    try:
        st = os.stat(manifest)
    except OSError:
        return None
    if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_MANIFEST_BYTES:
        return None
    try:
        root = ET.parse(manifest).getroot()
    except (OSError, ET.ParseError):
        return None
    name = root.findtext("name")
    return name.strip() if name and root.tag == "package" else None


def crawl(root: Path, depth: int = MAX_DEPTH) -> dict[str, Path]:
    """All packages under ``root`` (name -> directory), the first found winning, as ``rospkg`` crawls.

    The walk is bounded and loop-safe: each directory is visited once (by device and inode, so symbolic links
    back up the tree or to itself are not followed again), at most ``depth`` levels down and at most
    :data:`MAX_CRAWL_DIRECTORIES` directories in all.

    Args:
        root: The directory crawled.
        depth: Largest depth of subdirectories searched.

    Returns:
        Package directory by name.

    Raises:
        DescriptionError: More than :data:`MAX_CRAWL_DIRECTORIES` directories below ``root``.
    """
    found: dict[str, Path] = {}
    seen: set[tuple[int, int]] = set()

    def walk(d: Path, level: int) -> None:
        try:
            st = os.stat(d)
        except OSError:
            return
        key = (st.st_dev, st.st_ino)
        if key in seen or not stat.S_ISDIR(st.st_mode):
            return
        seen.add(key)
        if len(seen) > MAX_CRAWL_DIRECTORIES:
            raise DescriptionError(f"ROS package search directory {str(root)!r}: more than "
                                   f"{MAX_CRAWL_DIRECTORIES:,} directories below it; expected a workspace or a "
                                   "directory of packages (or give the package itself: --package NAME=DIR)")
        name = package_name(d)
        if name is not None:
            found.setdefault(name, d)
            return
        if level >= depth or any(os.path.lexists(d / m) for m in _IGNORE_MARKERS):
            return
        try:
            with os.scandir(d) as entries:
                subdirs = sorted(Path(e.path) for e in entries if not e.name.startswith(".") and e.name not in _SKIP
                                 and _is_dir(e))
        except OSError:
            return
        for sub in subdirs:
            walk(sub, level + 1)

    if root.is_dir():
        walk(root, 0)
    return found


def _is_dir(entry: os.DirEntry) -> bool:
    try:
        return entry.is_dir()
    except OSError:  # a link loop, a vanished entry
        return False


def _env_paths(variable: str) -> list[Path]:
    return [Path(p) for p in os.environ.get(variable, "").split(os.pathsep) if p]


@dataclass
class PackageIndex:
    """Where ROS packages are, looked up by name (see the module docstring for the order).

    Attributes:
        explicit: Packages given by name (name -> directory).
        search: Directories crawled for packages (before ``ROS_PACKAGE_PATH``).
        prefixes: Install prefixes (``<prefix>/share/NAME``; default ``AMENT_PREFIX_PATH``).
        used: Every package found so far (name -> directory): the trees a description may read files from.
    """

    explicit: dict[str, Path] = field(default_factory=dict)
    search: list[Path] = field(default_factory=list)
    prefixes: list[Path] = field(default_factory=list)
    used: dict[str, Path] = field(default_factory=dict)
    _crawled: dict[Path, dict[str, Path]] = field(default_factory=dict, repr=False)

    @classmethod
    def create(cls, packages: dict | None = None, dirs=(), environment: bool = True) -> PackageIndex:
        """An index of explicit ``packages`` (name -> directory), search directories ``dirs``, and (with
        ``environment``) ``ROS_PACKAGE_PATH``, ``AMENT_PREFIX_PATH`` and pip-installed robot data.

        Args:
            packages: Explicit packages, name -> directory (default ``None``: none).
            dirs: Directories searched for packages (crawled for ``package.xml``).
            environment: Also search ``ROS_PACKAGE_PATH``, ``AMENT_PREFIX_PATH`` and pip-installed robot data.

        Returns:
            The new :class:`PackageIndex`.

        Raises:
            DescriptionError: An explicit package directory that does not exist.
        """
        explicit = {}
        for name, d in (packages or {}).items():
            path = resolved(d, f"package {name}")
            if not path.is_dir():
                raise DescriptionError(f"package {name} = {d}: no such directory; expected the package's directory "
                                       "(the one holding its package.xml)")
            explicit[str(name)] = path
        search = [resolved(d, "package search directory") for d in dirs]
        prefixes = []
        if environment:
            search += _env_paths("ROS_PACKAGE_PATH")
            prefixes = _env_paths("AMENT_PREFIX_PATH")
            share = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix"
            if share.is_dir():
                prefixes.append(share)
        return cls(explicit, search, prefixes)

    def __repr__(self) -> str:
        return (f"PackageIndex(explicit={sorted(self.explicit)}, search={[str(d) for d in self.search]}, "
                f"prefixes={[str(d) for d in self.prefixes]})")

    def find(self, name: str) -> Path | None:
        """The directory of package ``name`` (resolved), or None.

        Args:
            name: The package's name.

        Returns:
            The package's resolved directory, or ``None`` if it is not found.
        """
        path = self._lookup(name)
        if path is not None:
            self.used[name] = path
        return path

    def _lookup(self, name: str) -> Path | None:
        if not name or "/" in name or name in (".", ".."):
            return None
        if name in self.explicit:
            return self.explicit[name]
        for root in self.search:
            if root not in self._crawled:
                self._crawled[root] = crawl(root)
            if name in self._crawled[root]:
                return self._crawled[root][name].resolve()
            if root.name == name and root.is_dir():
                return root
            if (root / name).is_dir():
                return (root / name).resolve()
        for prefix in self.prefixes:
            if (prefix / "share" / name).is_dir():
                return (prefix / "share" / name).resolve()
        return None

    def resolve_uri(self, uri: str) -> tuple[Path | None, str | None]:
        """The file a ``package://NAME/rest`` URI names, and the missing package's name if NAME was not found.

        Args:
            uri: A ``package://NAME/rest`` URI.

        Returns:
            ``(path, missing)``: the resolved file path and ``None``, or ``None`` and the name of the package that was
            not found.
        """
        rest = uri[len("package://"):]
        name, _, tail = rest.partition("/")
        root = self.find(name)
        if root is None:
            return None, name
        return (root / tail).resolve(), None

    def roots(self) -> list[Path]:
        """The directories a description may read files from: every package found and the explicit ones.

        Returns:
            The directories, sorted and without duplicates.
        """
        return sorted({*self.used.values(), *self.explicit.values()})


def missing_name(path: str) -> str | None:
    """The package name if ``path`` came from ``$(find NAME)`` of a package that was not found.

    Args:
        path: A path produced by ``$(find NAME)``.

    Returns:
        The package name, or ``None``.
    """
    match = re.match(re.escape(MISSING_ROOT) + r"/([^/]+)", str(path))
    return match.group(1) if match else None


@contextmanager
def xacro_find(index: PackageIndex):
    """While active, xacro's ``$(find NAME)`` is answered by ``index``.

    xacro 2 resolves ``$(find NAME)`` in ``xacro.substitution_args._eval_find`` (called for every ``$(find)`` in
    attributes and text, and bound as ``find`` for ``$(eval ...)``). Both are replaced for the duration (under
    :data:`XACRO_LOCK`) by the index's lookup; a package not found expands to ``MISSING_ROOT/NAME`` and its name is
    appended to the yielded list.

    Args:
        index: The :class:`PackageIndex` that answers ``$(find NAME)``.

    Yields:
        The list that collects the names of packages xacro asked for and did not find (filled while active).
    """
    import xacro.substitution_args as sa

    missing: list[str] = []

    def find(name: str) -> str:
        path = index.find(name)
        if path is None:
            if name not in missing:
                missing.append(name)
            return f"{MISSING_ROOT}/{name}"
        return str(path)

    with XACRO_LOCK:
        saved = sa._eval_find, sa._eval_dict.get("find")
        sa._eval_find = find
        sa._eval_dict["find"] = find
        try:
            yield missing
        finally:
            sa._eval_find = saved[0]
            sa._eval_dict["find"] = saved[1]


_FIND = re.compile(r"\$\(find\s+([^)\s]+)\s*\)")
_ARG = re.compile(r"\$\(arg\s+[^)]*\)")
_XACRO_NS = "http://www.ros.org/wiki/xacro"
_CONDITIONALS = ("if", "unless")


def required_packages(path: Path, index: PackageIndex, limit: int = 200) -> set[str]:
    """Packages whose files ``path`` includes unconditionally (``<xacro:include filename="$(find NAME)/..."/>``
    outside ``xacro:if``/``xacro:unless``), following the includes that resolve, found or not.

    A static scan: expansion stops at the first include it cannot read, and this finds the packages that later
    includes would need, so that all of them can be named at once.

    Args:
        path: The Xacro file scanned.
        index: The :class:`PackageIndex` resolving the includes that can be followed.
        limit: Largest number of files scanned.

    Returns:
        The names of those packages that ``index`` cannot find (empty: all are found).
    """
    seen: set[Path] = set()
    names: set[str] = set()
    todo = [Path(path).resolve()]
    while todo and len(seen) < limit:
        current = todo.pop()
        if current in seen or not current.is_file():
            continue
        seen.add(current)
        try:
            root = ET.parse(current).getroot()
        except (OSError, ET.ParseError):
            continue
        for spec in _unconditional_includes(root):
            names.update(_FIND.findall(spec))
            if _ARG.search(spec) or "${" in spec:
                continue
            text = _FIND.sub(lambda m: str(index.find(m.group(1)) or f"{MISSING_ROOT}/{m.group(1)}"), spec)
            target = Path(text) if os.path.isabs(text) else current.parent / text
            todo.append(target)
    return {n for n in names if index.find(n) is None}


def _unconditional_includes(element: ET.Element):
    """The ``filename`` of every include below ``element`` that no ``xacro:if``/``xacro:unless`` guards."""
    for child in element:
        tag = child.tag.split("}")[-1] if isinstance(child.tag, str) else ""
        namespaced = isinstance(child.tag, str) and (child.tag.startswith("{") or child.tag.startswith("xacro:"))
        if namespaced and tag in _CONDITIONALS:
            continue
        if namespaced and tag == "include" and child.get("filename"):
            yield child.get("filename")
        yield from _unconditional_includes(child)


__all__ = ["PackageIndex", "MissingPackagesError", "xacro_find", "required_packages", "crawl", "package_name",
           "missing_name", "MISSING_ROOT", "XACRO_LOCK", "HINT"]

"""Output files written atomically, with one-line errors.

Every file robotdyn writes (CSV, images, HTML pages) goes through :func:`atomic_output`: the content is written to
a temporary file in the target's directory and renamed over the target only once it is complete (``os.replace``,
atomic on POSIX), so a failing or interrupted run never truncates or half-writes an existing file. A target that
cannot be written (missing directory, a directory, no permission, a full disk) is a
:class:`~robotdyn.errors.OutputError` naming the file and what was expected. Files are created with the user's umask
(mode 0666 less the umask), as any program's ``open()`` creates them. A streamed simulation writes its rows, as they
are computed, to the visible ``<target>.partial`` instead (:func:`visible_output`), renamed over the target at the
end.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
from collections.abc import Iterator
from pathlib import Path

from .errors import OutputError

IMAGE_FORMATS = ("png", "pdf", "svg", "jpg", "jpeg", "eps", "ps", "tif", "tiff", "webp")
"""Image formats accepted by the plotting commands (matplotlib's, by file extension)."""


def check_target(path, what: str = "output file", suffixes: tuple[str, ...] | None = None) -> Path:
    """Validate an output path before any work is done: its directory exists and is writable, it is not a
    directory, and (with ``suffixes``) its extension is one of them.

    Args:
        path: The output file.
        what: What it is, for messages.
        suffixes: Allowed extensions (e.g. ``(".png", ".pdf")``; default ``None``: any).

    Returns:
        The validated path (a :class:`~pathlib.Path`).

    Raises:
        OutputError: The path is a directory, its directory is missing or not writable, or its extension is not
            allowed.
    """
    p = Path(path)
    if p.is_dir():
        raise OutputError(f"{what} {str(path)!r} is a directory; expected a file name")
    if p.exists() and not p.is_file():  # a device or pipe would be replaced by the atomic rename (e.g. /dev/null)
        raise OutputError(f"{what} {str(path)!r} is not a regular file (a device or pipe); expected a file name")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"{what} {str(path)!r}: directory {str(parent)!r} does not exist; expected an existing "
                          "directory")
    if not os.access(parent, os.W_OK):
        raise OutputError(f"{what} {str(path)!r}: directory {str(parent)!r} is not writable")
    if suffixes is not None and p.suffix.lower().lstrip(".") not in suffixes:
        raise OutputError(f"{what} {str(path)!r}: unknown format {p.suffix or '(no extension)'!r}; expected one of "
                          f"{', '.join('.' + s for s in suffixes)}")
    return p


def _create(path: Path, exclusive: bool) -> int:
    """Open ``path`` for writing, created with mode 0666 less the user's umask (as ``open()`` creates files; not
    tempfile's 0600): a file robotdyn writes gets the permissions any other program of the user's would give it."""
    flags = os.O_WRONLY | os.O_CREAT | (os.O_EXCL if exclusive else os.O_TRUNC) | getattr(os, "O_CLOEXEC", 0)
    return os.open(path, flags, 0o666)


def _temporary(target: Path) -> Path:
    """A new empty hidden file next to ``target`` (``.<name>.<random>.tmp<suffix>``), mode 0666 less the umask."""
    for _ in range(100):
        tmp = target.parent / f".{target.name}.{secrets.token_hex(4)}.tmp{target.suffix}"
        try:
            os.close(_create(tmp, exclusive=True))
            return tmp
        except FileExistsError:
            continue
    raise FileExistsError(errno.EEXIST, f"no free temporary name next to {target}")


@contextlib.contextmanager
def atomic_output(path, what: str = "output file") -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success it replaces ``path`` atomically, on any error it is
    removed and ``path`` is left as it was. OS errors become one-line :class:`OutputError`. The file is created
    with the user's umask (mode 0666 less the umask), whatever the mode of a file it replaces.

    Args:
        path: The output file.
        what: What it is, for messages.

    Yields:
        The temporary :class:`~pathlib.Path` to write to.
    """
    target = check_target(path, what)
    try:
        tmp = _temporary(target)
    except OSError as exc:
        raise OutputError(f"cannot write {what} {str(path)!r}: {exc.strerror or exc}") from None
    try:
        yield tmp
        os.replace(tmp, target)
    except OSError as exc:
        raise OutputError(f"cannot write {what} {str(path)!r}: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


PARTIAL_SUFFIX = ".partial"
"""What :func:`visible_output` appends to the target's name for the file being written."""


def try_lock(path) -> tuple[int, bool]:
    """Open ``path`` for reading and writing (created with mode 0666 less the umask, not truncated: another process
    may hold it) and try to take an exclusive ``flock`` on it without waiting.

    Args:
        path: The file to lock (``str`` or :class:`~pathlib.Path`); its directory must exist.

    Returns:
        ``(fd, held)``: the open file descriptor (the caller closes it; closing releases the lock) and whether this
        process holds the lock. ``held`` is False where another process holds it (fd still open, e.g. to read
        who); True also on a platform without ``flock`` (no lock is taken there).

    Raises:
        OSError: The file cannot be opened.
    """
    fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o666)
    try:
        import fcntl
    except ImportError:  # no flock (Windows): no lock
        return fd, True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return fd, False
    return fd, True


@contextlib.contextmanager
def visible_output(path, what: str = "output file") -> Iterator[tuple[Path, object]]:
    """Yield ``(partial path, binary file open for writing and reading)`` for an output written while it is computed
    (a streamed simulation): the rows go to ``<path>.partial``, visible next to the target from the first row on, and
    replace ``path`` atomically when the block ends normally (a finished file, or one the writer marked as
    partial); on an error the ``.partial`` file is removed and ``path`` is left as it was. A process killed hard
    (SIGKILL, power loss) leaves the ``.partial`` file with the rows written so far, and ``path`` untouched.

    The ``.partial`` file is locked (``flock``) while written: a second run writing the same target is refused in
    one line; a ``.partial`` left by a killed run is not locked and is overwritten.

    Args:
        path: The target file (``str`` or :class:`~pathlib.Path`); its directory must exist and be writable.
        what: What it is, for messages (default ``"output file"``).

    Yields:
        ``(partial, f)``: the path of ``<path>.partial`` and its binary file object, empty, open for reading and
        writing.

    Raises:
        OutputError: The target or its ``.partial`` file cannot be written, or another process is writing them.
    """
    target = check_target(path, what)
    partial = check_target(target.with_name(target.name + PARTIAL_SUFFIX), what)
    try:  # not truncated before it is locked: another run may be writing it
        fd, held = try_lock(partial)
    except OSError as exc:
        raise OutputError(f"cannot write {what} {str(partial)!r}: {exc.strerror or exc}") from None
    if not held:
        os.close(fd)
        raise OutputError(f"{what} {str(path)!r}: another process is writing it ({str(partial)!r} is locked); expected "
                          "one run per output file")
    ok = False
    try:
        os.ftruncate(fd, 0)  # a leftover of a killed run
        with open(os.dup(fd), "r+b") as f:  # the lock belongs to fd, closed after the rename
            yield partial, f
            f.flush()
        os.replace(partial, target)
        ok = True
    except OSError as exc:
        raise OutputError(f"cannot write {what} {str(path)!r}: {exc.strerror or exc}") from None
    finally:
        if not ok:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(partial)
        os.close(fd)  # releases the lock, after the rename


def save_figure(fig, path, dpi: int = 110) -> None:
    """Save a matplotlib figure atomically, in the format its extension names.

    Args:
        fig: The matplotlib figure.
        path: The image file (PNG, PDF, SVG, ... by its extension).
        dpi: Resolution of raster formats [dots per inch].
    """
    target = check_target(path, "plot", IMAGE_FORMATS)
    with atomic_output(target, "plot") as tmp:
        fig.savefig(tmp, dpi=dpi, format=target.suffix.lower().lstrip("."))

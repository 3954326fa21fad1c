"""Output files written atomically, with one-line errors.

Every file robotdyn writes (CSV, images, HTML pages) goes through :func:`atomic_output`: the content is written to
a temporary file in the target's directory and renamed over the target only once it is complete (``os.replace``,
atomic on POSIX), so a failing or interrupted run never truncates or half-writes an existing file. A target that
cannot be written (missing directory, a directory, no permission, a full disk) is a
:class:`~robotdyn.errors.OutputError` naming the file and what was expected.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
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


@contextlib.contextmanager
def atomic_output(path, what: str = "output file") -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success it replaces ``path`` atomically, on any error it is
    removed and ``path`` is left as it was. OS errors become one-line :class:`OutputError`.

    Args:
        path: The output file.
        what: What it is, for messages.
    """
    target = check_target(path, what)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".tmp{target.suffix}", dir=target.parent or ".")
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, target)
    except OSError as exc:
        raise OutputError(f"cannot write {what} {str(path)!r}: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


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

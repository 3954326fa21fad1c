"""Input files and directories given by a user, read safely: one clear line for each mistake, never a hang.

A path may name a FIFO (reading it blocks until someone writes), a device (``/dev/zero`` never ends), a file far
larger than any input, or a chain of symbolic links that loops. These helpers refuse each of them in one line
naming the path, before anything opens it:

- :func:`resolved`: a path resolved through its symbolic links (a loop is an :class:`~robotdyn.errors.InputError`);
- :func:`regular_file`: the ``os.stat`` of a path that must be a regular file of at most a given size;
- :func:`read_text`: the text of such a file, reading at most that size (a file that grows while it is read, or a
  ``/proc`` file that reports size 0, cannot make it read more).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from .errors import InputError


def resolved(path, what: str) -> Path:
    """``path`` (``~`` expanded) made absolute through its symbolic links.

    Args:
        path: A file or directory path (str or Path).
        what: What the path is, for the message (e.g. ``"--package"``, ``"package_dirs"``).

    Returns:
        The absolute, resolved path.

    Raises:
        InputError: The path's symbolic links form a loop (or another link error of the file system).
    """
    try:
        return Path(os.path.expanduser(str(path))).resolve()
    except (RuntimeError, OSError) as exc:  # Python 3.11: RuntimeError("Symlink loop from ..."); 3.13: OSError
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else "a loop of symbolic links"
        raise InputError(f"{what} = {str(path)!r}: {reason}; expected a file or directory that exists") from None


def regular_file(path, what: str, max_bytes: int) -> os.stat_result:
    """The status of ``path``, which must be a regular file (after symbolic links) of at most ``max_bytes`` bytes.

    Args:
        path: The file.
        what: What the file is, for the message (e.g. ``"sweep file"``).
        max_bytes: Largest size accepted [bytes].

    Returns:
        The ``os.stat_result`` of the file.

    Raises:
        InputError: Missing, unreadable, a directory, a FIFO, a device or a socket, or larger than ``max_bytes``.
    """
    try:
        st = os.stat(path)
    except OSError as exc:
        raise InputError(f"cannot read {what} {str(path)!r}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError(f"{what} {str(path)!r} is a directory; expected a file")
    if not stat.S_ISREG(st.st_mode):
        kind = ("a named pipe (FIFO)" if stat.S_ISFIFO(st.st_mode) else
                "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else
                "a socket" if stat.S_ISSOCK(st.st_mode) else "not a regular file")
        raise InputError(f"{what} {str(path)!r} is {kind}; expected a regular file")
    if st.st_size > max_bytes:
        raise InputError(f"{what} {str(path)!r}: {st.st_size:,} bytes; expected at most {max_bytes:,} bytes")
    return st


def read_text(path, what: str, max_bytes: int) -> str:
    """The UTF-8 text of a regular file of at most ``max_bytes`` bytes (see :func:`regular_file`).

    Args:
        path: The file.
        what: What the file is, for the message (e.g. ``"sweep file"``).
        max_bytes: Largest size read [bytes].

    Returns:
        The file's text.

    Raises:
        InputError: As :func:`regular_file`; also a file that grew beyond ``max_bytes`` while it was read, or that
            is not UTF-8 text.
    """
    regular_file(path, what, max_bytes)
    try:
        with open(path, "rb") as f:
            data = f.read(max_bytes + 1)
    except OSError as exc:
        raise InputError(f"cannot read {what} {str(path)!r}: {exc.strerror or exc}") from None
    if len(data) > max_bytes:
        raise InputError(f"{what} {str(path)!r}: more than {max_bytes:,} bytes; expected at most {max_bytes:,} bytes")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{what} {str(path)!r} is not UTF-8 text") from None


__all__ = ["resolved", "regular_file", "read_text"]

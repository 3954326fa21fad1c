"""The CLI's SIGTERM handler is the command's own: :func:`~robotdyn.cli.commands.main` restores the one it found.

``simulate`` and ``sweep`` install a SIGTERM handler that stops the run like Ctrl-C (a ``KeyboardInterrupt``), so
that the results computed so far are kept. In the ``robotdyn`` process, which exits after the command, that is the
whole story; but ``main`` is also called in-process (tests, notebooks, a user's script), and the handler left
installed then outlived the command: a process forked later (e.g. a ``multiprocessing`` pool's worker, which the
pool ends with SIGTERM) inherited it and raised ``KeyboardInterrupt`` where it should have ended, once while holding
the pool's queue lock, and its sibling waited on that lock forever (a CI hang in ``tests/test_batch.py``).
"""

from __future__ import annotations

import signal
import threading


def current():
    """The SIGTERM handler now installed (``None`` outside the main thread, where signals cannot be set).

    Returns:
        What :func:`signal.getsignal` gives (a callable, ``SIG_DFL``, ``SIG_IGN``, or ``None`` for a handler not
        installed from Python), wrapped in a one-element tuple; ``None`` outside the main thread.
    """
    if threading.current_thread() is not threading.main_thread():
        return None
    return (signal.getsignal(signal.SIGTERM),)


def restore(saved) -> None:
    """Reinstall the SIGTERM handler :func:`current` saved (nothing where it saved none, or where the handler was
    not installed from Python, which Python cannot reinstall).

    Args:
        saved: What :func:`current` returned.
    """
    if saved is None or saved[0] is None or threading.current_thread() is not threading.main_thread():
        return
    if signal.getsignal(signal.SIGTERM) is not saved[0]:
        signal.signal(signal.SIGTERM, saved[0])


__all__ = ["current", "restore"]

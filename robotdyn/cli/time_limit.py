"""The wall-clock limit of ``robotdyn simulate --time-limit SECONDS``.

Past the limit the run stops as it does on Ctrl-C or SIGTERM (a ``KeyboardInterrupt`` raised by a ``SIGALRM``
handler, which every engine turns into a partial result: the scipy and stick-slip loops between evaluations, the
compiled engine at its ~50 ms signal check, a streamed run anywhere), so the samples computed so far are kept and
written as a marked partial file. The limit covers the integration and the wheel-load columns, not the loading of
the robot before nor the writing of the files after.
"""

from __future__ import annotations

import math
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

from ..errors import InputError

EXIT_STATUS = 124
"""Exit status of a run stopped by its time limit (as GNU ``timeout``); Ctrl-C/SIGTERM give 130."""


class Limit:
    """The limit of one run: :meth:`start` arms it, :attr:`reached` says whether it stopped the run.

    Args:
        seconds: The wall-clock limit [s], or None for no limit (then :meth:`start` arms nothing).
    """

    def __init__(self, seconds: float | None) -> None:
        self.seconds, self.reached, self.armed = seconds, False, False

    def start(self) -> None:
        """Start counting (the run begins): ``KeyboardInterrupt`` in the main thread after :attr:`seconds`."""
        if self.seconds is not None:
            signal.setitimer(signal.ITIMER_REAL, self.seconds)
            self.armed = True

    def stop(self) -> None:
        """Disarm (the run is over; the files are written without a limit)."""
        if self.armed:
            signal.setitimer(signal.ITIMER_REAL, 0)
            self.armed = False

    def reason(self, partial: str | None) -> str | None:
        """A partial run's note, saying that the time limit stopped it (the note itself if it did not).

        Args:
            partial: The partial run's note (its first "interrupted" is replaced by the time limit when the limit
                was reached), or None for a complete run.

        Returns:
            The note, rewritten if the limit stopped the run; None (or the empty note) unchanged.
        """
        if not (self.reached and partial):
            return partial
        return partial.replace("interrupted", f"time limit of {self.seconds:g} s reached", 1)

    @property
    def status(self) -> int:
        """Exit status of a partial run: :data:`EXIT_STATUS` if the limit stopped it, else 130 (interrupted)."""
        return EXIT_STATUS if self.reached else 130


@contextmanager
def wall_clock_limit(seconds: float | None) -> Iterator[Limit]:
    """A :class:`Limit` whose timer (a ``SIGALRM`` raising ``KeyboardInterrupt``) is disarmed, and the previous
    handler restored, when the block ends (``seconds`` None: no limit).

    Args:
        seconds: The wall-clock limit [s], a positive finite number, or None for no limit.

    Yields:
        The run's :class:`Limit` (not yet started: the caller calls :meth:`Limit.start` when the run begins).

    Raises:
        InputError: A limit asked for outside the main thread (signals reach the main thread only), or not a
            positive finite number of seconds.
    """
    limit = Limit(seconds)
    if seconds is None:
        yield limit
        return
    if not (math.isfinite(seconds) and seconds > 0):
        raise InputError(f"--time-limit {seconds:g}; expected a positive number of seconds")
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        raise InputError("--time-limit needs the main thread of a POSIX process (a SIGALRM timer); expected the "
                         "robotdyn command itself")

    def expire(signum, frame):
        if limit.armed:
            limit.reached, limit.armed = True, False
            raise KeyboardInterrupt

    old = signal.signal(signal.SIGALRM, expire)
    try:
        yield limit
    finally:
        limit.stop()
        signal.signal(signal.SIGALRM, old)

"""The reporter of a running simulation, shared by the engines: progress on stderr and the wall-clock limit."""

from __future__ import annotations

import sys
import time

from ..errors import TimeLimitError


class Progress:
    """Prints the simulated time to stderr at most once a second, once the run has taken more than a second, and
    raises :class:`~robotdyn.errors.TimeLimitError` once the run has taken longer than its wall-clock limit.

    Args:
        t_end: Duration of the run [s] (for the percentage printed).
        enabled: Whether to print.
        time_limit: Wall-clock limit of the run [s] (None: none).
    """

    def __init__(self, t_end: float, enabled: bool, time_limit: float | None = None) -> None:
        self.t_end, self.enabled, self.time_limit = t_end, enabled, time_limit
        self.start = self.last = time.perf_counter()

    @property
    def needed(self) -> bool:
        """Whether calling it can do anything (print or stop)."""
        return self.enabled or self.time_limit is not None

    def __call__(self, t: float) -> None:
        if not self.needed:
            return
        now = time.perf_counter()
        if self.time_limit is not None and now - self.start > self.time_limit:
            raise TimeLimitError(f"the run exceeded its time limit of {self.time_limit:g} s at t = {t:.3g} s of "
                                 f"{self.t_end:g} s (a stiff or blown-up run; a longer time limit allows more)")
        if self.enabled and now - self.last >= 1.0:
            self.last = now
            print(f"simulate: t = {t:.2f} / {self.t_end:g} s ({100 * t / self.t_end:.0f}%)", file=sys.stderr, flush=True)

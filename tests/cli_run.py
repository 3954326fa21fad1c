"""Running the CLI (or any call) in-process under a wall-clock alarm, for the tests of inputs that once hung."""

from __future__ import annotations

import contextlib
import signal
import time

import pytest

from robotdyn.cli.commands import main


class _Hang(BaseException):
    pass


def _alarm(signum, frame):
    raise _Hang


@contextlib.contextmanager
def deadline(seconds: int, what: str):
    """Fail the test (``what`` ... "still running after N s") if the block runs longer than ``seconds``."""
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(seconds)
    try:
        yield
    except _Hang:
        pytest.fail(f"{what}: still running after {seconds} s")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def run_cli(argv, capsys, seconds: int) -> tuple[int, str, float]:
    """``main(argv)`` under :func:`deadline`: (exit status, stderr, wall time [s])."""
    start = time.perf_counter()
    with deadline(seconds, str(argv)):
        rc = main([str(a) for a in argv])
    return rc, capsys.readouterr().err, time.perf_counter() - start

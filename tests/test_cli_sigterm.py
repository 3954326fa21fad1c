"""``robotdyn.cli.main`` called in-process leaves the SIGTERM handler it found (robotdyn.cli.sigterm): ``simulate``
and ``sweep`` install their own (SIGTERM stops a run like Ctrl-C, results kept) and left it installed after they
returned, so a process forked later inherited it (the pool hang fixed in 50233e6)."""

from __future__ import annotations

import signal

import pytest

from robotdyn.cli import main


def _mine(signum, frame):  # a caller's own handler, which main() must give back
    raise AssertionError("not to be called")


@pytest.fixture
def own_handler():
    before = signal.signal(signal.SIGTERM, _mine)
    yield
    signal.signal(signal.SIGTERM, before)


@pytest.mark.parametrize("argv, status", [
    (["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "0.2", "--quiet"], 0),
    (["sweep", "quasimoro", "--vary", "M=4,5", "--t-end", "0.2", "--workers", "0", "--quiet", "--no-plot",
      "--out", "{d}/s"], 0),
    (["simulate", "quasimoro", "--scenario", "nowhere"], 2),
])
def test_main_gives_back_the_callers_sigterm_handler(own_handler, tmp_path, capsys, argv, status):
    assert main([a.replace("{d}", str(tmp_path)) for a in argv]) == status
    assert signal.getsignal(signal.SIGTERM) is _mine


def test_the_default_handler_is_given_back_too():
    before = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        assert main(["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "0.2", "--quiet"]) == 0
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    finally:
        signal.signal(signal.SIGTERM, before)

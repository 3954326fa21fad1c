"""A simulation stopped by SIGINT (Ctrl-C) or SIGTERM keeps what it computed: the CSV holds every sample up to the
interruption, marked partial (a last '# partial: ...' comment line that numpy.loadtxt skips), and robotdyn says so
on stderr with exit status 130; a file that existed before is replaced only by a complete write."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_stopped_simulation_writes_partial_csv(tmp_path, sig):
    csv = tmp_path / "run.csv"
    csv.write_text("old\n")
    env = {**os.environ, "ROBOTDYN_COMPILED": "0"}  # the Python path: slow enough to be stopped mid-run
    proc = subprocess.Popen([sys.executable, "-m", "robotdyn", "simulate", "quasimoro", "--scenario",
                             "rectilinear", "--t-end", "900", "--csv", str(csv)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 60
    for line in proc.stderr:  # wait until the integration is under way
        if line.startswith("simulate: t =") or time.time() > deadline:
            break
    time.sleep(0.2)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "wrote the partial results" in err and "interrupted at t =" in err
    lines = csv.read_text().splitlines()
    assert lines[0].startswith("t,") and lines[-1].startswith("# partial: interrupted at t =")
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert 2 <= len(data) and data[-1, 0] < 900
    assert np.all(np.diff(data[:, 0]) > 0)


def test_complete_simulation_is_not_marked_partial(tmp_path, capsys):
    """The counterpart: a run that reaches its end writes every sample up to t_end and no partial marker."""
    from robotdyn.cli import main

    csv = tmp_path / "run.csv"
    assert main(["simulate", "quasimoro", "--scenario", "rectilinear", "--t-end", "2", "--quiet", "--csv",
                 str(csv)]) == 0
    assert "partial" not in capsys.readouterr().err
    text = csv.read_text()
    assert "# partial" not in text
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert data[0, 0] == 0.0 and abs(data[-1, 0] - 2.0) < 1e-12

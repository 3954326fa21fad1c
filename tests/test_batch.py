"""Batch evaluation equals one-by-one evaluation, in one process and in worker processes."""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.simulation.batch import evaluate
from robotdyn.errors import RobotDynError


def test_batch_equals_single_evaluations(quasimoro):
    rng = np.random.default_rng(0)
    Q = rng.uniform(-2, 2, (40, quasimoro.nq))
    NU = rng.normal(size=(40, quasimoro.mobility))
    serial = evaluate(quasimoro, Q, NU, processes=1)
    parallel = evaluate(quasimoro, Q, NU, processes=2)
    for i in (0, 17, 39):
        red = quasimoro.reduced(Q[i], NU[i])
        assert np.allclose(serial.M[i], red.M, atol=1e-15) and np.allclose(serial.h[i], red.h, atol=1e-15)
    for name in ("M", "h", "g", "B", "S"):
        assert np.array_equal(getattr(serial, name), getattr(parallel, name))


def test_batch_shape_errors(quasimoro):
    with pytest.raises(RobotDynError, match=r"Q has shape \(3, 5\); expected \(N, 6\)"):
        evaluate(quasimoro, np.zeros((3, 5)), np.zeros((3, 3)))
    with pytest.raises(RobotDynError, match="NaN"):
        evaluate(quasimoro, np.full((2, 6), np.nan), np.zeros((2, 3)))

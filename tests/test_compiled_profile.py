"""Evaluator.profile (robotdyn/_compiled.cpp; make bench's 'where a compiled evaluation's time goes'): every part's
time is a positive, finite number of seconds (zero for the parts a robot does not have: springs, a feedback law),
Pinocchio's own CRBA + RNEA + frame Jacobians cost less than the whole evaluation that contains them, and
profiling leaves the evaluator evaluated at the state it was given (the same numbers as compute there)."""

from __future__ import annotations

import numpy as np
import pytest

import robotdyn
from robotdyn.fast import dispatch
from robotdyn.fast.dispatch import compiled_model

PARTS = ("evaluation", "pinocchio", "crba", "rnea", "frames", "rows", "projection", "drift", "reduce", "rhs",
         "pull_back", "gravity", "solve", "applied", "controller", "observe", "sample", "kinematics",
         "pinocchio_jacobians")
OPTIONAL = ("pull_back", "applied", "controller")  # zero where there is nothing to do


@pytest.mark.parametrize("name", ["quasimoro", "linkage_suspension"])
def test_profile_times_and_state(name):
    if not dispatch.enabled():
        pytest.skip("the compiled fast path is off")
    robot = robotdyn.load(name)
    rng = np.random.default_rng(4)
    q, nu = robot.neutral(), rng.normal(size=robot.mobility)
    fast = compiled_model(robot)
    ref = [np.array(x) for x in fast.compute(q, nu)]
    other = robot.neutral()
    fast.compute(other, 2.0 * nu)  # something else evaluated before the profile
    t = fast.ev.profile(q, nu, 50, 1.0)
    assert set(t) == set(PARTS)
    assert all(np.isfinite(t[p]) and t[p] > 0.0 for p in PARTS if p not in OPTIONAL)
    assert all(np.isfinite(t[p]) and t[p] >= 0.0 for p in OPTIONAL)  # (no residual, no springs, no feedback law)
    assert t["applied"] == 0.0 and t["controller"] == 0.0  # neither robot has springs, compliant wheels or a law
    assert t["pinocchio"] < t["evaluation"]
    ev = fast.ev
    for got, want in zip((ev.M, ev.h, ev.g, ev.B, ev.S, ev.w, ev.v), ref):
        np.testing.assert_array_equal(got, want)
    with pytest.raises(ValueError, match="repeat"):
        fast.ev.profile(q, nu, 0)

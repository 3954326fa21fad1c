"""Property-based tests (hypothesis) of the Python API on every robot (issue 15): for finite inputs, the reduced
model, forward dynamics, contact forces and a short simulation either return finite numbers or raise a named
RobotDynError (a singular state, a configuration off the constraints, a non-finite result), never another
exception and never a NaN."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import robotdyn
from robotdyn.errors import RobotDynError

ROBOTS = ["quasimoro", "omni_caster", "linkage_suspension", "adaptable_wheel", "mmr12_eod"]
_CACHE: dict[str, robotdyn.Robot] = {}


def robot(name: str) -> robotdyn.Robot:
    if name not in _CACHE:
        _CACHE[name] = robotdyn.load(name)
    return _CACHE[name]


finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)
scale = st.sampled_from([1e-9, 1e-3, 1.0, 1e3, 1e150, 1e300])


def _finite(*arrays) -> bool:
    return all(np.all(np.isfinite(np.asarray(a, float))) for a in arrays)


@pytest.mark.parametrize("name", ROBOTS)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), s=scale)
def test_reduced_and_forward_dynamics(name, data, s):
    r = robot(name)
    nu = np.array(data.draw(st.lists(finite, min_size=r.mobility, max_size=r.mobility))) * (s / 1e6)
    tau = np.array(data.draw(st.lists(finite, min_size=len(r.motors), max_size=len(r.motors)))) * (s / 1e6)
    q = r.neutral()
    try:
        red = r.reduced(q, nu)
        assert _finite(red.M, red.h, red.g, red.B, red.S, red.w, red.v)
        nudot = r.forward_dynamics(q, nu, tau)
        assert _finite(nudot)
        f = r.contact_forces(q, nu, tau=tau)
        assert _finite(f.lam, [w.force for w in f.wheels])
    except RobotDynError as exc:
        assert "\n" not in str(exc)


@pytest.mark.parametrize("name", ["quasimoro", "omni_caster"])
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(q=st.lists(finite, min_size=9, max_size=9))
def test_configurations_are_checked(name, q):
    r = robot(name)
    q = np.array(q[: r.nq])
    try:
        r.check_constraints(r.check_q(q))
        red = r.reduced(q, np.zeros(r.mobility))
        assert _finite(red.M, red.h)
    except RobotDynError as exc:
        assert "\n" not in str(exc)

"""The eigenvalue-only screen of the conditioning warning (robotdyn.reduction.conditioning._mass_below): it clears a
reduced mass matrix only where eigh's condition number is below SEVERE_CONDITION, and ill_conditioned gives the
list of the full computation (every part's condition number, then the filters) with and without it, on matrices of
known condition number Q diag(1, ..., 1/c) Q^T on either side of the thresholds."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from robotdyn.reduction import conditioning as cond


def spd(c: float, k: int, rng) -> np.ndarray:
    """A symmetric positive definite (k, k) matrix of 2-norm condition number c (eigenvalues 2 ... 2 / c)."""
    Q, _ = np.linalg.qr(rng.normal(size=(k, k)))
    return (Q * np.geomspace(2.0, 2.0 / c, k)) @ Q.T


def unscreened(red, names, nudot, forward=True):
    """ill_conditioned's filters on every part (the computation the screen skips where it proves nothing is named)."""
    parts = cond._parts(red, names)
    if not forward:
        parts = [p for p in parts if p.part != "mass matrix"]
    out = [p for p in parts if not p.condition <= cond.SEVERE_CONDITION]
    if nudot is not None and not np.abs(np.asarray(nudot, float)).max(initial=0.0) <= cond.PLAUSIBLE_ACCELERATION:
        out = [p for p in parts if p in out or not p.condition <= cond.NAME_CONDITION]
    return out


@pytest.mark.parametrize("k", [2, 3, 12])
def test_screen_clears_only_matrices_below_the_severe_condition(k):
    rng = np.random.default_rng(k)
    for c in (1e2, 1e6, 1e9, 4e9, 6e9, 2e10, 1e12):
        M = spd(c, k, rng)
        exact = cond.mass_condition(M)[0]
        assert exact == pytest.approx(c, rel=1e-3 if c < 1e11 else 0.5)
        cleared = cond._mass_below(M)
        assert not cleared or exact <= cond.SEVERE_CONDITION  # never clears a matrix the warning names
        assert cleared == (c < 0.5 * cond.SEVERE_CONDITION)  # (effective: it clears what is clearly below)
    assert not cond._mass_below(np.diag([1.0, -1e-3])) and not cond._mass_below(np.full((2, 2), np.nan))
    assert cond._mass_below(np.zeros((0, 0)))


@pytest.mark.parametrize("forward", [True, False])
def test_ill_conditioned_names_the_parts_of_the_full_computation(forward):
    """Every combination of a projection and a mass matrix below, between and above the thresholds, with plausible
    and implausible accelerations: the same parts, the same condition numbers (the list of the full computation),
    empty where nothing is named."""
    rng = np.random.default_rng(9)
    names = ["a", "b", "c"]
    seen = set()
    for proj in (3.0, 5e7, 3e10):
        for c in (10.0, 5e7, 3e10):
            for nudot in (None, np.ones(3), np.full(3, 1e7)):
                red = SimpleNamespace(projection=SimpleNamespace(condition=proj), M=spd(c, 3, rng))
                got = cond.ill_conditioned(red, names, nudot, forward)
                assert got == unscreened(red, names, nudot, forward)
                seen.add(bool(got))
    assert seen == {True, False}

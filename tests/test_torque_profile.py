"""Torque profiles (robotdyn.simulation.torque_profile): their values against closed forms, and the C++ evaluation
(robotdyn._compiled.TorqueProfile) bit for bit equal to the Python one at many times."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from robotdyn.fast.dispatch import available
from robotdyn.errors import InputError
from robotdyn.robots import quasimoro
from robotdyn.simulation.torque_profile import Constant, PiecewisePolynomial, Sine, Sum, Table, as_profile


def profiles():
    return {
        "constant": Constant([0.5, -0.25]),
        "pulse": Sine([0.1, 0.1], math.pi, start=0.0, stop=1.0),
        "sine": Sine([1.0, -2.0], 3.7, phase=0.3),
        "table": Table([0.0, 0.5, 2.0, 2.5], [[0.0, 1.0], [1.0, 1.0], [-1.0, 0.5], [0.0, 0.0]]),
        "sum": Constant([0.1, 0.2]) + Sine([0.3, 0.0], 2.0, start=0.5, stop=1.5) + Table([1.0, 2.0], [[0, 0], [1, 2]]),
        "piecewise": PiecewisePolynomial([0.0, 0.5, 2.0, 2.5], [[[1.0, -2.0], [0.5, 0.25], [-3.0, 1.5]],
                                                                 [[0.0, 1.0], [2.0, -1.0], [0.0, 0.0]],
                                                                 [[-1.0, 0.5], [0.125, 4.0], [2.0, -0.5]]]),
    }


def test_values_against_closed_forms():
    p = profiles()
    assert np.array_equal(p["constant"](3.0), [0.5, -0.25])
    assert np.allclose(p["pulse"](0.25), 0.1 * math.sin(math.pi * 0.25), rtol=0, atol=1e-17)
    assert np.array_equal(p["pulse"](1.0 + 1e-12), [0.0, 0.0]) and np.array_equal(p["pulse"](-1e-12), [0.0, 0.0])
    assert np.allclose(p["table"](1.25), [0.0, 0.75]) and np.array_equal(p["table"](9.0), [0.0, 0.0])
    assert np.array_equal(p["table"](-1.0), [0.0, 1.0])
    t = 1.2
    assert np.allclose(p["sum"](t), [0.1 + 0.3 * math.sin(2.0 * t), 0.2] + np.array([0.2, 0.4]), atol=1e-15)
    assert np.array_equal(p["sum"].breakpoints(), [0.5, 1.0, 1.5, 2.0])
    assert np.array_equal(p["sine"].breakpoints(), [])  # always on: no kink


def test_quasimoro_pulse_is_eq_19():
    """The scenarios' profile equals the paper's pulse (eq 19) as the module transcribes it."""
    prof = quasimoro.SCENARIOS["rectilinear"].torque
    rot = quasimoro.SCENARIOS["pure_rotation"].torque
    for t in np.linspace(-0.5, 3.0, 71):
        assert prof(t) == pytest.approx([quasimoro._pulse(t)] * 2, abs=1e-17)
        assert rot(t) == pytest.approx([quasimoro._pulse(t), -quasimoro._pulse(t)], abs=1e-17)


@pytest.mark.skipif(not available(), reason="compiled extension not built")
@pytest.mark.parametrize("name", list(profiles()))
def test_cpp_evaluation_is_bitwise_the_python_one(name):
    from robotdyn.simulation.compiled_engine import native_profile

    prof = profiles()[name]
    native = native_profile(prof)
    rng = np.random.default_rng(1)
    times = np.concatenate([rng.uniform(-1, 4, 2000), prof.breakpoints(), [0.0, 1.0, 2.0, 2.5]])
    for t in times:
        assert np.array_equal(native(float(t)), prof(float(t))), t


def test_profiles_pickle_and_compare():
    for prof in profiles().values():
        again = pickle.loads(pickle.dumps(prof))
        assert again == prof and np.array_equal(again(0.7), prof(0.7))
    assert Constant([1.0, 2.0]) != Constant([1.0, 2.5])


def test_bad_profiles_one_line():
    cases = [(lambda: Constant([1.0, np.nan]), "finite"),
             (lambda: Sine([1.0], 1.0, start=2.0, stop=1.0), "start <= stop"),
             (lambda: Table([0.0, 0.0], [[1.0], [2.0]]), "strictly increasing"),
             (lambda: Table([0.0, 1.0], [[1.0]]), "expected"),
             (lambda: Constant([1.0]) + Constant([1.0, 2.0]), "cannot be added"),
             (lambda: as_profile(Constant([1.0]), 2), "robot has 2")]
    for make, words in cases:
        with pytest.raises(InputError, match=words) as err:
            make()
        assert "\n" not in str(err.value)
    assert as_profile(lambda t, q, nu: 0, 2) is None  # a Python function: the scipy engine
    assert isinstance(Sum(Constant([1.0])), Sum)


@pytest.mark.parametrize("name", sorted(profiles()))
def test_values_at_many_times_are_the_scalar_ones(name):
    """``at(times)`` (vectorised, used by sweeps to find when the torques stop) equals the scalar evaluation at
    every time, knots, window edges and both sides of the table included, to 1 ulp-scale round-off, and is zero
    exactly where the scalar one is."""
    profile = profiles()[name].scaled(1.3)
    t = np.concatenate([np.linspace(-1.0, 4.0, 2001), [0.0, 0.5, 1.0, 1.5, 2.0, 2.5]])
    many = profile.at(t)
    one = np.array([profile(x) for x in t])
    assert many.shape == (t.size, 2)
    assert np.max(np.abs(many - one)) <= 4e-16 * max(1.0, np.max(np.abs(one)))
    assert np.array_equal(many == 0.0, one == 0.0)


def test_piecewise_polynomial_closed_form_breakpoints_and_fit():
    """Piece j is sum_i c_ji (t - x_j)^i on [x_j, x_j+1] (a shared knot belongs to the later piece), zero outside;
    every knot is a breakpoint unless the pieces are smooth. The fit of f(t) = (exp(-t/2) sin 3t, cos 2t) on [0, 4]
    s (its closed form) is within 1e-13 everywhere and states its error; a fit too coarse for the tolerance is refused
    in one line."""
    p = profiles()["piecewise"]
    c = p.coefficients
    for t, j in ((0.25, 0), (0.5, 1), (1.2, 1), (2.0, 2), (2.5, 2)):
        s = t - p.knots[j]
        assert np.allclose(p(t), c[j, 0] + c[j, 1] * s + c[j, 2] * s**2, rtol=0, atol=1e-15), t
    assert np.array_equal(p(-1e-12), [0.0, 0.0]) and np.array_equal(p(2.5 + 1e-12), [0.0, 0.0])
    assert p.breakpoints().tolist() == [0.0, 0.5, 2.0, 2.5]

    def f(t):
        return np.stack([np.exp(-t / 2) * np.sin(3 * t), np.cos(2 * t)], axis=-1)

    fit = PiecewisePolynomial.fit(f, 0.0, 4.0, pieces=16, degree=12)
    assert fit.breakpoints().tolist() == [0.0, 4.0]
    t = np.linspace(0.0, 4.0, 3001)
    assert np.abs(fit.at(t) - f(t)).max() < 1e-13 and fit.fit_error < 1e-13
    with pytest.raises(InputError, match="more pieces or a higher degree") as err:
        PiecewisePolynomial.fit(f, 0.0, 4.0, pieces=2, degree=3)
    assert "\n" not in str(err.value)
    for make, words in ((lambda: PiecewisePolynomial([0.0, 0.0], [[[1.0]]]), "increasing"),
                        (lambda: PiecewisePolynomial([0.0, 1.0, 2.0], [[[1.0]]]), "2 pieces"),
                        (lambda: PiecewisePolynomial.fit(f, 1.0, 0.0, 4), "start < stop")):
        with pytest.raises(InputError, match=words):
            make()

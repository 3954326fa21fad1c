"""Self-checks of the independent sympy oracle for the Quasimoro reduced dynamics."""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

try:  # tests/ as a package (rootdir on sys.path)
    from tests.oracles import quasimoro_sympy as qo
except ImportError:  # rootdir-less import (tests/ itself on sys.path)
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from oracles import quasimoro_sympy as qo

READINGS = ("axle", "com")


def _random_states(n, seed):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = rng.uniform(-np.pi, np.pi, 6)
        nu = rng.normal(size=3) * 3.0
        yield q, nu


def test_routes_agree_kane_vs_lagrange():
    # (a) KanesMethod with nonholonomic constraints == (b) projected Lagrangian,
    # exactly (symbolically) and numerically at 50 random states, to 1e-10.
    qo.self_test(n=50, seed=1, tol=1e-10)


@pytest.mark.parametrize("reading", READINGS)
def test_Mr_symmetric_positive_definite(reading):
    model = qo.quasimoro_reduced(qo.paper_defaults(), reading)
    for q, _ in _random_states(50, 2):
        Mr = model.M_r(q)
        np.testing.assert_allclose(Mr, Mr.T, atol=1e-14)
        assert np.linalg.eigvalsh(Mr).min() > 1e-6


@pytest.mark.parametrize("reading", READINGS)
def test_Mdot_minus_2C_skew(reading):
    model = qo.quasimoro_reduced(qo.paper_defaults(), reading)
    eps = 1e-6
    for q, nu in _random_states(50, 3):
        qdot = model.S(q) @ nu
        Mdot_fd = (model.M_r(q + eps * qdot) - model.M_r(q - eps * qdot)) / (2 * eps)
        Mdot = model.Mdot_r(q, nu)
        np.testing.assert_allclose(Mdot, Mdot_fd, atol=1e-8)
        N = Mdot - 2.0 * model.C_r(q, nu)
        np.testing.assert_allclose(N + N.T, 0.0, atol=1e-12)
        # full model: Mdot - 2C skew for the Christoffel C
        v = model.S(q) @ nu + np.random.default_rng(0).normal(size=6)
        Mf_dot = (model.M(q + eps * v) - model.M(q - eps * v)) / (2 * eps)
        Nf = Mf_dot - 2.0 * model.C(q, v)
        np.testing.assert_allclose(Nf + Nf.T, 0.0, atol=1e-7)


@pytest.mark.parametrize("reading", READINGS)
def test_energy_conserved_torque_free(reading):
    model = qo.quasimoro_reduced(qo.paper_defaults(), reading)
    q0 = np.array([0.1, -0.2, 0.3, 0.0, 0.0, 0.6])  # tilted intermediate body
    nu0 = np.array([1.0, -0.5, 0.8])
    y0 = np.concatenate([q0, nu0])
    sol = solve_ivp(model.rhs, (0.0, 5.0), y0, method="DOP853", rtol=1e-11, atol=1e-12,
                    dense_output=False, t_eval=np.linspace(0.0, 5.0, 101))
    assert sol.success
    E = np.array([model.energy(y[:6], y[6:]) for y in sol.y.T])
    E0 = E[0]
    assert E0 > 0
    assert np.max(np.abs(E - E0)) / abs(E0) < 1e-8
    # the motion is non-trivial (body swings, robot turns)
    assert np.ptp(sol.y[5]) > 0.1 and np.ptp(sol.y[2]) > 0.1
    # rolling constraints hold along the solution
    for y in sol.y.T[::10]:
        q, nu = y[:6], y[6:]
        np.testing.assert_allclose(model.A(q) @ (model.S(q) @ nu), 0.0, atol=1e-12)


def test_generalized_forces_and_constraints():
    s = qo.symbolic_reduced("axle")
    assert s["B"] == sp.Matrix([[0, 0], [0, 0], [0, 0], [1, 0], [0, 1], [1, 1]])
    assert s["B_r"] == sp.Matrix([[1, 0], [0, 1], [1, 1]])


def test_paper_eqs_24_26_28_hold_for_axle_reading():
    """The paper's coefficients A11..A19 (24), A2j (26) and eq. (28) coincide
    with the reduced equations when diag(J1, J2, J2) is taken about C2."""
    m, M, J1, J2, r, d, rho, g = qo.PARAM_SYMS
    th3 = qo.Q[5]
    c, s = sp.cos(th3), sp.sin(th3)
    Jpsi = J1 * c**2 + J2 * s**2
    A1 = {
        "dd1": m * r**2 * (3 + rho**2) / 2 + rho**2 * Jpsi + M * r**2 / 4,
        "dd2": -m * r**2 * rho**2 / 2 - rho**2 * Jpsi + M * r**2 / 4,
        "dd3": M * r * d * c / 2,
        "12": M * r * d * rho**2 * s,
        "23": 2 * rho**2 * (J1 - J2) * s * c,
        "31": -2 * rho**2 * (J1 - J2) * s * c,
        "11": 0,
        "22": -M * r * d * rho**2 * s,
        "33": -M * r * d * s / 2,
    }
    A2 = dict(A1)
    A2.update({"dd1": A1["dd2"], "dd2": A1["dd1"], "23": A1["31"], "31": A1["23"],
               "11": A1["22"], "22": A1["11"]})
    w2 = {"11": 1, "22": 1, "12": -2}  # (th2d - th1d)^2
    A3 = {"dd1": M * r * d * c / 2, "dd2": M * r * d * c / 2, "dd3": J2,
          "23": 0, "31": 0, "33": 0}
    for k, f in w2.items():
        A3[k] = f * (J1 - J2) * rho**2 * s * c
    rows = qo.paper_coefficients("axle")
    for i, ref in enumerate((A1, A2, A3)):
        for k, val in ref.items():
            assert qo._is_zero_trig(rows[i][k] - val), (i + 1, k, rows[i][k], val)
    assert qo._is_zero_trig(rows[2]["grav"] - M * g * d * s)
    # in the "com" reading J2 -> J2 + M d^2 everywhere (parallel-axis theorem)
    rows_com = qo.paper_coefficients("com")
    for i in range(3):
        for k, val in rows[i].items():
            if k == "B":
                continue
            assert qo._is_zero_trig(rows_com[i][k] - val.subs(J2, J2 + M * d**2)), (i + 1, k)

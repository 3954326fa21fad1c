"""Quasimoro: the paper's closed forms, transcribed as printed (no robotdyn model computation here).

Paper: Şt. Staicu, "Dynamics of Angeles's Quasimoro mobile robot using principle of virtual powers"
(Staicu, ``docs/bibliography.md``): the coefficients A11..A19 of eq 24 with the symmetries of
eq 26, the rows of eqs 23, 25, 28, the rectilinear torque of eq 29, the pure-rotation inertia of eq 31 and the
steady inclination amplitude read off Fig. 5 (section 3). Each function takes the parameters as a plain dict
(m, M, J1, J2, r, d, rho, g), so it can be read line by line against the paper.
"""

from __future__ import annotations

import numpy as np

STEADY_THETA3_AMPLITUDE = 0.0129
"""Sec 3 / Fig. 5: the body's steady inclination oscillates within +-0.0129 rad in the rectilinear manoeuvre."""


def paper_coefficients(p: dict, theta3: float) -> dict[str, float]:
    """The paper's coefficients A11..A19 (eq 24) at inclination theta3, as printed.

    Args:
        p: Parameters m, M, J1, J2, r, d, rho.
        theta3: Body inclination [rad].

    Returns:
        A dict of coefficient name (``A11`` to ``A19``) to value, as printed.
    """
    m, M, J1, J2, r, d, rho = (p[k] for k in ("m", "M", "J1", "J2", "r", "d", "rho"))
    s, c = np.sin(theta3), np.cos(theta3)
    yaw = J1 * c**2 + J2 * s**2
    return {
        "A11": 0.5 * m * r**2 * (3 + rho**2) + rho**2 * yaw + 0.25 * M * r**2,
        "A12": -0.5 * m * r**2 * rho**2 - rho**2 * yaw + 0.25 * M * r**2,
        "A13": 0.5 * M * r * d * c,
        "A14": M * r * d * rho**2 * s,
        "A15": 2 * rho**2 * (J1 - J2) * s * c,
        "A16": -2 * rho**2 * (J1 - J2) * s * c,
        "A17": 0.0,
        "A18": -M * r * d * rho**2 * s,
        "A19": -0.5 * M * r * d * s,
    }


# index pairs (i, j) of nu_i nu_j, nu = (theta1_dot, theta2_dot, theta3_dot), in the paper's order A_4..A_9
_PRODUCTS = [(0, 1), (1, 2), (0, 2), (0, 0), (1, 1), (2, 2)]


def paper_equations(p: dict, theta3: float) -> tuple[np.ndarray, dict[tuple[int, int], np.ndarray], np.ndarray]:
    """The paper's reduced model in nu = (theta1_dot, theta2_dot, theta3_dot), rows = eqs 23, 25, 28.

    Args:
        p: The parameters as a plain dict: m [kg], M [kg], J1 [kg m^2], J2 [kg m^2], r [m], d [m], rho [-] (and g
            [m/s^2] where gravity enters).
        theta3: Body inclination [rad].

    Returns:
        ``(M, quad, grav)``: the 3x3 inertia matrix, the velocity-product coefficient vectors
        ``{(i, j): 3-vector}`` and the gravity vector, so that row i reads
        ``M[i] @ nu_dot + sum quad[ij][i] nu_i nu_j + grav[i] = (m1, m2, m1 + m2)[i]``.
    """
    A = paper_coefficients(p, theta3)
    # eq 26: A21 = A12, A22 = A11, A23 = A13, A24 = A14, A25 = A16, A26 = A15, A27 = A18, A28 = A17, A29 = A19
    row1 = [A["A14"], A["A15"], A["A16"], A["A17"], A["A18"], A["A19"]]
    row2 = [A["A14"], A["A16"], A["A15"], A["A18"], A["A17"], A["A19"]]
    s, c = np.sin(theta3), np.cos(theta3)
    k = (p["J1"] - p["J2"]) * p["rho"] ** 2 * s * c  # eq 28: (J1 - J2) rho^2 (th2' - th1')^2 sin cos
    row3 = [-2 * k, 0.0, 0.0, k, k, 0.0]
    quad = {ij: np.array([row1[n], row2[n], row3[n]]) for n, ij in enumerate(_PRODUCTS)}
    half = 0.5 * p["M"] * p["r"] * p["d"] * c
    M = np.array([[A["A11"], A["A12"], A["A13"]], [A["A12"], A["A11"], A["A13"]], [half, half, p["J2"]]])
    grav = np.array([0.0, 0.0, p["M"] * p["g"] * p["d"] * s])
    return M, quad, grav


def paper_rectilinear_torque(p: dict, theta3: float, theta1_ddot: float, theta3_dot: float, theta3_ddot: float) -> float:
    """Eq 29: m1 = m2 = (3m + M) r^2 th1''/2 + M r d (th3'' cos th3 - th3'^2 sin th3)/2 (rectilinear motion).

    Args:
        p: The parameters as a plain dict: m [kg], M [kg], J1 [kg m^2], J2 [kg m^2], r [m], d [m], rho [-] (and g
            [m/s^2] where gravity enters).
        theta3: Body inclination [rad].
        theta1_ddot: Wheel angular acceleration [rad/s^2].
        theta3_dot: Inclination rate [rad/s].
        theta3_ddot: Inclination acceleration [rad/s^2].

    Returns:
        Each motor's torque m1 = m2 [N m].
    """
    m, M, r, d = p["m"], p["M"], p["r"], p["d"]
    return 0.5 * (3 * m + M) * r**2 * theta1_ddot + 0.5 * M * r * d * (
        theta3_ddot * np.cos(theta3) - theta3_dot**2 * np.sin(theta3)
    )


def paper_rotation_inertia(p: dict) -> float:
    """Eq 31: :math:`m_1 = |m_2|` = [m r^2 (3/2 + rho^2) + 2 rho^2 J1] th1'' (pure rotation, theta3 = 0).

    Args:
        p: The parameters as a plain dict: m [kg], M [kg], J1 [kg m^2], J2 [kg m^2], r [m], d [m], rho [-] (and g
            [m/s^2] where gravity enters).

    Returns:
        The factor of th1'' in m1 [kg m^2].
    """
    return p["m"] * p["r"] ** 2 * (1.5 + p["rho"] ** 2) + 2 * p["rho"] ** 2 * p["J1"]

"""Linkage-suspension six-wheel robot: the paper's closed forms and printed values, transcribed (no model here).

Paper: Chen, Wang, Zhong, Zhu, Wang, "Kinematics Analysis and Simulation of Mobile Robot Based on Linkage
Suspension" (Chen et al., ``docs/bibliography.md``): the D-H rows of Table 1 (eq 3's product
R -> A3), the contact rotation of eq 1, the omni-wheel attitude of eq 2, the entries of eq 4 exactly as printed
(with single-typo readings, :func:`eq4_readings`), the left-hand side of eq 10 as printed (and eq 5 evaluated with
Table 1's own axes, :func:`corrected_eq10_joint_terms`), and the numbers section 3 prints (Figs. 7, 8, 12).
Each function takes the Table 1 lengths as a plain dict.
"""

from __future__ import annotations

import numpy as np

PEAK_CENTROID_SPEED = 0.73
"""Sec 3.1 / Fig. 8: peak centroid speed [m/s] of the straight run."""
TRAVEL_DISTANCE = 2.0
"""Sec 3.1 / Fig. 7: distance travelled by the centroid [m] (0.52 -> -1.48 m)."""
PIVOT_TURNS = 2.0
"""Sec 3.2 / Fig. 12: the pivot-steering run turns the robot twice about itself."""


def dh(alpha: float, a: float, d: float, theta: float) -> np.ndarray:
    """Standard Denavit-Hartenberg transform Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha) (4x4).

    Args:
        alpha: Link twist [rad].
        a: Link length [m].
        d: Link offset [m].
        theta: Joint angle [rad].

    Returns:
        The 4x4 transform.
    """
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1.0]])


def table1_R_A3(p: dict, theta1: float, beta1: float) -> np.ndarray:
    """R -> A3 (right rear wheel axle) from the D-H rows of Table 1: D, B2, A3 (4x4, independent of the URDF).

    Args:
        p: Table 1 lengths as a plain dict [m]: a1, d1, a5, d5, a6, a7.
        theta1: The rocker angle theta1 [rad] (Table 1).
        beta1: The bogie angle beta1 [rad] (Table 1).

    Returns:
        The homogeneous transform (4, 4) [m] of A3 in R.
    """
    return dh(np.pi / 2, p["a1"], -p["d1"], 0.0) @ dh(0.0, p["a5"], p["d5"], 1.5 * np.pi - theta1) @ dh(
        -np.pi / 2, -p["a7"], 0.0, beta1)


def eq1(delta: float) -> np.ndarray:
    """Eq (1): A_i -> C_i rotation by the contact angle delta (as printed; a rotation about y).

    Args:
        delta: The contact angle delta [rad].

    Returns:
        The 3x3 rotation.
    """
    c, s = np.cos(delta), np.sin(delta)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def eq2(rho: float) -> np.ndarray:
    """Eq (2): the omni wheel's attitude matrix H (as printed; a rotation by rho about the wheel frame's z).

    Args:
        rho: The omni wheel's roller angle rho [rad].

    Returns:
        The 3x3 matrix H.
    """
    c, s = np.cos(rho), np.sin(rho)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def paper_eq4(p: dict, theta1: float, beta1: float, rho: float, delta: float) -> dict[str, float]:
    """The entries of eq (4), R -> C3 for the right rear wheel, exactly as printed.

    The printed list has a 'cosh rho' in T13 and labels the third-row, third-column entry 'T32' a second time;
    both are transcribed literally (T33 is the second 'T32').

    Args:
        p: Table 1 lengths as a plain dict [m]: a1, d1, a5, d5, a6, a7.
        theta1: The rocker angle theta1 [rad] (Table 1).
        beta1: The bogie angle beta1 [rad] (Table 1).
        rho: The roller angle rho [rad].
        delta: The contact angle delta [rad].

    Returns:
        A dict of entry name to value [m or dimensionless], as printed.
    """
    a1, d1, a5, d5, a7 = (p[k] for k in ("a1", "d1", "a5", "d5", "a7"))
    f = beta1 - theta1
    cd, sd, cr, sr, cf, sf = np.cos(delta), np.sin(delta), np.cos(rho), np.sin(rho), np.cos(f), np.sin(f)
    return {
        "T11": cd * cr * sf - sd * cf,
        "T12": -sr * sf,
        "T13": cd * cf - sd * np.cosh(rho) * sf,
        "T21": cd * cr,
        "T22": cr,
        "T23": sd * sr,
        "T31": -cd * cr * cf - sd * sf,
        "T32": sr * cf,
        "T33": sr * cf - cr * sd * cf,
        "T14": a1 - a5 * np.sin(theta1) - a7 * sf,
        "T24": -d5,
        "T34": d1 + a5 * np.cos(theta1) - a7 * cf,
    }


def eq4_readings(p: dict, theta1: float, beta1: float, rho: float, delta: float) -> dict[str, tuple[str, float]]:
    """Candidate corrections of the printed eq (4) entries (each a single, named typo).

    Args:
        p: Table 1 lengths as a plain dict [m]: a1, d1, a5, d5, a6, a7.
        theta1: The rocker angle theta1 [rad] (Table 1).
        beta1: The bogie angle beta1 [rad] (Table 1).
        rho: The roller angle rho [rad].
        delta: The contact angle delta [rad].

    Returns:
        A dict of entry name to ``(reading, value)``: the named correction and the corrected value.
    """
    a5, a7, d1 = p["a5"], p["a7"], p["d1"]
    f = beta1 - theta1
    cd, sd, cr, sr, cf, sf = np.cos(delta), np.sin(delta), np.cos(rho), np.sin(rho), np.cos(f), np.sin(f)
    return {
        "T13": ("cosh -> cos and '+' before sin(delta)", cd * cf + sd * cr * sf),
        "T21": ("cos(rho) -> sin(rho)", cd * sr),
        "T33": ("first term cos(delta) sin(beta1-theta1), not a copy of T32's sin(rho) cos(beta1-theta1)",
                cd * sf - cr * sd * cf),
        "T34": ("opposite sign (z of Table 1's own product)", -(d1 + a5 * np.cos(theta1) - a7 * cf)),
    }


def paper_eq10_lhs(p: dict, theta1: float, beta1: float, v0: np.ndarray, w0: np.ndarray, theta1_dot: float,
                   beta1_dot: float) -> np.ndarray:
    """Left-hand side of eq (10): the right rear wheel centre's velocity in R axes, as printed.

    Args:
        v0, w0: Body velocity and angular velocity (phi_0x, phi_0y, phi_0z) in R axes.
        p: Table 1 lengths as a plain dict [m]: a1, d1, a5, d5, a6, a7.
        theta1: The rocker angle theta1 [rad] (Table 1).
        beta1: The bogie angle beta1 [rad] (Table 1).
        theta1_dot: Rocker rate [rad/s].
        beta1_dot: Bogie rate [rad/s].

    Returns:
        The velocity (3,) [m/s] in R axes.
    """
    a1, d1, a5, d5, a7 = (p[k] for k in ("a1", "d1", "a5", "d5", "a7"))
    f = beta1 - theta1
    z = d1 + a5 * np.cos(theta1) - a7 * np.cos(f)
    x = a1 - a5 * np.sin(theta1) - a7 * np.sin(f)
    return np.array([
        v0[0] - z * w0[1] + d5 * w0[2] + (a7 * np.cos(f) + a5 * np.cos(theta1)) * theta1_dot
        + a7 * np.cos(f) * beta1_dot,
        v0[1] + z * w0[0] + x * w0[2],
        v0[2] - d5 * w0[0] - x * w0[1] + (a7 * np.sin(f) - a5 * np.sin(theta1)) * theta1_dot
        + a7 * np.sin(f) * beta1_dot,
    ])


def corrected_eq10_joint_terms(p: dict, theta1: float, beta1: float) -> tuple[np.ndarray, np.ndarray]:
    """Eq (5) evaluated with Table 1's own axes (omega1 = +theta1' y_R, omega2 = -beta1' y_R): the columns
    multiplying theta1' and beta1' (R axes).

    Args:
        p: Table 1 lengths as a plain dict [m]: a1, d1, a5, d5, a6, a7.
        theta1: The rocker angle theta1 [rad] (Table 1).
        beta1: The bogie angle beta1 [rad] (Table 1).

    Returns:
        The two columns (3,) each, in R axes, of theta1' and beta1' [m per rad].
    """
    a5, a7 = p["a5"], p["a7"]
    f = beta1 - theta1
    return (np.array([a7 * np.cos(f) - a5 * np.cos(theta1), 0.0, a5 * np.sin(theta1) + a7 * np.sin(f)]),
            np.array([-a7 * np.cos(f), 0.0, -a7 * np.sin(f)]))

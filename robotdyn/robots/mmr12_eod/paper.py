"""MMR12-EOD: the paper's closed forms and printed transforms, transcribed (no robotdyn model computation here).

Paper: L. A. Zuniga-Aviles, J. C. Pedraza-Ortega et al., "HTG-Based Kinematic Modeling for Positioning of a
Multi-Articulated Wheeled Mobile Manipulator", J. Intell. Robot. Syst. (2014)
(Zúñiga-Avilés et al. 2014, ``docs/bibliography.md``): Paul's link transform of Table 2, the lift of eqs 1/26,
A_C and the HTG product of sec 2.7.1, X_M of eq 2 as printed, the platform rates of eqs 12-14, the inverse
kinematics of eqs 3-5, 10-11 (eqs 6-9 use undefined symbols: not transcribed) and the matrices printed as
eqs 27-31. Each function takes the parameters as a plain dict (Table 2 names of :data:`.model.SPEC`).
"""

from __future__ import annotations

import numpy as np


def dh(theta: float, lam: float, l: float, alpha: float) -> np.ndarray:
    """Paul's link transform A = Rot(z, theta) Trans(0, 0, lambda) Trans(l, 0, 0) Rot(x, alpha) (Table 2).

    Args:
        theta: Joint angle theta [rad].
        lam: Offset lambda along z [m].
        l: Length l along x [m].
        alpha: Twist alpha [rad].

    Returns:
        The 4x4 transform.
    """
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, l * ct], [st, ct * ca, -ct * sa, l * st], [0.0, sa, ca, lam],
                     [0.0, 0.0, 0.0, 1.0]])


def _trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def paper_delta_lambda(p: dict, theta_C1: float, r: float | None = None) -> float:
    """Eqs (1)/(26): Delta lambda_C = l_CS1 sin(theta_C1) - lambda_C0 + r when >= 0, else 0 [m].

    Args:
        p: The parameters as a plain dict (Table 2 names of :data:`.model.SPEC`; lengths [m], angles [rad]).
        theta_C1: Arm angle theta_C1 [rad].
        r: Tip wheel radius [m] (default ``None``: ``p['r']``).

    Returns:
        Delta lambda_C [m] (>= 0).
    """
    r = p["r"] if r is None else r
    value = p["l_cs1"] * np.sin(theta_C1) - p["lambda_C0"] + r
    return float(value) if value >= 0 else 0.0


def paper_A_C(p: dict, x: float, y: float, phi: float, dlam: float) -> np.ndarray:
    """Sec 2.7.1 a): A_C = Trans(x_C0, y_C0, z_C0) Rot(z, phi) Trans(0, 0, Delta lambda_C), z_C0 = lambda_C0.

    Args:
        p: The parameters as a plain dict (Table 2 names of :data:`.model.SPEC`; lengths [m], angles [rad]).
        x: Platform x [m].
        y: Platform y [m].
        phi: Platform heading phi [rad].
        dlam: Platform lift Delta lambda_C [m] (eq 26).

    Returns:
        The 4x4 transform.
    """
    return _trans(x, y, p["lambda_C0"]) @ dh(phi, 0.0, 0.0, 0.0) @ _trans(0.0, 0.0, dlam)


def paper_htg_chain(p: dict, x, y, phi, dlam, theta1, lambda2, theta3, theta4, lambda6, theta_mu=0.0) -> np.ndarray:
    """The HTG product X_M = A_C A_0 A_1 A_2 A_3 A_4 E E_muP E_muR of sec 2.7.1 with Table 2's rows.

    Rows: 0 (alpha pi/2, l = -l0, lambda0, theta 0), 1 (alpha pi/2, theta1), 2 (alpha -pi/2, lambda2),
    3 (alpha pi/2, l3, theta3), 4 (theta4), E (lambda5), E_muP (lambda6), E_muR (alpha pi/2, theta_mu).

    Args:
        p: The parameters as a plain dict (Table 2 names of :data:`.model.SPEC`; lengths [m], angles [rad]).
        x: Platform x [m].
        y: Platform y [m].
        phi: Platform heading phi [rad].
        dlam: Platform lift Delta lambda_C [m] (eq 26).
        theta1: Manipulator joint 1 angle theta1 [rad] (Table 2's DH angle).
        lambda2: Prismatic joint 2 extension lambda2 [m].
        theta3: Joint 3 angle theta3 [rad].
        theta4: Joint 4 angle theta4 [rad].
        lambda6: Load joint E_muP extension lambda6 [m].
        theta_mu: Load joint E_muR angle theta_mu [rad].

    Returns:
        X_M (4x4).
    """
    h = np.pi / 2
    chain = [dh(0.0, p["lambda0"], -p["l0"], h), dh(theta1, 0.0, 0.0, h), dh(0.0, lambda2, 0.0, -h),
             dh(theta3, 0.0, p["l3"], h), dh(theta4, 0.0, 0.0, 0.0), dh(0.0, p["lambda5"], 0.0, 0.0),
             dh(0.0, lambda6, 0.0, 0.0), dh(theta_mu, 0.0, 0.0, h)]
    T = paper_A_C(p, x, y, phi, dlam)
    for A in chain:
        T = T @ A
    return T


def paper_X_M(p: dict, x, y, phi, dlam, theta1, lambda2, theta3, theta4, lambda6) -> np.ndarray:
    """Eq (2) exactly as printed: X_M = GT_4 E E_mu (load frame in global coordinates).

    Args:
        p: The parameters as a plain dict (Table 2 names of :data:`.model.SPEC`; lengths [m], angles [rad]).
        x: Platform x [m].
        y: Platform y [m].
        phi: Platform heading phi [rad].
        dlam: Platform lift Delta lambda_C [m] (eq 26).
        theta1: Manipulator joint 1 angle theta1 [rad] (Table 2's DH angle).
        lambda2: Prismatic joint 2 extension lambda2 [m].
        theta3: Joint 3 angle theta3 [rad].
        theta4: Joint 4 angle theta4 [rad].
        lambda6: Load joint E_muP extension lambda6 [m].

    Returns:
        X_M (4x4).
    """
    SC, CC = np.sin(phi), np.cos(phi)
    S1, C1 = np.sin(theta1), np.cos(theta1)
    S13, C13 = np.sin(theta1 + theta3), np.cos(theta1 + theta3)
    S4, C4 = np.sin(theta4), np.cos(theta4)
    l0, l3, lam0, lam5, lam6 = p["l0"], p["l3"], p["lambda0"], p["lambda5"], lambda6
    reach = S1 * lambda2 + l3 * C13 - l0
    return np.array([
        [S4 * SC + CC * C13 * C4, CC * S13, CC * C13 * S4 - C4 * SC, x + CC * reach + CC * lam5 * S13 + CC * lam6 * S13],
        [SC * C13 * C4 - CC * S4, SC * C13, SC * C13 * S4 + C4 * CC, y + SC * reach + SC * lam5 * S13 + SC * lam6 * S13],
        [S13 * C4, -C13, S13 * S4, p["lambda_C0"] + dlam + lam0 - lam5 * C13 - C1 * lambda2 + l3 * S13 - lam6 * C13],
        [0.0, 0.0, 0.0, 1.0],
    ])


def paper_platform_rates(p: dict, phi: float, thR_dot: float, thL_dot: float) -> np.ndarray:
    """Eqs (12)-(14) solved for (x', y', phi') given the wheel rates (r of eqs 13-14 = the drive-wheel radius).

    Args:
        p: The parameters as a plain dict (Table 2 names of :data:`.model.SPEC`; lengths [m], angles [rad]).
        phi: Platform heading phi [rad].
        thR_dot: Right wheel rate [rad/s].
        thL_dot: Left wheel rate [rad/s].

    Returns:
        (x', y', phi') [m/s, m/s, rad/s].
    """
    R, b = p["lambda_C0"], p["b"]
    phidot = R / (2 * b) * (thR_dot - thL_dot)  # eq 14
    v = thR_dot * R - phidot * b  # eq 13: x' cos + y' sin = theta_r' r - phi' b
    return np.array([v * np.cos(phi), v * np.sin(phi), phidot])  # eq 12: no lateral velocity


def paper_ik(p: dict, target, lambda2: float, theta1: float, theta3: float) -> dict[str, float]:
    """The evaluable inverse-kinematics equations (3), (4), (5), (10), (11).

    Args:
        p: Parameters.
        target: (d_x, d_y, d_z): the end-effector target; for eq 3 and eqs 10-11 in global coordinates, for eqs 4-5
            relative to the manipulator base (frame 0) as Fig. 8 suggests.
        lambda2, theta1, theta3: Arm values used on the right-hand sides.

    Returns:
        ``phi`` (eq 3), ``theta3`` (eq 4, NaN if the arccos argument leaves [-1, 1]), ``lambda2`` (eq 5),
        ``x_C`` (eq 10), ``y_C`` (eq 11). Eqs 6-9 use symbols (d_0, d_1, d_2, d_C, E1, P1) that the text never
        defines, so they are not transcribed.
    """
    dx, dy, dz = (float(t) for t in target)
    l0, l3, lam0, lam5 = p["l0"], p["l3"], p["lambda0"], p["lambda5"]
    c = (dx**2 + dy**2 + dz**2 - lambda2**2 - lam5**2) / (-2 * lambda2 * lam5)
    th3 = float(np.arccos(c)) if abs(c) <= 1 else float("nan")
    C3, S3 = np.cos(theta3), np.sin(theta3)
    lam2 = (dz + lam0 - lam5 * C3 + l3 * S3) / C3 if abs(C3) > 1e-12 else float("nan")
    phi = float(np.arctan2(dy, dx))
    S1, S13, C13 = np.sin(theta1), np.sin(theta1 + theta3), np.cos(theta1 + theta3)
    reach = lambda2 * S1 - l0 + l3 * C13 + lam5 * S13
    return {"phi": phi, "theta3": th3, "lambda2": float(lam2), "x_C": dx - np.cos(phi) * reach,
            "y_C": dy - np.sin(phi) * reach}


# printed numeric transforms, eqs (27)-(31), with the parameters printed beside each (sec 3)
PRINTED = {
    "eq 27": np.array([[1, 2.4493e-15, 0, 0], [-2.4493e-15, 1, 0, 0], [0, 0, 1, 0.15], [0, 0, 0, 1]]),
    "eq 28": np.array([[0.7071, -0.7071, 0, 2], [0.7071, 0.7071, 0, 2], [0, 0, 1, 0.15], [0, 0, 0, 1]]),
    "eq 29": np.array([[0.7071, 0.5, 0.5, 2.8567], [-0.7071, 0.5, 0.5, 2.8567], [0, -0.7071, -0.7071, 1.3305],
                       [0, 0, 0, 1]]),
    "eq 30": np.array([[0.7071, -0.7071, 0, 0], [0.7071, 0.7071, 0, 0], [0, 0, 1, 0.52], [0, 0, 0, 1]]),
    "eq 31": np.array([[0.7071, 0, -0.7071, 0], [0.7071, 0, 0.7071, 0], [0, -1, 0, 0.47], [0, 0, 0, 1]]),
}
"""The 4x4 matrices of eqs (27)-(31) as printed (4 decimals, except eq 27's 2.4493e-15)."""

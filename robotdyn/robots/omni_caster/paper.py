"""Omni caster platform: the paper's closed forms and printed numbers, transcribed (no robotdyn model here).

Paper: J. H. Chung, B.-J. Yi, W. K. Kim, S.-Y. Han, "Singularity-free dynamic modeling including wheel dynamics
for an omni-directional mobile robot with three caster wheels" (Chung, Yi, Kim & Han, ``docs/bibliography.md``):
the chain Jacobians [iG_phi^u] of eqs 12-14 and their inverses [iG_u^phi] of eqs 15-17 (with the erratum of
eq 16 as an option), the Hessian of eqs 18-19, the chain inertia of eq 43, the platform inertia of eq 50, the
operational-space inertia I_uu* of eqs 48/51 and bias of eq 49, the impulse of eq 60, the NOC Jacobians of
eqs A7-A9 and the two I_uu* printed in section 5. Each function takes the parameters as a plain dict
(Table 1-2 names of :data:`.model.SPEC`).
"""

from __future__ import annotations

import numpy as np

_CHAINS = (1, 2, 3)
"""The paper's chain numbers i (Fig. 2: chains 1 and 2 in front, 3 behind)."""


def paper_forward(p: dict, i: int, phi: float) -> np.ndarray:
    """[iG_phi^u] of eq (12)-(14) as printed: u' = G (eta_i', theta_i', phi_i').

    Args:
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).
        i: The chain number 1, 2 or 3 (Fig. 2).
        phi: The chain's steering angle phi_i [rad].

    Returns:
        The 3x3 matrix.
    """
    d, r, a, l, b = p["d"], p["r"], p["a"], p["l"], p["b"]
    s, c = np.sin(phi), np.cos(phi)
    if i == 1:
        return np.array([[-d * s - a, r * c, -a], [-d * c + l / 2, -r * s, l / 2], [1.0, 0.0, 1.0]])
    if i == 2:
        return np.array([[-d * s - a, r * c, -a], [-d * c - l / 2, -r * s, -l / 2], [1.0, 0.0, 1.0]])
    return np.array([[-d * s + b, r * c, b], [-d * c, -r * s, 0.0], [1.0, 0.0, 1.0]])


def paper_inverse(p: dict, i: int, phi: float, corrected: bool = True) -> np.ndarray:
    """[iG_u^phi] of eq (15)-(17): (eta_i', theta_i', phi_i') = G u'.

    Args:
        corrected: Apply the erratum of eq (16), entry (1, 3): the paper prints ``l/2 r cos phi2 - a r sin phi2``;
            the inverse of eq (13) (and the model) give ``-l/2 r cos phi2 - a r sin phi2`` (the chain-2 mirror of
            eq 15, l -> -l). ``False`` returns the matrix as printed.
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).
        i: The chain number 1, 2 or 3 (Fig. 2).
        phi: The chain's steering angle phi_i [rad].

    Returns:
        The 3x3 matrix.
    """
    d, r, a, l, b = p["d"], p["r"], p["a"], p["l"], p["b"]
    s, c = np.sin(phi), np.cos(phi)
    if i == 1:
        G = [[-r * s, -r * c, l / 2 * r * c - a * r * s],
             [d * c, -d * s, l / 2 * d * s + a * d * c],
             [r * s, r * c, d * r + a * r * s - l / 2 * r * c]]
    elif i == 2:
        e13 = (-l / 2 * r * c - a * r * s) if corrected else (l / 2 * r * c - a * r * s)
        G = [[-r * s, -r * c, e13],
             [d * c, -d * s, -l / 2 * d * s + a * d * c],
             [r * s, r * c, d * r + a * r * s + l / 2 * r * c]]
    else:
        G = [[-r * s, -r * c, b * r * s],
             [d * c, -d * s, -b * d * c],
             [r * s, r * c, d * r - b * r * s]]
    return np.array(G) / (d * r)


def paper_chain_inertia(p: dict) -> np.ndarray:
    """[iI_phi_phi*] of eq (43): diag(m2 p^2 + I_z1 + I_z2, 3/2 m1 r^2 + m2 r^2, 0), (eta, theta, phi) order.

    As printed, 3/2 m1 r^2 assumes the wheel's axle inertia is m1 r^2 / 2 (true of Table 2's values).

    Args:
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).

    Returns:
        The diagonal matrix (3, 3), (eta, theta, phi) order [kg m^2].
    """
    m1, m2, r = p["m_wheel"], p["m_link"], p["r"]
    return np.diag([m2 * p["p"] ** 2 + p["I_wheel_diam"] + p["I_link_z"], 1.5 * m1 * r**2 + m2 * r**2, 0.0])


def paper_platform_inertia(p: dict) -> np.ndarray:
    """[pl I_uu*] of eq (50): diag(m_pl, m_pl, m_pl b^2 / 2).

    Args:
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).

    Returns:
        The diagonal matrix (3, 3) [kg, kg, kg m^2].
    """
    return np.diag([p["m_pl"], p["m_pl"], 0.5 * p["m_pl"] * p["b"] ** 2])


def paper_inertia(p: dict, phi) -> np.ndarray:
    """I_uu* of eq (48) with (51): sum_i G_i^T I_phiphi G_i + pl I_uu*, G_i of eq (15)-(17) (corrected (16)).

    Args:
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).
        phi: Steering angles (phi1, phi2, phi3) [rad].

    Returns:
        I_uu* (3, 3) [kg, kg m, kg m^2].
    """
    I = paper_chain_inertia(p)
    out = paper_platform_inertia(p).copy()
    for i in _CHAINS:
        G = paper_inverse(p, i, phi[i - 1])
        out += G.T @ I @ G
    return out


def _dforward_dphi(p: dict, i: int, phi: float) -> np.ndarray:
    """d[iG_phi^u]/d phi_i (the only non-zero plane of the Hessian [iH_phiphi^u], eq 18 and A.1)."""
    d, r = p["d"], p["r"]
    s, c = np.sin(phi), np.cos(phi)
    return np.array([[-d * c, -r * s, 0.0], [d * s, -r * c, 0.0], [0.0, 0.0, 0.0]])


def paper_bias(p: dict, phi, nu, platform_terms: bool = True) -> np.ndarray:
    """u'^T P_uuu* u' of eq (49) with P_phiphiphi* = 0 (eq 43 is constant), [iH_uu^phi] of eq (19).

    The paper does not print the platform's [pl P_uuu*]; with ``platform_terms`` it is taken as the Newton-Euler
    terms of a rigid body in body axes, m_pl (-omega v_cy, omega v_cx, 0) (our reading, see the errata).

    Args:
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).
        phi: Steering angles (phi1, phi2, phi3) [rad].
        nu: The platform twist u' = (v_cx, v_cy, omega) [m/s, m/s, rad/s] in platform axes.
        platform_terms: Include the platform's own velocity products (our reading; the paper prints none).

    Returns:
        The velocity-product forces (3,) [N, N, N m].
    """
    phi = np.asarray(phi, float)
    nu = np.asarray(nu, float)
    I = paper_chain_inertia(p)
    out = np.zeros(3)
    for i in _CHAINS:
        Gu = paper_inverse(p, i, phi[i - 1])
        H = np.zeros((3, 3, 3))  # H[m, j, k] = d G_phi^u[m, j] / d phi_k, joint order (eta, theta, phi)
        H[:, :, 2] = _dforward_dphi(p, i, phi[i - 1])
        Hphi = -np.einsum("nm,mjk,ja,kb->nab", Gu, H, Gu, Gu)  # eq (19)
        phidd = np.einsum("nab,a,b->n", Hphi, nu, nu)  # joint accelerations at u'' = 0
        out += Gu.T @ I @ phidd
    if platform_terms:
        vx, vy, w = nu
        out += p["m_pl"] * np.array([-w * vy, w * vx, 0.0])
    return out


def paper_impulse(I_uu: np.ndarray, n, u_dot, e: float) -> float:
    """Eq (60): F = -(1 + e) u'^T n / (n^T I_uu*^-1 n) (transcribed separately from robotdyn.contact.impulse).

    Args:
        I_uu: The operational-space inertia I_uu* (3, 3).
        n: The impact direction (3,) in the twist's coordinates.
        u_dot: The twist before impact (3,).
        e: Coefficient of restitution (0 to 1).

    Returns:
        The impulse F [N s].
    """
    n = np.asarray(n, float)
    return float(-(1 + e) * np.dot(u_dot, n) / (n @ np.linalg.inv(I_uu) @ n))


# ------------------------------------------------------------------------------- NOC singularity (sec 3.1)
def paper_noc_jacobians(p: dict, phi) -> tuple[np.ndarray, np.ndarray]:
    """J_p (6x6) and J_a (6x3) of eq (A7)-(A8) from the columns ig_j of eq (12)-(14).

    Dependent rates (eta1', phi1', eta2', phi2', eta3', theta3'), independent (theta1', theta2', phi3'), eq (A9).

    Args:
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).
        phi: Steering angles (phi1, phi2, phi3) [rad].

    Returns:
        ``(J_p, J_a)``: (6, 6) and (6, 3).
    """
    g = {i: paper_forward(p, i, phi[i - 1]) for i in _CHAINS}
    z = np.zeros(3)
    Jp = np.block([[g[1][:, [0]], g[1][:, [2]], -g[2][:, [0]], -g[2][:, [2]], z[:, None], z[:, None]],
                   [g[1][:, [0]], g[1][:, [2]], z[:, None], z[:, None], -g[3][:, [0]], -g[3][:, [1]]]])
    Ja = np.block([[-g[1][:, [1]], g[2][:, [1]], z[:, None]], [-g[1][:, [1]], z[:, None], g[3][:, [2]]]])
    return Jp, Ja


def paper_noc_map(p: dict, phi) -> np.ndarray:
    """K with (theta1', theta2', phi3') = K u': rows theta of eq (15), theta of eq (16), phi of eq (17).

    The NOC model exists iff K is invertible (equivalently det J_p != 0); then its inertia is
    K^-T I_uu* K^-1 (the same kinetic energy in other velocities).

    Args:
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).
        phi: Steering angles (phi1, phi2, phi3) [rad].

    Returns:
        K (3, 3).
    """
    return np.vstack([paper_inverse(p, 1, phi[0])[1], paper_inverse(p, 2, phi[1])[1], paper_inverse(p, 3, phi[2])[2]])


PRINTED_WITH_WHEELS = np.array([[5.4329, 0.0537, -0.00078], [0.0537, 7.5379, 0.0107], [-0.00078, 0.0107, 0.0397]])
"""The with-wheel I_uu* printed in section 5 "at a configuration" (no configuration given)."""
PRINTED_NO_WHEELS = np.diag([5.0, 5.0, 0.025])
"""The no-wheel I_uu* printed in section 5."""

"""Omnidirectional platform on three active caster wheels (Chung, Yi, Kim, Han): the model side.

Description: ``urdf/omni_caster.urdf.xacro`` (Fig. 2, Tables 1-2); Pinocchio derives the dynamics from it.
Paper the parameters and manoeuvres come from: J. H. Chung, B.-J. Yi, W. K. Kim, S.-Y. Han, "Singularity-free
dynamic modeling including wheel dynamics for an omni-directional mobile robot with three caster wheels"
(Chung, Yi, Kim & Han, ``docs/bibliography.md``).

Coordinates: (x, y, psi) of the platform centre C and heading (world, m and rad), the steering angles phi_i
(platform relative to offset link i, eq 9-11: omega = eta_i' + phi_i') and the wheel angles theta_i.
Minimal velocities: the platform twist in BODY axes, u' = (v_cx, v_cy, omega) of eq (2) -- eq (6)-(8) write v_c in
the platform's unit vectors i, j -- through :mod:`robotdyn.reduction.operational_space`, so that the reduced inertia is the
paper's operational-space inertia I_uu* (eq 48) and the reduced bias its u'^T P_uuu* u' (eq 49).
Each wheel rolls without slipping (both tangential rows) and touches the floor; the 9 rows have rank 6 (the normal
rows vanish on the plane) and the mobility is 3 (Grubler count of section 2).

This module holds ``SPEC`` (Tables 1-2), the paper's NOC coordinates as a second spec (eq A9), the section-5
trajectories (eq 61) and their feed-forward scenarios, the impulse study of Figs. 16-19 on the model (eq 60 is
:func:`robotdyn.contact.impulse.impact`) and the ``impulse`` CLI subcommand. The paper's closed forms (eqs 12-19, 43,
48-51, 60, A7-A9) are in :mod:`robotdyn.robots.omni_caster.paper`, the comparison in :mod:`robotdyn.robots.omni_caster.comparison`.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from ...errors import InputError, SingularConstraintError
from ...reduction.operational_space import OperationalVelocities
from ...robot import MotorSpec, Parameter, Robot, RobotSpec, Wheel
from ...simulation.scenario import Scenario


CHAINS = (1, 2, 3)
NU_NAMES = ["v_cx", "v_cy", "omega"]

SPEC = RobotSpec(
    name="omni_caster",
    title="Omnidirectional platform on three active caster wheels (Chung, Yi, Kim, Han)",
    xacro="omni_caster.urdf.xacro",
    root="planar",
    paper=("Chung, Yi, Kim & Han, Singularity-free dynamic modeling including wheel dynamics "
           "for an omni-directional mobile robot with three caster wheels"),
    parameters=[
        Parameter("l", 0.173, "m", "distance A1A2 between the front steering axes (Table 1)", positive=True),
        Parameter("a", 0.05, "m", "A1, A2 lie a behind C along -j (Table 1, eq 6-7; an offset: 0 or < 0 valid)"),
        Parameter("b", 0.1, "m", "distance C A3 and platform radius (Table 1, eq 8, 50)", positive=True),
        Parameter("h", 0.045, "m", "height of the steering joint above the wheel centre (Table 1, eq 6; an offset: any sign)"),
        Parameter("d", 0.025, "m", "caster offset, steering axis to wheel centre (Table 1)", positive=True),
        Parameter("r", 0.025, "m", "wheel radius (Table 1)", positive=True),
        Parameter("m_pl", 5.0, "kg", "platform mass (from the printed diag(5, 5, 0.025) = eq 50; Table 2 garbled)",
                  positive=True),
        Parameter("m_wheel", 0.5, "kg", "mass of each wheel (Table 2)"),
        Parameter("I_wheel_axle", 1.5625e-4, "kg m^2", "wheel inertia about its axle (Table 2)"),
        Parameter("I_wheel_diam", 0.7813e-4, "kg m^2", "wheel inertia about a diameter, incl. the vertical (Table 2)"),
        Parameter("m_link", 0.025, "kg", "mass of each offset steering link (Table 2 as printed)"),
        Parameter("p", 0.0125, "m", "wheel centre to link mass centre, towards A_i (eq 37; not printed: d/2; 0 is valid: mass centre on the axle)"),
        Parameter("I_link_x", 8.438e-6, "kg m^2", "link central inertia about its x (A_i -> O_i) (Table 2)"),
        Parameter("I_link_y", 11.042e-6, "kg m^2", "link central inertia about its y (axle direction) (Table 2)"),
        Parameter("I_link_z", 2.604e-6, "kg m^2", "link central inertia about the vertical (Table 2)"),
    ],
    wheels=[Wheel(f"wheel_link_{i}", "r", name=f"wheel_{i}") for i in CHAINS],
    motors=[MotorSpec(f"drive_{i}", f"wheel_{i}") for i in CHAINS] + [MotorSpec(f"steer_{i}", f"steer_{i}") for i in CHAINS],
    labels={**{f"steer_{i}": f"phi{i}" for i in CHAINS}, **{f"wheel_{i}": f"theta{i}" for i in CHAINS}},
    operational=OperationalVelocities("platform", ("vx", "vy", "wz"), "local", NU_NAMES),
)

NOC_INDEPENDENT = ["theta1", "theta2", "phi3"]
"""The paper's independent joint set of the natural orthogonal complement, eq (A9)."""

NO_WHEELS = {"m_wheel": 0.0, "I_wheel_axle": 0.0, "I_wheel_diam": 0.0, "m_link": 0.0, "I_link_x": 0.0,
             "I_link_y": 0.0, "I_link_z": 0.0}
"""Parameter overrides that switch the wheel dynamics off (wheels and offset links massless)."""


def noc_spec() -> RobotSpec:
    """The same robot with the paper's NOC minimal coordinates (theta1', theta2', phi3'), eq (A9).

    Returns:
        The new :class:`~robotdyn.robot.RobotSpec` (``SPEC`` is not changed).
    """
    return dataclasses.replace(SPEC, operational=None, independent=list(NOC_INDEPENDENT))


def steering_configuration(robot: Robot, phi, psi: float = 0.0, x: float = 0.0, y: float = 0.0) -> np.ndarray:
    """Natural coordinates with the given steering angles (phi1, phi2, phi3) [rad], wheel angles zero.

    Args:
        robot: The omni caster :class:`~robotdyn.robot.Robot` (operational velocities: the platform twist).
        phi: Steering angles (phi1, phi2, phi3) [rad].
        psi: Platform heading [rad].
        x: Platform x [m].
        y: Platform y [m].

    Returns:
        Natural coordinates (n,).
    """
    phi = np.asarray(phi, float)
    if phi.shape != (3,) or not np.all(np.isfinite(phi)):
        raise InputError(f"steering angles {phi.tolist()}; expected 3 finite angles (phi1, phi2, phi3) in rad")
    q = robot.neutral()
    for label, value in (("x", x), ("y", y), ("psi", psi)):
        q[robot.coordinate_index(label)] = value
    for i in CHAINS:
        q[robot.coordinate_index(f"phi{i}")] = phi[i - 1]
    return q


def _anchor(p: dict, i: int) -> tuple[float, float]:
    """(x, y) components of the vector A_iC (eq 6-8) in platform axes."""
    return {1: (p["l"] / 2, p["a"]), 2: (-p["l"] / 2, p["a"]), 3: (0.0, -p["b"])}[i]


def noc_report(robot: Robot, noc: Robot, phi) -> dict:
    """Both formulations at one steering configuration: condition numbers and reduced inertias (NaN-free).

    Args:
        robot: The omni caster :class:`~robotdyn.robot.Robot` (operational velocities: the platform twist).
        noc: The same robot in the paper's NOC coordinates (:func:`noc_spec`).
        phi: Steering angles (phi1, phi2, phi3) [rad].

    Returns:
        dict with ``phi``, ``op_M`` (I_uu*, always finite), ``op_condition``, ``noc_M`` (``None`` when the NOC
        projection refuses), ``noc_condition`` and ``noc_error`` (the one-line message, or ``None``).
    """
    q = steering_configuration(robot, phi)
    red = robot.reduced(q, np.zeros(3))
    out = {"phi": np.asarray(phi, float), "op_M": red.M, "op_condition": red.projection.condition,
           "noc_M": None, "noc_condition": float("inf"), "noc_error": None}
    try:
        rn = noc.reduced(steering_configuration(noc, phi), np.zeros(3))
        out["noc_M"], out["noc_condition"] = rn.M, rn.projection.condition
    except SingularConstraintError as exc:
        out["noc_error"], out["noc_condition"] = str(exc), exc.condition
    return out


# ------------------------------------------------------------------------------------ trajectories (sec 5)
CIRCLE = {"R": 5.0, "T": 60.0}
"""Section 5: circular path of radius 5 m in 60 s (Figs. 5-12)."""
ELLIPSE = {"A": 3.0, "B": 1.0, "T": 30.0, "heading": "tangent"}
"""Section 5: elliptic path with radii 3 m and 1 m in 30 s (Figs. 13-15); heading ``"tangent"`` (j along the
path) or ``"fixed"`` (pure translation, psi = 0): the paper does not say which."""


def beta_profile(t, T: float, total: float = 2 * np.pi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eq (61): beta(t) = a3 t^3 + a4 t^4 + a5 t^5, rest to rest from 0 to ``total`` in T s.

    With total = 2 pi and T = 60 s the coefficients are the paper's a3 = 20 pi / 60^3, a4 = -30 pi / 60^4,
    a5 = 12 pi / 60^5. Returns (beta, beta', beta'') [rad, rad/s, rad/s^2]; constant outside [0, T].

    Args:
        t: Time(s) [s].
        T: Duration of the motion [s].
        total: Total angle [rad].

    Returns:
        ``(beta, beta', beta'')`` at the times given [rad, rad/s, rad/s^2], each shaped like t.
    """
    s = np.clip(np.asarray(t, float) / T, 0.0, 1.0)
    inside = (np.asarray(t, float) >= 0) & (np.asarray(t, float) <= T)
    b = total * (10 * s**3 - 15 * s**4 + 6 * s**5)
    bd = total * (30 * s**2 - 60 * s**3 + 30 * s**4) / T * inside
    bdd = total * (60 * s - 180 * s**2 + 120 * s**3) / T**2 * inside
    return b, bd, bdd


def path_state(kind: str, t, params: dict | None = None) -> dict:
    """Prescribed platform motion of section 5 at time(s) t.

    Assumptions (the paper leaves them open; Fig. 5 is not legible): the platform moves along its own +j axis
    (the printed with-wheel inertia, large in y, implies wheels rolling along j), counter-clockwise, from the
    origin with heading psi = 0; on the circle i points radially outward and psi = beta (the paper: "beta, the
    angle between the global X-axis and the local unit vector i"), centre (-R, 0); on the ellipse
    C = (A (cos beta - 1), B sin beta), beta from eq (61) with T = 30 s, and either j along the tangent
    (``heading="tangent"``, psi = tangent angle - pi/2, default) or a fixed heading psi = 0 (``"fixed"``).

    Args:
        kind: ``circle`` or ``ellipse``.
        t: Time(s) [s].
        params: Overrides of the path's constants (:data:`CIRCLE` or :data:`ELLIPSE`: R, A, B [m], T [s], heading)
            (default ``None``).

    Returns:
        dict with ``pose`` (x, y, psi), ``nu`` = u' = (v_cx, v_cy, omega) in body axes and ``nudot`` = u''
        (time derivative of the body components), each (..., 3).
    """
    t = np.asarray(t, float)
    if kind == "circle":
        c = {**CIRCLE, **(params or {})}
        R = c["R"]
        b, bd, bdd = beta_profile(t, c["T"])
        pose = np.stack([-R + R * np.cos(b), R * np.sin(b), b], axis=-1)
        nu = np.stack([0 * b, R * bd, bd], axis=-1)
        nudot = np.stack([0 * b, R * bdd, bdd], axis=-1)
    elif kind == "ellipse":
        c = {**ELLIPSE, **(params or {})}
        A, B = c["A"], c["B"]
        b, bd, bdd = beta_profile(t, c["T"])
        sb, cb = np.sin(b), np.cos(b)
        if c["heading"] == "fixed":
            z = 0 * b
            pose = np.stack([A * (cb - 1), B * sb, z], axis=-1)
            nu = np.stack([-A * sb * bd, B * cb * bd, z], axis=-1)
            nudot = np.stack([-A * cb * bd**2 - A * sb * bdd, -B * sb * bd**2 + B * cb * bdd, z], axis=-1)
            return {"pose": pose, "nu": nu, "nudot": nudot}
        if c["heading"] != "tangent":
            raise InputError(f"ellipse heading {c['heading']!r}; expected 'tangent' or 'fixed'")
        q2 = A**2 * sb**2 + B**2 * cb**2
        speed = np.sqrt(q2)  # ds/dbeta
        dspeed = (A**2 - B**2) * sb * cb / speed
        kappa = A * B / q2  # dpsi/dbeta
        dkappa = -A * B * 2 * (A**2 - B**2) * sb * cb / q2**2
        tangent = np.unwrap(np.arctan2(B * cb, -A * sb), axis=-1) if b.ndim else np.arctan2(B * cb, -A * sb)
        psi = tangent - np.pi / 2
        pose = np.stack([A * (cb - 1), B * sb, psi], axis=-1)
        nu = np.stack([0 * b, speed * bd, kappa * bd], axis=-1)
        nudot = np.stack([0 * b, dspeed * bd**2 + speed * bdd, dkappa * bd**2 + kappa * bdd], axis=-1)
    else:
        raise InputError(f"unknown path {kind!r}; expected 'circle' or 'ellipse'")
    return {"pose": pose, "nu": nu, "nudot": nudot}


def steady_steering(p: dict, u, trailing: bool = True) -> np.ndarray:
    """Steering angles (phi1, phi2, phi3) [rad] at which every steering rate vanishes for the body twist u.

    Geometry (independent of the model's Jacobians): the wheel centre O_i = A_i + d e_i must move along e_i
    (e_i the unit vector A_i -> O_i, at angle -phi_i in platform axes), i.e. (v_A x e)_z = omega d. ``trailing``
    picks the root with the wheel behind its steering axis (a passive caster's stable alignment).

    Args:
        p: The parameters as a plain dict, by the names of Tables 1-2 (:data:`.model.SPEC`: d, r, a, l, b, p [m];
            m_wheel, m_link, m_pl [kg]; inertias [kg m^2]).
        u: The platform twist u' = (v_cx, v_cy, omega) [m/s, m/s, rad/s] in platform axes.
        trailing: Pick the root with the wheel behind its steering axis.

    Returns:
        Steering angles (phi1, phi2, phi3) [rad].
    """
    vx, vy, w = np.asarray(u, float)
    out = np.zeros(3)
    for i in CHAINS:
        ax, ay = _anchor(p, i)
        Ax, Ay = -ax, -ay  # A_i in platform axes (A_iC = -A_i)
        vA = np.array([vx - w * Ay, vy + w * Ax])
        speed = np.hypot(*vA)
        if speed <= abs(w) * p["d"]:
            raise InputError(f"no steady steering for caster {i}: |v_A| = {speed:.3g} <= |omega| d; the "
                             "instantaneous centre lies inside the caster's circle")
        gamma = np.arctan2(vA[1], vA[0])
        delta = np.arcsin(w * p["d"] / speed)
        alpha = gamma + np.pi - delta if trailing else gamma + delta
        out[i - 1] = np.angle(np.exp(-1j * alpha))
    return out


def plan(robot: Robot, kind: str, n: int = 301, params: dict | None = None, rtol: float = 1e-10,
         t_end: float | None = None) -> dict:
    """The section-5 manoeuvre integrated through the model's kinematics (the paper integrates eq 15-17).

    Initial steering: :func:`steady_steering` for the body twist direction at t = 0+ (the circle's then stays
    constant: the paper's "keeps the original configuration"). q' = S(q) u'(t) is integrated with
    ``solve_ivp`` (DOP853); the platform pose that results must equal the prescribed one (checked in the tests).

    Args:
        robot: The omni caster :class:`~robotdyn.robot.Robot` (operational velocities: the platform twist).
        kind: ``circle`` or ``ellipse``.
        n: Number of output samples.
        params: Overrides of the path's constants (as :func:`path_state`).
        rtol: Integrator tolerance (relative and absolute).
        t_end: Stop at this time [s] (default ``None``: the path's T).

    Returns:
        dict with ``t`` (n,), ``q`` (n, nq), ``nu``, ``nudot`` (n, 3), ``pose`` (n, 3, prescribed), ``sol`` (dense).
        ``t_end`` (default T) stops early (a section of the manoeuvre).
    """
    from scipy.integrate import solve_ivp

    c = {**(CIRCLE if kind == "circle" else ELLIPSE), **(params or {})}
    T = c["T"]
    direction = path_state(kind, 0.5 * T, params)["nu"]
    if kind == "ellipse":  # direction of the twist at the start (curvature A/B^2 at beta = 0)
        direction = np.array([0.0, c["B"], c["A"] / c["B"] if c["heading"] == "tangent" else 0.0])
    q0 = steering_configuration(robot, steady_steering(robot.params, direction))

    def rhs(t, q):
        return robot.operational.projection(robot, q).S @ path_state(kind, t, params)["nu"]

    t_end = T if t_end is None else t_end
    sol = solve_ivp(rhs, (0.0, t_end), q0, method="LSODA", rtol=rtol, atol=rtol, dense_output=True)
    t = np.linspace(0.0, t_end, n)
    st = path_state(kind, t, params)
    return {"t": t, "q": sol.sol(t).T, "nu": st["nu"], "nudot": st["nudot"], "pose": st["pose"], "sol": sol,
            "kind": kind, "params": c}


def operational_forces(robot: Robot, pl: dict) -> np.ndarray:
    """Eq (47) along a plan: T_u = I_uu* u'' + u'^T P_uuu* u' (F_x, F_y [N], M_z [N m]) at each sample (n, 3).

    Args:
        robot: The omni caster :class:`~robotdyn.robot.Robot` (operational velocities: the platform twist).
        pl: A :func:`plan`.

    Returns:
        The forces (n, 3): F_x, F_y [N], M_z [N m] per sample.
    """
    out = np.zeros((len(pl["t"]), 3))
    for k in range(len(pl["t"])):
        red = robot.reduced(pl["q"][k], pl["nu"][k])
        out[k] = red.M @ pl["nudot"][k] + red.h
    return out


def kinetic_energy(robot: Robot, q: np.ndarray, nu: np.ndarray) -> float:
    """Kinetic energy [J] of the whole mechanism (Pinocchio, full velocities v = S nu).

    Args:
        robot: The omni caster :class:`~robotdyn.robot.Robot` (operational velocities: the platform twist).
        q: Natural coordinates (n,) [m, rad].
        nu: The platform twist u' = (v_cx, v_cy, omega) [m/s, m/s, rad/s] in platform axes.

    Returns:
        The kinetic energy [J].
    """
    return robot.energy(q, robot.reduced(q, nu).v) - robot.energy(q, np.zeros(robot.nq))


def wheel_mass_params(total: float, m_pl: float) -> dict:
    """Parameters for the paper's sweep: three wheels of total mass ``total`` (each a disc of radius r:
    axle inertia m r^2 / 2, diametral m r^2 / 4 -- Table 2's values at 0.5 kg), platform mass ``m_pl``;
    offset links as Table 2.

    Args:
        total: Total mass of the three wheels [kg].
        m_pl: Platform mass [kg].

    Returns:
        Parameter values by name.
    """
    r = SPEC.parameter("r").default
    m = total / 3.0
    return {"m_pl": m_pl, "m_wheel": m, "I_wheel_axle": m * r**2 / 2, "I_wheel_diam": m * r**2 / 4}


class PathScenario(Scenario):
    """A section-5 path followed by feed-forward motor torques (inverse dynamics of the model, eq 47).

    The six motors (three drives, three steering) produce T_u = B_r tau; tau is the least-squares (minimum-norm)
    solution of B_r(q) tau = I_uu*(q) u''(t) + u'^T P_uuu*(q) u' at the simulated state, so the platform
    twist follows the plan while the casters self-align kinematically. Initial steering: :func:`steady_steering`.

    Args:
        kind: ``circle`` or ``ellipse`` (also the scenario's name).
        description: One line, citing the paper's section.
        t_end: Default duration [s].
    """

    def __init__(self, kind: str, description: str, t_end: float) -> None:
        super().__init__(kind, description, t_end, plot=list(NU_NAMES))
        self.kind = kind

    def initial_state(self, robot) -> tuple[np.ndarray, np.ndarray]:
        c = CIRCLE if self.kind == "circle" else ELLIPSE
        u = np.array([0.0, c["R"], 1.0]) if self.kind == "circle" else np.array([0.0, c["B"], c["A"] / c["B"]])
        return steering_configuration(robot, steady_steering(robot.params, u)), np.zeros(3)

    def torque_law(self, robot):
        """tau(t, q, nu) for ``robot``.

        Args:
            robot: The omni caster :class:`~robotdyn.robot.Robot` (operational velocities: the platform twist).

        Returns:
            tau(t, q, nu) [N m], one per motor.
        """
        if self.kind == "circle":  # u'' = (0, R, 1) beta''(t), a cubic in t on [0, T]: computed torque as data
            return circle_law(robot)
        return ellipse_law(robot)  # u''(t) fitted piecewise to rounding: computed torque as data

    def run(self, robot, t_end: float | None = None, n_out: int | None = None, **kwargs):
        from ...simulation import simulate
        from ...simulation.feedback import FeedbackLaw

        t_end, n_out = self.span(t_end, n_out, streamed=kwargs.get("sink") is not None)
        q0, nu0 = self.initial_state(robot)
        law = self.torque_law(robot)
        if not isinstance(law, FeedbackLaw) or kwargs.get("engine") == "scipy":
            kwargs.setdefault("method", "LSODA")  # the scipy engine's stiff-capable default for these paths
        kwargs.setdefault("rtol", 1e-9)
        kwargs.setdefault("atol", 1e-9)
        return simulate(robot, t_end, q0, nu0, law, n_out=n_out, **kwargs)


def circle_law(robot: Robot, params: dict | None = None):
    """The circle's feed-forward torques tau = B_r^+ (I_uu* u''(t) + u'^T P_uuu* u') (eq 47, minimum-norm) as a
    :class:`~robotdyn.simulation.feedback.FeedbackLaw` (it runs compiled): u''(t) = (0, R, 1) beta''(t) with
    beta'' = total (60 s - 180 s^2 + 120 s^3) / T^2, s = t / T (eq 61), a cubic polynomial in t on [0, T].

    Args:
        robot: The omni caster :class:`~robotdyn.robot.Robot`.
        params: Overrides of :data:`CIRCLE` (R [m], T [s]) (default ``None``).

    Returns:
        The :class:`~robotdyn.simulation.feedback.FeedbackLaw` (motor torques [N m] against time and state).
    """
    from ...simulation.feedback import FeedbackLaw
    from ...simulation.torque_profile import Polynomial

    c = {**CIRCLE, **(params or {})}
    R, T, total = c["R"], c["T"], 2 * np.pi
    powers = total * np.array([0.0, 60.0 / T**3, -180.0 / T**4, 120.0 / T**5])
    return FeedbackLaw(acceleration=Polynomial(np.outer(powers, [0.0, R, 1.0]), 0.0, T), robot=robot)


ELLIPSE_FIT = {"pieces": 120, "degree": 13}
"""Pieces and degree of :func:`ellipse_law`'s fit of u''(t): 120 pieces of 0.25 s, degree 13, reach 2e-14 rad/s^2
(about 3e-14 of max abs(u'') = 0.84 m/s^2)."""


def ellipse_law(robot: Robot, params: dict | None = None):
    """The ellipse's feed-forward torques tau = B_r^+ (I_uu* u''(t) + u'^T P_uuu* u') (eq 47, minimum-norm) as a
    :class:`~robotdyn.simulation.feedback.FeedbackLaw` (it runs compiled): u''(t) of :func:`path_state` (a smooth
    function of beta(t) of eq 61, neither a polynomial nor a sine of t) on [0, T] as a
    :class:`~robotdyn.simulation.torque_profile.PiecewisePolynomial` fit (:data:`ELLIPSE_FIT`), checked to 1e-12 of
    max abs(u'') against :func:`path_state` (``fit_error`` on the profile: about 2e-14).

    Args:
        robot: The omni caster :class:`~robotdyn.robot.Robot`.
        params: Overrides of :data:`ELLIPSE` (A, B [m], T [s], heading) (default ``None``).

    Returns:
        The :class:`~robotdyn.simulation.feedback.FeedbackLaw` (motor torques [N m] against time and state).
    """
    from ...simulation.feedback import FeedbackLaw

    c = {**ELLIPSE, **(params or {})}
    return FeedbackLaw(acceleration=_ellipse_fit(tuple(sorted(c.items()))), robot=robot)


@functools.lru_cache(maxsize=8)
def _ellipse_fit(constants: tuple):
    """:func:`ellipse_law`'s fit of u''(t) for the path constants ``constants`` (sorted (name, value) pairs of
    :data:`ELLIPSE`), made once per set (profiles are not changed after construction)."""
    from ...simulation.torque_profile import PiecewisePolynomial

    c = dict(constants)
    return PiecewisePolynomial.fit(lambda t: path_state("ellipse", t, c)["nudot"], 0.0, c["T"], **ELLIPSE_FIT)


SCENARIOS = {
    "circle": PathScenario("circle", "sec 5: circle R = 5 m in 60 s, beta of eq 61, feed-forward torques "
                           "(inverse dynamics), body moving along +j", CIRCLE["T"]),
    "ellipse": PathScenario("ellipse", "sec 5: ellipse 3 m x 1 m in 30 s, beta of eq 61, feed-forward torques, "
                            "j along the tangent", ELLIPSE["T"]),
}


# ------------------------------------------------------------------------------------ impulse (sec 4, Figs 16-19)
IMPULSE_CONFIGS = {"fig16": (0.0, 0.0, 0.0), "fig17": (45.0, 45.0, 45.0), "fig18": (240.0, 120.0, 0.0),
                   "fig19": (60.0, 135.0, 315.0)}
"""Steering angles (phi1, phi2, phi3) [deg] of Figs. 16-19."""
RESTITUTION = 0.8
"""Coefficient of restitution of section 5's impulse study."""


def impulse_ellipses(robot: Robot, e: float = RESTITUTION, speed: float = 1.0, samples: int = 361) -> dict:
    """The impulse curves of Figs. 16-19: :math:`|F(a)|` for unit-speed head-on impacts of the platform centre.

    Args:
        robot: The omni caster :class:`~robotdyn.robot.Robot` (operational velocities: the platform twist).
        e: Coefficient of restitution (0 to 1).
        speed: Approach speed [m/s].
        samples: Number of directions over [0, 2 pi].

    Returns:
        {figure: (angles [rad], magnitudes [N s])} for :data:`IMPULSE_CONFIGS`.
    """
    from ...contact.impulse import impulse_curve

    out = {}
    for name, deg in IMPULSE_CONFIGS.items():
        M = robot.reduced(steering_configuration(robot, np.radians(deg)), np.zeros(3)).M
        out[name] = impulse_curve(M, e, speed, (0, 1), samples)
    return out


def _cmd_impulse(args) -> int:
    from ...cli.commands import _emit, _load
    from ...contact.impulse import impact
    from ...inputs import as_vector

    _, robot = _load(args)
    q = robot.check_q(args.q)
    robot.check_constraints(q)
    n = as_vector(args.direction, robot.mobility, "--direction", robot.velocity_names)
    red = robot.reduced(q, np.zeros(robot.mobility))
    from ...inputs import MAX_VELOCITY, refuse_together

    refuse_together(args, "v", "speed")
    if args.v is not None:
        nu = robot.check_nu(args.v, "--v")
    else:
        args.speed = 1.0 if args.speed is None else args.speed
        if not (np.isfinite(args.speed) and 0 < args.speed <= MAX_VELOCITY):
            raise InputError(f"--speed {args.speed:g}; expected a positive speed <= {MAX_VELOCITY:g} m/s")
        nn = np.linalg.norm(n)
        nu = (-args.speed * n / nn if nn > 0 else n) + 0.0  # + 0.0: no negative zeros in the output
    res = impact(red.M, n, nu, args.e)
    names = robot.velocity_names
    out = {"robot": args.robot, "q": q, "direction": res.direction, "e": args.e, "nu_before": nu,
           "impulse": res.magnitude, "effective_mass": res.effective_mass, "delta_nu": res.delta_nu,
           "nu_after": res.nu_after, "normal_before": res.normal_before, "normal_after": res.normal_after}
    text = [f"impulse along n = ({', '.join(f'{x:.6g}' for x in res.direction)}) in ({', '.join(names)}), "
            f"e = {args.e:g} (Chung et al. eq 60):",
            f"  F = {res.magnitude:.10g} N s   (effective mass {res.effective_mass:.10g} kg)",
            f"  normal velocity {res.normal_before:.6g} -> {res.normal_after:.6g}",
            *(f"  {nm:>8}: {a: .8g} -> {b: .8g}  (jump {c: .8g})"
              for nm, a, b, c in zip(names, nu, res.nu_after, res.delta_nu))]
    _emit(args, out, "\n".join(text))
    return 0


def register_cli(subparsers, parents) -> None:
    """``robotdyn impulse ROBOT --q ... --direction ... [--e 0.8] [--speed 1 | --v ...]``.

    Args:
        subparsers: The CLI's subparsers (``argparse`` action).
        parents: Parsers whose arguments it inherits (the common and robot arguments).
    """
    p = subparsers.add_parser("impulse", parents=parents,
                              help="impulse of a frictionless impact on a fixed surface (eq 60 of Chung et al.)")
    p.add_argument("--q", nargs="+", required=True, help="natural coordinates, in the order info lists them")
    p.add_argument("--direction", nargs="+", required=True,
                   help="surface normal n in the minimal coordinates (pointing from the surface to the robot)")
    p.add_argument("--e", type=float, default=RESTITUTION, help="coefficient of restitution (default 0.8)")
    p.add_argument("--speed", type=float, default=None, help="head-on approach speed along -n (default 1)")
    p.add_argument("--v", nargs="+", help="velocity before impact in the minimal coordinates (instead of --speed)")
    p.set_defaults(func=_cmd_impulse)

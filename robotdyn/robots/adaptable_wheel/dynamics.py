"""Adaptable-wheel tricycle: the full model driven along the section-7 missions (beyond the paper).

The paper stops at kinematics and statics; here the model of :mod:`robotdyn.robots.adaptable_wheel.model` follows the missions of
:mod:`robotdyn.robots.adaptable_wheel.missions` (the body's pose from the paper's IK, eqs 4-6 and 18-23) and Pinocchio's RNEA gives the motor
torques with inertia (:func:`mission_dynamics`, contact forces chosen as in eqs 28-30), or the wheels slide sideways
under a friction law (:func:`mission_friction`). Both report the paper's eq 35 and eqs 25-34 beside the model's
torques. Discussion: ``docs/errata/adaptable_wheel.md``
(Mardani & Ebrahimi 2016, ``docs/bibliography.md``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...reduction.actuation import input_matrix
from ...constraints.constraint import KinematicState
from ...errors import InputError
from ...constraints.joint_coupling import JointCoupling
from ...robot import Robot
from ...constraints.terrain import Terrain
from .comparison import euler_zyx, model_configuration
from .missions import IKRun
from .model import SPEC, WHEELS
from .paper import Commands, body_pose, paper_torque_eq35, solve_ik, static_torques


_BODY = ("x", "y", "z", "yaw", "pitch", "roll")


def _commands_at(run: IKRun, t: float) -> Commands:
    """The commands at any time t in the run's interval, q_zd continued from the nearest step (eqs 18-23 with a
    body of constant roll/pitch command: the yaw changes exactly as the path angle)."""
    m = run.mission
    i = int(np.clip(round(t / m.dt), 0, len(run.t) - 1))
    xd, yd, vx, vy = m.path(t)
    _, _, vx0, vy0 = m.path(run.t[i])
    change = (np.arctan2(vy, vx) - np.arctan2(vy0, vx0) + np.pi) % (2 * np.pi) - np.pi
    return Commands(xd, yd, m.h, m.qx(t), m.qy(t), run.yaw[i] + change)


def body_coordinates(run: IKRun, t: float, terrain: Terrain) -> np.ndarray:
    """(x, y, z, yaw, pitch, roll) of the body at time t from the commands (eqs 4-6).

    Args:
        run: An :class:`~robotdyn.robots.adaptable_wheel.missions.IKRun`.
        t: Time [s] in the run's interval.
        terrain: The surface (a :class:`~robotdyn.constraints.terrain.Terrain`).

    Returns:
        The array (6,): position (x, y, z) [m] in the world frame, then (yaw, pitch, roll) [rad].
    """
    R, d = body_pose(_commands_at(run, t), terrain)
    return np.concatenate([d, euler_zyx(R)])


@dataclass
class DynamicsRun:
    """Adjustment and wheel torques along a mission from the full model (kinetostatics with Pinocchio's RNEA).

    Attributes:
        t: (N,) times [s].
        tau_dynamic: (N, 6) motor torques with inertia (spin fr, fl, r, adjust fr, fl, r) [N m].
        tau_static: (N, 3) adjustment torques of eqs 25-34 at the same configurations (no inertia) [N m].
        tau_eq35: (N, 3) eq 35 [N m].
        normal_dynamic: (N, 3) normal contact forces with inertia [N].
        ratio_dynamic: (N, 3) friction use with inertia.
        lateral_slip: (N, 3) lateral sliding speed of each wheel's material contact point [m/s] (what rolling
            without slipping would forbid).
        qdot_model, qdot_fd: (N, 3) adjustment rates from the constraint layer (S nu) and from finite
            differences of the IK in time [rad/s].
        residual: (N,) residual of the model's generalised force balance [N, N m].
    """

    t: np.ndarray
    tau_dynamic: np.ndarray
    tau_static: np.ndarray
    tau_eq35: np.ndarray
    normal_dynamic: np.ndarray
    ratio_dynamic: np.ndarray
    lateral_slip: np.ndarray
    qdot_model: np.ndarray
    qdot_fd: np.ndarray
    residual: np.ndarray


def _derivatives(f: Callable[[float], np.ndarray], t: float, h: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """First and second derivatives by five-point central differences (truncation O(h^4))."""
    f2, f1, f0, g1, g2 = (f(t + k * h) for k in (-2, -1, 0, 1, 2))
    d1 = (f2 - 8 * f1 + 8 * g1 - g2) / (12 * h)
    d2 = (-f2 + 16 * f1 - 30 * f0 + 16 * g1 - g2) / (12 * h * h)
    return d1, d2


class MissionModel:
    """The full model along a kinematic mission: states from the IK and the constraint layer, torques from RNEA.

    The body follows the commanded pose (eqs 4-6, 18-23); the constraint layer (rolling rows without the lateral
    one, and the eq-1 couplings) gives the full velocity v = S(q) nu and acceleration a = S nu' + w for the body
    velocities nu (five-point differences of the commanded pose); Pinocchio's RNEA gives the generalised forces
    :math:`\\tau_{RNEA}(q, v, a)`. Its six root rows are the wrench the contacts must supply (weight plus inertial
    forces: eq 25 with inertia); the contact forces are chosen as in eqs 28-30
    (:func:`robotdyn.contact.statics.solve_contact_forces`); the remaining rows give the six motor torques and the three
    coupling forces by least squares (residual reported).

    Args:
        run: An :class:`IKRun` (its mission fixes the terrain).
        params: Parameter overrides (e.g. ``m_wheel``, ``I_adjust``).
        run: An :class:`~robotdyn.robots.adaptable_wheel.missions.IKRun` (its mission fixes the terrain).
        params: Parameter overrides (default ``None``).
    """

    def __init__(self, run: IKRun, params: dict | None = None) -> None:
        p = {**(params or {}), "terrain": run.mission.terrain}
        self.run = run
        self.rolling = Robot(SPEC, {**p, "lateral": "rolling"})
        self.slip = Robot(SPEC, {**p, "lateral": "slip"})
        self.p = self.slip.params
        self.body = np.array([self.slip.coordinate_index(c) for c in _BODY])
        self.adjust = np.array([self.slip.coordinate_index(f"q_{t}") for t in WHEELS])
        names = [m.name for m in self.rolling.motors]
        self.order = [names.index(f"spin_{t}") for t in WHEELS] + [names.index(f"adjust_{t}") for t in WHEELS]
        kin = KinematicState(self.rolling.model, self.rolling.data, self.rolling.neutral(), np.zeros(self.rolling.nq))
        labels = self.rolling.constraint_rows(kin).labels
        self.lateral_rows = [i for i, c in enumerate(labels) if c.endswith(".lateral")]

    def ik_at(self, t: float, guess=None) -> tuple[Commands, np.ndarray]:
        """Commands and IK solution at any time t of the run.

        Args:
            t: Time [s] in the run's interval.
            guess: Initial IK guess (6,) [rad] (default ``None``: the nearest step's solution).

        Returns:
            ``(commands, x)``: the :class:`Commands` at t and the IK solution vector of :func:`solve_ik`.
        """
        cmd = _commands_at(self.run, t)
        if guess is None:
            i = int(np.clip(round(t / self.run.mission.dt), 0, len(self.run.t) - 1))
            guess = np.concatenate([self.run.beta[i], self.run.q[i]])
        return cmd, solve_ik(cmd, self.p, self.slip.terrain, guess)[0]

    def state(self, t: float) -> tuple[Commands, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(commands, IK solution, q, v, a) at time t (natural coordinates of the model).

        Args:
            t: Time [s] in the run's interval.

        Returns:
            ``(commands, x, q, v, a)``: the :class:`Commands`, the IK solution, the configuration (nq,), velocities
            (nv,) and accelerations (nv,) [SI].
        """
        from ...reduction.reduced_dynamics import reduce

        cmd, x = self.ik_at(t)
        q = model_configuration(self.slip, cmd, x)
        nu, nudot = _derivatives(lambda s: body_coordinates(self.run, s, self.slip.terrain), t)
        red = reduce(self.slip, q, nu, independent=self.body)
        return cmd, x, q, red.v, red.S @ nudot + red.w

    def at(self, t: float) -> dict:
        """Torques, contact forces and checks at time t (see :class:`DynamicsRun` for the meaning).

        Args:
            t: Time [s] in the run's interval.

        Returns:
            A dict of the quantities at t: ``q``, ``v``, ``a``, ``x`` (the IK solution), ``tau`` (motor torques [N m]),
            ``forces``, ``normal``, ``ratio``, ``residual``, ``lateral_slip``, ``motor_power``, ``contact_power``,
            ``energy``, ``tau_static`` and ``tau_eq35`` (SI units; meanings as in :class:`DynamicsRun`).
        """
        rolling, pr = self.rolling, self.p
        cmd, x, q, v, a = self.state(t)
        tau_rnea = pin.rnea(rolling.model, rolling.data, q, v, a)
        kin = KinematicState(rolling.model, rolling.data, q, v)
        Eul = kin.frame(rolling.description.frame_id("body"))[1][3:][:, self.body[3:]]
        force = tau_rnea[self.body[:3]]
        moment = np.linalg.solve(Eul.T, tau_rnea[self.body[3:]])
        res = static_torques(cmd, x, pr, self.slip.terrain, extra_force=force - [0, 0, pr["m"] * pr["g"]],
                             extra_moment=moment)
        load = np.zeros(rolling.nq)
        couplings = []
        contact_power = 0.0
        k = 0
        for c in rolling.constraints:
            if isinstance(c, JointCoupling):
                couplings.append(c.rows(kin).A[0])
            else:
                Aw = c.contact(kin)["E"] @ c.rows(kin).A
                load += Aw.T @ res.forces[k]
                contact_power += res.forces[k] @ (Aw @ v)
                k += 1
        B = input_matrix(rolling.motors, kin)
        K = np.column_stack([B, np.array(couplings).T])
        sol, *_ = np.linalg.lstsq(K, tau_rnea - load, rcond=None)
        tau = sol[: B.shape[1]]
        rows = rolling.constraint_rows(kin)
        return {
            "q": q, "v": v, "a": a, "x": x, "tau": tau[self.order], "forces": res.forces, "normal": res.normal,
            "ratio": res.ratio, "residual": float(np.linalg.norm(K @ sol - (tau_rnea - load))),
            "lateral_slip": np.abs(rows.A[self.lateral_rows] @ v), "motor_power": float(tau @ (B.T @ v)),
            "contact_power": float(contact_power), "energy": rolling.energy(q, v),
            "tau_static": static_torques(cmd, x, pr, self.slip.terrain).torque,
            "tau_eq35": paper_torque_eq35(x[3:], pr),
        }


def mission_dynamics(run: IKRun, params: dict | None = None, every: int = 1) -> DynamicsRun:
    """Motor torques along a kinematic mission from the full model, with inertia (see :class:`MissionModel`).

    Args:
        run: An :class:`IKRun`.
        params: Parameter overrides (e.g. ``m_wheel``, ``I_adjust``).
        every: Use every n-th step of the run.

    Returns:
        The :class:`DynamicsRun` of the mission.
    """
    mm = MissionModel(run, params)
    idx = np.arange(0, len(run.t), every)
    n = len(idx)
    out = DynamicsRun(run.t[idx], np.zeros((n, 6)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
                      np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n))
    for row, i in enumerate(idx):
        t = run.t[i]
        r = mm.at(t)
        out.tau_dynamic[row], out.tau_static[row], out.tau_eq35[row] = r["tau"], r["tau_static"], r["tau_eq35"]
        out.normal_dynamic[row], out.ratio_dynamic[row] = r["normal"], r["ratio"]
        out.lateral_slip[row], out.residual[row] = r["lateral_slip"], r["residual"]
        out.qdot_model[row] = r["v"][mm.adjust]
        out.qdot_fd[row] = _derivatives(lambda s: mm.ik_at(s, r["x"])[1][3:], t)[0]
    return out



@dataclass
class FrictionRun:
    """Mission kinematics with a real lateral friction law (:func:`mission_friction`).

    The wheels roll along their rolling direction and slide sideways under the law of ``lateral`` (Coulomb with the
    robot's mu, Table 1: 1.0), so each lateral force is :math:`-\\mu f_n` times the slip direction: known once the
    normal loads are. Torques, normal loads and traction then follow from one square linear system per state
    (:func:`robotdyn.contact.sliding.inverse`).

    Attributes:
        t: (N,) times [s].
        tau: (N, 6) motor torques (spin fr, fl, r, adjust fr, fl, r) [N m].
        normal: (N, 3) normal loads [N].
        longitudinal: (N, 3) traction (the rolling rows' forces) [N].
        lateral: (N, 3) lateral friction forces from the law [N].
        slip: (N, 3) lateral slip velocities [m/s].
        required_mu: (N, 3) :math:`\\|(f_{t1}, f_{t2})\\| / f_n` (inf where :math:`f_n \\le 0`).
        residual: (N,) least-squares residual [N, N m] (> 0: no torques and contact forces realise the motion).
        rank: (N,) rank of the system (15 when regular).
        power: (N, 2) motor power and friction power [W] (their sum is dE/dt).
        energy: (N,) the robot's total energy [J].
        condition: (N,) 2-norm condition number of the system (large: nearly singular, loads ill-determined).
    """

    t: np.ndarray
    tau: np.ndarray
    normal: np.ndarray
    longitudinal: np.ndarray
    lateral: np.ndarray
    slip: np.ndarray
    required_mu: np.ndarray
    residual: np.ndarray
    rank: np.ndarray
    power: np.ndarray
    energy: np.ndarray
    condition: np.ndarray | None = None


def mission_friction(run: IKRun, lateral: str = "coulomb", params: dict | None = None, every: int = 1) -> FrictionRun:
    """Torques and contact forces along a kinematic mission with wheels that slide sideways under a friction law.

    Args:
        run: An :class:`IKRun` (its mission fixes the terrain).
        lateral: ``coulomb`` or ``linear`` (the ``lateral`` parameter of :data:`SPEC`).
        params: Parameter overrides (e.g. ``mu``).
        every: Use every n-th step of the run.

    Returns:
        The :class:`FrictionRun` of the mission.
    """
    from ...contact.sliding import inverse

    if lateral not in ("coulomb", "linear"):
        raise InputError(f"lateral = {lateral!r}; expected a friction law: coulomb or linear")
    mm = MissionModel(run, params)
    robot = Robot(SPEC, {**(params or {}), "terrain": run.mission.terrain, "lateral": lateral})
    idx = np.arange(0, len(run.t), every)
    n = len(idx)
    out = FrictionRun(run.t[idx], *(np.zeros((n, k)) for k in (6, 3, 3, 3, 3, 3)), np.zeros(n), np.zeros(n, int),
                      np.zeros((n, 2)), np.zeros(n), np.zeros(n))
    for row, i in enumerate(idx):
        _, _, q, v, a = mm.state(run.t[i])
        inv = inverse(robot, q, v, a)
        kin = KinematicState(robot.model, robot.data, q, v)
        out.tau[row] = inv.tau[mm.order]
        out.normal[row], out.lateral[row], out.slip[row] = inv.normal, inv.force[:, 1], inv.slip[:, 1]
        out.longitudinal[row] = [inv.multipliers[f"{t}.longitudinal"] for t in WHEELS]
        with np.errstate(divide="ignore", invalid="ignore"):
            out.required_mu[row] = np.where(inv.normal > 0, np.hypot(out.longitudinal[row], out.lateral[row])
                                            / inv.normal, np.inf)
        out.residual[row], out.rank[row], out.condition[row] = inv.residual, inv.rank, inv.condition
        out.power[row] = inv.tau @ (input_matrix(robot.motors, kin).T @ v), float(np.sum(inv.force * inv.slip))
        out.energy[row] = robot.energy(q, v)
    return out

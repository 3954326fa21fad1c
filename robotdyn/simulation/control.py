"""Input-output linearising control on the reduced (minimal-coordinate) model.

With :math:`v = S\\nu`, the reduced equations :math:`M_r\\dot\\nu + h = B_r\\tau` become :math:`\\dot\\nu = u` under
the computed torque :math:`B_r\\tau = M_r u + h` (state-space form :math:`\\dot x = [S\\nu; 0] + [0; I]u`, the
feedback linearisation of Yamamoto and Yun). Outputs :math:`y(q)` (points of frames, coordinates) have
:math:`\\dot y = J v = J S\\nu` and :math:`\\ddot y = JS\\,u + J w + \\dot J v` (:math:`w = \\dot S\\nu`), so the new input

.. math:: u = (JS)^+\\,(\\ddot y_d + K_d(\\dot y_d - \\dot y) + K_p(y_d - y) - Jw - \\dot J v) - N K_\\nu \\nu

gives :math:`\\ddot e + K_d\\dot e + K_p e = 0` for the output error :math:`e = y_d - y` (N projects onto the null
space of JS; the last term damps the redundant motion). Underactuated directions (rank-deficient
:math:`B_r`) are handled by solving :math:`M_r\\dot\\nu + h = B_r\\tau` for the torques and the free accelerations
of the uncontrolled velocities together (collocated partial feedback linearisation).

Units: SI (m, rad, s, N, N m). Frames' points and Jacobians are in world axes (LOCAL_WORLD_ALIGNED).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..constraints.constraint import KinematicState, skew
from ..errors import InputError
from .scenario import Scenario
from .engine import simulate
from .trajectory import Trajectory

Reference = Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]
"""A reference: t -> (y_d, y_d', y_d'') as arrays of the task's dimension."""


def hold(values) -> Reference:
    """A constant reference.

    Args:
        values: The constant value(s) y_d.

    Returns:
        A :data:`Reference` returning (y_d, 0, 0) at every time.
    """
    y = np.atleast_1d(np.asarray(values, dtype=float))
    z = np.zeros_like(y)
    return lambda t: (y, z, z)


@dataclass
class ProfileReference:
    """A reference as data: value, rate and acceleration as
    :class:`~robotdyn.simulation.torque_profile.TorqueProfile` terms of the task's dimension. Callable as a
    :data:`Reference`; with it a :class:`LinearisingController` runs on the compiled engine (the C++ twin in
    ``robotdyn/_controller.hpp``, ``Linearising``).

    Attributes:
        value: y_d(t) [m or rad].
        rate: y_d'(t) [per s].
        acceleration: y_d''(t) [per s^2].
    """

    value: object
    rate: object
    acceleration: object

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.value(t), self.rate(t), self.acceleration(t)

    def breakpoints(self) -> set[float]:
        """Times [s] where a profile is not smooth.

        Returns:
            The set of breakpoint times [s] of the value, rate and acceleration profiles.
        """
        return {float(b) for p in (self.value, self.rate, self.acceleration) for b in p.breakpoints()}


def hold_data(values) -> ProfileReference:
    """A constant reference as data (:func:`hold`'s values, zero rate and acceleration).

    Args:
        values: The constant value(s) y_d.

    Returns:
        The :class:`ProfileReference` holding ``values`` (width ``len(values)``) with zero rate and acceleration.
    """
    from .torque_profile import Constant

    y = np.atleast_1d(np.asarray(values, dtype=float))
    return ProfileReference(Constant(y), Constant(np.zeros_like(y)), Constant(np.zeros_like(y)))


class Task:
    """An output y(q) with its Jacobian rows J (on the full velocity v) and drift :math:`\\dot J v`."""

    reference: Reference

    def evaluate(self, robot, kin: KinematicState) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return (y, J, Jdot_v) at the state of ``kin``.

        Args:
            robot: The :class:`~robotdyn.robot.Robot`.
            kin: The :class:`~robotdyn.constraints.constraint.KinematicState` at (q, v).

        Returns:
            ``(y, J, Jdot_v)``: the output (d,), its Jacobian (d, nv) and the drift :math:`\\dot J v` (d,), in the
            task's units (m or rad).
        """
        raise NotImplementedError


@dataclass
class PointTask(Task):
    """The world position of a point fixed in a frame (selected world axes 0=x, 1=y, 2=z).

    Attributes:
        frame: Frame name.
        reference: t -> (p_d, p_d', p_d'') of the controlled components [m, m/s, m/s^2].
        offset: The point in the frame's axes [m] (default: the frame origin).
        axes: Controlled world components (0 = x, 1 = y, 2 = z; default all three).
    """

    frame: str
    reference: Reference
    offset: Sequence[float] = (0.0, 0.0, 0.0)
    axes: Sequence[int] = (0, 1, 2)

    def evaluate(self, robot, kin):
        fid = robot.description.frame_id(self.frame)
        placement, jac, djac = kin.frame(fid)
        r = placement.rotation @ np.asarray(self.offset, float)
        omega = jac[3:] @ kin.v
        J = jac[:3] - skew(r) @ jac[3:]
        drift = djac[:3] @ kin.v + np.cross(djac[3:] @ kin.v, r) + np.cross(omega, np.cross(omega, r))
        ax = list(self.axes)
        return (placement.translation + r)[ax], J[ax], drift[ax]


@dataclass
class CoordinateTask(Task):
    """Natural coordinates by label (a joint-space task).

    Attributes:
        labels: The controlled coordinates (display or joint names).
        reference: t -> (y_d, y_d', y_d'') of those coordinates [m or rad, per s, per s^2].
    """

    labels: Sequence[str]
    reference: Reference

    def evaluate(self, robot, kin):
        idx = [robot.coordinate_index(c) for c in self.labels]
        J = np.zeros((len(idx), robot.nq))
        J[np.arange(len(idx)), idx] = 1.0
        return kin.q[idx], J, np.zeros(len(idx))


def computed_torque(red, nudot: np.ndarray, controlled: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Motor torques realising the accelerations ``nudot`` of the ``controlled`` independent velocities.

    Solves :math:`M_r\\dot\\nu + h = B_r\\tau` for (tau, the uncontrolled accelerations) in least squares
    (minimum norm when the motors are redundant).

    Args:
        red: The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu).
        nudot: The wanted accelerations of the controlled independent velocities [m/s^2, rad/s^2].
        controlled: Indices of the controlled independent velocities (default ``None``: all).

    Returns:
        ``(tau, nudot_all)``: the torques and the full vector of independent accelerations they produce.
    """
    k = red.M.shape[0]
    ctrl = np.arange(k) if controlled is None else np.asarray(controlled, dtype=int)
    free = np.setdiff1d(np.arange(k), ctrl)
    m = red.B.shape[1]
    lhs = np.hstack([red.B, -red.M[:, free]])
    rhs = red.M[:, ctrl] @ nudot[ctrl] + red.h
    sol, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    tau = sol[:m]
    out = np.array(nudot, dtype=float)
    out[free] = sol[m:]
    return tau, out


@dataclass
class LinearisingController:
    """Computed torque on the reduced model plus PD output feedback (see the module docstring).

    Attributes:
        robot: The robot (its reduced model is the controller's model).
        tasks: Outputs to track, stacked.
        kp, kd: Proportional [1/s^2] and derivative [1/s] gains (the same for every output).
        damping: Gain [1/s] on the independent velocities in the null space of the outputs.
        controlled: Labels of the independent velocities the motors act on (``None``: all).
        secondary: Lower-priority tasks, tracked in the null space of ``tasks`` (least squares).
    """

    robot: object
    tasks: list[Task]
    kp: float = 4.0
    kd: float = 4.0
    damping: float = 2.0
    controlled: Sequence[str] | None = None
    secondary: list[Task] = field(default_factory=list)
    _ctrl: np.ndarray | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        if self.kp < 0 or self.kd < 0 or self.damping < 0:
            raise InputError(f"gains kp = {self.kp}, kd = {self.kd}, damping = {self.damping}; expected >= 0")
        names = self.robot.velocity_names
        if self.controlled is not None:
            unknown = [c for c in self.controlled if f"{c}_dot" not in names and c not in names]
            if unknown:
                raise InputError(f"controlled velocities {unknown} are not independent velocities {names}")
            self._ctrl = np.array([names.index(c if c in names else f"{c}_dot") for c in self.controlled])

    def outputs(self, q, nu, t: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(y, y', y_d, y_d') of the stacked tasks at (q, nu).

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.
            t: Time [s] at which the references are evaluated.

        Returns:
            ``(y, y', y_d, y_d')``, each (d,), the tasks stacked in order.
        """
        red = self.robot.reduced(q, nu)
        kin = KinematicState(self.robot.model, self.robot.data, q, red.v)
        ys, yds, ydots, yddots = [], [], [], []
        for task in self.tasks:
            y, J, _ = task.evaluate(self.robot, kin)
            yd, ydd, _ = task.reference(t)
            ys.append(y), ydots.append(J @ red.v), yds.append(yd), yddots.append(ydd)
        return np.concatenate(ys), np.concatenate(ydots), np.concatenate(yds), np.concatenate(yddots)

    def command(self, t: float, q: np.ndarray, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The new input u (eq: nu' = u) and the motor torques at (t, q, nu).

        Args:
            t: Time [s].
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.

        Returns:
            ``(u, tau)``: the new input (k,) and the motor torques (n_motors,) [N m or N].
        """
        red = self.robot.reduced(q, nu)
        kin = KinematicState(self.robot.model, self.robot.data, q, red.v)
        A, b = self._rows(self.tasks, t, kin, red)
        pinv = np.linalg.pinv(A, rcond=1e-10)
        u = pinv @ b
        N = np.eye(A.shape[1]) - pinv @ A
        if self.secondary:
            A2, b2 = self._rows(self.secondary, t, kin, red)
            A2N = A2 @ N
            pinv2 = np.linalg.pinv(A2N, rcond=1e-8)
            u = u + pinv2 @ (b2 - A2 @ u)
            N = N @ (np.eye(A.shape[1]) - pinv2 @ A2N)
        if self.damping:
            u -= N @ (self.damping * nu)
        tau, _ = computed_torque(red, u, self._ctrl)
        return u, tau

    def _rows(self, tasks, t, kin, red) -> tuple[np.ndarray, np.ndarray]:
        """Stacked JS and the commanded output accelerations minus Jw + Jdot v (eq 25)."""
        rows, rhs = [], []
        for task in tasks:
            y, J, drift = task.evaluate(self.robot, kin)
            yd, yd_dot, yd_ddot = (np.atleast_1d(np.asarray(a, float)) for a in task.reference(t))
            ydot = J @ red.v
            rows.append(J @ red.S)
            rhs.append(yd_ddot + self.kd * (yd_dot - ydot) + self.kp * (yd - y) - J @ red.w - drift)
        return np.vstack(rows), np.concatenate(rhs)

    def __call__(self, t: float, q: np.ndarray, nu: np.ndarray) -> np.ndarray:
        return self.command(t, q, nu)[1]

    def compiled_form(self) -> bool:
        """Whether the compiled engine can run this controller: every task a :class:`PointTask` or
        :class:`CoordinateTask` whose reference is a :class:`ProfileReference`.

        Returns:
            True where the compiled engine can run it.
        """
        return all(isinstance(task, (PointTask, CoordinateTask)) and isinstance(task.reference, ProfileReference)
                   for task in [*self.tasks, *self.secondary])

    def breakpoints(self) -> np.ndarray:
        """Sorted times [s] where a reference is not smooth (both engines restart there).

        Returns:
            The breakpoint times (b,) [s], ascending.
        """
        points = set()
        for task in [*self.tasks, *self.secondary]:
            if isinstance(task.reference, ProfileReference):
                points |= task.reference.breakpoints()
        return np.array(sorted(points), float)

    def native_controller(self, robot, fast):
        """The C++ twin (``robotdyn._compiled.Controller`` with its ``Linearising`` law) on ``fast``, the compiled
        model of ``robot`` (point tasks' frames are added to it once).

        Args:
            robot: The :class:`~robotdyn.robot.Robot` simulated (this controller's robot).
            fast: Its :class:`~robotdyn.fast.compiled.CompiledModel`.

        Returns:
            The ``robotdyn._compiled.Controller`` the compiled loop evaluates.
        """
        from .._compiled import Controller
        from .feedback import native_profile

        frames = fast.__dict__.setdefault("_task_frames", {})

        def encode(task):
            ref = task.reference
            profiles = (native_profile(ref.value), native_profile(ref.rate), native_profile(ref.acceleration))
            if isinstance(task, CoordinateTask):
                return (1, -1, np.zeros(3), [int(robot.coordinate_index(c)) for c in task.labels], *profiles)
            fid = robot.description.frame_id(task.frame)
            if fid not in frames:
                if fid in fast.frame_ids:
                    frames[fid] = fast.frame_ids.index(fid)
                else:
                    f = robot.model.frames[fid]
                    M = f.placement
                    frames[fid] = fast.ev.add_frame(int(f.parentJoint), np.hstack([M.rotation, M.translation[:, None]]))
                    fast.frame_ids.append(fid)
            return (0, frames[fid], np.asarray(task.offset, float), [int(a) for a in task.axes], *profiles)

        m, empty = len(robot.motors), np.zeros((0, 0))
        out = Controller(m, robot.nq, robot.mobility, None, empty, None, empty, None, None)
        out.set_linearising(float(self.kp), float(self.kd), float(self.damping),
                            [] if self._ctrl is None else [int(i) for i in self._ctrl],
                            [encode(t) for t in self.tasks], [encode(t) for t in self.secondary])
        return out


def tracking_errors(controller: LinearisingController, traj: Trajectory, task: int = 0,
                    after: float = 0.0) -> dict[str, float]:
    """Position error norms :math:`\\|y_d - y\\|` of one task along a trajectory: mean, RMS and max [same unit as y].

    Args:
        controller: The :class:`LinearisingController` run.
        traj: The :class:`~robotdyn.simulation.trajectory.Trajectory` it produced.
        task: Index of the task in the controller's tasks.
        after: Ignore samples before this time [s] (the transient).

    Returns:
        A dict with keys ``mean``, ``rms``, ``max`` and ``final`` (the last sample's error), floats in the unit of y.
    """
    errs = []
    for t, q, nu in zip(traj.t, traj.q, traj.nu):
        if t < after:
            continue
        red = controller.robot.reduced(q, nu)
        kin = KinematicState(controller.robot.model, controller.robot.data, q, red.v)
        y, _, _ = controller.tasks[task].evaluate(controller.robot, kin)
        yd = np.atleast_1d(controller.tasks[task].reference(t)[0])
        errs.append(float(np.linalg.norm(yd - y)))
    e = np.array(errs)
    return {"mean": float(e.mean()), "rms": float(np.sqrt(np.mean(e**2))), "max": float(e.max()),
            "final": float(e[-1])}


@dataclass
class ControlledScenario(Scenario):
    """A scenario whose torque law is built for the robot it runs on (e.g. a model-based controller).

    Attributes:
        name: Identifier (``robotdyn simulate ROBOT --scenario NAME``).
        description: One line, citing the paper's section.
        t_end: Default duration [s].
        torque: Motor torques used when ``make_controller`` is ``None`` (as :class:`Scenario`).
        q0: Initial coordinates by name [m, rad] (missing entries: the neutral configuration).
        nu0: Initial independent velocities by name (missing entries are zero).
        n_out: Default number of output samples.
        plot: Columns to plot (default all independent velocities).
        zoom: Length [s] of the zoomed transient window in plots (``None``: no zoom column).
        references: Horizontal reference lines per plotted column.
        make_controller: robot -> controller (a callable tau(t, q, nu)).
        adapt_robot: Optional robot -> robot (e.g. the same robot with other contacts) used for the run.
        initial: Optional robot -> (q0, nu0) overriding ``q0``/``nu0``.
    """

    make_controller: Callable | None = None
    adapt_robot: Callable | None = None
    initial: Callable | None = None

    def prepare(self, robot):
        """(robot used, controller) for a run on ``robot``.

        Args:
            robot: The :class:`~robotdyn.robot.Robot`.

        Returns:
            ``(robot, controller)``: the robot used and its :class:`LinearisingController`.
        """
        if self.adapt_robot is not None:
            robot = self.adapt_robot(robot)
        controller = self.make_controller(robot) if self.make_controller is not None else self.torque
        return robot, controller

    def run(self, robot, t_end: float | None = None, n_out: int | None = None, **kwargs) -> Trajectory:
        robot, controller = self.prepare(robot)
        q0, nu0 = self.initial(robot) if self.initial is not None else self.initial_state(robot)
        t_end = self.t_end if t_end is None else t_end
        n_out = n_out or max(2, int(round(self.n_out * t_end / self.t_end)))
        kwargs.setdefault("rtol", 1e-8)
        kwargs.setdefault("atol", 1e-10)
        traj = simulate(robot, t_end, q0, nu0, controller, n_out=n_out, **kwargs)
        traj.stats["controller"] = controller
        traj.stats["robot"] = robot
        return traj


__all__ = ["LinearisingController", "PointTask", "CoordinateTask", "Task", "hold", "hold_data", "ProfileReference", "computed_torque",
           "tracking_errors", "ControlledScenario"]

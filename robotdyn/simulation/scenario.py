"""Named scenarios: an initial state, an input law and a duration, run through :func:`robotdyn.simulation.engine.simulate`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..errors import RobotDynError
from .engine import simulate
from .trajectory import Trajectory


@dataclass
class Scenario:
    """A reproducible manoeuvre.

    Attributes:
        name: Identifier (``robotdyn simulate ROBOT --scenario NAME``).
        description: One line, citing the paper's section.
        t_end: Default duration [s].
        torque: Motor torques: a :class:`~robotdyn.simulation.torque_profile.TorqueProfile` (simulated by the compiled engine)
            or any ``tau(t, q, nu)`` (the scipy engine); None: unactuated.
        q0, nu0: Initial coordinates and independent velocities by name (missing entries are zero); with
            stick-slip wheels nu0 may name any coordinate's velocity (the full velocities v, see
            :meth:`initial_state`).
        n_out: Default number of output samples.
        plot: Columns to plot (the paper's figures); default all independent velocities.
        zoom: Length [s] of the zoomed transient window in plots (``None``: no zoom column).
        references: Horizontal reference lines per plotted column (the paper's printed values).
    """

    name: str
    description: str
    t_end: float
    torque: Callable[[float, np.ndarray, np.ndarray], np.ndarray] | None = None
    q0: dict[str, float] = field(default_factory=dict)
    nu0: dict[str, float] = field(default_factory=dict)
    n_out: int = 1801
    plot: list[str] = field(default_factory=list)
    zoom: float | None = None
    references: dict[str, list[tuple[float, str]]] = field(default_factory=dict)

    def initial_state(self, robot) -> tuple[np.ndarray, np.ndarray]:
        """(q0, nu0) as vectors for ``robot`` (nu0: the full velocities v (n,) where :meth:`_full_velocities`).

        Args:
            robot: The :class:`~robotdyn.robot.Robot` to run the scenario on.

        Returns:
            ``(q0, nu0)``: the neutral configuration with the scenario's ``q0`` entries set (n,) [m, rad], and the
            independent velocities (k,) [m/s, rad/s] (or the full velocities (n,), see above), zero except the scenario's ``nu0`` entries.
        """
        q0 = robot.neutral()
        for label, value in self.q0.items():
            q0[robot.coordinate_index(label)] = value
        if self._full_velocities(robot, q0):  # stick-slip wheels: v by coordinate (robotdyn.simulation.engine.simulate)
            v0 = np.zeros(robot.nq)
            for label, value in self.nu0.items():
                v0[robot.velocity_labels.index(label)] = value
            return q0, v0
        nu0 = np.zeros(robot.mobility)
        for label, value in self.nu0.items():
            nu0[robot.velocity_names.index(label)] = value
        return q0, nu0

    def _full_velocities(self, robot, q0: np.ndarray) -> bool:
        """Whether nu0 gives the full velocities v by coordinate: on a robot with stick-slip wheels, where it names
        a velocity that is not independent when every wheel sticks, or the robot's independent velocities do not fit
        that phase (e.g. a vehicle that every sticking wheel holds: none is free)."""
        from ..contact.stick_slip_wheel import stick_slip_wheels

        if not stick_slip_wheels(robot):
            return False
        if any(label not in robot.velocity_names for label in self.nu0):
            return True
        A = robot.rows_at(q0).A
        return robot.nq - (int(np.linalg.matrix_rank(A)) if A.size else 0) != robot.mobility

    def span(self, t_end: float | None = None, n_out: int | None = None, streamed: bool = False) -> tuple[float, int]:
        """The duration and the number of output samples of a run.

        Args:
            t_end: Duration [s] (default ``None``: the scenario's); must be finite and at least
                :data:`~robotdyn.simulation.engine.MIN_DURATION`.
            n_out: Number of output samples (default ``None``: the scenario's sampling rate over that duration).
            streamed: The run is written to a file in segments (:mod:`robotdyn.simulation.streaming`): no upper bound
                on the samples (else at most :data:`~robotdyn.simulation.engine.MAX_SAMPLES`).

        Returns:
            ``(t_end [s], n_out)``.

        Raises:
            RobotDynError: A duration or a number of samples out of range.
        """
        from .engine import MAX_SAMPLES, MIN_DURATION

        t_end = self.t_end if t_end is None else float(t_end)
        if not np.isfinite(t_end) or t_end <= 0:
            raise RobotDynError(f"t_end = {t_end} s; expected a positive duration")
        if t_end < MIN_DURATION:
            raise RobotDynError(f"t_end = {t_end:g} s; expected a duration of at least {MIN_DURATION:g} s")
        n = float(n_out) if n_out else max(2.0, round(self.n_out * t_end / self.t_end))
        if not 2 <= n <= (float("inf") if streamed else MAX_SAMPLES):
            raise RobotDynError(f"{n:.3g} output samples for t_end = {t_end:g} s; expected 2 to {MAX_SAMPLES:,} "
                                "samples (memory): give a shorter duration or fewer samples, or stream the run to a "
                                "CSV file (robotdyn simulate --csv)")
        return t_end, int(n)

    def run(self, robot, t_end: float | None = None, n_out: int | None = None, **kwargs) -> Trajectory:
        """Simulate the scenario on ``robot`` from its initial state with its torques.

        Args:
            robot: The :class:`~robotdyn.robot.Robot` (its motors in the order the scenario's torques use).
            t_end: Duration [s] (default ``None``: the scenario's).
            n_out: Number of output samples (default ``None``: the scenario's rate).
            **kwargs: Passed to :func:`~robotdyn.simulation.engine.simulate` (``rtol``, ``engine``, ``progress``, ...);
                with ``sink=`` the run streams to a file and returns a
                :class:`~robotdyn.simulation.streaming.StreamResult`.

        Returns:
            The :class:`~robotdyn.simulation.trajectory.Trajectory`.

        Raises:
            RobotDynError: A duration or number of samples out of range, or a failing integration.

        Example:
            >>> import robotdyn
            >>> from robotdyn.robots.quasimoro import model
            >>> robot = robotdyn.load("quasimoro")
            >>> traj = model.SCENARIOS["rectilinear"].run(robot, t_end=0.5, progress=False)
            >>> float(traj.t[-1]), traj.q.shape[1], traj.velocity_names
            (0.5, 6, ['theta1_dot', 'theta2_dot', 'theta3_dot'])
            >>> bool(traj.column("x")[-1] > 0)  # it drove forward
            True
        """
        t_end, n_out = self.span(t_end, n_out, streamed=kwargs.get("sink") is not None)
        q0, nu0 = self.initial_state(robot)
        return simulate(robot, t_end, q0, nu0, self.torque, n_out=n_out, **kwargs)

"""A simulated motion: the result of every engine (:func:`robotdyn.simulation.engine.simulate`, the compiled engine
of :mod:`robotdyn.simulation.compiled_engine` and the stick-slip engine of :mod:`robotdyn.simulation.stick_slip`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import RobotDynError


@dataclass
class Trajectory:
    """A simulated motion.

    Attributes:
        t: Times (N,) [s].
        q: Natural coordinates (N, n), named by ``coordinates``.
        nu: Independent velocities (N, k), named by ``velocity_names``.
        energy: Total mechanical energy at each time (N,) [J].
        residual: Largest holonomic residual at each time (N,).
        coordinates, velocity_names: Column names.
        stats: Integrator statistics (nfev, wall time).
        units: Unit of each column by name (m, rad, m/s, rad/s).
        friction_work: Work done by the slipping wheels' friction forces since t = 0 (N,) [J] (<= 0; ``None``
            without slipping wheels): energy balance E(t) - E(0) = motor work + friction_work.
        damper_work: Work done by joint dampers and compliant contacts' damping since t = 0 (N,) [J] (<= 0;
            ``None`` without them): E(t) - E(0) = motor work + friction_work + damper_work, with E counting the
            springs' and contacts' elastic energy.
        impact_loss: Kinetic energy taken by the touch-down impacts of rolling compliant wheels up to each sample
            (N,) [J] (>= 0, non-decreasing; ``None`` without such wheels,
            :mod:`robotdyn.simulation.compliant_rolling`): E(t) - E(0) = motor work + friction_work + damper_work -
            (impact_loss(t) - impact_loss(0)).
        robot, torque: The robot simulated and the torque law applied (``None``: unactuated), as
            :func:`~robotdyn.simulation.engine.simulate` received them: what a post-pass (wheel loads,
            :func:`robotdyn.contact.traction.traction`) must use, also where a scenario built its own controller
            or robot. Not part of comparisons or the CSV.
    """

    t: np.ndarray
    q: np.ndarray
    nu: np.ndarray
    energy: np.ndarray
    residual: np.ndarray
    coordinates: list[str]
    velocity_names: list[str]
    stats: dict = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    friction_work: np.ndarray | None = None
    robot: object | None = field(default=None, repr=False, compare=False)
    torque: object | None = field(default=None, repr=False, compare=False)
    damper_work: np.ndarray | None = None
    impact_loss: np.ndarray | None = None

    def __repr__(self) -> str:
        return f"Trajectory(t=[{self.t[0]:g}, {self.t[-1]:g}] s, N={len(self.t)}, wall={self.stats.get('wall', 0):.3g} s)"

    def column(self, name: str) -> np.ndarray:
        """A coordinate or independent velocity by name.

        Args:
            name: One of :attr:`coordinates` or :attr:`velocity_names`.

        Returns:
            Its values at the samples (N,) [m, rad, m/s or rad/s].

        Raises:
            RobotDynError: No column has that name.
        """
        if name in self.coordinates:
            return self.q[:, self.coordinates.index(name)]
        if name in self.velocity_names:
            return self.nu[:, self.velocity_names.index(name)]
        raise RobotDynError(f"no column {name!r}; expected one of {', '.join(self.coordinates + self.velocity_names)}")

    def to_csv(self, path, extra: dict[str, np.ndarray] | None = None) -> None:
        """Write ``t``, the q columns, the nu columns, then any ``extra`` columns by name (e.g. the wheel loads of
        :meth:`robotdyn.contact.traction.Traction.columns`), atomically.

        Args:
            path: The CSV file (one header line of column names; a partial run ends with a ``# partial:`` line).
            extra: More columns by name, each (N,) (default ``None``: none).

        Raises:
            OutputError: The file cannot be written.

        Example:
            >>> import numpy as np, robotdyn
            >>> from robotdyn.robots.quasimoro import model
            >>> traj = model.SCENARIOS["rectilinear"].run(robotdyn.load("quasimoro"), t_end=0.2, n_out=5, progress=False)
            >>> traj.to_csv("run.csv")
            >>> open("run.csv").readline().strip()
            't,x,y,psi,theta1,theta2,theta3,theta1_dot,theta2_dot,theta3_dot'
            >>> np.loadtxt("run.csv", delimiter=",", skiprows=1).shape
            (5, 10)
        """
        from ..output import atomic_output

        extra = extra or {}
        header = ",".join(["t", *self.coordinates, *self.velocity_names, *extra])
        data = np.column_stack([self.t, self.q, self.nu, *extra.values()])
        partial = self.stats.get("partial")
        with atomic_output(path, "CSV file") as tmp:
            np.savetxt(tmp, data, delimiter=",", header=header, comments="",
                       footer=f"# partial: {partial}" if partial else "")  # a comment line: loadtxt skips it

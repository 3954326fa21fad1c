"""Minimum-effort trajectories of the reduced dynamics by direct collocation, solved by IPOPT through CasADi.

The problem (one robot, fixed duration T):

.. math:: \\min_{x(\\cdot),\\,\\tau(\\cdot)} \\int_0^T \\lVert\\tau\\rVert^2\\,dt \\quad\\text{s.t.}\\quad
          \\dot x = f(x, \\tau) = \\begin{bmatrix} S(q)\\,\\nu \\\\ \\dot\\nu(q, \\nu, \\tau)\\end{bmatrix},\\;
          x(0) = x_0,\\; x_i(T) = x_{T,i}\\ (i\\ \\text{given}),\\; \\tau_{lo} \\le \\tau \\le \\tau_{hi},\\;
          x_{lo} \\le x \\le x_{hi},

with the state :math:`x = (q, \\nu)`: natural coordinates [m, rad] and independent velocities [m/s, rad/s], the
equations the simulation integrates (:mod:`robotdyn.simulation.engine`) and :math:`\\dot\\nu` the reduced forward
dynamics (:meth:`robotdyn.robot.Robot.forward_dynamics`). The cost is in N^2 m^2 s.

Transcription: trapezoidal direct collocation on N nodes :math:`t_j = jT/(N-1)`, the torques piecewise linear
between nodes (so that a :class:`~robotdyn.simulation.torque_profile.Table` of the optimal node torques is exactly
the control the collocation assumed, and a re-simulation with the exact model checks the result); defects
:math:`x_{j+1} - x_j - \\tfrac{h}{2}(f_j + f_{j+1}) = 0` and the trapezoid rule for the cost. The defects'
Jacobian is block-sparse (two state blocks and two torque blocks per interval) and built from
:math:`\\partial f/\\partial x, \\partial f/\\partial\\tau` at each node: analytic
(:meth:`robotdyn.robot.Robot.dynamics_derivatives`: ``dqdot_dq``, ``S``, ``dq``, ``dnu``, ``dtau``) or, for
comparison, central finite differences of the forward dynamics (``derivatives="finite-difference"``; with holonomic
rows the coordinates are stepped along their level set, :mod:`robotdyn.optimisation.manifold_steps`). The cost is
quadratic and its gradient exact in both cases; IPOPT's Hessian is its limited-memory (L-BFGS) approximation, in
both cases, so that the two differ only in the constraint Jacobian. With the effort cost IPOPT sees the torques in
units of their expected size and the effort in units of its expected value (:mod:`robotdyn.optimisation.scaling`:
powers of 2 from the torques of a guessed motion; without them a light robot's problem, where 1 N m gives
thousands of rad/s^2, did not converge).

Solver choice: IPOPT (interior point, sparse, the reference NLP solver of the optimal-control community) through
CasADi's ``nlpsol``, because CasADi's PyPI wheel bundles IPOPT with its sparse linear solver (MUMPS): it installs
with pip alone on Linux, macOS and Windows (``casadi`` 3.8: a 93 MB wheel, 277 MB installed, ~7 s to install),
whereas cyipopt has no Linux wheel and its build fails without a system IPOPT (pkg-config finds no ``ipopt``), and
scipy's ``trust-constr`` is not a sparse interior-point solver for large NLPs. The robot's dynamics enter as one
CasADi ``Callback`` (all defects at once) whose Jacobian is another ``Callback`` with a declared sparsity pattern:
the analytic derivatives are passed as callbacks; CasADi's automatic differentiation is not used through Pinocchio.
On the compiled model the nodes' dynamics (the defects, and either Jacobian) take one compiled call per iterate
(:mod:`robotdyn.optimisation.node_batches`), so that Python's per-call cost does not dwarf a 3 us evaluation.

Holonomic rows (wheels on a terrain, loop closures, couplings): every node is kept on the constraint manifold. The
defects of the dependent position coordinates (those the holonomic rows fix, :attr:`~robotdyn.reduction.
dynamics_derivatives.DynamicsDerivatives.positions` naming the others) are replaced by the independent holonomic
residuals :math:`\\phi(q_{j+1}) = 0` at nodes 1..N-1, whose Jacobian is the holonomic rows :math:`A_h`: the same
number of equations, and the dependent coordinates follow the manifold instead of drifting off it by the
trapezoid's error. The dynamics' derivatives in q are exact along the manifold's tangent; their part normal to it
lies in the row space of :math:`A_h` and only changes the holonomic rows' multipliers, not the optimum.

Traction limits (:mod:`robotdyn.optimisation.contact_limits`): with ``min_load`` or ``mu_max`` every node's wheel
loads :math:`f_n \\ge f_{min}` and friction cones :math:`\\|f_t\\| \\le \\mu_{max} f_n` are path constraints; with
``cost="peak-mu"`` the cost is the square of the largest required friction coefficient over wheels and nodes (an
epigraph variable s with :math:`\\|f_t\\|^2 \\le s f_n^2` at every node) plus ``effort_weight`` times the effort.
Their Jacobian comes from :meth:`robotdyn.robot.Robot.contact_force_derivatives` (``force_derivatives="analytic"``)
or from central differences of the forces.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, NonFiniteError
from ..inputs import MAX_POSITION
from ..fast.compiled import Fallback
from ..fast.compiled_derivatives import raw_derivatives
from ..fast.dispatch import ThreadModel
from .callbacks import _casadi, refusal, sparse_callback
from .node_batches import analytic_jacobians, central_jacobians, rhs_nodes
from .scaling import effort_units

DERIVATIVES = ("analytic", "finite-difference")
"""How the dynamics' Jacobian is computed (``derivatives`` of :class:`TrajectoryProblem`)."""
COSTS = ("effort", "peak-mu")
MAX_NODES = 10_000
"""Most collocation nodes of one problem (its Jacobian pattern and IPOPT's work grow with them; 10^8 exhausts
memory)."""
"""What :class:`TrajectoryProblem` minimises: ``effort`` :math:`\\int\\lVert\\tau\\rVert^2 dt`, or ``peak-mu`` the
square of the largest required friction coefficient over wheels and nodes plus ``effort_weight`` times the effort."""
HOLONOMIC_TOL = 1e-8
"""Largest holonomic residual [m or rad] accepted at q0 (the collocation keeps every node on the manifold)."""
FEASIBLE_DEFECT = 1e-6
"""Largest defect [state units] at which :attr:`TrajectorySolution.diagnosis` calls an iterate feasible."""
HELD_TOL = 1e-6
"""Largest defect [state units] of a held coordinate or velocity (:mod:`robotdyn.optimisation.held_coordinates`)
accepted at the optimum: their rows are not the NLP's, and a larger one means the motion would leave them."""


@dataclass
class TrajectorySolution:
    """An optimal motion on the collocation nodes (SI units).

    Attributes:
        t: Node times (N,) [s].
        q: Natural coordinates at the nodes (N, n) [m, rad].
        nu: Independent velocities at the nodes (N, k) [m/s, rad/s].
        tau: Motor torques at the nodes (N, m) [N m or N]; linear in between.
        cost: The objective at the optimum: the effort [N^2 m^2 s] or (``peak-mu``) the squared peak required mu
            plus ``effort_weight`` times the effort.
        status: IPOPT's return status (``Solve_Succeeded`` on success).
        success: Whether IPOPT converged.
        iterations: IPOPT iterations.
        wall_time: Wall-clock time of the solve [s].
        dynamics_calls: Forward-dynamics evaluations (defects and, with finite differences, the Jacobian).
        derivative_calls: Analytic derivative evaluations (``dynamics_derivatives``), one per node per Jacobian.
        max_defect: Largest collocation defect at the optimum (state units).
        derivatives: ``analytic`` or ``finite-difference``.
        coordinates, velocity_names, motors: Column names of q, nu and tau.
        forces: The ground's force on each wheel at the nodes (N, nw, 3) [N], (t1, t2, n) of its contact frame
            (``None`` without contact constraints or the ``peak-mu`` cost).
        wheels: The wheels' names, in the order of ``forces``.
        effort: :math:`\\int_0^T \\lVert\\tau\\rVert^2 dt` by the trapezoid rule [N^2 m^2 s] (equal to ``cost`` for
            the ``effort`` cost).
        force_calls: Contact-force evaluations (rows and finite differences).
        cost_kind: ``effort`` or ``peak-mu`` (the problem's ``cost``).
    """

    t: np.ndarray
    q: np.ndarray
    nu: np.ndarray
    tau: np.ndarray
    cost: float
    status: str
    success: bool
    iterations: int
    wall_time: float
    dynamics_calls: int
    derivative_calls: int
    max_defect: float
    derivatives: str
    coordinates: list[str] = field(default_factory=list)
    velocity_names: list[str] = field(default_factory=list)
    motors: list[str] = field(default_factory=list)
    forces: np.ndarray | None = None
    wheels: list[str] = field(default_factory=list)
    effort: float = math.nan
    force_calls: int = 0
    cost_kind: str = "effort"

    @property
    def required_mu(self) -> np.ndarray | None:
        """Each wheel's required friction coefficient :math:`\\lVert f_t\\rVert / f_n` at the nodes (N, nw)
        (``None`` without ``forces``)."""
        if self.forces is None:
            return None
        from .contact_limits import required_mu

        return required_mu(self.forces)

    @property
    def diagnosis(self) -> str:
        """What IPOPT's stop says about the problem, as one line (empty on success); what the CLI prints with a
        failed solve. The iteration limit is told apart by the largest defect: at most :data:`FEASIBLE_DEFECT`
        means that the iterates met the constraints and the cost still fell (the old code's light differential
        drive, :mod:`robotdyn.optimisation.scaling`), not that the problem is infeasible."""
        status = self.status.split(";")[0]
        if self.success:
            return ""
        if "held rows" in self.status:
            return ("the motion leaves a coordinate held at its start value (the constraints change rank along it): "
                    "ask for a motion that keeps it")
        if status == "Maximum_Iterations_Exceeded" and self.max_defect <= FEASIBLE_DEFECT:
            return ("the iteration limit came on feasible points (the constraints held) before the optimum: a badly "
                    "scaled problem (torques, distances or times of very different magnitudes) or a flat optimum, "
                    "not an infeasible one")
        if status in ("Maximum_Iterations_Exceeded", "Infeasible_Problem_Detected", "Restoration_Failed"):
            what = {"Maximum_Iterations_Exceeded": "the iteration limit came before the constraints held",
                    "Infeasible_Problem_Detected": "IPOPT found the constraints locally infeasible",
                    "Restoration_Failed": "IPOPT's restoration phase could not reduce the constraints' violation"}
            return f"{what[status]}: looser bounds, more time or more nodes may make the problem feasible"
        if status == "Invalid_Number_Detected":
            return "the model gave a non-finite number at a point IPOPT tried"
        return f"IPOPT stopped before convergence ({status})"

    def profile(self):
        """The optimal torques as a :class:`~robotdyn.simulation.torque_profile.Table` (linear between nodes,
        what the collocation assumed), for :func:`robotdyn.simulation.engine.simulate`.

        Returns:
            The :class:`~robotdyn.simulation.torque_profile.Table` of the node times [s] and torques [N m or N].
        """
        from ..simulation.torque_profile import Table

        return Table(self.t, self.tau)

    def __repr__(self) -> str:
        unit = " N^2 m^2 s" if self.cost_kind == "effort" else f" ({self.cost_kind})"
        return (f"TrajectorySolution({self.status}, cost={self.cost:.6g}{unit}, {len(self.t)} nodes, "
                f"{self.iterations} iterations, {self.wall_time:.3g} s, derivatives={self.derivatives})")


class TrajectoryProblem:
    """A minimum-effort (or least-peak-mu) motion of a robot between two states in a fixed time (see the module
    docstring).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` (holonomic rows are kept at every node).
        t_end: Duration T [s] (> 0).
        nodes: Number of collocation nodes N (3 to :data:`MAX_NODES`).
        q0: Initial natural coordinates (n,) [m, rad].
        nu0: Initial independent velocities (k,) [m/s, rad/s] (default: at rest).
        q_end: Final values of some coordinates, by name {coordinate: value} [m or rad]; the others are free.
        nu_end: Final independent velocities (k,) (default: at rest); ``None`` entries are free.
        tau_bounds: ``(lower, upper)`` motor torques [N m or N], each a number or one per motor
            (default: unbounded).
        bounds: Bounds on coordinates or velocities at every node, by name {name: (lower, upper)} [SI units]
            (the coordinates are always kept within their joint ranges).
        derivatives: ``analytic`` (default) or ``finite-difference`` (central differences of the forward dynamics,
            the comparison).
        guess: Initial guess ``(q (N, n), nu (N, k), tau (N, m))`` (default: the coordinates from ``q0`` towards
            ``q_end`` along a smooth rest-to-rest ramp, the velocities that best follow it through S(q) in least
            squares, no torque; a guess at rest everywhere can make the defects' Jacobian rank-deficient for
            nonholonomic robots).
        min_load: Least normal load of every wheel at every node [N] (default ``None``: none; 0 where ``mu_max`` or
            the ``peak-mu`` cost is asked).
        mu_max: Largest required friction coefficient :math:`\\|f_t\\|/f_n` of every wheel at every node (default
            ``None``: none).
        cost: ``effort`` (default, :math:`\\int\\|\\tau\\|^2dt`) or ``peak-mu`` (the squared peak required mu plus
            ``effort_weight`` times the effort).
        effort_weight: The effort's weight in the ``peak-mu`` cost [1/(N^2 m^2 s)] (default 1e-3).
        force_derivatives: ``analytic`` or ``finite-difference``, the contact forces' Jacobian (default: as
            ``derivatives``).
        rate_weight: Weight of the torques' rate :math:`\\int\\|\\dot\\tau\\|^2 dt` added to either cost (default 0:
            none) [cost units per N^2 m^2 / s]: it suppresses the node-to-node oscillation the trapezoidal rule
            leaves free in directions without inertia of their own (a massless mechanism).

    Where the constraints change rank along a coordinate at q0 (rows redundant only there, e.g. a car whose
    no-slip wheels allow a roll velocity at zero roll only), that coordinate and the velocity moving it are held at
    their q0 values (:attr:`held`, :mod:`robotdyn.optimisation.held_coordinates`): no motion of the robot leaves
    them, and the dynamics refuse every configuration off them.

    Raises:
        InputError: A wrong size, name or bound, non-finite data; an end value, start value or bound asking a held
            coordinate or velocity to move.
        ConstraintError: q0 off the holonomic constraint manifold (by more than :data:`HOLONOMIC_TOL`).
    """

    # the robot's compiled model for the calling thread: built in one thread, solved in another with the same numbers
    # (None: the Python path)
    _fast = ThreadModel()

    def __init__(self, robot, t_end: float, nodes: int, q0, nu0=None, q_end: dict | None = None,
                 nu_end=None, tau_bounds=None, bounds: dict | None = None, derivatives: str = "analytic",
                 guess=None, min_load: float | None = None, mu_max: float | None = None, cost: str = "effort",
                 effort_weight: float = 1e-3, force_derivatives: str | None = None, rate_weight: float = 0.0) -> None:
        self.robot = robot
        self.t_end = _finite(t_end, "t_end")
        if not self.t_end > 0:
            raise InputError(f"t_end = {t_end!r}; expected a finite duration > 0 [s]")
        if not (isinstance(nodes, (int, np.integer)) and 3 <= nodes <= MAX_NODES):
            raise InputError(f"nodes = {nodes!r}; expected an integer from 3 to {MAX_NODES:,}")
        self.nodes = int(nodes)
        if derivatives not in DERIVATIVES:
            raise InputError(f"derivatives = {derivatives!r}; expected one of {', '.join(DERIVATIVES)}")
        self.derivatives = derivatives
        if derivatives == "analytic":  # a constraint without a derivative rule: one line now, not at IPOPT's points
            _derivative_rules(robot)
        self.n, self.k, self.m = len(robot.coordinates), len(robot.velocity_names), len(robot.motors)
        if self.m == 0:
            raise InputError(f"robot {robot.spec.name!r} has no motors: nothing to optimise")
        self.q0 = robot.check_q(q0)
        self.nu0 = np.zeros(self.k) if nu0 is None else robot.check_nu(nu0)
        self._holonomic_setup()
        if cost not in COSTS:
            raise InputError(f"cost = {cost!r}; expected one of {', '.join(COSTS)}")
        self.cost_kind = cost
        self.effort_weight = _finite(effort_weight, "effort_weight")
        if self.effort_weight < 0:
            raise InputError(f"effort_weight = {effort_weight!r}; expected a finite number >= 0")
        self.rate_weight = _finite(rate_weight, "rate_weight")
        if self.rate_weight < 0:
            raise InputError(f"rate_weight = {rate_weight!r}; expected a finite number >= 0")
        force_derivatives = derivatives if force_derivatives is None else force_derivatives
        if force_derivatives not in DERIVATIVES:
            raise InputError(f"force_derivatives = {force_derivatives!r}; expected one of {', '.join(DERIVATIVES)}")
        self.limits = None
        if min_load is not None or mu_max is not None or cost == "peak-mu":
            from .contact_limits import ContactLimits

            self.limits = ContactLimits(robot, self.q0, None if min_load is None else _finite(min_load, "min_load"),
                                        None if mu_max is None else _finite(mu_max, "mu_max"),
                                        peak=cost == "peak-mu", derivatives=force_derivatives)
            self.limits.steps = self.steps
        self.force_derivatives = force_derivatives
        names = list(robot.coordinates) + list(robot.velocity_names)
        self.names = names
        nx = self.nx = self.n + self.k
        self.x_end = np.full(nx, np.nan)
        for name, value in (q_end or {}).items():
            if name not in robot.coordinates:
                raise InputError(f"q_end names {name!r}; expected one of the coordinates {robot.coordinates}")
            self.x_end[robot.coordinates.index(name)] = _finite(value, f"q_end[{name!r}]")
            if abs(self.x_end[robot.coordinates.index(name)]) > MAX_POSITION:
                raise InputError(f"q_end[{name!r}] = {value!r}; expected abs(value) <= {MAX_POSITION:g} m or rad "
                                 "(what a robot reaches)")
        nu_end = [0.0] * self.k if nu_end is None else list(nu_end)
        if len(nu_end) != self.k:
            raise InputError(f"nu_end has {len(nu_end)} entries; expected {self.k} ({robot.velocity_names})")
        for i, value in enumerate(nu_end):
            if value is not None:
                self.x_end[self.n + i] = _finite(value, f"nu_end[{i}]")
        self.tau_lo, self.tau_hi = _pair(tau_bounds, self.m, "tau_bounds")
        self.x_lo, self.x_hi = np.full(nx, -np.inf), np.full(nx, np.inf)
        self.x_lo[:self.n] = robot.description.lower  # the joint ranges (the dynamics refuse a q beyond them)
        self.x_hi[:self.n] = robot.description.upper
        for name, pair in (bounds or {}).items():
            if name not in names:
                raise InputError(f"bounds names {name!r}; expected a coordinate or velocity name of {names}")
            lo, hi = _pair(pair, 1, f"bounds[{name!r}]")
            i = names.index(name)
            self.x_lo[i], self.x_hi[i] = max(lo[0], self.x_lo[i]), min(hi[0], self.x_hi[i])
            if self.x_lo[i] > self.x_hi[i]:
                raise InputError(f"bounds[{name!r}] = {pair!r} lies outside the joint range of {name}")
        self.held_rows = np.zeros(0, int)
        self.held = self._hold_rank_changes()
        x0 = np.concatenate([self.q0, self.nu0])
        for what, x in (("the initial state", x0), ("the final state", self.x_end)):
            bad = [names[i] for i in range(nx) if np.isfinite(x[i]) and not self.x_lo[i] <= x[i] <= self.x_hi[i]]
            if bad:
                raise InputError(f"{what} is outside the bounds on {', '.join(bad)}")
        self.guess = guess
        self.calls = {"dynamics": 0, "derivatives": 0}
        self._fast = None
        self._fast = self._compiled_rhs()
        self._defect_cache = self._jac_cache = (None, None)
        self._solving = threading.Lock()  # (solve: one at a time per problem)

    def _holonomic_setup(self) -> None:
        """The holonomic rows at q0: which are independent (:attr:`hrows`), the independent position coordinates
        (:attr:`positions`, those whose defects are kept) and the defect rows kept (:attr:`keep`)."""
        from ..reduction.projection import independent_rows

        rows = self.robot.rows_at(self.q0)
        A_h = rows.A[rows.holonomic]
        self.hrows = independent_rows(A_h) if A_h.size else np.zeros(0, int)
        self.mh = len(self.hrows)
        if self.mh:
            self.robot.check_constraints(self.q0, tol=HOLONOMIC_TOL, rows=rows)
            d = self.robot.dynamics_derivatives(self.q0, self.nu0, np.zeros(self.m))
            self.positions = np.asarray(d.positions, int)
            if len(self.positions) != self.n - self.mh:
                raise InputError(f"robot {self.robot.spec.name!r}: {self.n - len(self.positions)} coordinates follow "
                                 f"from {self.mh} independent holonomic rows at q0; expected as many")
        else:
            self.positions = np.arange(self.n)
        self.keep = np.concatenate([self.positions, self.n + np.arange(self.k)])
        from .manifold_steps import ManifoldSteps

        # finite differences in q step along the holonomic level set (a redundant loop would open otherwise)
        self.steps = ManifoldSteps(self._holonomic, self.positions, self.n) if self.mh else None

    def _hold_rank_changes(self) -> list[str]:
        """Hold, at their q0 values, the coordinates along which the constraints change rank and the velocities that
        move them (:mod:`robotdyn.optimisation.held_coordinates`: no motion of the robot leaves q0 along them): their
        bounds become that value and finite differences never step them.

        Returns:
            The held coordinates' and velocities' names (empty: none).

        Raises:
            InputError: ``q_end``, ``bounds``, ``nu0`` or ``nu_end`` asking one of them for another value.
        """
        from .held_coordinates import held_velocities, rank_changing
        from .manifold_steps import ManifoldSteps

        held = rank_changing(self.robot, self.q0, self.positions, None if self.steps is None else self.steps.pair)
        if not held:
            return []
        S = self.robot.reduced(self.q0, np.zeros(self.k)).S
        idx = held + [self.n + j for j in held_velocities(S, held, self.robot.coordinates, self.robot.velocity_names)]
        value = np.concatenate([self.q0, np.zeros(self.k)])
        why = (f"the constraints change rank along {', '.join(self.names[i] for i in held)} at q0 (rows redundant "
               "only there), so no motion leaves it and the optimisation holds")
        for i in idx:
            asked = [x for x in (self.x_end[i], self.nu0[i - self.n] if i >= self.n else value[i]) if np.isfinite(x)]
            if any(x != value[i] for x in asked) or not self.x_lo[i] <= value[i] <= self.x_hi[i]:
                raise InputError(f"{self.names[i]} is asked to move, but {why} it at {value[i]:g}; expected no end "
                                 f"value, start value or bound on {self.names[i]} other than {value[i]:g}")
            self.x_lo[i] = self.x_hi[i] = value[i]
        if self.steps is None:  # finite differences step through ManifoldSteps, which skips the held coordinates
            self.steps = ManifoldSteps(self._holonomic, self.positions, self.n)
            if self.limits is not None:
                self.limits.steps = self.steps
        self.steps.held = set(held)
        # their defects are not constraints of the NLP: a held coordinate's is 0 = 0, a held velocity's (its
        # acceleration at the nodes) is implied to first order by the holonomic rows at the held coordinates, and
        # kept would leave the constraints' Jacobian rank-deficient; solve() checks them at the optimum instead
        self.held_rows = np.asarray(idx, int)
        self.keep = self.keep[~np.isin(self.keep, idx)]
        return [self.names[i] for i in idx]

    def _holonomic(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The independent holonomic rows' residuals (mh,) [m or rad] at q and their Jacobian (mh, n) (the rows
        A_h, exactly the residuals' gradient on the manifold)."""
        rows = self.robot.rows_at(q)
        hol = np.flatnonzero(rows.holonomic)[self.hrows]
        return rows.residual[hol], rows.A[hol]

    def __repr__(self) -> str:
        fixed = [self.names[i] for i in range(self.nx) if np.isfinite(self.x_end[i])]
        bounded = [self.names[i] for i in range(self.nx) if np.isfinite(self.x_lo[i]) or np.isfinite(self.x_hi[i])]
        return (f"TrajectoryProblem(robot={self.robot.spec.name!r}, t_end={self.t_end:g} s, nodes={self.nodes}, "
                f"final={fixed}, bounded={bounded}, tau in [{_fmt(self.tau_lo)}, {_fmt(self.tau_hi)}], "
                f"derivatives={self.derivatives!r}"
                + ("" if self.limits is None else f", min_load={self.limits.min_load}, mu_max={self.limits.mu_max}")
                + ("" if self.cost_kind == "effort" else f", cost='peak-mu', effort_weight={self.effort_weight:g}")
                + (f", held={self.held} (the constraints change rank along them)" if self.held else "") + ")")

    # --- the dynamics at the nodes -------------------------------------------------------------------------------

    @property
    def nz(self) -> int:
        """Length of the decision vector: the states, the torques and (cost ``peak-mu``) the peak variable."""
        return self.nodes * (self.nx + self.m) + (self.cost_kind == "peak-mu")

    def _split(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        N, nx = self.nodes, self.nx
        return z[:N * nx].reshape(N, nx), z[N * nx:N * (nx + self.m)].reshape(N, self.m)

    def _peak(self, z: np.ndarray) -> float:
        return float(z[-1]) if self.cost_kind == "peak-mu" else 0.0

    def _compiled_rhs(self):
        """The robot's compiled one-call :math:`(S\\nu, \\dot\\nu)` (:meth:`robotdyn.fast.compiled.CompiledModel.rhs`,
        what the simulation integrates) where it serves this robot and equals the Python path at q0, else None."""
        from ..contact.sliding import slipping_wheels
        from ..fast.dispatch import compiled_model

        # (joint springs and dampers are compiled: the rhs and the derivative set carry their Q; compliant wheels
        # are not, and compiled_model answers None for them)
        fast = None if slipping_wheels(self.robot) else compiled_model(self.robot)
        if fast is None:
            return None
        self._fast = None
        tau = np.linspace(-1.0, 1.0, self.m)
        nu = np.linspace(0.1, 0.2, self.k)
        try:
            ok = np.allclose(fast.rhs(self.q0, nu, tau, 0.0), self._f(np.concatenate([self.q0, nu]), tau),
                             rtol=1e-9, atol=1e-9)
        except Exception:  # a compiled fallback: the Python path serves
            ok = False
        return fast if ok else None

    def _f(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """:math:`f(x, \\tau) = (S\\nu, \\dot\\nu)` at one node."""
        self.calls["dynamics"] += 1
        q, nu = x[:self.n], x[self.n:]
        fast = self._fast
        if fast is not None:
            try:
                return np.array(fast.rhs(q, nu, u, 0.0))
            except Fallback:
                pass
        S = self.robot.reduced(q, nu).S
        nudot = self.robot.forward_dynamics(q, nu, u, check=False)
        return np.concatenate([S @ nu, nudot])

    def _jac_node(self, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:math:`(\\partial f/\\partial x, \\partial f/\\partial\\tau)` at one node, (nx, nx) and (nx, m)."""
        n = self.n
        if self.derivatives == "analytic":
            self.calls["derivatives"] += 1
            fast = self._fast
            if fast is not None:  # the compiled derivative set in one call (as _f takes the compiled rhs)
                raw = raw_derivatives(fast, x[:n], x[n:], u)
                if raw is not None:
                    _, dq, dnu, dtau, _, Vq, S, _ = raw
                    Fx, Fu = np.empty((self.nx, self.nx)), np.zeros((self.nx, self.m))
                    Fx[:n, :n], Fx[:n, n:], Fx[n:, :n], Fx[n:, n:] = Vq, S, dq, dnu
                    Fu[n:] = dtau
                    return Fx, Fu
            d = self.robot.dynamics_derivatives(x[:n], x[n:], u)
            Fx = np.block([[d.dqdot_dq, d.S], [d.dq, d.dnu]])
            Fu = np.vstack([np.zeros((n, self.m)), d.dtau])
            return Fx, Fu
        y = np.concatenate([x, u])
        J = np.empty((self.nx, y.size))
        for i in range(y.size):
            if i < self.nx and self.x_lo[i] == self.x_hi[i]:  # a variable its bounds fix: IPOPT never uses its column
                J[:, i] = 0.0
                continue
            step = np.cbrt(np.finfo(float).eps) * (1.0 + abs(y[i]))
            yp, ym = y.copy(), y.copy()
            yp[i] += step
            ym[i] -= step
            if self.steps is not None and i < n:  # along the holonomic level set; dependent columns zero
                pair = self.steps.pair(x[:n], i, step)
                if pair is None:
                    J[:, i] = 0.0
                    continue
                yp[:n], ym[:n] = pair
            J[:, i] = (self._f(yp[:self.nx], yp[self.nx:]) - self._f(ym[:self.nx], ym[self.nx:])) / (2 * step)
        return J[:, :self.nx], J[:, self.nx:]

    def _jac_nodes(self, X: np.ndarray, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:math:`(\\partial f/\\partial x, \\partial f/\\partial\\tau)` at every node, (N, nx, nx) and (N, nx, m)
        (all nodes in one compiled call, :mod:`robotdyn.optimisation.node_batches`, where it serves, else
        :meth:`_jac_node` at each), in two stacked arrays that :meth:`jacobian_values` slices at once."""
        N = len(X)
        if self.derivatives == "analytic":  # all nodes in one compiled call where it serves (node_batches)
            batch = analytic_jacobians(self._fast, self.n, X, U)
            self.calls["derivatives"] += N if batch is not None else 0
        else:
            batch = central_jacobians(self._fast, self.n, X, U, self.steps)
            if batch is not None:
                self.calls["dynamics"] += batch[2]
                batch = batch[:2]
        if batch is not None:
            return batch
        Fx = np.empty((N, self.nx, self.nx))
        Fu = np.empty((N, self.nx, self.m))
        for j in range(N):
            Fx[j], Fu[j] = self._jac_node(X[j], U[j])
        return Fx, Fu

    def defects(self, z: np.ndarray) -> np.ndarray:
        """Trapezoidal defects :math:`x_{j+1} - x_j - \\tfrac{h}{2}(f_j + f_{j+1})`, (N-1, nx) flattened.

        Args:
            z: Decision vector (:attr:`nz`,): the states :math:`x_j = (q_j, \\nu_j)` node after node, then the
                torques :math:`\\tau_j` node after node [SI units], then (cost ``peak-mu``) the peak variable.

        Returns:
            The defects ((N-1) nx,), node-major, in the state's (q, nu) order.
        """
        key = z.tobytes()
        cached, value = self._defect_cache  # (one read: another thread may replace the pair meanwhile)
        if cached == key:
            return value
        X, U = self._split(z)
        F = rhs_nodes(self._fast, self.n, X, U)  # all nodes in one compiled call, else node by node
        if F is None:
            F = np.array([self._f(X[j], U[j]) for j in range(self.nodes)])
        else:
            self.calls["dynamics"] += self.nodes
        h = self.t_end / (self.nodes - 1)
        out = (X[1:] - X[:-1] - 0.5 * h * (F[1:] + F[:-1])).ravel()
        if not np.all(np.isfinite(out)):
            raise NonFiniteError("trajectory optimisation: the dynamics are not finite at an iterate")
        self._defect_cache = (key, out)
        return out

    def constraints(self, z: np.ndarray) -> np.ndarray:
        """The NLP's constraint vector: the defects of the independent position coordinates and the velocities
        ((N-1) (p + k)), the independent holonomic residuals at nodes 1..N-1 ((N-1) mh, the dependent coordinates
        follow from them instead of their defects), then the contact rows of every node (N c,
        :class:`~robotdyn.optimisation.contact_limits.ContactLimits`).

        Args:
            z: Decision vector, as for :meth:`defects`.

        Returns:
            The constraint values, in that order.
        """
        N = self.nodes
        parts = [self.defects(z).reshape(N - 1, self.nx)[:, self.keep].ravel()]
        X, U = self._split(z)
        if self.mh:
            parts.append(np.concatenate([self._holonomic(X[j, :self.n])[0] for j in range(1, N)]))
        if self.limits is not None:
            s = self._peak(z)
            parts.append(np.concatenate([self.limits.values(X[j, :self.n], X[j, self.n:], U[j], s)
                                         for j in range(N)]))
        return np.concatenate(parts)

    def _blocks(self) -> list[tuple[int, int, int, int]]:
        """The Jacobian's dense blocks ``(row, column, rows, columns)``, in the order :meth:`jacobian_values`
        fills them."""
        N, nx, m, nd = self.nodes, self.nx, self.m, len(self.keep)
        out = []
        for j in range(N - 1):
            r = j * nd
            out += [(r, j * nx, nd, nx), (r, (j + 1) * nx, nd, nx), (r, N * nx + j * m, nd, m),
                    (r, N * nx + (j + 1) * m, nd, m)]
        r0 = (N - 1) * nd
        for j in range(1, N) if self.mh else ():
            out.append((r0 + (j - 1) * self.mh, j * nx, self.mh, self.n))
        r0 += (N - 1) * self.mh
        if self.limits is not None:
            c = self.limits.rows_per_node
            for j in range(N):
                out += [(r0 + j * c, j * nx, c, nx), (r0 + j * c, N * nx + j * m, c, m)]
                if self.cost_kind == "peak-mu":
                    out.append((r0 + j * c, self.nz - 1, c, 1))
        return out

    @property
    def n_constraints(self) -> int:
        """Length of :meth:`constraints`."""
        c = self.limits.rows_per_node if self.limits is not None else 0
        return (self.nodes - 1) * (len(self.keep) + self.mh) + self.nodes * c

    def _pattern(self):
        """Triplets (rows, cols) of the constraints' Jacobian, block by block in the order :meth:`jacobian_values`
        fills them."""
        rows, cols = [], []
        for r0, c0, nr, nc in self._blocks():
            rr, cc = np.meshgrid(r0 + np.arange(nr), c0 + np.arange(nc), indexing="ij")
            rows.append(rr.ravel())
            cols.append(cc.ravel())
        return np.concatenate(rows), np.concatenate(cols)

    def jacobian_values(self, z: np.ndarray) -> np.ndarray:
        """Values of the constraints' Jacobian :math:`\\partial(\\text{constraints})/\\partial z` at its structural
        nonzeros, block after block as :meth:`_blocks` lists them (each row-major): per interval
        :math:`\\partial/\\partial x_j, \\partial/\\partial x_{j+1}, \\partial/\\partial\\tau_j,
        \\partial/\\partial\\tau_{j+1}` of the kept defects, then the holonomic rows A_h at each node, then per node
        the contact rows' :math:`\\partial/\\partial x_j, \\partial/\\partial\\tau_j` (and :math:`\\partial/\\partial s`).

        Args:
            z: Decision vector, as for :meth:`defects`.

        Returns:
            The values (nnz,), in the order given above (that of the problem's sparsity pattern).
        """
        key = z.tobytes()
        cached, value = self._jac_cache  # (one read, as in defects)
        if cached == key:  # IPOPT asks again at the same point (e.g. after a function evaluation)
            return value
        X, U = self._split(z)
        N = self.nodes
        h = self.t_end / (N - 1)
        I = np.eye(self.nx)[self.keep]
        Fx, Fu = self._jac_nodes(X, U)
        Fx, Fu = Fx[:, self.keep], Fu[:, self.keep]
        # per interval j the four blocks d/dx_j, d/dx_{j+1}, d/dtau_j, d/dtau_{j+1}, each row-major (_blocks)
        vals = [np.concatenate([(-I - 0.5 * h * Fx[:-1]).reshape(N - 1, -1), (I - 0.5 * h * Fx[1:]).reshape(N - 1, -1),
                                (-0.5 * h * Fu[:-1]).reshape(N - 1, -1), (-0.5 * h * Fu[1:]).reshape(N - 1, -1)],
                               axis=1).ravel()]
        for j in range(1, N) if self.mh else ():
            vals.append(self._holonomic(X[j, :self.n])[1].ravel())
        if self.limits is not None:
            s = self._peak(z)
            for j in range(N):
                Jx, Ju, Js = self.limits.jacobian(X[j, :self.n], X[j, self.n:], U[j], s)
                vals += [Jx.ravel(), Ju.ravel()] + ([Js.ravel()] if self.cost_kind == "peak-mu" else [])
        out = np.concatenate(vals)
        if not np.all(np.isfinite(out)):
            raise NonFiniteError("trajectory optimisation: the dynamics' derivatives are not finite at an iterate")
        self._jac_cache = (key, out)
        return out

    # --- the NLP ---------------------------------------------------------------------------------------------------

    def _initial(self) -> np.ndarray:
        z = self._initial_states()
        if self.cost_kind == "peak-mu":  # s starts at the guess's own peak (squared): a feasible start for its rows
            X, U = self._split(z)
            F = np.array([self.limits.forces(X[j, :self.n], X[j, self.n:], U[j]) for j in range(self.nodes)])
            ratio = (F[..., 0] ** 2 + F[..., 1] ** 2) / np.maximum(F[..., 2], 1e-9 * self.limits.scale) ** 2
            z[-1] = min(float(np.max(ratio)), 1e6)
        return z

    def _initial_states(self) -> np.ndarray:
        N = self.nodes
        extra = [np.ones(1)] if self.cost_kind == "peak-mu" else []
        if self.guess is not None:
            q, nu, tau = (np.asarray(a, float) for a in self.guess)
            if q.shape != (N, self.n) or nu.shape != (N, self.k) or tau.shape != (N, self.m):
                raise InputError(f"guess shapes {q.shape}, {nu.shape}, {tau.shape}; expected ({N}, {self.n}), "
                                 f"({N}, {self.k}), ({N}, {self.m})")
            return np.concatenate([np.hstack([q, nu]).ravel(), tau.ravel()] + extra)
        x0 = np.concatenate([self.q0, self.nu0])
        x1 = np.where(np.isfinite(self.x_end), self.x_end, x0)
        t = np.linspace(0.0, self.t_end, N)
        s = 0.5 * (1.0 - np.cos(np.pi * t / self.t_end))  # smooth, at rest at both ends
        sdot = 0.5 * np.pi / self.t_end * np.sin(np.pi * t / self.t_end)
        X = x0 + s[:, None] * (x1 - x0)
        dq = x1[:self.n] - x0[:self.n]
        inner = X[1:-1, :self.n].copy()
        Ss = []
        for j in range(1, N - 1):  # velocities that best follow the coordinates' path (least squares on S)
            S = self.robot.reduced(X[j, :self.n], np.zeros(self.k)).S
            Ss.append(S)
            X[j, self.n:] = np.linalg.lstsq(S, sdot[j] * dq, rcond=None)[0]
        # kept for robotdyn.optimisation.scaling: the S(q_j) and their q_j, published as one finished pair (a thread
        # scaling this problem while another solve builds its guess reads the old pair or the new, never a half)
        self._guess_S_q = (np.array(Ss), inner)
        X[-1] = np.where(np.isfinite(self.x_end), self.x_end, X[-1])
        return np.concatenate([np.clip(X, self.x_lo, self.x_hi).ravel(), np.zeros(N * self.m)] + extra)

    def solve(self, tol: float = 1e-9, max_iter: int = 500, verbose: bool = False) -> TrajectorySolution:
        """Solve with IPOPT (CasADi ``nlpsol``, limited-memory Hessian).

        A problem may be solved from any thread (each evaluates its own compiled model). Calls on one problem from
        several threads at once run one after the other (the problem keeps its initial guess, caches and counters
        during a solve); problems built for the same robot solve in parallel.

        Args:
            tol: IPOPT's convergence tolerance (scaled KKT error) and its largest constraint violation [state units].
            max_iter: Largest number of IPOPT iterations.
            verbose: Print IPOPT's iteration log.

        Returns:
            A :class:`TrajectorySolution` (``success`` False, with IPOPT's status, if it did not converge).
        """
        if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
            raise InputError(f"tol = {tol!r}; expected a finite number > 0")
        if int(max_iter) != max_iter or max_iter < 0:
            raise InputError(f"max_iter = {max_iter!r}; expected an integer >= 0")
        with self._solving:
            return self._solve(tol, int(max_iter), verbose)

    def _solve(self, tol: float, max_iter: int, verbose: bool) -> TrajectorySolution:
        """:meth:`solve` after its checks, under the problem's lock."""
        ca = _casadi()
        N, nx, m = self.nodes, self.nx, self.m
        nz, ng = self.nz, self.n_constraints
        rows, cols = self._pattern()
        self._callbacks = []  # CasADi holds no Python reference to them
        constraints = sparse_callback("constraints", nz, ng, self.constraints, self.jacobian_values, rows, cols,
                                      self._callbacks)
        z0 = self._initial()
        # IPOPT's variables zhat = z / D and objective cf * cost: the torques in units of their expected size and the
        # effort in units of its expected value (robotdyn.optimisation.scaling; powers of 2, exact)
        D, cf = np.ones(nz), 1.0
        if self.cost_kind == "effort":
            units, cf = effort_units(self, z0)
            D[N * nx:N * (nx + m)] = np.tile(units, N)
        zhat = ca.MX.sym("z", nz)
        z = ca.DM(D) * zhat
        h = self.t_end / (N - 1)
        w = np.full(N, h)
        w[[0, -1]] = 0.5 * h
        weights = ca.DM(np.repeat(w, m))
        u = z[N * nx:N * (nx + m)]
        effort = ca.dot(weights * u, u)
        cost = effort if self.cost_kind == "effort" else z[nz - 1] + self.effort_weight * effort
        if self.rate_weight > 0:  # the torques' rate, sum |tau_{j+1} - tau_j|^2 / h (the integral of |dtau/dt|^2)
            du = u[m:] - u[:-m]
            cost = cost + self.rate_weight / h * ca.dot(du, du)
        lbx = np.concatenate([np.tile(self.x_lo, N), np.tile(self.tau_lo, N)])
        ubx = np.concatenate([np.tile(self.x_hi, N), np.tile(self.tau_hi, N)])
        if self.cost_kind == "peak-mu":  # s = (peak required mu)^2, within mu_max^2 if given
            mu_max = self.limits.mu_max
            lbx = np.append(lbx, 0.0)
            ubx = np.append(ubx, np.inf if mu_max is None else mu_max ** 2)
        x0 = np.concatenate([self.q0, self.nu0])
        lbx[:nx] = ubx[:nx] = x0
        fixed = np.flatnonzero(np.isfinite(self.x_end))
        lbx[(N - 1) * nx + fixed] = ubx[(N - 1) * nx + fixed] = self.x_end[fixed]
        lbg, ubg = np.zeros(ng), np.zeros(ng)
        if self.limits is not None:
            lo, hi = self.limits.bounds()
            c = self.limits.rows_per_node
            lbg[ng - N * c:], ubg[ng - N * c:] = np.tile(lo, N), np.tile(hi, N)
        opts = {"ipopt.hessian_approximation": "limited-memory", "ipopt.tol": tol, "ipopt.constr_viol_tol": tol,
                "ipopt.max_iter": int(max_iter), "ipopt.print_level": 5 if verbose else 0, "print_time": bool(verbose),
                "ipopt.sb": "yes", "ipopt.honor_original_bounds": "yes",
                "show_eval_warnings": False}  # a refused trial point: robotdyn.optimisation.callbacks._refused
        solver = ca.nlpsol("trajectory", "ipopt", {"x": zhat, "f": cf * cost, "g": constraints(z)}, opts)
        self.calls = {"dynamics": 0, "derivatives": 0}
        if self.limits is not None:
            self.limits.calls = 0
        self._defect_cache = self._jac_cache = (None, None)
        start = time.perf_counter()
        res = solver(x0=z0 / D, lbx=lbx / D, ubx=ubx / D, lbg=lbg, ubg=ubg)
        wall = time.perf_counter() - start
        stats = solver.stats()
        self.refused = refusal(self._callbacks)  # the model's first error at a trial point (None: none)
        zopt = np.asarray(res["x"], float).ravel() * D
        X, U = self._split(zopt)
        calls = dict(self.calls)
        if self.limits is not None:
            calls["forces"] = self.limits.calls
        g = self.constraints(zopt)
        nd = (N - 1) * (len(self.keep) + self.mh)
        max_defect = float(np.max(np.abs(g[:nd])))
        held = float(np.max(np.abs(self.defects(zopt).reshape(N - 1, nx)[:, self.held_rows]), initial=0.0))
        success = bool(stats["success"]) and held <= HELD_TOL  # the held rows' defects (see _hold_rank_changes)
        max_defect = max(max_defect, held)
        t = np.linspace(0.0, self.t_end, N)
        forces, wheels = None, []
        if self.limits is not None:
            forces = np.array([self.limits.forces(X[j, :self.n], X[j, self.n:], U[j]) for j in range(N)])
            wheels = list(self.limits.wheels)
        effort = float(np.sum(np.repeat(w, m) * U.ravel() ** 2))
        return TrajectorySolution(t, X[:, :self.n].copy(), X[:, self.n:].copy(), U.copy(), float(res["f"]) / cf,
                                  str(stats["return_status"]) + ("" if success or not stats["success"] else
                                                                 f"; held rows' largest defect {held:.2g}"),
                                  success, int(stats["iter_count"]),
                                  wall, calls["dynamics"], calls["derivatives"], max_defect, self.derivatives,
                                  list(self.robot.coordinates), list(self.robot.velocity_names),
                                  [mo.name for mo in self.robot.motors], forces=forces, wheels=wheels,
                                  effort=effort, force_calls=calls.get("forces", 0), cost_kind=self.cost_kind)


def _derivative_rules(robot) -> None:
    """Refuse, in one line, a robot some of whose constraints have no analytic derivative rule (a compliant wheel,
    exact Coulomb or stick-slip friction, a user's own constraint class): the checks of
    :meth:`robotdyn.robot.Robot.dynamics_derivatives`, made once before the solve (a robot without holonomic rows
    met them only at IPOPT's first point, as a failed solve)."""
    from ..constraints.row_derivatives import kind
    from ..contact.sliding import sliding_now

    sliding = bool(sliding_now(robot))
    if sliding:
        from ..contact.sliding_derivatives import smooth_sliding

        smooth_sliding(robot)
    for c in robot.constraints:
        kind(c, sliding=sliding)


def _finite(value, what: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        out = math.nan
    if not math.isfinite(out):
        raise InputError(f"{what} = {value!r}; expected a finite number")
    return out


def _pair(pair, size: int, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``(lower, upper)`` as two arrays of ``size`` (None: unbounded)."""
    if pair is None:
        return np.full(size, -np.inf), np.full(size, np.inf)
    try:
        lo, hi = pair
        lo = np.broadcast_to(np.asarray(lo, float), (size,)).copy()
        hi = np.broadcast_to(np.asarray(hi, float), (size,)).copy()
    except (TypeError, ValueError):
        raise InputError(f"{what} = {pair!r}; expected (lower, upper), each a number or {size} numbers") from None
    if np.any(np.isnan(lo)) or np.any(np.isnan(hi)) or np.any(lo > hi):
        raise InputError(f"{what} = {pair!r}; expected lower <= upper, no NaN")
    return lo, hi


def _fmt(a: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:g}" for v in a) + "]"


__all__ = ["TrajectoryProblem", "TrajectorySolution", "DERIVATIVES", "COSTS", "HOLONOMIC_TOL", "HELD_TOL",
           "FEASIBLE_DEFECT"]

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
comparison, central finite differences of the forward dynamics (``derivatives="finite-difference"``). The cost is
quadratic and its gradient exact in both cases; IPOPT's Hessian is its limited-memory (L-BFGS) approximation, in
both cases, so that the two differ only in the constraint Jacobian.

Solver choice: IPOPT (interior point, sparse, the reference NLP solver of the optimal-control community) through
CasADi's ``nlpsol``, because CasADi's PyPI wheel bundles IPOPT with its sparse linear solver (MUMPS): it installs
with pip alone on Linux, macOS and Windows (``casadi`` 3.8: a 93 MB wheel, 277 MB installed, ~7 s to install),
whereas cyipopt has no Linux wheel and its build fails without a system IPOPT (pkg-config finds no ``ipopt``), and
scipy's ``trust-constr`` is not a sparse interior-point solver for large NLPs. The robot's dynamics enter as one
CasADi ``Callback`` (all defects at once) whose Jacobian is another ``Callback`` with a declared sparsity pattern:
the analytic derivatives are passed as callbacks; CasADi's automatic differentiation is not used through Pinocchio.

Scope: robots without holonomic constraint rows (their natural coordinates are then all independent, e.g.
Quasimoro; a robot with loop closures or terrain-following rows is refused in one line: its collocation would need
the holonomic rows as path constraints, not built here).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, NonFiniteError
from .callbacks import sparse_callback

DERIVATIVES = ("analytic", "finite-difference")
"""How the dynamics' Jacobian is computed (``derivatives`` of :class:`TrajectoryProblem`)."""


def _casadi():
    try:
        import casadi
    except ImportError as exc:  # pragma: no cover - the test extra installs it
        raise InputError("trajectory optimisation needs CasADi (pip install casadi, or the `test` extra)") from exc
    return casadi


@dataclass
class TrajectorySolution:
    """An optimal motion on the collocation nodes (SI units).

    Attributes:
        t: Node times (N,) [s].
        q: Natural coordinates at the nodes (N, n) [m, rad].
        nu: Independent velocities at the nodes (N, k) [m/s, rad/s].
        tau: Motor torques at the nodes (N, m) [N m or N]; linear in between.
        cost: :math:`\\int_0^T \\lVert\\tau\\rVert^2 dt` by the trapezoid rule [N^2 m^2 s].
        status: IPOPT's return status (``Solve_Succeeded`` on success).
        success: Whether IPOPT converged.
        iterations: IPOPT iterations.
        wall_time: Wall-clock time of the solve [s].
        dynamics_calls: Forward-dynamics evaluations (defects and, with finite differences, the Jacobian).
        derivative_calls: Analytic derivative evaluations (``dynamics_derivatives``), one per node per Jacobian.
        max_defect: Largest collocation defect at the optimum (state units).
        derivatives: ``analytic`` or ``finite-difference``.
        coordinates, velocity_names, motors: Column names of q, nu and tau.
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

    def profile(self):
        """The optimal torques as a :class:`~robotdyn.simulation.torque_profile.Table` (linear between nodes,
        what the collocation assumed), for :func:`robotdyn.simulation.engine.simulate`.

        Returns:
            The :class:`~robotdyn.simulation.torque_profile.Table` of the node times [s] and torques [N m or N].
        """
        from ..simulation.torque_profile import Table

        return Table(self.t, self.tau)

    def __repr__(self) -> str:
        return (f"TrajectorySolution({self.status}, cost={self.cost:.6g} N^2 m^2 s, {len(self.t)} nodes, "
                f"{self.iterations} iterations, {self.wall_time:.3g} s, derivatives={self.derivatives})")


class TrajectoryProblem:
    """A minimum-effort motion of a robot between two states in a fixed time (see the module docstring).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` without holonomic constraint rows.
        t_end: Duration T [s] (> 0).
        nodes: Number of collocation nodes N (>= 3).
        q0: Initial natural coordinates (n,) [m, rad].
        nu0: Initial independent velocities (k,) [m/s, rad/s] (default: at rest).
        q_end: Final values of some coordinates, by name {coordinate: value} [m or rad]; the others are free.
        nu_end: Final independent velocities (k,) (default: at rest); ``None`` entries are free.
        tau_bounds: ``(lower, upper)`` motor torques [N m or N], each a number or one per motor
            (default: unbounded).
        bounds: Bounds on coordinates or velocities at every node, by name {name: (lower, upper)} [SI units].
        derivatives: ``analytic`` (default) or ``finite-difference`` (central differences of the forward dynamics,
            the comparison).
        guess: Initial guess ``(q (N, n), nu (N, k), tau (N, m))`` (default: the coordinates from ``q0`` towards
            ``q_end`` along a smooth rest-to-rest ramp, the velocities that best follow it through S(q) in least
            squares, no torque; a guess at rest everywhere can make the defects' Jacobian rank-deficient for
            nonholonomic robots).

    Raises:
        InputError: A wrong size, name or bound, a robot with holonomic rows, non-finite data.
    """

    def __init__(self, robot, t_end: float, nodes: int, q0, nu0=None, q_end: dict | None = None,
                 nu_end=None, tau_bounds=None, bounds: dict | None = None, derivatives: str = "analytic",
                 guess=None) -> None:
        self.robot = robot
        self.t_end = _finite(t_end, "t_end")
        if not self.t_end > 0:
            raise InputError(f"t_end = {t_end!r}; expected a finite duration > 0 [s]")
        if not (isinstance(nodes, (int, np.integer)) and nodes >= 3):
            raise InputError(f"nodes = {nodes!r}; expected an integer >= 3")
        self.nodes = int(nodes)
        if derivatives not in DERIVATIVES:
            raise InputError(f"derivatives = {derivatives!r}; expected one of {', '.join(DERIVATIVES)}")
        self.derivatives = derivatives
        self.n, self.k, self.m = len(robot.coordinates), len(robot.velocity_names), len(robot.motors)
        if self.m == 0:
            raise InputError(f"robot {robot.spec.name!r} has no motors: nothing to optimise")
        self.q0 = robot.check_q(q0)
        self.nu0 = np.zeros(self.k) if nu0 is None else robot.check_nu(nu0)
        holonomic = self._holonomic_rows()
        if holonomic:
            raise InputError(f"robot {robot.spec.name!r} has {holonomic} holonomic constraint row(s); trajectory "
                             "optimisation supports robots whose coordinates are all independent")
        names = list(robot.coordinates) + list(robot.velocity_names)
        self.names = names
        nx = self.nx = self.n + self.k
        self.x_end = np.full(nx, np.nan)
        for name, value in (q_end or {}).items():
            if name not in robot.coordinates:
                raise InputError(f"q_end names {name!r}; expected one of the coordinates {robot.coordinates}")
            self.x_end[robot.coordinates.index(name)] = _finite(value, f"q_end[{name!r}]")
        nu_end = [0.0] * self.k if nu_end is None else list(nu_end)
        if len(nu_end) != self.k:
            raise InputError(f"nu_end has {len(nu_end)} entries; expected {self.k} ({robot.velocity_names})")
        for i, value in enumerate(nu_end):
            if value is not None:
                self.x_end[self.n + i] = _finite(value, f"nu_end[{i}]")
        self.tau_lo, self.tau_hi = _pair(tau_bounds, self.m, "tau_bounds")
        self.x_lo, self.x_hi = np.full(nx, -np.inf), np.full(nx, np.inf)
        for name, pair in (bounds or {}).items():
            if name not in names:
                raise InputError(f"bounds names {name!r}; expected a coordinate or velocity name of {names}")
            lo, hi = _pair(pair, 1, f"bounds[{name!r}]")
            self.x_lo[names.index(name)], self.x_hi[names.index(name)] = lo[0], hi[0]
        x0 = np.concatenate([self.q0, self.nu0])
        for what, x in (("the initial state", x0), ("the final state", self.x_end)):
            bad = [names[i] for i in range(nx) if np.isfinite(x[i]) and not self.x_lo[i] <= x[i] <= self.x_hi[i]]
            if bad:
                raise InputError(f"{what} is outside the bounds on {', '.join(bad)}")
        self.guess = guess
        self.calls = {"dynamics": 0, "derivatives": 0}
        self._defect_cache = self._jac_cache = (None, None)

    def _holonomic_rows(self) -> int:
        """Number of coordinates fixed by holonomic rows at q0 (n less the independent position coordinates)."""
        d = self.robot.dynamics_derivatives(self.q0, self.nu0, np.zeros(self.m))
        return self.n - len(d.positions)

    def __repr__(self) -> str:
        fixed = [self.names[i] for i in range(self.nx) if np.isfinite(self.x_end[i])]
        bounded = [self.names[i] for i in range(self.nx) if np.isfinite(self.x_lo[i]) or np.isfinite(self.x_hi[i])]
        return (f"TrajectoryProblem(robot={self.robot.spec.name!r}, t_end={self.t_end:g} s, nodes={self.nodes}, "
                f"final={fixed}, bounded={bounded}, tau in [{_fmt(self.tau_lo)}, {_fmt(self.tau_hi)}], "
                f"derivatives={self.derivatives!r})")

    # --- the dynamics at the nodes -------------------------------------------------------------------------------

    def _split(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        N, nx = self.nodes, self.nx
        return z[:N * nx].reshape(N, nx), z[N * nx:].reshape(N, self.m)

    def _f(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """:math:`f(x, \\tau) = (S\\nu, \\dot\\nu)` at one node."""
        self.calls["dynamics"] += 1
        q, nu = x[:self.n], x[self.n:]
        S = self.robot.reduced(q, nu).S
        nudot = self.robot.forward_dynamics(q, nu, u, check=False)
        return np.concatenate([S @ nu, nudot])

    def _jac_node(self, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:math:`(\\partial f/\\partial x, \\partial f/\\partial\\tau)` at one node, (nx, nx) and (nx, m)."""
        n = self.n
        if self.derivatives == "analytic":
            self.calls["derivatives"] += 1
            d = self.robot.dynamics_derivatives(x[:n], x[n:], u)
            Fx = np.block([[d.dqdot_dq, d.S], [d.dq, d.dnu]])
            Fu = np.vstack([np.zeros((n, self.m)), d.dtau])
            return Fx, Fu
        y = np.concatenate([x, u])
        J = np.empty((self.nx, y.size))
        for i in range(y.size):
            step = np.cbrt(np.finfo(float).eps) * (1.0 + abs(y[i]))
            yp, ym = y.copy(), y.copy()
            yp[i] += step
            ym[i] -= step
            J[:, i] = (self._f(yp[:self.nx], yp[self.nx:]) - self._f(ym[:self.nx], ym[self.nx:])) / (2 * step)
        return J[:, :self.nx], J[:, self.nx:]

    def defects(self, z: np.ndarray) -> np.ndarray:
        """Trapezoidal defects :math:`x_{j+1} - x_j - \\tfrac{h}{2}(f_j + f_{j+1})`, (N-1, nx) flattened.

        Args:
            z: Decision vector (N (nx + m),): the states :math:`x_j = (q_j, \\nu_j)` node after node, then the
                torques :math:`\\tau_j` node after node [SI units].

        Returns:
            The defects ((N-1) nx,), node-major, in the state's (q, nu) order.
        """
        key = z.tobytes()
        if self._defect_cache[0] == key:
            return self._defect_cache[1]
        X, U = self._split(z)
        F = np.array([self._f(X[j], U[j]) for j in range(self.nodes)])
        h = self.t_end / (self.nodes - 1)
        out = (X[1:] - X[:-1] - 0.5 * h * (F[1:] + F[:-1])).ravel()
        if not np.all(np.isfinite(out)):
            raise NonFiniteError("trajectory optimisation: the dynamics are not finite at an iterate")
        self._defect_cache = (key, out)
        return out

    def _pattern(self):
        """Triplets (rows, cols) of the defects' Jacobian, block by block in the order :meth:`jacobian_values`
        fills them."""
        N, nx, m = self.nodes, self.nx, self.m
        rows, cols = [], []
        for j in range(N - 1):
            r = j * nx + np.arange(nx)
            for c0, width in ((j * nx, nx), ((j + 1) * nx, nx), (N * nx + j * m, m), (N * nx + (j + 1) * m, m)):
                rr, cc = np.meshgrid(r, c0 + np.arange(width), indexing="ij")
                rows.append(rr.ravel())
                cols.append(cc.ravel())
        return np.concatenate(rows), np.concatenate(cols)

    def jacobian_values(self, z: np.ndarray) -> np.ndarray:
        """Values of the defects' Jacobian :math:`\\partial(\\text{defects})/\\partial z` at its structural nonzeros,
        interval after interval (blocks :math:`\\partial/\\partial x_j, \\partial/\\partial x_{j+1},
        \\partial/\\partial\\tau_j, \\partial/\\partial\\tau_{j+1}`, each row-major), from the node Jacobians.

        Args:
            z: Decision vector, as for :meth:`defects`.

        Returns:
            The values (nnz,), in the order given above (that of the problem's sparsity pattern).
        """
        key = z.tobytes()
        if self._jac_cache[0] == key:  # IPOPT asks again at the same point (e.g. after a function evaluation)
            return self._jac_cache[1]
        X, U = self._split(z)
        h = self.t_end / (self.nodes - 1)
        I = np.eye(self.nx)
        node = [self._jac_node(X[j], U[j]) for j in range(self.nodes)]
        vals = []
        for j in range(self.nodes - 1):
            (Fx0, Fu0), (Fx1, Fu1) = node[j], node[j + 1]
            vals += [(-I - 0.5 * h * Fx0).ravel(), (I - 0.5 * h * Fx1).ravel(), (-0.5 * h * Fu0).ravel(),
                     (-0.5 * h * Fu1).ravel()]
        out = np.concatenate(vals)
        if not np.all(np.isfinite(out)):
            raise NonFiniteError("trajectory optimisation: the dynamics' derivatives are not finite at an iterate")
        self._jac_cache = (key, out)
        return out

    # --- the NLP ---------------------------------------------------------------------------------------------------

    def _initial(self) -> np.ndarray:
        N = self.nodes
        if self.guess is not None:
            q, nu, tau = (np.asarray(a, float) for a in self.guess)
            if q.shape != (N, self.n) or nu.shape != (N, self.k) or tau.shape != (N, self.m):
                raise InputError(f"guess shapes {q.shape}, {nu.shape}, {tau.shape}; expected ({N}, {self.n}), "
                                 f"({N}, {self.k}), ({N}, {self.m})")
            return np.concatenate([np.hstack([q, nu]).ravel(), tau.ravel()])
        x0 = np.concatenate([self.q0, self.nu0])
        x1 = np.where(np.isfinite(self.x_end), self.x_end, x0)
        t = np.linspace(0.0, self.t_end, N)
        s = 0.5 * (1.0 - np.cos(np.pi * t / self.t_end))  # smooth, at rest at both ends
        sdot = 0.5 * np.pi / self.t_end * np.sin(np.pi * t / self.t_end)
        X = x0 + s[:, None] * (x1 - x0)
        dq = x1[:self.n] - x0[:self.n]
        for j in range(1, N - 1):  # velocities that best follow the coordinates' path (least squares on S)
            S = self.robot.reduced(X[j, :self.n], np.zeros(self.k)).S
            X[j, self.n:] = np.linalg.lstsq(S, sdot[j] * dq, rcond=None)[0]
        X[-1] = np.where(np.isfinite(self.x_end), self.x_end, X[-1])
        return np.concatenate([np.clip(X, self.x_lo, self.x_hi).ravel(), np.zeros(N * self.m)])

    def solve(self, tol: float = 1e-9, max_iter: int = 500, verbose: bool = False) -> TrajectorySolution:
        """Solve with IPOPT (CasADi ``nlpsol``, limited-memory Hessian).

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
        ca = _casadi()
        N, nx, m = self.nodes, self.nx, self.m
        nz, ng = N * (nx + m), (N - 1) * nx
        rows, cols = self._pattern()
        self._callbacks = []  # CasADi holds no Python reference to them
        defects = sparse_callback("defects", nz, ng, self.defects, self.jacobian_values, rows, cols,
                                  self._callbacks)
        z = ca.MX.sym("z", nz)
        h = self.t_end / (N - 1)
        w = np.full(N, h)
        w[[0, -1]] = 0.5 * h
        weights = ca.DM(np.repeat(w, m))
        u = z[N * nx:]
        cost = ca.dot(weights * u, u)
        lbx = np.concatenate([np.tile(self.x_lo, N), np.tile(self.tau_lo, N)])
        ubx = np.concatenate([np.tile(self.x_hi, N), np.tile(self.tau_hi, N)])
        x0 = np.concatenate([self.q0, self.nu0])
        lbx[:nx] = ubx[:nx] = x0
        fixed = np.flatnonzero(np.isfinite(self.x_end))
        lbx[(N - 1) * nx + fixed] = ubx[(N - 1) * nx + fixed] = self.x_end[fixed]
        opts = {"ipopt.hessian_approximation": "limited-memory", "ipopt.tol": tol, "ipopt.constr_viol_tol": tol,
                "ipopt.max_iter": int(max_iter), "ipopt.print_level": 5 if verbose else 0, "print_time": bool(verbose),
                "ipopt.sb": "yes", "ipopt.honor_original_bounds": "yes"}
        solver = ca.nlpsol("trajectory", "ipopt", {"x": z, "f": cost, "g": defects(z)}, opts)
        self.calls = {"dynamics": 0, "derivatives": 0}
        self._defect_cache = self._jac_cache = (None, None)
        start = time.perf_counter()
        res = solver(x0=self._initial(), lbx=lbx, ubx=ubx, lbg=0.0, ubg=0.0)
        wall = time.perf_counter() - start
        stats = solver.stats()
        zopt = np.asarray(res["x"], float).ravel()
        X, U = self._split(zopt)
        calls = dict(self.calls)
        max_defect = float(np.max(np.abs(self.defects(zopt))))
        t = np.linspace(0.0, self.t_end, N)
        return TrajectorySolution(t, X[:, :self.n].copy(), X[:, self.n:].copy(), U.copy(), float(res["f"]),
                                  str(stats["return_status"]), bool(stats["success"]), int(stats["iter_count"]),
                                  wall, calls["dynamics"], calls["derivatives"], max_defect, self.derivatives,
                                  list(self.robot.coordinates), list(self.robot.velocity_names),
                                  [mo.name for mo in self.robot.motors])


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


__all__ = ["TrajectoryProblem", "TrajectorySolution", "DERIVATIVES"]

"""The posture, and the motor torques holding it, that need the least friction: a robot at rest, solved by IPOPT.

The problem (one robot at rest, :math:`\\nu = 0`):

.. math:: \\min_{x,\\,\\tau,\\,s} s \\quad\\text{s.t.}\\quad \\dot\\nu(q(x), 0, \\tau) = 0,\\quad
          \\|F_{t,i}\\| - s\\,F_{n,i} \\le 0\\ (i \\in \\text{friction wheels}),\\quad
          F_{n,i} \\ge F_{\\min,i}\\ (\\text{all wheels}),\\quad x_{lo} \\le x \\le x_{hi},\\;
          \\tau_{lo} \\le \\tau \\le \\tau_{hi},

with x the chosen posture coordinates (each one coordinate, or a group of coordinates moved together), q(x) the
configuration on the holonomic manifold with every other independent position coordinate held
(:func:`robotdyn.constraints.posture.solve_posture` solves the dependent ones), :math:`\\dot\\nu` the forward
dynamics (so the robot holds still) and :math:`F_i` the contact forces Robot.contact_forces reports at that state
(normal load :math:`F_{n,i}` [N], tangential force :math:`F_{t,i}` in the contact plane). With positive loads the
cone rows say :math:`\\mu_i = \\|F_{t,i}\\|/F_{n,i} \\le s`, so s at the optimum is the least peak required mu
(written as cones so that every row stays finite where an iterate unloads a wheel). The torques are decision
variables: an over-actuated robot (more motors than velocities) may hold a posture with many torque sets, and the
optimiser picks one.

Derivatives: the constraint Jacobian is dense and comes from
:meth:`robotdyn.robot.Robot.contact_force_derivatives` (its ``dynamics`` for :math:`\\dot\\nu`), along the manifold
through its tangent (``derivatives="analytic"``), or from central differences of the constraint values
(``"finite-difference"``, the comparison). IPOPT runs through CasADi with the callback plumbing of
:mod:`robotdyn.optimisation.callbacks` (the same as :mod:`robotdyn.optimisation.trajectory`), the objective's
gradient exact, the Hessian limited-memory. The solution is the branch of the forces' current structure (see
:mod:`robotdyn.contact.force_derivatives`: components that rigid-body dynamics and the rigid limit leave open enter
with their minimum-norm values).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, NonFiniteError
from ..reduction.dynamics_derivatives import position_coordinates
from .callbacks import _casadi, sparse_callback
from .trajectory import DERIVATIVES, _pair


@dataclass
class PostureSolution:
    """A least-friction posture at rest (SI units).

    Attributes:
        q: Natural coordinates at the optimum (n,) [m, rad].
        tau: Holding motor torques (n_motors,) [N m or N].
        x: The decision coordinates' values (p,) [m or rad], named by ``variables``.
        peak_mu: The least peak required mu s at the optimum [-].
        required_mu: Each friction wheel's :math:`\\|F_t\\|/F_n` there (by ``friction_wheels``).
        loads: Every wheel's normal load [N] there (by ``wheels``).
        status: IPOPT's return status (``Solve_Succeeded`` on success).
        success: Whether IPOPT converged.
        iterations: IPOPT iterations.
        wall_time: Wall-clock time of the solve [s].
        evaluations: Constraint evaluations (forces at a posture), finite differences' included.
        derivative_calls: Analytic derivative evaluations (``contact_force_derivatives``).
        derivatives: ``analytic`` or ``finite-difference``.
        variables: Names of the decision coordinates (a group as ``a=b``).
        wheels, friction_wheels: Wheel names.
    """

    q: np.ndarray
    tau: np.ndarray
    x: np.ndarray
    peak_mu: float
    required_mu: np.ndarray
    loads: np.ndarray
    status: str
    success: bool
    iterations: int
    wall_time: float
    evaluations: int
    derivative_calls: int
    derivatives: str
    variables: list[str] = field(default_factory=list)
    wheels: list[str] = field(default_factory=list)
    friction_wheels: list[str] = field(default_factory=list)

    def __repr__(self) -> str:
        xs = ", ".join(f"{n}={v:.4g}" for n, v in zip(self.variables, self.x))
        return (f"PostureSolution({self.status}, peak mu {self.peak_mu:.6g}, {xs}; {self.iterations} iterations, "
                f"{self.wall_time:.3g} s, derivatives={self.derivatives})")


class PostureProblem:
    """The posture and holding torques of a robot at rest with the least peak required mu (module docstring).

    Args:
        robot: A :class:`~robotdyn.robot.Robot` with motors and wheels.
        q0: A configuration on the holonomic manifold (n,) [m, rad]: the start, and the values of the independent
            position coordinates that are not decision variables.
        variables: The decision coordinates: each a coordinate name, or a tuple of names moved together (one
            value); all must be independent position coordinates
            (:attr:`~robotdyn.contact.force_derivatives.ContactForceDerivatives.positions`).
        bounds: Bounds by variable {name: (lower, upper)} [m or rad] (a group by its first name); default the
            description's joint ranges.
        friction_wheels: Wheels whose required mu is minimised (default: every wheel that is not a support wheel).
        min_load: Smallest normal load [N] of every wheel: one number, or {wheel: value} (default 0).
        held: Coordinates held at q0's values, never among those the holonomic rows move (e.g. the base's x, y, yaw);
            default: none named (the dependent coordinates are then chosen among all non-variables).
        tau_bounds: ``(lower, upper)`` motor torques [N m or N], each a number or one per motor (default: none).
        derivatives: ``analytic`` (default) or ``finite-difference``.

    Raises:
        InputError: An unknown or dependent coordinate, an unknown wheel, a wrong bound.
    """

    def __init__(self, robot, q0, variables, bounds: dict | None = None, friction_wheels=None,
                 min_load: float | dict = 0.0, held=(), tau_bounds=None, derivatives: str = "analytic") -> None:
        if derivatives not in DERIVATIVES:
            raise InputError(f"derivatives = {derivatives!r}; expected one of {', '.join(DERIVATIVES)}")
        self.robot, self.derivatives = robot, derivatives
        self.q0 = robot.check_q(q0)
        self.m, self.k = len(robot.motors), robot.mobility
        if self.m == 0:
            raise InputError(f"robot {robot.spec.name!r} has no motors: nothing holds a posture")
        self.tau0 = robot.inverse_dynamics(self.q0, np.zeros(self.k), np.zeros(self.k))[1]
        d0 = robot.contact_force_derivatives(self.q0, np.zeros(self.k), self.tau0)
        self.groups = []
        for v in variables:
            group = (v,) if isinstance(v, str) else tuple(v)
            for c in group:
                if c not in robot.coordinates:
                    raise InputError(f"posture variable {c!r} is not a coordinate; expected one of "
                                     f"{', '.join(robot.coordinates)}")
            self.groups.append([robot.coordinate_index(c) for c in group])
        if not self.groups:
            raise InputError("no posture variables; expected at least one coordinate name")
        # independent position coordinates: the variables and as many held ones as the holonomic rows leave, the
        # dependent ones chosen among the others
        rows = robot.rows_at(self.q0)
        chosen = sorted({i for g in self.groups for i in g})
        keep = {robot.coordinate_index(c) for c in held}
        others = np.array([i for i in range(robot.nq) if i not in chosen and i not in keep], int)
        positions, _ = position_coordinates(rows.A[rows.holonomic], others)
        self.positions = list(positions)
        dependent = [robot.coordinates[i] for i in sorted(set(chosen) | keep) if i not in self.positions]
        if dependent:
            raise InputError(f"posture variables or held coordinates {dependent} are fixed by the holonomic "
                             "constraints once the others are given; expected independent coordinates (drop some)")
        self.variables = ["=".join(v) if not isinstance(v, str) else v for v in variables]
        self.wheels = list(d0.wheels)
        kinds = {w.name: w.kind for w in robot.contact_forces(self.q0, np.zeros(self.k), self.tau0).wheels}
        fw = [w for w in self.wheels if kinds[w] != "support"] if friction_wheels is None else list(friction_wheels)
        for w in fw:
            if w not in self.wheels:
                raise InputError(f"unknown wheel {w!r}; expected one of {', '.join(self.wheels)}")
        self.friction = [self.wheels.index(w) for w in fw]
        self.friction_wheels = fw
        if isinstance(min_load, dict):
            unknown = set(min_load) - set(self.wheels)
            if unknown:
                raise InputError(f"min_load names {sorted(unknown)}; expected wheels of {self.wheels}")
            self.min_load = np.array([float(min_load.get(w, 0.0)) for w in self.wheels])
        else:
            self.min_load = np.full(len(self.wheels), float(min_load))
        if not np.all(np.isfinite(self.min_load)):
            raise InputError(f"min_load = {min_load!r}; expected finite loads [N]")
        p = len(self.groups)
        lo = np.array([robot.description.lower[g[0]] for g in self.groups], float)
        hi = np.array([robot.description.upper[g[0]] for g in self.groups], float)
        for name, pair in (bounds or {}).items():
            first = [v.split("=")[0] for v in self.variables]
            if name not in first:
                raise InputError(f"bounds names {name!r}; expected one of the variables {first}")
            (a,), (b,) = _pair(pair, 1, f"bounds[{name!r}]")
            lo[first.index(name)], hi[first.index(name)] = a, b
        self.x_lo, self.x_hi = lo, hi
        self.tau_lo, self.tau_hi = _pair(tau_bounds, self.m, "tau_bounds")
        self.p = p
        self.nz = p + self.m + 1
        self.calls = {"evaluations": 0, "derivatives": 0}
        self._q_cache: dict[bytes, np.ndarray] = {}
        self._last_q = self.q0.copy()
        self._val_cache = self._jac_cache = (None, None)

    def __repr__(self) -> str:
        return (f"PostureProblem(robot={self.robot.spec.name!r}, variables={self.variables}, "
                f"friction wheels={self.friction_wheels}, min loads={self.min_load.tolist()} N, "
                f"derivatives={self.derivatives!r})")

    # --- the posture and the constraints -----------------------------------------------------------------------------

    def posture(self, x: np.ndarray) -> np.ndarray:
        """q(x): the decision coordinates set to x, the other independent ones held, the dependent ones solved.

        Args:
            x: The decision coordinates' values (p,) [m or rad].

        Returns:
            Natural coordinates (n,) on the holonomic manifold [m, rad].
        """
        from ..constraints.posture import solve_posture

        key = np.asarray(x, float).tobytes()
        if key not in self._q_cache:
            q = self.q0.copy()
            for g, v in zip(self.groups, x):
                q[g] = v
            fixed = {self.robot.coordinates[i]: q[i] for i in self.positions}
            guess = self._last_q.copy()
            guess[self.positions] = q[self.positions]
            if len(self.positions) < self.robot.nq:
                q = solve_posture(self.robot, fixed, q0=guess, tol=1e-13, check_limits=False).q
            self._q_cache = {key: q}
            self._last_q = q
        return self._q_cache[key]

    def tangent(self, q: np.ndarray) -> np.ndarray:
        """:math:`\\partial q/\\partial q_P` (n, p) at q for this problem's independent position coordinates:
        identity on them, the dependent coordinates following the holonomic rows to first order.

        Args:
            q: Natural coordinates (n,) on the holonomic manifold [m, rad].

        Returns:
            The tangent (n, len(positions)).
        """
        from ..reduction.projection import independent_rows

        n = self.robot.nq
        ind = np.array(self.positions, int)
        T = np.zeros((n, ind.size))
        T[ind, np.arange(ind.size)] = 1.0
        dep = np.setdiff1d(np.arange(n), ind)
        if dep.size:
            rows = self.robot.rows_at(q)
            A = rows.A[rows.holonomic]
            A = A[independent_rows(A)]
            T[dep] = -np.linalg.solve(A[:, dep], A[:, ind])
        return T

    def _split(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        return z[:self.p], z[self.p:self.p + self.m], float(z[-1])

    def values(self, z: np.ndarray) -> np.ndarray:
        """The constraints (:math:`\\dot\\nu` (k), the cones (friction wheels), the normal loads (all wheels)).

        Args:
            z: Decision vector (x (p), tau (n_motors), s) [SI units].

        Returns:
            The values (k + len(friction_wheels) + len(wheels),) [rad/s^2 or m/s^2, N, N].
        """
        key = z.tobytes()
        if self._val_cache[0] == key:
            return self._val_cache[1]
        self.calls["evaluations"] += 1
        x, tau, s = self._split(z)
        q = self.posture(x)
        forces = self.robot.contact_forces(q, np.zeros(self.k), tau)
        F = np.array([w.force for w in forces.wheels])
        cone = np.hypot(F[self.friction, 0], F[self.friction, 1]) - s * F[self.friction, 2]
        out = np.concatenate([forces.nudot, cone, F[:, 2]])
        if not np.all(np.isfinite(out)):
            raise NonFiniteError("posture optimisation: the forces are not finite at an iterate")
        self._val_cache = (key, out)
        return out

    def jacobian(self, z: np.ndarray) -> np.ndarray:
        """The constraints' Jacobian (ng, nz), dense: analytic or central differences (``derivatives``).

        Args:
            z: Decision vector, as for :meth:`values`.

        Returns:
            The Jacobian (ng, p + n_motors + 1).
        """
        key = z.tobytes()
        if self._jac_cache[0] == key:
            return self._jac_cache[1]
        if self.derivatives == "analytic":
            x, tau, s = self._split(z)
            q = self.posture(x)
            self.calls["derivatives"] += 1
            d = self.robot.contact_force_derivatives(q, np.zeros(self.k), tau)
            T = self.tangent(q)
            Tx = np.column_stack([T[:, [self.positions.index(i) for i in g]].sum(axis=1)
                                  for g in self.groups])  # dq/dx
            Fq = d.dforce_dq @ Tx  # (W, 3, p)
            Ft = d.dforce_dtau
            f = self.friction
            ft = d.force[f, :2]
            norm = np.maximum(np.hypot(ft[:, 0], ft[:, 1]), 1e-300)[:, None]
            rows = [np.hstack([d.dynamics.dq @ Tx, d.dynamics.dtau, np.zeros((self.k, 1))])]
            dnorm_x = np.einsum("wc,wcp->wp", ft, Fq[f, :2]) / norm
            dnorm_t = np.einsum("wc,wcp->wp", ft, Ft[f, :2]) / norm
            rows.append(np.hstack([dnorm_x - s * Fq[f, 2], dnorm_t - s * Ft[f, 2], -d.force[f, 2][:, None]]))
            rows.append(np.hstack([Fq[:, 2], Ft[:, 2], np.zeros((len(self.wheels), 1))]))
            J = np.vstack(rows)
        else:
            J = np.empty((len(self.values(z)), self.nz))
            for i in range(self.nz):
                step = np.cbrt(np.finfo(float).eps) * (1.0 + abs(z[i]))
                zp, zm = z.copy(), z.copy()
                zp[i] += step
                zm[i] -= step
                J[:, i] = (self.values(zp) - self.values(zm)) / (2 * step)
        if not np.all(np.isfinite(J)):
            raise NonFiniteError("posture optimisation: the constraints' derivatives are not finite at an iterate")
        self._jac_cache = (key, J)
        return J

    # --- the NLP ---------------------------------------------------------------------------------------------------

    def solve(self, tol: float = 1e-10, max_iter: int = 300, verbose: bool = False) -> PostureSolution:
        """Solve with IPOPT (CasADi ``nlpsol``, limited-memory Hessian), from q0 and its least-squares holding
        torques.

        Args:
            tol: IPOPT's convergence tolerance (scaled KKT error) and its largest constraint violation.
            max_iter: Largest number of IPOPT iterations.
            verbose: Print IPOPT's iteration log.

        Returns:
            A :class:`PostureSolution` (``success`` False, with IPOPT's status, if it did not converge).
        """
        if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
            raise InputError(f"tol = {tol!r}; expected a finite number > 0")
        ca = _casadi()
        x0 = np.array([self.q0[g[0]] for g in self.groups])
        z0 = np.concatenate([np.clip(x0, self.x_lo, self.x_hi), np.clip(self.tau0, self.tau_lo, self.tau_hi), [0.0]])
        g0 = self.values(z0)
        nf, W = len(self.friction), len(self.wheels)
        F0 = g0[self.k + nf:]
        cone0 = g0[self.k:self.k + nf]
        loads0 = F0[self.friction]
        z0[-1] = float(np.max((cone0 + 0.0) / np.where(loads0 > 0, loads0, np.inf), initial=0.0))  # mu at the start
        ng = self.k + nf + W
        rows, cols = np.meshgrid(np.arange(ng), np.arange(self.nz), indexing="ij")
        self._callbacks = []
        g = sparse_callback("posture", self.nz, ng, self.values, lambda z: self.jacobian(z).ravel(), rows.ravel(),
                            cols.ravel(), self._callbacks)
        z = ca.MX.sym("z", self.nz)
        lbg = np.concatenate([np.zeros(self.k), np.full(nf, -np.inf), self.min_load])
        ubg = np.concatenate([np.zeros(self.k), np.zeros(nf), np.full(W, np.inf)])
        lbx = np.concatenate([self.x_lo, self.tau_lo, [0.0]])
        ubx = np.concatenate([self.x_hi, self.tau_hi, [np.inf]])
        opts = {"ipopt.hessian_approximation": "limited-memory", "ipopt.tol": tol, "ipopt.constr_viol_tol": tol,
                "ipopt.max_iter": int(max_iter), "ipopt.print_level": 5 if verbose else 0, "print_time": bool(verbose),
                "ipopt.sb": "yes", "ipopt.honor_original_bounds": "yes",
                "show_eval_warnings": False}  # a refused trial point: robotdyn.optimisation.callbacks._refused
        solver = ca.nlpsol("posture", "ipopt", {"x": z, "f": z[-1], "g": g(z)}, opts)
        self.calls = {"evaluations": 0, "derivatives": 0}
        start = time.perf_counter()
        res = solver(x0=z0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        wall = time.perf_counter() - start
        stats = solver.stats()
        calls = dict(self.calls)
        zopt = np.asarray(res["x"], float).ravel()
        x, tau, s = self._split(zopt)
        q = self.posture(x)
        forces = self.robot.contact_forces(q, np.zeros(self.k), tau)
        mu = np.array([forces.wheels[i].required_mu for i in self.friction])
        loads = np.array([w.normal for w in forces.wheels])
        return PostureSolution(q.copy(), tau.copy(), x.copy(), s, mu, loads, str(stats["return_status"]),
                               bool(stats["success"]), int(stats["iter_count"]), wall, calls["evaluations"],
                               calls["derivatives"], self.derivatives, list(self.variables), list(self.wheels),
                               list(self.friction_wheels))


__all__ = ["PostureProblem", "PostureSolution"]

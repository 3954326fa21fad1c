"""Constraint forces at a state: wheel-ground contact loads and loop-closure forces.

With the constraint rows :math:`A(q)v = 0` (m rows, rank r) the full equations of motion read

.. math:: M a + h = B\\tau + A^T\\lambda,\\qquad a = S\\dot\\nu + w,

so once :math:`\\dot\\nu` is known (forward dynamics from motor torques) or given (inverse dynamics), the residual
:math:`e = M a + h - B\\tau = \\mathrm{RNEA}(q, v, a) - B\\tau` lies in the range of :math:`A^T` and
:math:`A^T\\lambda = e` gives the constraint forces (the concepts page ``docs/concepts.md``).

Units and frames. Each row's multiplier is the force along that row:

- a rolling wheel's rows are the velocity of its material point at the contact along (t1, t2, n) of the contact
  frame (t1 = rolling direction, t2 = n x t1, n = terrain normal, upward), so its multipliers are the force
  *the ground exerts on the wheel* at the contact point, in N, split into longitudinal (t1), lateral (t2) and
  normal (n) components; a positive normal component presses the wheel up (a load);
- an omni wheel has a driving row (along its rollers' constrained direction) and a normal row; a support wheel
  only the normal row;
- a loop closure's rows are the relative motion of its frame 2 with respect to frame 1 in frame 1's axes, so its
  multipliers are the force [N] (x, y, z) and moment [N m] (rx, ry, rz) that the closure exerts on the body of
  frame 2, at frame 2's origin, in frame 1's axes (the body of frame 1 receives the opposite).

Redundant rows (r < m). :math:`\\lambda` is then determined only up to the null space N of :math:`A^T`: a rigid
four-wheel chassis on flat ground is statically indeterminate, and under a planar root the wheels' normal rows do
not act on any coordinate at all (the model has no vertical motion), so the normal loads are not determined by that
model. The result reports, per row and per wheel component, whether rigid-body dynamics determine it, and the
undetermined combinations (the columns of N). The open part is then fixed by the rigid limit of the wheels' normal
compliance (:mod:`robotdyn.contact.rigid_limit`: the split a stiff elastic chassis takes, no wheel pulling), and
the components it fixes are reported as such (:attr:`WheelForce.compliance`, "rigid limit of compliance"), next to
those rigid-body dynamics determine; what normal compliance cannot fix (e.g. a lateral squeeze between two wheels
of one axle) stays open, shown as the minimum-norm choice and flagged, never presented as the answer.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..reduction.actuation import input_matrix
from ..fast.dispatch import compiled_model
from ..constraints.constraint import ConstraintRows, KinematicState
from ..errors import InputError, NonFiniteError
from ..constraints.loop_closure import LoopClosure
from ..constraints.rolling_contact import RollingWheel
from .sliding import forward as forward_sliding
from .sliding import sliding_now, tangential
from .compliant_rolling import forward as rolling_forward
from .compliant_rolling import rolling_wheels
from .applied_forces import applied, has_applied, reduced_applied
from . import rigid_limit
from .compliance import wheel_stiffness

ILL_DETERMINED = 1e3
"""Condition number of the rows above which the forces are flagged as ill-determined (a note, not an error)."""

DETERMINED_TOL = 1e-8
"""A row (or force component) is determined when its weight in every null-space direction is below this."""


COMPLIANT_SOURCE = "compliant contact"
"""How a compliant wheel's normal load is reported (its force law of penetration and its rate)."""


@dataclass
class WheelForce:
    """The ground's force on one wheel at its contact point.

    Attributes:
        name: The wheel's name.
        kind: ``standard``, ``omni`` or ``support``.
        force: (3,) components along (t1 longitudinal, t2 lateral, n normal) of the contact frame [N].
        determined: (3,) whether rigid-body dynamics determine each component.
        world: (3,) the same force in world axes [N].
        point: (3,) the contact point in world coordinates [m].
        compliance: (3,) components rigid-body dynamics leave open and the rigid limit of the wheels' normal
            compliance fixes (:mod:`robotdyn.contact.rigid_limit`).
        frame: (3, 3) the contact frame in world axes, columns (t1, t2, n) (``None``: not given).
    """

    name: str
    kind: str
    force: np.ndarray
    determined: np.ndarray
    world: np.ndarray
    point: np.ndarray
    compliance: np.ndarray = field(default_factory=lambda: np.zeros(3, bool))
    frame: np.ndarray | None = field(default=None, repr=False)  # (3, 3) the contact frame, columns t1, t2, n

    @property
    def known(self) -> np.ndarray:
        """(3,) components with a value: determined by rigid-body dynamics or by the rigid limit of compliance."""
        return self.determined | self.compliance

    @property
    def source(self) -> str:
        """Which model produced the normal load: ``rigid`` (rigid-body dynamics), ``rigid limit of compliance``,
        ``compliant contact`` (a compliant wheel's force law of penetration), or ``open`` (none determines it)."""
        if self.kind == "compliant":
            return COMPLIANT_SOURCE
        if self.determined[2]:
            return "rigid"
        return rigid_limit.MODEL if self.compliance[2] else "open"

    @property
    def normal(self) -> float:
        """Normal load f_n [N] (positive: the ground pushes the wheel up)."""
        return float(self.force[2])

    @property
    def tangential(self) -> float:
        """Magnitude of the tangential (friction) force :math:`\\|(f_{t1}, f_{t2})\\|` [N]."""
        return float(np.hypot(self.force[0], self.force[1]))

    @property
    def required_mu(self) -> float:
        """Friction coefficient the motion requires, :math:`|f_t| / f_n` (``inf`` if the wheel is not pressed
        on the ground, :math:`f_n \\le 0`)."""
        return self.tangential / self.normal if self.normal > 0 else float("inf")

    @property
    def load_determined(self) -> bool:
        """Whether the normal load and the friction force are all determined by rigid-body dynamics."""
        return bool(self.determined.all())

    @property
    def load_known(self) -> bool:
        """Whether the normal load and the friction force all have a value (rigid, or rigid limit of compliance)."""
        return bool(self.known.all())

    def __repr__(self) -> str:
        flag = "" if self.load_determined else (f", {self.source}" if self.load_known else ", NOT all determined")
        return (f"WheelForce({self.name!r}, long={self.force[0]:.6g} N, lat={self.force[1]:.6g} N, "
                f"normal={self.force[2]:.6g} N{flag})")


@dataclass
class ConstraintForces:
    """Constraint forces of a robot at one state.

    Attributes:
        labels: Row names (constraint name and component), in row order.
        lam: (m,) multipliers :math:`\\lambda` [N or N m] (minimum-norm where not determined).
        determined: (m,) whether rigid-body dynamics determine each row's multiplier.
        null_space: (m, m - r) orthonormal basis of the undetermined combinations (zero columns: none).
        rank: Rank r of the constraint Jacobian.
        residual: :math:`\\|A^T\\lambda - e\\|` relative to :math:`\\|e\\|` (0 for a consistent motion; large when
            the given accelerations are not reachable with the motors).
        nudot: (k,) independent accelerations used.
        tau: Motor torques used [N m or N].
        wheels: One :class:`WheelForce` per rolling, omni or support wheel.
        closures: Loop-closure forces/moments by closure name, then component (x, y, z [N]; rx, ry, rz [N m]).
        condition: Condition number of the rows' rank-r part (large: nearly redundant rows, ill-determined forces).
        undetermined_reason: Why rows are undetermined (empty when all are determined).
        ill_conditioned: The ill-conditioned parts of the solve
            (:class:`~robotdyn.reduction.conditioning.IllConditioned`; a warning names them), empty when well
            conditioned.
        notes: How the forces were obtained where that is not the model itself (e.g. a planar model's loads from
            its floating twin).
        compliance: (m,) rows rigid-body dynamics leave open that the rigid limit of normal compliance fixes
            (``lam`` holds its values there).
        open_space: (m, d') orthonormal combinations that stay open after it (they move no normal load).
        unloaded: Wheels the rigid limit leaves unloaded (they would pull).
    """

    labels: list[str]
    lam: np.ndarray
    determined: np.ndarray
    null_space: np.ndarray
    rank: int
    residual: float
    nudot: np.ndarray
    tau: np.ndarray
    wheels: list[WheelForce] = field(default_factory=list)
    closures: dict[str, dict[str, float]] = field(default_factory=dict)
    undetermined_reason: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    condition: float = 1.0
    ill_conditioned: list = field(default_factory=list)
    compliance: np.ndarray | None = None
    open_space: np.ndarray | None = None
    unloaded: list[str] = field(default_factory=list)
    _tangential: list = field(default_factory=list, repr=False)  # per wheel: (row indices, D, friction or None)
    _inert: bool = field(default=False, repr=False)  # some row acts on no coordinate (a planar root's normal rows)

    @property
    def open(self) -> np.ndarray:
        """(m, d') the combinations still open (the null space itself where no compliance split was made)."""
        return self.null_space if self.open_space is None else self.open_space

    @property
    def all_determined(self) -> bool:
        """Whether every multiplier is determined by rigid-body dynamics."""
        return bool(self.determined.all())

    def minimum_mu(self) -> float | None:
        """The smallest friction coefficient with which some force distribution that rigid-body dynamics allow
        (:math:`\\lambda + N z`) lies inside every wheel's friction cone:
        :math:`\\min_z \\max_i \\|f_{t,i}(z)\\| / f_{n,i}` (a convex problem, solved by SLSQP in epigraph form).

        The normal loads are those of the rigid limit of compliance where rigid-body dynamics leave them open, and
        z then runs over what stays open (:attr:`open`). Equal to the largest per-wheel required mu when every
        friction force has a value; ``None`` when a normal load has none; ``inf`` when a wheel is not pressed on
        the ground (a wheel the rigid limit unloads included).

        Returns:
            The smallest friction coefficient (dimensionless, >= 0); ``float("inf")`` where a wheel is not pressed on
            the ground, ``None`` where a normal load has no value.
        """
        if not self.wheels or not all(w.known[2] for w in self.wheels):
            return None
        # a compliant wheel in the air carries nothing and needs no friction (robotdyn.contact.compliant_contact)
        pairs = [(t, w) for t, w in zip(self._tangential, self.wheels) if not (w.kind == "compliant" and w.normal <= 0)]
        if not pairs:
            return 0.0
        fn = np.array([w.normal for _, w in pairs])
        if np.any(fn <= 0):
            return float("inf")
        space = self.open
        maps = []  # f_t,i(z) = base_i + T_i z
        for (idx, D, friction), w in pairs:
            if friction is not None:
                maps.append((np.asarray(friction, float), np.zeros((2, space.shape[1]))))
            else:
                maps.append((D.T[:2] @ self.lam[idx], D.T[:2] @ space[idx]))
        return cone_minimum(maps, fn, space.shape[1])

    def wheel(self, name: str) -> WheelForce:
        """The force on the wheel called ``name``.

        Args:
            name: The wheel's name (its ``name``, else its frame).

        Returns:
            Its :class:`WheelForce`.
        """
        for w in self.wheels:
            if w.name == name:
                return w
        raise InputError(f"unknown wheel {name!r}; expected one of {', '.join(w.name for w in self.wheels)}")

    def as_dict(self) -> dict:
        """Plain data (for JSON): rows, wheels, closures and what is undetermined.

        Returns:
            A JSON-ready dict of plain Python values (forces in N, moments in N m).
        """
        return {
            "rows": {lab: float(x) for lab, x in zip(self.labels, self.lam)},
            "determined": {lab: bool(d) for lab, d in zip(self.labels, self.determined)},
            "wheels": {
                w.name: {"longitudinal": float(w.force[0]), "lateral": float(w.force[1]), "normal": w.normal,
                         "determined": {"longitudinal": bool(w.determined[0]), "lateral": bool(w.determined[1]),
                                        "normal": bool(w.determined[2])},
                         "source": w.source,
                         "required_mu": w.required_mu if w.load_known and w.normal > 0 else None,
                         "world": w.world.tolist(), "contact_point": w.point.tolist()}
                for w in self.wheels
            },
            "closures": self.closures,
            "rank": self.rank,
            "condition": self.condition,
            "ill_conditioned": [vars(f) for f in self.ill_conditioned],
            "rows_count": len(self.labels),
            "undetermined_combinations": [
                {lab: float(c) for lab, c in zip(self.labels, col) if abs(c) > DETERMINED_TOL}
                for col in self.null_space.T
            ],
            "undetermined_reason": self.undetermined_reason,
            "open_combinations": [
                {lab: float(c) for lab, c in zip(self.labels, col) if abs(c) > DETERMINED_TOL}
                for col in self.open.T
            ],
            "unloaded": self.unloaded,
            "notes": self.notes,
            "minimum_mu": self.minimum_mu(),
            "residual": self.residual,
        }

    def table(self) -> str:
        """A readable text table of the wheel and closure forces.

        Returns:
            The table as one string (lines joined with newlines; forces in N).
        """
        lines = []
        if self.wheels:
            lines.append("contact forces (ground on wheel, contact frame) [N]:")
            split = any(w.compliance.any() for w in self.wheels)
            lines.append(f"{'wheel':>16} {'longitudinal':>14} {'lateral':>14} {'normal':>14} {'required mu':>12}"
                         + (f"  {'load from':<26}" if split else ""))
            for w in self.wheels:
                cells = [f"{x:>14.6g}" if d else f"{'undetermined':>14}" for x, d in zip(w.force, w.known)]
                mu = w.required_mu if w.load_known else None
                mu_text = "-" if mu is None else ("lift-off" if w.normal <= 0 else f"{mu:.4g}")
                lines.append(f"{w.name:>16} " + " ".join(cells) + f" {mu_text:>12}"
                             + (f"  {_source_text(w)}" if split else ""))
        for name, comps in self.closures.items():
            det = {c: d for c, d in zip(self.labels, self.determined)}
            parts = [f"{c}={v:.6g}" if det[f"{name}.{c}"] else f"{c}=undetermined" for c, v in comps.items()]
            lines.append(f"closure {name} (on frame 2's body, frame 1's axes; N, N m): " + ", ".join(parts))
        for reason in self.undetermined_reason:
            lines.append(f"not determined by rigid-body dynamics: {reason}")
        if self.wheels and any(w.compliance.any() for w in self.wheels):
            lines.append(f"loads rigid-body dynamics leave open: {rigid_limit.MODEL} (the split a stiff elastic "
                         "chassis takes, no wheel pulling; totals, axle and side sums and moments as rigid-body "
                         "dynamics give them; stiffness ratios from the wheels' normal_stiffness)"
                         + (f"; unloaded (would pull): {', '.join(self.unloaded)}" if self.unloaded else ""))
        if self.wheels and not all(w.load_known for w in self.wheels):
            mu = self.minimum_mu()
            if mu is not None:
                lines.append(f"smallest mu with which some admissible split of the undetermined forces lies in every "
                             f"friction cone: {mu:.6g}")
        for note in self.notes:
            lines.append(f"note: {note}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        und = int((~self.determined).sum())
        return (f"ConstraintForces(rows={len(self.labels)}, rank={self.rank}, undetermined={und}, "
                f"wheels={[w.name for w in self.wheels]}, closures={list(self.closures)})")


def _source_text(w: WheelForce) -> str:
    """The table's "load from" cell: the normal load's model, and the tangential components still open."""
    text = "rigid-body dynamics" if w.source == "rigid" else w.source
    open_ = [name for name, k in zip(("longitudinal", "lateral"), w.known[:2]) if not k]
    return text + (f" ({' and '.join(open_)} open)" if open_ else "")


def cone_minimum(maps: list[tuple[np.ndarray, np.ndarray]], fn: np.ndarray, d: int) -> float:
    """The smallest friction coefficient over the undetermined combinations z (d of them):
    :math:`\\min_z \\max_i \\|b_i + T_i z\\| / f_{n,i}` (the algorithm of :meth:`ConstraintForces.minimum_mu`).

    Args:
        maps: Per wheel ``(b_i, T_i)``: its tangential force (t1, t2) [N] at z = 0 (2,) and how it changes with z
            (2, d), in its contact frame.
        fn: (W,) the wheels' normal loads [N], all positive.
        d: Number of undetermined combinations.

    Returns:
        The smallest ratio found (:func:`cone_split`'s first value).
    """
    return cone_split(maps, fn, d)[0]


def cone_split(maps: list[tuple[np.ndarray, np.ndarray]], fn: np.ndarray, d: int) -> tuple[float, np.ndarray]:
    """:func:`cone_minimum` and the combinations z (d,) that reach it (the split the smallest ratio is found at).

    Args:
        maps: Per wheel ``(b_i, T_i)`` as for :func:`cone_minimum`.
        fn: (W,) the wheels' normal loads [N] (or any positive scale per wheel, e.g. mu_i f_n,i), all positive.
        d: Number of undetermined combinations.

    Returns:
        ``(ratio, z)``: the smallest :math:`\\max_i \\|b_i + T_i z\\| / f_{n,i}` found and its z (d,): exact for
        d = 0 (or no T_i), a bounded scalar search for d = 1, SLSQP in epigraph form above.
    """
    ratio = lambda z: max(float(np.linalg.norm(b + T @ z)) / f for (b, T), f in zip(maps, fn))  # noqa: E731
    zero = np.zeros(d)
    if d == 0 or all(not np.any(T) for _, T in maps):
        return ratio(zero), zero
    if d == 1:  # one undetermined combination (two wheels on one axle, ...): a bounded scalar search
        from scipy.optimize import minimize_scalar

        scale = 10.0 * (1.0 + max(float(np.linalg.norm(b)) for b, _ in maps))
        res = minimize_scalar(lambda z: ratio(np.array([z])), bounds=(-scale, scale), method="bounded",
                              options={"xatol": 1e-12 * scale})
        best = np.array([float(res.x)])
        return (ratio(best), best) if ratio(best) <= ratio(zero) else (ratio(zero), zero)
    from scipy.optimize import minimize

    def cone(x, b, T, f):  # (t f)^2 - |b + T z|^2 >= 0 for x = (z, t)
        return (x[-1] * f) ** 2 - np.sum((b + T @ x[:-1]) ** 2)

    def cone_jac(x, b, T, f):  # its gradient in (z, t): the exact one, so SLSQP needs no differences
        return np.append(-2.0 * (b + T @ x[:-1]) @ T, 2.0 * x[-1] * f * f)

    cons = [{"type": "ineq", "fun": cone, "jac": cone_jac, "args": (b, T, f)} for (b, T), f in zip(maps, fn)]
    last = np.append(np.zeros(d), 1.0)
    x0 = np.append(np.zeros(d), ratio(zero))
    res = minimize(lambda x: x[-1], x0, jac=lambda x: last, constraints=cons,
                   bounds=[(None, None)] * d + [(0, None)], method="SLSQP", options={"ftol": 1e-14, "maxiter": 500})
    best = np.asarray(res.x[:-1], float)
    return (ratio(best), best) if ratio(best) <= ratio(zero) else (ratio(zero), zero)


def constraint_forces(robot, q, nu, tau=None, nudot=None, twin: bool = True, compliance: bool = True
                      ) -> ConstraintForces:
    """Constraint forces at (q, nu) for given motor torques (forward dynamics) or accelerations (inverse dynamics).

    Args:
        robot: A :class:`~robotdyn.robot.Robot`.
        q: Natural coordinates (n,) [m, rad].
        nu: Independent velocities (k,).
        tau: Motor torques [N m or N]; with ``nudot`` None the accelerations follow from forward dynamics
            (default: zero torques).
        nudot: Independent accelerations (k,); the motor torques then follow by least squares (``tau`` given
            too: those torques are used as given, and ``residual`` says whether they produce ``nudot``).
        twin: For a planar-root robot whose normal loads the planar model leaves undetermined, take them from its
            floating twin (:func:`_from_floating_twin`); False keeps the planar model's own answer.
        compliance: Fix what rigid-body dynamics leave open by the rigid limit of the wheels' normal compliance
            (:func:`apply_rigid_limit`); False keeps the minimum-norm values, flagged as undetermined.

    Returns:
        The :class:`ConstraintForces`.

    Example:
        >>> import robotdyn
        >>> from robotdyn.contact.contact_forces import constraint_forces
        >>> robot = robotdyn.load("quasimoro")
        >>> forces = constraint_forces(robot, robot.neutral(), [0.0, 0.0, 0.0], tau=[0.0, 0.0])
        >>> round(sum(w.normal for w in forces.wheels), 2)  # the weight (2 m + M) g [N]
        58.86
    """
    q = robot.check_q(q)
    nu = robot.check_nu(nu, "v")
    red = robot.reduced(q, nu)
    forward = nudot is None  # accelerations solved from the mass matrix (its conditioning then matters)
    friction = {}  # slipping wheels: name -> (J_t, friction force in (t1, t2))
    st = None
    jrows = red.jacobian_rows
    if sliding_now(robot):
        if nudot is not None:
            raise InputError("with slipping wheels the forces follow from motor torques: give tau, not nudot")
        tau = robot.check_tau(np.zeros(len(robot.motors)) if tau is None else tau)
        st = forward_sliding(robot, q, nu, tau)
        nudot = st.nudot
        kin_v = KinematicState(robot.model, robot.data, q, red.v)
        for i, wheel in enumerate(sliding_now(robot)):
            friction[wheel.name] = (tangential(wheel, kin_v)[0], st.force[i])
    elif nudot is None and rolling_wheels(robot):  # compliant wheels rolling while they press: their rows join
        tau = robot.check_tau(np.zeros(len(robot.motors)) if tau is None else tau)
        rolled = rolling_forward(robot, q, nu, tau, red=red)  # robotdyn.contact.compliant_rolling
        nudot = rolled.nudot
        if rolled.contact:  # their multipliers (minimum-norm, with the open part in the null space) are their forces
            labels = [lab for w in rolling_wheels(robot) if w.name in rolled.contact for lab in w.rolling_labels()]
            m = len(labels)
            jrows = ConstraintRows.stack([jrows, ConstraintRows(rolled.rows, None, np.zeros(m), np.zeros(m, bool),
                                                                labels)], robot.model.nv)
    elif nudot is None:
        tau = robot.check_tau(np.zeros(len(robot.motors)) if tau is None else tau)
        from ..reduction.reduced_dynamics import solve_mass

        nudot = solve_mass(red.M, red.B @ tau - red.h + reduced_applied(robot, red, q)[0])
    else:
        nudot = robot.check_nu(nudot, "a")
        if tau is None:
            tau = robot.inverse_dynamics(q, nu, nudot)[1]
        else:
            tau = robot.check_tau(tau)
    a = red.S @ nudot + red.w
    solve = lambda: _solve(robot, q, red.v, a, tau, jrows, friction)  # noqa: E731
    solved = None
    unsupported = False  # a planar model whose wheels cannot hold its out-of-plane equilibrium
    use_twin = twin and robot.spec.root == "planar" and not friction
    if use_twin and not _inert_normal(robot, jrows):  # (a normal row acting on nothing is undetermined: no solve)
        solved = solve()
        use_twin = _normal_open(robot, solved)
    if use_twin:
        planar = []  # the planar model's own forces: solved and assembled only where the twin cannot replace them

        def assemble_planar() -> ConstraintForces:
            planar.append(_assemble(robot, solve() if solved is None else solved, nudot, tau, friction))
            return planar[0]

        out = _from_floating_twin(robot, q, red.v, a, tau, nudot, assemble_planar)
        unsupported = bool(planar)
    else:
        out = _assemble(robot, solve() if solved is None else solved, nudot, tau, friction)
    if st is not None and st.lam is not None:  # the loads of the coupled solve (rigid limit with friction)
        apply_rigid_limit(robot, out, st.lam, st.unloaded)
    elif compliance and not friction and not unsupported:  # no equilibrium to split where support is lacking
        apply_rigid_limit(robot, out)
    from ..reduction.conditioning import WARN_CONDITION, IllConditioned

    system = [IllConditioned("force system", out.condition)] if out.condition > WARN_CONDITION else []
    out.ill_conditioned = robot.warn_conditioning(red, nudot, system, forward)
    return out


def apply_rigid_limit(robot, out: ConstraintForces, lam: np.ndarray | None = None, unloaded: tuple = ()
                      ) -> ConstraintForces:
    """Fix the loads that rigid-body dynamics leave open in ``out`` by the rigid limit of the wheels' normal
    compliance (:func:`robotdyn.contact.rigid_limit.split`), in place: ``lam`` on the rows it fixes, each wheel's
    force and its ``compliance`` flags, ``compliance``, ``open_space`` and ``unloaded``. The rows rigid-body
    dynamics determine keep their values bit for bit. Nothing changes where no normal load is open, nor where
    rows act on no coordinate of the model (a planar root's normal rows: no equilibrium to split; its floating
    twin's loads are split instead).

    Args:
        robot: The :class:`~robotdyn.robot.Robot` (its wheels' normal stiffnesses).
        out: The forces at a state (``lam`` the minimum-norm multipliers).
        lam: (m,) multipliers already split (with slipping wheels: :func:`robotdyn.contact.rigid_limit.coupled`,
            whose friction depends on them); ``None``: split here.
        unloaded: With ``lam``, the wheels it leaves unloaded.

    Returns:
        ``out`` itself, with its open loads fixed by the rigid limit (unchanged where there is nothing to fix).
    """
    if out.null_space.shape[1] == 0 or not out.wheels or all(w.determined[2] for w in out.wheels) or out._inert:
        return out
    rows = [np.asarray(idx, int) for idx, _, _ in out._tangential]
    dirs = [np.asarray(D, float) for _, D, _ in out._tangential]
    C = rigid_limit.normal_map(rows, dirs, len(out.lam))
    k = wheel_stiffness(robot, [w.name for w in out.wheels])
    res = rigid_limit.split(out.lam, out.null_space, C, k, out.determined)
    if lam is not None:
        given = np.array(lam, float)
        if res.open.shape[1]:
            given -= res.open @ (res.open.T @ given)
        given[out.determined] = out.lam[out.determined]
        res.lam, res.feasible = given, True
        res.unloaded = [i for i, w in enumerate(out.wheels) if w.name in unloaded]
    out.lam, out.compliance, out.open_space = res.lam, res.fixed, res.open
    out.unloaded = [out.wheels[i].name for i in res.unloaded]
    for w, idx, D, (_, _, fr) in zip(out.wheels, rows, dirs, out._tangential):
        force = D.T @ res.lam[idx]
        if fr is not None:
            force[:2] += fr
        known = _directions_determined(D, res.open, idx)
        w.compliance = known & ~w.determined
        w.force = np.where(w.determined, w.force, force)
        if w.frame is not None:
            w.world = w.frame @ w.force
    if not res.feasible:
        out.notes.append("no split of the loads pulls on no wheel here (the robot would tip or lift off): the loads "
                         f"shown are the {rigid_limit.MODEL} without the no-pull condition")
    return out



def _solve(robot, q, v, a, tau, rows, friction) -> tuple:
    """:math:`A^T\\lambda = \\mathrm{RNEA}(q, v, a) - B\\tau - \\sum J_t^T F_t` at a state whose accelerations are
    known (``rows``: the constraint rows there, ``None``: computed here), for :func:`_assemble`: ``(rows, lam, N,
    rank, residual, condition, wheel geometry, compliant wheels' states)``, refusing non-finite multipliers in one
    line. Without friction forces and where the robot's compiled
    model serves, e, :math:`\\lambda` on the projection's rows and the wheels' contact frames come from one compiled
    call (:meth:`robotdyn.fast.compiled.CompiledModel.forces_at`) and :math:`\\lambda` is made minimum-norm with the
    null space of :math:`A^T` (:func:`_from_basic`), the Python path's choice on undetermined rows; else all of it in
    Python."""
    fast = None if friction else compiled_model(robot)
    served = None if fast is None else _compiled_forces(fast, q, v, a, tau)
    if rows is None:  # the rows at (q, v): the compiled evaluation's, else the Python path's
        if served is not None:
            rows = ConstraintRows(served[3], None, np.zeros(len(fast.labels)), fast.holonomic, list(fast.labels))
        else:
            rows = robot.constraint_rows(KinematicState(robot.model, robot.data, q, v))
    A = rows.A
    compliant = {}
    if served is not None:  # lambda on the projection's rows and the wheels' contact frames, in C++
        lam_basic, e, (_, _, frames, points), _ = served
        geometry = {id(w): (f.reshape(3, 3).T, p) for w, f, p in zip(fast.wheels, frames, points)}
        with np.errstate(all="ignore"):
            lam, N, rank, residual, condition = _from_basic(A, e, lam_basic)
    else:
        model, data = robot.model, robot.data
        kin = KinematicState(model, data, q, v)
        B = input_matrix(robot.motors, kin)
        e = pin.rnea(model, data, q, v, a) - B @ tau
        if has_applied(robot):  # joint springs and compliant wheels (robotdyn.contact.applied_forces)
            app = applied(robot, q, v, kin)
            e -= app.Q
            compliant = app.wheels
        for Jt, force in friction.values():  # the friction forces are applied forces, known once the loads are
            e -= Jt.T @ force
        with np.errstate(all="ignore"):  # an overflow is refused below as a NonFiniteError, in one line
            lam, N, rank, residual, condition = _solve_transpose(A, e)
        geometry = kin
    if not (np.all(np.isfinite(lam)) and np.isfinite(residual)):
        raise NonFiniteError(f"constraint forces at this state are not finite (max |e| = {np.max(np.abs(e)):.3g})")
    return rows, lam, N, rank, residual, condition, geometry, compliant


def _inert_normal(robot, rows: ConstraintRows) -> bool:
    """Whether some rigid wheel's normal row is exactly zero in ``rows`` (a planar root's, on flat ground): it acts
    on no coordinate, so it is a null direction of :math:`A^T` and that wheel's normal load is undetermined
    (:func:`_normal_open` says so too, after the solve)."""
    index = {lab: i for i, lab in enumerate(rows.labels)}
    for c in robot.constraints:
        if isinstance(c, RollingWheel) and not getattr(c, "compliant", False):
            i = index.get(f"{c.name}.normal")
            if i is not None and not rows.A[i].any():
                return True
    return False


def _normal_open(robot, solved: tuple) -> bool:
    """Whether some wheel's normal load is undetermined in :func:`_solve`'s result: ``any(not w.determined[2] for w
    in _assemble(...).wheels)`` (the same test, :func:`_wheel_force`'s), without assembling the forces."""
    rows, _, N = solved[:3]
    if N.shape[1] == 0:
        return False
    index = {lab: i for i, lab in enumerate(rows.labels)}
    for c in robot.constraints:
        if isinstance(c, RollingWheel) and not getattr(c, "compliant", False):  # (a compliant wheel's is its law's)
            if not _directions_determined(c._directions, N, [index[lab] for lab in c._labels()])[2]:
                return True
    return False


def _assemble(robot, solved: tuple, nudot, tau, friction) -> ConstraintForces:
    """The :class:`ConstraintForces` of :func:`_solve`'s result: per wheel, per closure, the reasons and notes."""
    rows, lam, N, rank, residual, condition, geometry, compliant = solved
    A = rows.A
    served = isinstance(geometry, dict)
    determined = np.ones(len(lam), bool) if N.shape[1] == 0 else _row_norms(N) <= DETERMINED_TOL
    out = ConstraintForces(list(rows.labels), lam, determined, N, rank, residual, nudot, tau)
    out.condition = condition
    if condition > ILL_DETERMINED:
        out.notes.append(f"the rows' condition number is {condition:.3g}: nearly redundant rows, so the determined "
                         "forces (e.g. an internal squeeze between two wheels) hinge on small geometric differences "
                         "and a little compliance would redistribute them")
    index = {lab: i for i, lab in enumerate(rows.labels)}
    for c in robot.constraints:
        if getattr(c, "compliant", False):  # its force is its laws' (robotdyn.contact.compliant_contact)
            st = compliant[c.name]
            force, known = st["force"].copy(), np.ones(3, bool)
            idx = [index[lab] for lab in c.rolling_labels() if lab in index]  # rolling in contact: its rows
            if idx:
                force[:2] = c.tangent_directions.T @ lam[idx]
                if N.shape[1]:  # an open split (e.g. the side force of two wheels on one axle)
                    known[:2] = np.linalg.norm(c.tangent_directions.T @ N[idx], axis=1) <= DETERMINED_TOL
            out.wheels.append(WheelForce(c.name, "compliant", force, known, st["E"] @ force,
                                         np.array(st["point"], float)))
            out._tangential.append((idx, c._directions, None) if idx else ([], np.zeros((0, 3)), force[:2]))
        elif isinstance(c, RollingWheel):
            fr = friction.get(c.name, (None, None))[1]
            if served:
                E, p = geometry[id(c)]
            else:
                geo = c._geometry(geometry)
                E, p = geo[9], geo[5]
            idx = [index[lab] for lab in c._labels()]
            out.wheels.append(_wheel_force(c, E, p, idx, lam, N, fr))
            out._tangential.append((idx, c._directions, fr))
        elif isinstance(c, LoopClosure):
            out.closures[c.name] = {comp: float(lam[index[f"{c.name}.{comp}"]]) for comp in c.components
                                    if f"{c.name}.{comp}" in index}
    out.undetermined_reason = _reasons(A, rows.labels, N)
    if N.shape[1]:
        scale = max(np.abs(A).max(initial=0.0), 1.0)
        out._inert = bool(np.any(np.abs(A).max(axis=1, initial=0.0) <= 1e-12 * scale))
    return out


TWIN_RESIDUAL = 1e-8
"""Relative residual above which the wheels cannot hold a planar model's out-of-plane equilibrium."""


def floating_twin(robot) -> tuple:
    """A planar-root robot's floating twin and where its coordinates go in the twin's.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` with a planar root.

    Returns:
        ``(twin, index)``: the same description on a floating root (x, y, z, yaw, pitch, roll), built once per
        robot and terrain (kept as ``robot._floating_twin``), and for each of the planar model's coordinates (and
        velocities) its index in the twin's (``psi`` is the twin's ``yaw``; z, pitch and roll are the twin's own).
    """
    from dataclasses import replace

    twin = getattr(robot, "_floating_twin", None)
    if twin is None or twin.terrain is not robot.terrain:  # (re)built for the robot's current terrain
        spec = replace(robot.spec, root="floating", independent=None, operational=None)
        twin = type(robot)(spec, robot.params, robot.terrain)  # a Robot (robotdyn.robot, the layer above)
        robot._floating_twin = twin
    names = twin.description.joint_names
    return twin, [names.index("yaw" if j == "psi" else j) for j in robot.description.joint_names]


def _from_floating_twin(robot, q, v, a, tau, nudot, planar) -> ConstraintForces:
    """The loads of a planar-root model from its floating twin.

    A planar root holds the robot at z = 0, pitch = roll = 0 without saying by what; physically the ground does,
    through the wheels' normal rows. The same description on a floating root (x, y, z, yaw, pitch, roll), at the
    same state with zero z, pitch and roll rates and accelerations, has those rows active, and the out-of-plane
    equations of motion (vertical force, roll and pitch moments of the whole robot) then determine the normal
    loads. If the wheels cannot hold that equilibrium (e.g. a robot on two wheels with no other support) the
    residual says so and the planar result is kept, with the reason. ``planar``: a function giving the planar
    model's :class:`ConstraintForces` (called only then)."""
    twin, index = floating_twin(robot)

    def lift(x):
        out = np.zeros(twin.nq)
        out[index] = x
        return out

    qt, vt, at = lift(q), lift(v), lift(a)
    solved = _solve(twin, qt, vt, at, tau, None, {})  # (the twin's rows: compiled where it serves)
    residual = solved[4]
    if residual > TWIN_RESIDUAL:  # (the twin's forces are not assembled then)
        planar = planar()
        planar.undetermined_reason.append(
            f"the wheels cannot hold this planar model's out-of-plane equilibrium (relative residual "
            f"{residual:.3g} on its floating twin): the description lacks a support, so its normal loads stay "
            "undetermined")
        return planar
    out = _assemble(twin, solved, nudot, tau, {})
    out.notes.append("normal loads from the out-of-plane equilibrium (vertical force, roll and pitch moments) of the "
                     "same description on a floating root: the planar root's z, roll and pitch are held by the ground")
    return out


def _compiled_forces(fast, q, v, a, tau):
    """``(lambda on the projection's rows, e, wheel forces and frames)`` by the robot's compiled model ``fast``
    (:meth:`robotdyn.fast.compiled.CompiledModel.forces_at`), or ``None`` where it falls back."""
    from ..fast.compiled import Fallback

    try:
        return fast.forces_at(np.asarray(q, float), np.asarray(v, float), np.asarray(a, float),
                              np.asarray(tau, float))
    except Fallback:
        return None


def _from_basic(A: np.ndarray, e: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, float, float]:
    """As :func:`_solve_transpose`, from a solution ``lam`` of :math:`A^T\\lambda = e` (the compiled one, zero on
    redundant rows): the same null space, rank and condition number (SVD), and the minimum-norm solution
    :math:`\\lambda - NN^T\\lambda` (the same values on the determined rows; the Python path's choice on the
    others)."""
    m = A.shape[0]
    if m == 0:
        return np.zeros(0), np.zeros((0, 0)), 0, float(np.linalg.norm(e) / max(1.0, np.linalg.norm(e))), 1.0
    _, s, Vt = np.linalg.svd(A.T, full_matrices=True)
    tol = s.max(initial=0.0) * max(A.shape) * np.finfo(float).eps
    rank = int(np.sum(s > tol))
    N = Vt[rank:].T
    lam = lam - N @ (N.T @ lam)
    scale = max(np.linalg.norm(e), 1.0)
    condition = float(s[0] / s[rank - 1]) if rank else 1.0
    return lam, N, rank, float(np.linalg.norm(A.T @ lam - e) / scale), condition


def _solve_transpose(A: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, float, float]:
    """Minimum-norm :math:`\\lambda` of :math:`A^T\\lambda = e`, the null space of :math:`A^T` (orthonormal
    columns), the rank, the relative residual and the condition number of the rank-r part (largest over smallest
    nonzero singular value), by SVD (rank tolerance as numpy's ``matrix_rank``)."""
    m = A.shape[0]
    if m == 0:
        return np.zeros(0), np.zeros((0, 0)), 0, float(np.linalg.norm(e) / max(1.0, np.linalg.norm(e))), 1.0
    U, s, Vt = np.linalg.svd(A.T, full_matrices=True)  # A^T = U diag(s) Vt, n x m
    tol = s.max(initial=0.0) * max(A.shape) * np.finfo(float).eps
    rank = int(np.sum(s > tol))
    lam = Vt[:rank].T @ ((U[:, :rank].T @ e) / s[:rank])
    N = Vt[rank:].T
    scale = max(np.linalg.norm(e), 1.0)
    condition = float(s[0] / s[rank - 1]) if rank else 1.0
    return lam, N, rank, float(np.linalg.norm(A.T @ lam - e) / scale), condition


def _row_norms(X: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(X, axis=1)`` of a real 2-D array, by the same operations without its dispatch."""
    return np.sqrt(np.add.reduce(X * X, axis=1))


def _directions_determined(D: np.ndarray, N: np.ndarray, idx: list) -> np.ndarray:
    """Which of a wheel's contact-frame directions (t1, t2, n) carry a determined load: those on which no direction
    of the null space ``N`` of :math:`A^T` (columns) weighs more than :data:`DETERMINED_TOL` through the wheel's rows
    ``idx`` (row i acts along ``D[i]``); all three where ``N`` has no column."""
    if not N.shape[1]:
        return np.ones(3, bool)
    return _row_norms(D.T @ N[idx]) <= DETERMINED_TOL


def _wheel_force(wheel: RollingWheel, E: np.ndarray, p: np.ndarray, idx: list, lam: np.ndarray,
                 N: np.ndarray, friction: np.ndarray | None = None) -> WheelForce:
    """A wheel's force in its contact frame (E: columns t1, t2, n; contact point p), from its rows' multipliers
    (``idx``: the rows' indices; row i acts along D[i] of (t1, t2, n)); a slipping wheel's tangential part is its
    friction force (t1, t2)."""
    D = wheel._directions
    force = D.T @ lam[idx]
    # a direction with no row at all (e.g. the lateral direction of an omni wheel) carries no force: determined
    determined = _directions_determined(D, N, idx)
    kind = "support" if D.shape[0] == 1 else ("omni" if D.shape[0] == 2 else "standard")
    if friction is not None:  # the law's force along its free directions (zero along a rolling one)
        force[:2] += friction
        kind = "slipping"
    return WheelForce(wheel.name, kind, force, determined, E @ force, np.array(p, float), frame=np.asarray(E, float))


def _reasons(A: np.ndarray, labels: list[str], N: np.ndarray) -> list[str]:
    """Plain-language reasons why rows are undetermined: rows that act on no coordinate of the model (e.g. a
    wheel's normal row under a planar root), and combinations of rows that the motion cannot tell apart."""
    if N.shape[1] == 0:
        return []
    out = []
    scale = max(np.abs(A).max(initial=0.0), 1.0)
    inert = np.abs(A).max(axis=1, initial=0.0) <= 1e-12 * scale  # (row by row, vectorised)
    zero = [lab for lab, z in zip(labels, inert) if z]
    if zero:
        out.append(f"rows {', '.join(zero)} act on no coordinate of this model at this configuration (the tree "
                   "already enforces them; a wheel's normal row does so under a planar root, which has no vertical, "
                   "roll or pitch motion: a floating root determines normal loads)")
    others = N.shape[1] - len(zero)
    if others > 0:
        weighed = np.any(np.abs(N) > DETERMINED_TOL, axis=1)  # rows with a weight in some null-space direction
        mixed = sorted({lab for lab, w in zip(labels, weighed) if w} - set(zero))
        if any(lab.endswith(".normal") for lab in mixed):
            why = "the rows are redundant, e.g. more wheels than a rigid body needs"
        else:  # only tangential rows: wheels pushing against each other, which normal compliance does not fix
            why = ("wheels pushing against each other along these directions, which no motion tells apart; no "
                   "normal load is among them, so the values shown are the minimum-norm choice")
        out.append(f"{others} combination(s) of rows {', '.join(mixed)} (statically indeterminate: {why})")
    return out

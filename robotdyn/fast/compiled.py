"""The reduced model in one compiled call per state: the fast path of :mod:`robotdyn.reduction.reduced_dynamics`.

:class:`CompiledModel` evaluates :math:`M_r = S^TMS`, :math:`h = C_r\\nu + g_r = S^T\\,\\mathrm{RNEA}(q, S\\nu, w)`,
:math:`g_r`, :math:`B_r`, :math:`S` and :math:`w = \\dot S\\nu` with the formulas of the Python reference
(:mod:`robotdyn.constraints.rolling_contact` on a plane, :mod:`robotdyn.constraints.loop_closure`, :mod:`robotdyn.reduction.projection`,
:mod:`robotdyn.reduction.operational_space`, :mod:`robotdyn.reduction.actuation`) in C++ (``robotdyn/_compiled.cpp``: the
evaluator; its formulas are the kernels of ``robotdyn/kernels/``, one header per constraint kind named like its Python
module), on a copy of
the robot's Pinocchio model rebuilt joint by joint and checked against it when built (M, g and RNEA at a random
state). Pinocchio's own C++ algorithms do the rigid-body work, two passes per state: CRBA in the world convention
(M, the joint Jacobians and, from its composite inertias, :math:`g_k = -J_k^T (Y_k a_g)`) and RNEA without gravity
(:math:`C v`, and the zero-acceleration accelerations the drift terms need), so that
:math:`\\mathrm{RNEA}(q, v, w) = Cv + g + Mw`. The projection solves with the LU factors of :math:`A_d`; its exact
condition number and inverse (:class:`LazyProjection`) are computed on request.

It serves robots whose constraints are rolling wheels (standard, omni, support; with or without a radius joint) on
a plane, a sine or a bump terrain of :mod:`robotdyn.constraints.terrain`, loop closures and joint couplings with a
:class:`~robotdyn.constraints.joint_coupling.CosineLaw`, with independent velocities that are a selection of v or a frame twist
(:class:`~robotdyn.reduction.operational_space.OperationalVelocities`); :func:`why_not` names what keeps another robot on
the Python path. The row choice of the projection is the Python path's (its last projection); where that choice
stops working (a singular block, rows that no longer span, a wheel lying flat) the evaluation falls back to the
Python path, which re-chooses or raises its usual error. ``ROBOTDYN_COMPILED=0`` in the environment, or
:func:`robotdyn.fast.dispatch.use_compiled` ``(False)``, turns the fast path off (:mod:`robotdyn.fast.dispatch` is where
every caller asks for it). The same C++ object also runs whole simulations
(:mod:`robotdyn.simulation.compiled_engine`, :mod:`robotdyn.simulation.many_runs`) and gives the constraint forces
(:meth:`CompiledModel.forces`). ``tests/test_compiled.py`` checks every output against
the Python path on every robot.
"""

from __future__ import annotations

import threading

import numpy as np

from ..constraints.constraint import ConstraintRows, KinematicState
from ..errors import RobotDynError
from ..constraints.joint_coupling import CosineLaw, JointCoupling
from ..constraints.loop_closure import LoopClosure
from ..reduction.operational_space import OperationalProjection
from ..reduction.projection import Projection, inverse_and_condition
from ..reduction.reduced_dynamics import ReducedDynamics, checked, reference
from ..constraints.rolling_contact import RollingWheel
from ..constraints.terrain import BumpTerrain, RampTerrain, SineTerrain

try:
    from .. import _compiled
    from .._compiled import Fallback
except ImportError:  # built without a C++ compiler: the Python path serves every robot
    _compiled = None

    class Fallback(RuntimeError):
        """The compiled path cannot decide here (never raised without the extension)."""

_KINDS = {"RX": "RX", "RY": "RY", "RZ": "RZ", "PX": "PX", "PY": "PY", "PZ": "PZ",
          "RevoluteUnaligned": "RU", "PrismaticUnaligned": "PU"}
SELF_CHECK_TOL = 1e-9
"""Relative tolerance of the check of the rebuilt model against the robot's Pinocchio model."""


def available() -> bool:
    """Whether the compiled extension was built (it needs a C++ compiler at install time).

    Returns:
        ``True`` if ``robotdyn._compiled`` was imported.
    """
    return _compiled is not None


def _terrain_code(terrain) -> tuple[int, list[float]] | None:
    """The C++ code of a terrain of :mod:`robotdyn.constraints.terrain` (``None``: not compiled, e.g. a user function)."""
    if isinstance(terrain, RampTerrain):
        grad = terrain.gradient(0.0, 0.0)
        return 0, [terrain.h, float(grad[0]), float(grad[1])]
    if type(terrain) is SineTerrain:
        return 1, [terrain.a, terrain.kx, terrain.ky, terrain.phase]
    if type(terrain) is BumpTerrain:
        return 2, [terrain.h, terrain.x0, terrain.w, float("nan") if terrain.length is None else terrain.length]
    return None


_COMPILED_FORMULAS = {
    RollingWheel: ("rows", "jacobian", "drift", "contact", "_geometry", "_world_jacobian"),
    LoopClosure: ("rows", "jacobian", "drift"),
}
"""The methods of each constraint class whose formulas ``_compiled.cpp`` reproduces."""


def _compiled_formulas(constraint, base: type) -> bool:
    """Whether ``constraint`` is a ``base`` evaluated by ``base``'s own formulas (a subclass overriding one of them,
    e.g. :class:`robotdyn.contact.stick_slip_wheel.StickSlipWheel`, is not what the C++ code computes)."""
    cls = type(constraint)
    return isinstance(constraint, base) and all(getattr(cls, m) is getattr(base, m) for m in _COMPILED_FORMULAS[base])


def why_not(robot, applied: bool = False) -> str | None:
    """Why ``robot`` cannot use the compiled path (``None``: it can).

    Args:
        robot: The :class:`~robotdyn.robot.Robot`.
        applied: Whether compliant wheels are compiled too (the compiled simulation's model,
            :func:`robotdyn.fast.applied_model.applied_model`); default ``False``: they keep a robot on the
            Python path. Joint springs and dampers are compiled either way (the evaluator adds their
            :math:`S^T Q` to the forward dynamics, their terms to the derivative set and :math:`-Q` to the
            constraint forces' right-hand side: ``kernels/joint_springs*.hpp``); the reduced model
            :math:`M_r, h_r` it returns is without them, as the Python path's.

    Returns:
        A one-line reason, or ``None``.
    """
    if _compiled is None:
        return "the compiled extension robotdyn._compiled was not built"
    if any(getattr(c, "rolling", False) for c in robot.constraints) and not applied:  # contact.compliant_rolling
        return "compliant wheels that roll while in contact (friction = 'rolling') are evaluated on the Python path"
    if any(getattr(c, "compliant", False) for c in robot.constraints) and not applied:
        return "compliant wheels (normal force laws) are evaluated on the Python path (not compiled)"
    for i in range(1, robot.model.njoints):
        kind = robot.model.joints[i].shortname().replace("JointModel", "")
        if kind not in _KINDS:
            return f"joint {robot.model.names[i]!r} of type {kind} is not compiled"
    terrains = set()
    for c in robot.constraints:
        compliant = applied and getattr(c, "compliant", False)  # robotdyn.contact.compliant_contact
        if _compiled_formulas(c, RollingWheel) or compliant:
            if _terrain_code(c.terrain) is None:
                return f"wheel {c.name!r} rolls on {c.terrain!r}, whose formulas are not compiled"
            terrains.add(id(c.terrain))
            if compliant:
                from .compiled_applied import compliant_refusal

                reason = compliant_refusal(c)
                if reason is not None:
                    return reason
        elif isinstance(c, JointCoupling) and type(c).rows is JointCoupling.rows:
            if not (isinstance(c.law, CosineLaw) and c.dlaw == c.law.d and c.ddlaw == c.law.dd):
                return f"coupling {c.name!r} has a law other than a CosineLaw"
        elif not _compiled_formulas(c, LoopClosure):
            return f"constraint {c!r} is not compiled"
    if len(terrains) > 1:
        return "the wheels roll on different terrains"
    op = getattr(robot, "operational", None)
    if op is not None and not hasattr(op, "twist"):
        return f"operational velocities {op!r} are not compiled"
    return None


class LazyProjection(Projection):
    """The :class:`~robotdyn.reduction.projection.Projection` of a compiled evaluation: the same S, independent, dependent
    velocities and rows, with :math:`A_d^{-1}` and the exact 1-norm condition number computed from A on first
    access (by the formulas of :func:`robotdyn.reduction.projection.project`). The compiled path itself needs neither: it
    solves with the LU factors and decides singularity by LAPACK's condition estimate, switching to the exact
    number from an estimate of 1e8 on (``robotdyn/kernels/projection.hpp``).

    Args:
        S: (n, k) with v = S nu.
        hint: The Python projection whose choice of rows and velocities was used.
        A: The stacked constraint rows at this configuration (m, n).
    """

    def __init__(self, S: np.ndarray, hint: Projection, A: np.ndarray) -> None:  # noqa: D107 (no dataclass init)
        self.S, self.independent, self.dependent, self.rows = S, hint.independent, hint.dependent, hint.rows
        self._layout, self._A, self._exact = hint._layout, A, None

    def _inverse(self) -> tuple[np.ndarray | None, float]:
        if self._exact is None:
            self._exact = inverse_and_condition(self._A[self._layout[1]]) if self.rows.size else (None, 1.0)
        return self._exact

    @property
    def Ad_inv(self) -> np.ndarray | None:
        """:math:`A_d^{-1}` (rows used x dependent), ``None`` without constraints."""
        return self._inverse()[0]

    @property
    def condition(self) -> float:
        """1-norm condition number of the dependent block :math:`A_d` (1 without constraints)."""
        return self._inverse()[1]


def _placement(M) -> np.ndarray:
    return np.hstack([M.rotation, M.translation[:, None]])


class ThreadError(RobotDynError):
    """A :class:`CompiledModel` used from a thread other than the one that built it."""


class CompiledModel:
    """A robot's reduced model as one C++ object (build with :func:`compiled_model`).

    A compiled model belongs to the thread that built it: its evaluations write into the evaluator's own buffers and
    :meth:`compute` and :meth:`forces` return views of them, which a call from another thread would overwrite while
    the first still reads them (a lock could not protect views that outlive the call). Every evaluation from
    another thread therefore raises :class:`ThreadError` in one line; each thread gets its own model from
    :func:`robotdyn.fast.dispatch.compiled_model`.

    Args:
        robot: A :class:`~robotdyn.robot.Robot` for which :func:`why_not` is ``None``.

    Raises:
        RuntimeError: The rebuilt model differs from the robot's Pinocchio model (a bug, never silent).
    """

    def __init__(self, robot) -> None:
        model = robot.model
        self.robot = robot
        self.owner = threading.get_ident()  # the thread that may evaluate it (see the class docstring)
        self.constraints = list(robot.constraints)
        kinds, parents, placements, axes, inertias = [], [], [], [], []
        for i in range(1, model.njoints):
            joint = model.joints[i]
            kinds.append(_KINDS[joint.shortname().replace("JointModel", "")])
            parents.append(int(model.parents[i]))
            placements.append(_placement(model.jointPlacements[i]))
            extracted = joint.extract()
            axes.append(np.asarray(getattr(extracted, "axis", np.zeros(3)), float))
            Y = model.inertias[i]
            I = Y.inertia
            inertias.append(np.array([Y.mass, *Y.lever, I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2]]))
        ev = _compiled.Evaluator(kinds, parents, placements, axes, inertias, np.asarray(model.gravity.linear, float))
        frames: dict[int, int] = {}

        def frame(fid: int) -> int:
            if fid not in frames:
                f = model.frames[fid]
                frames[fid] = ev.add_frame(int(f.parentJoint), _placement(f.placement))
            return frames[fid]

        self.wheels = [c for c in self.constraints if isinstance(c, RollingWheel)]
        self.couplings = [c for c in self.constraints if isinstance(c, JointCoupling)]
        for c in self.constraints:
            if getattr(c, "compliant", False):  # a compliant wheel (robotdyn.fast.compiled_applied)
                from .compiled_applied import add_compliant_wheel

                ev.set_terrain(*_terrain_code(c.terrain))
                add_compliant_wheel(ev, c, frame(c.fid))
            elif isinstance(c, RollingWheel):
                ev.set_terrain(*_terrain_code(c.terrain))
                ev.add_wheel(frame(c.fid), np.asarray(c.axis, float), float(c.radius),
                             -1 if c.radius_index is None else int(c.radius_index), np.asarray(c._directions, float))
            elif isinstance(c, JointCoupling):
                law = c.law
                ev.add_coupling(int(c.i), int(c.j), law.amplitude, law.rate, law.phase, law.offset)
            else:
                ev.add_closure(frame(c.f1), frame(c.f2), [int(s) for s in c._sel])
        for m in robot.motors:
            ev.add_motor(int(m.index), int(m.jid), -1 if m.rid is None else frame(m.rid))
        if getattr(robot, "springs", None):  # joint springs and dampers (kernels/joint_springs*.hpp)
            from .compiled_applied import add_springs

            add_springs(ev, robot)
        self.loads_open = self.slip_simulated = False  # (set by _add_slipping)
        self.slip_refusal = self._add_slipping(ev, robot)
        if self.wheels and hasattr(ev, "set_normal_stiffness"):  # the rigid limit of :meth:`forces`' open loads
            from ..constraints.wheel_compliance import wheel_stiffness

            ev.set_normal_stiffness(wheel_stiffness(robot, [c.name for c in self.wheels]))
        self.operational = getattr(robot, "operational", None)
        if self.operational is not None:
            tw = self.operational.twist
            self._op = (frame(tw.fid), [int(s) for s in tw.select], tw.axes == "local")
        self.ev = ev
        self.frame_ids = sorted(frames, key=frames.get)  # Pinocchio frame ids in the evaluator's order
        rows = robot.rows_at(robot.neutral())
        self.labels, self.holonomic = rows.labels, rows.holonomic
        self._check_model()
        self._hint = None
        self._compute, self._generation, self._views = ev.compute, -1, None

    def _add_slipping(self, ev, robot) -> str | None:
        """Give the evaluator the slipping wheels' friction laws (each wheel's ``compiled_friction()``, see
        :class:`robotdyn.contact.sliding.SlippingWheel`; this stage does not import the contact stage): returns why
        their friction is not compiled (``None``: it is, or there are none). Their rows are compiled either way.

        Where the rows leave the wheels' normal loads open (a rigid chassis on four wheels), the simulation's
        right-hand side solves the loads with the friction as :func:`robotdyn.contact.sliding_rigid_limit.coupled`
        does (``kernels/sliding_rigid_limit.hpp``; :attr:`loads_open` True), but the compiled derivatives and batched
        runs do not: the string returned then says so, and :func:`robotdyn.simulation.compiled_engine.choose_engine`
        runs the simulation compiled all the same. Joint springs and dampers beside slipping wheels likewise: the
        simulation's right-hand side adds their generalised force (``Evaluator.slip_rhs``), the compiled derivatives
        and batched runs do not carry it, and the string returned says so."""
        sliding = [c for c in robot.constraints if getattr(c, "sliding", False)]  # contact.sliding.sliding_now
        if not sliding:
            return None
        opened = None
        if getattr(robot, "springs", None):  # (the compiled slipping derivatives carry no Q)
            from ..reduction.joint_springs import urdf_damping_hint

            opened = ("slipping wheels beside joint springs or dampers: their derivatives and batched runs are on the "
                      "Python path" + urdf_damping_hint(robot.springs))
            if not hasattr(ev, "works"):  # (an extension whose slipping solve carries no Q)
                return ("slipping wheels on a robot with joint springs or dampers are evaluated on the Python path"
                        + urdf_damping_hint(robot.springs))
        rows = robot.rows_at(robot.neutral())
        labels = rows.labels
        open_loads = _loads_open(rows.A, labels, self.wheels)
        if open_loads:
            opened = opened or ("the wheels' normal loads are statically indeterminate (split by the rigid limit of "
                                "their normal compliance, robotdyn.contact.rigid_limit, solved with the friction): "
                                "their derivatives and batched runs are on the Python path")
            if not hasattr(ev, "set_slip_open"):  # (an extension built before the compiled coupled solve)
                return opened
        laws = []
        for c in sliding:
            friction = c.compiled_friction() if hasattr(c, "compiled_friction") else \
                f"wheel {c.name!r} ({type(c).__name__}) is simulated on the Python path"
            if isinstance(friction, str):
                return friction
            code, free = friction
            laws.append((self.wheels.index(c), labels.index(f"{c.name}.normal"), code, free))
        for wheel, row, (law, p0, p1), free in laws:
            ev.add_slipping(wheel, row, law, float(p0), float(p1), free)
        if open_loads:
            ev.set_slip_open(True)
            self.loads_open = True
        self.slip_simulated = opened is not None  # (the simulation's right-hand side is compiled all the same)
        return opened

    def __repr__(self) -> str:
        return f"CompiledModel({self.robot.spec.name!r}, nv={self.ev.nv}, rows={self.ev.nrows})"

    def _mine(self) -> None:
        """Refuse a call from a thread that does not own the model (:class:`ThreadError`)."""
        if threading.get_ident() != self.owner:
            raise ThreadError(f"compiled model of {self.robot.spec.name} used from a thread that did not build it "
                              "(its buffers are the building thread's); expected one model per thread: call "
                              "robotdyn.fast.dispatch.compiled_model(robot) in each thread")

    def _check_model(self) -> None:
        """The rebuilt model must give Pinocchio's M, g and RNEA of the robot's model at a random state."""
        import pinocchio as pin

        model, data = self.robot.model, self.robot.model.createData()
        rng = np.random.default_rng(0)
        q, v, a = (rng.uniform(-1.0, 1.0, model.nv) for _ in range(3))
        M, g, tau = self.ev.full(q, v, a)
        ref_M = pin.crba(model, data, q)
        ref_M = np.triu(ref_M) + np.triu(ref_M, 1).T
        ref_g = pin.computeGeneralizedGravity(model, data, q)
        ref_tau = pin.rnea(model, data, q, v, a)
        for name, x, ref in (("M", M, ref_M), ("g", g, ref_g), ("RNEA", tau, ref_tau)):
            err = float(np.max(np.abs(x - ref))) / max(1.0, float(np.max(np.abs(ref))))
            if not err <= SELF_CHECK_TOL:
                raise RuntimeError(
                    f"compiled model of {self.robot.spec.name}: {name} differs from Pinocchio's by {err:.3g}"
                )

    @property
    def ready(self) -> bool:
        """Whether a projection was chosen (by the Python path's first evaluation), so :meth:`rhs` can run."""
        return self._hint is not None

    def _choose(self, q: np.ndarray, nu: np.ndarray) -> None:
        """Let the Python path choose the projection's rows at (q, nu) (it raises its usual errors there)."""
        self.select(checked(reference(self.robot, q, nu), q, nu).projection)

    def select(self, proj) -> None:
        """Use the row choice (and independent velocities) of a Python projection from now on.

        Args:
            proj: A projection of the Python path (:class:`~robotdyn.reduction.projection.Projection` or the
                operational one).
        """
        self._mine()
        if proj is self._hint:
            return
        if self.operational is not None:
            frame, select, local = self._op
            self.ev.set_operational([int(r) for r in proj.rows], frame, select, local)
        else:
            self.ev.set_selection([int(r) for r in proj.rows], [int(i) for i in proj.independent],
                                  [int(i) for i in proj.dependent])
        self._hint = proj

    def evaluate(self, q: np.ndarray, nu: np.ndarray) -> tuple:
        """The raw outputs at (q, nu): ``(M_r, h, g_r, B_r, S, w, v, A, residual, condition, inverse)``, with
        ``condition`` and ``inverse`` :math:`K^{-1}` for operational velocities, ``None`` otherwise (the exact
        condition number and :math:`A_d^{-1}` then come from :class:`LazyProjection`, on request).

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.

        Returns:
            ``(M_r (k, k), h (k,), g_r (k,), B_r (k, motors), S (n, k), w (n,), v (n,), A (m, n), residual, condition,
            inverse)`` as described above; ``condition`` and ``inverse`` are ``None`` except for operational
            velocities.

        Raises:
            robotdyn._compiled.Fallback: The current row choice does not work here (use the Python path).
        """
        self._mine()
        if self._hint is None:
            self._choose(q, nu)
        return self.ev.evaluate(q, nu)

    def compute(self, q: np.ndarray, nu: np.ndarray) -> tuple:
        """``(M_r, h, g_r, B_r, S, w, v)`` at (q, nu) without copies: read-only views of the evaluator's buffers,
        overwritten by the next call (copy what must be kept). The cheapest evaluation, e.g. inside an integrator.

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.

        Returns:
            The 7-tuple ``(M_r, h, g_r, B_r, S, w, v)`` of read-only array views.

        Raises:
            robotdyn._compiled.Fallback: As :meth:`evaluate`.
        """
        self._mine()
        if self._hint is None:
            self._choose(q, nu)
        generation = self._compute(q, nu)
        if generation != self._generation:
            ev = self.ev
            self._views = (ev.M, ev.h, ev.g, ev.B, ev.S, ev.w, ev.v)
            self._generation = generation
        return self._views

    def reduced(self, q: np.ndarray, nu: np.ndarray, independent: np.ndarray | None = None):
        """The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics` at (q, nu), or ``None`` where the Python path
        must decide (then call :meth:`select` with its projection): no projection chosen yet, other
        ``independent`` velocity indices than the chosen ones, or a :meth:`evaluate` fallback.

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.
            independent: Indices of the independent velocities in v (default ``None``: the chosen ones).

        Returns:
            The :class:`~robotdyn.reduction.reduced_dynamics.ReducedDynamics`, or ``None``.
        """
        self._mine()
        hint = self._hint
        if hint is None or (independent is not None and independent is not getattr(hint, "independent", None)
                            and not np.array_equal(independent, hint.independent)):
            return None
        try:
            M, h, g, B, S, w, v, A, residual, cond, inv = self.ev.evaluate(q, nu)
        except Fallback:
            return None
        if self.operational is not None:
            proj = OperationalProjection(S, hint.rows, cond, inv)
        else:
            proj = LazyProjection(S, hint, A)
        rows0 = ConstraintRows(A, None, residual, self.holonomic, self.labels)
        robot = self.robot
        full_rows = lambda: robot.constraint_rows(KinematicState(robot.model, robot.data, q, v))  # noqa: E731
        return ReducedDynamics(M, h, g, B, S, w, v, proj, rows0, _full_rows=full_rows)

    def rhs(self, q: np.ndarray, nu: np.ndarray, tau: np.ndarray, stabilisation: float) -> np.ndarray:
        """:math:`(\\dot q, \\dot\\nu)` of :func:`robotdyn.simulation.engine.simulate`'s ODE in one call.

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.
            tau: Motor torques [N m] (forces [N] on prismatic joints), one per motor in the robot's motor order.
            stabilisation: Gain alpha [1/s] of the pull-back of the holonomic residuals (0: none).

        Returns:
            The state derivative :math:`(\\dot q, \\dot\\nu)` as one array (nq + k,).

        Raises:
            robotdyn._compiled.Fallback: As :meth:`evaluate`.
        """
        self._mine()
        if self._hint is None:
            self._choose(q, nu)
        return self.ev.rhs(q, nu, tau, stabilisation)

    def forces(self, q: np.ndarray, nu: np.ndarray, tau: np.ndarray) -> tuple:
        """Forward dynamics and constraint forces in one call, without copies (views overwritten by the next call,
        as :meth:`compute`): ``(nudot, lambda, e, wheel forces (nw, 3) along (t1, t2, n), the same in world axes,
        contact frames (nw, 9: rows t1, t2, n), contact points (nw, 3))``, with
        :math:`A^T\\lambda = e = Ma + Cv + g - B\\tau` solved on the projection's rows by the LU factors of
        :math:`A_d` (the projection's own factorisation; operational velocities: its :math:`K^{-1}`); where the
        rows are redundant, the loads rigid-body dynamics leave open are those of the rigid limit of the wheels'
        normal compliance (:mod:`robotdyn.contact.rigid_limit`, the same formulas in C++; minimum norm along what
        normal compliance does not fix), every determined row keeping its value (``rigid_limit(False)``: the basic
        solution instead, zero on redundant rows).

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            nu: Independent velocities (k,) [m/s, rad/s], ordered as the robot's velocity names.
            tau: Motor torques [N m] (forces [N] on prismatic joints), one per motor in the robot's motor order.

        Returns:
            ``(nudot (k,), lambda (m,), e (n,), wheel forces (nw, 3) [N] in (t1, t2, n), wheel forces (nw, 3) [N] in
            world axes, contact frames (nw, 9), contact points (nw, 3) [m])``: read-only views, overwritten by the next
            call.

        Raises:
            robotdyn._compiled.Fallback: As :meth:`evaluate`; also where the compatible loads would pull on a wheel
                (the no-pull split is :func:`robotdyn.contact.contact_forces.constraint_forces`').
        """
        self._mine()
        if self._hint is None:
            self._choose(q, nu)
        generation = self.ev.forces(q, nu, tau)
        if generation != getattr(self, "_fgeneration", None):
            ev = self.ev
            self._fviews = (ev.nudot, ev.lam, ev.e, ev.wheel_local, ev.wheel_world, ev.wheel_frames,
                            ev.contact_points)
            self._fgeneration = generation
        return self._fviews

    def rigid_limit(self, on: bool = True) -> None:
        """Whether :meth:`forces` splits the open loads by the rigid limit of compliance (default) or returns the
        basic solution (zero on redundant rows).

        Args:
            on: ``True``: the rigid limit (:mod:`robotdyn.contact.rigid_limit`); ``False``: the basic solution.
        """
        self.ev.set_rigid_limit(bool(on))

    def forces_at(self, q: np.ndarray, v: np.ndarray, a: np.ndarray, tau: np.ndarray) -> tuple:
        """The constraint forces at given full velocities v and accelerations a (inverse dynamics):
        ``(lambda, e, (wheel forces, world forces, frames, points), A)`` as :meth:`forces` (copies), with the
        constraint rows A (rows in :attr:`labels`' order).

        Args:
            q: Natural coordinates (n,) [m, rad], ordered as the robot's coordinates.
            v: Full velocities (n,) [m/s, rad/s].
            a: Full accelerations (n,) [m/s^2, rad/s^2].
            tau: Motor torques [N m] (forces [N] on prismatic joints), one per motor in the robot's motor order.

        Returns:
            ``(lambda (m,), e (n,), (wheel forces, world forces, frames, points), A (m, n))``: copies, the inner tuple
            as in :meth:`forces` (forces in N, points in m).

        Raises:
            robotdyn._compiled.Fallback: As :meth:`evaluate`.
        """
        self._mine()
        if self._hint is None:
            self._choose(q, np.zeros(self.robot.mobility))
        return self.ev.forces_at(q, v, a, tau)

    def evaluate_many(self, Q: np.ndarray, NU: np.ndarray) -> tuple:
        """Many states in one call: ``(M_r (N, k, k), h (N, k), g_r (N, k), S (N, n, k), w (N, n),
        B_r (N, k, motors), failed)`` with ``failed`` the indices left for the Python path.

        Args:
            Q: Coordinates (N, n) [m, rad].
            NU: Independent velocities (N, k).

        Returns:
            ``(M_r (N, k, k), h (N, k), g_r (N, k), S (N, n, k), w (N, n), B_r (N, k, motors), failed)``, ``failed``
            the list of state indices left for the Python path.
        """
        self._mine()
        N, n = Q.shape
        k = NU.shape[1]
        Q, NU = np.ascontiguousarray(Q, float), np.ascontiguousarray(NU, float)
        M, h, g, S, w, B, failed = self.ev.evaluate_many(Q, NU)
        return M.reshape(N, k, k), h, g, S.reshape(N, n, k), w, B.reshape(N, k, -1), list(failed)


__all__ = ["Fallback", "CompiledModel", "ThreadError", "LazyProjection", "why_not", "available"]


def _loads_open(A: np.ndarray, labels: list[str], wheels: list) -> bool:
    """Whether the rows A (m, n) leave some wheel's normal load open (a combination of redundant rows moves it):
    the wheel constraints' normal components (their ``_labels()`` and ``_directions``) against the null space of
    :math:`A^T`."""
    if not len(A):
        return False
    _, s, Vt = np.linalg.svd(A.T, full_matrices=True)
    rank = int(np.sum(s > s.max(initial=0.0) * max(A.shape) * np.finfo(float).eps))
    if rank == A.shape[0]:
        return False
    N = Vt[rank:].T
    index = {lab: i for i, lab in enumerate(labels)}
    for c in wheels:
        idx = [index[lab] for lab in c._labels()]
        if np.linalg.norm(np.asarray(c._directions, float)[:, 2] @ N[idx]) > 1e-9:
            return True
    return False


__all__ = ["Fallback", "CompiledModel", "LazyProjection", "why_not", "available"]

"""Traction along a simulated motion: each wheel's normal load, the friction the motion requires, and where the
no-slip assumption breaks.

The forces are those of :func:`robotdyn.contact.contact_forces.constraint_forces` at every output sample of a
:class:`~robotdyn.simulation.trajectory.Trajectory` (a post-pass: the integrator is not slowed down), computed by the
fast pass of :mod:`robotdyn.contact.traction_fast` (compiled calls and stacked linear algebra over blocks of samples,
no force object per sample: ~40 us a sample on Quasimoro against ~1.5 ms) wherever it serves the robot, else by
``constraint_forces`` itself sample by sample (``method="reference"`` forces that: compliant wheels and exact
stick-slip runs, a few milliseconds a sample), with what one sample's call evaluated twice done once
(:mod:`robotdyn.contact.traction_memo`) and the minimum-mu column solved for all samples at once, only where the run
reports it (:mod:`robotdyn.contact.traction_minimum`); ``progress`` reports that pass on stderr. Per wheel:

- the normal load :math:`f_n` [N] (positive: pressed on the ground);
- the required friction coefficient :math:`\\mu_{req} = \\|f_t\\| / f_n` (``inf`` where :math:`f_n \\le 0`);
- events: the first time a wheel's load reaches zero (lift-off: rolling without slipping then needs the ground
  to pull) and, where the wheel's friction coefficient :math:`\\mu` is known, the first time
  :math:`\\mu_{req} > \\mu` (the wheel would slip). Event times are interpolated linearly between samples.

An exact stick-slip run (``friction = "stick_slip"``, :mod:`robotdyn.simulation.stick_slip`) is reported through the
same pass, each sample in the phases the run had there (:mod:`robotdyn.contact.stick_slip_traction`): a sticking
wheel's required friction is what it needs (at most its law's mu), a sliding wheel's friction force is
:math:`\\mu f_n`; its events are the exact times at which wheels start to slide and the load at which one unloads.

A wheel whose load rigid-body dynamics do not determine (a planar root, a statically indeterminate wheel set: see
:mod:`robotdyn.contact.contact_forces`) is reported as such; its columns are left out rather than filled with an arbitrary
split.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .contact_forces import constraint_forces
from .stick_slip_traction import check_mu, phase_states, phases_of
from .sliding import sliding_now
from .stick_slip_wheel import StickSlipWheel
from .traction_fast import WheelLoads, sample_loads, wheel_loads
from .traction_memo import once_per_sample
from .traction_minimum import cone_problem, minimum_mu_many
from ..errors import InputError


@dataclass
class TractionEvent:
    """The first sample where a wheel's no-slip assumption breaks.

    Attributes:
        kind: ``lift-off`` (a rigid contact's normal load <= 0), ``unloaded`` (a compliant contact's load reaches 0:
            its spring-damper stops pushing while the tyre still touches; it leaves the ground later, at the lift-off
            of the run's flight phases), ``slip`` (required friction > mu) or ``slide`` (a stick-slip wheel starts
            to slide: its friction reaches mu times its load).
        wheel: The wheel's name.
        t: Time [s], interpolated between the two samples around the crossing.
        value: The normal load [N] (lift-off), the required friction (slip) at the first sample past it, or the
            wheel's mu (slide).
    """

    kind: str
    wheel: str
    t: float
    value: float

    def __str__(self) -> str:
        loaded = self.kind in ("lift-off", "unloaded")
        what = f"load {self.value:.4g} N" if loaded else f"required mu {self.value:.4g}"
        if self.kind == "slide":
            return (f"wheel {self.wheel} starts to slide at t = {self.t:.6g} s (its friction reaches mu N, "
                    f"mu = {self.value:.4g})")
        if self.wheel == ANY_SPLIT:
            return (f"slip at t = {self.t:.4g} s: no admissible split of the open forces stays within mu (the "
                    f"smallest mu that holds is {self.value:.4g})")
        if self.kind == "unloaded":
            return (f"zero load of compliant wheel {self.wheel} at t = {self.t:.4g} s (its contact stops pushing "
                    "while the tyre still touches; it leaves the ground at its flight-phase lift-off)")
        return f"{self.kind} of wheel {self.wheel} at t = {self.t:.4g} s ({what})"


ANY_SPLIT = "(every admissible split)"
"""The :attr:`TractionEvent.wheel` of a slip that no split of the forces rigid-body dynamics leave open avoids
(the minimum-mu column above the wheels' mu)."""


@dataclass
class Traction:
    """Wheel loads and required friction along a trajectory.

    Attributes:
        t: Sample times (N,) [s].
        wheels: Names of the wheels whose normal loads are determined (columns of the arrays).
        normal: (N, W) normal loads [N].
        tangential: (N, W) friction force magnitudes [N].
        required_mu: (N, W) :math:`\\|f_t\\|/f_n` (``inf`` where :math:`f_n \\le 0`; only meaningful where
            ``friction_determined``).
        friction_determined: (W,) whether each wheel's friction force (so its required mu) is determined.
        minimum_mu: (N,) the smallest mu with which some admissible split of undetermined forces lies in every
            cone (:meth:`robotdyn.contact.contact_forces.ConstraintForces.minimum_mu`); ``None`` when every friction force
            is determined (then it is the largest per-wheel required mu) or a normal load is not.
        mu: (W,) the wheels' friction coefficients (``nan``: not given, no slip check).
        undetermined: Wheels whose loads rigid-body dynamics do not determine, with the reason.
        events: The first lift-off and slip of each wheel (and the first sample where no admissible split holds:
            wheel :data:`ANY_SPLIT`), in time order.
        sliding: Wheels whose tangential force follows a friction law (they slip by design: no no-slip check).
        compliance: Wheels whose normal loads rigid-body dynamics leave open at some sample and the rigid limit of
            the wheels' normal compliance gives (:mod:`robotdyn.contact.rigid_limit`).
        compliant: Wheels whose normal contact is a force law of the penetration (``contact = "compliant"``,
            :mod:`robotdyn.contact.compliant_contact`): their zero load is flight (:meth:`in_air`), not a broken
            assumption.
        stick_slip: Wheels that switch between sticking and sliding (``friction = "stick_slip"``): their slip is
            the run's own, decided by their law's mu (no no-slip check).
        phases: (N, W) ``True`` where a stick-slip wheel slides at that sample (``None``: no stick-slip wheel);
            there its friction force is :math:`\\mu f_n` and its ``required_mu`` equals its mu.
        known: (N, W) whether each wheel's friction force is determined at each sample (``None``: not recorded; a
            stick-slip run records it: a sliding wheel's is, a sticking one's may be left open at rest).
        method: Which pass computed the loads: ``fast`` (:mod:`robotdyn.contact.traction_fast`, a few samples
            possibly by the reference) or ``reference`` (:func:`~robotdyn.contact.contact_forces.constraint_forces`
            at every sample).
    """

    t: np.ndarray
    wheels: list[str]
    normal: np.ndarray
    tangential: np.ndarray
    required_mu: np.ndarray
    mu: np.ndarray
    friction_determined: np.ndarray
    undetermined: dict[str, str] = field(default_factory=dict)
    minimum_mu: np.ndarray | None = None
    events: list[TractionEvent] = field(default_factory=list)
    method: str = "reference"
    sliding: list[str] = field(default_factory=list)
    compliance: list[str] = field(default_factory=list)
    compliant: list[str] = field(default_factory=list)
    stick_slip: list[str] = field(default_factory=list)
    phases: np.ndarray | None = None
    known: np.ndarray | None = None

    def needs(self) -> np.ndarray:
        """(N, W) where ``required_mu`` is a need: a wheel that rolls without slipping there (not a friction law's
        wheel, not a stick-slip wheel while it slides) and whose friction force is determined.

        Returns:
            A boolean array (N, W), samples by wheels in wheel order.
        """
        out = np.tile(np.array([w not in self.sliding for w in self.wheels], bool) & self.friction_determined,
                      (len(self.t), 1))
        if self.phases is not None:
            out &= ~self.phases
        return out

    def max_required_mu(self) -> dict[str, float]:
        """Each wheel's largest required friction over the samples where it is a need (:meth:`needs`; for a
        stick-slip wheel, while it sticks), by name; wheels where it never is one are left out.

        Returns:
            A dict wheel name -> largest :math:`\\|f_t\\|/f_n` (``inf`` where the load reached zero).
        """
        needs = self.needs()
        out = {}
        for j, w in enumerate(self.wheels):
            if not self.friction_determined[j]:
                continue
            if w not in self.stick_slip:
                out[w] = float(np.max(self.required_mu[:, j]))
            elif needs[:, j].any():
                out[w] = float(np.max(self.required_mu[needs[:, j], j]))
        return out

    def in_air(self) -> np.ndarray:
        """(N, W) where a compliant wheel (:attr:`compliant`) is in the air: its load is zero (a force law that
        never pulls), the flight its model allows.

        Returns:
            A boolean array (N, W), samples by wheels in wheel order, ``True`` where that wheel flies.
        """
        flies = np.array([w in self.compliant for w in self.wheels], bool)
        return (self.normal <= 0) & flies

    def broken(self) -> np.ndarray:
        """(N, W) where the no-slip assumption is broken: a rigid contact's load <= 0 (it would pull: lift-off),
        or required friction above mu (every wheel where no admissible split of the open forces stays within mu).
        A compliant wheel in the air is flight (:meth:`in_air`), not counted here.

        Returns:
            A boolean array (N, W), samples by wheels in wheel order, ``True`` where the assumption is broken.
        """
        air = self.in_air()
        out = (self.normal <= 0) & ~air
        rolling = np.array([w not in self.sliding and w not in self.stick_slip for w in self.wheels], bool)
        known = np.isfinite(self.mu) & self.friction_determined & rolling
        out[:, known] |= (self.required_mu[:, known] > self.mu[known]) & ~air[:, known]
        over = self._split_over()
        if over is not None:
            out[over] = True
        return out

    def _split_over(self) -> np.ndarray | None:
        """(N,) where the minimum-mu column exceeds every wheel's mu (``None``: no such column or no mu)."""
        if self.minimum_mu is None or not self.wheels or not np.isfinite(self.mu).all() or self.stick_slip:
            return None  # (a stick-slip run's sticking wheels are switched by the same cone check: sticking_cone)
        return np.asarray(self.minimum_mu, float) > np.max(self.mu)

    def columns(self) -> dict[str, np.ndarray]:
        """CSV columns by name: ``<wheel>.normal`` [N] and ``<wheel>.mu_required`` for each determined wheel; for a
        stick-slip wheel also ``<wheel>.sliding`` (1 while it slides, 0 while it sticks) and ``<wheel>.friction``
        (its friction force's magnitude [N]: the force it needs while sticking, mu times its load while sliding,
        where ``mu_required`` equals its mu).

        Returns:
            A dict of column name to a (N,) float array, wheels in wheel order, then ``mu_required_min`` (the smallest
            friction coefficient of :meth:`ConstraintForces.minimum_mu`) where that applies.
        """
        out = {}
        for j, name in enumerate(self.wheels):
            out[f"{name}.normal"] = self.normal[:, j]
            if self.friction_determined[j]:
                out[f"{name}.mu_required"] = self.required_mu[:, j]
            if name in self.stick_slip:
                out[f"{name}.sliding"] = self.phases[:, j].astype(float)
                if self.friction_determined[j]:
                    out[f"{name}.friction"] = self.tangential[:, j]
        if self.minimum_mu is not None:
            out["mu_required_min"] = self.minimum_mu
        return out

    def summary(self) -> str:
        """One line: the extremes per wheel set and the first event (or that the no-slip assumption holds).

        Returns:
            The one-line summary.
        """
        parts = []
        slid = [w for j, w in enumerate(self.wheels) if self.phases is not None and self.phases[:, j].any()]
        if self.wheels:
            needs = self.needs()
            mus = self.required_mu[needs]
            finite = mus[np.isfinite(mus)]
            peak = finite.max() if finite.size else float("inf")
            if self.minimum_mu is not None:  # every wheel's need, the open forces split at best
                peak = max(peak if finite.size else 0.0, float(np.max(self.minimum_mu)))
            parts.append(f"loads {self.normal.min():.4g}..{self.normal.max():.4g} N"
                         + (f", required mu up to {peak:.3g}" + (" while sticking" if self.stick_slip else "")
                            if needs.any() or self.minimum_mu is not None else ""))
            if self.compliance:
                parts.append(f"loads of {', '.join(self.compliance)}: rigid limit of compliance")
            if self.minimum_mu is not None:
                parts.append(f"with the best split of undetermined forces mu >= {np.max(self.minimum_mu):.3g} suffices")
        if slid:
            share = ", ".join(f"{w} {100 * self.phases[:, self.wheels.index(w)].mean():.3g} %" for w in slid)
            parts.append(f"stick-slip wheels slide (friction mu N) on part of the run: {share} of the samples")
        if self.events:
            parts.append("first: " + str(self.events[0]))
        elif self.sliding:
            parts.append(f"wheels {', '.join(self.sliding)} slide under their friction law (no no-slip check)")
        elif self.wheels and not slid:  # (never "holds" where a wheel slides)
            checked = "within every wheel's mu" if np.isfinite(self.mu).all() else "loads stay positive"
            if not self.friction_determined.all():
                checked += ", friction of " + ", ".join(
                    w for w, d in zip(self.wheels, self.friction_determined) if not d) + " not determined"
            parts.append(f"no-slip assumption holds ({checked})")
        if self.undetermined:
            parts.append(f"loads of {', '.join(self.undetermined)} not determined by rigid-body dynamics")
        elif not self.wheels:
            parts.append("no wheel")
        return "traction: " + "; ".join(parts)

    def __repr__(self) -> str:
        return f"Traction(wheels={self.wheels}, N={len(self.t)}, events={len(self.events)})"


METHODS = ("auto", "reference")
"""How :func:`traction` computes the loads: ``auto`` by the fast pass (:func:`robotdyn.contact.traction_fast.
wheel_loads`) where it serves the robot, else sample by sample; ``reference`` sample by sample
(:func:`~robotdyn.contact.contact_forces.constraint_forces` at every sample)."""


def traction(robot, traj, torque: Callable | None = None, mu: float | dict[str, float] | None = None,
             method: str = "auto", progress: bool = False) -> Traction:
    """Wheel loads, required friction and no-slip events along a trajectory.

    Args:
        robot: The :class:`~robotdyn.robot.Robot` the trajectory was simulated with.
        traj: The :class:`~robotdyn.simulation.trajectory.Trajectory`.
        torque: The motor torques ``tau(t, q, nu)`` it was simulated with (``None``: unactuated).
        mu: Friction coefficient of every wheel, or by wheel name; default each wheel's own ``mu`` (its spec),
            else no slip check.
        method: ``auto`` (default): the fast pass of :mod:`robotdyn.contact.traction_fast` (compiled calls and
            stacked linear algebra over blocks of samples, the same numbers) where it serves the robot, the
            per-sample reference elsewhere (slipping wheels, no compiled model) and at the samples it cannot
            serve; ``reference``: :func:`~robotdyn.contact.contact_forces.constraint_forces` at every sample.
        progress: Report on stderr, once the pass has taken more than a second, the samples done (at most once a
            second) and at its end how long it took, by which pass and why (:class:`PassReport`).

    Returns:
        The :class:`Traction` (``method`` says which pass computed it: ``fast`` or ``reference``).

    Example:
        >>> import robotdyn
        >>> from robotdyn.contact.traction import traction
        >>> from robotdyn.robots.quasimoro import model
        >>> robot = robotdyn.load("quasimoro")
        >>> scenario = model.SCENARIOS["rectilinear"]
        >>> traj = scenario.run(robot, t_end=1.0, progress=False)
        >>> tr = traction(robot, traj, scenario.torque)
        >>> tr.wheels, round(float(tr.normal.min()), 2)  # (2 m + M) g / 2 on each wheel [N]
        (['wheel_A', 'wheel_B'], 29.43)
        >>> round(float(tr.minimum_mu.max()), 4)  # the friction the manoeuvre needs
        0.0103
    """
    if method not in METHODS:
        raise InputError(f"method = {method!r}; expected one of {', '.join(METHODS)}")
    table = phases_of(traj)
    report = PassReport(len(traj.t), progress)
    if table is not None:  # exact stick-slip: each sample in its phases, by the reference
        check_mu(robot, mu)
        report.why = "the fast pass does not serve exact stick-slip phases"
        with phase_states(robot, traj, table) as state:
            loads = _reference_loads(robot, traj, torque, state, report)
        used = "reference"
    else:
        loads = wheel_loads(robot, traj.t, traj.q, traj.nu, torque) if method == "auto" else None
        used = "reference" if loads is None else "fast"
        report.why = _why_reference(robot) if method == "auto" else "method = 'reference'"
    if loads is None:
        loads = _reference_loads(robot, traj, torque, report=report)
    report.done(used)
    names = loads.names
    undetermined = {}
    for j, name in enumerate(names):
        if not loads.normal_determined[:, j].all():
            undetermined[name] = "normal load not determined (see robotdyn.contact.contact_forces)"
    keep = [j for j, name in enumerate(names) if name not in undetermined]
    friction_known = loads.load_determined[:, keep].all(axis=0)
    normal = loads.normal[:, keep]
    tangential = loads.tangential[:, keep]
    with np.errstate(divide="ignore", invalid="ignore"):
        required = np.where(normal > 0, tangential / np.where(normal > 0, normal, 1.0), np.inf)
    wheels = [names[j] for j in keep]
    out = Traction(np.asarray(traj.t, float), wheels, normal, tangential, required,
                   _friction_coefficients(robot, wheels, mu), friction_known, undetermined)
    out.minimum_mu = loads.minimum_mu
    out.method = used
    by_law = {c.name for c in robot.constraints if not isinstance(c, StickSlipWheel) and (getattr(c, "sliding", False)
              or (hasattr(c, "law") and not getattr(c, "rolling", False)))}  # rolling compliant: no law, no slip
    out.sliding = [w for w in wheels if w in by_law]  # (they slip by design: their friction is their law's)
    compliant = {(w.name or w.frame) for w in robot.spec.wheels if getattr(w, "contact", "rigid") == "compliant"}
    out.compliant = [w for w in wheels if w in compliant]  # (a zero load is flight)
    if loads.compliance is not None:
        out.compliance = [names[j] for j in keep if loads.compliance[:, j].any()]
    if table is not None:
        out.stick_slip = [w for w in wheels if w in table.wheels]
        out.known = loads.load_determined[:, keep]
        out.phases = np.zeros((len(out.t), len(wheels)), bool)
        for j, w in enumerate(wheels):
            if w in table.wheels:
                out.phases[:, j] = table.sliding[:, table.wheels.index(w)]
    out.events = _events(out, traj.stats if table is not None else None)
    return out


class PassReport:
    """Progress of a traction pass on stderr (``simulate`` without ``--quiet``): nothing during its first second,
    then the samples done at most once a second, and at the end the time it took, by which pass and why the fast
    one did not serve (a per-sample reference pass costs milliseconds a sample).

    Args:
        n: Number of samples.
        enabled: Whether to print.
        interval: Seconds between two lines (and before the first) [s].
    """

    def __init__(self, n: int, enabled: bool, interval: float = 1.0) -> None:
        self.n, self.enabled, self.interval = n, enabled, interval
        self.start = self.last = time.perf_counter()
        self.why = ""
        self.printed = False

    def __call__(self, i: int) -> None:
        """Report that sample ``i`` is next (a line if a second has passed since the last).

        Args:
            i: The sample's index (0-based).
        """
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self.last >= self.interval:
            self.last, self.printed = now, True
            print(f"traction: sample {i} / {self.n} ({100 * i / max(self.n, 1):.0f}%), per-sample reference pass",
                  file=sys.stderr, flush=True)

    def done(self, used: str) -> None:
        """Report the end of the pass (a line if it took a second or more, or printed progress).

        Args:
            used: Which pass computed the loads (:attr:`Traction.method`: ``fast`` or ``reference``).
        """
        took = time.perf_counter() - self.start
        if self.enabled and (self.printed or took >= self.interval):
            why = f" ({self.why})" if used == "reference" and self.why else ""
            print(f"traction: {self.n} samples in {took:.3g} s by the {used} pass{why}", file=sys.stderr, flush=True)


def _why_reference(robot) -> str:
    """Why the fast pass (:func:`~robotdyn.contact.traction_fast.wheel_loads`) may not serve ``robot``: the reason
    its compiled model gives (:func:`robotdyn.fast.dispatch.why_not`), or its slipping wheels."""
    from ..fast.dispatch import why_not

    if sliding_now(robot):
        return "slipping wheels are evaluated on the Python path"
    return why_not(robot) or ""


def _reference_loads(robot, traj, torque, state: Callable[[int], np.ndarray] | None = None,
                     report: Callable[[int], None] | None = None) -> WheelLoads:
    """The :class:`~robotdyn.contact.traction_fast.WheelLoads` of a trajectory by
    :func:`~robotdyn.contact.contact_forces.constraint_forces` at every sample (only the loads are kept), with
    ``minimum_mu`` where every sample has a wheel whose load is not all determined and it is never ``None``;
    ``state(i)``, where given, sets the robot to sample i's state and returns its independent velocities
    (:func:`robotdyn.contact.stick_slip_traction.phase_states`); ``report(i)``, where given, is told each sample's
    index (:class:`PassReport`)."""
    zero = np.zeros(len(robot.motors))
    N = len(traj.t)
    names: list[str] = []
    normal = tangential = determined = None
    minimum = []
    with once_per_sample(robot) as next_sample:  # (what one sample's call evaluated twice: once)
        for i, t in enumerate(traj.t):
            next_sample()
            if report is not None:
                report(i)
            nu = traj.nu[i] if state is None else state(i)
            tau = zero if torque is None else np.asarray(torque(t, traj.q[i], nu), float)
            forces = constraint_forces(robot, traj.q[i], nu, tau=tau)
            names_i, fn, ft, det = sample_loads(forces)
            if normal is None:
                names = names_i
                normal, tangential = np.zeros((N, len(names))), np.zeros((N, len(names)))
                determined = np.zeros((N, len(names), 3), bool)
                compliance = np.zeros((N, len(names)), bool)
            normal[i], tangential[i], determined[i] = fn, ft, det
            compliance[i] = [w.compliance[2] for w in forces.wheels]
            if not det.all():
                minimum.append(cone_problem(forces))  # (solved for all samples at once below)
    if normal is None:
        normal, tangential, determined = np.zeros((0, 0)), np.zeros((0, 0)), np.zeros((0, 0, 3), bool)
        compliance = np.zeros((0, 0), bool)
    out = WheelLoads(names, normal, tangential, determined[:, :, 2], determined.all(axis=2), compliance=compliance)
    if minimum and len(minimum) == N and all(m is not None for m in minimum):
        out.minimum_mu = np.array(minimum_mu_many(minimum), float)
    return out


def _friction_coefficients(robot, wheels: list[str], mu) -> np.ndarray:
    """Each wheel's mu: the argument (a number or a dict by name), else the wheel spec's ``mu``, else nan."""
    own = {(w.name or w.frame): getattr(w, "mu", None) for w in robot.spec.wheels}
    out = np.full(len(wheels), np.nan)
    if isinstance(mu, dict):
        unknown = set(mu) - set(own)
        if unknown:
            raise InputError(f"unknown wheel(s) {', '.join(sorted(unknown))} in mu; expected {', '.join(own)}")
    for j, name in enumerate(wheels):
        value = mu.get(name) if isinstance(mu, dict) else mu
        value = own.get(name) if value is None else value
        if value is not None:
            value = float(value)
            if not np.isfinite(value) or value < 0:
                raise InputError(f"friction coefficient mu = {value} for wheel {name!r}; expected a number >= 0")
            out[j] = value
    return out


def _events(tr: Traction, stats: dict | None = None) -> list[TractionEvent]:
    """The first lift-off and the first slip of each wheel, interpolated between samples, in time order; for a
    stick-slip run (its ``stats``) the exact time each wheel first slides and where one unloaded."""
    events = []
    if stats is not None:
        first = {}
        for j, w in enumerate(tr.wheels):  # sliding from the start (launched with slip, or beyond its cone at t = 0)
            if w in tr.stick_slip and tr.phases[0, j]:
                first[w] = float(tr.t[0])
        for s in stats.get("switches", []):
            if s["phase"] == "slide" and s["wheel"] in tr.wheels:
                first.setdefault(s["wheel"], float(s["t"]))
        events += [TractionEvent("slide", w, t, float(tr.mu[tr.wheels.index(w)])) for w, t in first.items()]
        lift = stats.get("lift_off")
        if lift is not None and lift["wheel"] in tr.wheels:
            events.append(TractionEvent("lift-off", lift["wheel"], float(lift["t"]), float(lift["load"])))
    for j, name in enumerate(tr.wheels):
        fn = tr.normal[:, j]
        idx = np.flatnonzero(fn <= 0)
        if idx.size and not any(e.kind == "lift-off" and e.wheel == name for e in events):
            kind = "unloaded" if name in tr.compliant else "lift-off"  # (a compliant tyre's geometric lift-off
            events.append(TractionEvent(kind, name, _crossing(tr.t, fn, idx[0], 0.0), float(fn[idx[0]])))  # is later)
        if np.isfinite(tr.mu[j]) and tr.friction_determined[j] and name not in tr.sliding + tr.stick_slip:
            over = np.flatnonzero((fn > 0) & (tr.required_mu[:, j] > tr.mu[j]))
            if over.size:
                k = over[0]
                events.append(TractionEvent("slip", name, _crossing(tr.t, tr.required_mu[:, j], k, tr.mu[j]),
                                            float(tr.required_mu[k, j])))
    over = tr._split_over()
    if over is not None and over.any():
        k = int(np.flatnonzero(over)[0])
        level = float(np.max(tr.mu))
        events.append(TractionEvent("slip", ANY_SPLIT, _crossing(tr.t, np.asarray(tr.minimum_mu, float), k, level),
                                    float(tr.minimum_mu[k])))
    return _in_time_order(events, tr.wheels)


def _in_time_order(events: list[TractionEvent], wheels: list[str]) -> list[TractionEvent]:
    """Events sorted by time; those at the same instant (1e-12 s apart or less: crossings interpolated in the same
    sample interval differ only in their last bits) in a fixed order, lift-offs before slips, named wheels in the
    robot's order before the any-split slip, so that the summary's first event does not depend on rounding."""
    rank = {name: j for j, name in enumerate(wheels)}
    groups: list[list[TractionEvent]] = []
    for e in sorted(events, key=lambda e: e.t):
        if groups and abs(e.t - groups[-1][0].t) <= 1e-12:
            groups[-1].append(e)
        else:
            groups.append([e])
    return [e for g in groups for e in sorted(g, key=lambda e: (e.kind == "slip", rank.get(e.wheel, len(rank))))]


def _crossing(t: np.ndarray, y: np.ndarray, k: int, level: float) -> float:
    """Time where y crosses ``level`` between samples k-1 and k (linear interpolation; t[k] at the first
    sample or where y jumps to inf)."""
    if k == 0 or not (np.isfinite(y[k]) and np.isfinite(y[k - 1])) or y[k] == y[k - 1]:
        return float(t[k])
    s = (level - y[k - 1]) / (y[k] - y[k - 1])
    return float(t[k - 1] + min(max(s, 0.0), 1.0) * (t[k] - t[k - 1]))

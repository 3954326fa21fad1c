"""Motor torques as data: profiles of time that the compiled integrator evaluates without Python.

A scenario's torques ``tau(t, q, nu)`` may be any Python callable on the scipy path of
:func:`robotdyn.simulation.engine.simulate`; the compiled integrator (:mod:`robotdyn.simulation.compiled_engine`) runs without
the GIL and therefore takes torques as data: a :class:`TorqueProfile`, a sum of terms, each a vector over the
motors [N m or N] times a scalar function of time:

- :class:`Constant`: :math:`\\tau = c`;
- :class:`Sine`: :math:`\\tau = c \\sin(\\omega t + \\varphi)` inside a window :math:`t_0 \\le t \\le t_1`, zero
  outside (e.g. Staicu's Quasimoro pulse, eq 19: :math:`0.1 \\sin(\\pi t)` for :math:`t \\le 1` s);
- :class:`Table`: piecewise-linear interpolation of values at increasing times, held constant outside them;
- :class:`Polynomial`: :math:`\\tau = c_0 + c_1 t + \\dots + c_d t^d` inside a window, zero outside (Horner's
  scheme on both sides);
- :class:`PiecewisePolynomial`: a polynomial in :math:`t - x_j` on each piece :math:`[x_j, x_{j+1}]` of a set of
  knots, zero outside them; :meth:`PiecewisePolynomial.fit` interpolates a smooth function of time (Chebyshev
  interpolation on each piece) to a stated error;
- sums of these (``a + b``, or :class:`Sum`).

A profile is callable with the scipy path's signature ``profile(t, q, nu)`` (q and nu are ignored), and
:meth:`TorqueProfile.encode` gives the flat arrays the C++ side reads (``robotdyn/_compiled.cpp``,
``TorqueProfile``), which evaluates every term with the same floating-point operations in the same order (libm's
``sin`` on both sides), so that both paths see the same torques bit for bit (``tests/test_torque_profile.py``).
:meth:`TorqueProfile.breakpoints` lists the times where a profile is not smooth (window edges, table knots): the
compiled integrator steps onto them instead of stepping across a kink. Profiles pickle (for worker processes).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError

CONSTANT, SINE, TABLE, POLYNOMIAL, PIECEWISE = 0, 1, 2, 3, 4
"""Term kinds in :meth:`TorqueProfile.encode` (the C++ side's codes)."""


def _values(values, what: str) -> np.ndarray:
    out = np.atleast_1d(np.asarray(values, dtype=float))
    if out.ndim != 1 or not np.all(np.isfinite(out)):
        raise InputError(f"{what} = {values!r}; expected a finite torque per motor [N m or N]")
    return out


class TorqueProfile:
    """Base class: a sum of terms (see the module docstring). Subclasses define :meth:`_terms`."""

    @property
    def motors(self) -> int:
        """Number of motors (length of the torque vector)."""
        return self._all()[0][1].shape[-1]

    def _all(self) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """:meth:`_terms`, built once (profiles are not changed after construction)."""
        terms = self.__dict__.get("_cache")
        if terms is None:
            terms = self.__dict__["_cache"] = self._terms()
        return terms

    def _terms(self) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """``(kind, coefficients, parameters)`` per term (see :meth:`encode`)."""
        raise NotImplementedError

    def __call__(self, t: float, q=None, nu=None) -> np.ndarray:
        """The motor torques at time t [s] (q, nu ignored: the scipy path's ``tau(t, q, nu)`` signature)."""
        t = float(t)
        terms = self._all()
        out = np.zeros(terms[0][1].shape[-1])
        for kind, coef, par in terms:
            if kind == CONSTANT:
                out = out + coef
            elif kind == SINE:
                if par[2] <= t <= par[3]:
                    out = out + coef * math.sin(par[0] * t + par[1])
            elif kind == POLYNOMIAL:
                if par[0] <= t <= par[1]:
                    out = out + _horner(coef, t)
            elif kind == PIECEWISE:
                if par[1] <= t <= par[-1]:
                    j, s = _piece(par[1:], np.array([t]))
                    out = out + _horner(_blocks(coef, par)[j[0]], s[0])
            else:  # coef: (points, motors) values, par: the times
                out = out + _interpolate(par, coef, t)
        return out

    def at(self, times) -> np.ndarray:
        """The motor torques at many times at once (the same formulas as calling the profile, vectorised).

        Args:
            times: Times (T,) [s].

        Returns:
            (T, motors) [N m or N]: row i the value of ``self(times[i])``.
        """
        t = np.asarray(times, float).reshape(-1)
        terms = self._all()
        out = np.zeros((t.size, terms[0][1].shape[-1]))
        for kind, coef, par in terms:
            if kind == CONSTANT:
                out = out + coef
            elif kind == SINE:
                inside = (par[2] <= t) & (t <= par[3])
                out = out + np.where(inside[:, None], coef * np.sin(par[0] * t + par[1])[:, None], 0.0)
            elif kind == POLYNOMIAL:
                inside = (par[0] <= t) & (t <= par[1])
                out = out + np.where(inside[:, None], _horner(coef, t[:, None]), 0.0)
            elif kind == PIECEWISE:
                inside = (par[1] <= t) & (t <= par[-1])
                j, s = _piece(par[1:], t)
                blocks = np.moveaxis(_blocks(coef, par)[j], 0, 1)  # (degree + 1, T, motors)
                out = out + np.where(inside[:, None], _horner(blocks, s[:, None]), 0.0)
            else:
                i = np.clip(np.searchsorted(par, t, side="right") - 1, 0, len(par) - 2)
                s = (t - par[i]) / (par[i + 1] - par[i])
                inner = coef[i] + s[:, None] * (coef[i + 1] - coef[i])
                out = out + np.where((t <= par[0])[:, None], coef[0], np.where((t >= par[-1])[:, None], coef[-1],
                                                                                inner))
        return out

    def breakpoints(self) -> np.ndarray:
        """Sorted times [s] where the profile or its derivative jumps (window edges, table knots).

        Returns:
            The times (P,) [s], sorted, without duplicates.
        """
        points = []
        for kind, _, par in self._all():
            if kind == SINE:
                points += [x for x in par[2:4] if math.isfinite(x)]
            elif kind == POLYNOMIAL:
                points += [x for x in par[0:2] if math.isfinite(x)]
            elif kind == PIECEWISE:  # par[0]: whether the pieces join smoothly (only the ends are breakpoints)
                points += [par[1], par[-1]] if par[0] else list(par[1:])
            elif kind == TABLE:
                points += list(par)
        return np.array(sorted(set(map(float, points))), float)  # np.unique would import numpy.ma (~20 ms) on first use

    def encode(self) -> tuple[list[int], list[np.ndarray], list[np.ndarray]]:
        """The terms as the C++ side reads them: kinds, coefficient arrays ((motors,) or (points, motors)) and
        parameter arrays (sine: omega [rad/s], phase [rad], window start and end [s]; table: the times [s]).

        Returns:
            ``(kinds, coefficients, parameters)``: three lists with one entry per term.
        """
        terms = self._all()
        return ([k for k, _, _ in terms], [np.ascontiguousarray(c, float) for _, c, _ in terms],
                [np.ascontiguousarray(p, float) for _, _, p in terms])

    def __add__(self, other: TorqueProfile) -> Sum:
        if not isinstance(other, TorqueProfile):
            return NotImplemented
        return Sum(self, other)

    def scaled(self, factor: float) -> TorqueProfile:
        """The profile times a finite scalar ``factor`` (every term's coefficients scaled).

        Args:
            factor: The scale (dimensionless, finite).

        Returns:
            A :class:`Scaled` profile.
        """
        return Scaled(self, factor)

    def __eq__(self, other) -> bool:
        if not isinstance(other, TorqueProfile):
            return NotImplemented
        a, b = self._all(), other._all()
        return len(a) == len(b) and all(ka == kb and np.array_equal(ca, cb) and np.array_equal(pa, pb)
                                        for (ka, ca, pa), (kb, cb, pb) in zip(a, b))

    __hash__ = None


def _horner(coef: np.ndarray, t):
    """c_0 + t (c_1 + t (c_2 + ...)) per motor (coef: (degree + 1, motors)), the C++ side's order of operations."""
    p = coef[-1]
    for i in range(coef.shape[0] - 2, -1, -1):
        p = coef[i] + t * p
    return p


def _blocks(coef: np.ndarray, par: np.ndarray) -> np.ndarray:
    """A piecewise term's coefficients (pieces (degree + 1), motors) as (pieces, degree + 1, motors)."""
    return coef.reshape(len(par) - 2, -1, coef.shape[-1])


def _piece(knots: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The piece j of each time (the last knot belongs to the last piece) and s = t - knots[j] (the C++ side's
    choice)."""
    j = np.clip(np.searchsorted(knots, t, side="right") - 1, 0, len(knots) - 2)
    return j, t - knots[j]


def _interpolate(times: np.ndarray, values: np.ndarray, t: float) -> np.ndarray:
    """Piecewise-linear interpolation, held constant outside [times[0], times[-1]] (the C++ side's formula)."""
    if t <= times[0]:
        return values[0]
    if t >= times[-1]:
        return values[-1]
    i = int(np.searchsorted(times, t, side="right")) - 1
    s = (t - times[i]) / (times[i + 1] - times[i])
    return values[i] + s * (values[i + 1] - values[i])


class Constant(TorqueProfile):
    """Constant torques ``values`` (one per motor) [N m or N].

    Args:
        values: One torque [N m] (force [N] on a prismatic joint) per motor, in the robot's motor order.

    Raises:
        InputError: Not a finite vector.

    Example:
        >>> from robotdyn.simulation.torque_profile import Constant
        >>> tau = Constant([0.5, -0.5])
        >>> tau.at([0.0, 1.0]).tolist()
        [[0.5, -0.5], [0.5, -0.5]]
    """

    def __init__(self, values) -> None:
        self.values = _values(values, "torques")

    def _terms(self):
        return [(CONSTANT, self.values, np.zeros(0))]

    def __repr__(self) -> str:
        return f"Constant({self.values.tolist()})"


class Sine(TorqueProfile):
    """:math:`\\tau = a \\sin(\\omega t + \\varphi)` for ``start <= t <= stop``, zero outside.

    Args:
        amplitude: Per motor [N m or N].
        omega: Angular frequency [rad/s].
        phase: [rad].
        start, stop: The window [s] (default: always on).
    """

    def __init__(self, amplitude, omega: float, phase: float = 0.0, start: float = -math.inf,
                 stop: float = math.inf) -> None:
        self.amplitude = _values(amplitude, "amplitude")
        self.omega, self.phase, self.start, self.stop = float(omega), float(phase), float(start), float(stop)
        if not (math.isfinite(self.omega) and math.isfinite(self.phase)):
            raise InputError(f"sine torque: omega = {omega!r}, phase = {phase!r}; expected finite numbers")
        if math.isnan(self.start) or math.isnan(self.stop) or self.start > self.stop:
            raise InputError(f"sine torque window [{start!r}, {stop!r}] s; expected start <= stop")

    def _terms(self):
        return [(SINE, self.amplitude, np.array([self.omega, self.phase, self.start, self.stop]))]

    def __repr__(self) -> str:
        return (f"Sine({self.amplitude.tolist()}, omega={self.omega:g}, phase={self.phase:g}, "
                f"window=[{self.start:g}, {self.stop:g}] s)")


class Table(TorqueProfile):
    """Piecewise-linear torques through ``values[i]`` at ``times[i]`` (strictly increasing) [s], held at the first
    and last values outside them.

    Args:
        times: (points,) [s].
        values: (points, motors) [N m or N].
    """

    def __init__(self, times, values) -> None:
        self.times = np.asarray(times, dtype=float)
        self.values = np.asarray(values, dtype=float)
        if self.values.ndim == 1:
            self.values = self.values[:, None]
        if (self.times.ndim != 1 or self.times.size < 1 or self.values.shape[0] != self.times.size
                or self.values.shape[1] == 0):
            raise InputError(f"torque table: times {self.times.shape}, values {self.values.shape}; expected "
                             "(points,) and (points, motors)")
        if not (np.all(np.isfinite(self.times)) and np.all(np.isfinite(self.values))):
            raise InputError("torque table: expected finite times and values")
        if np.any(np.diff(self.times) <= 0):
            raise InputError("torque table: expected strictly increasing times")

    def _terms(self):
        return [(TABLE, self.values, self.times)]

    def __repr__(self) -> str:
        return f"Table({self.times.size} points, {self.times[0]:g} .. {self.times[-1]:g} s)"


class Polynomial(TorqueProfile):
    """:math:`\\tau = c_0 + c_1 t + \\dots + c_d t^d` for ``start <= t <= stop`` [s], zero outside (e.g. a quintic
    rest-to-rest reference and its derivatives).

    Args:
        coefficients: (degree + 1, motors), lowest power first [N m / s^i or N / s^i].
        start, stop: The window [s] (default: always on).

    Raises:
        InputError: Not a finite (degree + 1, motors) array, or an empty window.

    Example:
        >>> from robotdyn.simulation.torque_profile import Polynomial
        >>> Polynomial([[1.0], [0.0], [2.0]], 0.0, 1.0).at([0.5, 2.0]).tolist()  # 1 + 2 t^2 on [0, 1]
        [[1.5], [0.0]]
    """

    def __init__(self, coefficients, start: float = -math.inf, stop: float = math.inf) -> None:
        self.coefficients = np.asarray(coefficients, dtype=float)
        if self.coefficients.ndim == 1:
            self.coefficients = self.coefficients[:, None]
        if (self.coefficients.ndim != 2 or self.coefficients.size == 0
                or not np.all(np.isfinite(self.coefficients))):
            raise InputError(f"polynomial torque: coefficients of shape {self.coefficients.shape}; expected finite "
                             "(degree + 1, motors)")
        self.start, self.stop = float(start), float(stop)
        if math.isnan(self.start) or math.isnan(self.stop) or self.start > self.stop:
            raise InputError(f"polynomial torque window [{start!r}, {stop!r}] s; expected start <= stop")

    def _terms(self):
        return [(POLYNOMIAL, self.coefficients, np.array([self.start, self.stop]))]

    def __repr__(self) -> str:
        return (f"Polynomial(degree {self.coefficients.shape[0] - 1}, {self.coefficients.shape[1]} values, "
                f"window=[{self.start:g}, {self.stop:g}] s)")


class PiecewisePolynomial(TorqueProfile):
    """:math:`\\tau = c_{j0} + c_{j1} s + \\dots + c_{jd} s^d`, :math:`s = t - x_j`, on the piece
    :math:`x_j \\le t \\le x_{j+1}` of the knots :math:`x_0 < \\dots < x_m` [s], zero outside :math:`[x_0, x_m]`
    (a knot between two pieces belongs to the later one). Where the pieces are a fit of one smooth function
    (:meth:`fit`, ``smooth=True``) only :math:`x_0` and :math:`x_m` are breakpoints (:meth:`breakpoints`: the
    compiled integrator restarts there); else every knot is.

    Args:
        knots: (m + 1,) increasing times [s].
        coefficients: (m, degree + 1, motors), piece by piece, lowest power of s first [N m / s^i or N / s^i].
        smooth: Whether the pieces join smoothly (to rounding), so that the inner knots are not breakpoints
            (default False).

    Raises:
        InputError: Knots not finite and increasing, or coefficients not a finite (m, degree + 1, motors) array.

    Example:
        >>> from robotdyn.simulation.torque_profile import PiecewisePolynomial
        >>> PiecewisePolynomial([0.0, 1.0, 2.0], [[[0.0], [1.0]], [[1.0], [-1.0]]]).at([0.5, 1.5, 3.0]).tolist()
        [[0.5], [0.5], [0.0]]
    """

    def __init__(self, knots, coefficients, smooth: bool = False) -> None:
        self.knots = np.asarray(knots, dtype=float)
        self.coefficients = np.asarray(coefficients, dtype=float)
        if self.knots.ndim != 1 or self.knots.size < 2 or not np.all(np.isfinite(self.knots)) \
                or not np.all(np.diff(self.knots) > 0):
            raise InputError(f"piecewise polynomial: knots of shape {self.knots.shape}; expected at least two "
                             "finite, increasing times [s]")
        shape = self.coefficients.shape
        if (self.coefficients.ndim != 3 or shape[0] != self.knots.size - 1 or 0 in shape
                or not np.all(np.isfinite(self.coefficients))):
            raise InputError(f"piecewise polynomial: coefficients of shape {shape}; expected finite "
                             f"({self.knots.size - 1} pieces, degree + 1, motors)")
        self.smooth = bool(smooth)

    @classmethod
    def fit(cls, function, start: float, stop: float, pieces: int, degree: int = 13,
            tolerance: float = 1e-12) -> PiecewisePolynomial:
        """A smooth function of time on [start, stop] as a piecewise polynomial: on each of ``pieces`` equal pieces
        its Chebyshev interpolant of ``degree`` (at the Chebyshev points of the first kind), in powers of the
        piece's local time. Checked against ``function`` at 4 (degree + 1) points of every piece: the largest
        difference is kept as ``fit_error`` (in the function's units) and must not exceed
        ``tolerance * max(1, max |function|)``. The fit is smooth (only ``start`` and ``stop`` are breakpoints).

        Args:
            function: f(t) for an array of times (T,) [s], returning (T, motors) (or (T,) for one value).
            start, stop: The interval [s] (start < stop).
            pieces: Number of equal pieces (>= 1).
            degree: Degree of each piece's polynomial (>= 1; default 13).
            tolerance: Largest difference allowed, relative to max(1, max abs(f)) (default 1e-12).

        Returns:
            The :class:`PiecewisePolynomial` (``smooth``), with ``fit_error``.

        Raises:
            InputError: A bad interval, number of pieces or degree, a non-finite value of f, or a fit worse than
                ``tolerance`` (naming the error reached: more pieces or a higher degree would be needed).
        """
        from numpy.polynomial import Chebyshev, Polynomial as Power

        if not (math.isfinite(start) and math.isfinite(stop) and start < stop) or int(pieces) < 1 \
                or int(degree) < 1:
            raise InputError(f"piecewise polynomial fit on [{start!r}, {stop!r}] s with {pieces!r} pieces of degree "
                             f"{degree!r}; expected start < stop (finite), pieces >= 1 and degree >= 1")

        def values(t):
            v = np.asarray(function(t), dtype=float)
            v = v.reshape(len(t), -1)
            if not np.all(np.isfinite(v)):
                raise InputError("piecewise polynomial fit: the function returned a non-finite value")
            return v

        knots = np.linspace(float(start), float(stop), int(pieces) + 1)
        h, n = knots[1] - knots[0], int(degree) + 1
        x = -np.cos(np.pi * (np.arange(n) + 0.5) / n)  # Chebyshev points of the first kind on [-1, 1], increasing
        nodes = 0.5 * h * (1.0 + x)
        # values at the nodes -> Chebyshev coefficients on [0, h] -> coefficients of powers of s
        to_power = np.zeros((n, n))
        for k in range(n):
            power = Chebyshev(np.eye(n)[k], domain=[0.0, h]).convert(kind=Power, domain=[0.0, h],
                                                                      window=[0.0, h]).coef
            to_power[:len(power), k] = power
        v = values((knots[:-1, None] + nodes).ravel()).reshape(int(pieces), n, -1)
        cheb = np.einsum("ij,pjm->pim", np.linalg.inv(np.polynomial.chebyshev.chebvander(x, n - 1)), v)
        coef = np.einsum("ij,pjm->pim", to_power, cheb)  # (in two steps: the Chebyshev coefficients decay)
        check = np.linspace(0.0, h, 4 * n)
        ref = values((knots[:-1, None] + check).ravel()).reshape(int(pieces), len(check), -1)
        got = _horner(np.moveaxis(coef[:, :, None, :], 1, 0), check[None, :, None])
        scale = max(1.0, float(np.abs(ref).max()))
        error = float(np.abs(got - ref).max())
        if error > tolerance * scale:
            raise InputError(f"piecewise polynomial fit: error {error:.3g} on [{start:g}, {stop:g}] s with {pieces} "
                             f"pieces of degree {degree}; expected at most {tolerance:g} x {scale:.3g} (more pieces "
                             "or a higher degree)")
        out = cls(knots, np.array(coef), smooth=True)
        out.fit_error = error
        return out

    def _terms(self):
        m, d, motors = self.coefficients.shape
        return [(PIECEWISE, self.coefficients.reshape(m * d, motors),
                 np.concatenate([[1.0 if self.smooth else 0.0], self.knots]))]

    def __repr__(self) -> str:
        m, d, motors = self.coefficients.shape
        return (f"PiecewisePolynomial({m} pieces of degree {d - 1}, {motors} values, on [{self.knots[0]:g}, "
                f"{self.knots[-1]:g}] s{', smooth' if self.smooth else ''})")


class Sum(TorqueProfile):
    """The sum of profiles (all with the same number of motors).

    Args:
        *parts: The :class:`TorqueProfile` terms (at least one).

    Raises:
        InputError: No part, a part that is not a profile, or different numbers of motors.
    """

    def __init__(self, *parts: TorqueProfile) -> None:
        if not parts or not all(isinstance(p, TorqueProfile) for p in parts):
            raise InputError("a sum of torque profiles needs at least one TorqueProfile")
        if len({p.motors for p in parts}) != 1:
            raise InputError(f"torque profiles for {sorted({p.motors for p in parts})} motors cannot be added")
        self.parts = parts

    def _terms(self):
        return [term for p in self.parts for term in p._terms()]

    def __repr__(self) -> str:
        return " + ".join(repr(p) for p in self.parts)


class Scaled(TorqueProfile):
    """A profile times a scalar (:meth:`TorqueProfile.scaled`).

    Args:
        part: The :class:`TorqueProfile` scaled.
        factor: The scale (dimensionless, finite).

    Raises:
        InputError: ``part`` is not a profile or ``factor`` is not finite.
    """

    def __init__(self, part: TorqueProfile, factor: float) -> None:
        if not isinstance(part, TorqueProfile):
            raise InputError("only a TorqueProfile can be scaled as a profile")
        if not math.isfinite(factor):
            raise InputError(f"torque scale {factor!r}; expected a finite number")
        self.part, self.factor = part, float(factor)

    def _terms(self):
        return [(kind, self.factor * coef, par) for kind, coef, par in self.part._terms()]

    def __repr__(self) -> str:
        return f"{self.factor:g} * ({self.part!r})"


def as_profile(torque, motors: int) -> TorqueProfile | None:
    """``torque`` as a profile for a robot with ``motors`` motors.

    Args:
        torque: ``None`` (no torque), a :class:`TorqueProfile`, or a Python callable ``tau(t, q, nu)``.
        motors: The robot's number of motors.

    Returns:
        Zero constants for ``None``, the profile itself (checked), ``None`` for a Python callable (meaning
        "Python engine only").

    Raises:
        InputError: A profile for another number of motors.
    """
    if torque is None:
        return Constant(np.zeros(motors))
    if isinstance(torque, TorqueProfile):
        if torque.motors != motors:
            raise InputError(f"torque profile for {torque.motors} motors; the robot has {motors}")
        return torque
    return None


__all__ = ["TorqueProfile", "Constant", "Sine", "Table", "Polynomial", "PiecewisePolynomial", "Sum", "Scaled", "as_profile"]

"""Terrain surfaces z = f(x, y) with gradient and Hessian.

A terrain gives the height :math:`f`, its gradient :math:`(f_x, f_y)` and Hessian, all in the world frame (m).
The rolling contact only uses these three, so any smooth surface can be added by subclassing :class:`Terrain`
or by wrapping callables in :class:`FunctionTerrain`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


class Terrain:
    """Base class: a height field :math:`z = f(x, y)` (world frame, metres)."""

    def height(self, x: float, y: float) -> float:
        """:math:`f(x, y)` [m].

        Args:
            x: World x of the point [m].
            y: World y of the point [m].

        Returns:
            The ground height [m].
        """
        raise NotImplementedError

    def gradient(self, x: float, y: float) -> np.ndarray:
        """:math:`(f_x, f_y)` [-].

        Args:
            x: World x of the point [m].
            y: World y of the point [m].

        Returns:
            The slopes (2,) along world x and y [-].
        """
        raise NotImplementedError

    def hessian(self, x: float, y: float) -> np.ndarray:
        """:math:`[[f_{xx}, f_{xy}], [f_{xy}, f_{yy}]]` [1/m].

        Args:
            x: World x of the point [m].
            y: World y of the point [m].

        Returns:
            The 2x2 matrix of second derivatives [1/m].
        """
        raise NotImplementedError

    third = None
    """Optional ``third(x, y)``: the third derivatives :math:`f_{ijk}` (2, 2, 2) [1/m^2], used by the dynamics
    derivatives (:mod:`robotdyn.constraints.row_derivatives`) on curved terrain; without it they take central
    differences of the Hessian (and say so)."""

    @property
    def is_flat(self) -> bool:
        """True when the normal is constant (a plane): the contact point then needs no iteration."""
        return False

    def normal(self, x: float, y: float) -> np.ndarray:
        """Upward unit normal :math:`n = (-f_x, -f_y, 1) / \\|(-f_x, -f_y, 1)\\|`.

        Args:
            x: World x of the point [m].
            y: World y of the point [m].

        Returns:
            The unit normal (3,) in world axes.
        """
        fx, fy = self.gradient(x, y)
        m = np.array([-fx, -fy, 1.0])
        return m / np.linalg.norm(m)

    def normal_derivative(self, x: float, y: float) -> np.ndarray:
        """:math:`\\partial n / \\partial p` (3x3, last column zero) at the ground point (x, y).

        Args:
            x: World x of the point [m].
            y: World y of the point [m].

        Returns:
            The 3x3 derivative of the unit normal with respect to the world point p = (x, y, z) [1/m].
        """
        fx, fy = self.gradient(x, y)
        h = self.hessian(x, y)
        m = np.array([-fx, -fy, 1.0])
        norm = np.linalg.norm(m)
        n = m / norm
        dm = np.zeros((3, 3))
        dm[0, :2] = -h[0]
        dm[1, :2] = -h[1]
        return (np.eye(3) - np.outer(n, n)) @ dm / norm

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class RampTerrain(Terrain):
    """An inclined plane :math:`z = h + s (x\\cos\\alpha + y\\sin\\alpha)` of slope ``s`` rising along heading
    alpha [rad], at height ``h`` [m] above the origin.

    Args:
        slope: s, the rise per metre along the heading [-] (tan of the inclination angle).
        heading: alpha [rad], the world direction (from x towards y) in which the ground rises.
        height: h [m], the height at the world origin.
    """

    def __init__(self, slope: float, heading: float = 0.0, height: float = 0.0) -> None:
        self.slope = float(slope)
        self.heading = float(heading)
        self.h = float(height)
        self._g = self.slope * np.array([np.cos(self.heading), np.sin(self.heading)])

    def height(self, x: float, y: float) -> float:
        return self.h + float(self._g[0] * x + self._g[1] * y)

    def gradient(self, x: float, y: float) -> np.ndarray:
        return self._g.copy()

    def hessian(self, x: float, y: float) -> np.ndarray:
        return np.zeros((2, 2))

    def third(self, x: float, y: float) -> np.ndarray:
        """Third derivatives :math:`f_{ijk}` (2, 2, 2) [1/m^2] of the height, zero on a plane.

        Args:
            x: World x of the point [m].
            y: World y of the point [m].

        Returns:
            The array (2, 2, 2), indices in the order (x, y) [1/m^2]: zeros.
        """
        return np.zeros((2, 2, 2))

    @property
    def is_flat(self) -> bool:
        return True

    def __repr__(self) -> str:
        return f"RampTerrain(slope={self.slope}, heading={self.heading}, height={self.h})"


class FlatTerrain(RampTerrain):
    """The horizontal plane :math:`z = h`.

    Args:
        height: h [m].
    """

    def __init__(self, height: float = 0.0) -> None:
        super().__init__(0.0, 0.0, height)

    def __repr__(self) -> str:
        return f"FlatTerrain(height={self.h})"


class BumpTerrain(Terrain):
    """A smooth step-like bump across x: :math:`z = \\frac{h}{2}(1 + \\tanh((x - x_0)/w))` (a smooth step of
    height ``h`` at ``x0`` with ramp width ``w``); set ``length`` to come back down after it (a plateau).

    Args:
        height: h [m] (negative: a step down).
        x0: World x [m] of the step's midpoint.
        width: w [m], the ramp's width scale (the tanh's length).
        length: Length [m] of the plateau, after which a second step comes back down (default ``None``: stay up).
    """

    def __init__(self, height: float, x0: float = 0.0, width: float = 0.1, length: float | None = None) -> None:
        self.h, self.x0, self.w = float(height), float(x0), float(width)
        self.length = None if length is None else float(length)

    def _step(self, x: float, x0: float) -> tuple[float, float, float]:
        t = np.tanh((x - x0) / self.w)
        s = 1.0 - t * t
        return 0.5 * self.h * (1 + t), 0.5 * self.h * s / self.w, -self.h * t * s / self.w**2

    def _step3(self, x: float, x0: float) -> float:
        """The step's third derivative :math:`-h(1 - t^2)(1 - 3t^2)/w^3`, :math:`t = \\tanh((x - x_0)/w)`."""
        t = np.tanh((x - x0) / self.w)
        return -self.h * (1.0 - t * t) * (1.0 - 3.0 * t * t) / self.w**3

    def third(self, x: float, y: float) -> np.ndarray:
        """Third derivatives :math:`f_{ijk}` (2, 2, 2) [1/m^2] of the height, non-zero only in
        :math:`f_{xxx}` (the step varies along x only).

        Args:
            x: World x of the point [m].
            y: World y of the point [m].

        Returns:
            The array (2, 2, 2), indices in the order (x, y) [1/m^2]: only ``[0, 0, 0]`` non-zero.
        """
        out = np.zeros((2, 2, 2))
        out[0, 0, 0] = self._step3(x, self.x0) - (0.0 if self.length is None else self._step3(x, self.x0 + self.length))
        return out

    def _parts(self, x: float) -> tuple[float, float, float]:
        f, fx, fxx = self._step(x, self.x0)
        if self.length is not None:
            g, gx, gxx = self._step(x, self.x0 + self.length)
            f, fx, fxx = f - g, fx - gx, fxx - gxx
        return f, fx, fxx

    def height(self, x: float, y: float) -> float:
        return float(self._parts(x)[0])

    def gradient(self, x: float, y: float) -> np.ndarray:
        return np.array([self._parts(x)[1], 0.0])

    def hessian(self, x: float, y: float) -> np.ndarray:
        return np.array([[self._parts(x)[2], 0.0], [0.0, 0.0]])

    def __repr__(self) -> str:
        return f"BumpTerrain(height={self.h}, x0={self.x0}, width={self.w}, length={self.length})"


class SineTerrain(Terrain):
    """:math:`z = A \\sin(k_x x + k_y y + \\varphi)` (e.g. Mardani's rough surface :math:`\\sin(0.5(x+y))/15`).

    Args:
        amplitude: A [m].
        kx: k_x, the wavenumber along world x [rad/m].
        ky: k_y, the wavenumber along world y [rad/m].
        phase: phi [rad].
    """

    def __init__(self, amplitude: float, kx: float, ky: float = 0.0, phase: float = 0.0) -> None:
        self.a, self.kx, self.ky, self.phase = float(amplitude), float(kx), float(ky), float(phase)

    def _arg(self, x: float, y: float) -> float:
        return self.kx * x + self.ky * y + self.phase

    def height(self, x: float, y: float) -> float:
        return self.a * float(np.sin(self._arg(x, y)))

    def gradient(self, x: float, y: float) -> np.ndarray:
        c = self.a * np.cos(self._arg(x, y))
        return np.array([c * self.kx, c * self.ky])

    def hessian(self, x: float, y: float) -> np.ndarray:
        s = -self.a * np.sin(self._arg(x, y))
        k = np.array([self.kx, self.ky])
        return s * np.outer(k, k)

    def third(self, x: float, y: float) -> np.ndarray:
        """Third derivatives :math:`f_{ijk}` (2, 2, 2) [1/m^2] of the height,
        :math:`-A\\cos(k_x x + k_y y + \\varphi)\\,k_i k_j k_k` with :math:`k = (k_x, k_y)`.

        Args:
            x: World x of the point [m].
            y: World y of the point [m].

        Returns:
            The array (2, 2, 2), indices in the order (x, y) [1/m^2].
        """
        k = np.array([self.kx, self.ky])
        return -self.a * np.cos(self._arg(x, y)) * np.einsum("i,j,k->ijk", k, k, k)

    def __repr__(self) -> str:
        return f"SineTerrain(amplitude={self.a}, kx={self.kx}, ky={self.ky}, phase={self.phase})"


class FunctionTerrain(Terrain):
    """A terrain from user callables ``f(x, y)``, ``grad(x, y)``, ``hess(x, y)``.

    Args:
        f: The height f(x, y) [m] of world x, y [m].
        grad: Its gradient (f_x, f_y) [-] as a 2-vector.
        hess: Its Hessian, a 2x2 matrix [1/m].
    """

    def __init__(
        self,
        f: Callable[[float, float], float],
        grad: Callable[[float, float], np.ndarray],
        hess: Callable[[float, float], np.ndarray],
    ) -> None:
        self._f, self._grad, self._hess = f, grad, hess

    def height(self, x: float, y: float) -> float:
        return float(self._f(x, y))

    def gradient(self, x: float, y: float) -> np.ndarray:
        return np.asarray(self._grad(x, y), dtype=float)

    def hessian(self, x: float, y: float) -> np.ndarray:
        return np.asarray(self._hess(x, y), dtype=float)

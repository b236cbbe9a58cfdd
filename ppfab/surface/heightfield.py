"""A surface as a height field ``z = f(x, y)`` over its plan frame, fitted by a smoothing bicubic spline.

The samples (frame coordinates, mm) are interpolated (piecewise cubic, C1: Clough–Tocher) onto a regular plan grid (points outside
their convex hull continue the samples' quadratic trend; they lie outside the trim region), then an
interpolating bicubic spline (:class:`scipy.interpolate.RectBivariateSpline`) passes through the grid:
heights and slopes come from it.  The second derivatives (the second fundamental form in the
frame, which set the net's directions) come from a second, least-squares bicubic spline of the same grid
with knots ``smoothing`` mm apart: a faceted mesh has its curvature in its edges, and a net of panels of a
given size cannot follow curvature that changes within a panel.  A least-squares spline reproduces a cubic
exactly, so a smooth surface keeps its curvature up to its edges.

Examples
--------
>>> import numpy as np
>>> x, y = np.meshgrid(np.linspace(0, 10, 30), np.linspace(0, 6, 20), indexing="ij")
>>> pts = np.stack([x.ravel(), y.ravel(), (0.02 * x**2 - 0.03 * y**2).ravel()], axis=1)
>>> hf = fit_height_field(pts, cell=0.25, smoothing=0.5)
>>> round(float(hf.fxx(5.0, 3.0)), 3), round(float(hf.fyy(5.0, 3.0)), 3), round(float(hf.fxy(5.0, 3.0)), 3) + 0.0
(0.04, -0.06, 0.0)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import (CloughTocher2DInterpolator, NdBSpline, NearestNDInterpolator, RectBivariateSpline,
                               make_lsq_spline)
from scipy.spatial import Delaunay, QhullError

from ..errors import GeometryError

MAX_GRID = 400
"""Most plan grid points per side of the fit (the cell grows beyond)."""


@dataclass(frozen=True)
class HeightField:
    """``z = f(x, y)`` in frame coordinates; ``x`` and ``y`` bound the plan box of the fit; ``curvature`` is
    the smoothed spline the second derivatives are taken from."""

    spline: RectBivariateSpline
    x: np.ndarray
    y: np.ndarray
    curvature: NdBSpline

    def _ev(self, x: np.ndarray, y: np.ndarray, dx: int, dy: int) -> np.ndarray:
        xa = np.clip(np.asarray(x, dtype=float), self.x[0], self.x[-1])
        ya = np.clip(np.asarray(y, dtype=float), self.y[0], self.y[-1])
        if dx + dy == 2:
            pts = np.stack(np.broadcast_arrays(xa, ya), axis=-1)
            return np.asarray(self.curvature(pts, nu=(dx, dy)))
        return np.asarray(self.spline.ev(xa, ya, dx=dx, dy=dy))

    def f(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Height at plan points (clamped to the box of the fit)."""
        return self._ev(x, y, 0, 0)

    def fx(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return self._ev(x, y, 1, 0)

    def fy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return self._ev(x, y, 0, 1)

    def fxx(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return self._ev(x, y, 2, 0)

    def fxy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return self._ev(x, y, 1, 1)

    def fyy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return self._ev(x, y, 0, 2)

    def inside_box(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Whether plan points lie in the box of the fit."""
        return (x >= self.x[0]) & (x <= self.x[-1]) & (y >= self.y[0]) & (y <= self.y[-1])


def fit_height_field(local: np.ndarray, cell: float, smoothing: float) -> HeightField:
    """Fit ``z = f(x, y)`` to frame-coordinate samples ``local (N, 3)``.

    Parameters
    ----------
    local : (N, 3) float — samples in the plan frame, mm
    cell : target plan grid cell of the fit, mm (grows so that no side has more than :data:`MAX_GRID` points)
    smoothing : knot spacing of the least-squares curvature spline, mm
    """
    p = np.asarray(local, dtype=float)
    lo, hi = p[:, :2].min(axis=0), p[:, :2].max(axis=0)
    size = hi - lo
    lo, hi = lo + 1e-9 * size, hi - 1e-9 * size         # strictly inside the samples' box (no NaN on its edges)
    if not np.all(size > 0):
        raise GeometryError("the surface has no extent in plan: it is not a height field over any plan "
                            "(vertical?) — give [surface] plane_normal so that it is one")
    cell = max(cell, float(size.max()) / (MAX_GRID - 1))
    nx, ny = (np.maximum(np.ceil(size / cell).astype(int) + 1, 6)).tolist()
    gx, gy = np.linspace(lo[0], hi[0], nx), np.linspace(lo[1], hi[1], ny)
    X, Y = np.meshgrid(gx, gy, indexing="ij")
    try:
        tri = Delaunay(p[:, :2], qhull_options="Qbb Qc Qz Q12")
        z = CloughTocher2DInterpolator(tri, p[:, 2])(X, Y)
    except QhullError:
        raise GeometryError("the surface samples lie on a line in plan: not a height field over this "
                            "plan — give [surface] plane_normal") from None
    far = ~np.isfinite(z)
    if far.any():                       # outside the samples: their quadratic trend, continued from the nearest
        trend = _quadratic(p)
        rest = NearestNDInterpolator(p[:, :2], p[:, 2] - trend(p[:, 0], p[:, 1]))
        z[far] = trend(X[far], Y[far]) + rest(X[far], Y[far])
    spline = RectBivariateSpline(gx, gy, z, kx=3, ky=3, s=0.0)
    return HeightField(spline, gx, gy, _lsq_spline(gx, gy, z, smoothing))


def _quadratic(p: np.ndarray):
    """The least-squares quadratic ``z(x, y)`` of points ``(N, 3)``, as a function."""
    c = p[:, :2].mean(axis=0)
    def basis(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        u, v = x - c[0], y - c[1]
        return np.stack([np.ones_like(u), u, v, u * u, u * v, v * v], axis=-1)
    coef = np.linalg.lstsq(basis(p[:, 0], p[:, 1]), p[:, 2], rcond=None)[0]
    return lambda x, y: basis(np.asarray(x, dtype=float), np.asarray(y, dtype=float)) @ coef


def _knots(g: np.ndarray, step: float) -> np.ndarray:
    """Clamped cubic knots over ``g`` with interior knots about ``step`` apart (at least 4 cells apart)."""
    step = max(step, 4.0 * float(g[1] - g[0]))
    inner = np.linspace(g[0], g[-1], max(2, int(round((g[-1] - g[0]) / step)) + 1))[1:-1]
    return np.concatenate([[g[0]] * 4, inner, [g[-1]] * 4])


def _lsq_spline(gx: np.ndarray, gy: np.ndarray, z: np.ndarray, step: float) -> NdBSpline:
    """The least-squares bicubic tensor spline of grid values ``z (nx, ny)`` (separable on a full grid)."""
    tx, ty = _knots(gx, step), _knots(gy, step)
    cx = make_lsq_spline(gx, z, tx, k=3, axis=0).c                  # (len(tx) - 4, ny)
    c = make_lsq_spline(gy, cx, ty, k=3, axis=1).c.T                # (len(tx) - 4, len(ty) - 4)
    return NdBSpline((tx, ty), c, 3)

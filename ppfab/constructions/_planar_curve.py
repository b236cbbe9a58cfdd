"""Smooth planar curves given as 2D points in a plane's own frame (shared by the profile-curve and
translational constructions).

A :class:`PlaneFrame` maps plane coordinates ``(s, t)`` to space,
``o + s e1 + t e2`` (``e1, e2`` orthonormal, normal ``N = e1 × e2``).  A
:class:`PlanarCurve` is a cubic B-spline through (``fit="interpolate"``,
chord-length parameter) or over (``fit="control"``, clamped uniform knots) the
user's 2D points, with the derivatives the constructions need: unit tangent
``T``, in-plane unit normal ``m = σ N × T`` and its derivative
``m' = σ N × T'`` with ``T' = (c'' − (c''·T) T) / |c'|``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline, make_interp_spline

from ..errors import DesignError


@dataclass(frozen=True)
class PlaneFrame:
    """An orthonormal frame of a plane: ``origin (3,)``, in-plane axes ``e1, e2 (3,)``."""

    origin: np.ndarray
    e1: np.ndarray
    e2: np.ndarray

    @property
    def normal(self) -> np.ndarray:
        return np.cross(self.e1, self.e2)

    @classmethod
    def from_axes(cls, origin, axes, key: str) -> "PlaneFrame":
        """Frame from an origin and two axes (Gram–Schmidt); parallel or zero axes raise ``DesignError(key)``."""
        o = np.asarray(origin, dtype=float)
        a = np.asarray(axes, dtype=float)
        if o.shape != (3,):
            raise DesignError(key, f"origin needs 3 numbers, got {o.shape}")
        if a.shape != (2, 3):
            raise DesignError(key, f"needs two axes of 3 numbers each, got shape {a.shape}")
        n1 = np.linalg.norm(a[0])
        if n1 == 0:
            raise DesignError(key, "the first axis is the zero vector")
        e1 = a[0] / n1
        rest = a[1] - (a[1] @ e1) * e1
        n2 = np.linalg.norm(rest)
        if n2 <= 1e-9 * max(np.linalg.norm(a[1]), 1e-300):
            raise DesignError(key, "the two axes are parallel: they do not span a plane")
        return cls(o, e1, rest / n2)

    def to_space(self, st: np.ndarray) -> np.ndarray:
        st = np.asarray(st, dtype=float)
        return self.origin + st[..., :1] * self.e1 + st[..., 1:2] * self.e2

    def vector_to_space(self, st: np.ndarray) -> np.ndarray:
        st = np.asarray(st, dtype=float)
        return st[..., :1] * self.e1 + st[..., 1:2] * self.e2


class PlanarCurve:
    """A 2D B-spline ``(s(t), t(t))`` placed in a :class:`PlaneFrame` (extrapolates beyond its domain)."""

    def __init__(self, spline: BSpline, frame: PlaneFrame, name: str):
        self.spline = spline
        self.frame = frame
        self.name = name
        k = spline.k
        self.domain = (float(spline.t[k]), float(spline.t[-k - 1]))
        self._d1 = spline.derivative(1)
        self._d2 = spline.derivative(2) if k >= 2 else None
        tt = np.linspace(*self.domain, 2001)
        seg = np.linalg.norm(np.diff(spline(tt), axis=0), axis=1)
        self._tt = tt
        self._arc = np.concatenate([[0.0], np.cumsum(seg)])

    @property
    def length(self) -> float:
        return float(self._arc[-1])

    @property
    def extent(self) -> float:
        """Diagonal of the bounding box of the curve over its domain (space units)."""
        return float(np.linalg.norm(np.ptp(self.point(self._tt), axis=0)))

    def param_at_length(self, s: np.ndarray) -> np.ndarray:
        """Curve parameters at arc lengths ``s`` from the start (within the domain)."""
        return np.interp(s, self._arc, self._tt)

    def points2d(self, t: np.ndarray) -> np.ndarray:
        return self.spline(np.asarray(t, dtype=float))

    def point(self, t: np.ndarray) -> np.ndarray:
        """``c(t)``, ``(k, 3)``."""
        return self.frame.to_space(self.spline(np.asarray(t, dtype=float)))

    def derivative(self, t: np.ndarray) -> np.ndarray:
        """``c'(t)``, ``(k, 3)``."""
        return self.frame.vector_to_space(self._d1(np.asarray(t, dtype=float)))

    def _second(self, t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if self._d2 is None:
            return np.zeros(t.shape + (3,))
        return self.frame.vector_to_space(self._d2(t))

    def speed(self, t: np.ndarray) -> np.ndarray:
        return np.linalg.norm(self._d1(np.asarray(t, dtype=float)), axis=-1)

    def curvature(self, t: np.ndarray) -> np.ndarray:
        """Signed curvature ``(s' t'' − t' s'') / |c'|³`` in the plane's orientation, ``(k,)``."""
        t = np.asarray(t, dtype=float)
        d1 = self._d1(t)
        d2 = self._d2(t) if self._d2 is not None else np.zeros_like(d1)
        sp = np.linalg.norm(d1, axis=-1)
        return (d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]) / np.where(sp == 0, np.inf, sp ** 3)

    def unit_normal(self, t: np.ndarray, sign: float = 1.0) -> np.ndarray:
        """In-plane unit normal ``m(t) = σ N × T``, ``(k, 3)``."""
        d1 = self.derivative(t)
        T = d1 / np.linalg.norm(d1, axis=-1, keepdims=True)
        return sign * np.cross(self.frame.normal, T)

    def unit_normal_derivative(self, t: np.ndarray, sign: float = 1.0) -> np.ndarray:
        """``m'(t) = σ N × T'`` with ``T' = (c'' − (c''·T) T) / |c'|``, ``(k, 3)``."""
        d1 = self.derivative(t)
        sp = np.linalg.norm(d1, axis=-1, keepdims=True)
        T = d1 / sp
        d2 = self._second(t)
        dT = (d2 - np.einsum("...i,...i->...", d2, T)[..., None] * T) / sp
        return sign * np.cross(self.frame.normal, dT)


def fit_planar_curve(points, frame: PlaneFrame, fit: str, key: str, name: str) -> PlanarCurve:
    """Cubic (or lower, for few points) B-spline through or over 2D points ``(k, 2)`` in ``frame``.

    ``fit="interpolate"``: through the points, chord-length parameter;
    ``fit="control"``: the points are the control polygon of a clamped uniform
    B-spline.  Bad point lists raise :class:`DesignError` under ``key``.
    """
    for k, q in enumerate(points):
        if np.ndim(q) != 1 or len(q) != 2:
            raise DesignError(f"{key}[{k}]", f"needs 2 numbers [s, t] (a point in the plane's own coordinates), "
                                             f"got {np.ndim(q) and len(q)}")
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise DesignError(key, f"needs a list of [s, t] pairs (2D points in the plane), got shape {p.shape}")
    if len(p) < 3:
        raise DesignError(key, f"needs at least 3 points to define a curved profile, got {len(p)}")
    if not np.all(np.isfinite(p)):
        raise DesignError(key, "points must be finite numbers")
    chord = np.linalg.norm(np.diff(p, axis=0), axis=1)
    size = float(np.linalg.norm(np.ptp(p, axis=0))) or 1.0
    if chord.min() <= 1e-9 * size:
        k = int(np.argmin(chord))
        raise DesignError(f"{key}[{k + 1}]", f"repeats point {k} (consecutive points {chord[k]:.3g} apart)")
    k = min(3, len(p) - 1)
    if fit == "interpolate":
        tau = np.concatenate([[0.0], np.cumsum(chord)])
        spline = make_interp_spline(tau, p, k=k)
    elif fit == "control":
        inner = np.linspace(0.0, 1.0, len(p) - k + 1)
        knots = np.concatenate([np.zeros(k), inner, np.ones(k)]) * float(chord.sum())
        spline = BSpline(knots, p, k, extrapolate=True)
    else:
        raise DesignError("fit", f"must be 'interpolate' or 'control', got {fit!r}")
    return PlanarCurve(spline, frame, name)

"""Smooth planar curves drawn by a designer, and their support functions (§4.1.2, eqs. 14–15).

:class:`PlanarCurve` is the one planar curve of ppfab: a 2D B-spline ``c(t)``, ``t ∈ [t0, t1]``, optionally
placed in space by a :class:`~ppfab.frame.Frame` (then :meth:`PlanarCurve.point` is ``frame.to3d(c(t))``).
A designer gives a planar curve as a list of points (interpolated by a cubic
spline, chord-length parametrised) or as the control points of a clamped
B-spline (:meth:`PlanarCurve.from_points`, :meth:`PlanarCurve.from_control_points`, :func:`fit_planar_curve`
for the profile constructions of §3.2.1).  A *convex* curve has exactly one tangent line for each normal
direction ``(cos φ, sin φ)``; written ``x cos φ + y sin φ + p(φ) = 0`` it defines the
support function ``p(φ)`` of eqs. (14), (15).  :class:`ConvexSection` evaluates
the normal angle ``φ(t)`` (continuous, strictly monotone) and ``p(φ(t)) = −c(t)·n(t)``
along the curve, orienting the normal so that it equals a prescribed *crest
direction* at the crest point, and rejects curves whose curvature changes
sign (or vanishes), naming where.

Points beyond the ends (the ghost faces of a mesh) are evaluated on the
spline's polynomial extrapolation and are checked for convexity too.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import BSpline, make_interp_spline
from scipy.optimize import brentq

from .errors import DesignError
from .frame import Frame


def _rot90(v: np.ndarray) -> np.ndarray:
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


@dataclass(frozen=True, eq=False)
class PlanarCurve:
    """A parametric curve ``c(t)`` in R², ``t ∈ [t0, t1]`` (a scipy B-spline that extrapolates beyond its
    ends), optionally placed in space in the plane of ``frame``.

    2D: ``curve(t) (k, 2)``, :meth:`derivative`, :meth:`curvature`, :meth:`arclength_table`.
    In space (``frame`` given): :meth:`point`, :meth:`tangent`, :meth:`unit_normal` (in-plane normal),
    :meth:`unit_normal_derivative`, all ``(k, 3)``.
    """

    spline: BSpline
    t0: float
    t1: float
    closed: bool = False
    name: str = "curve"
    frame: Frame | None = None

    @classmethod
    def from_points(cls, points: ArrayLike, closed: bool = False, name: str = "curve") -> "PlanarCurve":
        """Interpolating cubic spline through ``points (k, 2)``, chord-length parameter (periodic when closed)."""
        p = _as_points(points, name, 4 if not closed else 3)
        if closed and np.linalg.norm(p[0] - p[-1]) > 1e-12 * _size(p):
            p = np.vstack([p, p[:1]])
        step = np.linalg.norm(np.diff(p, axis=0), axis=1)
        if np.any(step <= 1e-12 * _size(p)):
            k = int(np.argmax(step <= 1e-12 * _size(p)))
            raise DesignError(name, f"points {k} and {k + 1} coincide")
        t = np.concatenate([[0.0], np.cumsum(step)])
        spline = make_interp_spline(t, p, k=3, bc_type="periodic" if closed else "not-a-knot")
        if closed:
            spline.extrapolate = "periodic"
        return cls(spline, 0.0, float(t[-1]), closed, name)

    @classmethod
    def from_control_points(cls, points: ArrayLike, degree: int = 3, closed: bool = False,
                            name: str = "curve") -> "PlanarCurve":
        """Clamped uniform B-spline with control points ``(k, 2)`` (periodic uniform when closed)."""
        p = _as_points(points, name, 2 if not closed else 3)
        k = int(min(degree, len(p) - 1))
        if closed:
            cp = np.vstack([p, p[:k]])
            knots = np.arange(len(cp) + k + 1, dtype=float)
            spline = BSpline(knots, cp, k, extrapolate="periodic")
            return cls(spline, float(knots[k]), float(knots[len(cp)]), True, name)
        inner = np.linspace(0.0, 1.0, len(p) - k + 1)
        knots = np.concatenate([np.zeros(k), inner, np.ones(k)])
        return cls(BSpline(knots, p, k, extrapolate=True), 0.0, 1.0, False, name)

    # -- in the plane ---------------------------------------------------------------------------------
    def __call__(self, t: ArrayLike) -> np.ndarray:
        """``c(t)``, ``(k, 2)``."""
        return self.spline(np.asarray(t, dtype=float))

    @cached_property
    def _derivatives(self) -> tuple[BSpline, BSpline | None]:
        k = self.spline.k
        return self.spline.derivative(1), (self.spline.derivative(2) if k >= 2 else None)

    def derivative(self, t: np.ndarray, order: int = 1) -> np.ndarray:
        """``c'(t)`` (``order = 1``) or ``c''(t)`` (``order = 2``), ``(k, 2)``."""
        t = np.asarray(t, dtype=float)
        if order > 2:
            return self.spline.derivative(order)(t)
        d = self._derivatives[order - 1]
        return d(t) if d is not None else np.zeros(t.shape + (2,))

    def speed(self, t: np.ndarray) -> np.ndarray:
        """``|c'(t)|``, ``(k,)``."""
        return np.linalg.norm(self.derivative(t), axis=-1)

    def curvature(self, t: np.ndarray) -> np.ndarray:
        """Signed curvature ``(c' × c'') / |c'|³``, ``(k,)`` (positive turning counter-clockwise)."""
        d1, d2 = self.derivative(t), self.derivative(t, 2)
        cr = d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]
        sp = np.linalg.norm(d1, axis=-1)
        return cr / np.where(sp == 0, np.inf, sp ** 3)

    def arclength_table(self, samples: int = 4001, extend: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Dense ``t`` and arclength ``s(t)`` (trapezoidal rule on the speed) with ``s(t0) = 0``, over
        ``[t0 − extend, t1 + extend]``."""
        t = np.linspace(self.t0 - extend, self.t1 + extend, samples)
        speed = np.linalg.norm(self.derivative(t), axis=-1)
        s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t))])
        s0 = np.interp(self.t0, t, s)
        return t, s - s0

    @cached_property
    def _samples(self) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """Dense samples of a curve found strictly convex, by their number (:func:`support_values`)."""
        return {}

    @cached_property
    def _chord_table(self) -> tuple[np.ndarray, np.ndarray]:
        """``t`` at 2001 samples of ``[t0, t1]`` and the length of the inscribed polyline up to each."""
        tt = np.linspace(self.t0, self.t1, 2001)
        seg = np.linalg.norm(np.diff(self(tt), axis=0), axis=1)
        return tt, np.concatenate([[0.0], np.cumsum(seg)])

    @property
    def length(self) -> float:
        """Length of the curve over ``[t0, t1]`` (inscribed polyline of 2000 chords)."""
        return float(self._chord_table[1][-1])

    def param_at_length(self, s: np.ndarray) -> np.ndarray:
        """Curve parameters at arc lengths ``s`` from ``c(t0)`` (within the domain)."""
        tt, arc = self._chord_table
        return np.interp(s, arc, tt)

    # -- in space -------------------------------------------------------------------------------------
    def _placed(self) -> Frame:
        if self.frame is None:
            raise ValueError(f"curve {self.name!r} has no frame: it lies in no plane of space")
        return self.frame

    @property
    def extent(self) -> float:
        """Diagonal of the bounding box of the curve over ``[t0, t1]`` (space units)."""
        return float(np.linalg.norm(np.ptp(self.point(self._chord_table[0]), axis=0)))

    def point(self, t: np.ndarray) -> np.ndarray:
        """``c(t)`` in space, ``(k, 3)``."""
        return self._placed().to3d(self(t))

    def tangent(self, t: np.ndarray) -> np.ndarray:
        """``c'(t)`` in space, ``(k, 3)``."""
        return self._placed().vec3d(self.derivative(t))

    def unit_normal(self, t: np.ndarray, sign: float = 1.0) -> np.ndarray:
        """In-plane unit normal ``m(t) = σ N × T`` in space, ``(k, 3)`` (``N`` the frame's normal)."""
        d1 = self.tangent(t)
        T = d1 / np.linalg.norm(d1, axis=-1, keepdims=True)
        return sign * np.cross(self._placed().normal, T)

    def unit_normal_derivative(self, t: np.ndarray, sign: float = 1.0) -> np.ndarray:
        """``m'(t) = σ N × T'`` with ``T' = (c'' − (c''·T) T) / |c'|``, ``(k, 3)``."""
        d1 = self.tangent(t)
        sp = np.linalg.norm(d1, axis=-1, keepdims=True)
        T = d1 / sp
        d2 = self._placed().vec3d(self.derivative(t, 2))
        dT = (d2 - np.einsum("...i,...i->...", d2, T)[..., None] * T) / sp
        return sign * np.cross(self._placed().normal, dT)


def fit_planar_curve(points: Sequence[Sequence[float]], frame: Frame, fit: str, key: str, name: str) -> PlanarCurve:
    """Cubic (or lower, for few points) B-spline through or over 2D points ``(k, 2)`` placed in ``frame``.

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
    return PlanarCurve(spline, float(spline.t[k]), float(spline.t[-k - 1]), False, name, frame)


def _size(p: np.ndarray) -> float:
    return float(max(np.ptp(p, axis=0).max(), 1e-300))


def _as_points(points, name: str, minimum: int) -> np.ndarray:
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise DesignError(name, f"needs a list of [x, y] points, got shape {p.shape}")
    if len(p) < minimum:
        raise DesignError(name, f"needs at least {minimum} points, got {len(p)}")
    if not np.all(np.isfinite(p)):
        raise DesignError(name, "contains NaN or inf")
    return p


@dataclass(frozen=True)
class ConvexSection:
    """A strictly convex planar section with its normal angle and support function (eqs. 14–15).

    The unit normal is ``n(t) = σ · rot90(c'(t)/|c'(t)|)``; ``σ`` is chosen so that
    ``n = (cos φ*, sin φ*)`` at the crest ``t*``, and the angle ``φ(t)`` is continuous
    with ``φ(t*) = φ*``.
    """

    curve: PlanarCurve
    sigma: float
    crest_t: float
    crest_angle: float
    t_table: np.ndarray
    phi_table: np.ndarray

    @classmethod
    def prepare(cls, curve: PlanarCurve, crest_angle: float, margin: float = 0.0,
                max_turn: float | None = None) -> "ConvexSection":
        """Check convexity on ``[t0 − margin, t1 + margin]`` and find the crest where the normal is ``φ*``.

        Raises :class:`DesignError` (key = the curve's name) when the curvature
        changes sign or vanishes, when no point of the curve has the crest
        normal, or when the normal turns by ``max_turn`` or more from it.
        """
        name = curve.name
        t = np.linspace(curve.t0 - margin, curve.t1 + margin, 4001)
        kappa = curve.curvature(t)
        pts = curve(t)
        scale = _size(pts)
        ks = np.sign(np.median(kappa))
        weak = ks * kappa <= 1e-9 / scale
        if ks == 0 or np.any(weak):
            k = int(np.argmax(weak)) if ks != 0 else 0
            where = "beyond its ends (on the extension needed for the boundary faces)" \
                if not curve.t0 <= t[k] <= curve.t1 else f"near ({pts[k, 0]:.6g}, {pts[k, 1]:.6g})"
            raise DesignError(name, f"is not strictly convex: its curvature {kappa[k]:.3g} changes sign or vanishes "
                                    f"{where}; a principal section must be convex so that each normal direction "
                                    f"has one tangent (support function, §4.1.2)")
        star = np.array([np.cos(crest_angle), np.sin(crest_angle)])
        tin = np.linspace(curve.t0, curve.t1, 4001)
        tangent = curve.derivative(tin)
        tangent = tangent / np.linalg.norm(tangent, axis=-1, keepdims=True)
        found = None
        for sigma in (-ks, ks):                       # outward (convex side) normal first
            n = sigma * _rot90(tangent)
            cross = star[0] * n[:, 1] - star[1] * n[:, 0]
            dot = n @ star
            hit = np.flatnonzero((np.sign(cross[:-1]) != np.sign(cross[1:])) & (dot[:-1] > 0))
            exact = np.flatnonzero((cross == 0) & (dot > 0))
            if len(exact):
                found = (sigma, float(tin[exact[0]]))
                break
            if len(hit):
                k = int(hit[0])

                def f(x, sigma=sigma):
                    d = curve.derivative(np.array([x]))[0]
                    nn = sigma * _rot90(d)
                    return star[0] * nn[1] - star[1] * nn[0]
                found = (sigma, float(brentq(f, tin[k], tin[k + 1], xtol=1e-14 * max(1.0, abs(tin[k])))))
                break
        if found is None:
            raise DesignError(name, f"has no point where its normal is the crest direction "
                                    f"({star[0]:.3g}, {star[1]:.3g}) in its own plane: the two principal sections "
                                    f"must cross where both are horizontal (§4.1.2)")
        sigma, tc = found
        n = sigma * _rot90(curve.derivative(t))
        rel = np.unwrap(np.arctan2(star[0] * n[:, 1] - star[1] * n[:, 0], n @ star))
        rel -= 2 * np.pi * np.round(np.interp(tc, t, rel) / (2 * np.pi))
        sec = cls(curve, float(sigma), tc, float(crest_angle), t, crest_angle + rel)
        if max_turn is not None:
            turn = np.abs(rel).max()
            if turn >= max_turn:
                raise DesignError(name, f"turns its normal by {np.degrees(turn):.2f}° from the crest direction "
                                        f"(including the extension for the boundary faces); at most "
                                        f"{np.degrees(max_turn):.2f}° are possible here")
        return sec

    def normal(self, t: np.ndarray) -> np.ndarray:
        d = self.curve.derivative(t)
        return self.sigma * _rot90(d / np.linalg.norm(d, axis=-1, keepdims=True))

    def angle(self, t: np.ndarray) -> np.ndarray:
        """Continuous normal angle ``φ(t)`` (exact, on the branch of the dense table)."""
        n = self.normal(t)
        raw = np.arctan2(n[..., 1], n[..., 0])
        approx = np.interp(t, self.t_table, self.phi_table)
        return raw + 2 * np.pi * np.round((approx - raw) / (2 * np.pi))

    def support(self, t: np.ndarray) -> np.ndarray:
        """``p(φ(t)) = −c(t)·n(t)``: the tangent line is ``n·x + p = 0`` (eqs. 14, 15)."""
        return -np.einsum("...i,...i->...", self.curve(t), self.normal(t))

    @property
    def crest_point(self) -> np.ndarray:
        return self.curve(np.array([self.crest_t]))[0]

    def params_at_angles(self, phi: np.ndarray) -> np.ndarray:
        """Curve parameters where the normal angle is ``phi`` (inverse of the monotone table)."""
        order = np.argsort(self.phi_table)
        return np.interp(phi, self.phi_table[order], self.t_table[order])


def weak_curvature(curve: PlanarCurve, t: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """``(k,)`` bool at the parameters ``t`` (points ``pts``): the curvature vanishes there (relative to the
    curve's size) or has the sign opposite to most of the curve — an inflection or a straight piece."""
    kappa = curve.curvature(t)
    ks = np.sign(np.median(kappa))
    return ks * kappa <= 1e-9 / _size(pts)


def _convex_samples(curve: PlanarCurve, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """``t`` at ``samples`` points of ``[t0, t1]`` and ``c(t) (samples, 2)`` of a curve checked to be strictly
    convex there (kept on the curve: a construction asks for support values of one curve more than once)."""
    cache = curve._samples
    if samples not in cache:
        t = np.linspace(curve.t0, curve.t1, samples)
        pts = curve(t)
        weak = weak_curvature(curve, t, pts)
        if np.any(weak):
            k = int(np.argmax(weak))
            raise DesignError(curve.name, f"is not strictly convex: its curvature changes sign or vanishes near "
                                          f"({pts[k, 0]:.6g}, {pts[k, 1]:.6g}); the profile must be convex "
                                          f"(Remark 4.2: inflections would reverse the profile's direction)")
        cache[samples] = (t, pts)
    return cache[samples]


def support_values(curve: PlanarCurve, directions: np.ndarray, samples: int = 20001
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Support function ``h(ω) = max_t c(t)·ω`` of a convex curve for unit directions ``(k, 2)``.

    The maximum over a dense sample is polished by Newton steps on
    ``c'(t)·ω = 0``.  Returns the values ``(k,)`` and the curve parameters ``(k,)``
    where they are attained.  Raises :class:`DesignError` when the curve is not
    strictly convex, or (open curves) when the maximum for a direction lies at an
    end point: the curve does not have a tangent with that normal.
    """
    w = np.asarray(directions, dtype=float)
    t, pts = _convex_samples(curve, samples)
    proj = w @ pts.T                                    # (k, samples)
    best = np.argmax(proj, axis=1)
    if not curve.closed:
        ends = (best == 0) | (best == samples - 1)
        if np.any(ends):
            j = int(np.argmax(ends))
            ang = np.degrees(np.arctan2(w[j, 1], w[j, 0]))
            raise DesignError(curve.name, f"has no tangent with outward normal direction {ang:.2f}° (needed by face "
                                          f"column {j}, counting the ghost column beyond the boundary): extend the "
                                          f"profile curve")
    tb = t[best]
    lo, hi = (curve.t0, curve.t1) if not curve.closed else (-np.inf, np.inf)
    for _ in range(8):
        d1 = np.einsum("ki,ki->k", curve.derivative(tb), w)
        d2 = np.einsum("ki,ki->k", curve.derivative(tb, 2), w)
        step = np.where(d2 < 0, d1 / np.where(d2 == 0, -1.0, d2), 0.0)
        tb = np.clip(tb - step, lo, hi)
    return np.einsum("ki,ki->k", curve(tb), w), tb

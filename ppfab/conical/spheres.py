"""Families of oriented spheres and their discrete channel surfaces (paper §4.2.3, Steps 1–2).

Step 1: control spheres ``(x, y, z, r)`` are the control polygon of a clamped
B-spline curve ``Z(t)`` in R^4 (eq. 1).  It is sampled uniformly in the
tangential (Minkowski) distance of eq. (2): consecutive samples have equal
``d(Z_j, Z_{j+1})`` (starting from equal arclength ``∫ √<<Z', Z'>> dt``); this needs
``Z'`` spacelike everywhere (consecutive spheres in spacelike position: a common
oriented tangent cone exists, no sphere lies inside the next).

Step 2: the cone ``C_j`` touches ``Z_j`` and ``Z_{j+1}``; consecutive cones meet in
the plane ``W_j`` of eq. (16): the points ``(x, 0)`` with ``<<X − Z_j, H_j>> = 0``,
``H_j = E_j + E_{j+1}``, ``E_j = (Z_j − Z_{j−1}) / d(Z_j, Z_{j−1})``.  At the ends the
one-sided ``H_0 = E_1``, ``H_N = E_N`` give the planes of the characteristic circles
(:func:`bisector_normals`); :func:`bisector_normals_extended` uses ghost spheres
on the spline's extension instead, so that the end planes are bisectors too.
The Minkowski reflection ``σ_j`` in ``H_j`` through ``Z_j`` fixes ``W_j`` point by point and
maps cone ``C_{j−1}`` onto ``C_j`` (Remark 4.4).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import BSpline

from ppfab import planes as pl
from ppfab.errors import DesignError, GeometryError
from ppfab.transforms.laguerre import LaguerreMap


def check_spacelike_pairs(spheres: np.ndarray, key: str = "spheres") -> None:
    """Raise :class:`DesignError` naming the first consecutive pair of spheres not in spacelike position.

    ``d²(X_k, X_{k+1}) = |c_{k+1} − c_k|² − (r_{k+1} − r_k)² > 0`` is required (eq. 2).
    """
    X = np.asarray(spheres, dtype=float)
    if X.ndim != 2 or X.shape[1] != 4:
        raise DesignError(key, f"needs a list of [x, y, z, r] spheres, got shape {X.shape}")
    if not np.all(np.isfinite(X)):
        raise DesignError(key, "contains NaN or inf")
    diff = np.diff(X, axis=0)
    dc = np.linalg.norm(diff[:, :3], axis=1)
    dr = np.abs(diff[:, 3])
    size = max(float(np.ptp(X[:, :3], axis=0).max()), float(np.abs(X[:, 3]).max()), 1e-300)
    bad = dc - dr <= 1e-9 * size
    if np.any(bad):
        k = int(np.argmax(bad))
        what = "one lies inside the other" if dr[k] > dc[k] else "they touch (oriented contact)"
        raise DesignError(f"{key}[{k}]", f"spheres {k} and {k + 1} are not in spacelike position: "
                                         f"|Δr| = {dr[k]:.6g} ≥ |Δcenter| = {dc[k]:.6g} ({what}); "
                                         f"no common tangent cone exists")


class SphereSpline:
    """A clamped uniform B-spline curve ``Z(t)``, ``t ∈ [0, 1]``, of oriented spheres (Step 1).

    Parameters
    ----------
    control : (k, 4) float — control spheres ``(x, y, z, r)``, ``k ≥ 2``
    degree : B-spline degree (reduced to ``k − 1`` for short polygons)
    """

    def __init__(self, control: np.ndarray, degree: int = 3):
        X = np.asarray(control, dtype=float)
        check_spacelike_pairs(X)
        if len(X) < 2:
            raise DesignError("spheres", f"needs at least 2 control spheres, got {len(X)}")
        self.control = X
        self.degree = k = int(max(1, min(degree, len(X) - 1)))
        inner = np.linspace(0.0, 1.0, len(X) - k + 1)
        self.knots = np.concatenate([np.zeros(k), inner, np.ones(k)])
        self.spline = BSpline(self.knots, X, k, extrapolate=True)
        self._d1 = self.spline.derivative(1)

    def __call__(self, t: np.ndarray) -> np.ndarray:
        return self.spline(np.asarray(t, dtype=float))

    def derivative(self, t: np.ndarray) -> np.ndarray:
        return self._d1(np.asarray(t, dtype=float))

    def span_controls(self, t: float) -> tuple[int, int]:
        """Indices of the first and last control sphere influencing ``Z(t)``."""
        k = self.degree
        i = int(np.clip(np.searchsorted(self.knots, t, side="right") - 1, k, len(self.control) - 1))
        return i - k, i

    def speed_squared(self, t: np.ndarray) -> np.ndarray:
        """``<<Z'(t), Z'(t)>>`` (positive where the family is spacelike)."""
        d = self.derivative(t)
        return pl.minkowski_inner(d, d)

    def arclength_table(self, samples: int = 8001) -> tuple[np.ndarray, np.ndarray]:
        """Dense ``t`` and tangential arclength ``s(t)`` (Simpson on a uniform grid).

        Raises :class:`GeometryError` where ``Z'`` is not spacelike, naming the
        parameter and the control spheres that shape it there.
        """
        n = samples if samples % 2 == 1 else samples + 1
        t = np.linspace(0.0, 1.0, n)
        q = self.speed_squared(t)
        scale = float(np.abs(np.diff(self.control, axis=0)).max()) ** 2
        bad = q <= 1e-12 * scale
        if np.any(bad):
            k = int(np.argmax(bad))
            i0, i1 = self.span_controls(float(t[k]))
            raise GeometryError(f"the sphere family is not spacelike at t = {t[k]:.4f} (<<Z', Z'>> = {q[k]:.3g}): "
                                f"adjust control spheres {i0}..{i1} (radii change faster than centres move)",
                                element=f"spheres[{i0}:{i1 + 1}]", value=float(q[k]))
        speed = np.sqrt(q)
        h = t[1] - t[0]
        f0, f1, f2 = speed[:-2:2], speed[1:-1:2], speed[2::2]
        s_even = np.concatenate([[0.0], np.cumsum((f0 + 4 * f1 + f2) * h / 3.0)])
        s = np.empty(n)
        s[0::2] = s_even
        s[1::2] = s_even[:-1] + (5 * f0 + 8 * f1 - f2) * h / 12.0   # quadratic rule on the first half
        return t, s

    def sample_uniform(self, count: int, tol: float = 1e-12, maxiter: int = 100) -> tuple[np.ndarray, np.ndarray]:
        """``count`` spheres ``Z_0 … Z_{count−1}`` at equal tangential distances ``d(Z_j, Z_{j+1})``, and their ``t``.

        Starts from equal tangential arclength and equalises the chords by a fixed
        point iteration (cumulative chord lengths redistributed uniformly), so the
        Minkowski distances of consecutive spheres are equal as Remark 4.4 assumes.
        """
        if count < 2:
            raise GeometryError(f"need at least 2 spheres, got {count}")
        t, s = self.arclength_table()
        tk = np.interp(np.linspace(0.0, s[-1], count), s, t)
        for _ in range(3):                                         # Newton polish of the arclength
            sk = np.interp(tk, t, s)
            tk = np.clip(tk - (sk - np.linspace(0.0, s[-1], count)) / np.sqrt(self.speed_squared(tk)), 0.0, 1.0)
        tk[0], tk[-1] = 0.0, 1.0
        for _ in range(maxiter):
            c = tangential_distances(self(tk))
            C = np.concatenate([[0.0], np.cumsum(c)])
            if np.ptp(c) <= tol * c.mean():
                break
            tk = np.interp(np.linspace(0.0, C[-1], count), C, tk)
            tk[0], tk[-1] = 0.0, 1.0
        return self(tk), tk


def tangential_distances(Z: np.ndarray) -> np.ndarray:
    """``d(Z_j, Z_{j+1})`` of consecutive spheres ``(N+1, 4)`` → ``(N,)``; raises where not spacelike."""
    Z = np.asarray(Z, dtype=float)
    d2 = pl.tangential_distance_squared(Z[1:], Z[:-1])
    if np.any(d2 <= 0):
        k = int(np.argmax(d2 <= 0))
        raise GeometryError(f"sampled spheres {k} and {k + 1} are not in spacelike position (d² = {d2[k]:.3g})",
                            element=f"sphere {k}", value=float(d2[k]))
    return np.sqrt(d2)


def bisector_normals(Z: np.ndarray) -> np.ndarray:
    """``H_j`` of eq. (16) for spheres ``(N+1, 4)``: ``E_j + E_{j+1}`` inside, ``E_1``, ``E_N`` at the ends, ``(N+1, 4)``."""
    Z = np.asarray(Z, dtype=float)
    E = np.diff(Z, axis=0) / tangential_distances(Z)[:, None]    # E_1 .. E_N (row k is E_{k+1})
    return np.concatenate([E[:1], E[:-1] + E[1:], E[-1:]], axis=0)


def bisector_normals_extended(spline: "SphereSpline", t: np.ndarray) -> np.ndarray:
    """``H_0 … H_N`` of eq. (16) for the spheres ``Z(t_0) … Z(t_N)``, two-sided at the ends too.

    A ghost sphere beyond each end is taken from the B-spline's polynomial
    extension (at ``−t_1`` and ``2 − t_{N−1}``), so the end planes ``W_0``, ``W_N`` are
    bisectors like the others and the reflections ``σ_0``, ``σ_N`` carry the end
    cones to genuine ghost cones (every boundary vertex keeps four distinct faces).
    """
    t = np.asarray(t, dtype=float)
    Z = spline(np.concatenate([[-t[1]], t, [2.0 - t[-2]]]))
    return bisector_normals(Z)[1:-1]


def w_planes(Z: np.ndarray, H: np.ndarray | None = None) -> np.ndarray:
    """Unit planes ``W_j`` (eq. 16): points ``x`` with ``<<(x, 0) − Z_j, H_j>> = 0``, ``(N+1, 4)``.

    ``(x − c_j)·h + r_j h_4 = 0`` with ``H_j = (h, h_4)``.
    """
    Z = np.asarray(Z, dtype=float)
    H = bisector_normals(Z) if H is None else np.asarray(H, dtype=float)
    h = H[:, :3]
    length = np.linalg.norm(h, axis=1)
    if np.any(length <= 1e-12 * np.abs(H).max(axis=1)):
        k = int(np.argmax(length <= 1e-12 * np.abs(H).max(axis=1)))
        raise GeometryError(f"the plane W_{k} is undefined: the sphere family turns back on itself at sphere {k}",
                            element=f"W_{k}")
    P = np.concatenate([h, (-np.einsum("ji,ji->j", h, Z[:, :3]) + Z[:, 3] * H[:, 3])[:, None]], axis=1)
    return P / length[:, None]


def reflections(Z: np.ndarray, H: np.ndarray | None = None) -> list[LaguerreMap]:
    """The Minkowski reflections ``σ_j`` (in ``H_j`` through ``Z_j``) of Remark 4.4, one per sphere."""
    Z = np.asarray(Z, dtype=float)
    H = bisector_normals(Z) if H is None else H
    return [LaguerreMap.reflection(H[j], Z[j]) for j in range(len(Z))]

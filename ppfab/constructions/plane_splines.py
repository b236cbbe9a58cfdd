"""PP meshes from plane splines: quadratic Bézier curves in the space of weighted planes (§3.2.2, Fig. 11).

The dual surface ``f(u, v) = g(u) + h(v) − c`` (eq. 8) is made of two
tangent-continuous curves in R^4, each a chain of quadratic Bézier segments
(corrected formula, ``reference/README.md``)

    g⁽ⁱ⁾(u) = (1−u)² g_i + 2u(1−u) g_{i,i+1} + u² g_{i+1},   0 ≤ u ≤ 1.

The designer does not handle 4-vectors but planes: knot planes ``γ_i``, inner
control planes ``γ_{i,i+1}`` and tangent planes ``τ_i`` (the support planes of
the mesh at the knots, since ``g'`` is the support plane of the v-lines).  At
every knot the planes ``γ_{i−1,i}, γ_i, γ_{i,i+1}, τ_i`` must share one line
(the side condition; at the end knots ``γ_0, γ_01, τ_0``).  From unit plane
coordinates ``ḡ`` and ``t̄`` the control points follow by the recursive
re-weighting

    g_0 = ḡ_0,   g_i + μ_i t̄_i = λ_{i,i+1} ḡ_{i,i+1} =: g_{i,i+1},   g_{i,i+1} + ν_i t̄_{i+1} = λ_{i+1} ḡ_{i+1} =: g_{i+1},

so ``g'`` at both ends of a segment is a multiple of the tangent plane there.
Each step is a 4×2 linear system; it is consistent exactly when the side
condition holds.

Remark 3.3: the segments meet with a cusp at knot ``i`` when the order
``g_{i−1,i}, g_i, g_{i,i+1}`` along their common line is reversed, i.e. when
``ν_{i−1}`` and ``μ_i`` have opposite signs; this is reported as a
:class:`CuspWarning` naming the knot.

Keeping the side condition: with ``side_condition="project"`` the inner
planes ``γ_{i−1,i}, γ_{i,i+1}`` fix the line of knot ``i`` (at the ends
``γ_0 ∩ γ_01``) and ``γ_i`` and ``τ_i`` are replaced by the planes through that
line closest in normal direction (least-squares projection onto the
condition).  A missing ``τ_i`` defaults to the plane through the knot line
orthogonal to ``γ_i`` (support planes orthogonal to the panels, §2.3.2).
``side_condition="strict"`` instead rejects arrangements violating it by more
than ``tolerance``.
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass, replace

import numpy as np

from .. import planes as pl
from ..errors import DesignError, GeometryError
from ..faceimage import pp_from_curves
from ..mesh import QuadGrid
from ..schema import param
from .registry import construction

log = logging.getLogger("ppfab")


class CuspWarning(UserWarning):
    """A plane spline has a cusp at a knot (Remark 3.3)."""


def plane_from_entry(entry, key: str) -> np.ndarray:
    """A design-file plane: ``[nx, ny, nz, d]`` (``n·x + d = 0``) or ``[px, py, pz, nx, ny, nz]`` (point,
    normal); returned as a unit plane ``(4,)``.

    Examples
    --------
    >>> plane_from_entry([0, 0, 2, -4], "u_planes[0]")
    array([ 0.,  0.,  1., -2.])
    >>> plane_from_entry([1, 2, 3, 0, 0, 5], "u_planes[0]")        # through (1, 2, 3), normal z
    array([ 0.,  0.,  1., -3.])
    """
    e = np.asarray(entry, dtype=float)
    if e.shape == (4,):
        n, d = e[:3], e[3]
    elif e.shape == (6,):
        n = e[3:]
        d = -float(n @ e[:3])
    else:
        raise DesignError(key, f"a plane needs 4 numbers [nx, ny, nz, d] or 6 numbers [px, py, pz, nx, ny, nz], "
                               f"got {e.size}")
    length = float(np.linalg.norm(n))
    if not np.all(np.isfinite(e)) or length == 0:
        raise DesignError(key, "degenerate plane: its normal vector is zero")
    return np.concatenate([n, [d]]) / length


def knot_line(a: np.ndarray, b: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Line ``a ∩ b`` of two unit planes as (point nearest the origin, unit direction)."""
    d = np.cross(a[:3], b[:3])
    s = float(np.linalg.norm(d))
    if s <= 1e-9:
        raise GeometryError(f"{what}: the planes are parallel ({np.degrees(np.arcsin(min(s, 1.0))):.3g}°), "
                            f"they have no common line", element=what, value=s)
    d = d / s
    A = np.stack([a[:3], b[:3], d])
    p = np.linalg.solve(A, -np.array([a[3], b[3], 0.0]))
    return p, d


def project_to_pencil(plane: np.ndarray, point: np.ndarray, direction: np.ndarray, what: str) -> np.ndarray:
    """The unit plane through the line ``(point, direction)`` closest in normal to ``plane`` (orientation kept)."""
    n = plane[:3] - (plane[:3] @ direction) * direction
    s = float(np.linalg.norm(n))
    if s <= 1e-6:
        raise GeometryError(f"{what} is perpendicular to its knot line and cannot be turned into a plane through it",
                            element=what)
    n = n / s
    return np.concatenate([n, [-(n @ point)]])


def line_distance(plane: np.ndarray, point: np.ndarray, direction: np.ndarray, reach: float) -> float:
    """Largest distance from ``plane`` of the line's points within ``reach`` of ``point``."""
    d0 = plane[:3] @ point + plane[3]
    return abs(d0) + reach * abs(plane[:3] @ direction)


@dataclass
class PlaneSpline:
    """A tangent-continuous chain of quadratic Bézier segments in R^4.

    ``knots (K+1, 4)`` = ``g_i``, ``inner (K, 4)`` = ``g_{i,i+1}``; ``u ∈ [0, K]``,
    segment ``i`` on ``[i, i+1]`` (extrapolated beyond).  ``mu (K,)``,
    ``nu (K,)``: ``g_{i,i+1} − g_i = μ_i t̄_i``, ``g_{i+1} − g_{i,i+1} = ν_i t̄_{i+1}``;
    ``cusps``: interior knots where ``ν_{i−1} μ_i < 0`` (Remark 3.3).
    """

    knots: np.ndarray
    inner: np.ndarray
    tangents: np.ndarray
    mu: np.ndarray
    nu: np.ndarray
    cusps: list[int]
    name: str = "g"

    @property
    def segments(self) -> int:
        return len(self.inner)

    def _locate(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = np.asarray(u, dtype=float)
        seg = np.clip(np.floor(u), 0, self.segments - 1).astype(int)
        return seg, u - seg

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """``g(u)``, ``(k, 4)``."""
        seg, t = self._locate(u)
        t = t[..., None]
        return (1 - t) ** 2 * self.knots[seg] + 2 * t * (1 - t) * self.inner[seg] + t ** 2 * self.knots[seg + 1]

    def derivative(self, u: np.ndarray) -> np.ndarray:
        """``g'(u) = 2(1−u)(g_{i,i+1} − g_i) + 2u(g_{i+1} − g_{i,i+1})``, ``(k, 4)``."""
        seg, t = self._locate(u)
        t = t[..., None]
        return 2 * (1 - t) * (self.inner[seg] - self.knots[seg]) + 2 * t * (self.knots[seg + 1] - self.inner[seg])


def _knot_planes(i: int, K: int) -> str:
    """Names of the planes that must share the line of knot ``i`` (of ``K`` segments)."""
    names = ([f"gamma_{i - 1}{i}"] if i > 0 else []) + [f"gamma_{i}"] + ([f"gamma_{i}{i + 1}"] if i < K else [])
    return ", ".join(names + [f"tau_{i}"])


def _solve_pencil(a: np.ndarray, t: np.ndarray, b: np.ndarray, what: str) -> tuple[float, float]:
    """``a + μ t = λ b`` in least squares; returns ``(μ, λ)``."""
    A = np.stack([t, -b], axis=1)
    sol, *_ = np.linalg.lstsq(A, -a, rcond=None)
    sv = np.linalg.svd(A, compute_uv=False)
    if sv[-1] <= 1e-9 * sv[0]:
        raise GeometryError(f"{what}: the tangent plane coincides with the control plane, the re-weighting is "
                            f"undefined", element=what)
    return float(sol[0]), float(sol[1])


def plane_spline(control, tangents=None, side_condition: str = "project", tolerance: float = 1e-6,
                 g0: np.ndarray | None = None, name: str = "u", key: str | None = None) -> PlaneSpline:
    """Control points of a plane spline from user planes by the recursive re-weighting (§3.2.2).

    Parameters
    ----------
    control : 2K+1 planes ``γ_0, γ_01, γ_1, γ_12, …, γ_K`` (each a design-file plane, see :func:`plane_from_entry`)
    tangents : K+1 planes ``τ_0 … τ_K`` or ``None`` (default: through the knot line, orthogonal to ``γ_i``)
    side_condition : ``"project"`` (make the arrangement satisfy it) or ``"strict"`` (reject violations)
    tolerance : in ``"strict"`` mode the largest admissible distance of a plane from the knot line, relative to
        the extent of the knot lines (their feet spread, at least 1)
    g0 : (4,) weighted first control point (the common ``g_0 = h_0`` of both curves); default ``ḡ_0``
    name : ``"u"`` or ``"v"``, used in messages; key : design-file key of ``control`` (default ``{name}_planes``)

    Returns
    -------
    :class:`PlaneSpline`; cusps are warned about (:class:`CuspWarning`, logger ``ppfab``).
    """
    key = key or f"{name}_planes"
    tkey = f"{name}_tangents"
    if side_condition not in ("project", "strict"):
        raise DesignError("side_condition", f"must be 'project' or 'strict', got {side_condition!r}")
    if len(control) < 3 or len(control) % 2 == 0:
        raise DesignError(key, f"needs an odd number >= 3 of planes (gamma_0, gamma_01, gamma_1, ..., gamma_K), "
                               f"got {len(control)}")
    P = np.stack([plane_from_entry(e, f"{key}[{k}]") for k, e in enumerate(control)])
    K = (len(P) - 1) // 2
    gam, inner = P[0::2].copy(), P[1::2]
    if tangents is not None and len(tangents) != K + 1:
        raise DesignError(tkey, f"needs one tangent plane per knot: {K + 1}, got {len(tangents)}")
    tau = None if tangents is None else np.stack([plane_from_entry(e, f"{tkey}[{k}]") for k, e in enumerate(tangents)])
    # knot lines: interior from the inner planes, ends from the knot plane and its inner neighbour
    lines = []
    for i in range(K + 1):
        try:
            if i == 0:
                lines.append(knot_line(gam[0], inner[0], f"knot 0 ({key}[0], {key}[1])"))
            elif i == K:
                lines.append(knot_line(inner[K - 1], gam[K], f"knot {K} ({key}[{2 * K - 1}], {key}[{2 * K}])"))
            else:
                lines.append(knot_line(inner[i - 1], inner[i], f"knot {i} ({key}[{2 * i - 1}], {key}[{2 * i + 1}])"))
        except GeometryError as exc:
            raise DesignError(key, str(exc)) from None
    feet = np.array([p for p, _ in lines])
    reach = max(1.0, float(np.linalg.norm(np.ptp(feet, axis=0))))
    worst = 0.0
    T = np.zeros((K + 1, 4))
    for i, (p, d) in enumerate(lines):
        members = [] if i in (0, K) else [("gamma", gam[i], f"{key}[{2 * i}]")]
        if tau is not None:
            members.append(("tau", tau[i], f"{tkey}[{i}]"))
        for kind, plane, k_ in members:
            dist = line_distance(plane, p, d, reach)
            if side_condition == "strict" and dist > tolerance * reach:
                raise DesignError(k_, f"violates the side condition at knot {i}: the planes "
                                      f"{_knot_planes(i, K)} must share a line; this one is "
                                      f"{dist:.4g} away from it (allowed {tolerance * reach:.3g})")
            try:
                proj = project_to_pencil(plane, p, d, k_)
            except GeometryError as exc:
                raise DesignError(k_, str(exc)) from None
            worst = max(worst, dist / reach)
            if kind == "gamma":
                gam[i] = proj
            else:
                T[i] = proj
        if tau is None:
            n = np.cross(d, gam[i][:3])
            n /= np.linalg.norm(n)
            T[i] = np.concatenate([n, [-(n @ p)]])
    if worst > 1e-9:
        log.info("plane spline %s: side condition enforced by projection (largest change %.3g of the knot-line "
                 "extent)", name, worst)
    knots = np.zeros((K + 1, 4))
    ctrl = np.zeros((K, 4))
    mu, nu = np.zeros(K), np.zeros(K)
    knots[0] = gam[0] if g0 is None else np.asarray(g0, dtype=float)
    for i in range(K):
        try:
            mu[i], lam = _solve_pencil(knots[i], T[i], inner[i], f"knot {i} of {key}")
            ctrl[i] = lam * inner[i]
            nu[i], lam1 = _solve_pencil(ctrl[i], T[i + 1], gam[i + 1], f"knot {i + 1} of {key}")
        except GeometryError as exc:
            raise DesignError(key, str(exc)) from None
        for what, lam_, slot in (("inner", lam, 2 * i + 1), ("knot", lam1, 2 * i + 2)):
            if abs(lam_) <= 1e-9:
                raise DesignError(f"{key}[{slot}]", f"gets weight {lam_:.3g} in the re-weighting: the arrangement is "
                                                  f"degenerate at knot {i + (what == 'knot')}")
        knots[i + 1] = lam1 * gam[i + 1]
        if abs(mu[i]) <= 1e-12 or abs(nu[i]) <= 1e-12:
            raise DesignError(key, f"segment {i} degenerates: a control point coincides with a knot point")
    cusps = [i for i in range(1, K) if nu[i - 1] * mu[i] < 0]
    for i in cusps:
        msg = (f"plane spline {name}: cusp at knot {i} (Remark 3.3): the planes {_knot_planes(i, K)} are not in "
               f"that order around their common line")
        log.warning(msg)
        warnings.warn(msg, CuspWarning, stacklevel=2)
    return PlaneSpline(knots, ctrl, T, mu, nu, cusps, name)


def _face_parameters(segments: int, faces: int) -> np.ndarray:
    """Midpoints of ``faces`` equal cells of ``[0, segments]``."""
    return (np.arange(faces) + 0.5) * segments / faces


def plane_spline_mesh(g: PlaneSpline, h: PlaneSpline, faces_u: int, faces_v: int) -> QuadGrid:
    """PP mesh with face planes ``f(u_i, v_j) = g(u_i) + h(v_j) − g_0`` (eq. 8) at equal parameter steps."""
    if not np.allclose(g.knots[0], h.knots[0]):
        raise GeometryError("the two plane splines must start at the same weighted plane g_0 = h_0")
    grid = pp_from_curves(g, h, _face_parameters(g.segments, faces_u), _face_parameters(h.segments, faces_v),
                          g.knots[0])
    grid = replace(grid, meta={**grid.meta, "cusps_u": list(g.cusps), "cusps_v": list(h.cusps)})
    return grid


@dataclass(frozen=True)
class PlaneSplinesParams:
    """Control planes of two plane splines (§3.2.2); planes are [nx, ny, nz, d] or [px, py, pz, nx, ny, nz]."""

    u_planes: list[list[float]] = param(doc="gamma_0, gamma_01, gamma_1, ..., gamma_K of the u-spline (2K+1 planes)",
                                        min_length=3)
    v_planes: list[list[float]] = param(doc="gamma_0, gamma'_01, gamma'_1, ... of the v-spline; its first plane is "
                                            "the common corner plane, the same as u_planes[0]", min_length=3)
    u_tangents: list[list[float]] | None = param(None, doc="tau_0..tau_K, support planes at the u-knots (default: "
                                                            "through the knot line, orthogonal to gamma_i)")
    v_tangents: list[list[float]] | None = param(None, doc="support planes at the v-knots")
    side_condition: str = param("project", doc="'project': turn gamma_i and tau_i about the knot line into place; "
                                               "'strict': reject arrangements violating the side condition",
                                choices=("project", "strict"))
    tolerance: float = param(1e-6, doc="strict mode: allowed distance of a plane from its knot line, relative to the "
                                       "extent of the knot lines", exclusive_min=0)
    faces_u: int = param(20, doc="faces along u", min=2, max=4000)
    faces_v: int = param(14, doc="faces along v", min=2, max=4000)

    def __post_init__(self):
        self.splines(warn=False)

    def splines(self, warn: bool = True) -> tuple[PlaneSpline, PlaneSpline]:
        a = plane_from_entry(self.u_planes[0], "u_planes[0]")
        b = plane_from_entry(self.v_planes[0], "v_planes[0]")
        sign = 1.0 if a[:3] @ b[:3] >= 0 else -1.0
        ang = float(np.degrees(pl.angle_between(a, b)))
        if ang > 1e-6 or abs(a[3] - sign * b[3]) > 1e-9 * max(1.0, abs(a[3])):
            raise DesignError("v_planes[0]", f"must be the same plane as u_planes[0] (the common corner plane "
                                             f"g_0 = h_0); they differ by {ang:.3g}° and in offset by "
                                             f"{abs(a[3] - sign * b[3]):.4g}")
        with warnings.catch_warnings():
            if not warn:
                warnings.simplefilter("ignore", CuspWarning)
            g = plane_spline(self.u_planes, self.u_tangents, self.side_condition, self.tolerance, name="u")
            h = plane_spline(self.v_planes, self.v_tangents, self.side_condition, self.tolerance, g0=g.knots[0],
                             name="v")
        return g, h


@construction("plane_splines", PlaneSplinesParams,
              "PP mesh from quadratic plane splines with tangent (support) planes at the knots (§3.2.2)",
              section="§3.2.2")
def build_plane_splines(p: PlaneSplinesParams) -> QuadGrid:
    g, h = p.splines()
    return plane_spline_mesh(g, h, p.faces_u, p.faces_v)

"""PP meshes from two planar profile curves (§3.2.1, Example; Fig. 10).

The designer draws a curve ``c(u)`` in a plane ε and a curve ``d(v)`` in a
plane φ orthogonal to ε.  They meet at a point ``c0 ∈ ε ∩ φ`` where both have
the normal ``m0`` (along the line ε ∩ φ).  With ``m(u)``, ``n(v)`` the unit
normals of the curves within their planes, the dual surface (corrected
formula, see ``reference/README.md``)

    f(u, v) = [ m(u) + n(v) − m0 ;  m0·c0 − m(u)·c(u) − n(v)·d(v) ]
            = g(u) + h(v) − c,   g(u) = [m(u); −m(u)·c(u)],  h(v) = [n(v); −n(v)·d(v)],  c = [m0; −m0·c0]

is of the form of eq. (8): ``g(u) = f(u, v0)`` are the tangent planes along
``c`` and ``h(v) = f(u0, v)`` those along ``d``.  The surface
``x(u, v) = f ∩ f_u ∩ f_v`` (eq. 9) contains both curves: along ``v = v0`` the
three planes are the tangent plane at ``c(u)``, ``f_u = [m'; −m'·c]`` (it
contains ``c(u)`` since ``m ⊥ c'``) and ``f_v = [n'(v0); −n'(v0)·c0]``, whose
normal ``n'(v0)`` is the normal of ε, so it is ε itself.  The PP mesh samples
``f`` at face parameters (:func:`~ppfab.faceimage.pp_from_curves`).

Default placement: ε is the xz-plane (2D points ``[x, z]``), φ the yz-plane
(``[y, z]``), meeting along the z axis; a symmetric arch over x and one over y
with their apex on the z axis are valid input as they stand.

Preconditions (each failure is a :class:`~ppfab.errors.DesignError` naming the
key and the measured value): the planes are orthogonal; each curve crosses the
other's plane exactly once; the crossings coincide (the curves meet); both
normals there lie along ε ∩ φ (a common normal); the curves are strictly convex
(no inflection: ``f_u = g'`` vanishes where the curvature does).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from ppfab import planes as pl
from ..errors import DesignError
from ..faceimage import pp_from_curves
from ..mesh import QuadGrid
from ..schema import param
from ..curves import PlanarCurve, fit_planar_curve
from ..frame import Frame
from .registry import construction


def crossing(curve: PlanarCurve, plane_point: np.ndarray, plane_normal: np.ndarray, tol: float,
             key: str, other: str) -> float:
    """The unique parameter where ``curve`` crosses a plane (within the curve's domain).

    Raises :class:`DesignError` under ``key`` when it never gets within ``tol``
    of the plane or crosses it more than once.
    """
    tt = np.linspace(curve.t0, curve.t1, 4001)

    def dist(t):
        return np.einsum("...i,i->...", curve.point(np.atleast_1d(t)) - plane_point, plane_normal)

    s = dist(tt)
    roots = [float(tt[k]) for k in np.flatnonzero(s == 0)]
    for k in np.flatnonzero(s[:-1] * s[1:] < 0):
        roots.append(brentq(lambda t: float(dist(t)[0]), tt[k], tt[k + 1], xtol=1e-14 * (tt[-1] - tt[0])))
    roots = sorted(roots)
    span = tt[-1] - tt[0]
    roots = [r for k, r in enumerate(roots) if k == 0 or r - roots[k - 1] > 1e-6 * span]
    if not roots:
        near = int(np.argmin(np.abs(s)))
        lo, hi = tt[max(near - 1, 0)], tt[min(near + 1, len(tt) - 1)]
        best = minimize_scalar(lambda t: abs(float(dist(t)[0])), bounds=(lo, hi), method="bounded",
                               options={"xatol": 1e-12 * (tt[-1] - tt[0])})
        gap = abs(float(dist(best.x)[0]))
        if gap > tol:
            raise DesignError(key, f"curve {curve.name} does not reach the plane {other}: it stays {gap:.4g} away "
                                   f"(the two curves must meet on the line where the planes intersect)")
        return float(best.x)
    if len(roots) > 1:
        pts = ", ".join(f"{tuple(np.round(curve(t), 4).tolist())}" for t in roots[:4])
        raise DesignError(key, f"curve {curve.name} crosses the plane {other} {len(roots)} times (at {pts}); "
                               f"it must cross it once, at the common point of the two curves")
    return roots[0]


def check_convex(curve: PlanarCurve, key: str, t: np.ndarray | None = None) -> None:
    """Raise ``DesignError(key)`` if the signed curvature vanishes or changes sign on ``t``."""
    t = np.linspace(curve.t0, curve.t1, 801) if t is None else t
    kappa = curve.curvature(t)
    size = curve.length
    small = np.abs(kappa) * size <= 1e-6
    flip = np.sign(kappa) != np.sign(kappa[np.argmax(np.abs(kappa))])
    bad = small | flip
    if np.any(bad):
        k = int(np.argmax(bad))
        where = tuple(np.round(curve(t[k]), 4).tolist())
        raise DesignError(key, f"curve {curve.name} has an inflection or a straight piece near {where} (curvature "
                               f"{kappa[k]:.3g}); profile curves must bend one way only — the support planes are "
                               f"derivatives of the tangent planes and vanish where the curvature does")


class ProfileSurface:
    """The dual surface ``f(u, v) = g(u) + h(v) − c`` of two profile curves, its limit surface and meshes.

    Built by :func:`profile_surface`; ``u`` and ``v`` are the curves' own
    parameters (chord length, ``u0``/``v0`` at the common point).
    """

    def __init__(self, c: PlanarCurve, d: PlanarCurve, u0: float, v0: float, sign_c: float, sign_d: float):
        self.c_curve, self.d_curve = c, d
        self.u0, self.v0 = u0, v0
        self.sign_c, self.sign_d = sign_c, sign_d
        self.const = 0.5 * (self.g(np.array([u0]))[0] + self.h(np.array([v0]))[0])
        self.c0 = 0.5 * (c.point(np.array([u0]))[0] + d.point(np.array([v0]))[0])
        self.m0 = self.const[:3] / np.linalg.norm(self.const[:3])
        self.gap = float(np.linalg.norm(c.point(np.array([u0]))[0] - d.point(np.array([v0]))[0]))

    @staticmethod
    def _tangent_planes(curve: PlanarCurve, t: np.ndarray, sign: float) -> np.ndarray:
        m = curve.unit_normal(t, sign)
        return np.concatenate([m, -np.einsum("...i,...i->...", m, curve.point(t))[..., None]], axis=-1)

    @staticmethod
    def _support_planes(curve: PlanarCurve, t: np.ndarray, sign: float) -> np.ndarray:
        dm = curve.unit_normal_derivative(t, sign)
        return np.concatenate([dm, -np.einsum("...i,...i->...", dm, curve.point(t))[..., None]], axis=-1)

    def g(self, u: np.ndarray) -> np.ndarray:
        """Tangent planes ``[m(u); −m(u)·c(u)]`` along ``c``, ``(k, 4)``."""
        return self._tangent_planes(self.c_curve, np.asarray(u, dtype=float), self.sign_c)

    def h(self, v: np.ndarray) -> np.ndarray:
        """Tangent planes ``[n(v); −n(v)·d(v)]`` along ``d``, ``(k, 4)``."""
        return self._tangent_planes(self.d_curve, np.asarray(v, dtype=float), self.sign_d)

    def g_prime(self, u: np.ndarray) -> np.ndarray:
        """``f_u = g'(u) = [m'; −m'·c]`` (``m ⊥ c'``), the support planes of the v-lines, ``(k, 4)``."""
        return self._support_planes(self.c_curve, np.asarray(u, dtype=float), self.sign_c)

    def h_prime(self, v: np.ndarray) -> np.ndarray:
        """``f_v = h'(v)``, the support planes of the u-lines, ``(k, 4)``."""
        return self._support_planes(self.d_curve, np.asarray(v, dtype=float), self.sign_d)

    def f(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``f(u, v) = g(u) + h(v) − c`` (eq. 8), broadcast over ``u`` and ``v`` of the same shape."""
        u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
        return (self.g(u.ravel()) + self.h(v.ravel()) - self.const).reshape(u.shape + (4,))

    def limit_point(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``x(u, v) = f ∩ f_u ∩ f_v`` (eq. 9), shape ``u.shape + (3,)``."""
        u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
        fu = self.g_prime(u.ravel())
        fv = self.h_prime(v.ravel())
        return pl.intersect_three(self.f(u.ravel(), v.ravel()), fu, fv).reshape(u.shape + (3,))

    @staticmethod
    def face_parameters(curve: PlanarCurve, faces: int) -> np.ndarray:
        """Parameters of ``faces`` cells of equal arc length (their midpoints), ``(faces,)``."""
        s = (np.arange(faces) + 0.5) * curve.length / faces
        return curve.param_at_length(s)

    def mesh(self, faces_u: int, faces_v: int) -> QuadGrid:
        """The PP mesh with face planes ``f(u_i, v_j)`` at equal-arc-length face parameters.

        Ghost faces half a cell beyond each end (extrapolated curves) put the
        boundary vertices close to the ends of the curves.
        """
        u = self.face_parameters(self.c_curve, faces_u)
        v = self.face_parameters(self.d_curve, faces_v)
        for curve, t, key in ((self.c_curve, u, "c_points"), (self.d_curve, v, "d_points")):
            ext = np.concatenate([[2 * t[0] - t[1]], t, [2 * t[-1] - t[-2]]])
            check_convex(curve, key, np.linspace(ext[0], ext[-1], 801))
        grid = pp_from_curves(self.g, self.h, u, v, self.const)
        grid = replace(grid, meta={**grid.meta, "u": u, "v": v, "u0": self.u0, "v0": self.v0,
                                   "profile_gap": self.gap})
        return grid


def profile_surface(c_points, d_points, fit: str = "interpolate",
                    eps_origin=(0.0, 0.0, 0.0), eps_axes=((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
                    phi_origin=(0.0, 0.0, 0.0), phi_axes=((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
                    angle_tolerance_deg: float = 0.1, meet_tolerance: float = 1e-4) -> ProfileSurface:
    """Fit the two profile curves, check the preconditions of §3.2.1 and return the dual surface.

    Parameters
    ----------
    c_points : (k, 2) — curve ``c`` in ε's coordinates (default ε: ``[x, z]``)
    d_points : (l, 2) — curve ``d`` in φ's coordinates (default φ: ``[y, z]``)
    fit : ``"interpolate"`` (spline through the points) or ``"control"`` (B-spline control polygon)
    eps_origin, eps_axes, phi_origin, phi_axes : the planes' frames (origin, two in-plane axes)
    angle_tolerance_deg : allowed deviation from orthogonal planes and from a common normal
    meet_tolerance : allowed gap between the curves, relative to the larger curve's bounding box

    Raises
    ------
    DesignError naming the key (``phi_axes``, ``c_points``, ``d_points``) and the failed condition.

    Examples
    --------
    >>> S = profile_surface([[-2, 1.6], [0, 2], [2, 1.6]], [[-1, 1.8], [0, 2], [1, 1.8]])
    >>> S.mesh(4, 3).shape
    (5, 4)
    >>> u = S.u0 + 0.5                         # the limit surface contains c (eq. 9)
    >>> bool(np.allclose(S.limit_point(u, S.v0), S.c_curve.point([u])[0]))
    True
    """
    eps = Frame.from_axes(eps_origin, eps_axes, "eps_axes")
    phi = Frame.from_axes(phi_origin, phi_axes, "phi_axes")
    ang = float(np.degrees(pl.line_angle(eps.normal, phi.normal)))
    if abs(90.0 - ang) > angle_tolerance_deg:
        raise DesignError("phi_axes", f"planes eps and phi are not orthogonal: they meet at {ang:.4g}° "
                                      f"(needs 90° ± {angle_tolerance_deg:g}°)")
    c = fit_planar_curve(c_points, eps, fit, "c_points", "c")
    d = fit_planar_curve(d_points, phi, fit, "d_points", "d")
    check_convex(c, "c_points")
    check_convex(d, "d_points")
    tol = meet_tolerance * max(c.extent, d.extent)
    u0 = crossing(c, phi.origin, phi.normal, tol, "c_points", "phi")
    v0 = crossing(d, eps.origin, eps.normal, tol, "d_points", "eps")
    pc, pd = c.point(np.array([u0]))[0], d.point(np.array([v0]))[0]
    gap = float(np.linalg.norm(pc - pd))
    if gap > tol:
        raise DesignError("d_points", f"the curves do not meet: c reaches the line eps∩phi at "
                                      f"{tuple(np.round(pc, 4).tolist())}, d at {tuple(np.round(pd, 4).tolist())}, "
                                      f"{gap:.4g} apart (allowed {tol:.3g})")
    line = np.cross(eps.normal, phi.normal)
    line /= np.linalg.norm(line)
    if line @ (eps.ey + phi.ey) < 0:
        line = -line
    signs = []
    for curve, t, key in ((c, u0, "c_points"), (d, v0, "d_points")):
        m = curve.unit_normal(np.array([t]))[0]
        dev = float(np.degrees(pl.line_angle(m, line)))
        if dev > angle_tolerance_deg:
            raise DesignError(key, f"curve {curve.name} has no common normal with the other curve at the common "
                                   f"point: its normal there makes {dev:.4g}° with the line eps∩phi (its tangent must "
                                   f"be perpendicular to that line; allowed {angle_tolerance_deg:g}°)")
        signs.append(1.0 if m @ line > 0 else -1.0)
    return ProfileSurface(c, d, u0, v0, signs[0], signs[1])


@dataclass(frozen=True)
class ProfileCurvesParams:
    """Two planar profile curves meeting with a common normal (§3.2.1)."""

    c_points: list[list[float]] = param(doc="curve c in plane eps as 2D points [s, t] in eps's frame "
                                            "(default eps = xz-plane: [x, z])", min_length=3)
    d_points: list[list[float]] = param(doc="curve d in plane phi as 2D points (default phi = yz-plane: [y, z])",
                                        min_length=3)
    fit: str = param("interpolate", doc="'interpolate': spline through the points; 'control': the points are a "
                                        "B-spline control polygon", choices=("interpolate", "control"))
    faces_u: int = param(20, doc="faces along c", min=2, max=4000)
    faces_v: int = param(14, doc="faces along d", min=2, max=4000)
    eps_origin: list[float] = param([0.0, 0.0, 0.0], doc="a point of plane eps (origin of its 2D frame)", length=3)
    eps_axes: list[list[float]] = param([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], doc="two in-plane axes of eps", length=2)
    phi_origin: list[float] = param([0.0, 0.0, 0.0], doc="a point of plane phi", length=3)
    phi_axes: list[list[float]] = param([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], doc="two in-plane axes of phi", length=2)
    angle_tolerance_deg: float = param(0.1, doc="allowed deviation from orthogonal planes and from a common normal",
                                       exclusive_min=0, max=10)
    meet_tolerance: float = param(1e-4, doc="allowed gap between the curves relative to their size (the surface "
                                            "misses each curve by about half the gap)",
                                  exclusive_min=0, max=0.1)

    def __post_init__(self):
        self.surface()

    def surface(self) -> ProfileSurface:
        return profile_surface(self.c_points, self.d_points, self.fit, self.eps_origin, self.eps_axes,
                               self.phi_origin, self.phi_axes, self.angle_tolerance_deg, self.meet_tolerance)


@construction("profile_curves", ProfileCurvesParams,
              "PP mesh through two planar profile curves in orthogonal planes (§3.2.1)", section="§3.2.1")
def build_profile_curves(p: ProfileCurvesParams) -> QuadGrid:
    return p.surface().mesh(p.faces_u, p.faces_v)

"""Conical PP meshes from explicit face images (paper §4.1.1, eqs. 11–13, Appendix).

The face planes of a conical mesh whose polylines are all planar are samples
``f_ij = f(u_i, v_j)`` of

* Case 1 (eq. 11), ``d > 1``, ``e = √(d² − 1)``::

      f(u, v) = (e sin u,  d cos u + cosh v,  e sinh v,  g(u) + h(v))

* the rotational limit ``d → ∞`` (eq. 12)::

      f(u, v) = (sin u,  cos u,  sinh v,  g(u) + h(v))

* Case 2 (eq. 13)::

      f(u, v) = (u,  v,  (u² + v² − 1)/2,  g(u) + h(v))

for arbitrary functions ``g, h`` and any sampling ``u_i, v_j``.  Each is a
translation net ``G(u) + H(v)`` in R^4 (Prop. 3.1), so the mesh is PP; it is
conical because ``|n(u, v)|`` is itself a sum ``a(u) + b(v)`` (``d cosh v + cos u``,
``cosh v``, ``(u² + v² + 1)/2``), which makes the four unit normals around a
vertex coplanar, i.e. concyclic on ``S²``.  The meshes are built with
:func:`ppfab.faceimage.pp_from_face_image` (ghost faces, node axes along
``U_i ∩ W_j``) and checked for folds (:mod:`ppfab.folds`).

The smooth surface enveloped by ``f`` (Appendix) is :func:`envelope`; the mesh
vertices converge to it under refinement.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from ppfab.conical.cones import rigid_motion
from ..errors import DesignError, GeometryError
from ..faceimage import orient_axes, pp_from_face_image, sample_extended
from ..folds import check_folds, orientation_sign
from ..mesh import QuadGrid
from ..schema import param
from .registry import construction

CASES = ("case1", "rotational", "case2")

FRAMES = {
    # paper coordinates -> output, so that the face normal at u = v = 0 points to +z
    "case1": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
    "rotational": np.eye(3),
    "case2": np.diag([1.0, -1.0, -1.0]),
}
"""Rotations from the paper's coordinates to the ``z_up`` frame (face normal at ``u = v = 0`` is +z)."""


@dataclass(frozen=True)
class Series:
    """A real function of one variable: ``Σ a_k t^k + Σ_k (b_k cos kt + c_k sin kt + p_k cosh kt + q_k sinh kt)``.

    ``poly`` starts at ``k = 0``; the other lists start at ``k = 1``.

    Examples
    --------
    >>> Series(poly=[1.0, 2.0], cos=[3.0])(np.array([0.0]))
    array([4.])
    """

    poly: list[float] = param([], doc="polynomial coefficients a_0, a_1, … (lowest degree first)")
    cos: list[float] = param([], doc="coefficients b_k of cos(k t), k = 1, 2, …")
    sin: list[float] = param([], doc="coefficients c_k of sin(k t), k = 1, 2, …")
    cosh: list[float] = param([], doc="coefficients p_k of cosh(k t), k = 1, 2, …")
    sinh: list[float] = param([], doc="coefficients q_k of sinh(k t), k = 1, 2, …")

    def _terms(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        c = np.asarray(getattr(self, name), dtype=float)
        return c, np.arange(1, len(c) + 1, dtype=float)

    def __call__(self, t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        out = np.polyval(np.asarray(self.poly, dtype=float)[::-1], t) if self.poly else np.zeros_like(t)
        for name, fn in (("cos", np.cos), ("sin", np.sin), ("cosh", np.cosh), ("sinh", np.sinh)):
            c, k = self._terms(name)
            if len(c):
                out = out + fn(t[..., None] * k) @ c
        return out

    def derivative(self, t: np.ndarray) -> np.ndarray:
        """The first derivative, same shape as ``t``."""
        t = np.asarray(t, dtype=float)
        p = np.asarray(self.poly, dtype=float)
        out = np.polyval((p[1:] * np.arange(1, len(p)))[::-1], t) if len(p) > 1 else np.zeros_like(t)
        for name, fn in (("cos", lambda x: -np.sin(x)), ("sin", np.cos), ("cosh", np.sinh), ("sinh", np.cosh)):
            c, k = self._terms(name)
            if len(c):
                out = out + fn(t[..., None] * k) @ (c * k)
        return out

    @property
    def periodic(self) -> bool:
        """True when the function has period 2π (only a constant and cos/sin terms)."""
        return not any(self.poly[1:]) and not any(self.cosh) and not any(self.sinh)


# -- the normal image of eqs. (11)-(13) ----------------------------------------------------------

def _e(d: float) -> float:
    if not d > 1.0:
        raise GeometryError(f"case 1 needs d > 1 (e = sqrt(d² − 1)), got d = {d}", element="d", value=float(d))
    return float(np.sqrt(d * d - 1.0))


def normal_generators(case: str, d: float = 2.0) -> tuple[Callable, Callable, np.ndarray]:
    """Normal parts of the translation net ``n(u, v) = a(u) + b(v) − c`` of eqs. (11)–(13).

    Returns ``a: u (k,) -> (k, 3)``, ``b: v (k,) -> (k, 3)`` and ``c (3,)``
    (Case 1: ``a = (e sin u, d cos u, 0)``, ``b = (0, cosh v, e sinh v)``; rotational:
    ``(sin u, cos u, 0)``, ``(0, 0, sinh v)``; Case 2: ``(u, 0, u²/2)``, ``(0, v, v²/2)``, ``c = (0, 0, ½)``).
    """
    z = np.zeros
    if case == "case1":
        e = _e(d)
        return (lambda u: np.stack([e * np.sin(u), d * np.cos(u), z(np.shape(u))], -1),
                lambda v: np.stack([z(np.shape(v)), np.cosh(v), e * np.sinh(v)], -1), np.zeros(3))
    if case == "rotational":
        return (lambda u: np.stack([np.sin(u), np.cos(u), z(np.shape(u))], -1),
                lambda v: np.stack([z(np.shape(v)), z(np.shape(v)), np.sinh(v)], -1), np.zeros(3))
    if case == "case2":
        return (lambda u: np.stack([u, z(np.shape(u)), 0.5 * np.square(u)], -1),
                lambda v: np.stack([z(np.shape(v)), v, 0.5 * np.square(v)], -1), np.array([0.0, 0.0, 0.5]))
    raise GeometryError(f"unknown conical PP case {case!r}; valid: {', '.join(CASES)}", element="case")


def face_image(case: str, g: Callable, h: Callable, d: float = 2.0) -> tuple[Callable, Callable, np.ndarray]:
    """Generators ``G(u) (k, 4)``, ``H(v) (k, 4)`` and ``c (4,)`` with ``f(u, v) = G(u) + H(v) − c`` (eqs. 11–13)."""
    a, b, c = normal_generators(case, d)
    G = lambda u: np.concatenate([a(np.asarray(u, float)), np.asarray(g(u), float)[..., None]], -1)  # noqa: E731
    H = lambda v: np.concatenate([b(np.asarray(v, float)), np.asarray(h(v), float)[..., None]], -1)  # noqa: E731
    return G, H, np.concatenate([c, [0.0]])


def normal_field(case: str, u: np.ndarray, v: np.ndarray, d: float = 2.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n(u, v)``, ``n_u``, ``n_v`` of the chosen case, each ``(..., 3)`` (broadcast ``u``, ``v``)."""
    u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
    z = np.zeros_like(u)
    if case == "case1":
        e = _e(d)
        n = np.stack([e * np.sin(u), d * np.cos(u) + np.cosh(v), e * np.sinh(v)], -1)
        nu = np.stack([e * np.cos(u), -d * np.sin(u), z], -1)
        nv = np.stack([z, np.sinh(v), e * np.cosh(v)], -1)
    elif case == "rotational":
        n = np.stack([np.sin(u), np.cos(u), np.sinh(v)], -1)
        nu = np.stack([np.cos(u), -np.sin(u), z], -1)
        nv = np.stack([z, z, np.cosh(v)], -1)
    elif case == "case2":
        n = np.stack([u, v, 0.5 * (u * u + v * v - 1.0)], -1)
        nu = np.stack([np.ones_like(u), z, u], -1)
        nv = np.stack([z, np.ones_like(u), v], -1)
    else:
        raise GeometryError(f"unknown conical PP case {case!r}; valid: {', '.join(CASES)}", element="case")
    return n, nu, nv


def envelope(case: str, g: Series, h: Series, u: np.ndarray, v: np.ndarray, d: float = 2.0) -> np.ndarray:
    """The smooth surface ``x(u, v) = f × f_u × f_v`` enveloped by the planes (§4.1.2, Appendix), ``(..., 3)``.

    Solves ``n·x + g + h = 0``, ``n_u·x + ġ = 0``, ``n_v·x + ḣ = 0`` per point.
    """
    u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
    n, nu, nv = normal_field(case, u, v, d)
    A = np.stack([n, nu, nv], axis=-2)
    rhs = -np.stack([g(u) + h(v), g.derivative(u), h.derivative(v)], axis=-1)
    return np.linalg.solve(A, rhs[..., None])[..., 0]


def appendix_surface(case: str, g: Series, h: Series, u: np.ndarray, v: np.ndarray, d: float = 2.0) -> np.ndarray:
    """The Appendix's closed-form ``x(u, v)`` for Case 1 and Case 2 (paper coordinates), ``(..., 3)``.

    Case 1 in homogeneous coordinates ``(x1 : x2 : x3 : x4)``::

        x1 = d[(g+h) sin u cosh v + ġ cos u cosh v − ḣ sin u sinh v] + ġ
        x2 = e[(g+h) cos u cosh v − ġ sin u cosh v − ḣ cos u sinh v]
        x3 = −(g+h) cos u sinh v + ġ sin u sinh v + ḣ cos u cosh v + d ḣ
        x4 = −e (cos u + d cosh v)

    Case 2: ``x = [(u²−v²−1)ġ + 2uvḣ − 2u(g+h), (v²−u²−1)ḣ + 2uvġ − 2v(g+h), 2(g+h − uġ − vḣ)] / (u²+v²+1)``.
    """
    u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
    G, a, b = g(u) + h(v), g.derivative(u), h.derivative(v)
    if case == "case1":
        e = _e(d)
        s, c, sh, ch = np.sin(u), np.cos(u), np.sinh(v), np.cosh(v)
        x = np.stack([d * (G * s * ch + a * c * ch - b * s * sh) + a,
                      e * (G * c * ch - a * s * ch - b * c * sh),
                      -G * c * sh + a * s * sh + b * c * ch + d * b], -1)
        return x / (-e * (c + d * ch))[..., None]
    if case == "case2":
        k = 1.0 / (u * u + v * v + 1.0)
        return np.stack([(u * u - v * v - 1) * a + 2 * u * v * b - 2 * u * G,
                         (v * v - u * u - 1) * b + 2 * u * v * a - 2 * v * G,
                         2 * (G - u * a - v * b)], -1) * k[..., None]
    raise GeometryError(f"the Appendix gives closed forms for case1 and case2 only, not {case!r}", element="case")


# -- the mesh --------------------------------------------------------------------------------------

def _close_columns(grid: QuadGrid) -> QuadGrid:
    """Drop the duplicate last vertex column of a periodic sampling and mark the grid closed."""
    F = grid.extended_face_image
    assert F is not None and grid.support_w is not None and grid.axes is not None, \
        "a grid from pp_from_face_image carries its planes, axes and extended face image"
    return QuadGrid(grid.vertices[:, :-1], closed=True, support_u=grid.support_u,
                    support_w=grid.support_w[:-1], face_image=grid.face_image,
                    axes=grid.axes[:, :-1], extended_face_image=F[:, :-1], meta=grid.meta)


def conical_pp_grid(g: Series | Callable, h: Series | Callable, u: np.ndarray, v: np.ndarray, case: str = "case1",
                    d: float = 2.0, closed: bool = False, frame: str = "paper", check: bool = True) -> QuadGrid:
    """A conical PP mesh whose face planes are samples of eq. (11), (12) or (13).

    Parameters
    ----------
    g, h : functions of one variable (e.g. :class:`Series`) giving the 4th coordinate ``g(u) + h(v)``
    u : (m,) float — face parameters along ``u`` (strictly monotone), or with ``closed`` the first of
        ``m`` equally spaced angles covering ``2π`` (only ``u[0]`` and ``len(u)`` are used)
    v : (n,) float — face parameters along ``v``
    case : ``"case1"`` (eq. 11), ``"rotational"`` (eq. 12) or ``"case2"`` (eq. 13)
    d : the Case 1 parameter, ``d > 1``
    closed : ``u`` runs once around (case1, rotational; ``g`` must be 2π-periodic).  The grid is then
        transposed so that its closed rows follow ``u``: ``v[i, j] ≈ x(u_j, v_i)``
    frame : ``"paper"`` keeps the paper's coordinates; ``"z_up"`` rotates so the face normal at
        ``u = v = 0`` is ``+z`` (rotational: the axis is ``z`` in both frames; see :data:`FRAMES`)
    check : raise :class:`~ppfab.errors.FoldError` when the mesh folds

    Returns
    -------
    QuadGrid with ``(m+1, n+1)`` vertices (``(n+1, m)`` when closed), support planes ``U_i``, ``W_j``,
    the face image, node axes and the extended face image; the corner order of every face
    agrees with its face-image normal.
    """
    if case not in CASES:
        raise GeometryError(f"unknown conical PP case {case!r}; valid: {', '.join(CASES)}", element="case")
    G, H, c = face_image(case, g, h, d)
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    _check_samples(v, "v")
    if closed:
        if case == "case2":
            raise GeometryError("case2 cannot be closed: u is not an angle there", element="closed")
        if isinstance(g, Series) and not g.periodic:
            raise GeometryError("closed = true needs a 2π-periodic g(u) (a constant plus cos/sin terms only)",
                                element="g")
        if len(u) < 3:
            raise GeometryError(f"a closed mesh needs at least 3 faces around, got {len(u)}", element="u")
        m = len(u)
        ue = u[0] + 2.0 * np.pi * np.arange(-1, m + 1) / m           # u_{−1} … u_m, periodic ghosts
        Gs = G(ue)
        if not np.allclose(Gs[0], Gs[-2], rtol=1e-9, atol=1e-9 * max(1.0, float(np.abs(Gs).max()))):
            raise GeometryError("closed = true needs a 2π-periodic g(u)", element="g")
        faces_u, faces_v = ue[1:-1], v
    else:
        _check_samples(u, "u")
        faces_u, faces_v = u, v
    for attempt in range(2):
        vv = faces_v if attempt == 0 else faces_v[::-1]
        Hs = sample_extended(H, vv)
        if closed:
            built = _close_columns(pp_from_face_image(Hs, Gs, c))
            ref = built.face_image
        else:
            built = pp_from_face_image(sample_extended(G, faces_u), Hs, c)
            ref = built.face_image
        assert ref is not None, "pp_from_face_image sets the face image"
        s = orientation_sign(built, ref)
        grid = built
        if (s > 0).sum() >= (s < 0).sum():
            break
    meta = {**grid.meta, "case": case, "d": float(d) if case == "case1" else None,
            "u": faces_u, "v": vv, "closed_u": bool(closed), "frame": frame}
    grid = replace(grid, meta=meta)
    if check:
        if closed:
            check_folds(grid, vv, faces_u, context=f"conical PP mesh ({case})", names=("v", "u"))
        else:
            check_folds(grid, faces_u, vv, context=f"conical PP mesh ({case})", names=("u", "v"))
    if frame == "z_up":
        grid = rigid_motion(grid, FRAMES[case])
    elif frame != "paper":
        raise GeometryError(f"unknown frame {frame!r}; valid: paper, z_up", element="frame")
    F = grid.extended_face_image
    assert grid.axes is not None and F is not None, "pp_from_face_image sets the axes and extended face image"
    return replace(grid, axes=orient_axes(grid.axes, F))


def _check_samples(t: np.ndarray, name: str) -> None:
    if t.ndim != 1 or len(t) < 2:
        raise GeometryError(f"{name} needs at least 2 face parameters, got {t.size}", element=name)
    if not np.all(np.isfinite(t)):
        raise GeometryError(f"{name} contains NaN or inf", element=name)
    dt = np.diff(t)
    if not (np.all(dt > 0) or np.all(dt < 0)):
        k = int(np.argmax((dt <= 0) if dt[0] > 0 else (dt >= 0)))
        raise GeometryError(f"{name} must be strictly monotone: {name}[{k}] = {t[k]:.6g}, "
                            f"{name}[{k + 1}] = {t[k + 1]:.6g}", element=f"{name}[{k + 1}]", value=float(t[k + 1]))


# -- design-file method ----------------------------------------------------------------------------

@dataclass(frozen=True)
class ConicalPPParams:
    """Conical PP mesh from the explicit face image of §4.1.1 (eqs. 11–13)."""

    case: str = param("case1", doc="case1 (eq. 11), rotational (eq. 12) or case2 (eq. 13)", choices=CASES)
    d: float = param(2.0, doc="case1 only: position of the polar lines l: x2 = d, l̄: x2 = 1/d (d > 1)")
    g: Series = param(Series(), doc="g(u): table with poly/cos/sin/cosh/sinh coefficient lists")
    h: Series = param(Series(), doc="h(v): table with poly/cos/sin/cosh/sinh coefficient lists")
    u_range: list[float] = param([-0.5, 0.5], doc="face parameters u from … to (ignored when u is given)", length=2)
    v_range: list[float] = param([-0.5, 0.5], doc="face parameters v from … to (ignored when v is given)", length=2)
    faces_u: int = param(12, doc="number of faces along u", min=1, max=4000)
    faces_v: int = param(12, doc="number of faces along v", min=1, max=4000)
    u: list[float] = param([], doc="explicit face parameters u_i (any strictly monotone sampling)")
    v: list[float] = param([], doc="explicit face parameters v_j")
    closed: bool = param(False, doc="u runs once around 2π from u_range[0] (case1, rotational; g periodic)")
    frame: str = param("z_up", doc="z_up: face normal at u = v = 0 is +z (rotational: axis along z); "
                                   "paper: the paper's coordinates", choices=("z_up", "paper"))
    translate: list[float] = param([0.0, 0.0, 0.0], doc="move the result by [x, y, z] (after the frame rotation)",
                                   length=3)

    def __post_init__(self):
        if self.case == "case1" and not self.d > 1.0:
            raise DesignError("d", f"case1 needs d > 1 (e = sqrt(d² − 1) must be real), got {self.d}")
        if self.closed and self.case == "case2":
            raise DesignError("closed", "case2 cannot be closed (u is not an angle)")
        if self.closed and not self.g.periodic:
            raise DesignError("g", "closed = true needs a 2π-periodic g(u): only a constant and cos/sin terms")
        for name in ("u_range", "v_range"):
            a, b = getattr(self, name)
            if not a < b:
                raise DesignError(name, f"needs start < end, got [{a}, {b}]")
        for name in ("u", "v"):
            t = np.asarray(getattr(self, name), dtype=float)
            if len(t) == 1 or (len(t) > 1 and not (np.all(np.diff(t) > 0) or np.all(np.diff(t) < 0))):
                raise DesignError(name, "explicit face parameters must be at least 2 strictly monotone values")


def samples(p: ConicalPPParams) -> tuple[np.ndarray, np.ndarray]:
    """Face parameters ``u (m,)``, ``v (n,)`` of a parameter record."""
    u = np.asarray(p.u, float) if p.u else (
        p.u_range[0] + 2 * np.pi * np.arange(p.faces_u) / p.faces_u if p.closed
        else np.linspace(p.u_range[0], p.u_range[1], p.faces_u) if p.faces_u > 1
        else np.array([np.mean(p.u_range)]))
    v = np.asarray(p.v, float) if p.v else np.linspace(p.v_range[0], p.v_range[1], p.faces_v)
    return u, v


@construction("conical_pp", ConicalPPParams,
              "conical PP mesh from the explicit face image of eq. 11 (case1), 12 (rotational) or 13 (case2)",
              planar_families=("rows", "cols"), section="§4.1.1, eqs. 11–13")
def build_conical_pp(p: ConicalPPParams) -> QuadGrid:
    u, v = samples(p)
    if not p.closed and len(u) < 2:
        raise DesignError("faces_u", "needs at least 2 faces along u")
    if len(v) < 2:
        raise DesignError("faces_v", "needs at least 2 faces along v")
    grid = conical_pp_grid(p.g, p.h, u, v, case=p.case, d=p.d, closed=p.closed, frame=p.frame)
    return rigid_motion(grid, np.eye(3), np.asarray(p.translate, float)) if any(p.translate) else grid

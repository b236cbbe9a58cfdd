"""Conical PP meshes designed by their two principal planar sections (paper §4.1.2).

The designer draws two convex planar curves that cross where both are
horizontal (the crest): section A in the ``xz`` plane (points ``[x, z]``) and
section B in the ``yz`` plane (points ``[y, z]``).  They are the principal
sections of the design surface through the crest; the surface normal there is
``+z``.  Their support functions (eqs. 14, 15) enter the re-parametrised face
image, which is sampled to give a conical PP mesh.

Case 1 (§4.1.2), ``d > 1``, ``e = √(d² − 1)``, in the paper's coordinates
(``x2`` = up; A lies in ``x1x2``, B in ``x2x3``)::

    r(φ) = e² / (d − sin φ)   [= e²(sin φ + d)/(e² + cos² φ)]      (ellipse with a focus at 0)
    s(ψ) = e² / (d cos ψ − 1) [= e²(d cos ψ + 1)/(e² cos² ψ − sin² ψ)] (hyperbola branch, |ψ| < arccos(1/d))
    f̃(φ, ψ) = (r cos φ,  r sin φ + s cos ψ − d − 1,  s sin ψ,  r g̃(φ) + s h̃(ψ) − a(d + 1))

with ``a = g̃(π/2) = h̃(0)``: the translation net ``G(φ) + H(ψ) − c`` with
``G = r (cos φ, sin φ, 0, g̃)``, ``H = s (0, cos ψ, sin ψ, h̃)``, ``c = (0, d+1, 0, a(d+1))``.
At ``ψ = 0`` the planes are ``x1 cos φ + x2 sin φ + g̃(φ) = 0`` (eq. 14), at ``φ = π/2``
``x2 cos ψ + x3 sin ψ + h̃(ψ) = 0`` (eq. 15), so the cylinders over the sections
are tangent to the surface along them.  ``n(u, v)`` of eq. (11) is recovered with
``e sin u = r cos φ``, ``d cos u + 1 = r sin φ`` (the ellipse ``n(u, 0) = (e sin u, d cos u + 1, 0)``,
see reference/README.md) and ``cosh v + d = s cos ψ``, ``e sinh v = s sin ψ``.

Case 2 (parabolic pencils, eq. 13): ``n(u, 0) = (u, 0, (u² − 1)/2)``, ``r(φ) = 1/(1 − sin φ)``
``[= (sin φ + 1)/cos² φ]``, A in the ``x1x3`` plane, B in ``x2x3``, crest normal ``−x3``::

    G = r (cos φ, 0, sin φ, g̃),  H = s (0, cos ψ, sin ψ, h̃),  c = (0, 0, −1/2, a/2),  a = g̃(−π/2) = h̃(−π/2).

The output is rotated so that the crest normal is ``+z`` (the frames of
:data:`ppfab.constructions.conical_pp.FRAMES`); the mesh crosses the crest at
``(x_A, y_B, z)`` and its row polylines follow section A.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ppfab.conical.cones import rigid_motion
from ..errors import DesignError, GeometryError
from ..faceimage import orient_axes, pp_from_face_image
from ..folds import check_folds, orientation_sign
from ..mesh import QuadGrid
from ..schema import param
from ..curves import ConvexSection, PlanarCurve
from .conical_pp import FRAMES
from .registry import construction

# user 2D coordinates ([x, z] for A, [y, z] for B) -> the section's own plane in paper coordinates,
# and the crest normal angle there
_SECTION_FRAMES = {
    ("case1", "a"): (np.eye(2), np.pi / 2),                                   # (x1, x2) = (x, z)
    ("case1", "b"): (np.array([[0.0, 1.0], [-1.0, 0.0]]), 0.0),               # (x2, x3) = (z, −y)
    ("case2", "a"): (np.diag([1.0, -1.0]), -np.pi / 2),                        # (x1, x3) = (x, −z)
    ("case2", "b"): (-np.eye(2), -np.pi / 2),                                  # (x2, x3) = (−y, −z)
}


def polar_radius(case: str, which: str, angle: np.ndarray, d: float = 2.0) -> np.ndarray:
    """``r(φ)`` (which = "a") or ``s(ψ)`` (which = "b") of §4.1.2, in the short forms above."""
    angle = np.asarray(angle, dtype=float)
    if case == "case1":
        e2 = d * d - 1.0
        return e2 / (d - np.sin(angle)) if which == "a" else e2 / (d * np.cos(angle) - 1.0)
    if case == "case2":
        return 1.0 / (1.0 - np.sin(angle))
    raise GeometryError(f"principal sections exist for case1 and case2, not {case!r}", element="case")


def section_generators(case: str, which: str, angle: np.ndarray, support: np.ndarray, d: float = 2.0) -> np.ndarray:
    """``G(φ) (k, 4)`` (which = "a") or ``H(ψ) (k, 4)`` (which = "b") from normal angles and support values."""
    r = polar_radius(case, which, angle, d)
    c, s, z = np.cos(angle), np.sin(angle), np.zeros_like(angle)
    if case == "case1":
        normal = np.stack([c, s, z], -1) if which == "a" else np.stack([z, c, s], -1)
    else:
        normal = np.stack([c, z, s], -1) if which == "a" else np.stack([z, c, s], -1)
    return r[:, None] * np.concatenate([normal, support[:, None]], axis=-1)


def section_constant(case: str, a: float, d: float = 2.0) -> np.ndarray:
    """The constant ``c`` of the translation net ``G(φ) + H(ψ) − c``."""
    if case == "case1":
        return np.array([0.0, d + 1.0, 0.0, a * (d + 1.0)])
    return np.array([0.0, 0.0, -0.5, 0.5 * a])


def max_turn(case: str, which: str, d: float) -> float:
    """Largest normal turn from the crest that the polar representation allows."""
    if case == "case1" and which == "b":
        return float(np.arccos(1.0 / d))
    return float(np.pi)


def _face_params(curve: PlanarCurve, faces: int, sampling: str, section: ConvexSection | None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Curve parameters of the ``faces`` face samples plus one ghost beyond each end, and their arclengths.

    Face ``k`` sits at the middle of the ``k``-th of ``faces`` equal pieces (of arclength or of normal
    angle), the ghosts half a piece beyond the ends, so the mesh's boundary vertices fall near the
    curve's end points.
    """
    t, s = curve.arclength_table(extend=0.5 * (curve.t1 - curve.t0) / faces + 1e-9)
    length = float(np.interp(curve.t1, t, s))
    k = np.arange(-1, faces + 1) + 0.5
    if sampling == "arclength" or section is None:
        sk = k * length / faces
        return np.interp(sk, s, t), sk
    a0, a1 = section.angle(np.array([curve.t0, curve.t1]))
    phi = a0 + k * (a1 - a0) / faces
    tk = section.params_at_angles(phi)
    return tk, np.interp(tk, t, s)


def _prepare(points, case: str, which: str, kind: str, faces: int, sampling: str, d: float,
             degree: int) -> tuple[ConvexSection, np.ndarray, np.ndarray]:
    frame, crest = _SECTION_FRAMES[(case, which)]
    name = f"section_{which}"
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise DesignError(name, f"needs a list of [{'x' if which == 'a' else 'y'}, z] points, got shape {p.shape}")
    q = p @ frame.T
    curve = PlanarCurve.from_points(q, name=name) if kind == "interpolate" else \
        PlanarCurve.from_control_points(q, degree=degree, name=name)
    # ghost margin in curve parameter: half a face beyond each end (twice for safety with angle sampling)
    margin = (curve.t1 - curve.t0) / faces
    sec = ConvexSection.prepare(curve, crest, margin=margin, max_turn=max_turn(case, which, d))
    tk, sk = _face_params(curve, faces, sampling, sec)
    if tk[0] < curve.t0 - margin or tk[-1] > curve.t1 + margin:
        raise DesignError(name, "the angle sampling needs the curve far beyond its ends; use sampling = 'arclength'")
    return sec, tk, sk


def sections_grid(section_a, section_b, faces_a: int, faces_b: int, case: str = "case1", d: float = 2.0,
                  curve: str = "interpolate", sampling: str = "arclength", degree: int = 3,
                  check: bool = True) -> QuadGrid:
    """The conical PP mesh with principal sections A (``[x, z]`` points) and B (``[y, z]`` points).

    Parameters
    ----------
    section_a : (k, 2) float — section A in the ``xz`` plane (through-points or control points)
    section_b : (k, 2) float — section B in the ``yz`` plane
    faces_a, faces_b : number of faces along A (rows of faces) and along B
    case : ``"case1"`` (needs ``d > 1``) or ``"case2"``
    d : the Case 1 shape parameter (larger ``d``: closer to a surface of revolution; section B may
        turn its normal by at most ``arccos(1/d)`` from the crest)
    curve : ``"interpolate"`` (spline through the points) or ``"bspline"`` (control points)
    sampling : ``"arclength"`` (equal panel lengths along the sections) or ``"angle"`` (equal normal turn)
    check : raise :class:`~ppfab.errors.FoldError` when the mesh folds

    Returns
    -------
    QuadGrid ``(faces_a + 1, faces_b + 1)`` in the ``z_up`` frame with support planes, face image,
    node axes and ``meta`` (support values, normal angles ``phi``, ``psi``, arclengths ``s_a``, ``s_b``).
    """
    if case not in ("case1", "case2"):
        raise GeometryError(f"principal sections exist for case1 and case2, not {case!r}", element="case")
    if case == "case1" and not d > 1.0:
        raise GeometryError(f"case1 needs d > 1, got d = {d}", element="d", value=float(d))
    sec_a, ta, sa = _prepare(section_a, case, "a", curve, faces_a, sampling, d, degree)
    pb = np.asarray(section_b, dtype=float)
    sec_b, tb, sb = _prepare(pb, case, "b", curve, faces_b, sampling, d, degree)
    a_val = float(sec_a.support(np.array([sec_a.crest_t]))[0])
    b_val = float(sec_b.support(np.array([sec_b.crest_t]))[0])
    size = max(np.ptp(np.asarray(section_a, float), axis=0).max(), np.ptp(pb, axis=0).max())
    if abs(a_val - b_val) > 1e-6 * size:
        za, zb = _crest_height(case, a_val), _crest_height(case, b_val)
        raise DesignError("section_b", f"the sections do not meet: section_a is horizontal at z = {za:.6g}, "
                                       f"section_b at z = {zb:.6g} (difference {abs(za - zb):.3g}); they must cross "
                                       f"where both are horizontal (§4.1.2)")
    phi, psi = sec_a.angle(ta), sec_b.angle(tb)
    ga, hb = sec_a.support(ta), sec_b.support(tb) + (a_val - b_val)
    G = section_generators(case, "a", phi, ga, d)
    c = section_constant(case, a_val, d)
    for attempt in range(2):
        order = slice(None) if attempt == 0 else slice(None, None, -1)
        H = section_generators(case, "b", psi[order], hb[order], d)
        grid = pp_from_face_image(G, H, c)
        assert grid.face_image is not None, "pp_from_face_image sets the face image"
        s = orientation_sign(grid, grid.face_image)
        if (s > 0).sum() >= (s < 0).sum():
            break
    meta = {**grid.meta, "case": case, "d": float(d) if case == "case1" else None, "a": a_val,
            "phi": phi, "psi": psi[order], "s_a": sa, "s_b": sb[order],
            "support_a": ga, "support_b": hb[order], "crest": _crest_point(case, sec_a, sec_b)}
    grid = replace(grid, meta=meta)
    if check:
        check_folds(grid, sa[1:-1], sb[order][1:-1], context=f"conical_sections ({case})", names=("s_a", "s_b"))
    grid = rigid_motion(grid, FRAMES[case])
    assert grid.axes is not None and grid.extended_face_image is not None, \
        "pp_from_face_image sets the axes and extended face image"
    return replace(grid, axes=orient_axes(grid.axes, grid.extended_face_image))


def _crest_height(case: str, support_value: float) -> float:
    """Height z of the crest from the common support value (the crest tangent plane is z = −a resp. z = a)."""
    return -support_value


def _crest_point(case: str, sec_a: ConvexSection, sec_b: ConvexSection) -> np.ndarray:
    """The crossing point of the sections in output coordinates ``(x_A, y_B, z)``."""
    pa, pb = sec_a.crest_point, sec_b.crest_point
    if case == "case1":                     # A: (x1, x2), B: (x2, x3); output (x1, −x3, x2)
        return np.array([pa[0], -pb[1], pa[1]])
    return np.array([pa[0], pb[0] * -1.0, -pa[1]])   # A: (x1, x3), B: (x2, x3); output (x1, −x2, −x3)


# -- design-file method ----------------------------------------------------------------------------

@dataclass(frozen=True)
class ConicalSectionsParams:
    """Conical PP mesh from its two principal planar sections (§4.1.2)."""

    section_a: list[list[float]] = param(doc="section A in the xz plane: [x, z] points (crest normal +z)",
                                         min_length=2)
    section_b: list[list[float]] = param(doc="section B in the yz plane: [y, z] points, horizontal at the same z",
                                         min_length=2)
    case: str = param("case1", doc="case1 (orthogonal pencils, needs d > 1) or case2 (parabolic pencils)",
                      choices=("case1", "case2"))
    d: float = param(3.0, doc="case1 shape parameter d > 1; section B may turn by at most arccos(1/d) from +z")
    curve: str = param("interpolate", doc="interpolate: spline through the points; bspline: control points",
                       choices=("interpolate", "bspline"))
    degree: int = param(3, doc="B-spline degree (curve = 'bspline')", min=1, max=5)
    faces_a: int = param(16, doc="number of faces along section A", min=2, max=4000)
    faces_b: int = param(12, doc="number of faces along section B", min=2, max=4000)
    sampling: str = param("arclength", doc="arclength: equal panel lengths along the sections; angle: equal turn",
                          choices=("arclength", "angle"))

    def __post_init__(self):
        if self.case == "case1" and not self.d > 1.0:
            raise DesignError("d", f"case1 needs d > 1 (e = sqrt(d² − 1) must be real), got {self.d}")
        for name in ("section_a", "section_b"):
            pts = getattr(self, name)
            for k, p in enumerate(pts):
                if len(p) != 2:
                    raise DesignError(f"{name}[{k}]", f"needs 2 coordinates, got {len(p)}")
            need = 4 if self.curve == "interpolate" else 2
            if len(pts) < need:
                raise DesignError(name, f"needs at least {need} points for curve = '{self.curve}', got {len(pts)}")


@construction("conical_sections", ConicalSectionsParams,
              "conical PP mesh designed by its two principal planar sections (support functions, eqs. 14/15)",
              planar_families=("rows", "cols"), section="§4.1.2")
def build_conical_sections(p: ConicalSectionsParams) -> QuadGrid:
    return sections_grid(p.section_a, p.section_b, p.faces_a, p.faces_b, case=p.case, d=p.d, curve=p.curve,
                         sampling=p.sampling, degree=p.degree)

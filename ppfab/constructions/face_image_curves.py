"""PP meshes from sampled face-image curves ``g(u)``, ``h(v)`` (Prop. 3.1, eqs. 7–8).

The design-file form gives ``g`` and ``h`` as polynomial curves in R^4
(coefficient lists, lowest degree first, one list per coordinate), sampled
at uniform face parameters; this is the bundled default "face image" method
and the simplest way to write any PP mesh down.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DesignError
from ..faceimage import pp_from_curves
from ..mesh import QuadGrid
from ..schema import param
from .registry import construction


@dataclass(frozen=True)
class FaceImageCurvesParams:
    """Polynomial curves ``g(u)``, ``h(v)`` in R^4; ``f(u, v) = g(u) + h(v) − c`` (eq. 8)."""

    g: list[list[float]] = param(doc="4 coefficient lists (x, y, z, d components of g), lowest degree first", length=4)
    h: list[list[float]] = param(doc="4 coefficient lists of h(v)", length=4)
    c: list[float] = param([0.0, 0.0, 0.0, 0.0], doc="the constant c of eq. (8)", length=4)
    u_range: list[float] = param([0.0, 1.0], doc="parameter interval of u (faces)", length=2)
    v_range: list[float] = param([0.0, 1.0], doc="parameter interval of v (faces)", length=2)
    faces_u: int = param(10, doc="number of faces along u (rows of faces)", min=2, max=4000)
    faces_v: int = param(10, doc="number of faces along v", min=2, max=4000)

    def expected_vertices(self) -> int:
        """Vertices of the mesh this record builds (checked before building)."""
        return (self.faces_u + 1) * (self.faces_v + 1)

    def __post_init__(self):
        for name in ("g", "h"):
            if any(len(cf) == 0 for cf in getattr(self, name)):
                raise DesignError(name, "every coordinate needs at least one coefficient")
        for name in ("u_range", "v_range"):
            a, b = getattr(self, name)
            if not a < b:
                raise DesignError(name, f"needs start < end, got [{a}, {b}]")


def polynomial_curve(coeffs: list[list[float]]):
    """``t -> (len(t), 4)`` evaluating one polynomial per coordinate (coefficients lowest degree first)."""
    cs = [np.asarray(c, dtype=float)[::-1] for c in coeffs]
    return lambda t: np.stack([np.polyval(c, t) for c in cs], axis=-1)


@construction("face_image_curves", FaceImageCurvesParams,
              "PP mesh from polynomial face-image curves g(u), h(v) in R^4 (eq. 7/8)", section="§3.1, §3.2.1")
def build_face_image_curves(p: FaceImageCurvesParams) -> QuadGrid:
    u = np.linspace(p.u_range[0], p.u_range[1], p.faces_u)
    v = np.linspace(p.v_range[0], p.v_range[1], p.faces_v)
    return pp_from_curves(polynomial_curve(p.g), polynomial_curve(p.h), u, v, np.asarray(p.c))

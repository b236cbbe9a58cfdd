"""PP meshes as discrete bisector and radical-plane surfaces of two polylines (§3.1.3, Fig. 8).

A sphere ``Σ_g: |x|² + g[:3]·x + g[3] = 0`` (centre ``p``, radius ``r``:
``g = (−2p, |p|² − r²)``, :func:`~ppfab.planes.sphere_to_plane_coordinates`) and
another ``Σ_h`` have the radical plane ``g − h`` (the difference of their
equations); for points (``r = 0``) it is the bisector plane of ``p_g`` and
``p_h``.  With spheres ``g_0 … g_{m+1}`` along one polyline and
``h_0 … h_{n+1}`` along another, ``f_{a,b} = g_a − h_b`` is a translation net
(eq. 7 with ``h ↦ −h``): the face image of a PP mesh whose face planes are the
radical (bisector) planes.  The first and last sphere of each polyline give the
ghost faces, so the mesh has ``m × n`` faces and ``(m+1) × (n+1)`` vertices,
and every face plane, boundary ones included, is a bisector/radical plane of
given data.

Changing the radii changes only the 4th coordinates, so the face normals
``−2(p_g − p_h)`` stay and the mesh is replaced by a parallel mesh (Fig. 8 right).
Support planes: ``U_i = g_{i+1} − g_i`` is the radical plane of two consecutive
spheres of the first polyline (bisector of two consecutive points).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ppfab import planes as pl
from ..errors import DesignError, GeometryError
from ..faceimage import pp_from_face_image
from ..mesh import QuadGrid
from ..schema import param
from .registry import construction


def _spheres(points, radii, what: str) -> np.ndarray:
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] not in (3, 4):
        raise GeometryError(f"{what}: needs (k, 3) points or (k, 4) spheres [x, y, z, r], got shape {p.shape}",
                            element=what)
    if p.shape[1] == 4:
        if radii is not None:
            raise GeometryError(f"{what}: radii given twice (4th column and the radii argument)", element=what)
        return p
    r = np.zeros(len(p)) if radii is None else np.broadcast_to(np.asarray(radii, dtype=float), (len(p),))
    return np.concatenate([p, r[:, None]], axis=1)


def bisector_mesh(g_points: np.ndarray, h_points: np.ndarray, g_radii: np.ndarray | float | None = None,
                  h_radii: np.ndarray | float | None = None, min_sine: float = 1e-9) -> QuadGrid:
    """PP mesh whose face planes are the bisector (radical) planes of two polylines of points (spheres).

    Parameters
    ----------
    g_points : (m+2, 3) points or (m+2, 4) spheres ``[x, y, z, r]``
    h_points : (n+2, 3) or (n+2, 4)
    g_radii, h_radii : radii for 3-column input (scalar or per point; default 0 = bisector planes)

    Returns
    -------
    QuadGrid ``(m+1, n+1)``: face ``f[i, j]`` lies in the radical plane of sphere
    ``g_{i+1}`` and ``h_{j+1}``; ``extended_face_image`` holds all
    ``(m+2) × (n+2)`` planes ``g_a − h_b``.

    Raises
    ------
    GeometryError naming the coinciding centres (no bisector plane) or the
    consecutive concentric spheres (no support plane).

    Examples
    --------
    >>> g = [[s, 0.0, 1.0] for s in (-1, 0, 1, 2)]     # two skew lines: a hyperbolic paraboloid
    >>> h = [[0.0, t, -1.0] for t in (-1, 0, 1)]
    >>> bisector_mesh(g, h).shape
    (3, 2)
    """
    G = _spheres(g_points, g_radii, "g")
    H = _spheres(h_points, h_radii, "h")
    for name, S in (("g", G), ("h", H)):
        if len(S) < 3:
            raise GeometryError(f"polyline {name} needs at least 3 points (one face plus a ghost face at each end), "
                                f"got {len(S)}", element=name)
        if not np.all(np.isfinite(S)):
            raise GeometryError(f"polyline {name} has non-finite coordinates", element=name)
        step = np.linalg.norm(np.diff(S[:, :3], axis=0), axis=1)
        size = float(np.linalg.norm(np.ptp(S[:, :3], axis=0))) or 1.0
        if step.min() <= 1e-12 * size:
            k = int(np.argmin(step))
            raise GeometryError(f"points {name}_{k} and {name}_{k + 1} have the same centre: their radical plane (the "
                                f"support plane {'U' if name == 'g' else 'W'}_{k}) does not exist",
                                element=f"{name}_{k}", value=float(step[k]))
    gap = np.linalg.norm(G[:, None, :3] - H[None, :, :3], axis=-1)
    scale = float(np.linalg.norm(np.ptp(np.concatenate([G[:, :3], H[:, :3]]), axis=0))) or 1.0
    if gap.min() <= 1e-12 * scale:
        a, b = (int(k) for k in np.unravel_index(np.argmin(gap), gap.shape))
        raise GeometryError(f"g_{a} and h_{b} have the same centre: they have no bisector/radical plane "
                            f"(face image point {a},{b})", element=f"g_{a}, h_{b}", value=float(gap[a, b]))
    g = pl.sphere_to_plane_coordinates(G)
    h = -pl.sphere_to_plane_coordinates(H)
    grid = pp_from_face_image(g, h, None, min_sine=min_sine)
    grid = replace(grid, meta={**grid.meta, "g_spheres": G, "h_spheres": H})
    return grid


@dataclass(frozen=True)
class BisectorParams:
    """Two polylines of points or spheres; the face planes are their bisector / radical planes (§3.1.3)."""

    g: list[list[float]] = param(doc="first polyline: points [x, y, z] or spheres [x, y, z, r]; first and last "
                                     "give the ghost faces (mesh rows of faces = len(g) - 2)", min_length=3)
    h: list[list[float]] = param(doc="second polyline (mesh columns of faces = len(h) - 2)", min_length=3)
    g_radius: float = param(0.0, doc="radius added to every sphere of g (changing it gives a parallel mesh)")
    h_radius: float = param(0.0, doc="radius added to every sphere of h")

    def __post_init__(self):
        for name in ("g", "h"):
            for k, e in enumerate(getattr(self, name)):
                if len(e) not in (3, 4):
                    raise DesignError(f"{name}[{k}]", f"needs [x, y, z] or [x, y, z, r], got {len(e)} numbers")
            widths = {len(e) for e in getattr(self, name)}
            if len(widths) > 1:
                raise DesignError(name, "mixes points [x, y, z] and spheres [x, y, z, r]; use one form")
        try:
            bisector_mesh(*self.spheres())
        except GeometryError as exc:
            raise DesignError(_key_of(exc.element), str(exc)) from None

    def spheres(self) -> tuple[np.ndarray, np.ndarray]:
        out = []
        for name, extra in (("g", self.g_radius), ("h", self.h_radius)):
            S = np.asarray(getattr(self, name), dtype=float)
            if S.shape[1] == 3:
                S = np.concatenate([S, np.zeros((len(S), 1))], axis=1)
            S = S.copy()
            S[:, 3] += extra
            out.append(S)
        return out[0], out[1]


def _key_of(element: str | None) -> str:
    """Design-file key of an element name such as ``g_3`` (→ ``g[3]``); vertex failures blame ``g``."""
    head = (element or "").split(",")[0].strip()
    name, _, k = head.partition("_")
    return f"{name}[{k}]" if name in ("g", "h") and k.isdigit() else (name if name in ("g", "h") else "g")


@construction("bisector", BisectorParams,
              "PP mesh whose faces are the bisector (radical) planes of two polylines of points (spheres)",
              section="§3.1.3")
def build_bisector(p: BisectorParams) -> QuadGrid:
    G, H = p.spheres()
    return bisector_mesh(G, H)

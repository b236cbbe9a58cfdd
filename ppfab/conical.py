"""Conical meshes: residuals, cone axes (node axes) and offsets (§2.1.3, §2.3.3, §4).

A quad mesh with planar faces is *conical* when the faces around every vertex
touch a common cone of revolution (§2.3.3).  Equivalent tests, both measured here:

* the angle balance ``α1 + α3 = α2 + α4`` of the four face angles at an
  interior vertex (:func:`ppfab.metrics.grid_conical_residual`);
* the four unit face normals around a vertex are concyclic on ``S²``: they lie
  in a plane ``a·n = cos θ`` whose normal ``a`` is the cone axis (the vertices of
  the circular mesh ``M°_N`` of §4, Fig. 15).

The cone axes are the node axes of the canonical torsion-free support
structure (bisector planes of adjacent faces, §2.3.3).  Shifting every face
plane by the same distance ``δ`` along its unit normal keeps the mesh conical
(a Laguerre transform, §2.1.3); vertex ``v`` moves to ``v + δ a / (a·n)``.

Boundary vertices use the *extended* face planes of the grid: the ghost faces
one step beyond each side that the constructions keep in
``meta["extended_face_image"]`` (:mod:`ppfab.faceimage`).  The extended array has
shape ``(rows + 1, cols + 1, 4)`` for a grid of ``rows × cols`` vertices and
vertex ``v[i, j]`` is surrounded by ``E[i, j], E[i+1, j], E[i+1, j+1], E[i, j+1]``
(for a closed grid ``E[:, b]`` is face column ``(b − 1) mod cols``).  Without
stored ghosts a boundary face is repeated as its own ghost, which makes the
boundary axis the bisector of its faces.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from . import planes as pl
from .errors import GeometryError
from .mesh import QuadGrid
from .metrics import face_planarity, grid_conical_residual, plane_residual, polyline_planarity


# -- extended face planes -----------------------------------------------------------------

def extended_planes(grid: QuadGrid) -> np.ndarray:
    """Unit face planes with one ghost face beyond each side, ``(rows + 1, cols + 1, 4)``.

    Taken from ``meta["extended_face_planes"]`` (unit planes of a conical P
    construction) or ``meta["extended_face_image"]`` (the weighted face image of a
    PP construction, orientation of the weights kept) when the construction stored it
    and every vertex still lies on its four stored planes; otherwise the grid's corner-order
    face planes padded by repeating the boundary faces.
    """
    rows, cols = grid.shape
    size = float(np.linalg.norm(np.ptp(grid.vertices.reshape(-1, 3), axis=0))) or 1.0
    for key in ("extended_face_planes", "extended_face_image"):
        stored = grid.meta.get(key)
        if stored is not None:
            E = np.asarray(stored, dtype=float)
            if E.shape == (rows + 1, cols + 1, 4):
                E = pl.normalize(E)
                # stale planes (vertices changed after construction) are ignored
                if np.abs(pl.evaluate(vertex_planes(grid, E), grid.vertices[..., None, :])).max() <= 1e-7 * size:
                    return E
    f = grid.face_planes
    if grid.closed:
        f = np.concatenate([f[:, -1:], f], axis=1)
    else:
        f = np.concatenate([f[:, :1], f, f[:, -1:]], axis=1)
    return np.concatenate([f[:1], f, f[-1:]], axis=0)


def vertex_planes(grid: QuadGrid, E: np.ndarray | None = None) -> np.ndarray:
    """The four face planes around every vertex in cyclic order, ``(rows, cols, 4, 4)``."""
    E = extended_planes(grid) if E is None else np.asarray(E, dtype=float)
    return np.stack([E[:-1, :-1], E[1:, :-1], E[1:, 1:], E[:-1, 1:]], axis=-2)


# -- cone axes -------------------------------------------------------------------------------

def axis_of_normals(normals: np.ndarray, degenerate: float = 1e-12) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Axis of the circle through unit normals ``(..., k, 3)`` on ``S²``.

    The axis ``a`` is the normal of the least-squares plane ``a·n = c`` through
    the ``k`` points.  When the points do not span a plane (two distinct normals,
    e.g. on a cylinder or at a boundary with repeated ghosts) the axis is the
    direction in the null space closest to the mean normal (the bisector).

    Returns
    -------
    axis : (..., 3) unit, turned to the side of the normals (``a·n > 0``)
    cos : (...,) mean ``a·n_k`` (cosine of the cone's half opening towards the faces)
    residual : (...,) largest distance of a normal from the plane (0 when concyclic)
    """
    n = np.asarray(normals, dtype=float)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    mean = n.mean(axis=-2)
    y = n - mean[..., None, :]
    cov = np.einsum("...ki,...kj->...ij", y, y)
    w, vec = np.linalg.eigh(cov)
    top = np.maximum(w[..., 2:3], 1e-300)
    small = w <= w[..., :1] + degenerate * top                     # (..., 3) eigen-directions in the null space
    small = small | (w[..., 2:3] <= 1e-28)                         # all normals equal: any axis, take the mean
    coef = np.einsum("...ik,...i->...k", vec, mean) * small         # components of the mean in the null space
    a = np.einsum("...ik,...k->...i", vec, coef)
    length = np.linalg.norm(a, axis=-1, keepdims=True)
    if np.any(length <= 1e-14):
        idx = tuple(int(k) for k in np.argwhere(length[..., 0] <= 1e-14)[0])
        raise GeometryError(f"the face normals around vertex {idx} do not define a cone axis "
                            f"(they are spread over a great circle)", element=f"vertex {idx}")
    a = a / length
    c = np.einsum("...ki,...i->...k", n, a)
    residual = np.abs(c - c.mean(axis=-1, keepdims=True)).max(axis=-1)
    return a, c.mean(axis=-1), residual


def cone_axes(grid: QuadGrid, inward: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Node axes of a conical mesh: the axes of the vertex cones (§2.3.3).

    Parameters
    ----------
    grid : a conical grid (boundary vertices use the extended face planes)
    inward : turn the axes against the face normals (the side of the beams, as
        :func:`ppfab.faceimage.orient_axes` does); otherwise along them

    Returns
    -------
    axes : (rows, cols, 3) unit
    cos : (rows, cols) ``a·n`` of the faces at each vertex (positive)
    """
    P = vertex_planes(grid)
    a, c, _ = axis_of_normals(P[..., :3])
    return (-a if inward else a), c


def concyclic_residual(grid: QuadGrid) -> np.ndarray:
    """Largest distance of the four unit face normals at a vertex from their common circle, ``(rows, cols)``.

    Points on ``S²`` are concyclic iff coplanar; the value is in radians to
    first order.  At boundary vertices the ghost faces are included.
    """
    P = vertex_planes(grid)
    return axis_of_normals(P[..., :3])[2]


# -- offsets ----------------------------------------------------------------------------------

def offset(grid: QuadGrid, distance: float) -> QuadGrid:
    """The offset of a conical grid at constant face–face distance ``distance`` (§2.1.3).

    Every face plane moves by ``distance`` along its unit normal; vertex ``v``
    moves along its cone axis ``a`` to ``v + distance · a / (a·n)``.  The result
    is parallel to the input (same face normals), hence conical with the same
    planar polyline families; weighted face images are shifted with their
    weights (``F − |F_n| δ e4``), so a PP face image stays a translation net.

    Raises :class:`GeometryError` when a cone degenerates (``a·n ≤ 0.05``) or the
    offset planes do not meet at a vertex (the input is not conical).
    """
    d = float(distance)
    E = extended_planes(grid)
    P = vertex_planes(grid, E)
    a, c, res = axis_of_normals(P[..., :3])
    if np.any(c <= 0.05):
        idx = tuple(int(k) for k in np.argwhere(c <= 0.05)[0])
        raise GeometryError(f"vertex {idx}: its faces make {np.degrees(np.arccos(np.clip(c[idx], -1, 1))):.1f}° "
                            f"with the cone axis; an offset is ill defined", element=f"vertex {idx}", value=float(c[idx]))
    v = grid.vertices + d * a / c[..., None]
    meta = dict(grid.meta)
    for key in ("extended_face_image", "extended_face_planes"):
        if key in meta:
            meta[key] = _shift_planes(np.asarray(meta[key], dtype=float), d)
    meta["offset_distance"] = meta.get("offset_distance", 0.0) + d
    out = replace(grid, vertices=v, face_image=None if grid.face_image is None else _shift_planes(grid.face_image, d),
                  support_u=_refit(v, grid.support_u, rows=True), support_w=_refit(v, grid.support_w, rows=False),
                  meta=meta)
    return out


def _shift_planes(F: np.ndarray, d: float) -> np.ndarray:
    F = np.array(F, dtype=float)
    F[..., 3] -= np.linalg.norm(F[..., :3], axis=-1) * d
    return F


def _refit(v: np.ndarray, old: np.ndarray | None, rows: bool) -> np.ndarray | None:
    """Least-squares planes of the rows (or columns) of ``v``, oriented like ``old``."""
    if old is None:
        return None
    pts = v if rows else v.transpose(1, 0, 2)
    new, _ = pl.fit_plane(pts)
    old = pl.normalize(old)
    sign = np.where(np.einsum("ki,ki->k", new[:, :3], old[:, :3]) < 0, -1.0, 1.0)
    return new * sign[:, None]


# -- rigid motions --------------------------------------------------------------------------

def rigid_motion(grid: QuadGrid, rotation: np.ndarray, translation: np.ndarray | None = None) -> QuadGrid:
    """Apply ``x' = R x + t`` (``R`` a proper rotation) to a grid and all its planes and axes.

    Weighted planes map as ``(n, d) ↦ (R n, d − (R n)·t)``.
    """
    R = np.asarray(rotation, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-12) or np.linalg.det(R) < 0:
        raise GeometryError("rigid_motion needs a proper 3×3 rotation matrix")
    t = np.zeros(3) if translation is None else np.asarray(translation, dtype=float)

    def planes(p):
        if p is None:
            return None
        p = np.asarray(p, dtype=float)
        n = p[..., :3] @ R.T
        return np.concatenate([n, (p[..., 3] - n @ t)[..., None]], axis=-1)

    meta = dict(grid.meta)
    for key in ("extended_face_image", "extended_face_planes"):
        if key in meta:
            meta[key] = planes(meta[key])
    return replace(grid, vertices=grid.vertices @ R.T + t, support_u=planes(grid.support_u),
                   support_w=planes(grid.support_w), face_image=planes(grid.face_image),
                   axes=None if grid.axes is None else grid.axes @ R.T, meta=meta)


# -- one summary --------------------------------------------------------------------------------

@dataclass(frozen=True)
class ConicalQuality:
    """Measured properties of a (supposedly) conical P/PP grid.

    ``angle_max`` — max ``|α1 − α2 + α3 − α4|`` over interior vertices (rad);
    ``concyclic_max`` — max distance of the unit normals from their circle (rad, interior vertices);
    ``delta_f_max`` — max face planarity ``δ_f``;
    ``delta_p_rows_max`` / ``delta_p_cols_max`` — max ``δ_P`` of the row / column polylines;
    ``support_u_max`` / ``support_w_max`` — max distance of rows / columns from the grid's own
    support planes relative to their bounding box (NaN without support planes).
    """

    angle_max: float
    concyclic_max: float
    delta_f_max: float
    delta_p_rows_max: float
    delta_p_cols_max: float
    support_u_max: float
    support_w_max: float

    def as_dict(self) -> dict:
        return asdict(self)


def conical_quality(grid: QuadGrid) -> ConicalQuality:
    """Measure the conical, planar-face and planar-polyline properties of a grid at once."""
    v = grid.vertices
    if grid.closed:
        vv = np.concatenate([v[:, -1:], v, v[:, :1]], axis=1)
        angle = grid_conical_residual(vv) if v.shape[0] >= 3 else np.zeros(1)
        cyc = concyclic_residual(grid)[1:-1]
    else:
        angle = grid_conical_residual(v) if min(v.shape[:2]) >= 3 else np.zeros(1)
        cyc = concyclic_residual(grid)[1:-1, 1:-1]
    su = plane_residual(grid.rows(), grid.support_u).max() if grid.support_u is not None else np.nan
    sw = plane_residual(grid.cols(), grid.support_w).max() if grid.support_w is not None else np.nan
    return ConicalQuality(
        angle_max=float(np.max(angle, initial=0.0)),
        concyclic_max=float(np.max(cyc, initial=0.0)),
        delta_f_max=float(face_planarity(grid.face_corners).max()),
        delta_p_rows_max=float(polyline_planarity(grid.rows()).max()) if v.shape[1] >= 3 else 0.0,
        delta_p_cols_max=float(polyline_planarity(grid.cols()).max()) if v.shape[0] >= 3 else 0.0,
        support_u_max=float(su), support_w_max=float(sw),
    )

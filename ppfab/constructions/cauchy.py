"""PP meshes from Cauchy data (§3.1.2, Fig. 7).

Given the support planes ``U_0 … U_m`` (rows) and ``W_0 … W_n`` (columns)
every vertex is confined to its node axis ``l_ij = U_i ∩ W_j``.  With the
initial vertices ``v_{i,0} ∈ l_{i0}`` and ``v_{0,j} ∈ l_{0j}`` the rest follows:
``v_{i+1,j+1}`` is the intersection of the plane through ``v_{i,j}``,
``v_{i+1,j}``, ``v_{i,j+1}`` with the line ``l_{i+1,j+1}``.  Faces are planar by
construction and every row/column lies in its plane, so the result is an exact
PP mesh.

The propagation is unstable (the paper prefers eq. 7): it breaks down where a
node axis runs (nearly) parallel to the plane it must cross, which happens e.g.
where the Gaussian curvature changes sign.  Such a vertex raises
:class:`~ppfab.errors.GeometryError` naming ``(i, j)`` and the angle.

The sweep runs over anti-diagonals ``i + j = k``: all vertices of one diagonal
are computed in one vectorised step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ppfab import planes as pl
from ..errors import DesignError, GeometryError
from ..mesh import QuadGrid
from ..schema import param
from ppfab.transforms.pp import with_face_image
from .registry import construction


def node_axes_lines(U: np.ndarray, W: np.ndarray, min_angle_deg: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Lines ``U_i ∩ W_j`` as (point ``(m+1, n+1, 3)``, unit direction ``(m+1, n+1, 3)``).

    Raises :class:`GeometryError` naming ``(i, j)`` where ``U_i`` and ``W_j`` meet
    at less than ``min_angle_deg`` (their line is ill defined).
    """
    Un = pl.normalize(U)
    Wn = pl.normalize(W)
    ang = np.degrees(pl.angle_between(Un[:, None, :], Wn[None, :, :]))
    if ang.min() < min_angle_deg:
        i, j = (int(k) for k in np.unravel_index(np.argmin(ang), ang.shape))
        raise GeometryError(f"support planes U_{i} and W_{j} are nearly parallel ({ang[i, j]:.3g}° < "
                            f"{min_angle_deg:g}°): the node axis of vertex ({i}, {j}) is undefined",
                            element=f"vertex ({i}, {j})", value=float(ang[i, j]))
    a = np.broadcast_to(Un[:, None, :], ang.shape + (4,))
    b = np.broadcast_to(Wn[None, :, :], ang.shape + (4,))
    return pl.line_of_two_planes(a, b)


def _on_line(points: np.ndarray, p: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closest points on lines ``(p, d)`` and the distances to them, stacked."""
    foot = p + np.einsum("...i,...i->...", points - p, d)[..., None] * d
    return foot, np.linalg.norm(points - foot, axis=-1)


def cauchy_pp_mesh(U: np.ndarray, W: np.ndarray, first_col: np.ndarray, first_row: np.ndarray,
                   min_angle_deg: float = 1.0, snap_tolerance: float = 1e-9) -> QuadGrid:
    """Propagate a PP mesh from Cauchy data (Fig. 7).

    Parameters
    ----------
    U : (m+1, 4) float — row planes ``U_i`` (``n·x + d = 0``)
    W : (n+1, 4) float — column planes ``W_j``
    first_col : (m+1, 3) float — initial vertices ``v_{i,0}`` on ``U_i ∩ W_0``
    first_row : (n+1, 3) float — initial vertices ``v_{0,j}`` on ``U_0 ∩ W_j``
        (``first_col[0]`` and ``first_row[0]`` are both ``v_{0,0}``)
    min_angle_deg : smallest admissible angle between a node axis and the plane
        it is intersected with, and between ``U_i`` and ``W_j``
    snap_tolerance : initial vertices farther than this (relative to the
        diagonal of their bounding box) from their node axis raise; closer ones
        are projected onto it.

    Returns
    -------
    QuadGrid ``(m+1, n+1)`` with support planes, face image and node axes.

    Raises
    ------
    GeometryError naming the vertex ``(i, j)`` and the angle where the propagation breaks down.

    Examples
    --------
    >>> U = np.array([[1, 0, 0.0, -k] for k in range(3)], float)
    >>> W = np.array([[0, 1, 0.0, -k] for k in range(3)], float)
    >>> col = np.array([[k, 0, 0.1 * k * k] for k in range(3)], float)
    >>> row = np.array([[0, k, -0.1 * k * k] for k in range(3)], float)
    >>> float(cauchy_pp_mesh(U, W, col, row).vertices[2, 2, 2])   # a translational surface
    0.0
    """
    U, W = pl.as_planes(U), pl.as_planes(W)
    if U.ndim != 2 or W.ndim != 2 or len(U) < 2 or len(W) < 2:
        raise GeometryError("Cauchy data needs at least 2 planes U_i and 2 planes W_j")
    first_col = np.asarray(first_col, dtype=float)
    first_row = np.asarray(first_row, dtype=float)
    m1, n1 = len(U), len(W)
    if first_col.shape != (m1, 3) or first_row.shape != (n1, 3):
        raise GeometryError(f"initial vertices need shapes ({m1}, 3) (v_i0) and ({n1}, 3) (v_0j), "
                            f"got {first_col.shape} and {first_row.shape}")
    for name, planes in (("U", U), ("W", W)):
        nrm = np.linalg.norm(planes[:, :3], axis=1)
        if nrm.min() <= 1e-12 * max(1.0, float(np.abs(planes).max())):
            k = int(np.argmin(nrm))
            raise GeometryError(f"support plane {name}_{k} is degenerate (zero normal)", element=f"{name}_{k}")
    P, D = node_axes_lines(U, W, min_angle_deg)
    size = _size(np.concatenate([first_col, first_row]))
    col, dcol = _on_line(first_col, P[:, 0], D[:, 0])
    row, drow = _on_line(first_row, P[0, :], D[0, :])
    for dist, label, axis in ((dcol, "v_{k},0", "U_{k} ∩ W_0"), (drow, "v_0,{k}", "U_0 ∩ W_{k}")):
        k = int(np.argmax(dist))
        if dist[k] > snap_tolerance * size:
            raise GeometryError(f"initial vertex {label.format(k=k)} is {dist[k]:.3g} away from its node axis "
                                f"{axis.format(k=k)} (allowed {snap_tolerance * size:.3g})",
                                element=label.format(k=k), value=float(dist[k]))
    gap = float(np.linalg.norm(col[0] - row[0]))
    if gap > snap_tolerance * size:
        raise GeometryError(f"the two initial polylines must start at the same vertex v_00; they are {gap:.3g} apart",
                            element="v_00", value=gap)
    v = np.zeros((m1, n1, 3))
    v[:, 0] = col
    v[0, :] = row
    v[0, 0] = 0.5 * (col[0] + row[0])
    sin_min = np.sin(np.radians(min_angle_deg))
    for k in range(2, m1 + n1 - 1):
        i = np.arange(max(1, k - n1 + 1), min(k - 1, m1 - 1) + 1)     # target vertices (i, j), i + j = k
        j = k - i
        a, b, c = v[i - 1, j - 1], v[i, j - 1], v[i - 1, j]
        nrm = np.cross(b - a, c - a)
        length = np.linalg.norm(nrm, axis=-1)
        span = np.linalg.norm(b - a, axis=-1) * np.linalg.norm(c - a, axis=-1)
        sin_corner = length / np.where(span == 0, 1.0, span)
        if np.any(sin_corner < sin_min):
            q = int(np.argmin(sin_corner))
            ii, jj = int(i[q]), int(j[q])
            raise GeometryError(f"Cauchy propagation breaks down at vertex ({ii}, {jj}): face ({ii - 1}, {jj - 1}) "
                                f"has collapsed, its edges at v[{ii - 1}, {jj - 1}] meet at "
                                f"{np.degrees(np.arcsin(min(1.0, sin_corner[q]))):.3g}°",
                                element=f"vertex ({ii}, {jj})", value=float(np.degrees(np.arcsin(min(1.0, sin_corner[q])))))
        nrm = nrm / length[:, None]
        p, d = P[i, j], D[i, j]
        nd = np.einsum("ki,ki->k", nrm, d)
        if np.any(np.abs(nd) < sin_min):
            q = int(np.argmin(np.abs(nd)))
            ii, jj = int(i[q]), int(j[q])
            angle = float(np.degrees(np.arcsin(min(1.0, abs(nd[q])))))
            raise GeometryError(f"Cauchy propagation breaks down at vertex ({ii}, {jj}): the node axis "
                                f"U_{ii} ∩ W_{jj} meets the plane through v[{ii - 1}, {jj - 1}], v[{ii}, {jj - 1}], "
                                f"v[{ii - 1}, {jj}] at {angle:.3g}° (< {min_angle_deg:g}°)",
                                element=f"vertex ({ii}, {jj})", value=angle)
        t = np.einsum("ki,ki->k", nrm, a - p) / nd
        v[i, j] = p + t[:, None] * d
    if not np.all(np.isfinite(v)):
        raise GeometryError("Cauchy propagation produced non-finite vertices")
    grid = QuadGrid(v, support_u=pl.normalize(U), support_w=pl.normalize(W))
    return with_face_image(grid)


def _size(points: np.ndarray) -> float:
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) or 1.0


@dataclass(frozen=True)
class CauchyParams:
    """Support planes and the two initial polylines of a PP mesh (Fig. 7)."""

    support_u: list[list[float]] = param(doc="row planes U_0..U_m, each [nx, ny, nz, d] (n·x + d = 0)",
                                         min_length=2)
    support_w: list[list[float]] = param(doc="column planes W_0..W_n, each [nx, ny, nz, d]", min_length=2)
    boundary_u: list[list[float]] = param(doc="initial vertices v_00..v_m0 ([x, y, z], v_i0 on U_i ∩ W_0)",
                                          min_length=2)
    boundary_w: list[list[float]] = param(doc="initial vertices v_00..v_0n ([x, y, z], v_0j on U_0 ∩ W_j); "
                                              "the first equals boundary_u's first", min_length=2)
    snap_tolerance: float = param(1e-3, doc="initial vertices are projected onto their node axes; farther than this "
                                            "times the size of the initial polylines is an error", min=0)
    min_angle_deg: float = param(1.0, doc="propagation breaks down (error) where a node axis meets the plane it "
                                          "is intersected with at less than this angle", exclusive_min=0, max=45)

    def __post_init__(self):
        for name, width in (("support_u", 4), ("support_w", 4), ("boundary_u", 3), ("boundary_w", 3)):
            for k, entry in enumerate(getattr(self, name)):
                if len(entry) != width:
                    raise DesignError(f"{name}[{k}]", f"needs {width} numbers, got {len(entry)}")
        for name in ("support_u", "support_w"):
            for k, entry in enumerate(getattr(self, name)):
                if not any(entry[:3]):
                    raise DesignError(f"{name}[{k}]", "plane has a zero normal vector (degenerate plane)")
        for a, b in (("boundary_u", "support_u"), ("boundary_w", "support_w")):
            if len(getattr(self, a)) != len(getattr(self, b)):
                raise DesignError(a, f"needs one vertex per plane of {b}: {len(getattr(self, b))}, "
                                     f"got {len(getattr(self, a))}")
        # geometric preconditions, reported against the design-file keys
        U, W = np.asarray(self.support_u, float), np.asarray(self.support_w, float)
        try:
            P, D = node_axes_lines(U, W, self.min_angle_deg)
        except GeometryError as exc:
            raise DesignError("support_w", str(exc)) from None
        pts = np.concatenate([np.asarray(self.boundary_u, float), np.asarray(self.boundary_w, float)])
        tol = self.snap_tolerance * _size(pts)
        for name, lines, fmt in (("boundary_u", (P[:, 0], D[:, 0]), "U_{k} ∩ W_0"),
                                 ("boundary_w", (P[0, :], D[0, :]), "U_0 ∩ W_{k}")):
            _, dist = _on_line(np.asarray(getattr(self, name), float), *lines)
            k = int(np.argmax(dist))
            if dist[k] > tol:
                raise DesignError(f"{name}[{k}]", f"vertex is {dist[k]:.4g} away from its node axis "
                                                  f"{fmt.format(k=k)} (allowed {tol:.3g} = snap_tolerance x size)")
        gap = float(np.linalg.norm(np.subtract(self.boundary_u[0], self.boundary_w[0])))
        if gap > tol:
            raise DesignError("boundary_w[0]", f"must be the same vertex v_00 as boundary_u[0]; they are "
                                               f"{gap:.4g} apart (allowed {tol:.3g})")


@construction("cauchy", CauchyParams, "PP mesh propagated from support planes and two initial polylines (Fig. 7)",
              section="§3.1.2")
def build_cauchy(p: CauchyParams) -> QuadGrid:
    U, W = np.asarray(p.support_u, float), np.asarray(p.support_w, float)
    P, D = node_axes_lines(U, W, p.min_angle_deg)
    col, _ = _on_line(np.asarray(p.boundary_u, float), P[:, 0], D[:, 0])     # snapped onto the node axes
    row, _ = _on_line(np.asarray(p.boundary_w, float), P[0, :], D[0, :])
    col[0] = row[0] = 0.5 * (col[0] + row[0])
    return cauchy_pp_mesh(U, W, col, row, p.min_angle_deg, snap_tolerance=1e-9)

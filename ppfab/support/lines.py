"""Which mesh polylines carry planar beams: their planes, and the polylines left out of the planar families.

A polyline of a P or PP mesh is a planar beam when its vertices lie in a plane that is also a support plane:
the node axes of its vertices lie in that plane (§3.1).  :func:`polyline_planes` gives every polyline its
plane:

* polylines of 3 or more vertices that are not straight: the least-squares plane (:func:`ppfab.planes.fit_plane`);
* **straight** polylines (every vertex within ``straight_tolerance`` of the bounding-box diagonal from the
  least-squares line, e.g. the grid lines of a flat mesh): any plane through the line fits, and the one that
  contains the surface normal is taken — the plane through the line spanned by the line direction ``d`` and
  the mean vertex normal ``N̄`` made perpendicular to it, normal ``d × N̄``;
* 2-vertex polylines: ``nan`` (their plane is the support plane of their one edge, found with the axes).

A plane that makes every line in it far from the surface normal cannot carry a beam: an axis in a plane with
unit normal ``n`` is at least ``asin |n·N_v|`` from the unit vertex normal ``N_v``.  The *tilt* of a
polyline is the largest of these angles over its vertices; a polyline tilted by more than the support's
``max_normal_angle_deg`` (a curve lying in a flat part of the surface, whose plane is the tangent plane) is
left out of the planar families by the selector rule ``"tangent"``.

:func:`select_polylines` reads the design keys that choose polylines (``[support] exclude``, ``[beams]
segment``): polyline ids (indices into ``mesh.polylines``) and rule names (:data:`RULES`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ppfab import planes as pl
from ppfab.errors import DesignError
from ppfab.mesh import QuadMesh
from ppfab.metrics import relative_deviation

RULES: dict[str, str] = {
    "tangent": "polylines whose plane is further than support.max_normal_angle_deg from the surface normal at "
               "one of their vertices (no axis in that plane can be near the normal)",
    "boundary": "polylines that run along the boundary (every edge has one face)",
    "closed": "closed polylines (loops)",
    "singular": "polylines that end at a singular vertex (interior valence other than 4)",
    "closed-singular": "closed loops of a mesh with singular vertices",
    "nonplanar": "polylines whose vertices lie further than support.planar_tolerance (relative, δ_P) from "
                 "their plane",
}
"""The selector rules of ``[support] exclude`` and ``[beams] segment``: name → what it selects."""


@dataclass(frozen=True)
class PolylinePlanes:
    """Planes of all polylines of a mesh (see the module docstring).

    ``planes (L, 4)`` unit planes (``nan`` rows for 2-vertex polylines), ``deviation (L,)`` largest distance of
    a vertex from its plane (mesh units), ``relative (L,)`` the same over the bounding-box diagonal (δ_P),
    ``straight (L,)`` the plane was chosen by the straight-line rule, ``tilt_deg (L,)`` largest angle between
    the plane and a vertex normal (``asin |n·N_v|``, degrees; ``nan`` for 2-vertex polylines) and
    ``tilt_vertex (L,)`` the vertex where it is largest (−1 if none).
    """

    planes: np.ndarray
    deviation: np.ndarray
    relative: np.ndarray
    straight: np.ndarray
    tilt_deg: np.ndarray
    tilt_vertex: np.ndarray


def polyline_planes(mesh: QuadMesh, normals: np.ndarray, straight_tolerance: float = 1e-6) -> PolylinePlanes:
    """The plane of every polyline of ``mesh.polylines`` (least squares; the straight-line rule).

    Parameters
    ----------
    mesh : quad mesh
    normals : (N, 3) unit vertex normals
    straight_tolerance : a polyline whose vertices all lie within this fraction of its bounding-box diagonal
        of their least-squares line is straight

    Examples
    --------
    >>> import numpy as np
    >>> from ppfab.mesh import QuadGrid
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(3.0), indexing="ij")
    >>> flat = QuadGrid(np.stack([x, y, 0 * x], axis=-1)).to_quadmesh()
    >>> p = polyline_planes(flat, np.tile([0.0, 0.0, 1.0], (12, 1)))
    >>> bool(p.straight.all()), float(np.abs(p.planes[:, 2]).max())      # planes through the lines, vertical
    (True, 0.0)
    """
    lines = mesh.polylines
    v = mesh.vertices
    L = len(lines)
    planes = np.full((L, 4), np.nan)
    straight = np.zeros(L, dtype=bool)
    groups: dict[int, list[int]] = {}
    for k, p in enumerate(lines):
        if len(p) >= 3:
            groups.setdefault(len(p), []).append(k)
    for length, ks in groups.items():
        idx = np.stack([lines[k].vertices for k in ks])
        x = v[idx]                                              # (g, length, 3)
        c = x.mean(axis=1, keepdims=True)
        y = x - c
        _, s, vt = np.linalg.svd(y, full_matrices=False)        # s (g, 3) descending
        diag = np.linalg.norm(x.max(axis=1) - x.min(axis=1), axis=1)
        line_dev = np.sqrt(np.maximum(np.einsum("gki,gki->gk", y, y)
                                      - np.einsum("gki,gi->gk", y, vt[:, 0]) ** 2, 0.0)).max(axis=1)
        is_straight = line_dev <= straight_tolerance * np.maximum(diag, 1e-300)
        n = vt[:, 2].copy()
        if np.any(is_straight):
            d = vt[is_straight, 0]
            m = normals[idx[is_straight]].mean(axis=1)
            m -= np.einsum("gi,gi->g", m, d)[:, None] * d
            nn = np.cross(d, m)
            length_nn = np.linalg.norm(nn, axis=1)
            ok = length_nn > 1e-12
            nn[ok] /= length_nn[ok, None]
            nn[~ok] = n[is_straight][~ok]
            n[is_straight] = nn
        dd = -np.einsum("gi,gi->g", n, c[:, 0])
        planes[ks] = np.concatenate([n, dd[:, None]], axis=1)
        straight[ks] = is_straight
    dev = np.zeros(L)
    tilt = np.full(L, np.nan)
    tilt_v = -np.ones(L, dtype=np.int64)
    for k, p in enumerate(lines):
        if len(p) < 3:
            continue
        dev[k] = float(np.abs(pl.signed_distance(planes[k], v[p.vertices])).max())
        s = np.abs(normals[p.vertices] @ planes[k, :3])
        j = int(np.argmax(s))
        tilt[k] = float(np.degrees(np.arcsin(min(1.0, s[j]))))
        tilt_v[k] = int(p.vertices[j])
    return PolylinePlanes(planes, dev, relative_deviation(dev, mesh), straight, tilt, tilt_v)


def singular_vertices(mesh: QuadMesh) -> np.ndarray:
    """``(N,)`` bool: interior vertices whose valence is not 4."""
    topo = mesh.topology
    return ~topo.boundary_vertices & (topo.valence != 4)


def select_polylines(mesh: QuadMesh, selectors: Sequence[int | str], key: str,
                     planes: PolylinePlanes | None = None, max_normal_angle_deg: float = 90.0,
                     planar_tolerance: float = np.inf) -> np.ndarray:
    """``(L,)`` bool: the polylines a design key names — ids (indices into ``mesh.polylines``) and rules
    (:data:`RULES`).  ``planes`` is needed by the rules ``tangent`` and ``nonplanar``.

    Raises :class:`~ppfab.errors.DesignError` (naming ``key``) for an id out of range or an unknown rule.
    """
    lines = mesh.polylines
    L = len(lines)
    out = np.zeros(L, dtype=bool)
    topo = mesh.topology
    sing = singular_vertices(mesh)
    for s in selectors:
        if isinstance(s, bool) or not isinstance(s, (int, str)):
            raise DesignError(key, f"expected polyline ids and rule names, got {s!r}")
        if isinstance(s, int):
            if not 0 <= s < L:
                raise DesignError(key, f"polyline {s} does not exist (the mesh has {L} polylines, 0…{L - 1})")
            out[s] = True
            continue
        if s not in RULES:
            from ppfab.schema import suggest

            raise DesignError(key, f"unknown rule {s!r}{suggest(s, list(RULES))}; rules: {', '.join(RULES)}")
        if s in ("tangent", "nonplanar") and planes is None:
            raise DesignError(key, f"rule {s!r} needs the polyline planes")
        for k, p in enumerate(lines):
            vs = p.vertices
            if s == "tangent":
                assert planes is not None
                hit = bool(np.isfinite(planes.tilt_deg[k]) and planes.tilt_deg[k] > max_normal_angle_deg)
            elif s == "nonplanar":
                assert planes is not None
                hit = bool(len(p) >= 3 and planes.relative[k] > planar_tolerance)
            elif s == "boundary":
                hit = bool(topo.boundary_vertices[vs].all()) and _all_boundary_edges(mesh, p)
            elif s == "closed":
                hit = bool(p.closed)
            elif s == "singular":
                hit = bool(not p.closed and (sing[vs[0]] or sing[vs[-1]]))
            else:  # closed-singular
                hit = bool(p.closed and sing.any())
            out[k] |= hit
    return out


def _all_boundary_edges(mesh: QuadMesh, p) -> bool:
    topo = mesh.topology
    n = len(mesh.vertices)
    vs = p.vertices
    a, b = vs[:-1], vs[1:]
    if p.closed and len(vs) > 2:
        a, b = np.r_[a, vs[-1]], np.r_[b, vs[0]]
    keys = np.minimum(a, b) * n + np.maximum(a, b)
    ekey = topo.edges[:, 0] * n + topo.edges[:, 1]
    pos = np.searchsorted(ekey, keys)
    return bool(np.all(topo.edge_face_count[pos] == 1))

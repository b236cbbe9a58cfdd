"""Torsion-free support structures: node axes and support planes (§2.2, Def. 2.3).

A torsion-free support structure of a quad mesh gives every vertex ``v_i`` a
node axis ``A_i`` and every edge ``v_i v_j`` a support plane ``σ_ij`` that
contains both axes ``A_i`` and ``A_j`` (Def. 2.3).  Beams are cut from these
planes: a planar mesh polyline whose axes lie in its plane becomes one planar
beam plate (the P / PP case of §3.1).

The methods that find one, one module each (all return a :class:`SupportStructure`):

* :mod:`ppfab.support.pp` — PP meshes: the axis of ``v_ij`` is the line ``U_i ∩ W_j``
  of the two support planes (§3.1.1), exact wherever the polylines are planar.
* :mod:`ppfab.support.p` — P meshes: axes in the planes of the planar family,
  transverse support planes through consecutive axes; found as a parallel mesh
  whose offsets are constrained to those planes.
* :mod:`ppfab.support.conical` — conical meshes (§2.3.3): the axis of an interior vertex
  is the cone axis, the unit vector making equal angles with the adjacent unit face
  normals; boundary axes from a parallel mesh that keeps the interior fixed.
* :mod:`ppfab.support.parallel` — any planar-quad mesh: a parallel mesh ``M'`` (§2.2.3,
  Fig. 4) near the normal offset, by least squares; the planes through
  corresponding edges of ``M`` and ``M'`` form a torsion-free support structure and
  the axes are ``v'_i − v_i``.  Axes of polylines that are already planar are kept
  in their planes.

Orientation: the mesh's oriented face normals (corner order) point outward;
node axes point to the other side (into the structure, where the beams are).

Torsion (:func:`torsion`) of an edge is the angle between the planes spanned by
the edge and each of its two end axes: zero iff the axes are coplanar with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.topology import FAMILY_NAMES
from ppfab.mesh import QuadGrid, QuadMesh, as_quadmesh  # noqa: F401  (as_quadmesh: imported from here by the methods)
from ppfab.topology import Polyline


@dataclass(frozen=True, eq=False)
class SupportStructure:
    """Node axes and support planes of a quad mesh (Def. 2.3).

    Parameters
    ----------
    mesh : the quad mesh (vertex and face order of the input)
    axes : (N, 3) float, unit node axes, pointing to the inside (against the outward face normals)
    polyline_planes : (L, 4) float, unit plane of each polyline of ``mesh.polylines``
        (the support plane ``U_i``/``W_j`` or a least-squares plane; for 2-vertex polylines
        the support plane of the edge)
    polyline_deviation : (L,) float, largest distance of a polyline's vertices from its plane (mesh units)
    edge_planes : (E, 4) float, unit support plane of each edge of ``mesh.topology.edges``
    planar_families : families (0 rows, 1 cols) whose polylines lie in their planes with the axes
    kind : ``"pp"``, ``"p"``, ``"conical"`` or ``"parallel"``
    meta : solver record (iterations, constraint residual, …)
    polyline_planar : (L,) bool, the polyline's plane is a support plane (its axes lie in it), so the
        polyline can be one planar beam; default: the polylines of ``planar_families``
    left_out : ``(polyline, reason)`` of the polylines that were candidates for planar beams but were left out
        of the planar families (:mod:`ppfab.support.planar`); their edges are beams of one edge each
    planes_at : (N,) int, how many distinct support planes of planar beams pass through each vertex (2: the
        axis is their line, more: the least-squares line, 1 or 0: solved), when the method records it
    misfit : (N,) float, smallest singular value of the stacked unit normals of those planes where more than
        two meet (0 = they share the axis), when recorded
    """

    mesh: QuadMesh
    axes: np.ndarray
    polyline_planes: np.ndarray
    polyline_deviation: np.ndarray
    edge_planes: np.ndarray
    planar_families: tuple[int, ...]
    kind: str
    meta: dict = field(default_factory=dict)
    polyline_planar: np.ndarray | None = None
    left_out: tuple[tuple[int, str], ...] = ()
    planes_at: np.ndarray | None = None
    misfit: np.ndarray | None = None

    def __post_init__(self):
        if self.polyline_planar is None:
            fam = np.array([p.family for p in self.mesh.polylines], dtype=np.int64)
            object.__setattr__(self, "polyline_planar", np.isin(fam, list(self.planar_families)))
        pp = np.array(self.polyline_planar, dtype=bool, copy=True)
        pp.flags.writeable = False
        object.__setattr__(self, "polyline_planar", pp)
        for name in ("axes", "polyline_planes", "polyline_deviation", "edge_planes", "planes_at", "misfit"):
            if getattr(self, name) is None:
                continue
            a = np.array(getattr(self, name), dtype=np.int64 if name == "planes_at" else float, copy=True)
            a.flags.writeable = False
            object.__setattr__(self, name, a)

    @property
    def polylines(self) -> list[Polyline]:
        return self.mesh.polylines

    @property
    def vertices(self) -> np.ndarray:
        return self.mesh.vertices

    @property
    def edges(self) -> np.ndarray:
        """``(E, 2)`` edges, the order of :attr:`edge_planes` and :meth:`torsion`."""
        return self.mesh.topology.edges

    @cached_property
    def torsion(self) -> np.ndarray:
        """``(E,)`` torsion angle of every edge, radians (see :func:`torsion`)."""
        return torsion(self.mesh, self.axes)

    @cached_property
    def normal_angle_deg(self) -> np.ndarray:
        """``(N,)`` angle between each node axis and the surface normal at its vertex, degrees (0…90; the
        normal taken as a line, :func:`vertex_normals`)."""
        return np.degrees(pl.line_angle(self.axes, vertex_normals(self.mesh)))

    def torsion_offset(self, depth: float) -> np.ndarray:
        """``(E,)`` how far (mesh units) the axis at one end of an edge, followed for ``depth``,
        leaves the plane of the edge and the other axis (see :func:`torsion_offset`)."""
        return torsion_offset(self.mesh, self.axes, depth)

    @cached_property
    def grid_index(self) -> np.ndarray | None:
        """``(N, 2)`` grid index ``(i, j)`` of every vertex on a regular patch, else ``None``."""
        ids = self.mesh.grid_ids
        if self.mesh.grid is None or ids is None:
            return None
        out = -np.ones((len(self.vertices), 2), dtype=np.int64)
        ii, jj = np.indices(ids.shape)
        out[ids.ravel(), 0] = ii.ravel()
        out[ids.ravel(), 1] = jj.ravel()
        return out

    def polyline_grid_index(self, k: int) -> tuple[int, int] | None:
        """``(family, i or j)`` of polyline ``k`` on a regular patch (rows first, then columns), else ``None``."""
        g = self.mesh.grid
        if g is None:
            return None
        m1 = g.shape[0]
        return (0, k) if k < m1 else (1, k - m1)

    def summary(self) -> dict:
        """Plain numbers for reports: torsion max/mean (deg), worst polyline deviation, solver record."""
        t = np.degrees(self.torsion) if len(self.edges) else np.zeros(1)
        return {
            "kind": self.kind,
            "planar_families": [FAMILY_NAMES[f] for f in self.planar_families],
            "torsion_max_deg": float(t.max()), "torsion_mean_deg": float(t.mean()),
            "polyline_deviation_max": float(self.polyline_deviation.max()) if len(self.polyline_deviation) else 0.0,
            **{k: v for k, v in self.meta.items() if isinstance(v, (int, float, str))},
        }


# -- basic measures ---------------------------------------------------------------------------------


def vertex_normals(mesh: QuadMesh) -> np.ndarray:
    """``(N, 3)`` outward unit vertex normals: area-weighted sums of the oriented face normals.

    The diagonal cross product ``(c2 − c0) × (c3 − c1)`` of a quad is twice its
    vector area, so summing it over the faces at a vertex weights by area.
    """
    c = mesh.face_corners
    fn = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    acc = np.zeros((len(mesh.vertices), 3))
    np.add.at(acc, mesh.faces.ravel(), np.repeat(fn, 4, axis=0))
    length = np.linalg.norm(acc, axis=1)
    if np.any(length <= 0):
        k = int(np.flatnonzero(length <= 0)[0])
        raise GeometryError(f"vertex {k} has no defined normal (its faces cancel or are degenerate)",
                            element=f"vertex {k}")
    return acc / length[:, None]


def _edge_frames(mesh: QuadMesh) -> tuple[np.ndarray, np.ndarray]:
    e = mesh.topology.edges
    vec = mesh.vertices[e[:, 1]] - mesh.vertices[e[:, 0]]
    length = np.linalg.norm(vec, axis=1)
    if np.any(length <= 0):
        k = int(np.flatnonzero(length <= 0)[0])
        raise GeometryError(f"edge ({e[k, 0]}, {e[k, 1]}) has zero length", element=f"edge {k}", value=0.0)
    return e, vec / length[:, None]


def torsion(mesh: QuadMesh | QuadGrid, axes: np.ndarray) -> np.ndarray:
    """Torsion of every edge: the angle between the planes ``span(e, A_i)`` and ``span(e, A_j)``.

    Parameters
    ----------
    mesh : quad mesh with edges ``mesh.topology.edges (E, 2)``
    axes : (N, 3) float, node axes (any length, any sign)

    Returns
    -------
    (E,) float, radians in ``[0, π/2]``; zero iff the two axes and the edge are
    coplanar (Def. 2.3).  An axis along its edge raises :class:`GeometryError`.
    """
    mesh = as_quadmesh(mesh)
    a = np.asarray(axes, dtype=float)
    if a.shape != mesh.vertices.shape:
        raise GeometryError(f"axes need shape {mesh.vertices.shape}, got {a.shape}")
    e, eh = _edge_frames(mesh)
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    ni = np.cross(eh, a[e[:, 0]])
    nj = np.cross(eh, a[e[:, 1]])
    li, lj = np.linalg.norm(ni, axis=1), np.linalg.norm(nj, axis=1)
    bad = np.minimum(li, lj) < 1e-9
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise GeometryError(f"edge ({e[k, 0]}, {e[k, 1]}): a node axis runs along the edge "
                            f"(sine {min(li[k], lj[k]):.1e}); the support plane is undefined",
                            element=f"edge {k}", value=float(min(li[k], lj[k])))
    cr = np.linalg.norm(np.cross(ni, nj), axis=1)
    dot = np.abs(np.einsum("ij,ij->i", ni, nj))
    return np.arctan2(cr, dot)


def torsion_offset(mesh: QuadMesh | QuadGrid, axes: np.ndarray, depth: float) -> np.ndarray:
    """``(E,)`` the larger distance of the point ``v_j + depth·A_j`` from the plane ``span(v_i; e, A_i)``
    and vice versa: the torsion of an edge as a length at beam depth ``depth`` (mesh units)."""
    mesh = as_quadmesh(mesh)
    e, eh = _edge_frames(mesh)
    a = np.asarray(axes, dtype=float)
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    ni = np.cross(eh, a[e[:, 0]])
    nj = np.cross(eh, a[e[:, 1]])
    ni /= np.maximum(np.linalg.norm(ni, axis=1, keepdims=True), 1e-300)
    nj /= np.maximum(np.linalg.norm(nj, axis=1, keepdims=True), 1e-300)
    d1 = np.abs(np.einsum("ij,ij->i", a[e[:, 1]], ni))
    d2 = np.abs(np.einsum("ij,ij->i", a[e[:, 0]], nj))
    return float(depth) * np.maximum(d1, d2)


def edge_polyline_index(mesh: QuadMesh) -> np.ndarray:
    """``(E,)`` index of the polyline (``mesh.polylines``) containing each edge of ``mesh.topology.edges``."""
    edges = mesh.topology.edges
    n = len(mesh.vertices)
    keys = edges[:, 0] * n + edges[:, 1]
    out = -np.ones(len(edges), dtype=np.int64)
    for k, p in enumerate(mesh.polylines):
        idx = p.vertices
        a, b = idx[:-1], idx[1:]
        if p.closed and len(idx) > 2:
            a, b = np.r_[a, idx[-1]], np.r_[b, idx[0]]
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        pos = np.searchsorted(keys, lo * n + hi)
        out[pos] = k
    return out



def _span_planes(mesh: QuadMesh, axes: np.ndarray) -> np.ndarray:
    """Unit plane through each edge containing the mean of its two end axes, ``(E, 4)``."""
    e, eh = _edge_frames(mesh)
    ai, aj = axes[e[:, 0]], axes[e[:, 1]]
    aj = np.where((np.einsum("ij,ij->i", ai, aj) < 0)[:, None], -aj, aj)   # lines, not vectors
    nrm = np.cross(eh, ai) + np.cross(eh, aj)
    length = np.linalg.norm(nrm, axis=1)
    if np.any(length < 1e-12):
        k = int(np.flatnonzero(length < 1e-12)[0])
        raise GeometryError(f"edge ({e[k, 0]}, {e[k, 1]}): its node axes are parallel to it, "
                            "no support plane", element=f"edge {k}")
    nrm /= length[:, None]
    d = -np.einsum("ij,ij->i", nrm, mesh.vertices[e[:, 0]])
    return np.concatenate([nrm, d[:, None]], axis=1)


def _assemble(mesh: QuadMesh, axes: np.ndarray, polyline_planes: np.ndarray, planar_lines: np.ndarray,
              planar_families: tuple[int, ...], kind: str, meta: dict, left_out: tuple[tuple[int, str], ...] = (),
              planes_at: np.ndarray | None = None, misfit: np.ndarray | None = None) -> SupportStructure:
    """Edge planes (polyline plane on planar polylines, span of the axes elsewhere) and deviations."""
    edge_planes = _span_planes(mesh, axes)
    epl = edge_polyline_index(mesh)
    use = planar_lines[epl]
    edge_planes[use] = pl.normalize(polyline_planes[epl[use]])
    planes = np.array(polyline_planes, dtype=float)
    # 2-vertex polylines (and any unfitted one) carry the support plane of their edge
    missing = ~np.all(np.isfinite(planes), axis=1)
    if np.any(missing):
        first_edge = np.zeros(len(planes), dtype=np.int64)
        first_edge[epl[::-1]] = np.arange(len(epl))[::-1]
        planes[missing] = edge_planes[first_edge[missing]]
    planes = pl.normalize(planes)
    dev = np.array([float(np.abs(pl.signed_distance(planes[k], mesh.vertices[p.vertices])).max())
                    for k, p in enumerate(mesh.polylines)])
    return SupportStructure(mesh, axes, planes, dev, edge_planes, tuple(sorted(planar_families)), kind, meta,
                            np.asarray(planar_lines, dtype=bool), left_out, planes_at, misfit)


def _orient_inward(axes: np.ndarray, normals: np.ndarray, flip: bool) -> np.ndarray:
    a = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    sign = np.where(np.einsum("ij,ij->i", a, normals) > 0, -1.0, 1.0)
    if flip:
        sign = -sign
    return a * sign[:, None]

"""Torsion-free support structures: node axes and support planes (§2.2, Def. 2.3).

A torsion-free support structure of a quad mesh gives every vertex ``v_i`` a
node axis ``A_i`` and every edge ``v_i v_j`` a support plane ``σ_ij`` that
contains both axes ``A_i`` and ``A_j`` (Def. 2.3).  Beams are cut from these
planes: a planar mesh polyline whose axes lie in its plane becomes one planar
beam plate (the P / PP case of §3.1).

Constructors (all return a :class:`SupportStructure`):

* :func:`support_pp` — PP meshes: the axis of ``v_ij`` is the line ``U_i ∩ W_j``
  of the two support planes (§3.1.1), exact wherever the polylines are planar.
* :func:`support_p` — P meshes: axes in the planes of the planar family,
  transverse support planes through consecutive axes; found as a parallel mesh
  (below) whose offsets are constrained to those planes.
* :func:`support_conical` — conical meshes (§2.3.3): the axis of an interior vertex
  is the cone axis, the unit vector making equal angles with the adjacent unit face
  normals; boundary axes from a parallel mesh that keeps the interior fixed.
* :func:`support_parallel` — any planar-quad mesh: a parallel mesh ``M'`` (§2.2.3,
  Fig. 4) near the normal offset, by least squares; the planes through
  corresponding edges of ``M`` and ``M'`` form a torsion-free support structure and
  the axes are ``v'_i − v_i``.  Axes of polylines that are already planar are kept
  in their planes.

The parallel mesh is linear in the vertex offsets ``u_i = v'_i − v_i``: edge
``v'_i v'_j`` is parallel to ``v_i v_j`` iff ``(u_j − u_i) × ê_ij = 0`` (two
equations per edge).  We solve ``min Σ |u_i − t_i|²`` (``t_i`` the inward unit
vertex normal) subject to these equations (and ``n·u_i = 0`` for axes kept in a
plane) by an augmented Lagrangian with one sparse factorisation.

Orientation: the mesh's oriented face normals (corner order) point outward;
node axes point to the other side (into the structure, where the beams are).

Torsion (:func:`torsion`) of an edge is the angle between the planes spanned by
the edge and each of its two end axes: zero iff the axes are coplanar with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.sparse import coo_matrix, identity
from scipy.sparse.linalg import splu

from . import planes as pl
from .errors import DesignError, GeometryError
from .mesh import QuadGrid, QuadMesh
from .metrics import face_planarity
from .schema import param
from .topology import Polyline

__all__ = [
    "SupportStructure", "SupportParams", "support_structure", "support_pp", "support_p",
    "support_conical", "support_parallel", "torsion", "torsion_offset", "vertex_normals",
    "as_quadmesh", "parallel_offsets",
]

METHODS = ("auto", "pp", "p", "conical", "parallel")


@dataclass(frozen=True)
class SupportParams:
    """How the support structure is found (the ``[support]`` table of a design file)."""

    method: str = param("auto", doc="'auto', 'pp' (U_i ∩ W_j), 'p' (axes in the planes of one family), "
                                    "'conical' (cone axes), 'parallel' (least-squares parallel mesh)",
                        choices=METHODS)
    family: str = param("rows", doc="the planar family for method 'p': 'rows' or 'cols'",
                        choices=("rows", "cols"))
    planar_tolerance: float = param(1e-6, doc="δ_P (relative) below which a polyline counts as planar "
                                              "(method 'auto' and 'parallel')", min=0.0)
    max_normal_angle_deg: float = param(30.0, doc="methods 'p'/'parallel': if the exact parallel mesh turns an "
                                                  "axis further than this from the normal, use the least-squares "
                                                  "compromise (small torsion, reported)", exclusive_min=0, max=90)
    flip: bool = param(False, doc="turn all axes to the other side (beams on the outside)")


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

    def __post_init__(self):
        if self.polyline_planar is None:
            fam = np.array([p.family for p in self.mesh.polylines], dtype=np.int64)
            object.__setattr__(self, "polyline_planar", np.isin(fam, list(self.planar_families)))
        pp = np.array(self.polyline_planar, dtype=bool, copy=True)
        pp.flags.writeable = False
        object.__setattr__(self, "polyline_planar", pp)
        for name in ("axes", "polyline_planes", "polyline_deviation", "edge_planes"):
            a = np.array(getattr(self, name), dtype=float, copy=True)
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

    def torsion_offset(self, depth: float) -> np.ndarray:
        """``(E,)`` how far (mesh units) the axis at one end of an edge, followed for ``depth``,
        leaves the plane of the edge and the other axis (see :func:`torsion_offset`)."""
        return torsion_offset(self.mesh, self.axes, depth)

    def vertex_torsion(self) -> np.ndarray:
        """``(N,)`` largest torsion angle of the edges at each vertex, radians."""
        out = np.zeros(len(self.vertices))
        t = self.torsion
        np.maximum.at(out, self.edges[:, 0], t)
        np.maximum.at(out, self.edges[:, 1], t)
        return out

    @cached_property
    def edge_polyline(self) -> np.ndarray:
        """``(E,)`` index of the polyline (into :attr:`polylines`) that contains each edge."""
        return edge_polyline_index(self.mesh)

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

    def axis_plane_angle(self) -> np.ndarray:
        """``(L,)`` largest angle (radians) between an axis on a polyline and that polyline's plane."""
        out = np.zeros(len(self.polylines))
        n = pl.normalize(self.polyline_planes)[:, :3]
        for k, p in enumerate(self.polylines):
            s = np.abs(self.axes[p.vertices] @ n[k])
            out[k] = float(np.arcsin(np.clip(s.max(), 0.0, 1.0)))
        return out

    def summary(self) -> dict:
        """Plain numbers for reports: torsion max/mean (deg), worst polyline deviation, solver record."""
        t = np.degrees(self.torsion) if len(self.edges) else np.zeros(1)
        return {
            "kind": self.kind,
            "planar_families": [("rows", "cols")[f] for f in self.planar_families],
            "torsion_max_deg": float(t.max()), "torsion_mean_deg": float(t.mean()),
            "polyline_deviation_max": float(self.polyline_deviation.max()) if len(self.polyline_deviation) else 0.0,
            **{k: v for k, v in self.meta.items() if isinstance(v, (int, float, str))},
        }


# -- basic measures ---------------------------------------------------------------------------------

def as_quadmesh(mesh: QuadMesh | QuadGrid) -> QuadMesh:
    """A :class:`QuadMesh` view (a grid becomes its row-major quad mesh, keeping the grid)."""
    if isinstance(mesh, QuadGrid):
        return mesh.to_quadmesh()
    if not isinstance(mesh, QuadMesh):
        raise GeometryError(f"expected a QuadMesh or QuadGrid, got {type(mesh).__name__}")
    return mesh


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


def _polyline_fit(mesh: QuadMesh) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares plane and absolute deviation of every polyline (``nan`` planes for < 3 vertices)."""
    lines = mesh.polylines
    planes = np.full((len(lines), 4), np.nan)
    dev = np.zeros(len(lines))
    groups: dict[int, list[int]] = {}
    for k, p in enumerate(lines):
        if len(p) >= 3:
            groups.setdefault(len(p), []).append(k)
    for length, ks in groups.items():
        pts = mesh.vertices[np.stack([lines[k].vertices for k in ks])]
        planes[ks], dev[ks] = pl.fit_plane(pts)
    return planes, dev


def _relative(dev: np.ndarray, mesh: QuadMesh) -> np.ndarray:
    """Deviation relative to each polyline's bounding-box diagonal (δ_P of §3.3)."""
    out = np.zeros(len(dev))
    for k, p in enumerate(mesh.polylines):
        x = mesh.vertices[p.vertices]
        diag = float(np.linalg.norm(x.max(axis=0) - x.min(axis=0)))
        out[k] = dev[k] / diag if diag > 0 else 0.0
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
              planar_families: tuple[int, ...], kind: str, meta: dict) -> SupportStructure:
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
                            np.asarray(planar_lines, dtype=bool))


def _orient_inward(axes: np.ndarray, normals: np.ndarray, flip: bool) -> np.ndarray:
    a = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    sign = np.where(np.einsum("ij,ij->i", a, normals) > 0, -1.0, 1.0)
    if flip:
        sign = -sign
    return a * sign[:, None]


# -- PP ----------------------------------------------------------------------------------------------

def support_pp(mesh: QuadMesh | QuadGrid, flip: bool = False) -> SupportStructure:
    """Support structure of a PP patch: axis of ``v_ij`` along ``U_i ∩ W_j`` (§3.1.1).

    The planes are the grid's own ``support_u``/``support_w`` when it carries them,
    otherwise least-squares planes of the rows ``v[i, :]`` and columns ``v[:, j]``.
    Every row edge is supported by its ``U_i``, every column edge by its ``W_j``.

    Raises :class:`GeometryError` where ``U_i`` and ``W_j`` are (nearly) parallel.
    """
    qm = as_quadmesh(mesh)
    grid = qm.grid
    if grid is None:
        from .topology import recover_grid

        why = recover_grid(qm.topology)
        reason = why if isinstance(why, str) else "no grid recorded"
        raise GeometryError(f"support method 'pp' needs a regular patch (rows v[i, :] and columns v[:, j]); "
                            f"this mesh is not a regular grid: {reason}")
    U = grid.support_u if grid.support_u is not None else pl.fit_plane(grid.rows())[0]
    W = grid.support_w if grid.support_w is not None else pl.fit_plane(grid.cols())[0]
    U, W = pl.normalize(U), pl.normalize(W)
    ax = np.cross(U[:, None, :3], W[None, :, :3])
    s = np.linalg.norm(ax, axis=-1)
    if np.any(s < 1e-9):
        i, j = (int(k) for k in np.argwhere(s < 1e-9)[0])
        raise GeometryError(f"vertex ({i}, {j}): support planes U_{i} and W_{j} are parallel "
                            f"(sine {s[i, j]:.1e}), no node axis", element=f"vertex {i},{j}", value=float(s[i, j]))
    axes = np.zeros_like(qm.vertices)
    axes[qm.grid_ids.ravel()] = (ax / s[..., None]).reshape(-1, 3)
    axes = _orient_inward(axes, vertex_normals(qm), flip)
    planes = np.concatenate([U, W], axis=0)            # grid polylines: rows, then columns
    planar = np.ones(len(planes), dtype=bool)
    return _assemble(qm, axes, planes, planar, (0, 1), "pp", {"planes": "grid" if grid.support_u is not None
                                                              else "least squares"})


# -- parallel mesh by least squares ----------------------------------------------------------------------

def _perpendicular_pair(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``(k, 3)`` completing unit vectors ``d`` to orthonormal frames."""
    helper = np.eye(3)[np.argmin(np.abs(d), axis=1)]
    p = np.cross(d, helper)
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return p, np.cross(d, p)


def parallel_offsets(mesh: QuadMesh, target: np.ndarray, plane_normals: list[tuple[np.ndarray, np.ndarray]] = (),
                     fixed: np.ndarray | None = None, rho: float = 1e6, max_iter: int = 40,
                     tol: float = 1e-11) -> tuple[np.ndarray, dict]:
    """Offsets ``u (N, 3)`` of a parallel mesh ``v + u`` nearest to ``target`` (§2.2.3).

    Minimises ``Σ |u_i − t_i|²`` subject to ``(u_j − u_i) × ê_ij = 0`` on every edge
    (as two rows ``p·(u_j − u_i) = q·(u_j − u_i) = 0``, ``p, q ⊥ ê``) and
    ``n·u_i = 0`` for each ``(vertex ids, normals (k, 3))`` in ``plane_normals``;
    vertices with ``fixed`` keep ``u = target``.  Augmented Lagrangian:
    ``(I + ρ CᵀC) u = t − Cᵀλ + ρ Cᵀ r``, ``λ += ρ (C u − r)``, one sparse LU.

    Returns
    -------
    u : (N, 3) float
    info : ``iterations``, ``residual`` (largest constraint violation, units of ``target``)
    """
    n = len(mesh.vertices)
    t = np.asarray(target, dtype=float)
    e, eh = _edge_frames(mesh)
    p, q = _perpendicular_pair(eh)
    rows, cols, vals = [], [], []
    r0 = 0
    for vec in (p, q):
        k = np.arange(len(e)) + r0
        for sign, end in ((1.0, 1), (-1.0, 0)):
            for c in range(3):
                rows.append(k)
                cols.append(3 * e[:, end] + c)
                vals.append(sign * vec[:, c])
        r0 += len(e)
    for ids, normals in plane_normals:
        ids = np.asarray(ids, dtype=np.int64)
        nr = np.asarray(normals, dtype=float).reshape(-1, 3)
        k = np.arange(len(ids)) + r0
        for c in range(3):
            rows.append(k)
            cols.append(3 * ids + c)
            vals.append(nr[:, c])
        r0 += len(ids)
    C = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(r0, 3 * n)).tocsc()
    fixed = np.zeros(n, dtype=bool) if fixed is None else np.asarray(fixed, dtype=bool)
    free_cols = np.flatnonzero(~np.repeat(fixed, 3))
    fix_cols = np.flatnonzero(np.repeat(fixed, 3))
    x_fix = t.ravel()[fix_cols]
    Cf = C[:, free_cols]
    r = -(C[:, fix_cols] @ x_fix)
    live = np.diff(Cf.tocsr().indptr) > 0                   # rows that involve a free unknown
    Cf = Cf.tocsr()[live].tocsc()
    r = r[live]
    tf = t.ravel()[free_cols]
    info = {"iterations": 0, "residual": 0.0}
    u = t.ravel().copy()
    if len(free_cols):
        A = (identity(len(free_cols), format="csc") + rho * (Cf.T @ Cf)).tocsc()
        lu = splu(A)
        lam = np.zeros(Cf.shape[0])
        x = tf
        for it in range(1, max_iter + 1):
            x = lu.solve(tf - Cf.T @ lam + rho * (Cf.T @ r))
            res = Cf @ x - r
            lam += rho * res
            info = {"iterations": it, "residual": float(np.abs(res).max()) if len(res) else 0.0}
            if info["residual"] <= tol:
                break
        u[free_cols] = x
    return u.reshape(n, 3), info


def _axes_from_offsets(mesh: QuadMesh, u: np.ndarray, normals: np.ndarray, flip: bool) -> np.ndarray:
    length = np.linalg.norm(u, axis=1)
    small = length < 1e-6
    if np.any(small):
        k = int(np.flatnonzero(small)[0])
        raise GeometryError(f"vertex {k}: the least-squares parallel mesh collapses there (offset "
                            f"{length[k]:.1e} of the unit target), no node axis; the mesh is probably far "
                            "from having planar faces", element=f"vertex {k}", value=float(length[k]))
    return _orient_inward(u, normals, flip)


@dataclass(frozen=True)
class _VertexPlanes:
    """The (up to two) planes each vertex's axis is kept in: ``count (N,)``, unit normals ``n1, n2 (N, 3)``."""

    count: np.ndarray
    n1: np.ndarray
    n2: np.ndarray


def _project_into_planes(axes: np.ndarray, vp: _VertexPlanes) -> np.ndarray:
    """Put each constrained axis exactly into its plane, or along the line of its first two planes."""
    a = axes.copy()
    one = vp.count == 1
    a[one] -= np.einsum("ij,ij->i", a[one], vp.n1[one])[:, None] * vp.n1[one]
    two = vp.count >= 2
    line = np.cross(vp.n1[two], vp.n2[two])
    ok = np.linalg.norm(line, axis=1) >= 1e-9
    flat = a[two] - np.einsum("ij,ij->i", a[two], vp.n1[two])[:, None] * vp.n1[two]
    line = np.where(ok[:, None], line, flat)
    line *= np.where(np.einsum("ij,ij->i", line, a[two]) < 0, -1.0, 1.0)[:, None]
    a[two] = line
    return a / np.linalg.norm(a, axis=1, keepdims=True)


def _planar_constraints(mesh: QuadMesh, lines: np.ndarray, planes: np.ndarray
                        ) -> tuple[list[tuple[np.ndarray, np.ndarray]], _VertexPlanes]:
    """Rows ``n·u_i = 0`` for every vertex of the given polylines, and the planes per vertex."""
    nv = len(mesh.vertices)
    count = np.zeros(nv, dtype=np.int64)
    n1 = np.zeros((nv, 3))
    n2 = np.zeros((nv, 3))
    if len(lines) == 0:
        return [], _VertexPlanes(count, n1, n2)
    unit = pl.normalize(planes[lines])[:, :3]
    ids = np.concatenate([mesh.polylines[k].vertices for k in lines])
    nrm = np.concatenate([np.repeat(nvec[None], len(mesh.polylines[k]), axis=0) for k, nvec in zip(lines, unit)])
    order = np.argsort(ids, kind="stable")
    ids_s, nrm_s = ids[order], nrm[order]
    first = np.r_[True, ids_s[1:] != ids_s[:-1]]
    count[:] = np.bincount(ids, minlength=nv)
    n1[ids_s[first]] = nrm_s[first]
    rank = np.arange(len(ids_s)) - np.flatnonzero(first)[np.cumsum(first) - 1]
    n2[ids_s[rank == 1]] = nrm_s[rank == 1]
    return [(ids, nrm)], _VertexPlanes(count, n1, n2)


def support_parallel(mesh: QuadMesh | QuadGrid, planar_tolerance: float = 1e-6, flip: bool = False,
                     keep_planar: bool = True, max_normal_angle_deg: float = 30.0) -> SupportStructure:
    """Torsion-free support structure of any planar-quad mesh from a least-squares parallel mesh.

    The offsets ``u`` of a parallel mesh nearest to the inward unit vertex normals
    (:func:`parallel_offsets`) give the axes ``u_i / |u_i|``; corresponding edges of
    ``M`` and ``M + u`` span the support planes (Fig. 4).  With ``keep_planar``,
    polylines with ``δ_P ≤ planar_tolerance`` keep their axes in their planes, so
    they can become single planar beams; a family all of whose polylines (with at
    least 3 vertices) are planar is reported in ``planar_families``.

    On a mesh whose faces are far from planar the only parallel meshes are
    scaled copies and the exact axes become concurrent; when they leave the
    normals by more than ``max_normal_angle_deg`` the penalty solution is used
    instead (``meta['exact'] = False``): axes near the normals with small torsion,
    which :attr:`SupportStructure.torsion` reports.
    """
    qm = as_quadmesh(mesh)
    normals = vertex_normals(qm)
    planes, dev = _polyline_fit(qm)
    fitted = np.all(np.isfinite(planes), axis=1)
    planar = _planar_lines(qm, planes, dev, normals, planar_tolerance, max_normal_angle_deg) if keep_planar \
        else np.zeros(len(planes), dtype=bool)
    constraints, per_vertex = _planar_constraints(qm, np.flatnonzero(planar), planes)
    axes, meta = _solve_axes(qm, normals, constraints, per_vertex, flip, max_normal_angle_deg)
    families = _planar_families(qm, planar, fitted)
    meta["planar_polylines"] = int(planar.sum())
    return _assemble(qm, axes, planes, planar, families, "parallel", meta)


def _planar_lines(mesh: QuadMesh, planes: np.ndarray, dev: np.ndarray, normals: np.ndarray, tol: float,
                  max_angle_deg: float) -> np.ndarray:
    """Polylines whose axes can be kept in their planes: at least 4 vertices, ``δ_P ≤ tol``, not straight
    (the plane is determined: some vertex is 1e-3 of the bounding-box diagonal off the chord) and transverse
    (every vertex normal within ``90° − max_angle_deg`` of the plane's normal is excluded, since an axis in
    that plane could not come within ``max_angle_deg`` of the normal)."""
    rel = _relative(dev, mesh)
    out = np.zeros(len(planes), dtype=bool)
    sin_max = np.sin(np.radians(max_angle_deg))
    for k, p in enumerate(mesh.polylines):
        if len(p) < 4 or not np.all(np.isfinite(planes[k])) or rel[k] > tol:
            continue
        x = mesh.vertices[p.vertices]
        chord = x[-1] - x[0] if not p.closed else x[len(x) // 2] - x[0]
        diag = float(np.linalg.norm(x.max(axis=0) - x.min(axis=0)))
        cl = float(np.linalg.norm(chord))
        if cl == 0 or diag == 0:
            continue
        off = np.linalg.norm(np.cross(x - x[0], chord / cl), axis=1).max()
        if off < 1e-3 * diag:
            continue
        if np.abs(normals[p.vertices] @ planes[k, :3]).max() > sin_max:
            continue
        out[k] = True
    return out


def _solve_axes(mesh: QuadMesh, normals: np.ndarray, constraints: list, per_vertex: _VertexPlanes, flip: bool,
                max_normal_angle_deg: float) -> tuple[np.ndarray, dict]:
    """Axes of the exact least-squares parallel mesh; if that is unusable (an offset collapses or an axis
    leaves its normal by more than ``max_normal_angle_deg``, which happens when the faces are far from
    planar), the penalty solution with the largest stiffness ``ρ ∈ {1e4, …, 1}`` that keeps the axes
    within that angle — torsion is then small but not zero and is reported."""
    u, info = parallel_offsets(mesh, -normals, constraints)
    axes = _usable_axes(mesh, u, normals, per_vertex, flip, max_normal_angle_deg)
    meta = {"exact": True, "iterations": info["iterations"], "constraint_residual": info["residual"]}
    if axes is None:
        for rho in (1e4, 1e3, 1e2, 1e1, 1.0):
            u, info = parallel_offsets(mesh, -normals, constraints, rho=rho, max_iter=1)
            axes = _usable_axes(mesh, u, normals, per_vertex, flip, max_normal_angle_deg)
            if axes is not None:
                break
        if axes is None:
            axes = _project_into_planes(_axes_from_offsets(mesh, u, normals, flip), per_vertex)
        meta = {"exact": False, "stiffness": rho, "iterations": 1, "constraint_residual": info["residual"]}
    meta["normal_angle_max_deg"] = _normal_angle_max(axes, normals, flip)
    return axes, meta


def _usable_axes(mesh: QuadMesh, u: np.ndarray, normals: np.ndarray, per_vertex: _VertexPlanes, flip: bool,
                 max_angle: float) -> np.ndarray | None:
    """The axes, or ``None`` when an offset collapses or an axis is further than ``max_angle`` from the
    inward normal brought into the axis's planes (the closest the constraints allow)."""
    if np.linalg.norm(u, axis=1).min() < 1e-3:
        return None
    axes = _project_into_planes(_axes_from_offsets(mesh, u, normals, flip), per_vertex)
    best = _project_into_planes(-normals * (-1.0 if flip else 1.0), per_vertex)
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", axes, best), -1.0, 1.0)))
    return axes if ang.max() <= max_angle else None


def _normal_angle_max(axes: np.ndarray, normals: np.ndarray, flip: bool) -> float:
    c = -np.einsum("ij,ij->i", axes, normals) * (-1.0 if flip else 1.0)
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))).max())


def _planar_families(mesh: QuadMesh, planar: np.ndarray, fitted: np.ndarray) -> tuple[int, ...]:
    out = []
    for fam in (0, 1):
        ks = [k for k, p in enumerate(mesh.polylines) if p.family == fam and fitted[k]]
        if ks and all(planar[k] for k in ks):
            out.append(fam)
    return tuple(out)


# -- P ----------------------------------------------------------------------------------------------

def support_p(mesh: QuadMesh | QuadGrid, family: int | str = 0, planes: np.ndarray | None = None,
              flip: bool = False, max_normal_angle_deg: float = 30.0) -> SupportStructure:
    """Support structure of a P mesh: axes in the planes of one polyline family.

    Parameters
    ----------
    mesh : quad mesh with planar faces whose polylines of ``family`` are planar
    family : 0 / ``"rows"`` or 1 / ``"cols"``
    planes : (L_f, 4) float, optional — the planes of that family's polylines in the order of
        ``mesh.family(family)``; least-squares planes when omitted

    The axes lie in the planes ``U`` of the family (so each such polyline with its
    axes is one planar beam); the transverse support planes pass through the edge and
    both end axes.  Found as the parallel mesh nearest to the normal offset whose
    offsets lie in the planes (:func:`parallel_offsets`).
    """
    fam = _family(family)
    qm = as_quadmesh(mesh)
    normals = vertex_normals(qm)
    fit, dev = _polyline_fit(qm)
    lines = np.array([k for k, p in enumerate(qm.polylines) if p.family == fam], dtype=np.int64)
    if len(lines) == 0:
        raise GeometryError(f"the mesh has no polylines of family {('rows', 'cols')[fam]}")
    all_planes = fit.copy()
    if planes is not None:
        given = pl.as_planes(planes)
        if given.shape != (len(lines), 4):
            raise GeometryError(f"planes need shape ({len(lines)}, 4) for the {len(lines)} polylines of the family, "
                                f"got {given.shape}")
        all_planes[lines] = pl.normalize(given)
    use = lines[np.all(np.isfinite(all_planes[lines]), axis=1)]
    constraints, per_vertex = _planar_constraints(qm, use, all_planes)
    axes, meta = _solve_axes(qm, normals, constraints, per_vertex, flip, max_normal_angle_deg)
    planar = np.zeros(len(all_planes), dtype=bool)
    planar[use] = True
    return _assemble(qm, axes, all_planes, planar, (fam,), "p", meta)


def _family(family: int | str) -> int:
    if family in (0, "rows", "U", "u"):
        return 0
    if family in (1, "cols", "W", "w"):
        return 1
    raise DesignError("support.family", f"must be 'rows' or 'cols', got {family!r}")


# -- conical ------------------------------------------------------------------------------------------

def _vertex_face_normals(mesh: QuadMesh) -> tuple[np.ndarray, np.ndarray]:
    """Padded unit normals of the faces at each vertex, ``(N, k, 3)``, and a mask ``(N, k)``."""
    f = mesh.faces.ravel()
    fid = np.repeat(np.arange(len(mesh.faces)), 4)
    order = np.argsort(f, kind="stable")
    f, fid = f[order], fid[order]
    counts = np.bincount(f, minlength=len(mesh.vertices))
    start = np.r_[0, np.cumsum(counts)[:-1]]
    slot = np.arange(len(f)) - start[f]
    k = int(counts.max())
    normals = np.zeros((len(mesh.vertices), k, 3))
    mask = np.zeros((len(mesh.vertices), k), dtype=bool)
    normals[f, slot] = pl.normalize(mesh.face_planes)[fid, :3]
    mask[f, slot] = True
    return normals, mask


def cone_axes(mesh: QuadMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cone axes at vertices with at least 3 faces (§2.3.3).

    The axis ``a`` makes equal angles with the unit face normals ``n_k``:
    ``(n_k − n̄)·a = 0`` for all ``k``, solved in the least-squares sense as the
    eigenvector of the smallest eigenvalue of ``Σ (n_k − n̄)(n_k − n̄)ᵀ``.

    Returns
    -------
    axes : (N, 3) unit, pointing against the mean normal (inward); rows with fewer than 3 faces are 0
    cos_angle : (N,) mean ``−a·n_k`` (cosine of the cone's half opening angle complement)
    determined : (N,) bool, vertex has at least 3 faces
    """
    normals, mask = _vertex_face_normals(mesh)
    w = mask.astype(float)
    count = w.sum(axis=1)
    mean = np.einsum("nk,nki->ni", w, normals) / count[:, None]
    dev = (normals - mean[:, None, :]) * w[..., None]
    cov = np.einsum("nki,nkj->nij", dev, dev)
    _, vecs = np.linalg.eigh(cov)
    a = vecs[:, :, 0]
    a = np.where((np.einsum("ni,ni->n", a, mean) > 0)[:, None], -a, a)
    cos = -np.einsum("nki,ni,nk->n", normals, a, w) / count
    determined = count >= 3
    a[~determined] = 0.0
    return a, cos, determined


def support_conical(mesh: QuadMesh | QuadGrid, flip: bool = False) -> SupportStructure:
    """Support structure of a conical mesh: node axes are the cone axes (§2.3.3).

    At vertices with 3 or more faces the axis makes equal angles with the adjacent
    unit face normals (:func:`cone_axes`).  Those vertices are offset along their
    axes so that every face moves by the same distance (the constant-distance
    offset, a parallel mesh of a conical mesh); boundary vertices (1 or 2 faces)
    get the parallel-mesh offsets nearest to that same face offset.
    """
    qm = as_quadmesh(mesh)
    normals = vertex_normals(qm)
    a, cos, determined = cone_axes(qm)
    if np.any(determined & (cos < 1e-3)):
        k = int(np.flatnonzero(determined & (cos < 1e-3))[0])
        raise GeometryError(f"vertex {k}: the cone axis is (nearly) tangent to the faces "
                            f"(cos {cos[k]:.1e}); the faces there do not touch a cone", element=f"vertex {k}")
    fn, mask = _vertex_face_normals(qm)
    target = np.zeros_like(qm.vertices)
    target[determined] = a[determined] / cos[determined, None]
    # boundary: the minimum-norm offset moving each of its faces inward by 1 (n_k · u = −1):
    # −n_1 at a corner, −(n_1 + n_2)/(1 + n_1·n_2) between two faces
    one = mask.sum(axis=1) == 1
    two = mask.sum(axis=1) == 2
    target[one] = -fn[one, 0]
    s2 = fn[two, 0] + fn[two, 1]
    target[two] = -s2 / (1.0 + np.einsum("ij,ij->i", fn[two, 0], fn[two, 1]))[:, None]
    u, info = parallel_offsets(qm, target, fixed=determined)
    axes = _axes_from_offsets(qm, u, normals, False)
    axes[determined] = a[determined]
    if flip:
        axes = -axes
    resid = conical_axis_residual(qm, axes)
    meta = {"iterations": info["iterations"], "constraint_residual": info["residual"],
            "equal_angle_residual_max": float(np.nanmax(resid)) if np.any(np.isfinite(resid)) else 0.0}
    planes, dev = _polyline_fit(qm)
    planar = np.zeros(len(planes), dtype=bool)
    return _assemble(qm, axes, planes, planar, (), "conical", meta)


def conical_axis_residual(mesh: QuadMesh, axes: np.ndarray) -> np.ndarray:
    """``(N,)`` spread ``max_k − min_k`` of the angles between the axis and the adjacent unit face
    normals, radians; ``nan`` at vertices with fewer than 3 faces.  Zero for cone axes of a conical mesh."""
    fn, mask = _vertex_face_normals(mesh)
    c = np.einsum("nki,ni->nk", fn, np.asarray(axes, dtype=float))
    ang = np.arccos(np.clip(np.abs(c), 0.0, 1.0))
    hi = np.where(mask, ang, -np.inf).max(axis=1)
    lo = np.where(mask, ang, np.inf).min(axis=1)
    out = hi - lo
    out[mask.sum(axis=1) < 3] = np.nan
    return out


# -- dispatch -------------------------------------------------------------------------------------------

def support_structure(mesh: QuadMesh | QuadGrid, params: SupportParams | None = None,
                      planar_families: tuple | list | None = None) -> SupportStructure:
    """The support structure chosen by ``params.method``.

    ``auto``: when ``planar_families`` names the families a construction keeps planar
    (``"rows"``/``"cols"`` or 0/1) — both on a patch → :func:`support_pp`, one →
    :func:`support_p` with that family.  Otherwise: a patch carrying ``U_i``/``W_j`` or with
    both families planar (δ_P ≤ ``planar_tolerance``) → :func:`support_pp`; one family
    planar → :func:`support_p`; a conical planar-quad mesh (residual ≤ 1e-6 rad) →
    :func:`support_conical`; otherwise :func:`support_parallel`.
    """
    p = params or SupportParams()
    qm = as_quadmesh(mesh)
    method = p.method
    fam = None
    if method == "auto" and planar_families:
        fams = sorted({_family(f) for f in planar_families})
        if len(fams) == 2 and qm.grid is not None:
            method = "pp"
        elif len(fams) == 1:
            method, fam = "p", fams[0]
    if method == "auto":
        method = _auto_method(qm, p.planar_tolerance)
    if method == "pp":
        return support_pp(qm, flip=p.flip)
    if method == "p":
        if fam is None:
            fam = _auto_family(qm) if p.method == "auto" else _family(p.family)
        return support_p(qm, fam, flip=p.flip, max_normal_angle_deg=p.max_normal_angle_deg)
    if method == "conical":
        return support_conical(qm, flip=p.flip)
    if method == "parallel":
        return support_parallel(qm, p.planar_tolerance, flip=p.flip, max_normal_angle_deg=p.max_normal_angle_deg)
    raise DesignError("support.method", f"unknown method {method!r}; valid: {', '.join(METHODS)}")


def _family_planarity(mesh: QuadMesh) -> dict[int, float]:
    planes, dev = _polyline_fit(mesh)
    rel = _relative(dev, mesh)
    out = {}
    for fam in (0, 1):
        ks = [k for k, p in enumerate(mesh.polylines) if p.family == fam and len(p) >= 3]
        out[fam] = float(max(rel[ks])) if ks else np.inf
    return out


def _auto_family(mesh: QuadMesh) -> int:
    fp = _family_planarity(mesh)
    return 0 if fp[0] <= fp[1] else 1


def _auto_method(mesh: QuadMesh, tol: float) -> str:
    grid = mesh.grid
    if grid is not None and grid.support_u is not None and grid.support_w is not None:
        return "pp"
    fp = _family_planarity(mesh)
    planar = [f for f in (0, 1) if fp[f] <= tol]
    if planar and grid is None:
        return "parallel"           # keeps the axes of planar polylines in their planes
    if len(planar) == 2:
        return "pp"
    if planar:
        return "p"
    if float(face_planarity(mesh.face_corners).max()) <= 1e-3:
        a, _, det = cone_axes(mesh)
        res = conical_axis_residual(mesh, np.where(det[:, None], a, 0.0))
        if np.any(det) and float(np.nanmax(res)) <= 1e-6:
            return "conical"
    return "parallel"

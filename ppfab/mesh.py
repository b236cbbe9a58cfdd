"""The two mesh types of ppfab.

:class:`QuadGrid` — a regular patch, vertices ``(m+1, n+1, 3)``, optionally
closed in the ``j`` direction (row polylines ``v[i, :]`` are loops).  This is
what the constructions make.  Row polylines lie in the support planes ``U_i``,
column polylines in ``W_j`` (when the grid carries them).

:class:`QuadMesh` — any all-quad mesh, vertices ``(N, 3)``, faces ``(F, 4)``,
with polyline families traced through valence-4 vertices (see
:mod:`ppfab.topology`).  A grid converts to it losslessly
(``vertex id = i·(n+1) + j``, faces row-major) and back.

Both are thin: arrays in, arrays out, read-only, derived data cached,
transforms return new objects.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from types import MappingProxyType
from typing import Any, Mapping, Sequence, overload

import numpy as np

from .errors import GeometryError
from .topology import Polyline, Topology, grid_face_indices, recover_grid


@overload
def _readonly(a: None, dtype: Any = float) -> None: ...
@overload
def _readonly(a: np.ndarray | Sequence[Any], dtype: Any = float) -> np.ndarray: ...
def _readonly(a: np.ndarray | Sequence[Any] | None, dtype: Any = float) -> np.ndarray | None:
    """A read-only copy of ``a`` as ``dtype`` (``None`` stays ``None``)."""
    if a is None:
        return None
    out = np.array(a, dtype=dtype, copy=True)
    out.flags.writeable = False
    return out


def face_corners_of_grid(v: np.ndarray, closed: bool = False) -> np.ndarray:
    """Corners ``(m, n', 4, 3)`` of the faces of a grid ``v (m+1, n+1, 3)``.

    Face ``f[i, j]`` has corners ``v[i,j], v[i+1,j], v[i+1,j+1], v[i,j+1]``;
    with ``closed`` the last column of faces wraps to ``j = 0``.
    """
    nxt = np.roll(v, -1, axis=1) if closed else v[:, 1:]
    cur = v if closed else v[:, :-1]
    return np.stack([cur[:-1], cur[1:], nxt[1:], nxt[:-1]], axis=-2)


def face_planes_of_corners(c: np.ndarray) -> np.ndarray:
    """Unit planes ``(..., 4)`` of quads ``(..., 4, 3)``: normal = diagonal cross product, through the centroid.

    The normal ``(c2 − c0) × (c3 − c1)`` is the mean of the four corner
    normals and orients the plane by the face's corner order.
    """
    n = np.cross(c[..., 2, :] - c[..., 0, :], c[..., 3, :] - c[..., 1, :])
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    n = n / np.where(length == 0, 1.0, length)
    centroid = c.mean(axis=-2)
    return np.concatenate([n, -np.einsum("...i,...i->...", n, centroid)[..., None]], axis=-1)


@dataclass(frozen=True, eq=False)
class QuadGrid:
    """A regular quad patch.

    Parameters
    ----------
    vertices : (m+1, n+1, 3) float
    closed : rows ``v[i, :]`` are closed loops (``j`` periodic)
    support_u : (m+1, 4) float, optional — planes ``U_i`` of the rows (``n·x + d = 0``)
    support_w : (n+1, 4) float, optional — planes ``W_j`` of the columns
    face_image : (m, n', 4) float, optional — weighted face planes ``f_ij`` (§2.2.1)
    axes : (m+1, n+1, 3) float, optional — unit node axes of the construction
    vertex_ids : (m+1, n+1) int, optional — index of each vertex in the file it came from
    extended_face_image : (m+2, n'+2, 4) float, optional — the weighted face image with one ghost face
        beyond each side (PP constructions, eq. 7); vertex ``v[i, j]`` lies on faces ``[i:i+2, j:j+2]``
    extended_face_planes : (m+2, n'+2, 4) float, optional — unit face planes with ghost faces (conical
        constructions and transforms)
    meta : read-only record of how the construction was made (its parameters, sample positions, cusps,
        the spheres it started from): diagnostics only, never read by another stage

    The support planes and axes a grid carries are its construction's; the node axes and support planes
    that are fabricated live only in :class:`ppfab.support.structure.SupportStructure`.
    """

    vertices: np.ndarray
    closed: bool = False
    support_u: np.ndarray | None = None
    support_w: np.ndarray | None = None
    face_image: np.ndarray | None = None
    axes: np.ndarray | None = None
    vertex_ids: np.ndarray | None = None
    extended_face_image: np.ndarray | None = None
    extended_face_planes: np.ndarray | None = None
    meta: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        v = np.asarray(self.vertices, dtype=float)
        if v.ndim != 3 or v.shape[2] != 3 or v.shape[0] < 2 or v.shape[1] < 2:
            raise GeometryError(f"grid vertices need shape (m+1, n+1, 3) with m, n >= 1, got {v.shape}")
        if not np.all(np.isfinite(v)):
            bad = tuple(int(k) for k in np.argwhere(~np.isfinite(v))[0][:2])
            raise GeometryError(f"grid vertex {bad} is not finite (NaN or inf)", element=str(bad))
        object.__setattr__(self, "vertices", _readonly(v))
        for name in ("support_u", "support_w", "face_image", "axes", "extended_face_image", "extended_face_planes"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))
        object.__setattr__(self, "vertex_ids", _readonly(self.vertex_ids, np.int64))
        object.__setattr__(self, "meta", MappingProxyType(dict(self.meta)))

    # -- shape -------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """``(m+1, n+1)``: rows and columns of vertices."""
        return self.vertices.shape[0], self.vertices.shape[1]

    @property
    def face_shape(self) -> tuple[int, int]:
        """``(m, n)`` faces, or ``(m, n+1)`` when closed."""
        m1, n1 = self.shape
        return m1 - 1, (n1 if self.closed else n1 - 1)

    @property
    def n_faces(self) -> int:
        return int(np.prod(self.face_shape))

    # -- geometry ------------------------------------------------------------------------
    @cached_property
    def face_corners(self) -> np.ndarray:
        """``(m, n', 4, 3)`` corners of every face (see :func:`face_corners_of_grid`)."""
        return face_corners_of_grid(self.vertices, self.closed)

    @cached_property
    def face_planes(self) -> np.ndarray:
        """``(m, n', 4)`` unit face planes oriented by corner order."""
        return face_planes_of_corners(self.face_corners)

    def rows(self) -> np.ndarray:
        """Row polylines ``v[i, :]``, shape ``(m+1, n+1, 3)`` (planes ``U_i``)."""
        return self.vertices

    def cols(self) -> np.ndarray:
        """Column polylines ``v[:, j]``, shape ``(n+1, m+1, 3)`` (planes ``W_j``)."""
        return self.vertices.transpose(1, 0, 2)

    def edges_u(self) -> np.ndarray:
        """Edge vectors along rows ``v[i, j+1] − v[i, j]``, ``(m+1, n', 3)``."""
        v = self.vertices
        return (np.roll(v, -1, axis=1) - v) if self.closed else np.diff(v, axis=1)

    def edges_v(self) -> np.ndarray:
        """Edge vectors along columns ``v[i+1, j] − v[i, j]``, ``(m, n+1, 3)``."""
        return np.diff(self.vertices, axis=0)

    def diagonals(self) -> tuple[np.ndarray, np.ndarray]:
        """Face diagonals ``c2 − c0`` and ``c3 − c1``, each ``(m, n', 3)``."""
        c = self.face_corners
        return c[..., 2, :] - c[..., 0, :], c[..., 3, :] - c[..., 1, :]

    # -- conversion ---------------------------------------------------------------------
    @cached_property
    def vertex_index(self) -> np.ndarray:
        """``(m+1, n+1)`` row-major vertex ids used by :meth:`to_quadmesh` and OBJ output."""
        m1, n1 = self.shape
        return np.arange(m1 * n1).reshape(m1, n1)

    def to_quadmesh(self) -> "QuadMesh":
        """The same mesh as a :class:`QuadMesh` (row-major vertices and faces); lossless."""
        faces = grid_face_indices(self.vertex_index, self.closed).reshape(-1, 4)
        return QuadMesh(self.vertices.reshape(-1, 3), faces, grid=self)

    def with_vertices(self, vertices: np.ndarray, **changes: Any) -> "QuadGrid":
        """A copy with new vertices (planes, axes and the construction record dropped unless given)."""
        keep: dict[str, Any] = {"support_u": None, "support_w": None, "face_image": None, "axes": None,
                                "extended_face_image": None, "extended_face_planes": None, "meta": {}}
        keep.update(changes)
        return replace(self, vertices=vertices, **keep)

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """Triangulated view: vertices ``(N, 3)`` in row-major order and ``(2F, 3)`` triangles
        (:meth:`QuadMesh.triangles`)."""
        qm = self.to_quadmesh()
        return qm.vertices, qm.triangles()


class QuadMesh:
    """Any all-quad mesh.

    Parameters
    ----------
    vertices : (N, 3) float
    faces : (F, 4) int, corner order gives the orientation
    grid : the :class:`QuadGrid` this mesh was made from or recovered as, if any
    grid_ids : (m+1, n+1) int — the vertex id of grid vertex ``v[i, j]`` in this mesh
        (row-major when omitted)
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, grid: QuadGrid | None = None,
                 grid_ids: np.ndarray | None = None):
        v = np.asarray(vertices, dtype=float)
        f = np.asarray(faces)
        if v.ndim != 2 or v.shape[1] != 3:
            raise GeometryError(f"vertices need shape (N, 3), got {v.shape}")
        if f.ndim != 2 or f.shape[1] != 4:
            raise GeometryError(f"faces need shape (F, 4), got {f.shape}")
        if len(f) and (f.min() < 0 or f.max() >= len(v)):
            raise GeometryError("a face refers to a vertex that does not exist")
        if not np.all(np.isfinite(v)):
            k = int(np.argwhere(~np.isfinite(v))[0][0])
            raise GeometryError(f"vertex {k} is not finite (NaN or inf)", element=f"vertex {k}")
        self.vertices = _readonly(v)
        self.faces = _readonly(f, np.int64)
        self._grid = grid
        if grid is not None and grid_ids is None:
            grid_ids = grid.vertex_index
        self.grid_ids = _readonly(grid_ids, np.int64)

    def __repr__(self) -> str:
        return f"QuadMesh(V={len(self.vertices)}, F={len(self.faces)})"

    @cached_property
    def topology(self) -> Topology:
        return Topology(self.faces, len(self.vertices))

    @property
    def polylines(self) -> list[Polyline]:
        """Mesh polylines (see :mod:`ppfab.topology`), family 0 = rows on a grid."""
        if self._grid is not None:
            return self._grid_polylines
        return self.topology.polylines

    @cached_property
    def _grid_polylines(self) -> list[Polyline]:
        g = self._grid
        ids = self.grid_ids
        assert g is not None and ids is not None, "grid polylines of a mesh that was not made from a grid"
        rows = [Polyline(ids[i].copy(), g.closed, 0) for i in range(ids.shape[0])]
        cols = [Polyline(ids[:, j].copy(), False, 1) for j in range(ids.shape[1])]
        return rows + cols

    def family(self, k: int) -> list[Polyline]:
        """Polylines of family ``k`` (0 or 1)."""
        return [p for p in self.polylines if p.family == k]

    @cached_property
    def face_corners(self) -> np.ndarray:
        """``(F, 4, 3)`` face corner coordinates."""
        return self.vertices[self.faces]

    @cached_property
    def face_planes(self) -> np.ndarray:
        """``(F, 4)`` unit face planes oriented by corner order."""
        return face_planes_of_corners(self.face_corners)

    @cached_property
    def edges(self) -> np.ndarray:
        """Unique undirected edges ``(E, 2)``."""
        return self.topology.edges

    def edge_lengths(self) -> np.ndarray:
        e = self.edges
        return np.linalg.norm(self.vertices[e[:, 1]] - self.vertices[e[:, 0]], axis=1)

    def diagonals(self) -> tuple[np.ndarray, np.ndarray]:
        """Face diagonals ``c2 − c0`` and ``c3 − c1``, each ``(F, 3)``."""
        c = self.face_corners
        return c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]

    @property
    def grid(self) -> QuadGrid | None:
        """The grid this mesh came from, if it was made from one."""
        return self._grid

    def to_grid(self) -> QuadGrid:
        """Recover the regular patch from connectivity, whatever the vertex order.

        Raises :class:`GeometryError` saying why when the mesh is not a
        regular grid (disk with four corners or annulus with closed rows).
        """
        if self._grid is not None:
            return self._grid
        found = recover_grid(self.topology)
        if isinstance(found, str):
            raise GeometryError(f"not a regular grid: {found}")
        ids, closed = found
        return QuadGrid(self.vertices[ids], closed=closed, vertex_ids=ids)

    def try_grid(self) -> QuadGrid | None:
        """:meth:`to_grid`, or ``None`` when the mesh is not a regular patch."""
        try:
            return self.to_grid()
        except GeometryError:
            return None

    def with_vertices(self, vertices: np.ndarray) -> "QuadMesh":
        """Same connectivity, new positions (a grid origin is carried along)."""
        grid = None
        if self._grid is not None:
            grid = self._grid.with_vertices(np.asarray(vertices)[self.grid_ids])
        return QuadMesh(vertices, self.faces, grid=grid, grid_ids=self.grid_ids)

    def triangles(self) -> np.ndarray:
        """``(2F, 3)`` vertex indices of a triangulated view: every face split along its diagonal 0–2
        (triangles ``(0, 1, 2)`` of all faces, then ``(0, 2, 3)``), for display and export."""
        f = self.faces
        return np.concatenate([f[:, [0, 1, 2]], f[:, [0, 2, 3]]], axis=0)


def as_quadmesh(mesh: QuadMesh | QuadGrid) -> QuadMesh:
    """A :class:`QuadMesh` view of either mesh type (a grid becomes its row-major quad mesh, keeping the grid).

    Raises :class:`GeometryError` for anything else."""
    if isinstance(mesh, QuadGrid):
        return mesh.to_quadmesh()
    if not isinstance(mesh, QuadMesh):
        raise GeometryError(f"expected a QuadMesh or QuadGrid, got {type(mesh).__name__}")
    return mesh

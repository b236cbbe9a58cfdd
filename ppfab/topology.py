"""Combinatorics of all-quad meshes: edges, vertex fans, polylines, grid recovery.

Mesh polylines are traced "straight" through a vertex: an edge continues
into the edge two face-steps further around the vertex.  They pass through
interior vertices of valence 4 and boundary vertices with a regular fan
(two faces, three edges); they stop at singular vertices, at corners
(including the re-entrant corners of a jagged boundary, three faces and four
edges) and at the boundary.

The two polyline families are found by 2-colouring edges through faces:
in a quad, edges 0 and 2 (corner pairs (0,1), (2,3)) belong to one family,
edges 1 and 3 to the other.  Around a singular vertex of odd valence this
colouring can be inconsistent; :attr:`Topology.families_consistent` says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components

from .errors import DesignError

FAMILY_NAMES: tuple[str, str] = ("rows", "cols")
"""The one encoding of the two polyline families: family 0 = ``"rows"`` (``v[i, :]``, planes ``U_i``),
family 1 = ``"cols"`` (``v[:, j]``, planes ``W_j``)."""


def family_index(family: int | str, key: str = "family") -> int:
    """0 for ``"rows"`` (also ``0``, ``"U"``), 1 for ``"cols"`` (also ``1``, ``"W"``); else :class:`DesignError`.

    >>> family_index("cols"), family_index(0)
    (1, 0)
    """
    if family in (0, "rows", "U", "u"):
        return 0
    if family in (1, "cols", "W", "w"):
        return 1
    raise DesignError(key, f"must be 'rows' or 'cols', got {family!r}")


def families_of(choice: str) -> tuple[str, ...]:
    """The families an ``[optimize] families`` choice makes planar: ``"both"`` → ``("rows", "cols")``.

    >>> families_of("both"), families_of("cols"), families_of("none")
    (('rows', 'cols'), ('cols',), ())
    """
    return {"rows": ("rows",), "cols": ("cols",), "both": FAMILY_NAMES}.get(choice, ())




@dataclass(frozen=True)
class Polyline:
    """A mesh polyline: vertex indices in order, whether it closes, its family (0 or 1)."""

    vertices: np.ndarray
    closed: bool
    family: int

    def __len__(self) -> int:
        return len(self.vertices)


class Topology:
    """Derived combinatorics of a quad mesh ``faces (F, 4)`` with ``n_vertices`` vertices."""

    def __init__(self, faces: np.ndarray, n_vertices: int):
        self.faces = np.asarray(faces, dtype=np.int64)
        self.n_vertices = int(n_vertices)

    # -- half edges ---------------------------------------------------------------
    @cached_property
    def half_edges(self) -> np.ndarray:
        """``(4F, 2)`` directed edges ``faces[f, k] → faces[f, k+1]`` in face order."""
        f = self.faces
        return np.stack([f.ravel(), np.roll(f, -1, axis=1).ravel()], axis=1)

    def _key(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return a * self.n_vertices + b

    @cached_property
    def edges(self) -> np.ndarray:
        """Unique undirected edges ``(E, 2)`` with ``a < b``, sorted."""
        he = np.sort(self.half_edges, axis=1)
        n = max(self.n_vertices, int(he.max(initial=-1)) + 1)
        keys = np.unique(he[:, 0] * n + he[:, 1])          # lexicographic (a, b) order, as unique(axis=0)
        return np.stack([keys // n, keys % n], axis=1).reshape(-1, 2)

    @cached_property
    def edge_faces(self) -> np.ndarray:
        """``(E, 2)`` the faces on either side of each edge (``-1`` on the boundary)."""
        he = self.half_edges
        lo, hi = np.sort(he, axis=1).T
        eid = np.searchsorted(self._key(*self.edges.T), self._key(lo, hi))
        face_of = np.repeat(np.arange(len(self.faces)), 4)
        out = -np.ones((len(self.edges), 2), dtype=np.int64)
        order = np.argsort(eid, kind="stable")
        eid_s, face_s = eid[order], face_of[order]
        first = np.r_[True, eid_s[1:] != eid_s[:-1]]
        out[eid_s[first], 0] = face_s[first]
        out[eid_s[~first], 1] = face_s[~first]
        return out

    @cached_property
    def edge_face_count(self) -> np.ndarray:
        """How many face corners use each undirected edge (1 boundary, 2 interior, >2 non-manifold)."""
        lo, hi = np.sort(self.half_edges, axis=1).T
        eid = np.searchsorted(self._key(*self.edges.T), self._key(lo, hi))
        return np.bincount(eid, minlength=len(self.edges))

    @cached_property
    def valence(self) -> np.ndarray:
        """Number of edges at each vertex, ``(N,)``."""
        return np.bincount(self.edges.ravel(), minlength=self.n_vertices)

    @cached_property
    def boundary_vertices(self) -> np.ndarray:
        """Boolean ``(N,)``: vertex lies on a boundary edge."""
        b = np.zeros(self.n_vertices, dtype=bool)
        b[self.edges[self.edge_face_count == 1].ravel()] = True
        return b

    @cached_property
    def face_count(self) -> np.ndarray:
        """Faces at each vertex, ``(N,)``."""
        return np.bincount(self.faces.ravel(), minlength=self.n_vertices)

    # -- rotation around vertices -------------------------------------------------
    @cached_property
    def _rotation(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Sorted keys of directed edges (v→q) and the edge one face further (v→p) around v.

        In face ``(…, p, v, q, …)`` the edges ``v→q`` and ``v→p`` are consecutive
        around ``v``; the map ``v→q ↦ v→p`` rotates by one face.
        """
        f = self.faces
        v = f.ravel()
        q = np.roll(f, -1, axis=1).ravel()
        p = np.roll(f, 1, axis=1).ravel()
        src = self._key(v, q)
        dst = self._key(v, p)
        order = np.argsort(src)
        return src[order], dst[order], np.repeat(np.arange(len(f)), 4)[order]

    def _rotate(self, keys: np.ndarray, forward: bool = True) -> np.ndarray:
        src, dst, _ = self._rotation
        a, b = (src, dst) if forward else (dst, src)
        order = np.argsort(a)
        a_s, b_s = a[order], b[order]
        pos = np.searchsorted(a_s, keys)
        pos = np.clip(pos, 0, len(a_s) - 1)
        found = a_s[pos] == keys
        return np.where(found, b_s[pos], -1)

    def _regular_through(self) -> np.ndarray:
        """Boolean ``(N,)``: polylines may pass straight through this vertex."""
        interior = ~self.boundary_vertices
        reg_interior = interior & (self.valence == 4) & (self.face_count == 4)
        reg_boundary = self.boundary_vertices & (self.valence == 3) & (self.face_count == 2)
        return reg_interior | reg_boundary

    @cached_property
    def opposite(self) -> dict[int, int]:
        """Map key(v→a) → key(v→b) with ``v→b`` straight on from ``a→v`` (two face-steps round v)."""
        n = self.n_vertices
        he = self.half_edges
        keys = np.unique(np.concatenate([self._key(he[:, 0], he[:, 1]), self._key(he[:, 1], he[:, 0])]))
        two_fwd = self._rotate(self._rotate(keys, True), True)
        two_fwd = np.where(self._rotate(keys, True) < 0, -1, two_fwd)
        two_bwd = self._rotate(self._rotate(keys, False), False)
        two_bwd = np.where(self._rotate(keys, False) < 0, -1, two_bwd)
        result = np.where(two_fwd >= 0, two_fwd, two_bwd)
        vert = keys // n
        ok = (result >= 0) & self._regular_through()[vert]
        return dict(zip(keys[ok].tolist(), result[ok].tolist()))

    # -- polylines -----------------------------------------------------------------
    @cached_property
    def edge_family(self) -> np.ndarray:
        """``(E,)`` family label 0/1 of each edge from face 2-colouring."""
        return self._colouring[0]

    @cached_property
    def families_consistent(self) -> bool:
        """False when the face 2-colouring of edges meets a contradiction (odd singularity)."""
        return self._colouring[1]

    @cached_property
    def _colouring(self) -> tuple[np.ndarray, bool]:
        faces = self.faces
        nf = len(faces)
        he = self.half_edges
        lo, hi = np.sort(he, axis=1).T
        eid = np.searchsorted(self._key(*self.edges.T), self._key(lo, hi)).reshape(nf, 4)
        ef = self.edge_faces
        interior = (ef[:, 1] >= 0)
        adj = coo_matrix((np.ones(interior.sum() * 2),
                          (np.r_[ef[interior, 0], ef[interior, 1]], np.r_[ef[interior, 1], ef[interior, 0]])),
                         shape=(nf, nf)).tocsr()
        ncomp, comp = connected_components(adj, directed=False)
        # position of each edge inside each of its faces
        pos = {}
        for f in range(nf):
            for k in range(4):
                pos[(f, int(eid[f, k]))] = k
        phase = -np.ones(nf, dtype=np.int64)
        consistent = True
        for c in range(ncomp):
            root = int(np.flatnonzero(comp == c)[0])
            order, pred = breadth_first_order(adj, root, directed=False, return_predecessors=True)
            phase[root] = 0
            for f in order[1:]:
                g = pred[f]
                shared = set(eid[f].tolist()) & set(eid[g].tolist())
                e = shared.pop()
                phase[f] = (pos[(g, e)] + phase[g] - pos[(f, e)]) % 2
        label = -np.ones(len(self.edges), dtype=np.int64)
        # family 0 = odd positions when phase 0, so that on a row-major grid family 0 = rows
        lab_fk = (np.arange(4)[None, :] + 1 + phase[:, None]) % 2
        for f in range(nf):
            for k in range(4):
                e = eid[f, k]
                if label[e] < 0:
                    label[e] = lab_fk[f, k]
                elif label[e] != lab_fk[f, k]:
                    consistent = False
        return label, consistent

    @cached_property
    def polylines(self) -> list[Polyline]:
        """All mesh polylines, each edge in exactly one; traced straight through regular vertices."""
        n = self.n_vertices
        opp = self.opposite
        edges = self.edges
        ekey = self._key(*edges.T)
        visited = np.zeros(len(edges), dtype=bool)

        def eindex(a: int, b: int) -> int:
            lo, hi = (a, b) if a < b else (b, a)
            return int(np.searchsorted(ekey, lo * n + hi))

        def walk(a: int, b: int, start_edge: int) -> tuple[list[int], bool]:
            """From directed edge a→b go on; return vertices after ``b`` and whether we closed."""
            out: list[int] = []
            while True:
                nxt = opp.get(b * n + a)
                if nxt is None:
                    return out, False
                c = nxt % n
                e = eindex(b, c)
                if e == start_edge:
                    return out, True
                if visited[e]:
                    return out, False
                visited[e] = True
                out.append(c)
                a, b = b, c

        result: list[Polyline] = []
        labels = self.edge_family
        for e in range(len(edges)):
            if visited[e]:
                continue
            visited[e] = True
            a, b = (int(x) for x in edges[e])
            fwd, closed = walk(a, b, e)
            if closed:
                verts = [a, b] + fwd
            else:
                bwd, _ = walk(b, a, e)
                verts = bwd[::-1] + [a, b] + fwd
            seq = np.asarray(verts, dtype=np.int64)
            if closed and len(seq) > 1 and seq[-1] == seq[0]:
                seq = seq[:-1]
            result.append(Polyline(seq, closed, int(labels[e])))
        # deterministic order: by family, then smallest vertex id
        result.sort(key=lambda p: (p.family, int(p.vertices.min()), len(p)))
        return result


def recover_grid(topo: Topology) -> tuple[np.ndarray, bool] | str:
    """Recover the grid index array of a regular patch from connectivity alone.

    Returns ``(ids, closed)`` with ``ids (m+1, n+1)`` the vertex index of
    ``v[i, j]`` and ``closed`` whether rows close (``j`` periodic), such that
    every face equals ``v[i,j], v[i+1,j], v[i+1,j+1], v[i,j+1]`` up to its
    starting corner — or a string saying why the mesh is not a regular grid.
    """
    faces = topo.faces
    nv = topo.n_vertices
    if not topo.families_consistent:
        return "polyline families cannot be told apart consistently (odd singular vertex)"
    interior = ~topo.boundary_vertices
    bad = np.flatnonzero(interior & (topo.valence != 4))
    if len(bad):
        return f"interior vertex {int(bad[0])} has valence {int(topo.valence[bad[0]])} (singular)"
    lines = topo.polylines
    fam = [[p for p in lines if p.family == k] for k in (0, 1)]
    closed0 = [p.closed for p in fam[0]]
    closed1 = [p.closed for p in fam[1]]
    if any(closed1) and not any(closed0):
        fam = fam[::-1]
        closed0, closed1 = closed1, closed0
    if any(closed1):
        return "polylines of both families close (a torus is not a patch)"
    if any(closed0) and not all(closed0):
        return "some but not all polylines of one family are closed"
    closed = all(closed0) and len(closed0) > 0
    member = -np.ones(nv, dtype=np.int64)   # family-0 polyline through each vertex
    where = -np.ones(nv, dtype=np.int64)
    for k, p in enumerate(fam[0]):
        if np.any(member[p.vertices] >= 0):
            return "a vertex lies on two polylines of the same family"
        member[p.vertices] = k
        where[p.vertices] = np.arange(len(p))
    if np.any(member < 0):
        return f"vertex {int(np.flatnonzero(member < 0)[0])} lies on no polyline of the first family"
    col: np.ndarray | None
    if closed:
        col = fam[1][0].vertices
    else:
        corners = np.flatnonzero(topo.boundary_vertices & (topo.valence == 2) & (topo.face_count == 1))
        if len(corners) != 4:
            return f"boundary has {len(corners)} corners, a patch needs 4"
        c = int(corners.min())
        col = next((p.vertices for p in fam[1] if p.vertices[0] == c or p.vertices[-1] == c), None)
        if col is None:
            return "no polyline starts at a corner"
        if col[0] != c:
            col = col[::-1]
    rows = []
    for vtx in col:
        p = fam[0][member[vtx]]
        seq = p.vertices
        s = int(where[vtx])
        if closed:
            seq = np.roll(seq, -s)
        elif s == len(seq) - 1:
            seq = seq[::-1]
        elif s != 0:
            return f"row through vertex {int(vtx)} does not start on the boundary column"
        rows.append(seq)
    if len({len(r) for r in rows}) != 1:
        return "rows have different lengths (not a regular grid)"
    ids = np.array(rows)
    if len(np.unique(ids)) != nv or ids.size != nv:
        return "vertices are not covered exactly once by the grid"
    # orient each row so that consecutive rows bound faces
    face_set = {tuple(sorted(f)) for f in faces.tolist()}
    for i in range(1, len(ids)):
        quad = tuple(sorted((ids[i - 1, 0], ids[i, 0], ids[i, 1], ids[i - 1, 1])))
        if quad not in face_set:
            if closed:
                ids[i] = np.roll(ids[i][::-1], 1)
            else:
                return "rows are not aligned"
    m1, n1 = ids.shape
    ncols = n1 if closed else n1 - 1
    if len(faces) != (m1 - 1) * ncols:
        return f"{len(faces)} faces, a {m1} x {n1} grid has {(m1 - 1) * ncols}"
    grid_faces = grid_face_indices(ids, closed)
    if {tuple(sorted(f)) for f in grid_faces.reshape(-1, 4).tolist()} != face_set:
        return "faces do not match the recovered grid"
    # orientation: reverse j if the file's faces run the other way
    g0 = grid_faces.reshape(-1, 4)[0].tolist()
    f0 = next(f for f in faces.tolist() if sorted(f) == sorted(g0))
    k = f0.index(g0[0])
    if np.roll(f0, -k).tolist() != g0:
        ids = ids[:, ::-1] if not closed else np.roll(ids[:, ::-1], 1, axis=1)
    return ids, closed


def grid_face_indices(ids: np.ndarray, closed: bool) -> np.ndarray:
    """Face corner indices ``(m, n', 4)`` of a grid of vertex ids (``n' = n+1`` when closed)."""
    nxt = np.roll(ids, -1, axis=1) if closed else ids[:, 1:]
    cur = ids if closed else ids[:, :-1]
    return np.stack([cur[:-1], cur[1:], nxt[1:], nxt[:-1]], axis=-1)

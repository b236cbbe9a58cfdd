"""Residuals of the energies of §3.3 and their analytic sparse Jacobian.

Variables (paper §3.3): the vertices ``v``, a normal ``n_f`` per face and a
normal ``n_σ`` per support plane (one per selected polyline).  With the
residual vector ``r`` the total energy is ``E = ‖r‖²`` where

* ``E_f = Σ_f Σ_{edges vw of f} ⟨n_f, v − w⟩²`` — rows ``√λ_f ⟨n_f, w − v⟩``,
* ``E_P = Σ_σ Σ_{edges vw of σ} ⟨n_σ, v − w⟩²`` — rows ``√λ_P ⟨n_σ, w − v⟩``,
* ``E_1 = Σ (‖n‖² − 1)²`` over all face and support normals — rows ``√λ_1 (‖n‖² − 1)``,
* ``E_fair = Σ_{triples uvw} ‖(u − v) − (v − w)‖²`` along polylines — rows ``√(s λ_fair) (u − 2v + w − t)``
  with ``t = 0`` (absolute, the paper) or ``t`` = the input's second difference (relative),
* ``E_close = Σ_v ‖v − v⁰‖²`` (rows ``√(s λ_close) (v − v⁰)``) or, towards a reference surface,
  ``Σ_v ⟨n⁰_v, v − p⁰_v⟩²`` with foot points ``p⁰`` and unit normals ``n⁰`` (rows ``√(s λ_close) ⟨n⁰, v − p⁰⟩``),
  plus, towards a surface, ``E_slide = Σ_v ‖v − v⁰‖²`` with the small weight ``s λ_close ε`` (``ε`` = slide):
  the vertices may slide along the surface, but not freely (absolute fairness would otherwise shrink the
  mesh along its own surface and pull in its boundary),
* ``E_shape`` (not in the paper): a one-sided barrier that keeps quads from degenerating.  For every
  face corner, ``a = ((v_k − v_{k−1}) × (v_{k+1} − v_k))·m_f / ℓ_f²`` is twice the signed area of the
  corner triangle measured against a reference unit normal ``m_f`` of the face (``ℓ_f`` = mean input edge
  length of the face); rows ``√λ_shape max(0, κ a⁰ − a)``.  For every edge, rows
  ``√λ_shape max(0, κ − ‖v − w‖² / ‖v⁰ − w⁰‖²)``.  Zero as long as every corner keeps the fraction ``κ``
  of its input area and every edge ``√κ`` of its input length, so it does not bias a good solution,
* ``E_conical = Σ_v (α_0 − α_1 + α_2 − α_3)²`` over interior valence-4 vertices (§2.3.3; the mesh is conical
  iff every row vanishes) — rows ``√λ_c (α_0 − α_1 + α_2 − α_3)``, see :mod:`.terms`,
* ``E_orth`` (near-rectangular panels, §4): per face corner ``c = cos α``; rows ``√(s λ_⊥) c`` (``"right"``) or
  ``√λ_⊥ max(0, |c| − |c⁰|)`` (``"keep"``: no corner moves further from 90° than in the input),
* ``E_crease`` (a barrier, not in the paper): per interior edge, with ``θ_e`` the angle between the diagonal
  normals of its two faces, rows ``√λ_shape max(0, θ_e − θ_b)`` (radians), ``θ_b`` a few degrees below the
  crease limit of the step guard: the gradient turns the solver away from creasing an edge before the guard
  has to refuse the step,
* ``E_axes`` (right angles between support planes and panels, §2.3.2): ``Σ_σ Σ_{faces f along σ} ⟨n_σ, n_f⟩²``
  — rows ``√(s λ_axes) ⟨n_σ, n_f⟩``.  Zero when every support plane is normal to the panels it carries, which
  puts the node axis ``U_i ∩ W_j`` of a PP mesh along the surface normal,
* ``E_nodes = Σ_{nodes} ⟨n_U, n_W⟩²`` over the vertices where a planar row (normal ``n_U``) and a planar column
  (``n_W``) cross (§2.3.4, orthogonal nodes: the two support planes at right angles) — rows ``√λ_⊥n ⟨n_U, n_W⟩``;
  it acts through the support normals, so it needs them among the unknowns (``plane_unknowns``),
* ``E_circular = Σ_f (α_0 − α_1 + α_2 − α_3)²`` over the faces, ``α_k`` the corner angles (§2.3.3, Remark 2.1;
  with planar faces the mesh is circular iff every row vanishes) — rows ``√λ_○ (α_0 − α_1 + α_2 − α_3)``, see
  :func:`.terms.face_angle_balance`,

``s`` being the regularisation factor of the current stage (1 at the start): the soft goals (fairness,
closeness, right angles, axes) fade with it, the constraints and barriers keep their weights.
The paper's total energy is ``λ_P E_P + λ_f E_f + λ_1 E_1 + λ_fair E_fair``.

The full state is one flat vector ``z = [V (N·3), N_σ (S·3), N_f (F·3)]``;
the unknowns ``x = z[free]`` omit the coordinates of fixed vertices.  The
Jacobian has a fixed sparsity pattern: its CSC structure is computed once and
only the values are refilled per iteration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from ..topology import Polyline
from .selection import edge_pairs, triples
from .terms import (angle_balance, corner_cosines, crease_stars, dihedral, dihedral_and_grad, face_angle_balance,
                    face_corners_index)

BLOCKS = ("E_f", "E_P", "E_1", "E_fair", "E_close", "E_shape_corner", "E_shape_edge", "E_conical", "E_orth",
          "E_axes", "E_slide", "E_crease", "E_circular", "E_nodes")


@dataclass(frozen=True)
class Weights:
    """The λ of §3.3 (``planarity`` = λ_P, ``faces`` = λ_f, ``unit`` = λ_1), the regularisers and the barrier."""

    planarity: float = 1.0
    faces: float = 1.0
    unit: float = 1.0
    fair: float = 0.01
    close: float = 0.01
    shape: float = 1.0
    shape_ratio: float = 0.25
    conical: float = 0.0
    orthogonal: float = 0.0
    axes: float = 0.0
    slide: float = 0.3
    circular: float = 0.0
    nodes: float = 0.0


class Residuals:
    """The residual vector ``r(z, s)`` and its Jacobian ``∂r/∂x``.

    Parameters
    ----------
    vertices0 : (N, 3) float, the input (already normalised) vertices
    faces : (F, 4) int
    edges : (E, 2) int, unique undirected edges (for the edge barrier)
    planar : polylines that get a support plane
    fair : polylines that carry E_fair
    free : (N,) bool, vertices that may move
    weights : :class:`Weights`
    fairness : ``"absolute"`` or ``"relative"``
    closeness : ``"vertices"``, ``"surface"`` or ``"none"``
    planar_faces : include E_f and the face normals
    plane_unknowns : keep the support normals among the unknowns of the linear system; by default they
        are eliminated by variable projection instead (:meth:`project_normals` after every step), which
        keeps the system as sparse as the mesh (a support normal couples all vertices of its polyline)
    stars : (K, 5) int, conical stars ``[v, w_0..w_3]`` (:func:`.terms.conical_stars`) for ``E_conical``
    orthogonality : ``"right"`` or ``"keep"`` (``E_orth``)
    axes_pairs : ``(owner (P,), face (P,))`` support plane / face pairs of ``E_axes`` (:func:`.terms.polyline_faces`)
    edge_faces, crease_start : ``(E, 2)`` faces of every edge and ``θ_b`` (radians) of ``E_crease`` (off if ``None``)
    circles : (C, 4) int, the faces of ``E_circular`` (off if ``None`` or ``weights.circular`` is 0)
    nodes : (K, 2) int, positions in ``planar`` of the row and the column crossing at each node of ``E_nodes``
        (off if ``None`` or ``weights.nodes`` is 0)
    """

    def __init__(self, vertices0: np.ndarray, faces: np.ndarray, edges: np.ndarray, planar: list[Polyline],
                 fair: list[Polyline], free: np.ndarray, weights: Weights, fairness: str = "relative",
                 closeness: str = "vertices", planar_faces: bool = True, plane_unknowns: bool = False,
                 stars: np.ndarray | None = None, orthogonality: str = "keep",
                 axes_pairs: tuple[np.ndarray, np.ndarray] | None = None,
                 edge_faces: np.ndarray | None = None, crease_start: float | None = None,
                 circles: np.ndarray | None = None, nodes: np.ndarray | None = None):
        v0 = np.asarray(vertices0, dtype=float)
        faces = np.asarray(faces, dtype=np.int64)
        edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        self.vertices0 = v0
        self.n_vertices = nv = len(v0)
        self.weights = weights
        self.closeness = closeness
        self.n_faces = nf = len(faces) if (planar_faces and weights.faces > 0) else 0
        self.n_planes = ns = len(planar) if weights.planarity > 0 else 0
        self.free = np.asarray(free, dtype=bool)
        # -- variable layout: [vertices, support normals, face normals] ------------------------
        self.n_full = 3 * (nv + ns + nf)
        self.v_slice = slice(0, 3 * nv)
        self.s_slice = slice(3 * nv, 3 * (nv + ns))
        self.f_slice = slice(3 * (nv + ns), self.n_full)
        free_full = np.ones(self.n_full, dtype=bool)
        free_full[: 3 * nv] = np.repeat(self.free, 3)
        free_full[self.s_slice] = plane_unknowns
        self.plane_unknowns = plane_unknowns
        self.free_index = np.flatnonzero(free_full)
        self.n_unknowns = len(self.free_index)
        self.n_face_unknowns = 3 * nf
        col_of = -np.ones(self.n_full, dtype=np.int64)
        col_of[self.free_index] = np.arange(self.n_unknowns)
        vcol = col_of[self.v_slice].reshape(nv, 3)
        scol = col_of[self.s_slice].reshape(ns, 3)
        fcol = col_of[self.f_slice].reshape(nf, 3)
        # -- residual blocks --------------------------------------------------------------------
        fa = faces[:nf].ravel()
        fb = np.roll(faces[:nf], -1, axis=1).ravel()
        self.face_edges = (fa, fb, np.repeat(np.arange(nf), 4))
        pairs, pown = edge_pairs(planar[:ns])
        self.plane_edges = (pairs[:, 0], pairs[:, 1], pown)
        self.triples = triples(fair) if weights.fair > 0 else np.zeros((0, 3), dtype=np.int64)
        ta, tb, tc = self.triples.T
        self.fair_target = (v0[ta] - 2 * v0[tb] + v0[tc]) if fairness == "relative" \
            else np.zeros((len(self.triples), 3))
        use_close = closeness != "none" and weights.close > 0
        self.close_vertices = np.flatnonzero(self.free) if use_close else np.zeros(0, dtype=np.int64)
        self.slide_vertices = self.close_vertices if (closeness == "surface" and weights.slide > 0) \
            else np.zeros(0, dtype=np.int64)
        self.ref_points = v0.copy()
        self.ref_normals = np.zeros_like(v0)
        # shape barrier on corners and edges
        shape_faces = faces if weights.shape > 0 else np.zeros((0, 4), dtype=np.int64)
        self.shape_faces = shape_faces
        self.corner = (np.roll(shape_faces, 1, axis=1).ravel(), shape_faces.ravel(),
                       np.roll(shape_faces, -1, axis=1).ravel())
        self.corner_face = np.repeat(np.arange(len(shape_faces)), 4)
        quads = v0[shape_faces]
        self.face_scale2 = np.linalg.norm(quads - np.roll(quads, -1, axis=1), axis=-1).mean(axis=1) ** 2
        self.set_shape_reference(v0)
        self.corner_floor = weights.shape_ratio * self._corner_area(v0)
        self.shape_edges = edges if weights.shape > 0 else np.zeros((0, 2), dtype=np.int64)
        se = self.shape_edges
        self.edge_len2 = np.einsum("ij,ij->i", v0[se[:, 1]] - v0[se[:, 0]], v0[se[:, 1]] - v0[se[:, 0]])
        # geometric goals: conical stars, corner angles, support planes normal to the panels
        no_int = np.zeros((0, 5), dtype=np.int64)
        self.stars = np.asarray(stars, dtype=np.int64).reshape(-1, 5) if (stars is not None and weights.conical > 0) \
            else no_int
        self.orthogonality = orthogonality
        self.corners = face_corners_index(faces) if weights.orthogonal > 0 else np.zeros((0, 3), dtype=np.int64)
        self.corner_cos0 = np.abs(corner_cosines(v0, self.corners)[0])
        ao, af = axes_pairs if (axes_pairs is not None and weights.axes > 0 and ns and nf) else \
            (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
        self.axes_pairs = (np.asarray(ao, dtype=np.int64), np.asarray(af, dtype=np.int64))
        if edge_faces is not None and crease_start is not None and weights.shape > 0:
            self.crease_verts, self.crease_slot = crease_stars(faces, edge_faces)
        else:
            self.crease_verts, self.crease_slot = np.zeros((0, 6), dtype=np.int64), np.zeros((0, 4), dtype=np.int64)
        self.crease_start = float(crease_start) if crease_start is not None else np.pi
        self.circles = np.asarray(circles, dtype=np.int64).reshape(-1, 4) \
            if (circles is not None and weights.circular > 0) else np.zeros((0, 4), dtype=np.int64)
        self.nodes = np.asarray(nodes, dtype=np.int64).reshape(-1, 2) \
            if (nodes is not None and weights.nodes > 0 and ns) else np.zeros((0, 2), dtype=np.int64)
        # -- Jacobian pattern, block by block in value order ------------------------------------------
        cv = self.close_vertices
        close_cols = vcol[cv].reshape(-1, 1) if closeness == "vertices" else vcol[cv]
        cp, ck, cq = self.corner
        cols_per_block = [
            np.concatenate([vcol[fb], vcol[fa], fcol[self.face_edges[2]]], axis=1),
            np.concatenate([vcol[pairs[:, 1]], vcol[pairs[:, 0]], scol[pown]], axis=1),
            np.concatenate([fcol, scol]),
            np.stack([vcol[ta], vcol[tb], vcol[tc]], axis=-1).reshape(-1, 3),   # row (t, coord) → 3 vertices
            close_cols,
            np.concatenate([vcol[cp], vcol[ck], vcol[cq]], axis=1),
            np.concatenate([vcol[se[:, 0]], vcol[se[:, 1]]], axis=1),
            vcol[self.stars].reshape(-1, 15),
            vcol[self.corners].reshape(-1, 9),
            np.concatenate([scol[self.axes_pairs[0]], fcol[self.axes_pairs[1]]], axis=1),
            vcol[self.slide_vertices].reshape(-1, 1),
            vcol[self.crease_verts].reshape(-1, 18),
            vcol[self.circles].reshape(-1, 12),
            scol[self.nodes].reshape(-1, 6),
        ]
        cols_per_block = [np.asarray(c, dtype=np.int64) for c in cols_per_block]
        cols_per_block = [c.reshape(len(c), int(np.prod(c.shape[1:], dtype=np.int64))) for c in cols_per_block]
        sizes = [len(c) for c in cols_per_block]
        self.block_starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.n_residuals = int(self.block_starts[-1])
        # the values in order (row by row, as jacobian() lays them out); rows never decrease along it, so a
        # stable sort by column puts them in CSC order (by column, then row)
        cols_all = np.concatenate([c.ravel() for c in cols_per_block])
        per_row = np.repeat([c.shape[1] for c in cols_per_block], sizes)
        rows_all = np.repeat(np.arange(self.n_residuals, dtype=np.int64), per_row)
        keep = np.flatnonzero(cols_all >= 0)
        cols_kept = cols_all[keep]
        order = np.argsort(cols_kept, kind="stable")
        self._take = keep[order]
        self._indices = rows_all[self._take]
        self._indptr = np.concatenate([[0], np.cumsum(np.bincount(cols_kept, minlength=self.n_unknowns))]
                                      ).astype(np.int64)
        self.nnz = len(self._take)

    # -- state -----------------------------------------------------------------------------
    def pack(self, vertices: np.ndarray, plane_normals: np.ndarray, face_normals: np.ndarray) -> np.ndarray:
        """The full state ``z`` from ``(N, 3)`` vertices, ``(S, 3)`` support and ``(F, 3)`` face normals."""
        return np.concatenate([np.asarray(vertices, float).ravel(),
                               np.asarray(plane_normals, float)[: self.n_planes].ravel(),
                               np.asarray(face_normals, float)[: self.n_faces].ravel()])

    def unpack(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(vertices (N, 3), support normals (S, 3), face normals (F, 3))`` views of ``z``."""
        return (z[self.v_slice].reshape(-1, 3), z[self.s_slice].reshape(-1, 3), z[self.f_slice].reshape(-1, 3))

    def project_normals(self, z: np.ndarray) -> np.ndarray:
        """``z`` with the support normals that are not unknowns replaced by their optimum (variable projection).

        (Normals that are unknowns of the linear system are left alone: re-fitting them would make a
        nearly straight polyline's plane jump between equally good planes.)

        For fixed vertices the energy of a normal ``n`` is ``λ nᵀCn + λ_1 (‖n‖² − 1)²`` with
        ``C = Σ_edges e eᵀ`` (``λ`` = λ_P or λ_f), minimised by ``n = t·e_min`` (unit eigenvector of the
        smallest eigenvalue ``c_min`` of ``C``) with ``t² = max(0, 1 − λ c_min / (2 λ_1))``.  Signs follow
        the previous normals.
        """
        out = np.array(z, dtype=float)
        if self.plane_unknowns:
            return out
        v, ns, _ = self.unpack(out)
        w = self.weights
        for (ia, ib, own), normals, lam in ((self.plane_edges, ns, w.planarity),):
            if not len(normals):
                continue
            e = v[ib] - v[ia]
            outer = (e[:, :, None] * e[:, None, :]).reshape(len(e), 9)
            cov = np.stack([np.bincount(own, outer[:, k], minlength=len(normals)) for k in range(9)], axis=1)
            vals, vecs = np.linalg.eigh(cov.reshape(-1, 3, 3))
            n_opt = vecs[:, :, 0] * np.sqrt(np.maximum(0.0, 1.0 - lam * vals[:, 0] / (2.0 * w.unit)))[:, None]
            sign = np.where(np.einsum("ij,ij->i", n_opt, normals) < 0, -1.0, 1.0)
            normals[...] = n_opt * sign[:, None]
        return out

    def set_reference(self, points: np.ndarray, normals: np.ndarray) -> None:
        """Foot points ``(N, 3)`` and unit normals ``(N, 3)`` of the surface closeness term."""
        self.ref_points = np.asarray(points, dtype=float)
        self.ref_normals = np.asarray(normals, dtype=float)

    def set_shape_reference(self, vertices: np.ndarray) -> None:
        """Reference unit normals ``m_f (F, 3)`` of the corner barrier from the faces of ``vertices (N, 3)``."""
        c = np.asarray(vertices)[self.shape_faces]
        n = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
        self.shape_normals = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)

    def _corner_area(self, v: np.ndarray) -> np.ndarray:
        """``a`` per corner: ``((v_k − v_{k−1}) × (v_{k+1} − v_k))·m_f / ℓ_f²``."""
        cp, ck, cq = self.corner
        e1 = v[ck] - v[cp]
        e2 = v[cq] - v[ck]
        m = self.shape_normals[self.corner_face]
        return np.einsum("ij,ij->i", np.cross(e1, e2), m) / self.face_scale2[self.corner_face]

    # -- residuals ---------------------------------------------------------------------------
    def _sqrt_weights(self, s: float) -> list[float]:
        w = self.weights
        orth = s * w.orthogonal if self.orthogonality == "right" else w.orthogonal
        return [np.sqrt(w.faces), np.sqrt(w.planarity), np.sqrt(w.unit), np.sqrt(s * w.fair),
                np.sqrt(s * w.close), np.sqrt(w.shape), np.sqrt(w.shape), np.sqrt(w.conical), np.sqrt(orth),
                np.sqrt(s * w.axes), np.sqrt(s * w.close * w.slide), np.sqrt(w.shape), np.sqrt(w.circular), np.sqrt(w.nodes)]

    def blocks(self, z: np.ndarray) -> list[np.ndarray]:
        """Unweighted residual blocks in the order of :data:`BLOCKS` (not to be changed by the caller).

        The last state's blocks are kept: an LM iteration asks for them three times at one state (the trial
        step's residual, the record's energies, the next linearisation's residual).  They are reused when ``z``
        is equal element for element and the references the blocks read (foot points and their normals, the
        shape normals) are the same arrays; where only references changed (a new stage) only the blocks that read
        them are computed again."""
        z = np.asarray(z)
        key = (self.ref_points, self.ref_normals, self.shape_normals)       # held: no id is reused meanwhile
        memo = getattr(self, "_memo", None)
        if memo is not None and memo[1].shape == z.shape and np.array_equal(memo[1], z):
            if all(a is b for a, b in zip(memo[0], key)):
                return memo[2]
            out = list(memo[2])                  # a new stage's foot points or shape normals: only their blocks
            v = self.unpack(z)[0]
            if memo[0][0] is not key[0] or memo[0][1] is not key[1]:
                out[4] = self._close_block(v)
            if memo[0][2] is not key[2]:
                out[5] = np.maximum(0.0, self.corner_floor - self._corner_area(v))
            self._memo = (key, memo[1], out)
            return out
        out = self._blocks(z)
        self._memo = (key, z.copy(), out)
        return out

    def _close_block(self, v: np.ndarray) -> np.ndarray:
        """``r_close``: the vertices' offsets from their input places, or along the foot points' normals."""
        cv = self.close_vertices
        if self.closeness == "vertices":
            return (v[cv] - self.vertices0[cv]).ravel()
        return np.einsum("ij,ij->i", self.ref_normals[cv], v[cv] - self.ref_points[cv])

    def _blocks(self, z: np.ndarray) -> list[np.ndarray]:
        v, ns, nf = self.unpack(z)
        fa, fb, fown = self.face_edges
        pa, pb, pown = self.plane_edges
        r_f = np.einsum("ij,ij->i", nf[fown], v[fb] - v[fa])
        r_p = np.einsum("ij,ij->i", ns[pown], v[pb] - v[pa])
        normals = np.concatenate([nf, ns])
        r_1 = np.einsum("ij,ij->i", normals, normals) - 1.0
        a, b, c = self.triples.T
        r_fair = (v[a] - 2.0 * v[b] + v[c] - self.fair_target).ravel()
        r_close = self._close_block(v)
        r_corner = np.maximum(0.0, self.corner_floor - self._corner_area(v))
        se = self.shape_edges
        d = v[se[:, 1]] - v[se[:, 0]]
        r_edge = np.maximum(0.0, self.weights.shape_ratio - np.einsum("ij,ij->i", d, d) / self.edge_len2)
        r_con = angle_balance(v, self.stars)[0]
        cos = corner_cosines(v, self.corners)[0]
        r_orth = cos if self.orthogonality == "right" else np.maximum(0.0, np.abs(cos) - self.corner_cos0)
        ao, af = self.axes_pairs
        r_axes = np.einsum("ij,ij->i", ns[ao], nf[af])
        sv = self.slide_vertices
        r_slide = (v[sv] - self.vertices0[sv]).ravel()
        theta = dihedral(v, self.crease_verts, self.crease_slot)
        r_crease = np.maximum(0.0, theta - self.crease_start)
        r_circ = face_angle_balance(v, self.circles)[0]
        r_nodes = np.einsum("ij,ij->i", ns[self.nodes[:, 0]], ns[self.nodes[:, 1]])
        return [r_f, r_p, r_1, r_fair, r_close, r_corner, r_edge, r_con, r_orth, r_axes, r_slide, r_crease, r_circ,
                r_nodes]

    def residual(self, z: np.ndarray, s: float = 1.0) -> np.ndarray:
        """The weighted residual vector ``r (R,)``; ``‖r‖²`` is the total energy at regularisation ``s``."""
        return np.concatenate([c * blk for c, blk in zip(self._sqrt_weights(s), self.blocks(z))])

    def energies(self, z: np.ndarray, s: float = 1.0) -> dict[str, float]:
        """Unweighted energies of :data:`BLOCKS` (``E_shape`` = corners + edges) and the weighted ``total``."""
        blk = self.blocks(z)
        sq = [float(b @ b) for b in blk]
        weighted = sum(c * c * e for c, e in zip(self._sqrt_weights(s), sq))
        out = dict(zip(BLOCKS[:5], sq[:5]))
        out["E_shape"] = sq[5] + sq[6]
        out.update(zip(BLOCKS[7:], sq[7:]))
        out["total"] = float(weighted)
        return out

    def jacobian(self, z: np.ndarray, s: float = 1.0) -> sparse.csc_matrix:
        """``∂r/∂x`` as a CSC matrix ``(R, n_unknowns)`` (analytic, see module docstring).

        The barriers' active rows are read from the residual blocks at ``z`` (kept from the residual the solver
        has just evaluated there, :meth:`blocks`); a crease's derivative is computed only where it is active."""
        v, ns, nf = self.unpack(z)
        blk = self.blocks(z)
        (cf, cpl, c1, cfair, cclose, cshape, _, ccon, corth, caxes, cslide, ccrease, ccirc,
         cnodes) = self._sqrt_weights(s)
        vals = []
        for (ia, ib, own), normals, c in ((self.face_edges, nf, cf), (self.plane_edges, ns, cpl)):
            n = normals[own]
            vals.append(c * np.concatenate([n, -n, v[ib] - v[ia]], axis=1))
        vals.append(2.0 * c1 * np.concatenate([nf, ns]))
        vals.append(np.tile(cfair * np.array([1.0, -2.0, 1.0]), 3 * len(self.triples)))
        cv = self.close_vertices
        vals.append(np.full(3 * len(cv), cclose) if self.closeness == "vertices" else cclose * self.ref_normals[cv])
        cp, ck, cq = self.corner
        e1 = v[ck] - v[cp]
        e2 = v[cq] - v[ck]
        m = self.shape_normals[self.corner_face]
        active = blk[5] > 0                                      # r_corner = max(0, floor − area)
        coef = -(cshape * active / self.face_scale2[self.corner_face])[:, None]
        d_e1 = np.cross(e2, m)                                   # ∂(e1 × e2)·m / ∂e1
        d_e2 = np.cross(m, e1)                                   # ∂(e1 × e2)·m / ∂e2
        vals.append(coef * np.concatenate([-d_e1, d_e1 - d_e2, d_e2], axis=1))
        se = self.shape_edges
        d = v[se[:, 1]] - v[se[:, 0]]
        active = blk[6] > 0                                      # r_edge = max(0, ratio − |d|² / ℓ²)
        g = (2.0 * cshape * active / self.edge_len2)[:, None] * d
        vals.append(np.concatenate([g, -g], axis=1))
        vals.append(ccon * angle_balance(v, self.stars)[1].reshape(-1, 15))
        cos, dcos = corner_cosines(v, self.corners)
        if self.orthogonality == "keep":
            dcos = dcos * (np.sign(cos) * (np.abs(cos) > self.corner_cos0))[:, None, None]
        vals.append(corth * dcos.reshape(-1, 9))
        ao, af = self.axes_pairs
        vals.append(caxes * np.concatenate([nf[af], ns[ao]], axis=1))
        vals.append(np.full(3 * len(self.slide_vertices), cslide))
        crease = np.zeros((len(self.crease_verts), 18))
        on = np.flatnonzero(blk[11] > 0)                         # r_crease = max(0, θ − θ_b)
        if len(on):
            crease[on] = ccrease * dihedral_and_grad(v, self.crease_verts[on], self.crease_slot[on])[1].reshape(-1, 18)
        vals.append(crease)
        vals.append(ccirc * face_angle_balance(v, self.circles)[1].reshape(-1, 12))
        vals.append(cnodes * np.concatenate([ns[self.nodes[:, 1]], ns[self.nodes[:, 0]]], axis=1))
        data = np.concatenate([np.ravel(x) for x in vals])[self._take]
        return sparse.csc_matrix((data, self._indices, self._indptr), shape=(self.n_residuals, self.n_unknowns))

    def sparsity(self) -> sparse.csc_matrix:
        """The 0/1 sparsity pattern of the Jacobian (for generic solvers)."""
        return sparse.csc_matrix((np.ones(self.nnz), self._indices, self._indptr),
                                 shape=(self.n_residuals, self.n_unknowns))

"""Node axes from the support planes they must lie in; the freedom left is used to make the support
torsion-free, near the surface normals, with axes that do not cross within the beam depth.

Every polyline that carries a planar beam (``planar``) has a plane ``n_k·x + d_k = 0`` that contains the node
axes of its vertices (§3.1).  With ``c_v`` such planes through a vertex ``v``:

* ``c_v ≥ 2`` — the axis is fixed: the line through ``v`` lying in all of them.  For two planes it is their
  line of intersection ``U ∩ W`` (§3.1.1), direction ``n_1 × n_2``.  For more (polylines that end at a singular
  vertex, or at a re-entrant corner of a jagged boundary) it is the unit ``a`` minimising ``Σ_k (n_k·a)²``:
  the right singular vector of the stacked normals ``(c_v, 3)`` for the smallest singular value ``σ_min``;
  ``σ_min = 0`` iff the planes share a line (then the axis is exact).  Otherwise each plate ending there is
  cut along the axis brought into its own plane, and the misfit shows as the torsion of its last edge
  (``≈ asin |n_k·a|``), which the build measures against ``beams.max_torsion_mm``.  Two planes that are
  (nearly) the same count as one.
* ``c_v = 1`` — one degree of freedom: ``a(θ) = cos θ p + sin θ q`` with ``p`` the target direction (the
  inward vertex normal) brought into the plane and ``q = n × p``.
* ``c_v = 0`` — two: ``a(x, y) = (t + x b_1 + y b_2) / |…|`` with ``t`` the target and ``b_1, b_2 ⊥ t``.

The free parameters minimise (Levenberg–Marquardt, sparse normal equations)

    E = Σ_{e free} det(ê, a_i, a_j)²  +  w_n² Σ_v |a_v − a_v(0)|²  +  w_c² Σ_e max(0, h_min − h_e)²,

where the first sum runs over the edges of polylines that are not planar beams (their support plane is
spanned by the edge and its two axes, torsion-free iff ``det = 0``, Def. 2.3), the second keeps the axes
near the normals, and the third keeps consecutive axes from crossing within the beam depth ``D``:
``h_e = 1 + (D / |e|) (a_j − a_i)·ê`` is the length of the bottom edge ``(v_j + D a_j) − (v_i + D a_i)``
along ``ê`` over the top edge's; the axes of the edge cross less than ``D`` below it when ``h_e < 0``
(``h_min = 0.25`` keeps the crossing beyond ``D / 0.75``).  ``w_n`` is lowered stage by stage
(``1, 10⁻¹, …, 10⁻⁸``; with ``strips`` then ``10⁻¹⁰, 10⁻¹², 0``) until the largest ``|det|`` is below
``torsion_target`` (in a build a quarter of ``beams.max_torsion_mm`` over the depth, with ``strips`` 10⁻¹³,
:mod:`ppfab.support.planar`): the result is the torsion-free
structure, within that share of the tolerance, that the continuation reaches from the normals.  Whatever torsion remains (a system with no
exact solution) is reported by the structure's torsion and stops a build beyond ``beams.max_torsion_mm``.

For a P mesh (one family planar) every vertex has ``c_v = 1`` and the transverse polylines decouple: each
has one free parameter, the axes propagating along it (§3.1).  Such strips — every connected set of free
edges that is a tree or a single cycle of ``c_v = 1`` vertices, or a tree through one fixed axis — are solved
exactly first when asked (the P method; :mod:`ppfab.support.strips`: propagation, the free angle chosen to keep the axes near the
normals) and held; the energy above is minimised only over the vertices the combinatorics leave (a vertex
with no plane, a strip with two fixed axes or more than one cycle).  For a PP mesh every vertex has
``c_v ≥ 2`` and nothing is solved.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix, diags
from scipy.sparse.linalg import spsolve

from ppfab.mesh import QuadMesh

from .strips import StripAxes, strip_axes
from .structure import edge_polyline_index

H_MIN = 0.25
"""Smallest bottom-to-top edge length ratio the crossing term keeps (axes crossing beyond ``D / (1 − H_MIN)``)."""

SAME_PLANE = 1e-6
"""Second singular value of a vertex's stacked plane normals below which its planes count as one."""


@dataclass(frozen=True)
class AxisSolution:
    """Node axes and how they were found.

    ``axes (N, 3)`` unit, inward; ``planes_at (N,)`` number of distinct support planes of planar beams
    through each vertex (2 = the axis is their line, more = least squares, 1 = one free angle, 0 = free);
    ``misfit (N,)`` ``σ_min`` of the stacked plane normals where more than two planes meet (0 elsewhere);
    ``free_edges (E,)`` bool, edges whose support plane is spanned by their axes; ``torsion_det (E,)``
    ``det(ê, a_i, a_j)`` of every edge; ``iterations`` Levenberg–Marquardt steps, ``stages`` continuation
    stages, ``normal_weight`` the last ``w_n``; ``exact (N,)`` bool, axes found by exact propagation along
    their strip (:mod:`ppfab.support.strips`), ``strips`` how many strips were propagated, ``forced`` how many
    were left to the penalty solve.
    """

    axes: np.ndarray
    planes_at: np.ndarray
    misfit: np.ndarray
    free_edges: np.ndarray
    torsion_det: np.ndarray
    iterations: int
    stages: int
    normal_weight: float
    exact: np.ndarray | None = None
    strips: int = 0
    forced: int = 0


def _vertex_planes(mesh: QuadMesh, planes: np.ndarray, planar: np.ndarray) -> list[np.ndarray]:
    """Unit normals ``(c_v, 3)`` of the distinct planar-beam planes through each vertex."""
    nv = len(mesh.vertices)
    ids, ks = [], []
    for k, p in enumerate(mesh.polylines):
        if planar[k]:
            u = np.unique(p.vertices)
            ids.append(u)
            ks.append(np.full(len(u), k))
    out: list[np.ndarray] = [np.zeros((0, 3)) for _ in range(nv)]
    if not ids:
        return out
    vid = np.concatenate(ids)
    kid = np.concatenate(ks)
    order = np.argsort(vid, kind="stable")
    vid, kid = vid[order], kid[order]
    cuts = np.flatnonzero(np.diff(vid)) + 1
    n = planes[:, :3] / np.linalg.norm(planes[:, :3], axis=1, keepdims=True)
    for v_block, k_block in zip(np.split(vid, cuts), np.split(kid, cuts)):
        out[int(v_block[0])] = n[k_block]
    return out


def _perpendicular(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.eye(3)[np.argmin(np.abs(t), axis=1)]
    b1 = np.cross(t, helper)
    b1 /= np.linalg.norm(b1, axis=1, keepdims=True)
    return b1, np.cross(t, b1)


def fixed_axes(normals_at: list[np.ndarray], target: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Axes of the vertices with two or more distinct planes, the planes' count, the misfit, and the one
    plane of the others (rows of zeros where there is none).

    Returns ``axes (N, 3)`` (``nan`` where not fixed), ``count (N,)``, ``misfit (N,)``, ``plane (N, 3)``.
    """
    nv = len(normals_at)
    axes = np.full((nv, 3), np.nan)
    count = np.zeros(nv, dtype=np.int64)
    misfit = np.zeros(nv)
    plane = np.zeros((nv, 3))
    by_size: dict[int, list[int]] = {}
    for v, n in enumerate(normals_at):
        if len(n) == 1:
            count[v] = 1
            plane[v] = n[0]
        elif len(n) >= 2:
            by_size.setdefault(len(n), []).append(v)
    for size, vs in by_size.items():
        idx = np.asarray(vs)
        stack = np.stack([normals_at[v] for v in vs])                 # (g, c, 3)
        _, s, vt = np.linalg.svd(stack, full_matrices=True)            # s (g, min(c, 3))
        same = s[:, 1] < SAME_PLANE
        a = vt[:, 2]
        a = a * np.where(np.einsum("gi,gi->g", a, target[idx]) < 0, -1.0, 1.0)[:, None]
        fix = idx[~same]
        axes[fix] = a[~same]
        count[fix] = size
        misfit[fix] = s[~same, 2] if size >= 3 else 0.0
        one = idx[same]
        count[one] = 1
        plane[one] = vt[same, 0]
    return axes, count, misfit, plane


class _Problem:
    """The free parameters of the axes and the residuals of the energy in the module docstring."""

    def __init__(self, mesh: QuadMesh, target: np.ndarray, count: np.ndarray, plane: np.ndarray,
                 fixed: np.ndarray, free_edges: np.ndarray, depth: float | None):
        self.v = mesh.vertices
        self.e = mesh.topology.edges
        self.nv = len(self.v)
        self.fixed = fixed
        self.count = count
        one = np.flatnonzero(count == 1)
        zero = np.flatnonzero(count == 0)
        self.one, self.zero = one, zero
        p = target[one] - np.einsum("ij,ij->i", target[one], plane[one])[:, None] * plane[one]
        lp = np.linalg.norm(p, axis=1)
        bad = lp < 1e-9                       # a plane tangent to the surface: any direction in it
        if np.any(bad):
            p[bad] = _perpendicular(plane[one][bad])[0]
            lp[bad] = 1.0
        self.p = p / lp[:, None]
        self.q = np.cross(plane[one], self.p)
        self.t0 = target[zero]
        self.b1: np.ndarray
        self.b2: np.ndarray
        self.b1, self.b2 = _perpendicular(self.t0) if len(zero) else (np.zeros((0, 3)), np.zeros((0, 3)))
        # columns: θ of each count-1 vertex, then (x, y) of each count-0 vertex
        self.col = -np.ones((self.nv, 2), dtype=np.int64)
        self.col[one, 0] = np.arange(len(one))
        self.col[zero, 0] = len(one) + 2 * np.arange(len(zero))
        self.col[zero, 1] = self.col[zero, 0] + 1
        self.n_var = len(one) + 2 * len(zero)
        free_v = count <= 1
        touch = free_v[self.e[:, 0]] | free_v[self.e[:, 1]]
        self.tors_edges = np.flatnonzero(free_edges & touch)
        self.depth = depth
        self.cross_edges = np.flatnonzero(touch) if depth else np.zeros(0, dtype=np.int64)
        vec = self.v[self.e[:, 1]] - self.v[self.e[:, 0]]
        self.length = np.linalg.norm(vec, axis=1)
        self.eh = vec / self.length[:, None]
        self.start = self.axes(np.zeros(self.n_var))

    def axes(self, x: np.ndarray) -> np.ndarray:
        a = self.fixed.copy()
        th = x[: len(self.one)]
        a[self.one] = np.cos(th)[:, None] * self.p + np.sin(th)[:, None] * self.q
        if len(self.zero):
            xy = x[len(self.one):].reshape(-1, 2)
            u = self.t0 + xy[:, :1] * self.b1 + xy[:, 1:] * self.b2
            a[self.zero] = u / np.linalg.norm(u, axis=1, keepdims=True)
        return a

    def derivatives(self, x: np.ndarray, a: np.ndarray) -> np.ndarray:
        """``(N, 2, 3)`` ∂a_v/∂(its parameters) (zero rows for fixed vertices and unused slots)."""
        d = np.zeros((self.nv, 2, 3))
        th = x[: len(self.one)]
        d[self.one, 0] = -np.sin(th)[:, None] * self.p + np.cos(th)[:, None] * self.q
        if len(self.zero):
            xy = x[len(self.one):].reshape(-1, 2)
            u = self.t0 + xy[:, :1] * self.b1 + xy[:, 1:] * self.b2
            lu = np.linalg.norm(u, axis=1, keepdims=True)
            az = a[self.zero]
            for s, b in enumerate((self.b1, self.b2)):
                d[self.zero, s] = (b - az * np.einsum("ij,ij->i", az, b)[:, None]) / lu
        return d

    def residuals(self, x: np.ndarray, wn: float, wc: float, jac: bool = True):
        a = self.axes(x)
        e = self.e
        blocks_r: list[np.ndarray] = []
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        d = self.derivatives(x, a) if jac else None
        r0 = 0

        def add(grad_by_end: list[tuple[np.ndarray, np.ndarray]], row_ids: np.ndarray) -> None:
            """``grad_by_end``: (vertex ids, ∂r/∂a (k, 3)) per end; chain rule into the parameters."""
            assert d is not None
            for vid, g in grad_by_end:
                for s in (0, 1):
                    c = self.col[vid, s]
                    ok = c >= 0
                    if np.any(ok):
                        rows.append(row_ids[ok])
                        cols.append(c[ok])
                        vals.append(np.einsum("ij,ij->i", g[ok], d[vid[ok], s]))

        te = self.tors_edges
        if len(te):
            ai, aj, eh = a[e[te, 0]], a[e[te, 1]], self.eh[te]
            blocks_r.append(np.einsum("ij,ij->i", eh, np.cross(ai, aj)))
            if jac:
                ids = r0 + np.arange(len(te))
                add([(e[te, 0], np.cross(aj, eh)), (e[te, 1], np.cross(eh, ai))], ids)
            r0 += len(te)
        free = np.flatnonzero(self.count <= 1)
        if len(free):
            diff = a[free] - self.start[free]
            blocks_r.append(wn * diff.ravel())
            if jac:
                for c3 in range(3):
                    g = np.zeros((len(free), 3))
                    g[:, c3] = wn
                    add([(free, g)], r0 + 3 * np.arange(len(free)) + c3)
            r0 += 3 * len(free)
        ce = self.cross_edges
        if len(ce) and self.depth:
            k = self.depth / self.length[ce]
            h = 1.0 + k * np.einsum("ij,ij->i", a[e[ce, 1]] - a[e[ce, 0]], self.eh[ce])
            active = h < H_MIN
            blocks_r.append(wc * np.where(active, H_MIN - h, 0.0))
            if jac and np.any(active):
                act = np.flatnonzero(active)
                g = (wc * k[act])[:, None] * self.eh[ce[act]]
                add([(e[ce[act], 1], -g), (e[ce[act], 0], g)], r0 + act)
            r0 += len(ce)
        r = np.concatenate(blocks_r) if blocks_r else np.zeros(0)
        if not jac:
            return r, None
        J = coo_matrix((np.concatenate(vals) if vals else np.zeros(0),
                        (np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64),
                         np.concatenate(cols) if cols else np.zeros(0, dtype=np.int64))),
                       shape=(r0, self.n_var)).tocsr()
        return r, J


def _levenberg_marquardt(prob: _Problem, x: np.ndarray, wn: float, wc: float, max_iter: int = 100
                         ) -> tuple[np.ndarray, int]:
    r, J = prob.residuals(x, wn, wc)
    cost = float(r @ r)
    mu = 1e-6
    it = 0
    for it in range(1, max_iter + 1):
        JtJ = (J.T @ J).tocsc()
        g = J.T @ r
        dg = JtJ.diagonal()
        step = spsolve((JtJ + diags(mu * np.maximum(dg, 1e-12))).tocsc(), -g)
        r2, _ = prob.residuals(x + step, wn, wc, jac=False)
        cost2 = float(r2 @ r2)
        if cost2 < cost:
            x = x + step
            r, J = prob.residuals(x, wn, wc)
            done = cost - cost2 <= 1e-14 * max(cost, 1e-300) or float(np.abs(step).max()) < 1e-13
            cost = cost2
            mu = max(mu / 3.0, 1e-12)
            if done:
                break
        else:
            mu *= 4.0
            if mu > 1e8:
                break
    return x, it


def solve_axes(mesh: QuadMesh, normals: np.ndarray, planes: np.ndarray, planar: np.ndarray, flip: bool = False,
               depth: float | None = None, torsion_target: float = 1e-10, strips: bool = False) -> AxisSolution:
    """Node axes of a support structure whose planar beams are the polylines ``planar`` (module docstring).

    Parameters
    ----------
    mesh : quad mesh
    normals : (N, 3) outward unit vertex normals (the axes point the other way unless ``flip``)
    planes : (L, 4) planes of ``mesh.polylines``; rows of ``planar`` must be finite
    planar : (L,) bool, polylines whose plane is a support plane
    depth : beam depth in mesh units for the crossing term (none without it)
    torsion_target : stop lowering the normal weight once every ``|det(ê, a_i, a_j)|`` is below this
    strips : solve the strips that allow it exactly first (:mod:`ppfab.support.strips`; the P method)
    """
    target = -np.asarray(normals, dtype=float) * (-1.0 if flip else 1.0)
    normals_at = _vertex_planes(mesh, planes, planar)
    fixed, count, misfit, plane = fixed_axes(normals_at, target)
    epl = edge_polyline_index(mesh)
    free_edges = ~np.asarray(planar, dtype=bool)[epl]
    nv = len(mesh.vertices)
    exact = (strip_axes(mesh.vertices, mesh.topology.edges, free_edges, target, count, plane,
                        np.nan_to_num(fixed), depth, H_MIN) if strips else
             StripAxes(np.full((nv, 3), np.nan), np.zeros(nv, dtype=bool), 0, 0, 0, 0))
    held = count.copy()
    held[exact.solved] = 2                        # solved exactly: no parameters left
    fixed[exact.solved] = exact.axes[exact.solved]
    prob = _Problem(mesh, target, held, plane, np.nan_to_num(fixed), free_edges, depth)
    x = np.zeros(prob.n_var)
    iterations = stages = 0
    wn = 1.0
    if prob.n_var:
        weights = list(10.0 ** -np.arange(0, 9)) + ([1e-10, 1e-12, 0.0] if strips else [])
        for stage, wn in enumerate(weights, start=1):
            x, it = _levenberg_marquardt(prob, x, float(wn), 1.0)
            iterations += it
            stages = stage
            a = prob.axes(x)
            te = prob.tors_edges
            det = np.abs(np.einsum("ij,ij->i", prob.eh[te], np.cross(a[prob.e[te, 0]], a[prob.e[te, 1]])))
            if not len(te) or float(det.max()) <= torsion_target:
                break
    a = prob.axes(x)
    e = mesh.topology.edges
    det_all = np.einsum("ij,ij->i", prob.eh, np.cross(a[e[:, 0]], a[e[:, 1]]))
    return AxisSolution(a, count, misfit, free_edges, det_all, iterations, stages, float(wn), exact.solved,
                        exact.strips, exact.forced)

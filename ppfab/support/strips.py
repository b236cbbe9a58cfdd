"""Exact node axes along the transverse strips of a P mesh (§3.1): one free angle per strip.

In a P mesh every axis of a vertex ``v`` lies in the plane ``U`` of the planar-family polyline through ``v``.
Along an edge ``e`` of the other family the two axes must be coplanar with ``e`` (torsion-free, Def. 2.3):
given the axis ``a`` at one end, the axis at the other end lies in the plane ``span(e, a)`` and in that end's
plane ``U'`` (normal ``u'``), so its direction is

    a' = (e × a) × u' = (e·u') a − (a·u') e,

which is *linear* in ``a``.  Starting a strip (a transverse polyline, or any tree of such edges whose
vertices each lie in one plane) with ``a(θ) = cos θ p + sin θ q`` (``p`` the target direction brought into
the start plane, ``q`` the other in-plane direction), every axis of the strip is ``a_v(θ) = cos θ P_v +
sin θ Q_v`` with ``P_v, Q_v`` propagated once.  The free angle ``θ`` (a line direction: ``θ ∈ [0, π)``) is
chosen to minimise

    F(θ) = Σ_v ∠(a_v(θ), t_v)²  +  Σ_e max(0, h_min − h_e)²

(``t_v`` the target, the inward normal; ``h_e`` the crossing measure of :mod:`ppfab.support.axes`, with the
beam depth), by sampling ``θ`` and refining the best sample: a 1-D problem per strip, and every edge of the
strip is torsion-free to rounding.

Other strip shapes:

* a closed strip (a cycle) must return to its start axis: the start direction is a real eigenvector of the
  2 × 2 map once around (its monodromy) — none, one or two (the one with the smaller ``F`` is taken), or
  every direction when the monodromy is a multiple of the identity (then ``θ`` is free as on an open strip);
* a tree through one vertex whose axis is already fixed (two or more planes there) has no free angle: it is
  propagated from that vertex.

Anything else (a vertex with no plane, two fixed vertices on one strip, a strip with more than one cycle, a
closed strip whose monodromy has no real eigenvector, a propagation that degenerates) is left to the penalty
solve of :func:`~ppfab.support.axes.solve_axes`, whose torsion is reported and gated.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

SAMPLES = 180
"""Samples of the free angle over ``[0, π)`` before the best is refined."""

REFINE = 3
"""Rounds of refinement around the best sample (the angle then to ``π / 180 / 16³ ≈ 4e-6`` rad)."""

DEGENERATE = 1e-9
"""A propagated axis shorter than this share of its strip's largest is degenerate (the plane ``span(e, a)``
is the next polyline plane): the strip goes to the penalty solve."""


@dataclass(frozen=True)
class StripAxes:
    """Axes found by exact propagation.

    ``axes (N, 3)`` unit and inward where ``solved``, ``nan`` elsewhere; ``solved (N,)`` bool;
    ``strips`` how many strips were propagated (``free`` of them with a free angle chosen, ``closed`` of
    them closed); ``forced`` how many strips were left to the penalty solve.
    """

    axes: np.ndarray
    solved: np.ndarray
    strips: int
    free: int
    closed: int
    forced: int


def _in_plane_basis(target: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``p`` the target brought into the plane with unit ``normal`` (any in-plane direction if the target is
    normal to it), ``q = normal × p``."""
    p = target - (target @ normal) * normal
    if np.linalg.norm(p) < 1e-9:
        helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
        p = np.cross(normal, helper)
    p = p / np.linalg.norm(p)
    return p, np.cross(normal, p)


def _step(a: np.ndarray, e: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``(…, 3)`` the axis direction at the far end of edge ``e`` (plane normal ``u``) from ``a`` at the near
    end: ``(e × a) × u`` (module docstring), linear in ``a``."""
    return a * (e @ u) - np.multiply.outer(a @ u, e)


def _bfs(root: int, adj: dict[int, list[int]]) -> list[tuple[int, int]]:
    """``(parent, child)`` pairs of a breadth-first traversal from ``root`` (the root's parent is -1)."""
    out = [(-1, root)]
    seen = {root}
    queue = deque([root])
    while queue:
        v = queue.popleft()
        for w in adj[v]:
            if w not in seen:
                seen.add(w)
                out.append((v, w))
                queue.append(w)
    return out


class _Strip:
    """One strip: its vertices in propagation order and the edges among them."""

    def __init__(self, verts: np.ndarray, vertices: np.ndarray, target: np.ndarray, edges: np.ndarray,
                 depth: float | None, h_min: float):
        self.verts = verts
        self.target = target[verts]
        self.pos = {int(v): k for k, v in enumerate(verts)}
        ii = np.array([self.pos[int(i)] for i in edges[:, 0]], dtype=np.int64)
        jj = np.array([self.pos[int(j)] for j in edges[:, 1]], dtype=np.int64)
        self.ii, self.jj = ii, jj
        vec = vertices[edges[:, 1]] - vertices[edges[:, 0]]
        self.length = np.linalg.norm(vec, axis=1)
        self.eh = vec / self.length[:, None]
        self.depth = depth
        self.h_min = h_min

    def oriented(self, a: np.ndarray) -> np.ndarray:
        """``(…, k, 3)`` unit axes turned towards the targets; zero rows stay zero."""
        n = np.linalg.norm(a, axis=-1, keepdims=True)
        u = a / np.maximum(n, 1e-300)
        s = np.where(np.einsum("...ij,ij->...i", u, self.target) < 0, -1.0, 1.0)
        return u * s[..., None]

    def cost(self, a: np.ndarray) -> np.ndarray:
        """``F`` of the module docstring for axes ``(…, k, 3)`` (unnormalised); degenerate axes count as
        perpendicular to their targets."""
        n = np.linalg.norm(a, axis=-1)
        big = n.max(axis=-1, keepdims=True)
        u = self.oriented(a)
        c = np.clip(np.einsum("...ij,ij->...i", u, self.target), -1.0, 1.0)
        ang = np.where(n > DEGENERATE * big, np.arccos(c), np.pi / 2)
        f = np.sum(ang ** 2, axis=-1)
        if self.depth and len(self.ii):
            h = 1.0 + (self.depth / self.length) * np.einsum("...ij,ij->...i", u[..., self.jj, :] - u[..., self.ii, :],
                                                             self.eh)
            f = f + np.sum(np.maximum(0.0, self.h_min - h) ** 2, axis=-1)
        return f

    def best_angle(self, P: np.ndarray, Q: np.ndarray) -> float:
        """The free angle minimising ``F``: :data:`SAMPLES` samples over ``[0, π)``, then :data:`REFINE`
        rounds of 32 samples over the two intervals around the best so far (each 16 times finer)."""
        th = np.linspace(0.0, np.pi, SAMPLES, endpoint=False)
        step = np.pi / SAMPLES
        best_t, best_f = 0.0, np.inf
        for _ in range(REFINE + 1):
            a = np.cos(th)[:, None, None] * P + np.sin(th)[:, None, None] * Q
            f = self.cost(a)
            k = int(np.argmin(f))
            if f[k] < best_f:
                best_t, best_f = float(th[k]), float(f[k])
            th = best_t + step * np.linspace(-1.0, 1.0, 33)
            step /= 16.0
        return best_t


def _propagate(order: list[tuple[int, int]], vertices: np.ndarray, plane: np.ndarray, start: np.ndarray,
               n_out: int, pos: dict[int, int]) -> np.ndarray:
    """``(…, k, 3)`` axes propagated along ``order`` from ``start (…, 3)`` at the root (rescaled per step so
    long strips neither overflow nor vanish; a common factor per vertex does not change the directions)."""
    out = np.zeros(start.shape[:-1] + (n_out, 3))
    root = order[0][1]
    out[..., pos[root], :] = start
    for par, child in order[1:]:
        e = vertices[child] - vertices[par]
        a = _step(out[..., pos[par], :], e / np.linalg.norm(e), plane[child])
        scale = np.max(np.linalg.norm(a, axis=-1))
        out[..., pos[child], :] = a / scale if scale > 0 else a
    return out


def strip_axes(vertices: np.ndarray, edges: np.ndarray, free_edges: np.ndarray, target: np.ndarray,
               count: np.ndarray, plane: np.ndarray, fixed: np.ndarray, depth: float | None = None,
               h_min: float = 0.25) -> StripAxes:
    """Exact axes of every strip that allows them (module docstring).

    Parameters
    ----------
    vertices : (N, 3) float
    edges : (E, 2) int, ``mesh.topology.edges``
    free_edges : (E,) bool, edges whose support plane is spanned by their axes (not on a planar beam)
    target : (N, 3) unit target directions (inward normals)
    count : (N,) number of distinct planar-beam planes through each vertex
    plane : (N, 3) the unit normal of the one plane where ``count == 1``
    fixed : (N, 3) the fixed axes where ``count ≥ 2``
    depth : beam depth (mesh units) for the crossing term, none without it
    """
    nv = len(vertices)
    axes = np.full((nv, 3), np.nan)
    solved = np.zeros(nv, dtype=bool)
    fe = edges[np.asarray(free_edges, dtype=bool)]
    stats = {"strips": 0, "free": 0, "closed": 0, "forced": 0}
    if not len(fe):
        return StripAxes(axes, solved, 0, 0, 0, 0)
    g = coo_matrix((np.ones(len(fe)), (fe[:, 0], fe[:, 1])), shape=(nv, nv))
    ncomp, label = connected_components(g, directed=False)
    edge_label = label[fe[:, 0]]
    order_e = np.argsort(edge_label, kind="stable")
    cuts = np.searchsorted(edge_label[order_e], np.arange(ncomp + 1))
    vorder = np.argsort(label, kind="stable")
    vcuts = np.searchsorted(label[vorder], np.arange(ncomp + 1))
    for c in range(ncomp):
        ce = fe[order_e[cuts[c]:cuts[c + 1]]]
        if not len(ce):
            continue
        verts = vorder[vcuts[c]:vcuts[c + 1]]
        cnt = count[verts]
        n_fixed = int((cnt >= 2).sum())
        if (cnt == 0).any() or n_fixed > 1 or len(ce) > len(verts) or (n_fixed and len(ce) != len(verts) - 1):
            stats["forced"] += 1
            continue
        adj: dict[int, list[int]] = {int(v): [] for v in verts}
        for i, j in ce:
            adj[int(i)].append(int(j))
            adj[int(j)].append(int(i))
        strip = _Strip(verts, vertices, target, ce, depth, h_min)
        closed = len(ce) == len(verts)
        if n_fixed:
            root = int(verts[np.flatnonzero(cnt >= 2)[0]])
        else:
            ends = [v for v in adj if len(adj[v]) == 1]
            root = min(ends) if ends else int(verts.min())
        order = _bfs(root, adj)
        free_angle = False
        if n_fixed:
            a = _propagate(order, vertices, plane, fixed[root], len(verts), strip.pos)
        else:
            p, q = _in_plane_basis(target[root], plane[root])
            both = _propagate(order, vertices, plane, np.stack([p, q]), len(verts), strip.pos)
            P, Q = both[0], both[1]
            if closed:
                cand = _closing_angles(order, adj, vertices, plane, root, p, q, both, strip.pos)
                if cand is None:                      # every start closes the loop: free as an open strip
                    t = strip.best_angle(P, Q)
                elif not cand:
                    stats["forced"] += 1
                    continue
                else:
                    costs = [float(strip.cost(np.cos(t) * P + np.sin(t) * Q)) for t in cand]
                    t = cand[int(np.argmin(costs))]
                free_angle = cand is None
            else:
                t = strip.best_angle(P, Q)
                free_angle = True
            a = np.cos(t) * P + np.sin(t) * Q
        n = np.linalg.norm(a, axis=1)
        if not np.all(n > DEGENERATE * n.max()):
            stats["forced"] += 1
            continue
        axes[verts] = strip.oriented(a)
        solved[verts] = True
        stats["strips"] += 1
        stats["free"] += int(free_angle)
        stats["closed"] += int(closed)
    return StripAxes(axes, solved, stats["strips"], stats["free"], stats["closed"], stats["forced"])


def _closing_angles(order: list[tuple[int, int]], adj: dict[int, list[int]], vertices: np.ndarray,
                    plane: np.ndarray, root: int, p: np.ndarray, q: np.ndarray, both: np.ndarray,
                    pos: dict[int, int]) -> list[float] | None:
    """Start angles of a closed strip whose axes return to the start axis once around: the real eigen-
    directions of the 2 × 2 monodromy in the basis ``(p, q)`` (the breadth-first tree of a cycle leaves one
    edge out; stepping across it back into the root's plane closes the loop); ``None`` when the monodromy
    is a multiple of the identity (every start closes), ``[]`` when no start does."""
    in_tree = {frozenset((a, b)) for a, b in order[1:]}
    closing = next(((a, b) for a in adj for b in adj[a] if frozenset((a, b)) not in in_tree), None)
    if closing is None:
        return []
    a_end, b_end = closing
    # go around: root → … → a_end (one branch), across to b_end, → … → root (the other branch, reversed);
    # both ends lie on the tree, so carry P/Q at a_end across the closing edge into b_end's plane, then back
    # along b_end's branch to the root
    parent = {child: par for par, child in order}
    path_b = [b_end]
    while path_b[-1] != root:
        path_b.append(parent[path_b[-1]])
    cur = both[:, pos[a_end], :]                 # (2, 3): images of p and q at a_end
    prev = a_end
    for v in path_b:
        e = vertices[v] - vertices[prev]
        cur = _step(cur, e / np.linalg.norm(e), plane[v])
        cur = cur / max(float(np.max(np.linalg.norm(cur, axis=-1))), 1e-300)
        prev = v
    # cur now holds the images of p and q back at the root; but the branch root → b_end was also walked from
    # the root by the tree, so the loop is root → a_end → b_end → root
    M = np.array([[cur[0] @ p, cur[1] @ p], [cur[0] @ q, cur[1] @ q]])
    w, vec = np.linalg.eig(M)
    if np.max(np.abs(M)) == 0:
        return []
    if np.allclose(M, M[0, 0] * np.eye(2), atol=1e-12 * np.max(np.abs(M))):
        return None
    out = []
    for k in range(2):
        if abs(w[k].imag) <= 1e-12 * np.max(np.abs(w)) and abs(w[k].real) > 0:
            x = np.real(vec[:, k])
            out.append(float(np.arctan2(x[1], x[0])))
    return out

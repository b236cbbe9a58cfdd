"""The weighted face image ``M_F`` and normal image ``M_N`` (§2.2, Prop. 2.4/2.5) and PP meshes from it (§3.1).

Face image of a mesh with a torsion-free support structure (Prop. 2.4):
weighted face planes ``f`` such that for every edge the support plane is the
difference of the weighted planes of the two faces sharing it, eq. (5)
(read ``s = f_r − f_l`` as in ``reference/README.md``).

PP meshes (Prop. 3.1, eq. 6/7): the face image is a translation net,
``f_ij = g_i + h_j − c``.  Then

* the row support planes are ``U_i = f_{i,j} − f_{i−1,j} = g_i − g_{i−1}``,
* the column support planes are ``W_j = h_j − h_{j−1}``,
* vertex ``v_ij`` is the intersection of an adjacent face plane with ``U_i`` and ``W_j``.

To make boundary vertices well defined the face image is *extended* by one
ghost face beyond each side: ``g (m+2, 4)``, ``h (n+2, 4)`` give the
extended image ``F (m+2, n+2, 4)``; the mesh has vertices ``(m+1, n+1)``,
its face ``f[i, j]`` is ``F[i+1, j+1]`` and vertex ``v[i, j]`` is surrounded by
``F[i:i+2, j:j+2]``.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import breadth_first_order
from scipy.sparse.linalg import spsolve

from ppfab import planes as pl
from .errors import GeometryError
from .mesh import QuadGrid, QuadMesh


def extended_face_image(g: np.ndarray, h: np.ndarray, c: np.ndarray | None = None) -> np.ndarray:
    """``F[a, b] = g[a] + h[b] − c`` (eq. 7), shape ``(len(g), len(h), 4)``."""
    g = pl.as_planes(g)
    h = pl.as_planes(h)
    c = np.zeros(4) if c is None else pl.as_planes(c)
    return g[:, None, :] + h[None, :, :] - c


def pp_from_face_image(g: np.ndarray, h: np.ndarray, c: np.ndarray | None = None,
                       min_sine: float = 1e-9) -> QuadGrid:
    """PP mesh from discrete generators of the face image (Prop. 3.1, eq. 7).

    Parameters
    ----------
    g : (m+2, 4) float — ``g_0 … g_{m+1}`` (first and last give the ghost faces)
    h : (n+2, 4) float — ``h_0 … h_{n+1}``
    c : (4,) float, optional — the constant of eq. (7) (default 0)
    min_sine : vertices where the face plane and the two support planes are
        closer than this to sharing a line raise :class:`GeometryError`.

    Returns
    -------
    QuadGrid with ``(m+1, n+1)`` vertices, ``support_u = U (m+1, 4)``,
    ``support_w = W (n+1, 4)``, ``face_image = F[1:-1, 1:-1] (m, n, 4)`` and unit
    node axes along ``U_i ∩ W_j``.

    Examples
    --------
    >>> g = np.array([[0, 0, 1, 0], [.1, 0, 1, 0], [.2, 0, 1, 0]], float)
    >>> h = np.array([[0, 0, 0, -1], [0, .1, 0, -1], [0, .2, 0, -1]], float)
    >>> pp_from_face_image(g, h).shape
    (2, 2)
    """
    g = pl.as_planes(g)
    h = pl.as_planes(h)
    if g.ndim != 2 or h.ndim != 2 or len(g) < 3 or len(h) < 3:
        raise GeometryError("g and h need at least 3 samples each (one face plus a ghost face on each side)")
    F = extended_face_image(g, h, c)
    U = g[1:] - g[:-1]
    W = h[1:] - h[:-1]
    for name, planes in (("U", U), ("W", W)):
        nrm = np.linalg.norm(planes[:, :3], axis=1)
        if np.any(nrm <= 1e-14 * max(1.0, float(np.abs(planes).max()))):
            k = int(np.argmin(nrm))
            raise GeometryError(f"support plane {name}_{k} is degenerate: consecutive samples of "
                                f"{'g' if name == 'U' else 'h'} differ only in the 4th coordinate",
                                element=f"{name}_{k}")
    fn = np.linalg.norm(F[..., :3], axis=-1)
    if np.any(fn <= 1e-14):
        a, b = (int(k) for k in np.argwhere(fn <= 1e-14)[0])
        raise GeometryError(f"face plane F[{a}, {b}] has a zero normal", element=f"face {a},{b}")
    m1, n1 = len(U), len(W)
    face = F[1:, 1:]          # an adjacent face of each vertex: F[i+1, j+1]
    Ui = np.broadcast_to(U[:, None, :], (m1, n1, 4))
    Wj = np.broadcast_to(W[None, :, :], (m1, n1, 4))
    v = intersect_checked(face, Ui, Wj, min_sine)
    axes = orient_axes(np.cross(pl.normalize(Ui)[..., :3], pl.normalize(Wj)[..., :3]), F)
    return QuadGrid(v, support_u=U, support_w=W, face_image=F[1:-1, 1:-1], axes=axes,
                    extended_face_image=F)


def intersect_checked(face: np.ndarray, u: np.ndarray, w: np.ndarray, min_sine: float) -> np.ndarray:
    """Vectorised ``face ∩ U ∩ W`` that names the first vertex where the planes nearly share a line."""
    nf, nu, nw = (pl.normalize(p)[..., :3] for p in (face, u, w))
    det = np.abs(np.einsum("...i,...i->...", nf, np.cross(nu, nw)))
    if np.any(det < min_sine):
        i, j = (int(k) for k in np.argwhere(det < min_sine)[0])
        raise GeometryError(f"vertex ({i}, {j}) is undefined: its face plane and support planes U_{i}, W_{j} "
                            f"nearly share a line (|det| = {det[i, j]:.2e})", element=f"vertex {i},{j}",
                            value=float(det[i, j]))
    return pl.intersect_three(face, u, w)


def orient_axes(axes: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Unit node axes ``(m+1, n+1, 3)`` turned to the inner side: against the mean normal of the
    four surrounding face planes ``F[i:i+2, j:j+2]`` of the extended face image (panels on the
    outside, beams below them)."""
    a = axes / np.linalg.norm(axes, axis=-1, keepdims=True)
    n = pl.normalize(F)[..., :3]
    mean = n[:-1, :-1] + n[1:, :-1] + n[:-1, 1:] + n[1:, 1:]
    sign = np.where(np.einsum("...i,...i->...", a, mean) > 0, -1.0, 1.0)
    return a * sign[..., None]


def sample_extended(fn: Callable[[np.ndarray], np.ndarray], t: np.ndarray) -> np.ndarray:
    """Sample a curve ``fn(t) -> (k, 4)`` at face parameters ``t (k,)`` plus one ghost step beyond each end."""
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or len(t) < 2:
        raise GeometryError("a curve needs at least 2 face parameters")
    ext = np.concatenate([[2 * t[0] - t[1]], t, [2 * t[-1] - t[-2]]])
    out = np.asarray(fn(ext), dtype=float)
    if out.shape != (len(ext), 4):
        raise GeometryError(f"curve function must return shape ({len(ext)}, 4), got {out.shape}")
    if not np.all(np.isfinite(out)):
        raise GeometryError("curve function returned NaN or inf")
    return out


def pp_from_curves(g: Callable[[np.ndarray], np.ndarray], h: Callable[[np.ndarray], np.ndarray],
                   u: np.ndarray, v: np.ndarray, c: np.ndarray | None = None) -> QuadGrid:
    """PP mesh whose face planes are samples ``f(u_i, v_j) = g(u_i) + h(v_j) − c`` (eq. 8).

    ``u (m,)`` and ``v (n,)`` are the parameters of the mesh's faces; one ghost
    face beyond each side is sampled so the mesh has ``(m+1, n+1)`` vertices.
    """
    return pp_from_face_image(sample_extended(g, u), sample_extended(h, v), c)


# -- face image of an existing mesh --------------------------------------------------------

def _edge_ratio(f_l: np.ndarray, f_r: np.ndarray, s: np.ndarray) -> np.ndarray:
    """``λ`` with ``λ f_r − f_l = μ s`` (least squares over the 4 coordinates), stacked."""
    a = np.stack([f_r, -s], axis=-1)                    # (..., 4, 2)
    ata = np.einsum("...ki,...kj->...ij", a, a)
    atb = np.einsum("...ki,...k->...i", a, f_l)
    sol = np.linalg.solve(ata, atb[..., None])[..., 0]
    return sol[..., 0]


def pp_face_image(grid: QuadGrid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weighted face image of a PP grid with its support planes ``U_i``, ``W_j`` (Prop. 2.4).

    The support planes are the grid's own (``support_u/support_w``) or least-
    squares fits of the rows and columns.  Weights are propagated so that
    ``F[i, j] − F[i−1, j] ∝ U_i`` and ``F[i, j] − F[i, j−1] ∝ W_j`` (eq. 5),
    starting from the unit plane of face ``(0, 0)``.

    Returns
    -------
    F : (m, n, 4) weighted face planes
    U : (m+1, 4), W : (n+1, 4) unit support planes
    """
    if grid.closed:
        raise GeometryError("the PP face image needs an open patch (rows of a closed grid are not translates)")
    U = grid.support_u if grid.support_u is not None else pl.fit_plane(grid.rows())[0]
    W = grid.support_w if grid.support_w is not None else pl.fit_plane(grid.cols())[0]
    U, W = pl.normalize(U), pl.normalize(W)
    f = grid.face_planes                                     # (m, n, 4) unit
    m, n = f.shape[:2]
    # across a row polyline i (faces (i-1, j) and (i, j)): support U_i
    lam_i = _edge_ratio(f[:-1], f[1:], np.broadcast_to(U[1:m, None, :], (m - 1, n, 4)))
    lam_j = _edge_ratio(f[:, :-1], f[:, 1:], np.broadcast_to(W[None, 1:n, :], (m, n - 1, 4)))
    w = np.ones((m, n))
    w[1:, 0] = np.cumprod(lam_i[:, 0]) if m > 1 else w[1:, 0]
    if n > 1:
        w[:, 1:] = w[:, :1] * np.cumprod(lam_j, axis=1)
    return f * w[..., None], U, W


def grid_from_face_image(F: np.ndarray, U: np.ndarray, W: np.ndarray, min_sine: float = 1e-9) -> QuadGrid:
    """Vertices of a grid from its face planes and support planes (Prop. 2.5).

    ``F (m, n, 4)``, ``U (m+1, 4)``, ``W (n+1, 4)``; vertex ``v[i, j] = f ∩ U_i ∩ W_j``
    with ``f`` an adjacent face.
    """
    F = pl.as_planes(F)
    m, n = F.shape[:2]
    if U.shape != (m + 1, 4) or W.shape != (n + 1, 4):
        raise GeometryError(f"support planes need shapes ({m + 1}, 4) and ({n + 1}, 4)")
    ii = np.minimum(np.arange(m + 1), m - 1)
    jj = np.minimum(np.arange(n + 1), n - 1)
    face = F[ii][:, jj]
    v = intersect_checked(face, np.broadcast_to(U[:, None], (m + 1, n + 1, 4)),
                          np.broadcast_to(W[None, :], (m + 1, n + 1, 4)), min_sine)
    return QuadGrid(v, support_u=U, support_w=W, face_image=F)


def face_image(mesh: QuadMesh, axes: np.ndarray) -> np.ndarray:
    """Weighted face image of any quad mesh with node axes ``(N, 3)`` (Prop. 2.4).

    For each interior edge the ratio ``λ = w_r / w_l`` makes ``w_r f_r − w_l f_l``
    contain the node axes of both end points; the weights are propagated over
    a spanning tree of the dual graph by one sparse solve of
    ``log w_r − log w_l = log λ`` (complex logarithms carry the signs).

    Returns
    -------
    (F, 4) weighted face planes (face 0 keeps unit weight per connected piece).
    """
    f = mesh.face_planes
    topo = mesh.topology
    ef = topo.edge_faces
    inner = np.flatnonzero(ef[:, 1] >= 0)
    e = topo.edges[inner]
    a = np.asarray(axes, dtype=float)
    nl, nr = f[ef[inner, 0], :3], f[ef[inner, 1], :3]
    num = np.einsum("ei,ei->e", nl, a[e[:, 0]]) * np.einsum("ei,ei->e", nr, a[e[:, 0]]) + \
        np.einsum("ei,ei->e", nl, a[e[:, 1]]) * np.einsum("ei,ei->e", nr, a[e[:, 1]])
    den = np.einsum("ei,ei->e", nr, a[e[:, 0]]) ** 2 + np.einsum("ei,ei->e", nr, a[e[:, 1]]) ** 2
    if np.any(den <= 1e-28) or np.any(np.abs(num) <= 1e-28):
        raise GeometryError("a node axis lies in a face plane: the support structure is degenerate (Def. 2.3)")
    lam = num / den
    nf = len(f)
    adj = csr_matrix((np.ones(len(inner)), (ef[inner, 0], ef[inner, 1])), shape=(nf, nf))
    adj = adj + adj.T
    logw = np.zeros(nf, dtype=complex)
    seen = np.zeros(nf, dtype=bool)
    lookup = {}
    for k, (l_, r_) in enumerate(ef[inner].tolist()):
        lookup[(l_, r_)] = np.log(complex(lam[k]))
        lookup[(r_, l_)] = -np.log(complex(lam[k]))
    for root in range(nf):
        if seen[root]:
            continue
        order, pred = breadth_first_order(adj, root, directed=False, return_predecessors=True)
        rows = [0]
        cols = [order[0]]
        vals = [1.0]
        rhs = [0.0]
        for r, face in enumerate(order[1:], start=1):
            p = pred[face]
            rows += [r, r]
            cols += [face, p]
            vals += [1.0, -1.0]
            rhs.append(lookup[(p, face)])
        local = {int(fc): k for k, fc in enumerate(order)}
        mat = coo_matrix((vals, (rows, [local[int(c)] for c in cols])), shape=(len(order), len(order))).tocsc()
        sol = spsolve(mat, np.asarray(rhs, dtype=complex)) if len(order) > 1 else np.zeros(1, complex)
        logw[order] = np.atleast_1d(sol)
        seen[order] = True
    w = np.real(np.exp(logw))
    return f * w[:, None]


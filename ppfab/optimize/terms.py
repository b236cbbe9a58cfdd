"""Geometric energies beyond §3.3: conical vertices, corner angles, support planes normal to the panels.

Each function returns residuals and their analytic derivatives with respect to
the vertices it touches, vectorised over all rows:

* **Conical (angle balance, §2.3.3 / §4).**  At an interior vertex ``v`` of
  valence 4 with neighbours ``w_0..w_3`` in cyclic order, the face angles are
  ``α_k = ∠(w_k − v, w_{k+1} − v)``; the mesh is conical at ``v`` iff
  ``α_0 − α_1 + α_2 − α_3 = 0`` [Liu et al. 2006].  Rows ``α_0 − α_1 + α_2 − α_3``
  (radians); columns the 5 vertices ``v, w_0..w_3``.
* **Circular (opposite angles, §2.3.3, Remark 2.1).**  For a face ``c_0..c_3`` with corner angles ``α_k``,
  rows ``α_0 − α_1 + α_2 − α_3`` (radians); with planar faces it vanishes iff the quad is inscribed in a
  circle.  Columns the 4 corners.
* **Corner angles (near-rectangular panels, §4).**  For the corner ``k`` of a
  face with ``a = c_{k−1} − c_k``, ``b = c_{k+1} − c_k``: ``c = cos α = â·b̂``.  Rows
  ``c`` (``"right"``: right angles) or ``max(0, |c| − |c⁰|)`` (``"keep"``: no corner
  further from 90° than in the input).  Columns the 3 corner vertices.

Derivatives, with ``θ = ∠(a, b)``, ``p_a = b − (a·b / ‖a‖²) a`` (the part of ``b``
normal to ``a``) and ``p_b`` likewise::

    ∂θ/∂a = −p_a / (‖p_a‖ ‖a‖),      ∂θ/∂b = −p_b / (‖p_b‖ ‖b‖),
    ∂(â·b̂)/∂a = (b̂ − (â·b̂) â) / ‖a‖,   ∂(â·b̂)/∂b = (â − (â·b̂) b̂) / ‖b‖,

and the derivative with respect to the apex is minus their sum.

The orthogonal-node term (§2.3.4: where a planar row and a planar column cross, their support planes meet at
a right angle) is ``⟨n_U, n_W⟩`` per node, bilinear in the support normals; :func:`node_pairs` lists the
nodes.  The support-plane term (right angles between support planes and panels,
§2.3.2) is bilinear in the normals and lives with ``E_P`` in
:mod:`.residuals`; :func:`polyline_faces` lists its (polyline, face) pairs.
"""

from __future__ import annotations

import numpy as np

from ..topology import Polyline


def conical_stars(faces: np.ndarray, n_vertices: int, interior: np.ndarray) -> np.ndarray:
    """Stars ``(K, 5)`` ``[v, w_0, w_1, w_2, w_3]`` of the interior vertices with exactly 4 faces.

    Parameters
    ----------
    faces : (F, 4) int, consistently oriented
    n_vertices : N
    interior : (N,) bool, vertices not on the boundary

    The neighbours ``w_k`` are in cyclic order: the corner of a face at ``v`` runs from ``w_k`` (its previous
    corner) to ``w_{k+1}`` (its next corner).  Vertices whose four corners do not close up into one cycle
    (non-manifold or inconsistently oriented neighbourhoods) are left out.
    """
    f = np.asarray(faces, dtype=np.int64)
    if len(f) == 0:
        return np.zeros((0, 5), dtype=np.int64)
    vert = f.ravel()
    prev = np.roll(f, 1, axis=1).ravel()
    nxt = np.roll(f, -1, axis=1).ravel()
    count = np.bincount(vert, minlength=n_vertices)
    cand = np.flatnonzero((count == 4) & np.asarray(interior, dtype=bool))
    if not len(cand):
        return np.zeros((0, 5), dtype=np.int64)
    order = np.argsort(vert, kind="stable")
    start = np.searchsorted(vert[order], cand)
    corners = order[start[:, None] + np.arange(4)]                      # (K, 4) corner ids of each vertex
    p, q = prev[corners], nxt[corners]                                   # (K, 4)
    ring = np.zeros((len(cand), 4), dtype=np.int64)
    ring[:, 0], ring[:, 1] = p[:, 0], q[:, 0]
    ok = np.ones(len(cand), dtype=bool)
    cur = q[:, 0]
    for k in (2, 3):
        hit = p == cur[:, None]
        ok &= hit.sum(axis=1) == 1
        cur = q[np.arange(len(cand)), np.argmax(hit, axis=1)]
        ring[:, k] = cur
    hit = p == cur[:, None]                                              # the cycle closes at w_0
    ok &= (hit.sum(axis=1) == 1) & (q[np.arange(len(cand)), np.argmax(hit, axis=1)] == ring[:, 0])
    ok &= np.array([len(set(r)) == 4 for r in ring.tolist()], dtype=bool) if len(ring) else ok
    return np.concatenate([cand[:, None], ring], axis=1)[ok]


def _angle_and_grad(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``θ = ∠(a, b) (M,)`` and ``∂θ/∂a, ∂θ/∂b (M, 3)`` for vectors ``(M, 3)``."""
    aa = np.einsum("ij,ij->i", a, a)
    bb = np.einsum("ij,ij->i", b, b)
    ab = np.einsum("ij,ij->i", a, b)
    theta = np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), ab)
    pa = b - (ab / aa)[:, None] * a
    pb = a - (ab / bb)[:, None] * b
    npa = np.maximum(np.linalg.norm(pa, axis=1), 1e-300)
    npb = np.maximum(np.linalg.norm(pb, axis=1), 1e-300)
    da = -pa / (npa * np.sqrt(aa))[:, None]
    db = -pb / (npb * np.sqrt(bb))[:, None]
    return theta, da, db


SIGNS = np.array([1.0, -1.0, 1.0, -1.0])


def angle_balance(v: np.ndarray, stars: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Conical residual ``α_0 − α_1 + α_2 − α_3`` per star ``(K,)`` and its derivative ``(K, 5, 3)``
    with respect to ``v, w_0..w_3`` (see module docstring)."""
    k = len(stars)
    if k == 0:
        return np.zeros(0), np.zeros((0, 5, 3))
    c = v[stars[:, 0]]
    w = v[stars[:, 1:]]                                                  # (K, 4, 3)
    a = (w - c[:, None]).reshape(-1, 3)
    b = (np.roll(w, -1, axis=1) - c[:, None]).reshape(-1, 3)
    theta, da, db = _angle_and_grad(a, b)
    r = (theta.reshape(k, 4) * SIGNS).sum(axis=1)
    da = da.reshape(k, 4, 3) * SIGNS[None, :, None]
    db = db.reshape(k, 4, 3) * SIGNS[None, :, None]
    jac = np.zeros((k, 5, 3))
    jac[:, 1:] += da                                                     # w_k is ``a`` of angle k
    jac[:, 1:] += np.roll(db, 1, axis=1)                                 # w_{k+1} is ``b`` of angle k
    jac[:, 0] = -(da.sum(axis=1) + db.sum(axis=1))
    return r, jac


def face_angle_balance(v: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Circular residual ``α_0 − α_1 + α_2 − α_3`` per quad ``(F,)`` (``α_k`` the corner angle at ``c_k``, between
    ``c_{k−1} − c_k`` and ``c_{k+1} − c_k``) and its derivative ``(F, 4, 3)`` with respect to ``c_0..c_3``.

    A planar convex quad is inscribed in a circle iff its opposite angles add up to π, i.e. iff this residual
    vanishes (its angles add up to 2π): with ``E_f`` it makes the mesh circular (§2.3.3, Remark 2.1)."""
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 4)
    k = len(f)
    if k == 0:
        return np.zeros(0), np.zeros((0, 4, 3))
    c = v[f]                                                             # (F, 4, 3)
    a = (np.roll(c, 1, axis=1) - c).reshape(-1, 3)                       # c_{k−1} − c_k
    b = (np.roll(c, -1, axis=1) - c).reshape(-1, 3)                      # c_{k+1} − c_k
    theta, da, db = _angle_and_grad(a, b)
    r = (theta.reshape(k, 4) * SIGNS).sum(axis=1)
    da = da.reshape(k, 4, 3) * SIGNS[None, :, None]
    db = db.reshape(k, 4, 3) * SIGNS[None, :, None]
    jac = -(da + db)                                                     # the apex c_k of angle k
    jac += np.roll(da, -1, axis=1)                                       # c_k is ``a`` of angle k + 1
    jac += np.roll(db, 1, axis=1)                                        # c_k is ``b`` of angle k − 1
    return r, jac


def face_corners_index(faces: np.ndarray) -> np.ndarray:
    """Corners ``(4F, 3)`` ``[previous, apex, next]`` of every face corner, in face order."""
    f = np.asarray(faces, dtype=np.int64)
    return np.stack([np.roll(f, 1, axis=1).ravel(), f.ravel(), np.roll(f, -1, axis=1).ravel()], axis=1)


def corner_cosines(v: np.ndarray, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``cos α`` per corner ``(C,)`` and its derivative ``(C, 3, 3)`` w.r.t. ``[previous, apex, next]``."""
    if len(corners) == 0:
        return np.zeros(0), np.zeros((0, 3, 3))
    a = v[corners[:, 0]] - v[corners[:, 1]]
    b = v[corners[:, 2]] - v[corners[:, 1]]
    la = np.linalg.norm(a, axis=1)
    lb = np.linalg.norm(b, axis=1)
    ah, bh = a / la[:, None], b / lb[:, None]
    cos = np.einsum("ij,ij->i", ah, bh)
    da = (bh - cos[:, None] * ah) / la[:, None]
    db = (ah - cos[:, None] * bh) / lb[:, None]
    return cos, np.stack([da, -(da + db), db], axis=1)


def polyline_faces(lines: list[Polyline], edges: np.ndarray, edge_faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(polyline, face) pairs for the support-plane term: every face with an edge on the polyline.

    ``edges (E, 2)`` the mesh's unique edges ``a < b``, ``edge_faces (E, 2)`` their faces (``-1`` none).
    Returns ``owner (P,)`` (position in ``lines``) and ``face (P,)``, each pair once, by polyline and face.
    """
    if not lines:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    a_parts, b_parts, own_parts = [], [], []
    for s, p in enumerate(lines):
        v = np.asarray(p.vertices, dtype=np.int64)
        a = v if p.closed else v[:-1]
        b = np.roll(v, -1) if p.closed else v[1:]
        a_parts.append(a)
        b_parts.append(b)
        own_parts.append(np.full(len(a), s, dtype=np.int64))
    a, b, own = np.concatenate(a_parts), np.concatenate(b_parts), np.concatenate(own_parts)
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    base = int(max(e.max(initial=-1), a.max(initial=-1), b.max(initial=-1))) + 1
    keys = e[:, 0] * base + e[:, 1]
    order = np.argsort(keys, kind="stable")
    want = np.minimum(a, b) * base + np.maximum(a, b)
    at = np.clip(np.searchsorted(keys[order], want), 0, max(len(keys) - 1, 0))
    found = keys[order][at] == want if len(keys) else np.zeros(len(want), dtype=bool)
    idx = order[at[found]]
    faces = np.asarray(edge_faces, dtype=np.int64)[idx]                     # (k, 2)
    owner = np.repeat(own[found], 2)
    face = faces.ravel()
    keep = face >= 0
    pair = np.unique(owner[keep] * (int(face.max(initial=0)) + 1) + face[keep])
    width = int(face.max(initial=0)) + 1
    return pair // width, pair % width


def node_pairs(lines: list[Polyline]) -> tuple[np.ndarray, np.ndarray]:
    """The nodes where a planar polyline of each family crosses, for orthogonal nodes (§2.3.4).

    Returns ``pairs (K, 2)`` — positions in ``lines`` of the family-0 and the family-1 polyline through each
    node — and ``vertex (K,)``, the node's vertex.  A vertex on two polylines of one family (a singular
    vertex) keeps the first of each."""
    first: dict[tuple[int, int], int] = {}
    for s, p in enumerate(lines):
        for v in p.vertices.tolist():
            first.setdefault((int(v), int(p.family)), s)
    verts = sorted({v for v, f in first if f == 0} & {v for v, f in first if f == 1})
    pairs = np.array([[first[(v, 0)], first[(v, 1)]] for v in verts], dtype=np.int64).reshape(-1, 2)
    return pairs, np.asarray(verts, dtype=np.int64)


def crease_stars(faces: np.ndarray, edge_faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The six vertices around every interior edge, for the crease barrier.

    Returns ``verts (E', 6)`` — the 4 corners of the first face, then the 2 corners of the second face that
    are not on the first — and ``slot_b (E', 4)``: the position in ``verts`` of each corner of the second face.
    """
    f = np.asarray(faces, dtype=np.int64)
    ef = np.asarray(edge_faces, dtype=np.int64)
    ef = ef[(ef >= 0).all(axis=1)]
    fa, fb = f[ef[:, 0]], f[ef[:, 1]]
    same = fb[:, :, None] == fa[:, None, :]                             # (E, 4 of b, 4 of a)
    shared = same.any(axis=2)
    slot = np.where(shared, np.argmax(same, axis=2), 4 + np.cumsum(~shared, axis=1) - 1)
    ok = (shared.sum(axis=1) == 2)
    verts = np.zeros((len(ef), 6), dtype=np.int64)
    verts[:, :4] = fa
    rows = np.arange(len(ef))
    for k in range(4):
        extra = ~shared[:, k] & ok
        verts[rows[extra], slot[extra, k]] = fb[extra, k]
    return verts[ok], slot[ok]


def dihedral(v: np.ndarray, verts: np.ndarray, slot_b: np.ndarray) -> np.ndarray:
    """The dihedral angles ``θ (E,)`` of :func:`dihedral_and_grad` without their derivative (the residual needs
    no more): the same operations, so the same numbers to the last bit."""
    if len(verts) == 0:
        return np.zeros(0)
    rows = np.arange(len(verts))
    ca = v[verts[:, :4]]
    cb = v[verts[rows[:, None], slot_b]]
    a = np.cross(ca[:, 2] - ca[:, 0], ca[:, 3] - ca[:, 1])
    b = np.cross(cb[:, 2] - cb[:, 0], cb[:, 3] - cb[:, 1])
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))


def dihedral_and_grad(v: np.ndarray, verts: np.ndarray, slot_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Dihedral angle ``θ (E,)`` (radians) between the diagonal normals ``n = (c2 − c0) × (c3 − c1)`` of the two
    faces of each edge, and ``∂θ/∂(6 vertices) (E, 6, 3)`` (see :func:`crease_stars`).

    With ``g = ∂θ/∂n`` (:func:`_angle_and_grad`) and ``d1 = c2 − c0``, ``d2 = c3 − c1``:
    ``∂θ/∂c2 = d2 × g = −∂θ/∂c0`` and ``∂θ/∂c3 = g × d1 = −∂θ/∂c1``.
    """
    e = len(verts)
    if e == 0:
        return np.zeros(0), np.zeros((0, 6, 3))
    rows = np.arange(e)
    ca = v[verts[:, :4]]
    cb = v[verts[rows[:, None], slot_b]]
    d1a, d2a = ca[:, 2] - ca[:, 0], ca[:, 3] - ca[:, 1]
    d1b, d2b = cb[:, 2] - cb[:, 0], cb[:, 3] - cb[:, 1]
    theta, ga, gb = _angle_and_grad(np.cross(d1a, d2a), np.cross(d1b, d2b))

    def corners(g: np.ndarray, d1: np.ndarray, d2: np.ndarray) -> np.ndarray:
        x, y = np.cross(d2, g), np.cross(g, d1)
        return np.stack([-x, -y, x, y], axis=1)

    jac = np.zeros((e, 6, 3))
    jac[:, :4] += corners(ga, d1a, d2a)
    cbj = corners(gb, d1b, d2b)
    for k in range(4):
        jac[rows, slot_b[:, k]] += cbj[:, k]
    return theta, jac

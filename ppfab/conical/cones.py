"""Conical meshes: residuals, cone axes (node axes) and offsets (§2.1.3, §2.3.3, §4).

A quad mesh with planar faces is *conical* when the faces around every vertex
touch a common cone of revolution (§2.3.3).  Equivalent tests, both measured here:

* the angle balance ``α1 + α3 = α2 + α4`` of the four face angles at an
  interior vertex (:func:`ppfab.metrics.grid_conical_residual`);
* the four unit face normals around a vertex are concyclic on ``S²``: they lie
  in a plane ``a·n = cos θ`` whose normal ``a`` is the cone axis (the vertices of
  the circular mesh ``M°_N`` of §4, Fig. 15).

The cone axes are the node axes of the canonical torsion-free support
structure (bisector planes of adjacent faces, §2.3.3).  Shifting every face
plane by the same distance ``δ`` along its unit normal keeps the mesh conical
(a Laguerre transform, §2.1.3); vertex ``v`` moves to ``v + δ a / (a·n)``.

Boundary vertices use the *extended* face planes of the grid: the ghost faces
one step beyond each side that the constructions keep in
``QuadGrid.extended_face_image`` (:mod:`ppfab.faceimage`).  The extended array has
shape ``(rows + 1, cols + 1, 4)`` for a grid of ``rows × cols`` vertices and
vertex ``v[i, j]`` is surrounded by ``E[i, j], E[i+1, j], E[i+1, j+1], E[i, j+1]``
(for a closed grid ``E[:, b]`` is face column ``(b − 1) mod cols``).  Without
stored ghosts (a grid read from a file) :func:`ghost_planes` builds them so that
every boundary vertex is conical and planar boundary polylines stay planar under
Laguerre maps and offsets (Minkowski reflections in the polyline's plane).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.folds import check_folds
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.transforms.laguerre import LaguerreMap
from ppfab.metrics import face_planarity, grid_conical_residual, plane_residual, polyline_planarity


# -- extended face planes -----------------------------------------------------------------

PLANAR_BOUNDARY_TOL = 1e-7
"""A boundary polyline within this distance of a plane (relative to the bounding-box diagonal) counts as planar."""


def extended_planes(grid: QuadGrid) -> np.ndarray:
    """Unit face planes with one ghost face beyond each side, ``(rows + 1, cols + 1, 4)``.

    Taken from ``grid.extended_face_planes`` (unit planes of a conical P
    construction) or ``grid.extended_face_image`` (the weighted face image of a
    PP construction, orientation of the weights kept) when the construction stored it
    and every vertex still lies on its four stored planes; otherwise built by
    :func:`ghost_planes`.
    """
    rows, cols = grid.shape
    size = _size(grid)
    for stored in (grid.extended_face_planes, grid.extended_face_image):
        if stored is not None:
            E = np.asarray(stored, dtype=float)
            if E.shape == (rows + 1, cols + 1, 4):
                E = pl.normalize(E)
                # stale planes (vertices changed after construction) are ignored
                if np.abs(pl.evaluate(vertex_planes(grid, E), grid.vertices[..., None, :])).max() <= 1e-7 * size:
                    return E
    return ghost_planes(grid)


def ghost_planes(grid: QuadGrid, tol: float = PLANAR_BOUNDARY_TOL) -> np.ndarray:
    """The unit face planes padded with conical ghost faces, ``(rows + 1, cols + 1, 4)``.

    A ghost face lies beyond a boundary face and passes through its boundary
    edge.  The ghosts are chosen so that the four planes around a boundary vertex
    touch one cone of revolution (concyclic normals): the vertex gets a cone
    axis, and its four planes meet in exactly that vertex.

    * **Planar boundary polyline** (within ``tol`` × bounding-box diagonal of its
      support plane, or else of its least-squares plane) ``W = (w, w₄)``, ``|w| = 1``:
      the ghosts are the Minkowski reflection (§2.1.1,
      :meth:`ppfab.laguerre.LaguerreMap.reflection`) of the boundary faces in
      ``H = (w, h₄)`` through a point ``Z = (p, 0)`` of ``W``.  It fixes every sphere
      with ``<<X − Z, H>> = 0``, among them the points of ``W``; the cone of a boundary
      vertex is the one in that hyperplane (direction ``(a, −c)`` with
      ``a·w + c h₄ = 0``), mapped to itself.  All cones of the polyline then lie in
      one hyperplane, so Laguerre maps and offsets keep the polyline planar
      (Prop. 2.1).  ``h₄`` is extrapolated from the interior: with
      ``h(a, c) = −(a·w)/c``, the bisector axis ``b ∝ n_k + n_{k+1}`` of the two faces
      at a boundary vertex and the axis ``a'`` of its interior neighbour,
      ``h₄ = median(2 h(b) − h(a'))`` (the bisector cone sits half a step inside;
      taking it itself makes a ghost coincide with its face where the net is
      principal, and ``h₄ = 0``, a Euclidean mirror, folds meshes that meet ``W``
      obliquely).  Corner ghosts are reflected in the column and then the row
      hyperplane.
    * **Non-planar open boundary polyline**: the ghosts are propagated.  At the
      middle boundary vertex the cone touching its two faces whose axis is nearest
      to the axis of the interior neighbour is chosen; vertex by vertex the circle
      through the three known normals then gives the next ghost, the second plane
      through the next boundary edge tangent to that cone.  A corner ghost is the
      reflection of the row ghost in the column hyperplane when the column is
      planar, else the tangent plane whose normal is opposite the face's normal on
      the corner cone's circle.
    * Otherwise (closed non-planar boundary, a single boundary face, degenerate
      cones) each boundary face is its own ghost: the boundary cones are the
      bisectors of two faces, which Laguerre maps and offsets handle, but the
      four planes of such a vertex meet in a line, not a point.

    Parameters
    ----------
    grid : a quad grid with planar faces
    tol : planarity tolerance of a boundary polyline, relative to the bounding-box diagonal
    """
    v = grid.vertices
    rows, cols = grid.shape
    f = pl.normalize(grid.face_planes)                          # (m, n', 4)
    m, size = rows - 1, _size(grid)
    fc = np.concatenate([f[:, -1:], f], axis=1) if grid.closed else f
    inner = _interior_cones(fc)                                 # interior vertices v[1:-1, 1:-1] (closed: v[1:-1])
    col_maps: list[LaguerreMap | None] = [None, None]
    ghosts: np.ndarray | None
    if grid.closed:
        pad = fc                                                # E[:, b] is face column (b − 1) mod cols
    else:
        sides = []
        for k, j in enumerate((0, -1)):
            support = None if grid.support_w is None else grid.support_w[j]
            W = _boundary_plane(v[:, j], support, size, tol)
            nb = None if inner is None else (inner[0][:, j], inner[1][:, j])
            cmap = None if W is None else _reflection(W, f[:-1, j, :3], f[1:, j, :3], nb)
            col_maps[k] = cmap
            if cmap is not None:
                ghosts = cmap.planes(f[:, j])
            else:
                ghosts = _propagated(v[:, j], f[:, j], None if nb is None else nb[0])
            sides.append(f[:, j] if ghosts is None else ghosts)
        pad = np.concatenate([sides[0][:, None], f, sides[1][:, None]], axis=1)   # (m, n + 2, 4)
    out = []
    for i, fi in ((0, 0), (m, m - 1)):
        support = None if grid.support_u is None else grid.support_u[i]
        U = _boundary_plane(v[i], support, size, tol)
        nb = None if inner is None else (inner[0][fi - (fi > 0)], inner[1][fi - (fi > 0)])
        umap = None if U is None else _reflection(U, fc[fi, :-1, :3], fc[fi, 1:, :3], nb)
        if umap is not None:
            out.append(umap.planes(pad[fi]))                   # corners: column ghosts reflected in turn
            continue
        ghosts = None if grid.closed else _propagated(v[i], f[fi], None if nb is None else nb[0])
        if ghosts is None:
            out.append(pad[fi])
            continue
        corners = [_corner_ghost(v[i, c], f[fi, c], ghosts[c], pad[fi, c], col_maps[k])
                   for k, c in enumerate((0, -1))]
        out.append(np.concatenate([corners[0][None], ghosts, corners[1][None]], axis=0))
    return np.concatenate([out[0][None], pad, out[1][None]], axis=0)


def _size(grid: QuadGrid) -> float:
    return float(np.linalg.norm(np.ptp(grid.vertices.reshape(-1, 3), axis=0))) or 1.0


def _interior_cones(fc: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Axes ``(m − 1, k, 3)`` and ``a·n`` ``(m − 1, k)`` of the cones at the vertices surrounded by four faces of
    ``fc (m, k + 1, 4)`` (for a closed grid ``fc`` starts with the last face column); ``None`` if there are none
    or they are degenerate."""
    if fc.shape[0] < 2 or fc.shape[1] < 2:
        return None
    P = np.stack([fc[:-1, :-1], fc[1:, :-1], fc[1:, 1:], fc[:-1, 1:]], axis=-2)
    try:
        a, c, _ = axis_of_normals(P[..., :3])
    except GeometryError:
        return None
    return a, c


def _boundary_plane(points: np.ndarray, support: np.ndarray | None, size: float, tol: float) -> np.ndarray | None:
    """The unit plane of a boundary polyline ``(k, 3)``: its support plane if the points lie in it, else the
    least-squares plane if they lie in that (within ``tol · size``), else ``None``."""
    if len(points) < 3:
        return None
    if support is not None and np.all(np.isfinite(support)) and np.linalg.norm(support[:3]) > 0:
        W = pl.normalize(support)
        if np.abs(pl.evaluate(W, points)).max() <= tol * size:
            return W
    W, res = pl.fit_plane(points)
    return W if res <= tol * size else None


def _reflection(W: np.ndarray, n1: np.ndarray, n2: np.ndarray,
                neighbours: tuple[np.ndarray, np.ndarray] | None) -> LaguerreMap | None:
    """The Minkowski reflection in ``H = (w, h₄)`` through a point of the plane ``W`` (see :func:`ghost_planes`).

    ``n1, n2 (k, 3)`` are the unit normals of the two faces at each of the ``k`` boundary vertices between
    corners, ``neighbours`` the axes ``(k, 3)`` and cosines ``(k,)`` of their interior neighbours.  ``None``
    when ``H`` is (nearly) null.
    """

    w = W[:3]
    b = n1 + n2
    length = np.linalg.norm(b, axis=-1)
    ok = length > 1e-9
    if not np.any(ok):
        return None
    b = b / np.where(ok, length, 1.0)[:, None]
    h = -(b @ w) / np.einsum("ki,ki->k", b, n1)
    if neighbours is not None and len(neighbours[0]) == len(h):
        h = 2.0 * h + (neighbours[0] @ w) / neighbours[1]
    h4 = float(np.median(h[ok]))
    if not np.isfinite(h4) or 1.0 - h4 * h4 <= 1e-6:
        return None
    return LaguerreMap.reflection(np.r_[w, h4], np.r_[-W[3] * w, 0.0])


def _second_tangent(axis: np.ndarray, face: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray | None:
    """The plane through the line ``pq`` other than ``face`` that touches the cone with unit ``axis`` (apex on
    the line) touched by ``face``: its normal is the mirror image of the face normal in the projection of the
    axis onto the plane normal to ``pq``."""
    t = q - p
    if np.linalg.norm(t) <= 0.0:
        return None
    t = t / np.linalg.norm(t)
    ap = axis - (axis @ t) * t
    length = np.linalg.norm(ap)
    if length <= 1e-9:
        return None
    ap = ap / length
    n = 2.0 * (face[:3] @ ap) * ap - face[:3]
    return np.r_[n, -(n @ p)]


def _circle_axis(n1: np.ndarray, n2: np.ndarray, n3: np.ndarray) -> np.ndarray | None:
    """Axis of the circle through three unit normals, turned towards them (``None`` if they are collinear)."""
    a = np.cross(n2 - n1, n3 - n1)
    length = np.linalg.norm(a)
    if length <= 1e-14:
        return None
    a = a / length
    return a if a @ n1 > 0 else -a


def _propagated(points: np.ndarray, faces: np.ndarray, axes: np.ndarray | None) -> np.ndarray | None:
    """Conical ghosts ``(k, 4)`` beyond the boundary faces ``faces (k, 4)`` of an open polyline ``points
    (k + 1, 3)`` (``faces[i]`` holds the edge ``points[i], points[i+1]``); ``axes (k − 1, 3)`` are the cone axes
    of the interior neighbours of ``points[1:-1]``.  Sequential along the boundary (each cone needs the
    previous ghost); ``None`` when the extension degenerates or folds."""
    k = len(faces)
    if k < 2:
        return None
    n = faces[:, :3]
    mid = k // 2                                                # vertex between faces mid − 1 and mid
    a = axes[mid - 1] if axes is not None and len(axes) == k - 1 else n[mid - 1] + n[mid]
    u = n[mid - 1] - n[mid]
    if np.linalg.norm(u) > 1e-12:                               # touch both faces: a·n_{mid−1} = a·n_mid
        u = u / np.linalg.norm(u)
        a = a - (a @ u) * u
    if np.linalg.norm(a) <= 1e-9:
        return None
    a = a / np.linalg.norm(a)
    g = np.empty_like(faces)
    first = (_second_tangent(a, faces[mid - 1], points[mid], points[mid - 1]),
             _second_tangent(a, faces[mid], points[mid], points[mid + 1]))
    if first[0] is None or first[1] is None:
        return None
    g[mid - 1], g[mid] = first
    for i in range(mid + 1, k):                                 # forward: vertex i knows g[i − 1]
        a = _circle_axis(n[i - 1], n[i], g[i - 1, :3])
        nxt = None if a is None else _second_tangent(a, faces[i], points[i], points[i + 1])
        if nxt is None:
            return None
        g[i] = nxt
    for i in range(mid - 1, 0, -1):                             # backward: vertex i knows g[i]
        a = _circle_axis(n[i - 1], n[i], g[i, :3])
        nxt = None if a is None else _second_tangent(a, faces[i - 1], points[i], points[i - 1])
        if nxt is None:
            return None
        g[i - 1] = nxt
    if not np.all(np.isfinite(g)) or np.any(np.einsum("ki,ki->k", g[:, :3], n) <= 0.0):
        return None                                             # a ghost turned away: the extension folds
    return g


def _corner_ghost(p: np.ndarray, face: np.ndarray, row_ghost: np.ndarray, col_ghost: np.ndarray, col_map) -> np.ndarray:
    """The ghost diagonally beyond a corner face at vertex ``p`` (see :func:`ghost_planes`)."""
    if col_map is not None:
        return col_map.planes(row_ghost)
    a = _circle_axis(face[:3], row_ghost[:3], col_ghost[:3])
    if a is None:
        return row_ghost
    n = 2.0 * (a @ face[:3]) * a - face[:3]
    return np.r_[n, -(n @ p)]


def vertex_planes(grid: QuadGrid, E: np.ndarray | None = None) -> np.ndarray:
    """The four face planes around every vertex in cyclic order, ``(rows, cols, 4, 4)``."""
    E = extended_planes(grid) if E is None else np.asarray(E, dtype=float)
    return np.stack([E[:-1, :-1], E[1:, :-1], E[1:, 1:], E[:-1, 1:]], axis=-2)


# -- cone axes -------------------------------------------------------------------------------

def axis_of_normals(normals: np.ndarray, degenerate: float = 1e-12,
                    mask: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Axis of the circle through unit normals ``(..., k, 3)`` on ``S²``.

    The axis ``a`` is the normal of the least-squares plane ``a·n = c`` through
    the ``k`` points: ``(n_k − n̄)·a = 0``, the eigenvector of the smallest eigenvalue of
    ``Σ (n_k − n̄)(n_k − n̄)ᵀ``.  When the points do not span a plane (two distinct normals,
    e.g. on a cylinder or at a boundary with repeated ghosts) the axis is the
    direction in the null space closest to the mean normal (the bisector).
    ``mask (..., k)`` marks the normals present when the stacks are padded.

    Returns
    -------
    axis : (..., 3) unit, turned to the side of the normals (``a·n > 0``)
    cos : (...,) mean ``a·n_k`` (cosine of the cone's half opening towards the faces)
    residual : (...,) largest distance of a normal from the plane (0 when concyclic)
    """
    n = np.asarray(normals, dtype=float)
    if mask is None:
        n = n / np.linalg.norm(n, axis=-1, keepdims=True)
        w = None
        mean = n.mean(axis=-2)
        y = n - mean[..., None, :]
    else:
        w = np.asarray(mask, dtype=float)
        n = n / np.where(w[..., None] > 0, np.linalg.norm(n, axis=-1, keepdims=True), 1.0)
        mean = np.einsum("...k,...ki->...i", w, n) / w.sum(axis=-1)[..., None]
        y = (n - mean[..., None, :]) * w[..., None]
    cov = np.einsum("...ki,...kj->...ij", y, y)
    ev, vec = np.linalg.eigh(cov)
    top = np.maximum(ev[..., 2:3], 1e-300)
    small = ev <= ev[..., :1] + degenerate * top                    # (..., 3) eigen-directions in the null space
    small = small | (ev[..., 2:3] <= 1e-28)                         # all normals equal: any axis, take the mean
    coef = np.einsum("...ik,...i->...k", vec, mean) * small         # components of the mean in the null space
    a = np.einsum("...ik,...k->...i", vec, coef)
    length = np.linalg.norm(a, axis=-1, keepdims=True)
    if np.any(length <= 1e-14):
        idx = tuple(int(k) for k in np.argwhere(length[..., 0] <= 1e-14)[0])
        raise GeometryError(f"the face normals around vertex {idx} do not define a cone axis "
                            f"(they are spread over a great circle)", element=f"vertex {idx}")
    a = a / length
    c = np.einsum("...ki,...i->...k", n, a)
    if w is None:
        return a, c.mean(axis=-1), np.abs(c - c.mean(axis=-1, keepdims=True)).max(axis=-1)
    cm = (c * w).sum(axis=-1) / w.sum(axis=-1)
    residual = np.where(w > 0, np.abs(c - cm[..., None]), 0.0).max(axis=-1)
    return a, cm, residual


def vertex_face_normals(mesh: QuadMesh) -> tuple[np.ndarray, np.ndarray]:
    """Padded unit normals of the faces at each vertex of a quad mesh, ``(N, k, 3)``, and a mask ``(N, k)``."""
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


def cone_axes(mesh: QuadGrid | QuadMesh, inward: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Node axes of a conical mesh: the axes of the vertex cones (§2.3.3), :func:`axis_of_normals` of the
    unit normals of the faces around each vertex.

    Parameters
    ----------
    mesh : a conical grid (boundary vertices use the extended face planes, ghosts included), or any quad
        mesh (the faces around each vertex; vertices with fewer than 3 faces have no cone)
    inward : turn the axes against the face normals (the side of the beams, as
        :func:`ppfab.faceimage.orient_axes` does); otherwise along them

    Returns
    -------
    axes : (rows, cols, 3) for a grid, (N, 3) for a quad mesh; unit, 0 where undetermined
    cos : (rows, cols) or (N,) ``a·n`` of the faces at each vertex (positive); ``nan`` where undetermined
    """
    if isinstance(mesh, QuadGrid):
        P = vertex_planes(mesh)
        a, c, _ = axis_of_normals(P[..., :3])
        return (-a if inward else a), c
    normals, mask = vertex_face_normals(mesh)
    determined = mask.sum(axis=1) >= 3
    axes = np.zeros((len(mesh.vertices), 3))
    cos = np.full(len(mesh.vertices), np.nan)
    if np.any(determined):
        a, c, _ = axis_of_normals(normals[determined], mask=mask[determined])
        axes[determined] = -a if inward else a
        cos[determined] = c
    return axes, cos


def concyclic_residual(grid: QuadGrid) -> np.ndarray:
    """Largest distance of the four unit face normals at a vertex from their common circle, ``(rows, cols)``.

    Points on ``S²`` are concyclic iff coplanar; the value is in radians to
    first order.  At boundary vertices the ghost faces are included.
    """
    P = vertex_planes(grid)
    return axis_of_normals(P[..., :3])[2]


# -- offsets ----------------------------------------------------------------------------------

CONICAL_TOLERANCE = 1e-5
"""Largest distance (radians, to first order) of the unit face normals at a vertex from their common
circle for :func:`offset_faces` to treat a grid as conical: above the precision of published conical
meshes stored as text (5.7e-6 for ``DOS__conical1.obj``), far below a mesh that is not conical (1e-3)."""


def offset_faces(grid: QuadGrid, distance: float, tol: float = CONICAL_TOLERANCE) -> QuadGrid:
    """The offset of a conical grid at constant face–face distance ``distance`` (§2.1.3).

    Every face plane moves by ``distance`` along its unit normal; vertex ``v``
    moves along its cone axis ``a`` to ``v + distance · a / (a·n)``.  The result
    is parallel to the input (same face normals), hence conical with the same
    planar polyline families; weighted face images are shifted with their
    weights (``F − |F_n| δ e4``), so a PP face image stays a translation net.

    The extended planes used (stored or built by :func:`ghost_planes`) are shifted too and kept in
    ``extended_face_planes``; they pass through the new vertices.

    Raises :class:`GeometryError` when a cone degenerates (``a·n ≤ 0.05``) or the
    offset planes do not meet at a vertex: the input is not conical, the four unit normals at some vertex
    lie further than ``tol`` from a circle (:func:`concyclic_residual`), and moving the vertices along
    the fitted axes would bend the faces out of plane.
    """
    d = float(distance)
    E = extended_planes(grid)
    P = vertex_planes(grid, E)
    a, c, res = axis_of_normals(P[..., :3])
    if np.any(res > tol):
        idx = tuple(int(k) for k in np.unravel_index(int(np.argmax(res)), res.shape))
        raise GeometryError(f"vertex {idx}: the face normals around it are {float(res.max()):.2e} from a common circle "
                            f"(> {tol:g}); the mesh is not conical, so no offset at constant face distance exists",
                            element=f"vertex {idx}", value=float(res.max()))
    if np.any(c <= 0.05):
        idx = tuple(int(k) for k in np.argwhere(c <= 0.05)[0])
        raise GeometryError(f"vertex {idx}: its faces make {np.degrees(np.arccos(np.clip(c[idx], -1, 1))):.1f}° "
                            f"with the cone axis; an offset is ill defined", element=f"vertex {idx}", value=float(c[idx]))
    v = grid.vertices + d * a / c[..., None]
    meta = {**grid.meta, "offset_distance": grid.meta.get("offset_distance", 0.0) + d}
    image = grid.extended_face_image
    out = replace(grid, vertices=v, face_image=None if grid.face_image is None else _shift_planes(grid.face_image, d),
                  support_u=_refit(v, grid.support_u, rows=True), support_w=_refit(v, grid.support_w, rows=False),
                  extended_face_image=None if image is None else _shift_planes(np.asarray(image, dtype=float), d),
                  extended_face_planes=_shift_planes(E, d),          # the planes used, through the new vertices
                  meta=meta)
    return out


def _shift_planes(F: np.ndarray, d: float) -> np.ndarray:
    F = np.array(F, dtype=float)
    F[..., 3] -= np.linalg.norm(F[..., :3], axis=-1) * d
    return F


def _refit(v: np.ndarray, old: np.ndarray | None, rows: bool) -> np.ndarray | None:
    """Least-squares planes of the rows (or columns) of ``v``, oriented like ``old``."""
    if old is None:
        return None
    pts = v if rows else v.transpose(1, 0, 2)
    new, _ = pl.fit_plane(pts)
    old = pl.normalize(old)
    sign = np.where(np.einsum("ki,ki->k", new[:, :3], old[:, :3]) < 0, -1.0, 1.0)
    return new * sign[:, None]


# -- rigid motions --------------------------------------------------------------------------

def rigid_motion(grid: QuadGrid, rotation: np.ndarray, translation: np.ndarray | None = None) -> QuadGrid:
    """Apply ``x' = R x + t`` (``R`` a proper rotation) to a grid and all its planes and axes.

    Weighted planes map as ``(n, d) ↦ (R n, d − (R n)·t)``.
    """
    R = np.asarray(rotation, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-12) or np.linalg.det(R) < 0:
        raise GeometryError("rigid_motion needs a proper 3×3 rotation matrix")
    t = np.zeros(3) if translation is None else np.asarray(translation, dtype=float)

    def planes(p):
        if p is None:
            return None
        p = np.asarray(p, dtype=float)
        n = p[..., :3] @ R.T
        return np.concatenate([n, (p[..., 3] - n @ t)[..., None]], axis=-1)

    return replace(grid, vertices=grid.vertices @ R.T + t, support_u=planes(grid.support_u),
                   support_w=planes(grid.support_w), face_image=planes(grid.face_image),
                   axes=None if grid.axes is None else grid.axes @ R.T,
                   extended_face_image=planes(grid.extended_face_image),
                   extended_face_planes=planes(grid.extended_face_planes))


# -- one summary --------------------------------------------------------------------------------

@dataclass(frozen=True)
class ConicalQuality:
    """Measured properties of a (supposedly) conical P/PP grid.

    ``angle_max`` — max ``|α1 − α2 + α3 − α4|`` over interior vertices (rad);
    ``concyclic_max`` — max distance of the unit normals from their circle (rad, interior vertices);
    ``delta_f_max`` — max face planarity ``δ_f``;
    ``delta_p_rows_max`` / ``delta_p_cols_max`` — max ``δ_P`` of the row / column polylines;
    ``support_u_max`` / ``support_w_max`` — max distance of rows / columns from the grid's own
    support planes relative to their bounding box (NaN without support planes).
    """

    angle_max: float
    concyclic_max: float
    delta_f_max: float
    delta_p_rows_max: float
    delta_p_cols_max: float
    support_u_max: float
    support_w_max: float

    def as_dict(self) -> dict:
        return asdict(self)


def conical_quality(grid: QuadGrid) -> ConicalQuality:
    """Measure the conical, planar-face and planar-polyline properties of a grid at once."""
    v = grid.vertices
    if grid.closed:
        vv = np.concatenate([v[:, -1:], v, v[:, :1]], axis=1)
        angle = grid_conical_residual(vv) if v.shape[0] >= 3 else np.zeros(1)
        cyc = concyclic_residual(grid)[1:-1]
    else:
        angle = grid_conical_residual(v) if min(v.shape[:2]) >= 3 else np.zeros(1)
        cyc = concyclic_residual(grid)[1:-1, 1:-1]
    su = plane_residual(grid.rows(), grid.support_u).max() if grid.support_u is not None else np.nan
    sw = plane_residual(grid.cols(), grid.support_w).max() if grid.support_w is not None else np.nan
    return ConicalQuality(
        angle_max=float(np.max(angle, initial=0.0)),
        concyclic_max=float(np.max(cyc, initial=0.0)),
        delta_f_max=float(face_planarity(grid.face_corners).max()),
        delta_p_rows_max=float(polyline_planarity(grid.rows()).max()) if v.shape[1] >= 3 else 0.0,
        delta_p_cols_max=float(polyline_planarity(grid.cols()).max()) if v.shape[0] >= 3 else 0.0,
        support_u_max=float(su), support_w_max=float(sw),
    )


# -- Laguerre maps of conical meshes ----------------------------------------------------------

def laguerre_transform(grid: QuadGrid, lmap: "LaguerreMap", check: bool = True, max_residual: float = 1e-6) -> QuadGrid:
    """Apply a Laguerre map to a conical grid (§2.1.3): face planes map, vertices follow their cones.

    The cone of vertex ``v`` (axis ``a``, ``a·n = c``) is the sphere line ``(v, 0) + t (a, −c)``;
    the new vertex is the radius-0 sphere of its image.  Planar faces, the
    conical property and planar polylines (Prop. 2.1) carry over; support planes
    present on the input are refitted to the new rows / columns.

    Raises :class:`GeometryError` when the input is not conical (residual above
    ``max_residual``) or a vertex goes to infinity (its cone becomes a
    cylinder), and :class:`~ppfab.errors.FoldError` (with ``check``) when the image folds.
    """
    E = extended_planes(grid)
    a, c, res = axis_of_normals(vertex_planes(grid, E)[..., :3])
    if np.max(res[1:-1, 1:-1] if not grid.closed else res[1:-1], initial=0.0) > max_residual:
        idx = tuple(int(k) for k in np.argwhere(res == res.max())[0])
        raise GeometryError(f"the mesh is not conical at vertex {idx} (normals off their circle by {res.max():.3g}); "
                            f"a Laguerre map cannot be applied to its faces", element=f"vertex {idx}",
                            value=float(res.max()))
    v = grid.vertices
    zero = np.zeros(v.shape[:-1] + (1,))
    base = lmap.spheres(np.concatenate([v, zero], axis=-1))
    direc = lmap.lam * np.concatenate([a, -c[..., None]], axis=-1) @ lmap.A.T
    denom = direc[..., 3]
    size = np.linalg.norm(np.ptp(v.reshape(-1, 3), axis=0))
    tstar = -base[..., 3] / np.where(denom == 0, np.nan, denom)
    new = base[..., :3] + tstar[..., None] * direc[..., :3]
    bad = ~np.isfinite(new).all(axis=-1) | (np.linalg.norm(new - new.reshape(-1, 3).mean(0), axis=-1) > 1e6 * max(float(size), 1e-300))
    if np.any(bad):
        idx = tuple(int(k) for k in np.argwhere(bad)[0])
        raise GeometryError(f"vertex {idx} goes to infinity under the Laguerre map (its cone becomes a cylinder)",
                            element=f"vertex {idx}")
    Enew = lmap.planes(E)
    out = QuadGrid(new, closed=grid.closed, support_u=_refit(new, grid.support_u, rows=True),
                   support_w=_refit(new, grid.support_w, rows=False), face_image=None, axes=None,
                   vertex_ids=grid.vertex_ids, extended_face_planes=Enew, meta=grid.meta)
    inner = Enew[1:-1, 1:] if grid.closed else Enew[1:-1, 1:-1]
    if check:
        check_folds(out, reference=inner, context="the Laguerre image")
    a2, _, _ = axis_of_normals(vertex_planes(out, Enew)[..., :3])
    return replace(out, axes=-a2)

"""Quality metrics of §3.3 and mesh sanity checks.

* ``δ_f`` of a face: distance between the two diagonal lines divided by the
  mean diagonal length (paper §3.3).
* ``δ_P`` of a polyline: largest distance of its vertices from the
  least-squares plane divided by the diagonal of its bounding box (§3.3).
  Polylines with fewer than three vertices are planar by definition and skipped.
* Absolute panel deviation: largest distance of a face corner from the
  face's least-squares plane, in the mesh's units (mm in fabrication).
* Conical residual at an interior valence-4 vertex with face angles
  ``α1..α4`` in cyclic order: ``|α1 − α2 + α3 − α4|`` (§2.3.3; a mesh is
  conical iff it vanishes at every interior vertex).
* Folds: neighbouring faces whose oriented normals point in opposite
  directions (the mesh passes through a cuspidal edge), and faces whose
  corners turn the wrong way (non-convex or self-intersecting quads).
* Creases: at every interior edge the dihedral angle ``θ_e ∈ [0°, 180°]``
  between the oriented unit normals of its two faces (0° where the faces are
  coplanar).  A fold is a crease past 90°.  A crease that an optimisation
  *created* is measured against the input, edge by edge: ``θ_e − θ⁰_e``.
* Corner angles: the deviation ``|α − 90°|`` of every face corner angle from a
  right angle (near-rectangular panels, §4).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ppfab import planes as pl
from .mesh import QuadGrid, QuadMesh, as_quadmesh
from .topology import Polyline


def face_planarity(corners: np.ndarray) -> np.ndarray:
    """``δ_f`` for quads ``(..., 4, 3)``: diagonal distance / mean diagonal length (§3.3)."""
    c = np.asarray(corners, dtype=float)
    d1 = c[..., 2, :] - c[..., 0, :]
    d2 = c[..., 3, :] - c[..., 1, :]
    cross = np.cross(d1, d2)
    cn = np.linalg.norm(cross, axis=-1)
    w = c[..., 1, :] - c[..., 0, :]
    dist = np.abs(np.einsum("...i,...i->...", w, cross)) / np.where(cn == 0, 1.0, cn)
    mean_len = 0.5 * (np.linalg.norm(d1, axis=-1) + np.linalg.norm(d2, axis=-1))
    return dist / np.where(mean_len == 0, 1.0, mean_len)


def face_deviation(corners: np.ndarray) -> np.ndarray:
    """Largest distance of a corner from the face's least-squares plane, ``(...)``, mesh units."""
    _, residual = pl.fit_plane(np.asarray(corners, dtype=float))
    return residual


def polyline_planarity(points: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """``δ_P`` for polylines ``(..., k, 3)`` (optionally padded, ``weights`` 0 = absent).

    Returns ``(...)``; polylines with fewer than 3 present vertices get 0.
    """
    x = np.asarray(points, dtype=float)
    w = np.ones(x.shape[:-1]) if weights is None else np.asarray(weights, dtype=float)
    count = (w > 0).sum(axis=-1)
    _, residual = pl.fit_plane(x, np.where(count[..., None] >= 3, w, np.ones_like(w)))
    big = np.where(w[..., None] > 0, x, np.nan)
    diag = np.linalg.norm(np.nanmax(big, axis=-2) - np.nanmin(big, axis=-2), axis=-1)
    out = residual / np.where(diag == 0, 1.0, diag)
    return np.where(count >= 3, out, 0.0)


def plane_residual(points: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """Largest distance of each polyline ``(..., k, 3)`` from its given plane ``(..., 4)``, relative to its bbox diagonal."""
    x = np.asarray(points, dtype=float)
    dist = np.abs(pl.signed_distance(np.asarray(planes)[..., None, :], x)).max(axis=-1)
    diag = np.linalg.norm(x.max(axis=-2) - x.min(axis=-2), axis=-1)
    return dist / np.where(diag == 0, 1.0, diag)


def polyline_fit(mesh: QuadMesh) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares plane ``(L, 4)`` and absolute deviation ``(L,)`` of every polyline of ``mesh.polylines``.

    The deviation is the largest distance of a polyline's vertices from its plane (mesh units); polylines with
    fewer than 3 vertices get ``nan`` planes and deviation 0.  ``δ_P`` (§3.3) is this deviation over the
    bounding-box diagonal (:func:`relative_deviation`).
    """
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


def relative_deviation(dev: np.ndarray, mesh: QuadMesh) -> np.ndarray:
    """``(L,)`` deviation of each polyline relative to its bounding-box diagonal (``δ_P`` of §3.3)."""
    out = np.zeros(len(dev))
    for k, p in enumerate(mesh.polylines):
        x = mesh.vertices[p.vertices]
        diag = float(np.linalg.norm(x.max(axis=0) - x.min(axis=0)))
        out[k] = dev[k] / diag if diag > 0 else 0.0
    return out


def pad_polylines(vertices: np.ndarray, lines: list[Polyline]) -> tuple[np.ndarray, np.ndarray]:
    """Stack polylines of different lengths into ``(L, kmax, 3)`` points and ``(L, kmax)`` weights."""
    if not lines:
        return np.zeros((0, 1, 3)), np.zeros((0, 1))
    kmax = max(len(p) for p in lines)
    idx = np.zeros((len(lines), kmax), dtype=np.int64)
    w = np.zeros((len(lines), kmax))
    for r, p in enumerate(lines):
        idx[r, : len(p)] = p.vertices
        w[r, : len(p)] = 1.0
    return vertices[idx], w


def grid_conical_residual(v: np.ndarray) -> np.ndarray:
    """``|α1 − α2 + α3 − α4|`` at interior vertices of a grid ``(m+1, n+1, 3)`` → ``(m−1, n−1)``."""
    c = v[1:-1, 1:-1]
    e = [v[1:-1, 2:] - c, v[2:, 1:-1] - c, v[1:-1, :-2] - c, v[:-2, 1:-1] - c]
    ang = [_angle(e[k], e[(k + 1) % 4]) for k in range(4)]
    return np.abs(ang[0] - ang[1] + ang[2] - ang[3])


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cr = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.einsum("...i,...i->...", a, b)
    return np.arctan2(cr, dot)


def circular_residual(corners: np.ndarray) -> np.ndarray:
    """``|α_0 − α_1 + α_2 − α_3|`` over the corner angles of every quad ``(F, 4, 3)`` → ``(F,)`` (radians): a
    planar convex quad is inscribed in a circle iff its opposite angles add up to π, i.e. iff this is 0
    (§2.3.3, Remark 2.1: circular meshes)."""
    c = np.asarray(corners, dtype=float)
    ang = _angle(np.roll(c, 1, axis=1) - c, np.roll(c, -1, axis=1) - c)          # (F, 4)
    return np.abs(ang[:, 0] - ang[:, 1] + ang[:, 2] - ang[:, 3])


def mesh_conical_residual(mesh: QuadMesh) -> np.ndarray:
    """Conical residual at every interior valence-4 vertex of a general quad mesh (NaN elsewhere)."""
    topo = mesh.topology
    v = np.asarray(mesh.vertices)
    f = np.asarray(mesh.faces)
    # corner angle of every face corner and its vertex
    prev = np.roll(f, 1, axis=1)
    nxt = np.roll(f, -1, axis=1)
    ang = _angle(v[prev] - v[f], v[nxt] - v[f]).ravel()
    vert = f.ravel()
    res = np.full(len(v), np.nan)
    regular = (~topo.boundary_vertices) & (topo.valence == 4) & (topo.face_count == 4)
    # cyclic face order around v: rotate by one face starting from any edge
    src, dst, face = topo._rotation
    n = topo.n_vertices
    corner_of = {}
    for fi, k, vv in zip(np.repeat(np.arange(len(f)), 4), np.tile(np.arange(4), len(f)), vert):
        corner_of[(int(fi), int(vv))] = fi * 4 + k
    key_to = dict(zip(src.tolist(), zip(dst.tolist(), face.tolist())))
    for vv in np.flatnonzero(regular):
        k0 = int(src[np.searchsorted(src, vv * n)])
        key, alphas = k0, []
        for _ in range(4):
            key, fc = key_to[key]
            alphas.append(ang[corner_of[(fc, int(vv))]])
        res[vv] = abs(alphas[0] - alphas[1] + alphas[2] - alphas[3])
    return res


def dihedral_angles(face_normals: np.ndarray, edge_faces: np.ndarray) -> np.ndarray:
    """Dihedral angle ``θ_e`` in degrees ``(E,)`` between the two faces of each edge (NaN on the boundary).

    Parameters
    ----------
    face_normals : (F, 3) oriented face normals (any length; zero-length normals give NaN)
    edge_faces : (E, 2) int, the faces on either side of each edge, ``-1`` on the boundary

    ``θ_e = atan2(‖n_a × n_b‖, n_a · n_b)``: 0° for coplanar faces, 90° for a right-angled ridge,
    above 90° a fold (the faces turn back on each other).

    Examples
    --------
    >>> n = np.array([[0.0, 0, 1], [0, 1, 1]])
    >>> dihedral_angles(n, np.array([[0, 1], [0, -1]])).round(6).tolist()
    [45.0, nan]
    """
    n = np.asarray(face_normals, dtype=float)
    ef = np.asarray(edge_faces, dtype=np.int64)
    out = np.full(len(ef), np.nan)
    inner = (ef >= 0).all(axis=1)
    a, b = n[ef[inner, 0]], n[ef[inner, 1]]
    cr = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.einsum("ij,ij->i", a, b)
    ok = (np.linalg.norm(a, axis=1) > 0) & (np.linalg.norm(b, axis=1) > 0)
    out[np.flatnonzero(inner)] = np.where(ok, np.degrees(np.arctan2(cr, dot)), np.nan)
    return out


def mesh_dihedral_angles(mesh: QuadMesh | QuadGrid) -> np.ndarray:
    """Dihedral angles ``(E,)`` in degrees at the edges of ``mesh.edges`` (NaN on the boundary), from the
    diagonal normals ``(c2 − c0) × (c3 − c1)`` of the faces."""
    qm = as_quadmesh(mesh)
    return dihedral_angles(qm.face_planes[:, :3], qm.topology.edge_faces)


@dataclass(frozen=True)
class CreaseReport:
    """Creases of a mesh measured against a reference (the input of an optimisation).

    angles : (E,) dihedral angle of every edge, degrees (NaN on the boundary)
    change : (E,) ``angles − angles of the reference`` (NaN on the boundary)
    limit : degrees; an edge above it that was not above it in the reference is a *created* crease
    created : (k,) indices into ``mesh.edges`` of the created creases, largest first
    """

    angles: np.ndarray
    change: np.ndarray
    limit: float
    created: np.ndarray

    @property
    def max(self) -> float:
        """Largest dihedral angle, degrees (0 for a mesh without interior edges)."""
        a = self.angles[np.isfinite(self.angles)]
        return float(a.max()) if a.size else 0.0

    @property
    def change_max(self) -> float:
        """Largest increase of an edge's dihedral angle over the reference, degrees."""
        c = self.change[np.isfinite(self.change)]
        return float(max(c.max(), 0.0)) if c.size else 0.0


def crease_report(angles: np.ndarray, reference: np.ndarray, limit: float) -> CreaseReport:
    """Compare dihedral angles ``(E,)`` with those of a reference ``(E,)`` (same edges), degrees.

    An edge is a created crease when its angle exceeds ``limit`` (by more than 1e-6°, the rounding of a
    guard that holds edges at the limit) and exceeds its reference angle (an input crease that was already
    beyond the limit and did not grow is not counted).
    """
    a = np.asarray(angles, dtype=float)
    r = np.asarray(reference, dtype=float)
    change = a - r
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero(np.isfinite(a) & (a > limit + 1e-6) & (change > 1e-9))
    return CreaseReport(a, change, float(limit), bad[np.argsort(-a[bad])])


def conjugacy_defect(mesh: QuadMesh | QuadGrid) -> float:
    """How far the net is from a conjugate net, as a ratio of twist to normal curvature (dimensionless).

    A quad mesh approximates a parametrisation; planar quads approximate a *conjugate* one (§2.3.1), whose
    mixed second derivative is tangent.  Per face, the normal part of the mixed difference
    ``t_f = |⟨n_f, c0 − c1 + c2 − c3⟩|`` (≈ the twist ``II(e1, e2)``, a length) is compared with the turning of
    the surface across the face's edges, ``ℓ_f θ̄_f`` (mean edge length × mean dihedral angle in radians of its
    interior edges, ≈ the normal curvatures ``II(e, e)``)::

        defect = Σ_f t_f / Σ_f ℓ_f θ̄_f

    About 0 for a conjugate net (planar quads: every ``t_f = 0``), of order 1 for a net at 45° to the
    principal directions (a geodesic or S-net on a doubly curved surface), where planar faces with
    planar polylines need new polylines along conjugate curves.  0 for a mesh without curvature.
    """
    qm = as_quadmesh(mesh)
    c = qm.face_corners
    if not len(c):
        return 0.0
    n = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    t = np.abs(np.einsum("ij,ij->i", n, c[:, 0] - c[:, 1] + c[:, 2] - c[:, 3]))
    ell = np.linalg.norm(c - np.roll(c, -1, axis=1), axis=-1).mean(axis=1)
    theta = np.radians(mesh_dihedral_angles(qm))
    ef = qm.topology.edge_faces
    inner = np.isfinite(theta)
    sides = np.concatenate([ef[inner, 0], ef[inner, 1]])
    total = np.bincount(sides, np.concatenate([theta[inner], theta[inner]]), minlength=len(c))
    count = np.bincount(sides, minlength=len(c))
    denom = float((ell * total / np.maximum(count, 1)).sum())
    return float(t.sum() / denom) if denom > 0 else 0.0


def corner_angles(corners: np.ndarray) -> np.ndarray:
    """Corner angles ``(..., 4)`` in degrees of quads ``(..., 4, 3)`` (the angle at corner ``k`` between
    the edges to corners ``k − 1`` and ``k + 1``)."""
    c = np.asarray(corners, dtype=float)
    return np.degrees(_angle(np.roll(c, 1, axis=-2) - c, np.roll(c, -1, axis=-2) - c))


def polygon_area(q: np.ndarray) -> np.ndarray:
    """Signed areas ``(...)`` of plane polygons ``(..., k, 2)`` by the shoelace formula
    ``½ Σ (x_i y_{i+1} − x_{i+1} y_i)``: positive when the corners run counter-clockwise.

    >>> float(polygon_area(np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])))
    2.0
    """
    q = np.asarray(q, dtype=float)
    x, y = q[..., 0], q[..., 1]
    return 0.5 * (np.sum(x * np.roll(y, -1, axis=-1), axis=-1) - np.sum(y * np.roll(x, -1, axis=-1), axis=-1))


def flipped_edges(face_planes: np.ndarray, edge_faces: np.ndarray) -> np.ndarray:
    """Interior edges whose two faces have opposite oriented normals, ``(k,)`` edge indices."""
    ef = edge_faces
    inner = ef[:, 1] >= 0
    n = face_planes[:, :3]
    dots = np.einsum("ij,ij->i", n[ef[inner, 0]], n[ef[inner, 1]])
    return np.flatnonzero(inner)[dots < 0]


def nonconvex_faces(corners: np.ndarray) -> np.ndarray:
    """Boolean ``(...)``: a quad whose corners do not all turn the same way about its normal."""
    c = np.asarray(corners, dtype=float)
    n = np.cross(c[..., 2, :] - c[..., 0, :], c[..., 3, :] - c[..., 1, :])
    e_in = c - np.roll(c, 1, axis=-2)
    e_out = np.roll(c, -1, axis=-2) - c
    turn = np.einsum("...ki,...i->...k", np.cross(e_in, e_out), n)
    return np.any(turn <= 0, axis=-1)


@dataclass(frozen=True)
class Quality:
    """The quality summary of a mesh (all relative values dimensionless, ``abs`` in mesh units)."""

    faces: int
    delta_f_max: float
    delta_f_mean: float
    deviation_abs_max: float
    delta_p_rows_max: float
    delta_p_rows_mean: float
    delta_p_cols_max: float
    delta_p_cols_mean: float
    polylines_rows: int
    polylines_cols: int
    polylines_skipped: int
    conical_max: float
    conical_mean: float
    circular_max: float
    circular_mean: float
    crease_max: float
    crease_edges_over_30: int
    corner_deviation_max: float
    flipped_edges: int
    nonconvex_faces: int
    degenerate_edges: int
    grid_shape: tuple[int, int] | None
    closed: bool

    def as_dict(self) -> dict:
        return asdict(self)

    def table(self) -> str:
        """Human-readable metrics table."""
        g = f"regular grid {self.grid_shape[0]} x {self.grid_shape[1]}" + (" (rows closed)" if self.closed else "") \
            if self.grid_shape else "general quad mesh"
        rows = [
            ("combinatorics", g),
            ("faces", f"{self.faces}"),
            ("delta_f max / mean", f"{self.delta_f_max:.3e} / {self.delta_f_mean:.3e}"),
            ("panel deviation max (mesh units)", f"{self.deviation_abs_max:.3e}"),
            (f"delta_P rows ({self.polylines_rows}) max / mean",
             f"{self.delta_p_rows_max:.3e} / {self.delta_p_rows_mean:.3e}"),
            (f"delta_P cols ({self.polylines_cols}) max / mean",
             f"{self.delta_p_cols_max:.3e} / {self.delta_p_cols_mean:.3e}"),
            ("polylines skipped (< 3 vertices)", f"{self.polylines_skipped}"),
            ("conical residual max / mean (rad)", f"{self.conical_max:.3e} / {self.conical_mean:.3e}"),
            ("circular residual max / mean (rad)", f"{self.circular_max:.3e} / {self.circular_mean:.3e}"),
            ("crease max (dihedral angle, deg) / edges > 30 deg", f"{self.crease_max:.2f} / {self.crease_edges_over_30}"),
            ("corner angle max deviation from 90 deg", f"{self.corner_deviation_max:.2f}"),
            ("folds (flipped edges / non-convex faces)", f"{self.flipped_edges} / {self.nonconvex_faces}"),
            ("degenerate edges", f"{self.degenerate_edges}"),
        ]
        width = max(len(r[0]) for r in rows)
        return "\n".join(f"{k.ljust(width)}  {v}" for k, v in rows)


def _stats(a: np.ndarray) -> tuple[float, float]:
    a = np.asarray(a, dtype=float)
    a = a[np.isfinite(a)]
    return (float(a.max()), float(a.mean())) if a.size else (0.0, 0.0)


def family_planarity(mesh: QuadMesh, family: int) -> tuple[np.ndarray, int]:
    """``δ_P`` of every polyline of a family with >= 3 vertices, and the number skipped."""
    if mesh.grid is not None:
        g = mesh.grid
        pts = g.rows() if family == 0 else g.cols()
        return polyline_planarity(pts), 0
    lines = mesh.family(family)
    keep = [p for p in lines if len(p) >= 3]
    pts, w = pad_polylines(np.asarray(mesh.vertices), keep)
    return polyline_planarity(pts, w), len(lines) - len(keep)


def quality(mesh: QuadMesh | QuadGrid, degenerate_tol: float = 1e-9) -> Quality:
    """All metrics of a mesh; a :class:`QuadGrid` is measured with its grid structure."""
    grid = mesh if isinstance(mesh, QuadGrid) else mesh.grid
    qm = as_quadmesh(mesh)
    corners = qm.face_corners
    df = face_planarity(corners)
    dev = face_deviation(corners)
    rows, skip0 = family_planarity(qm, 0)
    cols, skip1 = family_planarity(qm, 1)
    if grid is not None:
        v = grid.vertices
        if grid.closed:
            v = np.concatenate([v[:, -1:], v, v[:, :1]], axis=1)
            conical = grid_conical_residual(v)
        else:
            conical = grid_conical_residual(v) if min(v.shape[:2]) >= 3 else np.zeros(0)
    else:
        conical = mesh_conical_residual(qm)
    circ = circular_residual(corners)
    lengths = qm.edge_lengths()
    scale = float(np.mean(lengths)) if len(lengths) else 1.0
    crease = mesh_dihedral_angles(qm)
    corner_dev = np.abs(corner_angles(corners) - 90.0)
    return Quality(
        faces=len(corners),
        delta_f_max=_stats(df)[0], delta_f_mean=_stats(df)[1],
        deviation_abs_max=_stats(dev)[0],
        delta_p_rows_max=_stats(rows)[0], delta_p_rows_mean=_stats(rows)[1],
        delta_p_cols_max=_stats(cols)[0], delta_p_cols_mean=_stats(cols)[1],
        polylines_rows=len(rows), polylines_cols=len(cols), polylines_skipped=skip0 + skip1,
        conical_max=_stats(conical)[0], conical_mean=_stats(conical)[1],
        circular_max=_stats(circ)[0], circular_mean=_stats(circ)[1],
        crease_max=_stats(crease)[0], crease_edges_over_30=int(np.sum(np.nan_to_num(crease) > 30.0)),
        corner_deviation_max=_stats(corner_dev)[0],
        flipped_edges=len(flipped_edges(qm.face_planes, qm.topology.edge_faces)),
        nonconvex_faces=int(nonconvex_faces(corners).sum()),
        degenerate_edges=int((lengths <= degenerate_tol * scale).sum()),
        grid_shape=grid.shape if grid is not None else None,
        closed=bool(grid.closed) if grid is not None else False,
    )

"""Support structures from a parallel mesh found by least squares (§2.2.3, Fig. 4).

The parallel mesh is linear in the vertex offsets ``u_i = v'_i − v_i``: edge
``v'_i v'_j`` is parallel to ``v_i v_j`` iff ``(u_j − u_i) × ê_ij = 0`` (two
equations per edge).  We solve ``min Σ |u_i − t_i|²`` (``t_i`` the inward unit
vertex normal) subject to these equations (and ``n·u_i = 0`` for axes kept in a
plane) by an augmented Lagrangian with one sparse factorisation.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix, identity
from scipy.sparse.linalg import splu

from ppfab import planes as pl
from ppfab.errors import GeometryError
from ppfab.mesh import QuadGrid, QuadMesh
from ppfab.metrics import polyline_fit, relative_deviation

from .registry import support_method
from .structure import SupportStructure, _assemble, _edge_frames, _orient_inward, as_quadmesh, vertex_normals

if TYPE_CHECKING:  # pragma: no cover
    from .params import BeamContext, SupportParams


def _perpendicular_pair(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``(k, 3)`` completing unit vectors ``d`` to orthonormal frames."""
    helper = np.eye(3)[np.argmin(np.abs(d), axis=1)]
    p = np.cross(d, helper)
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return p, np.cross(d, p)


def parallel_offsets(mesh: QuadMesh, target: np.ndarray, plane_normals: Sequence[tuple[np.ndarray, np.ndarray]] = (),
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
    planes, dev = polyline_fit(qm)
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
    rel = relative_deviation(dev, mesh)
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


@support_method("parallel", "any planar-quad mesh: a least-squares parallel mesh")
def _build(mesh: QuadMesh, params: "SupportParams", family: int | None,
           beams: "BeamContext | None" = None) -> SupportStructure:
    return support_parallel(mesh, params.planar_tolerance, flip=params.flip,
                            max_normal_angle_deg=params.max_normal_angle_deg)

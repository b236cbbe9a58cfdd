"""Surfaces for the tests of ppfab.surface: real roofs resampled into triangle meshes, NURBS written with rhino3dm.

The real ones start from quad meshes of other people's projects (the shared data, whose README gives the
repository, path and commit of each file):

* ``compas_libigl__inspired_mesh_quads_Conjugate.off`` — compas-dev/compas_libigl,
  data/libigl-tutorial-data/inspired_mesh_quads_Conjugate.off (a roof, 43 × 26 m, units m);
* ``DOS__botanic-garden-bubble-0.obj`` — WWmore/DOS @ f15cff51, objs/obj_equilibrium/botanic-garden-bubble-0.obj
  (a funicular shell, 31 × 28 m, units m).

So that no edge of the surface follows the original net, each is resampled: random plan points (seeded) get
their height from the original quads (each split into two triangles, interpolated linearly in plan with
matplotlib's triangle interpolator), and a Delaunay triangulation of those points (scipy) is the new
triangle mesh, cut to the original's plan outline.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def resample_quad_mesh(path: Path, n_points: int, seed: int, hole: tuple[float, float, float] | None = None,
                       crop: tuple[float, float, float] | None = None):
    """A trimesh triangle mesh on the surface of the quad mesh ``path`` whose edges do not follow its net.

    hole : ``(x, y, r)`` in the file's units — drop the triangles whose centroid lies within ``r`` of it
    crop : ``(x, y, r)`` — keep only the part within ``r`` of it in plan (a panel of a larger roof)
    """
    import matplotlib.tri as mtri
    import trimesh
    from scipy.spatial import Delaunay

    from ppfab.io import read_mesh

    m = read_mesh(path)
    v = np.asarray(m.vertices, dtype=float)
    f = np.asarray(m.faces)
    tri = np.concatenate([f[:, [0, 1, 2]], f[:, [0, 2, 3]]])
    plan = mtri.Triangulation(v[:, 0], v[:, 1], tri)
    height = mtri.LinearTriInterpolator(plan, v[:, 2])
    rng = np.random.default_rng(seed)
    lo, hi = v[:, :2].min(axis=0), v[:, :2].max(axis=0)
    pts = rng.uniform(lo, hi, size=(4 * n_points, 2))
    z = np.ma.filled(height(pts[:, 0], pts[:, 1]), np.nan)
    keep = np.isfinite(z)
    if crop is not None:
        keep &= np.hypot(pts[:, 0] - crop[0], pts[:, 1] - crop[1]) < crop[2]
    pts, z = pts[keep][:n_points], z[keep][:n_points]
    if crop is None:                    # the original's boundary vertices too, so the outline is kept
        bnd = np.flatnonzero(m.topology.boundary_vertices)
        pts = np.concatenate([pts, v[bnd, :2]])
        z = np.concatenate([z, v[bnd, 2]])
    d = Delaunay(pts)
    c = pts[d.simplices].mean(axis=1)
    inside = np.isfinite(np.ma.filled(height(c[:, 0], c[:, 1]), np.nan))
    # also the midpoints of the edges, so no triangle bridges a concave part of the outline
    for a, b in ((0, 1), (1, 2), (2, 0)):
        mid = 0.5 * (pts[d.simplices[:, a]] + pts[d.simplices[:, b]])
        mid = 0.999 * mid + 0.001 * c
        inside &= np.isfinite(np.ma.filled(height(mid[:, 0], mid[:, 1]), np.nan))
    simplices = d.simplices[inside]
    if hole is not None:
        cc = pts[simplices].mean(axis=1)
        simplices = simplices[np.hypot(cc[:, 0] - hole[0], cc[:, 1] - hole[1]) > hole[2]]
    mesh = trimesh.Trimesh(np.column_stack([pts, z]), simplices, process=True)
    mesh.remove_unreferenced_vertices()
    return mesh


def write_nurbs(path: Path, heights, size_x: float, size_y: float, unit: str = "Meters",
                as_brep: bool = False) -> None:
    """Write a bicubic NURBS surface (4 × 4 control points, Bézier) over ``size_x × size_y`` with control
    heights ``heights (4, 4)`` into a ``.3dm`` in ``unit`` (as a one-face Brep when ``as_brep``)."""
    import rhino3dm

    ns = rhino3dm.NurbsSurface.Create(3, False, 4, 4, 4, 4)
    for i in range(4):
        for j in range(4):
            ns.Points[i, j] = rhino3dm.Point4d(size_x * i / 3, size_y * j / 3, float(heights[i][j]), 1.0)
    for k, t in enumerate([0, 0, 0, 1, 1, 1]):
        ns.KnotsU[k] = t
        ns.KnotsV[k] = t
    model = rhino3dm.File3dm()
    model.Settings.ModelUnitSystem = getattr(rhino3dm.UnitSystem, unit)
    if as_brep:
        model.Objects.AddBrep(rhino3dm.Brep.CreateFromSurface(ns))
    else:
        model.Objects.AddSurface(ns)
    model.Write(str(path), 7)


def diagonal_gaps(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """δ_f of every quad (§3.3), ``(F,)``: the distance between the lines of its diagonals over their mean length;
    ``vertices (n, 3)``, ``faces (F, 4)``."""
    c = vertices[np.asarray(faces)]
    d1, d2 = c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]
    n = np.cross(d1, d2)
    gap = np.abs(np.einsum("ij,ij->i", c[:, 1] - c[:, 0], n)) / np.linalg.norm(n, axis=1)
    return gap / (0.5 * (np.linalg.norm(d1, axis=1) + np.linalg.norm(d2, axis=1)))


def line_plane_gap(mesh, families: tuple[int, ...]) -> tuple[float, int]:
    """The largest distance of a vertex of a polyline of ``families`` (3 or more vertices) from that polyline's
    least-squares plane (SVD), over the polyline's largest extent; and how many polylines were measured."""
    v = np.asarray(mesh.vertices, dtype=float)
    worst, count = 0.0, 0
    for line in mesh.polylines:
        if line.family in families and len(line.vertices) >= 3:
            p = v[np.asarray(line.vertices)]
            q = p - p.mean(axis=0)
            worst = max(worst, float(np.abs(q @ np.linalg.svd(q)[2][-1]).max()) / float(np.ptp(p, axis=0).max()))
            count += 1
    return worst, count


def face_pairs(faces: np.ndarray) -> list[tuple[int, int]]:
    """The pairs of faces of ``faces (F, k)`` that share an edge."""
    shared: dict[tuple[int, int], list[int]] = {}
    for fi, f in enumerate(np.asarray(faces).tolist()):
        for i, j in zip(f, f[1:] + f[:1]):
            shared.setdefault((min(i, j), max(i, j)), []).append(fi)
    return [(fs[0], fs[1]) for fs in shared.values() if len(fs) == 2]


def nurbs_distance_and_crease(path: Path, vertices: np.ndarray, faces: np.ndarray, mm_per_unit: float
                              ) -> tuple[float, float]:
    """Measured against the NURBS of the ``.3dm`` at ``path`` by its own evaluation (rhino3dm) and not by
    ppfab: the largest distance (mm) of a vertex of ``vertices (n, 3)`` (mm) to the surface — the nearest of
    61 × 61 samples refined by scipy's Nelder–Mead — and the largest crease excess (degrees): over every two
    faces of ``faces (F, 4)`` sharing an edge, the angle between their least-squares planes minus the angle
    between the surface's normals at the points nearest their centres."""
    import rhino3dm
    from scipy.optimize import minimize

    geometry = rhino3dm.File3dm.Read(str(path)).Objects[0].Geometry
    surface = geometry.Faces[0].UnderlyingSurface() if hasattr(geometry, "Faces") else geometry
    (u0, u1), (w0, w1) = [(surface.Domain(k).T0, surface.Domain(k).T1) for k in (0, 1)]
    lo, hi = np.array([u0, w0]), np.array([u1, w1])

    def at(st: np.ndarray) -> np.ndarray:
        q = surface.PointAt(*map(float, np.clip(st, lo, hi)))
        return mm_per_unit * np.array([q.X, q.Y, q.Z])

    grid = np.array([(s, t) for s in np.linspace(u0, u1, 61) for t in np.linspace(w0, w1, 61)])
    samples = np.array([at(g) for g in grid])

    def nearest(p: np.ndarray):
        start = grid[int(np.argmin(np.linalg.norm(samples - p, axis=1)))]
        return minimize(lambda st: float(np.linalg.norm(at(st) - p)), start, method="Nelder-Mead",
                        options={"xatol": 1e-9 * (u1 - u0), "fatol": 1e-6, "maxiter": 2000})

    far = max(float(nearest(p).fun) for p in vertices)

    def unit(n) -> np.ndarray:
        n = np.array([n.X, n.Y, n.Z])
        return n / np.linalg.norm(n)

    surface_n = [unit(surface.NormalAt(*map(float, np.clip(nearest(c).x, lo, hi))))
                 for c in vertices[faces].mean(axis=1)]
    panel_n = [np.linalg.svd(vertices[f] - vertices[f].mean(axis=0))[2][2] for f in faces]
    pairs = face_pairs(faces)
    assert pairs, "no two faces share an edge"
    return far, max(turn_deg(panel_n[a], panel_n[b]) - turn_deg(surface_n[a], surface_n[b]) for a, b in pairs)


def turn_deg(m: np.ndarray, n: np.ndarray) -> float:
    """The angle (degrees, 0–90) between two unit normals, whichever way each points."""
    return float(np.degrees(np.arccos(min(1.0, abs(float(m @ n))))))

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

"""glazing.step against mesh.obj: every pane edge bites at least ``panels.min_bite`` on its gasket.

Recomputed from the written files only: each pane is its mesh face (``mesh.obj``) in its least-squares plane,
inset by half the gap with mitred corners (shapely), moved by the glazing offset (strip + gasket thickness,
``manifest.json`` ``fabrication.glazing``) to the side its gaskets are on; each pane edge is matched to the face
edge it was inset from, the gasket under it found by position (the strip whose centre is nearest the edge's
midpoint; ``edge_nodes`` of ``parts.csv`` pair each strip with its gasket), and its top face (the four vertices of the ``GK-…`` solid farthest from the strip) projected into the pane's
plane.  At nine stations along the stretch of the edge the gasket spans (1 mm in from its ends) the bite is
the length of the pane's inward ray over the gasket; the smallest must reach ``min_bite``, and each pane's
smallest must agree with ``bites.csv`` within 0.01 mm.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..contract import gasket_id
from . import Verification, check, read_csv
from ._shapes import solid_points
from ._step_read import read_or_report


def _cross2(a: np.ndarray, b: np.ndarray) -> float:
    """The z component of ``a × b`` for two vectors of the plane (2,)."""
    return float(a[0] * b[1] - a[1] * b[0])


def _pane_plane(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    c = corners.mean(axis=0)
    vt = np.linalg.svd(corners - c)[2]
    return c, vt[:2], vt[2]


def edge_bites(corners: np.ndarray, gap: float, offset: float, gaskets: dict[tuple[int, int], np.ndarray],
               face: np.ndarray, stations: int = 9, tree: cKDTree | None = None) -> dict[tuple[int, int], float]:
    """Mesh edge ``(a, b)`` (sorted vertex ids) → the smallest bite (mm) of the pane edge over it.

    ``corners (4, 3)`` of the face ``face (4,)`` (vertex ids); ``gaskets``: mesh edge → ``(8, 3)`` vertices of
    its gasket solid ``and`` its strip's centre (row 8); ``tree``: a k-d tree of those centres in the order of
    ``gaskets`` (built here when not given: pass one when calling per face)."""
    from shapely.geometry import LineString, Point, Polygon

    values = list(gaskets.values())
    if tree is None and values:
        tree = cKDTree(np.array([g[8] for g in values]))
    c, uv, n = _pane_plane(corners)
    flat = (corners - c) @ uv.T
    pane = Polygon(flat)
    if not pane.exterior.is_ccw:
        pane = Polygon(flat[::-1])
    inner = pane.buffer(-0.5 * gap, join_style="mitre")
    ring = np.asarray(inner.exterior.coords)[:-1]
    out: dict[tuple[int, int], float] = {}
    for k in range(len(ring)):
        p, q = ring[k], ring[(k + 1) % len(ring)]
        mid = 0.5 * (p + q)
        dist = []
        for j in range(4):                                   # the face edge this pane edge was inset from
            a, b = flat[j], flat[(j + 1) % 4]
            t = (b - a) / np.linalg.norm(b - a)
            dist.append(abs(_cross2(t, mid - a)) + abs(_cross2(t, (q - p) / np.linalg.norm(q - p))))
        j = int(np.argmin(dist))
        key = tuple(sorted((int(face[j]), int(face[(j + 1) % 4]))))
        mid3 = c + mid @ uv
        if tree is None:
            out[key] = 0.0           # type: ignore[index]
            continue
        g = values[int(tree.query(mid3)[1])]                   # by position: the nearest strip centre
        pts, centre = g[:8], g[8]
        side = np.sign((pts.mean(axis=0) - c) @ n) or 1.0
        normal = side * n
        up = np.linalg.svd(pts - pts.mean(axis=0))[2][2]           # the gasket's thickness direction
        up = up if (pts.mean(axis=0) - centre) @ up > 0 else -up   # away from its strip
        top = pts[np.argsort(-((pts - centre) @ up))[:4]]          # the gasket face the glass rests on
        origin = c + offset * normal
        gq = (top - origin) @ uv.T
        gpoly = Polygon(gq).convex_hull
        d = (q - p) / np.linalg.norm(q - p)
        inward = np.array([-d[1], d[0]])
        if not inner.contains(Point(*(0.5 * (p + q) + 1e-3 * inward))):
            inward = -inward
        s = (gq - p) @ d
        lo, hi = max(0.0, float(s.min()) + 1.0), min(float(np.linalg.norm(q - p)), float(s.max()) - 1.0)
        if hi <= lo:
            out[key] = 0.0           # type: ignore[index]
            continue
        bites = []
        for sv in np.linspace(lo, hi, stations):
            start = p + sv * d
            ray = LineString([start, start + 1000.0 * inward])
            bites.append(ray.intersection(gpoly).length)
        out[key] = float(min(bites))  # type: ignore[index]
    return out


@check("bite", 64)
def check_bite(v: Verification) -> None:
    m = v.data.get("manifest", {})
    files = m.get("files", {})
    rel = files.get("glazing_step")
    mesh = v.data.get("mesh")
    if rel is None or mesh is None:
        return
    fab = m.get("fabrication", {})
    gl = fab.get("glazing", {})
    offset = float(gl.get("thickness", 0.0)) + float(gl.get("gasket_thickness", 0.0))
    min_bite = float(fab.get("panels", {}).get("min_bite", 0.0))
    gap = float(fab.get("panel_gap", 0.0))
    read = read_or_report(v, rel)
    if read is None:
        return
    solids = {s.name: s.solid for s in read}
    gaskets: dict[tuple[int, int], np.ndarray] = {}
    for row in v.data.get("parts", []):
        if row["kind"] != "strip":
            continue
        pid = row["part_id"]
        strip, gasket = solids.get(pid), solids.get(gasket_id(pid))
        if strip is None or gasket is None:
            v.error(rel, pid, "strip or its gasket has no solid")
            continue
        a, b = (int(x) for x in row["edge_nodes"].split(";"))
        gaskets[(min(a, b), max(a, b))] = np.vstack([solid_points(gasket), solid_points(strip).mean(axis=0)])
    written: dict[str, float] = {}
    if files.get("bites_csv"):
        for r in read_csv(v.folder / files["bites_csv"]):
            written[r["panel"]] = min(written.get(r["panel"], np.inf), float(r["bite_mm"]))
    low = []
    tree = cKDTree(np.array([g[8] for g in gaskets.values()])) if gaskets else None
    for row in v.data.get("parts", []):
        if row["kind"] != "panel" or row.get("face", "") == "":
            continue
        face = np.asarray(mesh.faces[int(row["face"])])
        bites = edge_bites(mesh.vertices[face], gap, offset, gaskets, face, tree=tree)
        for key, bite in bites.items():
            if bite < min_bite - 1e-6:
                low.append((bite, row["part_id"], key))
        w = written.get(row["part_id"])
        if w is not None and bites and abs(w - min(bites.values())) > 0.01:
            v.error(rel, row["part_id"], f"smallest bite is {min(bites.values()):.3f} mm from the files, "
                                         f"bites.csv says {w:.3f} mm")
    for bite, pid, key in sorted(low)[:20]:
        v.error(rel, pid, f"the pane edge over mesh edge {key[0]}-{key[1]} bites {bite:.2f} mm on its gasket, "
                          f"less than panels.min_bite = {min_bite:g} mm")
    v.checked.append("bite")

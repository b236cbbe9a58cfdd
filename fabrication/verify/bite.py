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

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..contract import gasket_id
from . import Verification, check
from ._cells import CellReader
from ._shapes import solid_points
from ._step_read import read_or_report


def _cross2(a: np.ndarray, b: np.ndarray) -> float:
    """The z component of ``a × b`` for two vectors of the plane (2,)."""
    return float(a[0] * b[1] - a[1] * b[0])


def _pane_plane(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    c = corners.mean(axis=0)
    vt = np.linalg.svd(corners - c)[2]
    return c, vt[:2], vt[2]


@dataclass(frozen=True)
class EdgeMeasure:
    """A pane edge measured on the gasket under it: the smallest bite over the stations, the length of the
    stretch the gasket spans (less 1 mm at both ends), the pane edge's length and the tilt between the pane
    and the gasket's top face (degrees); ``bites.csv`` holds the same as ``bite_mm, supported_mm, edge_mm,
    tilt_deg``."""

    bite: float
    supported: float
    length: float
    tilt_deg: float


def edge_bites(corners: np.ndarray, gap: float, offset: float, gaskets: dict[tuple[int, int], np.ndarray],
               face: np.ndarray, stations: int = 9, tree: cKDTree | None = None) -> dict[tuple[int, int], float]:
    """Mesh edge ``(a, b)`` (sorted vertex ids) → the smallest bite (mm) of the pane edge over it
    (:func:`edge_measures`)."""
    return {k: m.bite for k, m in edge_measures(corners, gap, offset, gaskets, face, stations, tree).items()}


def edge_measures(corners: np.ndarray, gap: float, offset: float, gaskets: dict[tuple[int, int], np.ndarray],
                  face: np.ndarray, stations: int = 9,
                  tree: cKDTree | None = None) -> dict[tuple[int, int], EdgeMeasure]:
    """Mesh edge ``(a, b)`` (sorted vertex ids) → the :class:`EdgeMeasure` of the pane edge over it.

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
    out: dict[tuple[int, int], EdgeMeasure] = {}
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
        length = float(np.linalg.norm(q - p))
        if tree is None:
            out[key] = EdgeMeasure(0.0, 0.0, length, 90.0)           # type: ignore[index]
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
            out[key] = EdgeMeasure(0.0, 0.0, length, 90.0)           # type: ignore[index]
            continue
        bites = []
        for sv in np.linspace(lo, hi, stations):
            start = p + sv * d
            ray = LineString([start, start + 1000.0 * inward])
            bites.append(ray.intersection(gpoly).length)
        tilt = float(np.degrees(np.arccos(min(1.0, abs(float(n @ up))))))
        out[key] = EdgeMeasure(float(min(bites)), hi - lo, length, tilt)  # type: ignore[index]
    return out


BITE_TOLERANCE_MM = 0.01
"""How far a value of ``bites.csv`` (written to 0.001 mm) may be from the one measured on the files."""
TILT_TOLERANCE_DEG = 0.01


def _strip_length(points: np.ndarray) -> float:
    """The length of a strip solid (a box): its extent along its longest principal direction."""
    c = points - points.mean(axis=0)
    return float(np.ptp(c @ np.linalg.svd(c)[2][0]))


def _check_rows(v: Verification, rel: str, measured: dict[str, dict[tuple[int, int], EdgeMeasure]],
                strip_edge: dict[str, tuple[int, int]]) -> None:
    """Every row of ``bites.csv`` against the measure of its pane edge (found by its strip's mesh edge), and a
    row for every pane edge measured."""
    cells = CellReader(v, rel)
    rows = v.read_table(rel)
    if rows is None:
        return
    seen: set[tuple[str, tuple[int, int]]] = set()
    for n, r in enumerate(rows, start=1):
        panel, strip = cells.text(n, r, "panel"), cells.text(n, r, "strip")
        if panel is None or strip is None:
            continue
        if panel not in measured:
            v.error(rel, f"row {n} column panel", f"{panel!r} is not a panel of parts.csv")
            continue
        key = strip_edge.get(strip)
        if key is None or key not in measured[panel]:
            v.error(rel, f"row {n} column strip", f"{strip!r} is not a strip under an edge of {panel}")
            continue
        if (panel, key) in seen:
            v.error(rel, f"row {n}", f"a second row for the edge of {panel} over mesh edge {key[0]}-{key[1]}")
        seen.add((panel, key))
        m = measured[panel][key]
        for column, want, tol in (("bite_mm", m.bite, BITE_TOLERANCE_MM),
                                  ("supported_mm", m.supported, BITE_TOLERANCE_MM),
                                  ("edge_mm", m.length, BITE_TOLERANCE_MM),
                                  ("tilt_deg", m.tilt_deg, TILT_TOLERANCE_DEG)):
            got = cells.number(n, r, column)
            if got is not None and abs(got - want) > tol:
                v.error(rel, f"row {n} column {column}", f"{panel} over mesh edge {key[0]}-{key[1]} ({strip}): "
                                                         f"{got:g} written, {want:.3f} measured on the files")
    for panel, edges in measured.items():
        for key in sorted(edges):
            if (panel, key) not in seen:
                v.error(rel, panel, f"no row for the pane edge over mesh edge {key[0]}-{key[1]} "
                                    f"(it bites {edges[key].bite:.3f} mm)")


@check("bite")
def check_bite(v: Verification) -> None:
    m = v.manifest
    files = m.get("files", {})
    rel = files.get("glazing_step")
    mesh = v.mesh
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
    strip_edge: dict[str, tuple[int, int]] = {}
    prel = files.get("parts_csv", "parts.csv")
    for row in (v.parts or []):
        if row["kind"] != "strip":
            continue
        pid = row["part_id"]
        strip, gasket = solids.get(pid), solids.get(gasket_id(pid))
        if strip is None or gasket is None:
            v.error(rel, pid, "strip or its gasket has no solid")
            continue
        if not row.get("edge_nodes"):
            continue                                     # the parts check named the cell
        a, b = (int(x) for x in row["edge_nodes"].split(";"))
        strip_pts = solid_points(strip)
        gaskets[(min(a, b), max(a, b))] = np.vstack([solid_points(gasket), strip_pts.mean(axis=0)])
        strip_edge[pid] = (min(a, b), max(a, b))
        length = _strip_length(strip_pts)
        if row.get("length_mm") and abs(float(row["length_mm"]) - length) > BITE_TOLERANCE_MM:
            v.error(prel, pid, f"length_mm {float(row['length_mm']):.3f} differs from the strip's solid in {rel} "
                               f"({length:.3f} mm)")
    low = []
    tree = cKDTree(np.array([g[8] for g in gaskets.values()])) if gaskets else None
    measured: dict[str, dict[tuple[int, int], EdgeMeasure]] = {}
    for row in (v.parts or []):
        if row["kind"] != "panel" or row.get("face", "") == "":
            continue
        face = np.asarray(mesh.faces[int(row["face"])])
        edges = edge_measures(mesh.vertices[face], gap, offset, gaskets, face, tree=tree)
        measured[row["part_id"]] = edges
        for key, e in edges.items():
            if e.bite < min_bite - 1e-6:
                low.append((e.bite, row["part_id"], key))
        written = row.get("bite_min_mm", "")
        if written != "" and edges and abs(float(written) - min(e.bite for e in edges.values())) > BITE_TOLERANCE_MM:
            v.error(prel, row["part_id"], f"bite_min_mm {float(written):.3f} differs from the smallest bite measured "
                                          f"on the files, {min(e.bite for e in edges.values()):.3f} mm")
    if files.get("bites_csv"):
        _check_rows(v, files["bites_csv"], measured, strip_edge)
    for bite, pid, key in sorted(low)[:20]:
        v.error(rel, pid, f"the pane edge over mesh edge {key[0]}-{key[1]} bites {bite:.2f} mm on its gasket, "
                          f"less than panels.min_bite = {min_bite:g} mm")
    v.checked.append("bite")

"""Checks shared by the exchange-model checks (IFC, Rhino, glTF): names, data and placement of part solids.

A solid read back from a file is compared with the part's ``parts.csv`` row and the mesh (``mesh.obj``):

* a panel lies parallel to its mesh face on its gaskets: every vertex at a distance ``δ ∈ [z − ε, z + t + ε]``
  from the plane fitted to the face's corners (oriented to the side the solid is on), reaching both, ``t`` the
  glass thickness, ``ε`` the planarity tolerance plus the file's precision and the seat ``z`` within
  :func:`seat_range`; its volume is the row's ``area_mm2 × thickness_mm``;
* a beam plate lies on its support plane (the row's ``plane``): every vertex at ``|δ| ≤ t/2 + ε``, reaching
  ``±t/2`` on both sides; the mesh vertices of its nodes (the row's ``nodes``) on that plane within the beam
  plane tolerance; its volume is ``area_mm2 × thickness_mm``;
* and in its plane, its base polygon has the corners of the face inset by half the gap (a panel) or of its DXF
  cutting outline mapped back through its placement and frame (a plate): :func:`check_outline_place`;
* a retention box (setting block, stop, pressure gasket, plate, cover cap) has the corners its row's frame and
  size give (:func:`check_box_place`), the screws of a plate a round prism at each station (:func:`check_screw_points`).
"""

from __future__ import annotations

import numpy as np

from . import Verification, shared_by_confined
from ._tolerance import type_tolerance
from ._shapes import cross_rows, literal


def parse_list(text: str) -> list:
    """A list written into ``parts.csv`` (``[0.99, -0.12, 0.0, 15709.2]``), or ``[]``."""
    value = literal(text)
    return list(value) if isinstance(value, (list, tuple)) else []


def polygon_area_3d(points: np.ndarray) -> float:
    """Area of a planar polygon ``(k, 3)`` (half the norm of the sum of ``p_i × p_{i+1}``)."""
    p = np.asarray(points, dtype=float)
    p = p - p.mean(axis=0)
    return 0.5 * float(np.linalg.norm(cross_rows(p, np.roll(p, -1, axis=0)).sum(axis=0)))


@shared_by_confined
def seat_range(v: Verification) -> tuple[float, float]:
    """Where a pane's underside may lie above its face's plane, mm: the glazing offset (``manifest.json``
    ``glazing.offset_mm``, strip + gasket; 0 without strips) ± half the strip width × the tangent of the larger
    of ``glazing.max_tilt_deg`` and the largest ``tilt_deg`` of ``bites.csv`` (a gasket tilted by that angle
    raises or lowers the pane by at most that much over its width), ± ``panels.planarity_tolerance`` for the
    faces' corners off their least-squares plane.  Worked out once per verification (:attr:`FolderData.seat`)."""
    if v.read.seat is None:
        v.read.seat = _seat_range(v)
    return v.read.seat


def _seat_range(v: Verification) -> tuple[float, float]:
    from ._shapes import number

    m = v.manifest
    nominal = float(m.get("glazing", {}).get("offset_mm", 0.0) or 0.0)
    if not nominal:
        return 0.0, 0.0
    gl = m.get("fabrication", {}).get("glazing", {})
    tilt = float(gl.get("max_tilt_deg", 0.0))
    rel = m.get("files", {}).get("bites_csv")
    if rel and (v.folder / rel).is_file():
        tilt = max([tilt] + [number(r.get("tilt_deg"), 0.0) for r in v.table(rel)])
    flat = float(m.get("fabrication", {}).get("planarity_tolerance", 0.1) or 0.1)     # a face's corners off its plane
    from ..glazing.seat import seat_range as bound               # the build refuses panes above the same bound

    return bound(nominal, float(gl.get("width", 0.0)), tilt, flat)


def reference_outline(v: Verification, row: dict[str, str]) -> np.ndarray | None:
    """Where a part's outline must be in 3D, ``(k, 3)`` mm, from files other than the one checked: a panel's mesh
    face inset by half the gap in the face's plane; a beam plate's cutting outline on its DXF sheet mapped back
    through its ``parts.csv`` placement (``p = M R(−rotation)(s − (x, y))``) and frame (``origin + p_x x_dir +
    p_y y_dir``)."""
    from .congruence import inset_face_2d

    mesh = v.mesh
    fab = v.manifest.get("fabrication", {})
    if row["kind"] == "panel" and mesh is not None and row.get("face", "") != "":
        corners = mesh.vertices[mesh.faces[int(row["face"])]]
        c = corners.mean(axis=0)
        vt = np.linalg.svd(corners - c)[2]
        return c + inset_face_2d(corners, 0.5 * float(fab.get("panel_gap", 0.0))) @ vt[:2]
    sheet = v.dxf_outlines.get(row["part_id"])
    frame = literal(row.get("frame", ""))
    if row["kind"] != "beam" or sheet is None or not isinstance(frame, dict):
        return None
    a = np.radians(float(row["rotation_deg"]))
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    q = (np.asarray(sheet, dtype=float) - [float(row["x"]), float(row["y"])]) @ rot    # R(−a) applied to rows
    if row.get("mirrored") == "1":
        q[:, 0] = -q[:, 0]
    o, ex, ey = (np.asarray(frame[k], dtype=float) for k in ("origin", "x_dir", "y_dir"))
    return o + q[:, :1] * ex + q[:, 1:2] * ey


def check_outline_place(v: Verification, rel: str, row: dict[str, str], ring: np.ndarray, eps: float,
                        crossings: bool = False) -> None:
    """The solid's base polygon ``ring (k, 3)`` has the corners of :func:`reference_outline`, seen along the
    part's normal (each reference corner within ``eps`` of a corner of the ring).

    ``crossings``: the ring's corners are where two edge lines known to ``eps`` cross (the union of a bevelled
    plate's two faces, :func:`two_face_outline`), so a corner where the outline turns by an angle θ is known only
    to ``eps / sin θ`` along the outline: a reference corner then has to lie within ``eps`` of both edge lines of
    its ring corner (on a default of 44 × 30 faces a plate's faces crossed at 0.91° in float32 ``model.glb``:
    0.122 mm along the outline, 0.0007 mm across it)."""
    ref = reference_outline(v, row)
    if ref is None:
        return
    ring = np.asarray(ring, dtype=float)
    c = ref.mean(axis=0)
    n = np.linalg.svd(ref - c)[2][2]
    flat = ring - np.outer((ring - c) @ n, n)
    gap = np.inf
    if len(flat):
        dist = np.linalg.norm(ref[:, None, :] - flat[None, :, :], axis=2)
        if crossings and len(flat) >= 3:
            i = dist.argmin(axis=1)                                     # the ring corner of each reference corner
            e = ref - flat[i]
            normals = []
            for a, b in ((np.roll(flat, 1, axis=0)[i], flat[i]), (flat[i], np.roll(flat, -1, axis=0)[i])):
                u = np.cross(n, b - a)                                  # across each edge line, in the plane
                normals.append(u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300))
            gap = float(np.maximum(np.abs(np.einsum("ij,ij->i", e, normals[0])),
                                   np.abs(np.einsum("ij,ij->i", e, normals[1]))).max())
        else:
            gap = float(dist.min(axis=1).max())
    if len(ring) != len(ref) or gap > eps:
        v.error(rel, row["part_id"], f"outline is {gap:.3g} mm from where "
                                     f"{'its mesh face' if row['kind'] == 'panel' else 'its DXF outline'} puts it "
                                     f"({len(ring)} corners, expected {len(ref)})")


def _drop_straight(q: np.ndarray, tol: float) -> np.ndarray:
    """The polygon ``q (k, 2)`` without its corners within ``tol`` of the line through their neighbours, the
    straightest first, one at a time (shapely's topology-preserving simplification keeps a ring's first points)."""
    q = np.asarray(q, dtype=float)
    while len(q) > 3:
        prev, nxt = np.roll(q, 1, axis=0), np.roll(q, -1, axis=0)
        chord = nxt - prev
        off = np.abs(chord[:, 0] * (q[:, 1] - prev[:, 1]) - chord[:, 1] * (q[:, 0] - prev[:, 0]))
        off = off / np.maximum(np.linalg.norm(chord, axis=1), 1e-300)
        k = int(np.argmin(off))
        if off[k] >= tol:
            break
        q = np.delete(q, k, axis=0)
    return q


def two_face_outline(row: dict[str, str], bottom: np.ndarray, top: np.ndarray,
                     eps: float = 0.0) -> tuple[np.ndarray, float] | None:
    """For a beam plate modelled between two different faces (bevelled under its strips), the faces' rings
    ``bottom, top (k, 3)`` mm, world: the outline cut from the sheet (their union seen along the plate's
    ``parts.csv`` frame normal, ``(r, 3)`` on its mid-plane) and the mean of the two faces' areas (mm²), by which
    its volume goes (:mod:`fabrication.verify.step`); ``None`` without a frame or an overlap of the faces.
    Where the faces cross on nearly one line the union has corners that are none; with ``eps`` (the precision
    of the points read, mm) a corner within ``4 eps`` of the line through its neighbours is dropped."""
    from ppfab.metrics import polygon_area

    from ._shapes import faces_union, frame_of, to_frame

    frame = frame_of(row)
    if frame is None:
        return None
    b2, t2 = to_frame(bottom, frame)[:, :2], to_frame(top, frame)[:, :2]
    cut = faces_union(b2, t2, grid=eps if eps > 0 else None)
    if cut is None:
        return None
    if eps > 0:
        cut = _drop_straight(cut, 4.0 * eps)
    ring = frame["origin"] + cut[:, :1] * frame["x_dir"] + cut[:, 1:] * frame["y_dir"]
    return ring, 0.5 * (abs(float(polygon_area(b2))) + abs(float(polygon_area(t2))))


def _faces_differ(row: dict[str, str], bottom: np.ndarray, top: np.ndarray, eps: float) -> bool:
    """Whether two rings of one plate differ seen along its frame normal by more than ``eps`` mm (a prism's are
    one outline; a ring count that differs is a difference too)."""
    from ._shapes import frame_of, to_frame

    b, t = np.asarray(bottom, dtype=float), np.asarray(top, dtype=float)
    frame = frame_of(row)
    if frame is None or b.shape != t.shape:
        return frame is not None
    return float(np.abs(to_frame(b, frame)[:, :2] - to_frame(t, frame)[:, :2]).max(initial=0.0)) > eps


def check_part_solid(v: Verification, rel: str, row: dict[str, str], points: np.ndarray, volume: float,
                     eps: float = 1e-6, volume_tol: float = 1e-6, ring: np.ndarray | None = None,
                     holes: bool = False, top_ring: np.ndarray | None = None,
                     outline_eps: float | None = None) -> None:
    """The placement and volume of one part's solid (vertices ``points (n, 3)`` mm, ``volume`` mm³; with
    ``ring``, its base polygon, also where it lies in its plane; with ``holes``, the solid has the bolt holes
    ``parts.csv`` lists (``holes`` × ``hole_mm``), so its volume is the area less theirs times the thickness).

    ``top_ring`` (a beam plate whose top face is not its base, bevelled under its strips): the union of the two
    rings is the outline placed, and the volume is ``t`` times their mean area less the holes, within 1e-4.
    ``outline_eps`` (a pane drawn as its type's outline): how far the base polygon may lie from its own face's.
    Placed: a pane on its face, a retention box on its ``parts.csv`` frame, a strip in the box its span puts it
    in (:func:`.glazing_step.check_strip_place`), a beam plate about its support plane.
    """
    pid = row["part_id"]
    mean_area = None
    if ring is not None and top_ring is not None and row["kind"] == "beam" and _faces_differ(row, ring, top_ring,
                                                                                            max(eps, 1e-4)):
        two = two_face_outline(row, np.asarray(ring, dtype=float), np.asarray(top_ring, dtype=float), eps)
        if two is None:
            v.error(rel, pid, "its two faces do not overlap into one outline in its parts.csv frame")
            return
        ring, mean_area = two
    # the two faces' union has corners where their edges cross, met by edges read to eps and snapped to the grid
    # of eps: a few eps off (a bevelled plate of the Enneper roof in model.3dm, 1.13e-3 mm at eps 0.9e-3)
    place_eps = 4.0 * eps if mean_area is not None else eps
    if ring is not None:
        check_outline_place(v, rel, row, ring, max(place_eps, 1e-4) if outline_eps is None else outline_eps,
                            crossings=mean_area is not None)
    fab = v.manifest.get("fabrication", {})
    t = float(row.get("thickness_mm") or 0.0)
    area = float(row.get("area_mm2") or 0.0) if mean_area is None else mean_area
    if holes and row["kind"] in ("beam", "splice"):
        area -= np.pi / 4.0 * float(row.get("holes") or 0) * float(row.get("hole_mm") or 0.0) ** 2
    pts = np.asarray(points, dtype=float)
    allowed = volume_tol * area * t if mean_area is None else max(volume_tol, 1e-4) * area * t
    if row["kind"] == "panel":
        # a pane is modelled on its own face while its area_mm2 is that of its type's outline, which is cut:
        # congruent within congruence_tolerance, so the two areas differ by at most perimeter × tolerance
        tol = type_tolerance(fab)
        allowed = max(allowed, float(row.get("perimeter_mm") or 0.0) * tol * t)
    if t > 0 and area > 0 and abs(volume - area * t) > allowed:
        v.error(rel, pid, f"volume {volume:.6g} mm³ ≠ area × thickness {area * t:.6g} mm³")
    mesh = v.mesh
    if row["kind"] == "panel" and mesh is not None and row.get("face", "") != "":
        corners = mesh.vertices[mesh.faces[int(row["face"])]]
        c = corners.mean(axis=0)
        n = np.linalg.svd(corners - c)[2][2]
        d = (pts - c) @ n
        if abs(d.max()) < abs(d.min()):
            d = -d
        tol = float(fab.get("planarity_tolerance", 0.0)) + eps
        lo, hi = seat_range(v)
        if abs(d.max() - d.min() - t) > tol or not lo - tol <= d.min() <= hi + tol:
            v.error(rel, pid, f"solid spans {d.min():.4g} … {d.max():.4g} mm from face {row['face']}'s plane, "
                              f"expected z … z + {t:g} mm with its seat z in {lo:.4g} … {hi:.4g} mm")
    elif row["kind"] in BOX_KINDS:
        check_box_place(v, rel, row, pts, max(eps, 1e-3))
    elif row["kind"] == "strip":
        from .glazing_step import check_strip_place

        check_strip_place(v, rel, row, pts, eps)
    elif row["kind"] == "beam":
        plane = parse_list(row.get("plane", ""))
        if len(plane) != 4:
            return
        pn = np.asarray(plane, dtype=float)
        scale = float(np.linalg.norm(pn[:3]))
        d = (pts @ pn[:3] + pn[3]) / scale
        if abs(np.abs(d).max() - 0.5 * t) > eps or d.max() < 0.5 * t - eps or d.min() > -0.5 * t + eps:
            v.error(rel, pid, f"solid spans {d.min():.4g} … {d.max():.4g} mm about its support plane, "
                              f"expected ±{0.5 * t:g} mm")
        nodes = parse_list(row.get("nodes", ""))
        if mesh is not None and nodes:
            tol = float(fab.get("beam_plane_tolerance", 0.0)) + 1e-6
            dn = (mesh.vertices[np.asarray(nodes, dtype=int)] @ pn[:3] + pn[3]) / scale
            if np.abs(dn).max() > tol:
                v.error(rel, pid, f"its support plane passes {np.abs(dn).max():.3g} mm from a mesh vertex of its "
                                  f"nodes (tolerance {tol:g} mm)")


def check_names(v: Verification, rel: str, found: list[str], kind_of: dict[str, str], what: str) -> None:
    """Every part in ``parts.csv`` once among ``found`` (the names read from the file), nothing else."""
    seen: set[str] = set()
    for name in found:
        if name in seen:
            v.error(rel, name, f"more than one {what} carries this name")
        seen.add(name)
        if name not in kind_of:
            v.error(rel, name or "(unnamed)", f"{what} is not a part in parts.csv")
    for name in sorted(set(kind_of) - seen):
        v.error(rel, name, f"part has no {what}")


def same_value(text: str, value: object) -> bool:
    """A ``parts.csv`` cell and a value read from another file agree (numbers to 1e-9 relative)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            a = float(text)
        except ValueError:
            return False
        return abs(a - float(value)) <= 1e-9 * max(1.0, abs(a))
    return str(value) == text


BOX_KINDS = ("setting_block", "stop", "pressure_gasket", "pressure_plate", "cover_cap")
"""The retention kinds drawn as a box on their ``parts.csv`` frame."""


def _row_frame(row: dict[str, str]) -> tuple[np.ndarray, ...] | None:
    frame = literal(row.get("frame", ""))
    if not isinstance(frame, dict):
        return None
    try:
        return tuple(np.asarray(frame[k], dtype=float) for k in ("origin", "x_dir", "y_dir", "normal"))
    except (KeyError, TypeError, ValueError):
        return None


def box_corners(row: dict[str, str]) -> np.ndarray | None:
    """``(8, 3)``: the corners of a retention box from its ``parts.csv`` row — ``origin + a·L·x_dir + b·W·y_dir +
    c·H·normal`` for ``a, b, c ∈ {0, 1}`` — or ``None`` when a cell is missing."""
    f = _row_frame(row)
    try:
        size = [float(row[k]) for k in ("length_mm", "width_mm", "height_mm")]
    except (KeyError, TypeError, ValueError):
        return None
    if f is None:
        return None
    o, x, y, n = f
    return np.array([o + a * size[0] * x + b * size[1] * y + c * size[2] * n
                     for c in (0, 1) for b in (0, 1) for a in (0, 1)])


def check_box_place(v: Verification, rel: str, row: dict[str, str], points: np.ndarray, eps: float = 1e-3) -> None:
    """A retention box's solid (vertices ``points``) has the eight corners of :func:`box_corners`: each corner
    within ``eps`` of a vertex and each vertex within ``eps`` of a corner."""
    ref = box_corners(row)
    if ref is None:
        v.error(rel, row["part_id"], "parts.csv row has no frame and size to place it by")
        return
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    d = np.linalg.norm(ref[:, None, :] - pts[None, :, :], axis=2) if len(pts) else np.full((8, 1), np.inf)
    gap = max(float(d.min(axis=1).max()), float(d.min(axis=0).max()))
    if gap > eps:
        v.error(rel, row["part_id"], f"solid is {gap:.3g} mm from the box its parts.csv row places")


def check_screw_points(v: Verification, rel: str, row: dict[str, str], points: np.ndarray,
                       eps: float = 1e-3) -> None:
    """The screws of a plate (vertices ``points`` of all of them): one round prism at each of the row's
    ``screw_stations_mm`` along its frame's ``x_dir``, ``diameter_mm`` across (corners on the circle) and
    ``length_mm`` along ``normal`` from the origin's height; as many as ``quantity``."""
    pid = row["part_id"]
    f = _row_frame(row)
    try:
        xs = [float(x) for x in str(row.get("screw_stations_mm", "")).split(";") if x]
        r, length, qty = 0.5 * float(row["diameter_mm"]), float(row["length_mm"]), int(float(row["quantity"]))
    except (KeyError, TypeError, ValueError):
        f = None
    if f is None:
        v.error(rel, pid, "parts.csv row has no frame, stations, diameter, length and quantity to place it by")
        return
    if len(xs) != qty:
        v.error("parts.csv", pid, f"lists {len(xs)} screw stations for a quantity of {qty}")
    o, ex, ey, n = f
    d = np.asarray(points, dtype=float).reshape(-1, 3) - o
    u, w, h = d @ ex, d @ ey, d @ n
    near = np.abs(u[:, None] - np.asarray(xs)[None, :]).argmin(axis=1) if xs else np.zeros(len(d), dtype=int)
    found = 0
    for k, x in enumerate(xs):
        mine = near == k
        if not mine.any():
            continue
        found += 1
        radial = np.hypot(u[mine] - x, w[mine])
        if np.abs(radial - r).max() > eps + 1e-3 * r or abs(float(h[mine].min())) > eps \
                or abs(float(h[mine].max()) - length) > eps:
            v.error(rel, pid, f"screw {k + 1} is not the {2 * r:g} mm × {length:g} mm round prism at {x:g} mm "
                              f"along its strip that parts.csv places")
    if found != len(xs):
        v.error(rel, pid, f"{found} screws drawn, parts.csv places {len(xs)}")

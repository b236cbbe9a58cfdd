"""Shared readers of the verify checks: rows of the CSV tables, plate frames, solid outlines, point matching.

Not a check (the leading underscore keeps it out of the registry).
"""

from __future__ import annotations

import ast
import json
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.spatial import cKDTree


def cross3(a: np.ndarray | Sequence[float], b: np.ndarray | Sequence[float]) -> np.ndarray:
    """``a × b`` of two 3-vectors, written out (``np.cross`` costs 10–40 µs a call in its set-up alone; the text
    reader's volumes and the erection sweep call it hundreds of thousands of times)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(k, 3)`` the row-wise cross products of two ``(k, 3)`` arrays, written out (what :func:`cross3` is to one
    pair: ``np.cross`` moves axes on every call)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def open_ring(points: np.ndarray) -> np.ndarray:
    """``(k, d)`` a ring's points without its closing point, when its last point repeats its first
    (``np.allclose``'s test: each coordinate within 1e-8 + 1e-5 of its size; a twentieth of ``np.allclose``'s
    time, which is most of reading a profile's few points)."""
    if len(points) > 1:
        a, b = points[0], points[-1]
        if bool((np.abs(a - b) <= 1e-8 + 1e-5 * np.abs(b)).all()):
            return points[:-1]
    return points


def number(text: Any, default: float = float("nan")) -> float:
    """A CSV cell as a float (``default`` when empty or not a number)."""
    try:
        return float(text)
    except (TypeError, ValueError):
        return default


def literal(text: str) -> Any:
    """A cell holding a JSON value (``[0, 1]``, ``{"origin": …}``; a Python literal as builds before 0.2 wrote
    it), or ``None`` when it does not."""
    if not text:
        return None
    try:
        return json.loads(text)
    except ValueError:
        pass
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, MemoryError, RecursionError):
        return None


def frame_of(row: dict[str, str]) -> dict[str, np.ndarray] | None:
    """The plate frame of a ``parts.csv`` beam row: ``origin``, ``x_dir``, ``y_dir``, ``normal`` (unit)."""
    doc = literal(row.get("frame", ""))
    if not isinstance(doc, dict):
        return None
    try:
        return {k: np.asarray(doc[k], dtype=float).reshape(3) for k in ("origin", "x_dir", "y_dir", "normal")}
    except (KeyError, TypeError, ValueError):
        return None


def to_frame(points: np.ndarray, frame: dict[str, np.ndarray]) -> np.ndarray:
    """3D points ``(k, 3)`` in a plate frame: ``(k, 3)`` columns x, y (in the plate), z (across it)."""
    d = np.asarray(points, dtype=float) - frame["origin"]
    return np.stack([d @ frame["x_dir"], d @ frame["y_dir"], d @ frame["normal"]], axis=1)


SAME_POINT_MM = 1e-7
"""Two consecutive points of an outline closer than this (mm) are one (the cut outline's rule, ``joints._clean``)."""


def merge_close(ring: np.ndarray, corners: np.ndarray, tol: float) -> np.ndarray:
    """``ring (k, 2)`` with every point within ``tol`` (mm) of one of ``corners (m, 2)`` moved onto it, then each
    run of consecutive points within :data:`SAME_POINT_MM` kept once.  Snap rounding can put a point a few 1e-7 mm
    from a corner where two faces' collinear edges meet; were both kept, each would lie on the line through its
    neighbours and the corner would be dropped with them (a notched plate's union lost a 33 mm² corner that way).
    The build's cut outline does the same in :func:`fabrication.beams.bevel_cut.cut_outline`, written apart:
    verify shares no code with what it checks."""
    from scipy.spatial import cKDTree

    d, k = cKDTree(corners).query(ring)
    out = np.where((d <= tol)[:, None], corners[k], ring)
    # a point may go onto the front face's corner and its neighbour onto the back face's, 1e-10 mm apart: such a
    # pair is one point (kept, both would be dropped as straight by any collinearity test)
    kept = [out[0]]
    for p in out[1:]:
        if np.linalg.norm(p - kept[-1]) > SAME_POINT_MM:
            kept.append(p)
    while len(kept) > 1 and np.linalg.norm(kept[-1] - kept[0]) <= SAME_POINT_MM:
        kept.pop()
    return np.asarray(kept)


def faces_union(front: np.ndarray, back: np.ndarray, grid: float | None = None) -> np.ndarray | None:
    """The outline cut from the sheet for a plate with two faces ``(k, 2)`` each (frame coordinates): their
    union's corners, near-duplicate and collinear points (1 µm off the line through their neighbours) dropped as
    the cut outline drops them; ``None`` when the two do not overlap into one polygon.  ``grid`` (mm): the
    union is taken on that precision grid (points read in single precision: the two faces share their end cuts,
    segments on one line that rounding would otherwise make cross)."""
    import shapely
    from shapely.geometry import Polygon

    # on a precision grid always: two faces share their end cuts and bottom edge, and where a shared corner differs
    # in the 14th digit GEOS's floating overlay can return one face for the union (a welded plate's text-read
    # faces: 259,577 for 260,561 mm²); snap-rounded at 1e-9 mm it is robust
    size = grid if grid else 1e-9
    union = shapely.union(Polygon(front), Polygon(back), grid_size=size)
    if union.geom_type != "Polygon":                      # slivers and lines the grid left beside the outline
        parts = sorted((g for g in shapely.get_parts(union) if g.geom_type == "Polygon"), key=lambda g: -g.area)
        if parts and all(g.area <= 2.0 * max(size, 1e-6) * g.length for g in parts[1:]):
            union = parts[0]
    if union.geom_type != "Polygon":
        return None
    cut = merge_close(np.asarray(union.exterior.coords)[:-1], np.vstack([front, back]), 1e-5)
    prev, nxt = np.roll(cut, 1, axis=0), np.roll(cut, -1, axis=0)
    cross = (cut[:, 0] - prev[:, 0]) * (nxt[:, 1] - cut[:, 1]) - (cut[:, 1] - prev[:, 1]) * (nxt[:, 0] - cut[:, 0])
    return cut[np.abs(cross) > 1e-6 * np.linalg.norm(nxt - prev, axis=1)]


def torsion_tolerance(manifest: dict[str, Any]) -> tuple[float, str]:
    """The torsion a build may have, mm at beam depth, and the key it comes from: ``beams.max_torsion_mm``
    when the design has it, else ``beams.plane_tolerance`` (how far a vertex may be off its beam's plane)."""
    beams = manifest.get("fabrication", {}).get("beams", {})
    if beams.get("max_torsion_mm") is not None:
        return float(beams["max_torsion_mm"]), "beams.max_torsion_mm"
    return float(beams.get("plane_tolerance", manifest.get("fabrication", {}).get("beam_plane_tolerance", 0.5))), \
        "beams.plane_tolerance"


def solid_points(solid: Any) -> np.ndarray:
    """``(k, 3)`` vertices of a solid: a CAD solid's, or the ``points`` of the text-level reader's record."""
    pts = getattr(solid, "points", None)
    if isinstance(pts, np.ndarray):
        return pts
    return np.array([tuple(p) for p in solid.vertices()], dtype=float).reshape(-1, 3)


def face_outline(solid: Any, normal: np.ndarray) -> np.ndarray | None:
    """The ordered outer boundary ``(k, 3)`` of the planar face of ``solid`` facing ``normal`` (a plate's top or
    bottom face), from the chain of its edges; ``None`` when the solid has no such face.  A record of the
    text-level reader gives its own (:meth:`~._step_text_read.TextSolid.face_outline`)."""
    if hasattr(solid, "face_outline"):
        return solid.face_outline(normal)
    n = np.asarray(normal, dtype=float)
    for face in solid.faces():
        try:
            fn = np.array(tuple(face.normal_at()), dtype=float)
        except Exception:  # noqa: BLE001 - a non-planar face
            continue
        if abs(float(fn @ n)) < 1.0 - 1e-9:
            continue
        segs = [(np.array(tuple(e.start_point())), np.array(tuple(e.end_point()))) for e in face.outer_wire().edges()]
        return _chain(segs)
    return None


def _chain(segs: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray | None:
    if not segs:
        return None
    pts = [segs[0][0], segs[0][1]]
    rest = segs[1:]
    while rest:
        end = pts[-1]
        k = min(range(len(rest)), key=lambda i: min(np.linalg.norm(rest[i][0] - end), np.linalg.norm(rest[i][1] - end)))
        a, b = rest.pop(k)
        pts.append(b if np.linalg.norm(a - end) <= np.linalg.norm(b - end) else a)
    return np.array(pts[:-1])


def set_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance from a point of either set to the nearest point of the other (``inf`` if counts differ)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if len(a) != len(b) or len(a) == 0:
        return float("inf")
    return float(max(cKDTree(b).query(a)[0].max(), cKDTree(a).query(b)[0].max()))


def cyclic_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Smallest largest corner distance between polygons ``a`` and ``b`` over cyclic relabellings and reversal
    of ``b`` (``inf`` when their corner counts differ)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or len(a) == 0:
        return float("inf")
    best = float("inf")
    for poly in (b, b[::-1]):
        for k in range(len(poly)):
            best = min(best, float(np.linalg.norm(np.roll(poly, k, axis=0) - a, axis=1).max()))
    return best


def boundary_distance(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """``(m,)`` distance of 2D points from the boundary of a polygon ``(k, 2)``."""
    p = np.asarray(points, dtype=float)[:, None, :]
    a = np.asarray(polygon, dtype=float)
    b = np.roll(a, -1, axis=0)
    e = b - a
    t = np.clip(np.einsum("mki,ki->mk", p - a, e) / np.maximum(np.einsum("ki,ki->k", e, e), 1e-300), 0.0, 1.0)
    foot = a + t[..., None] * e
    return np.linalg.norm(p - foot, axis=-1).min(axis=1)


def edges_on_line(polygon: np.ndarray, point: np.ndarray, direction: np.ndarray, tol: float) -> bool:
    """Whether some edge of a 2D polygon lies on the line ``point + s·direction`` (both ends within ``tol``)."""
    a = np.asarray(polygon, dtype=float)
    d = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    nrm = np.array([-d[1], d[0]])
    off = (a - point) @ nrm
    on = np.abs(off) <= tol
    return bool(np.any(on & np.roll(on, -1)))

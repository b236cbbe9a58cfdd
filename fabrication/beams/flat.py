"""Beam plates as flat parts for nesting and DXF cutting sheets.

The flat outline of a plate is its outline in its own 2D frame (slots and end
cuts included; raised by ``Δ`` on the top-edge spans it is bevelled on, :mod:`fabrication.beams.bevel_cut`), so placing the part on a sheet and mapping it back into the
structure use the same coordinates; the frame (origin, x and y directions) is
recorded in ``meta['frame']``.  Node axes are drawn as marking lines (layer
``MARK``), clipped to the material (a half-lap slot removes half of its axis).  The bolt holes of the splices
at a piece's ends are :attr:`HoledPart.holes` (cut as circles); the bevels to plane after cutting are
:attr:`HoledPart.bevels` (drawn on their own layer with their instruction).
"""

from __future__ import annotations

import numpy as np
from shapely.geometry import LineString, Polygon

from dataclasses import dataclass, field

from fabrication.flatpart import FlatPart
from ppfab.metrics import polygon_area

from .plates import BeamPlate


@dataclass(frozen=True, eq=False)
class HoledPart(FlatPart):
    """A flat part with round holes cut inside its outline: ``holes`` ``(h, 3)`` centre ``x, y`` (part frame) and
    diameter, mm; the DXF writers cut them as circles on ``CUT``."""

    holes: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    bevels: tuple["BevelMark", ...] = ()


@dataclass(frozen=True, eq=False)
class BevelMark:
    """A top-edge span to plane after cutting: the raised edge as cut ``line (2, 2)`` (part frame) and the shop
    instruction ``text`` (angle, the face that keeps the raised edge by its face mark, ``Δ``)."""

    line: np.ndarray
    text: str


def bevel_marks(plate: BeamPlate) -> tuple[BevelMark, ...]:
    """One :class:`BevelMark` per bevelled span of ``plate``: the span's edge of the cut outline (the raised
    edge, the longest edge of the cut outline on the raised line) and ``BEVEL 13.6° U+ +1.45``: planed at the
    lean to the strip, the face marked ``U+`` keeps the edge, the other face loses ``2Δ`` (``Δ`` in mm)."""
    from fabrication.marking import face_marks, face_sign

    if not plate.bevels or plate.cut_outline is None:
        return ()
    q = plate.cut_outline
    nxt = np.roll(q, -1, axis=0)
    marks = face_marks(plate.family, face_sign(plate.frame.normal, plate.plane[:3], False))
    out = []
    h = 0.5 * plate.thickness
    for b in plate.bevels:
        a, bb, c, w = b.line
        z = h * b.side                                    # the raised face's line: a·x + b·y = c − w·z
        off = np.abs(q @ np.array([a, bb]) - (c - w * z))
        off_n = np.abs(nxt @ np.array([a, bb]) - (c - w * z))
        on = np.flatnonzero((off <= 1e-6) & (off_n <= 1e-6))
        if not len(on):
            continue
        k = int(max(on, key=lambda i: float(np.linalg.norm(nxt[i] - q[i]))))
        face = marks[0] if b.side > 0 else marks[1]
        out.append(BevelMark(np.array([q[k], nxt[k]]), f"BEVEL {b.lean_deg:.1f}\u00b0 {face} +{b.delta:.2f}"))
    return tuple(out)


def axis_marks(plate: BeamPlate, min_length: float = 1.0) -> tuple[np.ndarray, ...]:
    """Node axis lines ``top_k → bottom_k`` (2D) clipped to the outline, each a ``(2, 2)`` array."""
    poly = Polygon(plate.flat_outline)
    out = []
    for c in plate.chain.tolist():
        seg = LineString([plate.top[c], plate.bottom[c]]).intersection(poly)
        parts = getattr(seg, "geoms", [seg])
        for g in parts:
            if g.geom_type == "LineString" and g.length >= min_length:
                out.append(np.asarray(g.coords, dtype=float))
    return tuple(out)


CONGRUENT_MM = 0.05
"""Two plate outlines are one type when, in their principal-axes poses, every vertex of one lies within this of
the matching vertex of the other (mm, each coordinate): half the 0.1 mm grid the types were once keyed by, compared
without rounding, so two congruent plates whose coordinates straddle a rounding boundary (743.149… and 743.150…
mm) are not split into two types."""


def _poses(outline: np.ndarray, mirror: bool) -> list[np.ndarray]:
    """The outline moved to its centroid and turned to its principal axes, in its 2 (or 4 with reflections)
    remaining poses, each counter-clockwise: ``(n, 2)`` arrays."""
    p = np.asarray(outline, dtype=float)
    c = p - p.mean(axis=0)
    _, vecs = np.linalg.eigh(c.T @ c)
    vecs = vecs[:, ::-1]
    if np.linalg.det(vecs) < 0:          # a rotation, so that only the reflections below mirror
        vecs[:, 1] *= -1
    base = c @ vecs
    out = []
    for sx, sy in ((1, 1), (-1, -1)) + (((-1, 1), (1, -1)) if mirror else ()):
        q = base * np.array([sx, sy])
        out.append(q[::-1] if polygon_area(q) < 0 else q)
    return out


def congruent(a: np.ndarray, b_poses: list[np.ndarray], tol: float = CONGRUENT_MM) -> bool:
    """Whether the pose ``a (n, 2)`` matches one of ``b_poses`` vertex for vertex, up to where the vertex list
    starts, within ``tol`` in each coordinate."""
    n = len(a)
    shifts = (np.arange(n)[:, None] + np.arange(n)[None, :]) % n          # (shift, vertex)
    for b in b_poses:
        if len(b) != n:
            return False
        if float(np.abs(b[shifts] - a[None]).max(axis=(1, 2)).min()) <= tol:
            return True
    return False


def congruent_outlines(a: np.ndarray, b: np.ndarray, mirror: bool = True, tol: float = CONGRUENT_MM) -> bool:
    """Whether two outlines ``(n, 2)`` are congruent (rigid motions, and reflections with ``mirror``) within
    ``tol`` per vertex coordinate in their principal-axes poses: the test :func:`type_ids` groups plates by."""
    return congruent(_poses(a, mirror)[0], _poses(b, mirror), tol)


def type_ids(plates: list[BeamPlate], mirror: bool = True) -> dict[str, str]:
    """``part_id → type id`` (``BT001``, … in order of first appearance); congruent plates (:func:`congruent`,
    reflections included with ``mirror``) with the same splice holes and bevels share a type.

    Candidates are found by vertex count and area (to within a bucket either side, so no tolerance is cut by a
    rounding boundary), then compared vertex for vertex."""
    area_bucket = 1000.0                                     # mm²: far above what 0.05 mm per vertex changes
    buckets: dict[tuple, list[tuple[np.ndarray, str]]] = {}
    out: dict[str, str] = {}
    count = 0
    for p in plates:
        extra = (len(p.holes), tuple(sorted((round(b.delta, 1), b.side) for b in p.bevels)))
        poses = _poses(p.flat_outline, mirror)
        k = int(np.floor(abs(float(polygon_area(p.flat_outline))) / area_bucket))
        found = None
        for kk in (k - 1, k, k + 1):
            for rep, tid in buckets.get((len(poses[0]), extra, kk), []):
                if congruent(rep, poses):
                    found = tid
                    break
            if found:
                break
        if found is None:
            count += 1
            found = f"BT{count:03d}"
            buckets.setdefault((len(poses[0]), extra, k), []).append((poses[0], found))
        out[p.part_id] = found
    return out


def flat_part(plate: BeamPlate, material: str = "", density: float = 0.0, type_id: str = "") -> FlatPart:
    """One :class:`~fabrication.flatpart.FlatPart` (kind ``"beam"``) for a plate."""
    area = float(polygon_area(plate.flat_outline))            # as cut (raised where bevelled)
    mass = area * plate.thickness * density * 1e-9           # the plate as cut, before its bevels are planed
    meta = {
        "material": material, "thickness_mm": plate.thickness, "depth_mm": plate.depth,
        "mass_kg": mass, "length_mm": plate.length, "area_mm2": area,
        "beam_id": plate.beam_id, "family": ("rows", "cols")[plate.family], "piece": plate.piece,
        "pieces": plate.n_pieces, "nodes": plate.nodes.tolist(), "slots": len(plate.slots),
        "frame": plate.frame.as_dict(), "plane": plate.plane.tolist(),
    }
    if len(plate.holes):
        meta["holes"] = len(plate.holes)
        meta["hole_mm"] = float(plate.holes[0, 2])
    if plate.bevels:
        meta["bevels"] = len(plate.bevels)
    if plate.notches:
        meta["notches"] = [n.cell() for n in plate.notches]
    return HoledPart(plate.part_id, "beam", plate.flat_outline.copy(), marks=axis_marks(plate), label=plate.part_id,
                     type_id=type_id, rotations=None, mirror_allowed=True, meta=meta, holes=plate.holes.copy(),
                     bevels=bevel_marks(plate))


def flat_parts(plates: list[BeamPlate], material: str = "", density: float = 0.0,
               types: dict[str, str] | None = None) -> list[FlatPart]:
    """Flat parts of all plates (type ids from :func:`type_ids` unless given)."""
    types = types if types is not None else type_ids(plates)
    return [flat_part(p, material, density, types.get(p.part_id, "")) for p in plates]

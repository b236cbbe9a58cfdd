"""The parts to nest as flat arrays: every allowed pose of every part with its box and area.

Planning works on boxes inflated by the spacing ``s``: a pose of size ``w × h`` occupies
``(w + s) × (h + s)`` in the usable area inflated to ``(L + s) × (H + s)``; boxes that do
not overlap there leave at least ``s`` between parts, and inside it means inside the trim.
A pose's *twins* are the poses of the same part with the same box (e.g. turned 180°): a
row may swap a pose for a twin to nestle better.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ppfab.errors import NestingError

from ..flatpart import FlatPart
from .params import NestingParams
from .shapes import Orient, free_angles, orientations


@dataclass(eq=False)
class Catalog:
    """Poses of all parts (index ``o``), grouped by part (index ``p``).

    Attributes
    ----------
    orients : list of :class:`~.shapes.Orient`
    o_part : (O,) part of each pose; o_w, o_h : (O,) inflated box ``w + s``, ``h + s``
    part_start : (P+1,) pose range of each part; part_area : (P,) outline areas, mm²
    twins : (O,) box class of a pose within its part
    L, H : inflated usable length and height, mm; spacing : s, mm
    """

    parts: list[FlatPart]
    orients: list[Orient]
    o_part: np.ndarray
    o_w: np.ndarray
    o_h: np.ndarray
    part_start: np.ndarray
    part_area: np.ndarray
    twins: np.ndarray
    L: float
    H: float
    spacing: float

    @property
    def n_parts(self) -> int:
        return len(self.parts)


def _check_outline(part: FlatPart) -> np.ndarray:
    outline = np.asarray(part.outline, dtype=float)
    if outline.ndim != 2 or outline.shape[1] != 2 or len(outline) < 3 or not np.all(np.isfinite(outline)):
        raise NestingError(f"part {part.part_id}: outline must be a finite (k>=3, 2) polygon, got shape {outline.shape}")
    if part.area <= 0:
        raise NestingError(f"part {part.part_id}: outline is not counter-clockwise or has no area "
                           f"(area {part.area:.3g} mm²)")
    from shapely.geometry import Polygon
    from shapely.validation import explain_validity

    poly = Polygon(outline)
    if not poly.is_valid:      # a self-crossing outline has no well-defined halo: spacing could not be kept
        raise NestingError(f"part {part.part_id}: outline is not a simple polygon ({explain_validity(poly)})")
    return outline


def part_rotations(part: FlatPart, params: NestingParams) -> list[float]:
    """Rotations allowed for ``part``: its own, else the nesting's (plus edge-aligning angles when free)."""
    rots = list(part.rotations) if part.rotations is not None else list(params.rotations)
    if params.free_rotation and part.rotations is None:
        rots = sorted(set(float(r) % 360.0 for r in rots) | set(free_angles(np.asarray(part.outline, dtype=float))))
    return [float(r) % 360.0 for r in rots]


def build_catalog(parts: list[FlatPart], params: NestingParams) -> Catalog:
    """Poses of ``parts`` that fit the usable area.

    Raises :class:`NestingError` for a duplicate part id, a malformed outline, or a part that
    fits the usable area in none of its allowed poses (naming it and its size).
    """
    s = float(params.spacing)
    x0, y0, x1, y1 = params.usable()
    L, H = (x1 - x0) + s, (y1 - y0) + s
    orients: list[Orient] = []
    starts = [0]
    seen: set[str] = set()
    for i, part in enumerate(parts):
        if part.part_id in seen:
            raise NestingError(f"part id {part.part_id!r} occurs twice in the parts to nest")
        seen.add(part.part_id)
        outline = _check_outline(part)
        rots = part_rotations(part, params)
        poses = [o for o in orientations(i, outline, rots, bool(part.mirror_allowed), s)
                 if o.w + s <= L + 1e-9 and o.h + s <= H + 1e-9]
        if not poses:
            w, h = np.ptp(outline, axis=0)
            raise NestingError(f"part {part.part_id} ({w:.1f} x {h:.1f} mm) fits no sheet: usable area is "
                               f"{x1 - x0:.1f} x {y1 - y0:.1f} mm, rotations {rots}")
        orients.extend(poses)
        starts.append(len(orients))
    part_start = np.array(starts, dtype=np.int64)
    o_part = np.array([o.part for o in orients], dtype=np.int64)
    o_w = np.array([o.w for o in orients]) + s
    o_h = np.array([o.h for o in orients]) + s
    twins = np.zeros(len(orients), dtype=np.int64)
    for p in range(len(parts)):
        keys: list[tuple[float, float]] = []
        for o in range(part_start[p], part_start[p + 1]):
            key = (round(o_w[o], 6), round(o_h[o], 6))
            if key not in keys:
                keys.append(key)
            twins[o] = keys.index(key)
    area = np.array([p.area for p in parts], dtype=float)
    return Catalog(parts, orients, o_part, o_w, o_h, part_start, area, twins, L, H, s)

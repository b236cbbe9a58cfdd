"""The parts to nest as flat arrays: every allowed pose of every part with its box and area.

Planning works on boxes inflated by the spacing ``s``: a pose of size ``w × h`` occupies
``(w + s) × (h + s)`` in the usable area inflated to ``(L + s) × (H + s)``; boxes that do
not overlap there leave at least ``s`` between parts, and inside it means inside the trim.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ppfab.errors import NestingError

from ..flatpart import FlatPart
from .params import NestingParams
from .shapes import Orient, free_angles, halos, orientations, unique_angles


@dataclass(eq=False)
class Catalog:
    """Poses of all parts (index ``o``), grouped by part (index ``p``).

    Attributes
    ----------
    orients : list of :class:`~.shapes.Orient`
    o_part : (O,) part of each pose; o_w, o_h : (O,) inflated box ``w + s``, ``h + s``
    part_start : (P+1,) pose range of each part; part_area : (P,) outline areas, mm²
    L, H : inflated usable length and height, mm; spacing : s, mm
    """

    parts: list[FlatPart]
    orients: list[Orient]
    o_part: np.ndarray
    o_w: np.ndarray
    o_h: np.ndarray
    part_start: np.ndarray
    part_area: np.ndarray
    L: float
    H: float
    spacing: float

    @property
    def n_parts(self) -> int:
        return len(self.parts)


def _check_outlines(parts: list[FlatPart]) -> tuple[list[np.ndarray], np.ndarray]:
    """The outlines as float arrays and their areas; a malformed, clockwise or self-crossing one is named."""
    import shapely
    from shapely.validation import explain_validity

    outlines = []
    areas = np.zeros(len(parts))
    for i, part in enumerate(parts):
        outline = np.asarray(part.outline, dtype=float)
        if outline.ndim != 2 or outline.shape[1] != 2 or len(outline) < 3 or not np.all(np.isfinite(outline)):
            raise NestingError(f"part {part.part_id}: outline must be a finite (k>=3, 2) polygon, got shape {outline.shape}")
        x, y = outline[:, 0], outline[:, 1]
        areas[i] = 0.5 * float(x[:-1] @ y[1:] - y[:-1] @ x[1:] + x[-1] * y[0] - y[-1] * x[0])
        if areas[i] <= 0:
            raise NestingError(f"part {part.part_id}: outline is not counter-clockwise or has no area "
                               f"(area {areas[i]:.3g} mm²)")
        outlines.append(outline)
    polys = np.array([shapely.Polygon(o) for o in outlines], dtype=object)
    valid = shapely.is_valid(polys)
    if not valid.all():       # a self-crossing outline has no well-defined halo: spacing could not be kept
        k = int(np.flatnonzero(~valid)[0])
        raise NestingError(f"part {parts[k].part_id}: outline is not a simple polygon ({explain_validity(polys[k])})")
    return outlines, areas


def rotation_policy(part: FlatPart, params: NestingParams) -> tuple[bool, list[float]]:
    """``(free, angles)`` for ``part``: free rotation, else the allowed angles (degrees).

    The part's own policy wins (``free_rotation``, then ``rotations``); a part without one takes the
    nesting's (``free_rotation``, ``rotations``).  For a free part ``angles`` are the preferred ones.
    """
    if part.free_rotation:
        return True, [float(r) for r in params.rotations]
    if part.rotations is not None:
        return False, [float(r) for r in part.rotations]
    return bool(params.free_rotation), [float(r) for r in params.rotations]


def part_rotations(part: FlatPart, params: NestingParams) -> list[float]:
    """Rotations tried for ``part``: the allowed ones, or for a free part its preferred ones, the angles
    that lay each (longest) hull edge along the bottom or the top, and its minimum-area rectangle frame."""
    free, rots = rotation_policy(part, params)
    if free:
        rots = rots + free_angles(np.asarray(part.outline, dtype=float))
    return unique_angles(rots)


def build_catalog(parts: list[FlatPart], params: NestingParams) -> Catalog:
    """Poses of ``parts`` that fit the usable area.

    Raises :class:`NestingError` for a duplicate part id, a malformed outline, or a part that
    fits the usable area in none of its allowed poses (naming it and its size).
    """
    s = float(params.spacing)
    x0, y0, x1, y1 = params.usable()
    L, H = (x1 - x0) + s, (y1 - y0) + s
    seen: set[str] = set()
    for part in parts:
        if part.part_id in seen:
            raise NestingError(f"part id {part.part_id!r} occurs twice in the parts to nest")
        seen.add(part.part_id)
    outlines, area = _check_outlines(parts)
    part_halos = halos(outlines, s)
    orients: list[Orient] = []
    starts = [0]
    for i, part in enumerate(parts):
        outline = outlines[i]
        free, _ = rotation_policy(part, params)
        rots = part_rotations(part, params)
        poses = [o for o in orientations(i, outline, rots, bool(part.mirror_allowed), s, part_halos[i], not free)
                 if o.w + s <= L + 1e-9 and o.h + s <= H + 1e-9]
        if not poses:
            w, h = np.ptp(outline, axis=0)
            what = "any rotation" if free else f"rotations {rots}"
            raise NestingError(f"part {part.part_id} ({w:.1f} x {h:.1f} mm) fits no sheet: usable area is "
                               f"{x1 - x0:.1f} x {y1 - y0:.1f} mm, {what}")
        orients.extend(poses)
        starts.append(len(orients))
    part_start = np.array(starts, dtype=np.int64)
    o_part = np.array([o.part for o in orients], dtype=np.int64)
    o_w = np.array([o.w for o in orients]) + s
    o_h = np.array([o.h for o in orients]) + s
    return Catalog(parts, orients, o_part, o_w, o_h, part_start, area, L, H, s)

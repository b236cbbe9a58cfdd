"""Marking of flat parts on a cutting sheet: upright labels placed inside the part, and the face mark of a plate.

Label placement.  A label is a block of text lines (part id, face mark, nest tag) written with one rotation
``θ`` in the *sheet* frame, normalised into ``(−45°, 135°]`` (:func:`upright_deg`) so that it reads from the
bottom or the right edge of the sheet, as drafting convention (ISO 128) has it: one reading direction per sheet
— a label along a nearly vertical side reads upwards, never downwards beside a neighbour that reads upwards.  ``θ`` follows the part's long side (the minimum rotated rectangle of the outline).  The block's
box (:func:`block_size`: ``LABEL_CHAR_WIDTH`` text heights per character, ``LABEL_LINE_PITCH`` heights per
line) is placed inside the outline shrunk by a margin, and clear of keep-out shapes (the node-axis marks);
slots are notches of the outline, so the shrunk outline already keeps the text clear of them.  Of the grid of
candidate centres whose box fits, the one furthest from the boundary wins; the height is the largest of a
descending series that fits.

Face mark.  A beam plate lies in its support plane ``n·x + d = 0`` (``parts.csv`` column ``plane``).  Its flat
frame maps part coordinates to 3D with normal ``N = x_dir × y_dir``; on the sheet a part is placed by
``R(θ)·M`` with ``M`` the mirror ``x ↦ −x`` when ``mirrored``.  The face that looks up from the sheet has the
3D normal ``σN`` with ``σ = −1`` for a mirrored placement, so it faces along ``+n`` iff ``σ(N·n) > 0``:
the mark engraved on it reads ``U+`` (rows) / ``W+`` (columns), else ``U-`` / ``W-``; the face underneath
carries the opposite sign (:func:`face_marks`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LABEL_CHAR_WIDTH = 0.8
"""Width of one character of a label, in text heights (CAM single-stroke and TrueType fonts measure
0.6–0.75; the box is conservative)."""

LABEL_LINE_PITCH = 1.5
"""Distance between the baselines of two label lines, in text heights of the larger line."""

FAMILY_LETTERS = "UW"
"""The face-mark letter of a plate of family 0 (rows, planes ``U_i``) and 1 (columns, planes ``W_j``)."""


READING_RANGE_DEG = (-45.0, 135.0)
"""Text directions (degrees, counter-clockwise from the sheet's x axis) that read from the bottom or the right
edge of a sheet: the half-open range ``(−45°, 135°]``.  Every direction has exactly one representative in it up to
a half turn, so the labels of one sheet never read in opposite directions."""


def reads_from_bottom_or_right(angle_deg: float) -> bool:
    """Whether text turned ``angle_deg`` reads from the bottom or the right edge (:data:`READING_RANGE_DEG`).

    >>> reads_from_bottom_or_right(90.0), reads_from_bottom_or_right(-87.0), reads_from_bottom_or_right(180.0)
    (True, False, False)
    """
    a = (float(angle_deg) + 180.0) % 360.0 - 180.0
    lo, hi = READING_RANGE_DEG
    return lo + 1e-9 < a <= hi + 1e-9


def upright_deg(angle_deg: float) -> float:
    """The text direction ``angle_deg`` turned by a multiple of 180° into ``(−45°, 135°]`` (it reads from the bottom
    or the right edge, :data:`READING_RANGE_DEG`).

    >>> upright_deg(180.0), upright_deg(-90.0), upright_deg(271.0), upright_deg(90.0), upright_deg(-87.0)
    (0.0, 90.0, 91.0, 90.0, 93.0)
    """
    lo, hi = READING_RANGE_DEG
    a = (float(angle_deg) - lo) % 180.0 + lo
    # within 0.01° above the lower end: the upper end (a turn of at most 0.01°), so that a drawing's rounding of
    # the angle (an SVG writes two decimals) never lands on −45° itself
    return hi if a <= lo + 0.01 else a + 0.0


def face_sign(frame_normal: np.ndarray, plane_normal: np.ndarray, mirrored: bool) -> int:
    """``+1`` when the face looking up from the sheet faces along ``+n`` (the plane normal), else ``−1``.

    ``frame_normal`` : (3,) ``x_dir × y_dir`` of the part's flat frame; ``plane_normal`` : (3,) ``n``.
    """
    s = float(np.dot(frame_normal, plane_normal)) * (-1.0 if mirrored else 1.0)
    return 1 if s > 0 else -1


def face_marks(family: int, sign: int) -> tuple[str, str]:
    """``(top, underside)`` face marks: ``("U+", "U-")`` for a row plate whose up face looks along ``+n``.

    >>> face_marks(1, -1)
    ('W-', 'W+')
    """
    letter = FAMILY_LETTERS[family] if 0 <= family < len(FAMILY_LETTERS) else "R"
    return f"{letter}{'+' if sign > 0 else '-'}", f"{letter}{'-' if sign > 0 else '+'}"


@dataclass(frozen=True)
class TextLine:
    """One line of a label block: ``text`` on ``layer``, ``scale`` × the block's text height."""

    text: str
    layer: str
    scale: float = 1.0


@dataclass(frozen=True)
class PlacedLine:
    """A label line placed in the sheet: its middle-centre point ``(2,)``, height, rotation (degrees)."""

    line: TextLine
    centre: np.ndarray
    height: float
    rotation_deg: float


@dataclass(frozen=True)
class LabelPlacement:
    """Where a block went: its lines, the block box ``(4, 2)`` and whether it fits inside the part."""

    lines: tuple[PlacedLine, ...]
    box: np.ndarray
    fits: bool


def block_size(lines: list[TextLine], height: float) -> tuple[float, float, np.ndarray]:
    """``(width, depth, offsets)`` of a block of ``lines`` at text ``height``: ``offsets`` (k,) are the
    line centres along the block's up direction, first line on top."""
    hs = np.array([height * ln.scale for ln in lines])
    width = max(LABEL_CHAR_WIDTH * len(ln.text) * h for ln, h in zip(lines, hs))
    steps = [LABEL_LINE_PITCH * max(a, b) for a, b in zip(hs[:-1], hs[1:])]
    pos = -np.r_[0.0, np.cumsum(steps)] if steps else np.zeros(1)
    top, bottom = pos[0] + 0.75 * hs[0], pos[-1] - 0.75 * hs[-1]
    return float(width), float(top - bottom), pos - 0.5 * (top + bottom)


def _long_side_deg(poly) -> float:
    rect = np.asarray(poly.minimum_rotated_rectangle.exterior.coords)[:4]
    e = np.diff(np.r_[rect, rect[:1]], axis=0)[:2]
    k = int(np.argmax(np.linalg.norm(e, axis=1)))
    return float(np.degrees(np.arctan2(e[k, 1], e[k, 0])))


def _box(centre: np.ndarray, width: float, depth: float, angle_deg: float) -> np.ndarray:
    a = np.radians(angle_deg)
    u, v = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
    hw, hd = 0.5 * width, 0.5 * depth
    return np.array([centre - hw * u - hd * v, centre + hw * u - hd * v, centre + hw * u + hd * v,
                     centre - hw * u + hd * v])


def place_label(outline: np.ndarray, lines: list[TextLine], margin: float, max_height: float,
                min_height: float = 2.0, keep_out: tuple[np.ndarray, ...] = (),
                keep_out_areas: tuple[np.ndarray, ...] = (), prefer_deg: float | None = None) -> LabelPlacement:
    """Place a label block upright inside ``outline`` (see module docstring).

    Parameters
    ----------
    outline : (k, 2) part outline in sheet coordinates, mm
    lines : the block's lines, first on top
    margin : clearance of the block from the outline (and its slots) and from ``keep_out``, mm
    max_height, min_height : text height range of the block, mm (lines scale it by ``TextLine.scale``)
    keep_out : polylines ``(p, 2)`` the block must keep ``margin`` from (marking lines)
    keep_out_areas : polygons ``(p, 2)`` the block must keep ``margin`` from (other labels)
    prefer_deg : a direction tried first at every height (e.g. 0 for horizontal text on a drawing), before the
        part's long side

    Returns
    -------
    LabelPlacement — ``fits`` is False when no height down to ``min_height`` fits; the block is then put at the
    pole of inaccessibility at ``min_height``.
    """
    from shapely.geometry import Polygon

    poly = Polygon(outline)
    if not poly.is_valid:
        poly = poly.buffer(0)
    angle = upright_deg(_long_side_deg(poly))
    if not _room_for(poly, block_size(lines, min_height), margin):
        return _pole(poly, lines, min_height, angle)
    region = free_region(poly, keep_out, keep_out_areas, margin)
    angles = [angle] if prefer_deg is None else [upright_deg(prefer_deg), angle]
    centroid = np.array(region.centroid.coords[0]) if not region.is_empty else np.zeros(2)
    for ang in angles:
        height = max_height
        while height >= min_height - 1e-9 and not region.is_empty:
            width, depth, _ = block_size(lines, height)
            best = _fit(region, region.buffer(-0.5 * depth), width, depth, ang, centroid)
            if best is not None:
                return _placed(lines, best, height, ang, True)
            height *= 0.85
    return _pole(poly, lines, min_height, angle)


def free_region(poly, keep_out: tuple[np.ndarray, ...], keep_out_areas: tuple[np.ndarray, ...], margin: float):
    """Where a label block of :func:`place_label` may lie: the outline ``poly`` (shapely) shrunk by ``margin``
    (mitred), less every keep-out line ``(p, 2)`` grown by ``margin`` (flat ends) and every keep-out polygon grown
    by ``margin`` (mitred) — taken away at once, by their union: an elevation's plate face among hundreds of
    lines was cut down one difference per line, each on a region of more and more edges."""
    import shapely
    from shapely.geometry import LineString, Polygon

    region = poly.buffer(-margin, join_style="mitre")
    cuts = [LineString(m).buffer(margin, cap_style="flat") for m in keep_out if len(m) >= 2]
    cuts += [Polygon(q).buffer(margin, join_style="mitre") for q in keep_out_areas]
    return region.difference(shapely.union_all(cuts)) if cuts else region


def _pole(poly, lines: list[TextLine], height: float, angle: float) -> LabelPlacement:
    """The block that does not fit: at the outline's pole of inaccessibility, ``height`` high."""
    from shapely.ops import polylabel

    pole = polylabel(poly, tolerance=max(np.sqrt(max(poly.area, 1e-9)) * 0.01, 0.1))
    return _placed(lines, np.array([pole.x, pole.y]), height, angle, False)


def _room_for(poly, size: tuple[float, float, np.ndarray], margin: float) -> bool:
    """Whether the outline ``poly`` may hold a block of ``size`` (:func:`block_size`: the smallest one tried) with
    ``margin`` all round, by two tests any fitting block passes: a box ``depth`` deep inside the outline shrunk by
    ``margin`` holds a disc of that diameter, so the outline shrunk by ``margin + depth / 2`` is not empty; its
    diagonal, at least ``width`` long, lies inside the outline, so two of the outline's vertices are at least
    that far apart.  On a drawing at a small scale most panes fail the first (an elevation of the bundled
    default at 88 x 60 faces labels none), and the search among keep-outs is then skipped."""
    width, depth, _ = size
    hull = poly.convex_hull
    if hull.geom_type != "Polygon":             # an empty or degenerate outline holds nothing
        return False
    pts = np.asarray(hull.exterior.coords)
    gaps = np.sqrt(((pts[:, None, :] - pts[None, :, :]) ** 2).sum(axis=-1))
    if float(gaps.max()) < width:
        return False
    return not poly.buffer(-(margin + 0.5 * depth)).is_empty


def _fit(region, inner, width: float, depth: float, angle: float, centroid: np.ndarray) -> np.ndarray | None:
    """The centre of a ``width × depth`` box at ``angle`` inside ``region`` (candidates on a grid over ``inner``,
    the region shrunk by half the depth): the centroid when the box fits there, else among the candidates within
    10 % of the largest clearance the one nearest the centroid; ``None`` when none fits."""
    import shapely

    if inner.is_empty:
        return None
    a = np.radians(angle)
    u, v = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
    shapely.prepare(region)
    if shapely.within(shapely.polygons(_box(centroid, width, depth, angle)), region):
        return centroid                     # the usual case (a convex pane): no search
    x0, y0, x1, y1 = inner.bounds
    step = max(0.25 * depth, np.hypot(x1 - x0, y1 - y0) / 60.0)
    gx, gy = np.meshgrid(np.arange(x0, x1 + step, step), np.arange(y0, y1 + step, step))
    pts = np.c_[gx.ravel(), gy.ravel()]
    pts = pts[shapely.contains_xy(inner, pts[:, 0], pts[:, 1])]
    if not len(pts):
        return None
    hw, hd = 0.5 * width, 0.5 * depth
    corners = (pts[:, None, :] + np.array([-hw, hw, hw, -hw])[None, :, None] * u
               + np.array([-hd, -hd, hd, hd])[None, :, None] * v)
    boxes = shapely.polygons(corners)
    ok = np.flatnonzero(shapely.within(boxes, region))
    if not len(ok):
        return None
    # clearance to the region's edge: the rings of its polygonal parts (the boundary of a geometry collection —
    # what a difference can leave — is not defined and would measure NaN everywhere)
    rings = [r for g in shapely.get_parts(region) if g.geom_type == "Polygon"
             for r in (g.exterior, *g.interiors)]
    if not rings:
        return pts[ok[int(np.argmin(np.linalg.norm(pts[ok] - centroid, axis=1)))]]
    room = np.nan_to_num(shapely.distance(boxes[ok], shapely.multilinestrings(rings)), nan=0.0)
    good = ok[room >= 0.9 * room.max()]
    return pts[good[int(np.argmin(np.linalg.norm(pts[good] - centroid, axis=1)))]]


def _placed(lines: list[TextLine], centre: np.ndarray, height: float, angle: float, fits: bool) -> LabelPlacement:
    width, depth, offsets = block_size(lines, height)
    a = np.radians(angle)
    v = np.array([-np.sin(a), np.cos(a)])
    placed = tuple(PlacedLine(ln, centre + off * v, height * ln.scale, angle) for ln, off in zip(lines, offsets))
    return LabelPlacement(placed, _box(centre, width, depth, angle), fits)

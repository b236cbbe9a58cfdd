"""Drawings for installers as SVG: a key plan, elevations and one sheet per node type.

Views are parallel projections of the structure in mm.  A view is given by its viewing direction ``d``
(3,) and up vector ``u``; its picture coordinates are ``(X·r, X·u)`` with ``r = d × u`` (plan: ``d = −z``,
``u = +y``; front elevation: ``d = +y``; side elevation: ``d = +x``; both ``u = +z``).  Panels are drawn back to
front (painter's order by ``X·d``).

Labels.  Every label is placed with :func:`fabrication.marking.place_label`: reading from the bottom
or the right edge (rotation in (−45°, 135°]), its box (``LABEL_CHAR_WIDTH`` text heights per character, 1.5 heights deep, larger than the
monospace glyphs drawn) inside the projected panel shrunk by a margin, clear of the beam labels placed before
it.  On the key plan beam part ids sit on the middle edge of each piece, along it; a beam label that would overlap
another is moved to the next edge out from the middle.  Text height scales with the panel (a fraction of the
short side of its projected outline).  The key plan labels every panel and beam piece — at its place, or, where
panels overlap in plan and a label finds no room, in a list below the view; an elevation labels the
beam plates seen broadside (:data:`BROADSIDE`) on their projected faces, nearest first, and the panels facing
the viewer (:data:`FACING`) whose label fits at the beam labels' height — a roof seen from the side shows its
panels edge-on, so those are found on the key plan.

Node sheets: the node's plates seen along its axis (plate traces ``a × n`` with their thickness and part
ids), the angles between them, a slot detail (width, length, plate depth) and the list of the type's nodes
with their beams, angles and slot widths.  Text is drawn in the monospace font ``DejaVu Sans Mono``.

Files are plain SVG 1.1 written with :mod:`xml.etree.ElementTree` (no drawing library), deterministic.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .contract import one_line
from .marking import LABEL_CHAR_WIDTH, TextLine, place_label, upright_deg

SVG_NS = "http://www.w3.org/2000/svg"
FONT = "DejaVu Sans Mono, monospace"
FACING = 0.15
"""An elevation labels a panel whose projected area is at least this fraction of its true area (and whose label
fits at the height of the beam labels)."""

BROADSIDE = 0.7
"""An elevation labels a beam plate seen broadside: ``|n·d|`` at least this (n the plate's plane normal)."""

VIEWS = {
    "plan": (np.array([0.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.0])),
    "front": (np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])),
    "side": (np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])),
}
"""View name → (viewing direction, up)."""

VIEW_TITLES = {"plan": "Key plan (view from above)", "front": "Elevation looking north (+y)",
               "side": "Elevation looking east (+x)"}


@dataclass(frozen=True)
class DrawnText:
    """A text of a drawing: part id (or ``""``), text, centre in picture mm, height mm, rotation (degrees, CCW)."""

    part_id: str
    text: str
    centre: np.ndarray
    height: float
    rotation_deg: float
    box: np.ndarray


def project(points: np.ndarray, view: str) -> np.ndarray:
    """``(..., 3)`` points → ``(..., 2)`` picture coordinates of ``view``."""
    d, u = VIEWS[view]
    r = np.cross(d, u)
    p = np.asarray(points, dtype=float)
    return np.stack([p @ r, p @ u], axis=-1)


def _fmt(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".")


class SvgSheet:
    """An SVG document in picture millimetres (``y`` up; flipped into SVG's ``y`` down on output): a picture
    point ``(x, y)`` is drawn at ``(x − x0, y1 − y)``, with ``x0 y1`` recorded in the root's ``data-frame``."""

    def __init__(self, bounds: tuple[float, float, float, float], width_px: float, title: str):
        x0, y0, x1, y1 = bounds
        self.x0, self.y1 = x0, y1
        w, h = x1 - x0, y1 - y0
        self.root = ET.Element("svg", {"xmlns": SVG_NS, "version": "1.1", "width": _fmt(width_px),
                                       "height": _fmt(width_px * h / w), "viewBox": f"0 0 {_fmt(w)} {_fmt(h)}",
                                       "font-family": FONT, "data-frame": f"{x0!r} {y1!r}"})
        ET.SubElement(self.root, "title").text = one_line(title)   # XML 1.0 admits no control characters
        ET.SubElement(self.root, "rect", {"x": "0", "y": "0", "width": _fmt(w), "height": _fmt(h), "fill": "white"})
        self.texts: list[DrawnText] = []

    def extend_down(self, by: float) -> None:
        """Make the picture ``by`` mm taller at the bottom (for a legend below the view)."""
        _, _, w, h = (float(x) for x in self.root.get("viewBox", "0 0 1 1").split())
        px = float(self.root.get("width", "1"))
        self.root.set("viewBox", f"0 0 {_fmt(w)} {_fmt(h + by)}")
        self.root.set("height", _fmt(px * (h + by) / w))
        bg = self.root.find("rect")
        if bg is not None:
            bg.set("height", _fmt(h + by))

    def xy(self, p: np.ndarray) -> tuple[float, float]:
        return float(p[0] - self.x0), float(self.y1 - p[1])

    def polygon(self, pts: np.ndarray, fill: str, stroke: str, width: float, **extra: str) -> None:
        q = " ".join("{:.1f},{:.1f}".format(*self.xy(p)) for p in pts)
        ET.SubElement(self.root, "polygon", {"points": q, "fill": fill, "stroke": stroke,
                                             "stroke-width": _fmt(width), **extra})

    def line(self, pts: np.ndarray, stroke: str, width: float, **extra: str) -> None:
        q = " ".join("{:.1f},{:.1f}".format(*self.xy(p)) for p in pts)
        ET.SubElement(self.root, "polyline", {"points": q, "fill": "none", "stroke": stroke,
                                              "stroke-width": _fmt(width), **extra})

    def text(self, text: str, centre: np.ndarray, height: float, rotation_deg: float = 0.0, part_id: str = "",
             fill: str = "#102a43", anchor: str = "middle") -> DrawnText:
        """A text centred on ``centre`` (``anchor="start"``: starting there), font size ``height``."""
        text = one_line(text)                      # XML 1.0 admits no control characters
        x, y = self.xy(centre)
        attrs = {"x": _fmt(x), "y": _fmt(y), "font-size": _fmt(height), "text-anchor": anchor,
                 "dominant-baseline": "central", "fill": fill}
        if rotation_deg:
            attrs["transform"] = f"rotate({_fmt(-rotation_deg)} {_fmt(x)} {_fmt(y)})"
        if part_id:
            attrs["data-part"] = part_id
        el = ET.SubElement(self.root, "text", attrs)
        el.text = text
        w = LABEL_CHAR_WIDTH * len(text) * height
        a = np.radians(rotation_deg)
        ux, vy = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
        lo = {"start": 0.0, "end": -w}.get(anchor, -0.5 * w)
        box = np.array([centre + lo * ux - 0.75 * height * vy, centre + (lo + w) * ux - 0.75 * height * vy,
                        centre + (lo + w) * ux + 0.75 * height * vy, centre + lo * ux + 0.75 * height * vy])
        drawn = DrawnText(part_id, text, np.asarray(centre, dtype=float), height, rotation_deg, box)
        self.texts.append(drawn)
        return drawn

    def tostring(self) -> str:
        ET.indent(self.root, space=" ")
        return ET.tostring(self.root, encoding="unicode", xml_declaration=False) + "\n"


# -- views ----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ViewResult:
    """An SVG view and what it shows: ``labelled`` part ids, ``unfit`` ids drawn at the smallest height."""

    svg: str
    labelled: tuple[str, ...]
    unfit: tuple[str, ...]
    texts: tuple[DrawnText, ...]


def _short_side(poly) -> float:
    rect = np.asarray(poly.minimum_rotated_rectangle.exterior.coords)[:3]
    return float(min(np.linalg.norm(rect[1] - rect[0]), np.linalg.norm(rect[2] - rect[1])))


def _beam_label_slots(top3: np.ndarray, view: str) -> list[tuple[np.ndarray, float, int]]:
    """Candidate places of a beam label along a piece's top edge ``(p, 3)``: ``(centre, angle, edge)`` for
    each edge, the middle edge first."""
    q = project(top3, view)
    k = len(q) - 1
    order = sorted(range(k), key=lambda e: abs(e - 0.5 * (k - 1)))
    out = []
    for e in order:
        a, b = q[e], q[e + 1]
        if np.linalg.norm(b - a) < 1e-6:
            continue
        out.append((0.5 * (a + b), upright_deg(float(np.degrees(np.arctan2(b[1] - a[1], b[0] - a[0])))), e))
    return out


def view_svg(view: str, panels: Sequence, plates: Sequence, title: str, width_px: float = 2400.0) -> ViewResult:
    """The key plan (``view="plan"``) or an elevation (``"front"``, ``"side"``) as SVG.

    Parameters
    ----------
    panels : objects with ``part_id`` and ``outline_3d() -> (k, 3)`` (:class:`~fabrication.panels.Panel`)
    plates : beam plates (:class:`~fabrication.beams.plates.BeamPlate`: ``part_id``, ``frame``, ``top``,
        ``bottom``, ``family``)
    """
    from shapely import STRtree
    from shapely.geometry import Polygon

    d, _ = VIEWS[view]
    outl = [np.asarray(p.outline_3d(), dtype=float) for p in panels]
    proj = [project(o, view) for o in outl]
    pts = np.concatenate(proj + [project(p.frame.to3d(p.top), view) for p in plates])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = float(max(hi - lo))
    pad = 0.04 * span
    head = 0.05 * span
    bounds = (float(lo[0] - pad), float(lo[1] - pad), float(hi[0] + pad), float(hi[1] + pad + 2.0 * head))
    sheet = SvgSheet(bounds, width_px, title)
    normals = []
    for o in outl:
        c = o - o.mean(axis=0)
        n = np.cross(c[2 % len(c)] - c[0], c[3 % len(c)] - c[1])
        normals.append(n / max(np.linalg.norm(n), 1e-12))
    facing_ratio = np.array([abs(float(n @ d)) for n in normals])
    plan = view == "plan"
    show = np.ones(len(panels), dtype=bool) if plan else facing_ratio >= FACING
    if not plan:                      # facing the viewer: the outward normal points back at the viewer
        show &= np.array([float(n @ d) < 0 for n in normals])
    depth = np.array([float(o.mean(axis=0) @ d) for o in outl])
    for k in np.argsort(-depth):
        sheet.polygon(proj[k], "#dbe9f6" if show[k] else "#f1f4f7", "#4a6fa5", 0.0015 * span)
    for p in plates:
        colour = "#b5541c" if p.family == 0 else "#1f5f9e"
        sheet.line(project(p.frame.to3d(p.top), view), colour, 0.002 * span)
    edge = [float(np.median(np.linalg.norm(np.diff(q, axis=0), axis=1))) for q in outl]
    beam_h = (0.07 if plan else 0.045) * float(np.median(edge)) if edge else 0.01 * span
    if plates and not plan:
        beam_h = min(beam_h, 0.25 * float(np.median([p.depth for p in plates])))
    placed: list[np.ndarray] = []
    labelled: list[str] = []
    unfit: list[str] = []
    tree_polys: list = []

    def clear(box: np.ndarray) -> bool:
        b = Polygon(box)
        return not any(b.intersects(q) for q in tree_polys)

    if plan:
        for p in plates:
            for centre, angle, _ in _beam_label_slots(p.frame.to3d(p.top), view):
                w = LABEL_CHAR_WIDTH * len(p.part_id) * beam_h
                a = np.radians(angle)
                u, v = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
                box = np.array([centre - 0.5 * w * u - 0.75 * beam_h * v, centre + 0.5 * w * u - 0.75 * beam_h * v,
                                centre + 0.5 * w * u + 0.75 * beam_h * v, centre - 0.5 * w * u + 0.75 * beam_h * v])
                if clear(box):
                    sheet.text(p.part_id, centre, beam_h, angle, p.part_id,
                               fill="#5a2a0a" if p.family == 0 else "#0b3a66")
                    tree_polys.append(Polygon(box))
                    placed.append(box)
                    labelled.append(p.part_id)
                    break
            else:
                unfit.append(p.part_id)          # listed below the view
    else:
        # plates seen broadside (|n·d| >= BROADSIDE), nearest first, labelled on their projected face
        near_first = sorted(plates, key=lambda p: float(p.frame.origin @ d))
        for p in near_first:
            if abs(float(p.plane[:3] @ d)) < BROADSIDE:
                continue
            face = project(p.frame.to3d(p.raw_outline), view)
            fpoly = Polygon(face)
            if not fpoly.is_valid or fpoly.area <= 0:
                continue
            short = _short_side(fpoly)
            where = place_label(face, [TextLine(p.part_id, "LABEL")], margin=0.04 * short,
                                max_height=min(0.3 * short, 2.0 * beam_h), min_height=0.8 * beam_h,
                                keep_out_areas=tuple(placed))
            if where.fits:
                pl = where.lines[0]
                sheet.text(p.part_id, pl.centre, pl.height, pl.rotation_deg, p.part_id,
                           fill="#5a2a0a" if p.family == 0 else "#0b3a66")
                tree_polys.append(Polygon(where.box))
                placed.append(where.box)
                labelled.append(p.part_id)
    import shapely

    beam_boxes = tuple(placed)
    index = STRtree([Polygon(b) for b in beam_boxes]) if beam_boxes else None
    label_polys: list = []                       # panel labels placed so far (projected panels may overlap)
    for k, p in enumerate(panels):
        if not show[k]:
            continue
        poly = Polygon(proj[k])
        short = _short_side(poly)
        zone = poly.buffer(0.1 * short)
        near = tuple(beam_boxes[int(i)] for i in index.query(zone)) if index is not None else ()
        if label_polys:
            hit = shapely.intersects(np.array(label_polys, dtype=object), zone)
            near += tuple(np.asarray(label_polys[int(i)].exterior.coords)[:4] for i in np.flatnonzero(hit))
        where = place_label(proj[k], [TextLine(p.part_id, "LABEL")], margin=0.04 * short,
                            max_height=0.16 * short, min_height=0.04 * short if plan else 0.8 * beam_h,
                            keep_out_areas=near, prefer_deg=0.0)
        if not where.fits:
            if plan:
                unfit.append(p.part_id)
            continue
        pl = where.lines[0]
        sheet.text(p.part_id, pl.centre, pl.height, pl.rotation_deg, p.part_id)
        label_polys.append(Polygon(where.box))
        labelled.append(p.part_id)
    sheet.text(title, np.array([lo[0], hi[1] + pad + 1.5 * head]), 0.4 * head, 0.0, anchor="start")
    sheet_furniture(sheet, lo, hi, pad, head, view)
    if unfit:
        # parts whose label has no room at its place (panels overlapping in this view): listed below the view
        step = 1.6 * beam_h
        per_row = max(1, int((hi[0] - lo[0]) // (LABEL_CHAR_WIDTH * 12 * beam_h)))
        sheet.text("not labelled at their place (no room in this view):", np.array([lo[0], lo[1] - pad - step]),
                   beam_h, 0.0, anchor="start")
        for q, pid in enumerate(unfit):
            r, c = divmod(q, per_row)
            at = np.array([lo[0] + c * LABEL_CHAR_WIDTH * 12 * beam_h, lo[1] - pad - (r + 2) * step])
            sheet.text(pid, at, beam_h, 0.0, anchor="start")
        rows = (len(unfit) + per_row - 1) // per_row
        sheet.extend_down(pad + (rows + 2.5) * step)
    return ViewResult(sheet.tostring(), tuple(labelled), tuple(unfit), tuple(sheet.texts))


def scale_bar_length(width: float) -> float:
    """The scale bar of a view ``width`` mm wide: the largest 1, 2 or 5 × 10^k mm not over a fifth of it.

    >>> scale_bar_length(27_438.0), scale_bar_length(9_000.0), scale_bar_length(600.0)
    (5000.0, 1000.0, 100.0)
    """
    top = 0.2 * float(width)
    k = np.floor(np.log10(top))
    return float(max(m * 10.0 ** k for m in (1.0, 2.0, 5.0) if m * 10.0 ** k <= top))


def sheet_furniture(sheet: SvgSheet, lo: np.ndarray, hi: np.ndarray, pad: float, head: float, view: str) -> None:
    """The row above a view's title: a scale bar (four alternating segments, ``data-length-mm``), the extent of
    the view in mm with its axes, and on the key plan a north arrow (``+y`` is north, as the elevations' titles
    say).  Each is placed after the one before, so no text overlaps."""
    y = float(hi[1] + pad + 0.5 * head)
    width = float(hi[0] - lo[0])
    length = scale_bar_length(width)
    label = f"{length / 1000:g} m" if length >= 1000 else f"{length:g} mm"
    axes = {"plan": ("x", "y"), "front": ("x", "z"), "side": ("y", "z")}[view]
    extent = (f"extent {hi[0] - lo[0]:,.0f} mm ({axes[0]}) x {hi[1] - lo[1]:,.0f} mm ({axes[1]})"
              .replace(",", " "))
    # the text height: 0.3 of the header, less where the row would not fit the view's width (a tall, narrow view)
    h = min(0.3 * head, (width - length) / (LABEL_CHAR_WIDTH * (len(label) + len(extent)) + 5.0))
    x = float(lo[0])
    group = ET.SubElement(sheet.root, "g", {"class": "scale-bar", "data-length-mm": _fmt(length)})
    for s in range(4):
        a, b = x + s * length / 4, x + (s + 1) * length / 4
        q = " ".join("{:.1f},{:.1f}".format(*sheet.xy(np.array(p))) for p in
                     ((a, y - 0.25 * h), (b, y - 0.25 * h), (b, y + 0.25 * h), (a, y + 0.25 * h)))
        ET.SubElement(group, "polygon", {"points": q, "fill": "#102a43" if s % 2 == 0 else "white",
                                         "stroke": "#102a43", "stroke-width": _fmt(0.02 * h)})
    x += length + 0.5 * h
    sheet.text(label, np.array([x, y]), h, 0.0, anchor="start")
    x += LABEL_CHAR_WIDTH * len(label) * h + 2.0 * h
    sheet.text(extent, np.array([x, y]), h, 0.0, anchor="start")
    if view == "plan":
        tip = np.array([float(hi[0]) - 0.5 * h, y + 0.45 * head])
        arrow = np.array([tip, tip + [0.35 * h, -0.8 * head], tip + [0.0, -0.6 * head], tip + [-0.35 * h, -0.8 * head]])
        sheet.polygon(arrow, "#102a43", "#102a43", 0.02 * h, **{"class": "north-arrow"})
        sheet.text("N", np.array([float(hi[0]) - 1.6 * h, y]), h, 0.0)


# -- node sheets ----------------------------------------------------------------------------------

def direction_deg(t2: np.ndarray) -> float:
    """The direction of ``t2 (2,)`` in degrees (``atan2``), ``(−180°, 180°]``."""
    return float(np.degrees(np.arctan2(t2[1], t2[0])))


NODE_BAND = 50.0
"""Half the length of a plate's band in a node sheet's view along the axis (picture units)."""


def node_sheet_svg(ntype, depth: float, thickness: float, width_px: float = 900.0,
                   ends: dict[str, np.ndarray] | None = None) -> str:
    """One node type (:class:`~fabrication.nodetypes.NodeType`) as an SVG sheet (see module docstring).

    ``ends``: for a plate that ends at the type's representative node, the direction ``(3,)`` from the node into
    the plate — it is drawn on that side only (a corner's two plates meet in an L, not cross in an X); a plate
    running through is drawn on both sides.  Each label lies beyond its band's end, reading from the bottom or the
    right edge (:func:`~fabrication.marking.upright_deg`), inside the view's square, clear of the lines above and
    below it."""
    rep = ntype.nodes[0]
    axis = np.asarray(rep["axis"], dtype=float)
    rows = []
    for r in ntype.nodes:
        beams = " x ".join(b["part_id"] for b in r["beams"])
        dih = ", ".join(f"{p['dihedral_deg']:.2f}" for p in r.get("pairs", []) if p.get("dihedral_deg") is not None)
        sw = f"{r['slot_width_mm']:.2f}" if r.get("slot_width_mm") is not None else "-"
        rows.append(f"{r['node_id']:<7} {beams:<34} {dih:>14} {sw:>8}")
    line_h = 14.0
    table_h = line_h * (len(rows) + 1)
    height = table_h + 30.0 + 330.0 + 12.0 * max(len(rep.get("pairs", [])) - 1, 0)
    sheet = SvgSheet((0.0, 0.0, 600.0, height), width_px, f"node type {ntype.type_id}")
    top = height - 20.0
    ang_txt = ", ".join(f"{a:g}" for a in ntype.angles_deg) or "-"
    sheet.text(f"Node type {ntype.type_id}: {ntype.joint}, {len(rep['beams'])} plates, dihedral {ang_txt} deg, "
               f"{len(ntype.nodes)} nodes", np.array([10.0, top]), 11.0, anchor="start")
    sheet.text(f"axis of {rep['node_id']}: ({axis[0]:.4f}, {axis[1]:.4f}, {axis[2]:.4f}), pointing into the "
               "structure", np.array([10.0, top - 18.0]), 9.0, anchor="start")
    # plates seen along the axis: the view's square spans top − 50 … top − 290 (caption above, pairs below)
    c = np.array([150.0, top - 170.0])
    ex = np.cross(axis, [0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.cross(axis, [1.0, 0.0, 0.0])
    ex /= np.linalg.norm(ex)
    ey = np.cross(axis, ex)
    sheet.line(np.array([c - [6, 0], c + [6, 0]]), "#000", 0.8, **{"class": "node-centre"})
    sheet.line(np.array([c - [0, 6], c + [0, 6]]), "#000", 0.8, **{"class": "node-centre"})
    ends = ends or {}
    for b in rep["beams"]:
        n = np.asarray(b["plane"][:3], dtype=float)
        t = np.cross(axis, n)
        t2 = np.array([t @ ex, t @ ey])
        t2 /= max(np.linalg.norm(t2), 1e-12)
        end = ends.get(b["part_id"])
        side = None
        if end is not None and b.get("role") == "end":
            s = float(np.asarray(end, dtype=float) @ (t2[0] * ex + t2[1] * ey))
            side = 1.0 if s >= 0 else -1.0
        a, z = (c, c + NODE_BAND * side * t2) if side is not None else (c - NODE_BAND * t2, c + NODE_BAND * t2)
        half = 4.0
        nrm = np.array([-t2[1], t2[0]])
        band = np.array([a - half * nrm, z - half * nrm, z + half * nrm, a + half * nrm])
        colour = "#b5541c" if b["part_id"].startswith("B-U") else "#1f5f9e"
        sheet.polygon(band, "#f4e3d7" if colour == "#b5541c" else "#d7e6f4", colour, 0.8,
                      **{"data-part": b["part_id"], "data-role": str(b.get("role", ""))})
        # the label beyond the band's end; on a through plate the end whose direction reads from the bottom or the
        # right edge, so it reads outwards from the node
        if side is not None:
            out = side * t2
        else:
            out = t2 if abs(upright_deg(direction_deg(t2)) - direction_deg(t2)) < 1e-9 else -t2
        ang = direction_deg(out)
        shown = upright_deg(ang)
        sheet.text(b["part_id"], c + (NODE_BAND + 6.0) * out, 8.0, shown, b["part_id"],
                   anchor="start" if abs(shown - ang) < 1e-6 else "end")
    for k, p in enumerate(rep.get("pairs", [])):
        if p.get("dihedral_deg") is None:
            continue
        sheet.text(f"{p['a']} / {p['b']}: {p['dihedral_deg']:.2f} deg", np.array([10.0, top - 300.0 - 12 * k]),
                   8.0, anchor="start")
    sheet.text("plates seen along the node axis", np.array([10.0, top - 34.0]), 8.0, anchor="start")
    # slot detail
    sx, sy = 330.0, top - 260.0
    scale = 180.0 / max(depth, 1e-9)
    width = ntype.slot_width_range
    if width is not None:
        w = width[1] * scale
        body = np.array([[sx, sy], [sx + 220, sy], [sx + 220, sy + depth * scale], [sx, sy + depth * scale]])
        sheet.polygon(body, "#eef2f6", "#333", 0.8)
        slot = np.array([[sx + 110 - w / 2, sy + depth * scale], [sx + 110 - w / 2, sy + 0.5 * depth * scale],
                         [sx + 110 + w / 2, sy + 0.5 * depth * scale], [sx + 110 + w / 2, sy + depth * scale]])
        sheet.polygon(slot, "white", "#c00", 0.8)
        sheet.text("half-lap slot: row plate from the top, column from below",
                   np.array([sx - 10, sy + depth * scale + 30]), 7.0, anchor="start")
        sheet.text(f"width {width[0]:.2f}-{width[1]:.2f} mm", np.array([sx + 110 + w / 2 + 6, sy + 0.75 * depth * scale]),
                   8.0, anchor="start")
        sheet.text(f"length {0.5 * depth:g} mm", np.array([sx + 110 + w / 2 + 6, sy + 0.75 * depth * scale - 14]),
                   8.0, anchor="start")
        sheet.text(f"plate depth {depth:g} mm, thickness {thickness:g} mm", np.array([sx, sy - 12]), 8.0,
                   anchor="start")
    else:
        sheet.text(f"{ntype.joint} joint: no slots", np.array([sx, sy + 60]), 8.0, anchor="start")
        sheet.text(f"plate depth {depth:g} mm, thickness {thickness:g} mm", np.array([sx, sy + 46]), 8.0,
                   anchor="start")
    # node list
    y = table_h + 4.0
    sheet.text(f"{'node':<7} {'beams':<34} {'dihedral deg':>14} {'slot mm':>8}", np.array([10.0, y]), 9.0,
               anchor="start")
    for k, row in enumerate(rows):
        sheet.text(row, np.array([10.0, y - line_h * (k + 1)]), 9.0, anchor="start")
    return sheet.tostring()

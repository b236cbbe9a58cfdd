"""Drawings for installers as SVG: a key plan and elevations (the node sheets: :mod:`fabrication.node_sheets`).

Views are parallel projections of the structure in mm.  A view is given by its viewing direction ``d``
(3,) and up vector ``u``; its picture coordinates are ``(X·r, X·u)`` with ``r = d × u`` (plan: ``d = −z``,
``u = +y``; front elevation: ``d = +y``; side elevation: ``d = +x``; both ``u = +z``).  Panels are drawn back to
front (painter's order by ``X·d``).

Sheets.  Every drawing is one sheet of paper (:mod:`fabrication.paper`: A1 or A3, frame, title block) with the view
at a standard scale; texts are one height on paper per class, at least 2.5 mm.

Labels.  Every label is a box (``LABEL_CHAR_WIDTH`` text heights per character, 1.5 heights deep, larger than the
monospace glyphs drawn) reading from the bottom or the right edge (rotation in (−45°, 135°]), clear of every
other label and of every drawn line by half a millimetre on paper.  On the key plan a beam plate's id lies beside
the middle edge of its top line, inside the panel next to it (the next edge out from the middle where there is no
room); a panel's id inside its projected outline (:func:`fabrication.marking.place_label`).  The key plan labels
every panel and beam piece — at its place, or, where a label finds no room (panels overlapping in plan, a piece
shorter than its id), in a list below the view; an elevation labels the beam plates seen broadside
(:data:`BROADSIDE`) on their projected faces, nearest first, and the panels facing the viewer (:data:`FACING`)
whose label fits — a roof seen from the side shows its panels edge-on, so those are found on the key plan.

Files are plain SVG 1.1 written with :mod:`xml.etree.ElementTree` (no drawing library), deterministic.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .contract import one_line
from .marking import LABEL_CHAR_WIDTH, TextLine, place_label, upright_deg
from .paper import (DEFAULT_PAPER, GAP, TEXT_MM, PaperSheet, SheetInfo, drawing_area, fitting_scales,
                    paper_advice, scale_text)

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

    def extend_right(self, by: float) -> None:
        """Make the picture ``by`` mm wider on the right."""
        if by <= 0:
            return
        _, _, w, h = (float(x) for x in self.root.get("viewBox", "0 0 1 1").split())
        self.root.set("viewBox", f"0 0 {_fmt(w + by)} {_fmt(h)}")
        bg = self.root.find("rect")
        if bg is not None:
            bg.set("width", _fmt(w + by))

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
             fill: str = "#102a43", anchor: str = "middle", kind: str = "") -> DrawnText:
        """A text centred on ``centre`` (``anchor="start"``: starting there), font size ``height``; ``kind`` its
        class of text (``data-class``: ``panel``, ``beam``; all of a class are one height on paper)."""
        text = one_line(text)                      # XML 1.0 admits no control characters
        x, y = self.xy(centre)
        attrs = {"x": _fmt(x), "y": _fmt(y), "font-size": _fmt(height), "text-anchor": anchor,
                 "dominant-baseline": "central", "fill": fill}
        if rotation_deg:
            attrs["transform"] = f"rotate({_fmt(-rotation_deg)} {_fmt(x)} {_fmt(y)})"
        if part_id:
            attrs["data-part"] = part_id
        if kind:
            attrs["data-class"] = kind
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
    """An SVG sheet of a view and what it shows: ``labelled`` part ids, ``unfit`` ids listed below the view (no
    room at their place), the view's texts (model mm) and the scale's denominator."""

    svg: str
    labelled: tuple[str, ...]
    unfit: tuple[str, ...]
    texts: tuple[DrawnText, ...]
    scale: int = 0


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


def view_svg(view: str, panels: Sequence, plates: Sequence, title: str, paper: str = DEFAULT_PAPER,
             sheet: SheetInfo | None = None) -> ViewResult:
    """The key plan (``view="plan"``) or an elevation (``"front"``, ``"side"``) as one SVG sheet on ``paper``.

    The view is drawn at the first standard scale (:func:`fabrication.paper.fitting_scales`) at which it and the
    list of parts without room at their place fit the drawing area.  Labels are one height on paper per class
    (:data:`fabrication.paper.TEXT_MM`) and are placed clear of every drawn line and of each other
    (:func:`_layout`); ``sheet`` fills the title block (default: sheet 1 of 1 titled ``title``).

    Parameters
    ----------
    panels : objects with ``part_id`` and ``outline_3d() -> (k, 3)`` (:class:`~fabrication.panels.Panel`)
    plates : beam plates (:class:`~fabrication.beams.plates.BeamPlate`: ``part_id``, ``frame``, ``top``,
        ``bottom``, ``family``)
    """
    info = sheet or SheetInfo(project="", title=title, paper=paper)
    outl = [np.asarray(p.outline_3d(), dtype=float) for p in panels]
    proj = [project(o, view) for o in outl]
    pts = np.concatenate(proj + [project(p.frame.to3d(p.top), view) for p in plates])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    ax0, ay0, ax1, ay1 = drawing_area(info.paper)
    size = hi - lo
    chosen: tuple[int, _Laid, int, int] | None = None
    pad = 2.0 * VIEW_PAD_MM
    for s in fitting_scales(float(size[0]) + pad, float(size[1]) + pad, info.paper):
        laid = _layout(view, panels, plates, outl, proj, lo, hi, float(s))
        rows, per_row = _list_rows(laid.unfit, ax1 - ax0)
        listed = GAP + (rows + 1) * LIST_PITCH * TEXT_MM["note"] if rows else 0.0
        need = (hi[1] - lo[1]) / s + pad + listed
        if need <= ay1 - ay0 + 1e-9 and (hi[0] - lo[0]) / s + pad <= ax1 - ax0 + 1e-9:
            chosen = (s, laid, rows, per_row)
            break
        if listed + pad > ay1 - ay0:     # the list alone overfills the area; a smaller picture only lengthens it
            break
    if chosen is None:
        from ppfab.errors import DesignError

        raise DesignError("output.paper", f"{VIEW_TITLES[view]}: the view and the ids without room at their place "
                                          f"do not fit {info.paper} paper at any standard scale: "
                                          f"{paper_advice(info.paper)}")
    s, laid, rows, per_row = chosen
    page = PaperSheet(info, s)
    page.frame()
    x = ax0 + max(0.0, 0.5 * (ax1 - ax0 - (hi[0] - lo[0]) / s - pad))     # centred across the drawing area
    view_el = page.embed(laid.sheet.root, x, ay0, float(s))
    view_el.set("data-view", view)
    bottom = ay0 + float(view_el.get("height", "0"))
    if laid.unfit:
        h = TEXT_MM["note"]
        y = bottom + GAP + 0.5 * LIST_PITCH * h
        page.text("not labelled at their place (no room in this view):", ax0, y, "note",
                  attrs={"class": "unfit-heading"})
        col = _list_column(laid.unfit)
        for q, pid in enumerate(laid.unfit):
            r, c = divmod(q, per_row)
            page.text(pid, ax0 + c * col, y + (r + 1) * LIST_PITCH * h, "note", attrs={"data-listed": pid})
    sheet_furniture(page, lo, hi, view)
    return ViewResult(page.tostring(), laid.labelled, laid.unfit, laid.texts, int(s))


LIST_PITCH = 1.6
"""Line pitch of the list below a view, in text heights."""


VIEW_PAD_MM = 5.0
"""Paper mm kept round a view's geometry: a beam label beside an outer plate line (at most 0.75 mm off the line
and 3.75 mm deep) stays inside the picture."""


def _list_column(ids: Sequence[str]) -> float:
    """Width on paper of a column of the list of ``ids`` below a view."""
    return LABEL_CHAR_WIDTH * TEXT_MM["note"] * (max(len(i) for i in ids) + 2)


def _list_rows(ids: Sequence[str], width: float) -> tuple[int, int]:
    """``(rows, per row)`` of the list of ``ids`` below a view ``width`` mm wide on paper."""
    if not ids:
        return 0, 1
    per_row = max(1, int(width // _list_column(ids)))
    return (len(ids) + per_row - 1) // per_row, per_row


@dataclass(frozen=True)
class _Laid:
    """A view laid out at one scale: the view (model mm), what is labelled, what has no room at its place."""

    sheet: SvgSheet
    labelled: tuple[str, ...]
    unfit: tuple[str, ...]
    texts: tuple[DrawnText, ...]


def _layout(view: str, panels: Sequence, plates: Sequence, outl: list[np.ndarray], proj: list[np.ndarray],
            lo: np.ndarray, hi: np.ndarray, s: float) -> _Laid:
    """Draw the view in model mm and place its labels for the scale ``1:s``.

    Every label is a box (:func:`fabrication.marking.block_size`) clear of every other label and of every drawn
    line (panel outlines, plate lines) by half a millimetre on paper.  On the key plan a beam plate's id lies
    beside the middle edge of its top line (the next edge out from the middle when there is no room), inside the
    panel next to it; a panel's id inside its outline.  An elevation labels the plates seen broadside on their
    projected faces, nearest first, and the panels facing the viewer.  A part whose label finds no room is
    left for the list below the view (on the key plan, which names every part)."""
    from shapely import STRtree
    from shapely.geometry import LineString, Polygon

    d, _ = VIEWS[view]
    pad = VIEW_PAD_MM * s
    bounds = (float(lo[0] - pad), float(lo[1] - pad), float(hi[0] + pad), float(hi[1] + pad))
    sheet = SvgSheet(bounds, 1.0, "view")
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
        sheet.polygon(proj[k], "#dbe9f6" if show[k] else "#f1f4f7", "#4a6fa5", 0.18 * s)
    tops = [project(p.frame.to3d(p.top), view) for p in plates]
    for p, top in zip(plates, tops):
        sheet.line(top, "#b5541c" if p.family == 0 else "#1f5f9e", 0.35 * s)
    lines = [LineString(np.r_[q, q[:1]]) for q in proj] + [LineString(t) for t in tops if len(t) >= 2]
    line_tree = STRtree(lines)
    margin = 0.5 * s
    picture = Polygon([(bounds[0], bounds[1]), (bounds[2], bounds[1]), (bounds[2], bounds[3]),
                       (bounds[0], bounds[3])]).buffer(-margin, join_style="mitre")
    beam_h, panel_h = TEXT_MM["beam"] * s, TEXT_MM["panel"] * s
    label_polys: list = []
    labelled: list[str] = []
    unfit: list[str] = []

    def near_lines(zone) -> tuple[np.ndarray, ...]:
        return tuple(np.asarray(lines[int(i)].coords) for i in line_tree.query(zone))

    def near_labels(zone) -> tuple[np.ndarray, ...]:
        return tuple(np.asarray(q.exterior.coords)[:4] for q in label_polys if q.intersects(zone))

    def free(box: np.ndarray) -> bool:
        """The label box clear of every line and label and inside the picture (a beam label beside an outer plate
        line, pushed out, left the frame of the Fig. 16 example's key plan)."""
        if not picture.contains(Polygon(box)):
            return False
        b = Polygon(box).buffer(0.9 * margin, join_style="mitre")
        return not len(line_tree.query(b, predicate="intersects")) and not any(b.intersects(q) for q in label_polys)

    def put(pid: str, centre: np.ndarray, height: float, angle: float, kind: str, fill: str = "#102a43") -> None:
        drawn = sheet.text(pid, centre, height, angle, pid, fill=fill, kind=kind)
        label_polys.append(Polygon(drawn.box))
        labelled.append(pid)

    if plan:
        for p, top3 in zip(plates, (p.frame.to3d(p.top) for p in plates)):
            fill = "#5a2a0a" if p.family == 0 else "#0b3a66"
            spot = _beam_spot(top3, view, p.part_id, beam_h, margin, free)
            if spot is None:
                unfit.append(p.part_id)          # listed below the view
            else:
                put(p.part_id, spot[0], beam_h, spot[1], "beam", fill)
    else:
        # plates seen broadside (|n·d| >= BROADSIDE), nearest first, labelled on their projected face
        for p in sorted(plates, key=lambda p: float(p.frame.origin @ d)):
            if abs(float(p.plane[:3] @ d)) < BROADSIDE:
                continue
            face = project(p.frame.to3d(p.raw_outline), view)
            fpoly = Polygon(face)
            if not fpoly.is_valid or fpoly.area <= 0:
                continue
            where = place_label(face, [TextLine(p.part_id, "LABEL")], margin=margin, max_height=beam_h,
                                min_height=beam_h, keep_out=near_lines(fpoly), keep_out_areas=near_labels(fpoly))
            if where.fits and picture.contains(Polygon(where.box)):   # a plate's face may reach past the view
                pl = where.lines[0]
                put(p.part_id, pl.centre, beam_h, pl.rotation_deg, "beam",
                    "#5a2a0a" if p.family == 0 else "#0b3a66")
    for k, p in enumerate(panels):
        if not show[k]:
            continue
        poly = Polygon(proj[k])
        if not poly.is_valid:
            poly = poly.buffer(0)
        own = proj[k]
        keep = tuple(q for q in near_lines(poly) if not (len(q) == len(own) + 1 and np.allclose(q[:-1], own)))
        where = place_label(proj[k], [TextLine(p.part_id, "LABEL")], margin=margin, max_height=panel_h,
                            min_height=panel_h, keep_out=keep, keep_out_areas=near_labels(poly), prefer_deg=0.0)
        if not where.fits or not free(where.box):
            if plan:
                unfit.append(p.part_id)
            continue
        pl = where.lines[0]
        put(p.part_id, pl.centre, panel_h, pl.rotation_deg, "panel")
    return _Laid(sheet, tuple(labelled), tuple(unfit), tuple(sheet.texts))


def _beam_spot(top3: np.ndarray, view: str, text: str, height: float, margin: float,
               free) -> tuple[np.ndarray, float] | None:
    """Where a beam plate's label goes on the key plan: beside an edge of its top line (the middle edge first),
    on either side, a little further out each try, the first box ``free`` accepts; ``(centre, angle)``."""
    w = LABEL_CHAR_WIDTH * len(text) * height
    for centre, angle, _ in _beam_label_slots(top3, view):
        a = np.radians(angle)
        u, v = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
        for off in (1.5, 3.0, 5.0):
            for side in (1.0, -1.0):
                c = centre + side * (0.75 * height + off * margin) * v
                box = np.array([c - 0.5 * w * u - 0.75 * height * v, c + 0.5 * w * u - 0.75 * height * v,
                                c + 0.5 * w * u + 0.75 * height * v, c - 0.5 * w * u + 0.75 * height * v])
                if free(box):
                    return c, angle
    return None


def scale_bar_length(width: float) -> float:
    """The scale bar of a view ``width`` mm wide: the largest 1, 2 or 5 × 10^k mm not over a fifth of it.

    >>> scale_bar_length(27_438.0), scale_bar_length(9_000.0), scale_bar_length(600.0)
    (5000.0, 1000.0, 100.0)
    """
    top = 0.2 * float(width)
    k = np.floor(np.log10(top))
    return float(max(m * 10.0 ** k for m in (1.0, 2.0, 5.0) if m * 10.0 ** k <= top))


def sheet_furniture(page: PaperSheet, lo: np.ndarray, hi: np.ndarray, view: str) -> None:
    """The band left of the title block: a scale bar (four alternating segments, ``data-length-mm`` the model
    length it stands for) with its length, the extent of the view in mm with its axes, and on the key plan a
    north arrow (``+y`` is north, as the elevations' titles say), each on paper beside the one before."""
    s = float(page.scale)
    bx0, by0, bx1, _ = page.band_left()
    width = float(hi[0] - lo[0])
    length = scale_bar_length(width)
    label = f"{length / 1000:g} m" if length >= 1000 else f"{length:g} mm"
    axes = {"plan": ("x", "y"), "front": ("x", "z"), "side": ("y", "z")}[view]
    extent = (f"extent {hi[0] - lo[0]:,.0f} mm ({axes[0]}) x {hi[1] - lo[1]:,.0f} mm ({axes[1]})"
              .replace(",", " "))
    x, y = bx0 + GAP, by0 + 9.0
    group = ET.SubElement(page.root, "g", {"class": "scale-bar", "data-length-mm": _fmt(length)})
    for k in range(4):
        a, b = x + k * length / s / 4, x + (k + 1) * length / s / 4
        q = " ".join(f"{_fmt(px)},{_fmt(py)}" for px, py in ((a, y - 1.0), (b, y - 1.0), (b, y + 1.0), (a, y + 1.0)))
        ET.SubElement(group, "polygon", {"points": q, "fill": "#102a43" if k % 2 == 0 else "white",
                                         "stroke": "#102a43", "stroke-width": "0.1"})
    page.text(label, x + length / s + 2.0, y, "note")
    page.text(extent, x, by0 + 19.0, "note")
    page.text(f"scale {scale_text(int(s))} on {page.info.paper}", x, by0 + 29.0, "note")
    if view == "plan":
        ax = bx1 - GAP - 6.0
        tip = (ax, by0 + 5.0)
        q = " ".join(f"{_fmt(px)},{_fmt(py)}" for px, py in
                     (tip, (ax + 3.0, by0 + 25.0), (ax, by0 + 20.0), (ax - 3.0, by0 + 25.0)))
        ET.SubElement(page.root, "polygon", {"points": q, "fill": "#102a43", "stroke": "#102a43",
                                             "stroke-width": "0.1", "class": "north-arrow"})
        page.text("N", ax - 7.0, by0 + 15.0, "note", anchor="middle")

"""Drawing sheets on paper: ISO 216 sizes, a frame, a title block and standard scales.

Every drawing of ``drawings/`` is one sheet of a named paper size (:data:`PAPER_SIZES`, landscape; ``[output]
paper``), drawn in paper millimetres: the root ``<svg>`` is ``width="841mm" height="594mm"`` with a viewBox of the
same numbers.  Inside an ISO 5457 frame (20 mm filing margin on the left, 10 mm elsewhere; the grid reference of
:data:`GRID_FIELDS` in the margins) a band at the bottom
holds the title block (ISO 7200: project, sheet title, sheet number of total, scale, paper, units, date, the
ppfab version) on the right and the scale bar, the view's extent and the north arrow on the left; the drawing
area is the frame's inside above the band.

A view in model millimetres is embedded as a nested ``<svg class="view">`` whose viewBox is in model mm and whose
``width``/``height`` on paper are the model size divided by the scale's denominator (``data-scale``), so a
picture point ``(x, y)`` of the view lies on paper at ``(vx + (x − x0)/s, vy + (y1 − y)/s)`` (``x0 y1`` the view's
``data-frame``).  The scale is the first of :data:`STANDARD_SCALES` at which the view and what goes below it fit
the drawing area.

Text heights on paper are at least :data:`MIN_TEXT_MM` (ISO 3098 for drawings read at arm's length) and one per
class (:data:`TEXT_MM`): every panel label of a sheet is as high as every other, and so for beam labels, notes and
the title block.
"""

from __future__ import annotations

import os
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from .contract import one_line
from .marking import LABEL_CHAR_WIDTH

SVG_NS = "http://www.w3.org/2000/svg"
FONT = "DejaVu Sans Mono, monospace"

PAPER_SIZES = {"A0": (1189.0, 841.0), "A1": (841.0, 594.0), "A3": (420.0, 297.0)}
"""Paper name → (width, height) in mm, landscape (ISO 216), largest first."""

DEFAULT_PAPER = "A1"

STANDARD_SCALES = (1, 2, 5, 10, 20, 25, 50, 100, 200, 250, 500, 1000, 2000, 2500, 5000, 10000, 20000, 50000)
"""Denominators of the scales a view is drawn at (ISO 5455: 1, 2 and 5 × 10^k, and the common 1:25, 1:250)."""

GRID_FIELDS = {"A0": (24, 16), "A1": (16, 12), "A3": (8, 6)}
"""Fields of the grid reference system (ISO 5457) per paper: numbered along the top and bottom margins, lettered
along the left and right ones, so a part is found as "D7"."""

MIN_TEXT_MM = 2.5
"""The smallest text height on paper, mm (ISO 3098)."""

TEXT_MM = {"panel": 2.5, "beam": 2.5, "note": 2.5, "block": 2.5, "block_title": 3.5, "project": 5.0, "grid": 2.5}
"""Text height on paper (mm) of each class of text."""

FRAME_MARGINS = (20.0, 10.0, 10.0, 10.0)
"""Left (filing), top, right, bottom distance of the frame from the paper's edge, mm (ISO 5457)."""

BAND_HEIGHT = 38.0
"""Height of the band at the bottom of the frame holding the title block and the scale bar, mm."""

TITLE_BLOCK_WIDTH = 180.0
"""Width of the title block, mm (ISO 7200)."""

GAP = 4.0
"""Clearance on paper between the drawing area's contents (view, lists), mm."""


def paper_size(name: str) -> tuple[float, float]:
    """``(width, height)`` mm of the paper ``name``; a ``ValueError`` naming the sizes there are otherwise."""
    try:
        return PAPER_SIZES[name]
    except KeyError:
        raise ValueError(f"paper {name!r} is not a known size: use one of {', '.join(PAPER_SIZES)}") from None


def larger_paper(name: str) -> str | None:
    """The next larger paper of :data:`PAPER_SIZES` than ``name`` (by area), ``None`` for the largest.

    >>> larger_paper("A3"), larger_paper("A1"), larger_paper("A0")
    ('A1', 'A0', None)
    """
    w, h = paper_size(name)
    bigger = [(pw * ph, p) for p, (pw, ph) in PAPER_SIZES.items() if pw * ph > w * h]
    return min(bigger)[1] if bigger else None


def paper_advice(name: str) -> str:
    """What to do when a drawing does not fit the paper ``name``: the design key giving the next larger paper, or,
    on the largest, fewer and larger panels."""
    bigger = larger_paper(name)
    if bigger is not None:
        return f"use a larger paper ([output] paper = \"{bigger}\")"
    return (f"{name} is the largest paper ppfab draws on: fewer, larger panels (the geometry's faces) or shorter part "
            "ids")


def frame_box(paper: str) -> tuple[float, float, float, float]:
    """The frame's inside ``(x0, y0, x1, y1)`` on paper (SVG frame: y runs down)."""
    w, h = paper_size(paper)
    left, top, right, bottom = FRAME_MARGINS
    return left, top, w - right, h - bottom


def drawing_area(paper: str) -> tuple[float, float, float, float]:
    """The drawing area ``(x0, y0, x1, y1)`` on paper: the frame's inside above the title block's band, less
    :data:`GAP` all round."""
    x0, y0, x1, y1 = frame_box(paper)
    return x0 + GAP, y0 + GAP, x1 - GAP, y1 - BAND_HEIGHT - GAP


def fitting_scales(width: float, height: float, paper: str) -> list[int]:
    """The standard scale denominators (ascending) at which a ``width × height`` mm picture fits the drawing area;
    the largest scale listed when none does.

    >>> fitting_scales(27_438.0, 20_000.0, "A1")[:2]
    [50, 100]
    """
    x0, y0, x1, y1 = drawing_area(paper)
    out = [s for s in STANDARD_SCALES if width / s <= x1 - x0 + 1e-9 and height / s <= y1 - y0 + 1e-9]
    return out or [STANDARD_SCALES[-1]]


def scale_text(denominator: int) -> str:
    """``"1:50"``; ``0`` means a diagram that is not to scale."""
    return f"1:{denominator}" if denominator else "NTS (diagram, dimensions in mm)"


def issue_date() -> str:
    """The date in the title blocks: that of ``SOURCE_DATE_EPOCH`` (the reproducible-builds convention), else
    ``"-"`` (a build's files depend on its inputs only, never on the clock)."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH", "")
    if epoch.strip().isdigit():
        return time.strftime("%Y-%m-%d", time.gmtime(int(epoch)))
    return "-"


@dataclass(frozen=True)
class SheetInfo:
    """What a sheet's title block says (the scale is the sheet's own): project (design name), sheet title, sheet
    number of ``total``, paper size, the issue date."""

    project: str
    title: str
    number: int = 1
    total: int = 1
    paper: str = DEFAULT_PAPER
    date: str = "-"


@dataclass(frozen=True)
class PaperText:
    """A text drawn on a sheet: its class, the text, its box ``(4, 2)`` on paper (SVG frame, mm) and height."""

    kind: str
    text: str
    box: np.ndarray
    height: float


def _fmt(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".")


def text_box(x: float, y: float, text: str, height: float, rotation_deg: float = 0.0,
             anchor: str = "middle") -> np.ndarray:
    """The box ``(4, 2)`` of a text at ``(x, y)`` in an SVG frame (y down; ``rotation_deg`` counter-clockwise as
    seen, i.e. the SVG ``rotate(−θ)``): ``LABEL_CHAR_WIDTH`` heights per character, ±0.75 heights deep."""
    w = LABEL_CHAR_WIDTH * len(text) * height
    lo = {"start": 0.0, "end": -w}.get(anchor, -0.5 * w)
    a = np.radians(rotation_deg)
    u, v = np.array([np.cos(a), -np.sin(a)]), np.array([np.sin(a), np.cos(a)])
    c = np.array([x, y])
    return np.array([c + lo * u - 0.75 * height * v, c + (lo + w) * u - 0.75 * height * v,
                     c + (lo + w) * u + 0.75 * height * v, c + lo * u + 0.75 * height * v])


def fit_text(text: str, height: float, width: float) -> str:
    """``text`` cut (ending in ``~``) to what fits ``width`` mm at ``height``."""
    n = int(width // (LABEL_CHAR_WIDTH * height))
    return text if len(text) <= n else text[:max(n - 1, 0)] + "~"


class PaperSheet:
    """One sheet: the paper, its frame and title block; views embedded at a scale; texts on paper recorded."""

    def __init__(self, info: SheetInfo, scale: int):
        self.info, self.scale = info, scale
        self.width, self.height = paper_size(info.paper)
        self.root = ET.Element("svg", {"xmlns": SVG_NS, "version": "1.1", "width": f"{_fmt(self.width)}mm",
                                       "height": f"{_fmt(self.height)}mm",
                                       "viewBox": f"0 0 {_fmt(self.width)} {_fmt(self.height)}",
                                       "font-family": FONT, "data-paper": info.paper,
                                       "data-scale": str(scale)})
        ET.SubElement(self.root, "title").text = one_line(f"{info.project}: {info.title}")
        ET.SubElement(self.root, "rect", {"x": "0", "y": "0", "width": _fmt(self.width), "height": _fmt(self.height),
                                          "fill": "white"})
        self.texts: list[PaperText] = []
        self.furniture = ET.SubElement(self.root, "g", {"class": "sheet-frame"})

    # -- drawing on paper ------------------------------------------------------------------------
    def rect(self, x0: float, y0: float, x1: float, y1: float, width: float, parent: ET.Element | None = None,
             fill: str = "none", attrs: dict[str, str] | None = None) -> None:
        ET.SubElement(self.furniture if parent is None else parent, "rect",
                      {"x": _fmt(x0), "y": _fmt(y0), "width": _fmt(x1 - x0), "height": _fmt(y1 - y0), "fill": fill,
                       "stroke": "#102a43", "stroke-width": _fmt(width), **(attrs or {})})

    def line(self, pts: list[tuple[float, float]], width: float, parent: ET.Element | None = None) -> None:
        ET.SubElement(self.furniture if parent is None else parent, "polyline",
                      {"points": " ".join(f"{_fmt(x)},{_fmt(y)}" for x, y in pts), "fill": "none",
                       "stroke": "#102a43", "stroke-width": _fmt(width)})

    def text(self, text: str, x: float, y: float, kind: str, anchor: str = "start", parent: ET.Element | None = None,
             attrs: dict[str, str] | None = None) -> PaperText:
        """A text on paper at ``(x, y)`` (its middle height), of class ``kind`` (:data:`TEXT_MM`), with extra
        attributes ``attrs``."""
        text = one_line(text)
        h = TEXT_MM[kind]
        el = ET.SubElement(self.root if parent is None else parent, "text",
                           {"x": _fmt(x), "y": _fmt(y), "font-size": _fmt(h), "text-anchor": anchor,
                            "dominant-baseline": "central", "fill": "#102a43", "data-class": kind, **(attrs or {})})
        el.text = text
        placed = PaperText(kind, text, text_box(x, y, text, h, 0.0, anchor), h)
        self.texts.append(placed)
        return placed

    # -- frame and title block -------------------------------------------------------------------
    def frame(self) -> None:
        """The frame (0.7 mm) and the title block (bottom right), filled from :attr:`info`."""
        x0, y0, x1, y1 = frame_box(self.info.paper)
        self.rect(x0, y0, x1, y1, 0.7, attrs={"class": "frame"})
        self.grid_reference()
        by = y1 - BAND_HEIGHT
        self.line([(x0, by), (x1, by)], 0.35)
        bx = x1 - TITLE_BLOCK_WIDTH
        block = ET.SubElement(self.root, "g", {"class": "title-block"})
        self.rect(bx, by, x1, y1, 0.5, parent=block)
        rows = (by + 10.0, by + 18.0, by + 28.0)          # row lines: project | title | scale, sheet | date, version
        for y in rows:
            self.line([(bx, y), (x1, y)], 0.25, parent=block)
        cw = TITLE_BLOCK_WIDTH / 3
        for y_top, y_bot in ((rows[1], rows[2]), (rows[2], y1)):
            for k in (1, 2):
                self.line([(bx + k * cw, y_top), (bx + k * cw, y_bot)], 0.25, parent=block)
        info, pad = self.info, 2.0
        self.text(fit_text(info.project or "untitled", TEXT_MM["project"], TITLE_BLOCK_WIDTH - 2 * pad), bx + pad, by + 5.0,
                  "project", parent=block, attrs={"data-field": "project"})
        self.text(fit_text(info.title, TEXT_MM["block_title"], TITLE_BLOCK_WIDTH - 2 * pad), bx + pad,
                  by + 14.0, "block_title", parent=block, attrs={"data-field": "title"})
        from ppfab import __version__

        cells = (("scale", f"scale {scale_text(self.scale)}" if self.scale else "scale NTS"),
                 ("sheet", f"sheet {info.number} of {info.total}"), ("paper", f"{info.paper}, units mm"),
                 ("date", f"date {info.date}"), ("version", f"ppfab {__version__}"), ("checked", "checked:"))
        for k, (field, value) in enumerate(cells):
            r, c = divmod(k, 3)
            y = (rows[1] + rows[2]) / 2 if r == 0 else (rows[2] + y1) / 2
            self.text(fit_text(value, TEXT_MM["block"], cw - 2 * pad), bx + c * cw + pad, y, "block", parent=block,
                      attrs={"data-field": field})

    def grid_reference(self) -> None:
        """The grid reference system in the margins (ISO 5457, :data:`GRID_FIELDS`): a tick from the frame to the
        paper's edge between two fields, the field's number (along the top and bottom) or letter (along the left
        and right) midway between its ticks."""
        cols, rows = GRID_FIELDS.get(self.info.paper, (8, 6))
        x0, y0, x1, y1 = frame_box(self.info.paper)
        group = ET.SubElement(self.root, "g", {"class": "grid-reference"})
        dx, dy = (x1 - x0) / cols, (y1 - y0) / rows
        for k in range(1, cols):
            x = x0 + k * dx
            self.line([(x, 0.0), (x, y0)], 0.25, parent=group)
            self.line([(x, y1), (x, self.height)], 0.25, parent=group)
        for k in range(1, rows):
            y = y0 + k * dy
            self.line([(0.0, y), (x0, y)], 0.25, parent=group)
            self.line([(x1, y), (self.width, y)], 0.25, parent=group)
        for k in range(cols):
            x = x0 + (k + 0.5) * dx
            for y in (0.5 * y0, 0.5 * (y1 + self.height)):
                self.text(str(k + 1), x, y, "grid", anchor="middle", parent=group)
        for k in range(rows):
            y = y0 + (k + 0.5) * dy
            for x in (0.5 * x0, 0.5 * (x1 + self.width)):
                self.text("ABCDEFGHJKLMNPRSTUVWXYZ"[k], x, y, "grid", anchor="middle", parent=group)

    def band_left(self) -> tuple[float, float, float, float]:
        """The part of the bottom band left of the title block ``(x0, y0, x1, y1)`` (scale bar, extent, north)."""
        x0, _, x1, y1 = frame_box(self.info.paper)
        return x0, y1 - BAND_HEIGHT, x1 - TITLE_BLOCK_WIDTH, y1

    # -- views -------------------------------------------------------------------------------------
    def embed(self, view: ET.Element, x: float, y: float, scale: float) -> ET.Element:
        """Put the view ``view`` (an ``<svg>`` whose viewBox is in model mm) on paper with its top-left corner at
        ``(x, y)``, ``1/scale`` paper mm per model mm; returns the nested element."""
        _, _, w, h = (float(t) for t in view.get("viewBox", "0 0 1 1").split())
        view.attrib.pop("xmlns", None)
        view.set("x", _fmt(x))
        view.set("y", _fmt(y))
        view.set("width", f"{w / scale:.6g}")
        view.set("height", f"{h / scale:.6g}")
        view.set("class", "view")
        view.set("overflow", "visible")          # a nested svg clips to its box otherwise
        view.set("data-scale", f"{scale:.6g}")
        self.root.append(view)
        return view

    def tostring(self) -> str:
        ET.indent(self.root, space=" ")
        return ET.tostring(self.root, encoding="unicode", xml_declaration=False) + "\n"


def view_transform(root: ET.Element) -> list[tuple[ET.Element, np.ndarray, float]]:
    """For each nested view of a sheet (``<svg>`` inside the root): the element, its top-left corner on paper
    ``(2,)`` and its scale (model mm per paper mm, from ``width`` against the viewBox)."""
    out = []
    for el in root:
        if el.tag.endswith("svg"):
            _, _, w, _ = (float(t) for t in el.get("viewBox", "0 0 1 1").split())
            out.append((el, np.array([float(el.get("x", 0)), float(el.get("y", 0))]),
                        w / float(el.get("width", "1").removesuffix("mm"))))
    return out

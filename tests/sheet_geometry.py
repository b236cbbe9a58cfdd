"""Text boxes and drawn lines of a drawing sheet (SVG) or a DXF, measured independently of the writers: text
boxes from matplotlib's metrics of the font the drawing names (DejaVu Sans Mono), lines from the file's own
elements, all in one frame (paper mm for an SVG sheet, drawing units for a DXF)."""

from __future__ import annotations

import functools
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

NS = "{http://www.w3.org/2000/svg}"


@dataclass(frozen=True)
class Text:
    """A text: what it says, its box (shapely polygon) and height in the sheet's frame."""

    text: str
    box: object
    height: float
    element: object


@functools.lru_cache(maxsize=None)
def _advance(height: float) -> float:
    """The advance of one glyph of DejaVu Sans Mono at ``height`` (font size): matplotlib's layout of 100 M's."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath

    return float(TextPath((0, 0), "M" * 100, size=height,
                          prop=FontProperties(family="DejaVu Sans Mono")).get_extents().x1) / 100.0


def glyph_extent(text: str, height: float) -> float:
    """The advance of ``text`` in DejaVu Sans Mono (monospaced: every glyph advances alike) at ``height``."""
    assert text.strip(), "a drawing holds an empty text"
    return len(text) * _advance(round(height, 6))


def _svg_text_box(t: ET.Element, to_paper) -> Text:
    from shapely.geometry import Polygon

    h = float(t.get("font-size"))
    w = glyph_extent(t.text or "", h)
    x0 = {"start": 0.0, "end": -w}.get(t.get("text-anchor", "start"), -0.5 * w)
    local = np.array([[x0, -0.6 * h], [x0 + w, -0.6 * h], [x0 + w, 0.6 * h], [x0, 0.6 * h]])
    rot = re.findall(r"rotate\(([-0-9.e]+)", t.get("transform", ""))
    a = np.radians(float(rot[0])) if rot else 0.0
    r = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    pts = to_paper(local @ r.T + [float(t.get("x")), float(t.get("y"))])
    return Text(t.text or "", Polygon(pts), h * float(to_paper.scale), t)


class _Map:
    def __init__(self, origin=(0.0, 0.0), scale: float = 1.0):
        self.origin, self.scale = np.asarray(origin, dtype=float), scale

    def __call__(self, pts: np.ndarray) -> np.ndarray:
        return self.origin + np.asarray(pts, dtype=float) * self.scale


def _points(s: str) -> np.ndarray:
    return np.array([[float(c) for c in p.split(",")] for p in s.split()])


def svg_sheet(path) -> tuple[ET.Element, list[Text], list[tuple[object, object]]]:
    """``(root, texts, lines)`` of an SVG sheet in paper mm; ``lines`` are ``(LineString, element)`` for every
    polygon, polyline and stroked rect (the white background and unstroked fills left out)."""
    from shapely.geometry import LineString

    root = ET.parse(path).getroot()
    texts: list[Text] = []
    lines: list[tuple[object, object]] = []

    def walk(el: ET.Element, m: _Map) -> None:
        for child in el:
            tag = child.tag.removeprefix(NS)
            if tag == "svg":
                _, _, w, _ = (float(t) for t in child.get("viewBox").split())
                s = float(child.get("width").removesuffix("mm")) / w
                walk(child, _Map(m(np.array([float(child.get("x", 0)), float(child.get("y", 0))])), m.scale * s))
            elif tag == "g":
                walk(child, m)
            elif tag == "text":
                texts.append(_svg_text_box(child, m))
            elif tag in ("polygon", "polyline"):
                q = m(_points(child.get("points")))
                if tag == "polygon":
                    q = np.r_[q, q[:1]]
                lines.append((LineString(q), child))
            elif tag == "rect" and child.get("stroke") not in (None, "none"):
                x, y = float(child.get("x")), float(child.get("y"))
                w, h = float(child.get("width")), float(child.get("height"))
                q = m(np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h], [x, y]]))
                lines.append((LineString(q), child))

    walk(root, _Map())
    return root, texts, lines


def overlaps(texts: list[Text]) -> list[tuple[str, str]]:
    """Pairs of texts whose boxes overlap."""
    from shapely import STRtree

    tree = STRtree([t.box for t in texts])
    out = []
    for i, t in enumerate(texts):
        for j in tree.query(t.box, predicate="intersects"):
            if j > i:
                out.append((t.text, texts[int(j)].text))
    return out


def crossings(texts: list[Text], lines: list[tuple[object, object]]) -> list[tuple[str, str]]:
    """``(text, line element tag)`` for every text whose box a drawn line crosses or enters."""
    from shapely import STRtree

    tree = STRtree([g for g, _ in lines])
    out = []
    for t in texts:
        for j in tree.query(t.box, predicate="intersects"):
            el = lines[int(j)][1]
            out.append((t.text, el.get("data-part") or el.get("class") or el.tag.removeprefix(NS)))
    return out


def _dxf_text_box(e):
    """The box of a DXF ``TEXT`` from ezdxf's text size tools (the width of its font, cap height and
    descender), around its insertion point (left baseline) turned by its rotation."""
    from ezdxf.tools.text_size import text_size
    from shapely.geometry import Polygon

    ts = text_size(e)
    below = ts.total_height - ts.cap_height
    local = np.array([[0.0, -below], [ts.width, -below], [ts.width, ts.cap_height], [0.0, ts.cap_height]])
    a = np.radians(float(e.dxf.rotation))
    r = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    if int(e.dxf.get("text_generation_flag", 0)) & 2:        # backward text runs from its start leftwards
        local[:, 0] *= -1.0
    at = e.dxf.insert
    h, v = int(e.dxf.halign), int(e.dxf.valign)
    if h or v:                        # aligned text: placed about its alignment point (DXF group codes 72, 73)
        at = e.dxf.align_point if e.dxf.hasattr("align_point") else e.dxf.insert
        sign = -1.0 if int(e.dxf.get("text_generation_flag", 0)) & 2 else 1.0
        local = local - [sign * {0: 0.0, 1: 0.5 * ts.width, 2: ts.width, 4: 0.5 * ts.width}.get(h, 0.0),
                         {0: 0.0, 1: -below, 2: 0.5 * ts.cap_height, 3: ts.cap_height}.get(v, 0.0)]
    return Polygon(local @ r.T + np.array([float(at[0]), float(at[1])]))


def dxf_sheet(path) -> tuple[list[Text], list[tuple[object, object]]]:
    """``(texts, lines)`` of a DXF's modelspace: every ``TEXT`` (and each dimension's own text) with its box, and
    every drawn line (polyline, line, circle, arc, a dimension's lines) as ``(geometry, owner)``; a dimension's
    text carries its dimension as owner, so its own lines are its leader."""
    import ezdxf
    from shapely.geometry import LineString, Point

    doc = ezdxf.readfile(path)
    texts: list[Text] = []
    lines: list[tuple[object, object]] = []

    def add(e, owner) -> None:
        kind = e.dxftype()
        if kind == "TEXT":
            texts.append(Text(e.dxf.text, _dxf_text_box(e), float(e.dxf.height), owner))
        elif kind == "MTEXT":
            from ezdxf import bbox
            from shapely.geometry import box

            ext = bbox.extents([e])
            texts.append(Text(e.text, box(ext.extmin.x, ext.extmin.y, ext.extmax.x, ext.extmax.y),
                              float(e.dxf.char_height), owner))
        elif kind == "LWPOLYLINE":
            pts = [tuple(p[:2]) for p in e.get_points()]
            if e.closed:
                pts.append(pts[0])
            lines.append((LineString(pts), owner))
        elif kind == "LINE":
            lines.append((LineString([tuple(e.dxf.start)[:2], tuple(e.dxf.end)[:2]]), owner))
        elif kind == "CIRCLE":
            lines.append((Point(tuple(e.dxf.center)[:2]).buffer(float(e.dxf.radius), 32).exterior, owner))
        elif kind == "ARC":
            pts = [tuple(p)[:2] for p in e.flattening(0.05)]
            lines.append((LineString(pts), owner))
        elif kind == "POINT":
            return
        elif kind == "DIMENSION":
            for sub in e.virtual_entities():
                add(sub, e)

    for e in doc.modelspace():
        add(e, e)
    return texts, lines


FACE_LAYERS = {"top": ("MARK_BACK",), "back": ("MARK", "LABEL")}
"""A cutting sheet's two faces: the layers a text of each face ignores (MARK_BACK is engraved on the face
underneath, so its texts and lines never meet the top face's)."""


def dxf_problems(path) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
    """``(overlapping text pairs, (text, line layer) crossings)`` of a DXF, per face of the sheet
    (:data:`FACE_LAYERS`); a text's own dimension lines (its leader) are left out of the crossings."""
    from shapely import STRtree

    texts, lines = dxf_sheet(path)
    over: list[tuple[str, str]] = []
    cross: list[tuple[str, str]] = []
    for face, other in FACE_LAYERS.items():
        mine = [t for t in texts if (t.element.dxf.layer == "MARK_BACK") == (face == "back")]
        seen = [(g, o) for g, o in lines if o.dxf.layer not in other]
        over += overlaps(mine) if mine else []
        if not seen:
            continue
        tree = STRtree([g for g, _ in seen])
        for t in mine:
            for j in tree.query(t.box, predicate="intersects"):
                owner = seen[int(j)][1]
                if owner is not t.element:
                    cross.append((t.text, owner.dxf.layer))
    return over, cross

"""DXF cutting files (ezdxf): one flat file per stock sheet, one per part or part type, and a reader.

Layout of a cutting sheet (DESIGN.md, output contract): R2010, ``$INSUNITS`` = 4 (mm),
origin at the sheet's lower-left corner; layers

* ``SHEET`` — the stock outline, ``TRIM`` — the usable area after edge trim,
* ``CUT`` — one closed ``LWPOLYLINE`` per part in sheet coordinates, carrying XDATA under
  the application id ``PPFAB``: ``part_id=…``, ``nest_tag=…``, ``kind=…``, ``type_id=…``; a beam piece's splice
  bolt holes as ``CIRCLE`` entities (XDATA ``part_id=…``, ``hole_mm=…``),
* ``LABEL`` — part id and nest tag as TEXT (never machined),
* ``MARK`` — marking on the face that looks up from the sheet: lines (reference corner of a panel, node axes of
  a beam) and, on a beam plate, its id and face mark as TEXT (XDATA ``part_id=…``, ``mark=id|face``),
* ``MARK_BACK`` — a beam plate's underside: its node axes and its face mark (backward text).

Labels read from the bottom or the right edge of the sheet (rotation in (−45°, 135°]) and are placed inside the part, clear of its
edges, slots and node-axis lines (:mod:`fabrication.marking`).  The header carries kerf notes per cutting
process (``$CUSTOMPROPERTY`` ``PPFAB_KERF_*``); outlines are nominal.  Material and thickness are on every file
three times: the title text ends with ``material …, thickness … mm``, the header has ``PPFAB_MATERIAL`` and
``PPFAB_THICKNESS_MM`` (R2004 and later; an R12 or R2000 file has no custom properties) and each CUT outline's
XDATA ends with ``material=…``, ``thickness_mm=…`` (:data:`~fabrication.contract.STOCK_XDATA_KEYS`).

No blocks, no splines: flat geometry a CAM program reads as it is.  Files are byte-for-byte
reproducible: handles are assigned in a fixed order and ezdxf's time stamps and GUIDs are
fixed (``ezdxf.options.write_fixed_meta_data_for_testing`` while a file is built and saved).
:func:`read_sheet_dxf` re-reads a file with ``ezdxf.readfile``, audits it and extracts the
parts by their XDATA; the tests and ``ppfab verify`` use it.
"""

from __future__ import annotations

import contextlib
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ppfab.errors import VerificationError

from . import Files, writer

from ..contract import (BEVEL_LAYER, DIM_LAYER, DXF_INSUNITS_MM, DXF_OLDEST, DXF_VERSION, FACE_MARK_PATTERN, GLASS_SHEET_DIR,
                        GLASS_SHEET_PREFIX, KERF_NOTES, LAYERS, MARK_LAYERS, PLATE_SHEET_DIR, PLATE_SHEET_PREFIX,
                        REQUIRED_LAYERS, STOCK_HEADER_VARS, TYPE_DIR, TYPE_PREFIX, XDATA_APPID, dxf_text, xdata_fields,
                        sheet_file, sheet_files, stock_title, stock_xdata, thickness_text, type_file, xdata_strings)
from ..flatpart import FlatPart, Placement, place_points
from ..marking import TextLine, face_marks, face_sign, place_label

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord



@contextlib.contextmanager
def _fixed_metadata():
    import ezdxf

    old = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        yield
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = old


def sort_classes(doc) -> None:
    """ezdxf adds a CLASS per entity type in use in set order (varies with the hash seed): add them now and
    sort them, so that the CLASSES section is the same in every process."""
    classes = doc.classes
    classes.add_required_classes(doc.dxfversion)
    ordered = sorted(classes.classes.items())
    classes.classes.clear()
    classes.classes.update(ordered)


def save_doc(doc, path: str | os.PathLike) -> None:
    """Save ``doc`` with deterministic bytes (sorted classes, fixed ezdxf metadata)."""
    sort_classes(doc)
    with _fixed_metadata():
        doc.saveas(path)


def _new_doc(version: str = DXF_VERSION):
    import ezdxf

    doc = ezdxf.new(version, setup=False)
    doc.units = DXF_INSUNITS_MM                 # millimetres
    doc.header["$INSUNITS"] = DXF_INSUNITS_MM
    doc.header["$MEASUREMENT"] = 1              # metric
    for name, colour in LAYERS.items():
        doc.layers.add(name, color=colour)
    doc.appids.add(XDATA_APPID)
    return doc


def stock_of(parts: list[FlatPart]) -> tuple[str, str]:
    """``(material, thickness)`` of ``parts`` as text: their distinct values joined by ``"; "`` (one value on a
    sheet of one stock)."""
    materials = sorted({str(p.meta.get("material", "")) for p in parts})
    thicknesses = sorted({thickness_text(p.meta.get("thickness_mm", "")) for p in parts})
    return "; ".join(materials), "; ".join(thicknesses)


def add_stock(doc, msp, stock: tuple[str, str], title: str, height: float = 40.0,
              insert: tuple[float, float] = (0.0, -80.0)) -> None:
    """The title (ending with the material and thickness) on LABEL and the header custom properties."""
    text = f"{title} - {stock_title(*stock)}" if title else stock_title(*stock)
    msp.add_text(dxf_text(text), height=height, dxfattribs={"layer": "LABEL", "insert": insert})
    if doc.dxfversion >= "AC1018":
        for name, value in zip(STOCK_HEADER_VARS, stock):
            doc.header.custom_vars.append(name, dxf_text(value))


PLATE_TEXT_MAX, PANEL_TEXT_MAX = 25.0, 60.0
"""Largest text height of a label on a beam plate (engraved) and on a glass pane, mm."""


BEVEL_TEXT_MAX = 8.0
"""Largest text height of a bevel instruction on a beam plate, mm."""


def _short_side(points: np.ndarray) -> float:
    """The short side of the minimum rotated rectangle of a polygon ``(k, 2)``."""
    from shapely.geometry import Polygon

    rect = np.asarray(Polygon(points).minimum_rotated_rectangle.exterior.coords)[:3]
    return float(min(np.linalg.norm(rect[1] - rect[0]), np.linalg.norm(rect[2] - rect[1])))


def face_mark_of(part: FlatPart, mirrored: bool) -> tuple[str, str]:
    """``(up face, underside)`` marks of a beam plate placed with ``mirrored`` (:mod:`fabrication.marking`);
    ``("", "")`` for a part without a support plane."""
    frame, plane = part.meta.get("frame"), part.meta.get("plane")
    if part.kind != "beam" or not frame or plane is None:
        return "", ""
    family = {"rows": 0, "cols": 1}.get(str(part.meta.get("family", "")), 2)
    sign = face_sign(np.asarray(frame["normal"], dtype=float), np.asarray(plane, dtype=float)[:3], mirrored)
    return face_marks(family, sign)


def _label_lines(part: FlatPart, tag: str, mirrored: bool) -> tuple[list[TextLine], str]:
    """The label block of a part and the underside's face mark: a beam plate gets its id and face mark engraved
    (MARK) with the id and nest tag on LABEL; a pane its id and nest tag on LABEL."""
    text = part.label or part.part_id
    up, back = face_mark_of(part, mirrored)
    lines = [TextLine(text, "LABEL")]
    if part.kind == "beam":
        lines = [TextLine(text, "MARK")] + ([TextLine(up, "MARK")] if up else []) + [TextLine(text, "LABEL", 0.6)]
    if tag:
        lines.append(TextLine(tag, "LABEL", 0.6))
    return lines, back


class CuttingSheet:
    """Builder of one flat DXF: ``add_part`` for each placed part, then ``write(path)``.

    Parameters
    ----------
    sheet_size : (length, width) of the stock sheet, mm; ``None`` for a part file (no SHEET/TRIM)
    usable : (x0, y0, x1, y1) usable area after trim (layer TRIM), mm
    title : text written on LABEL below the sheet (sheet number, material)
    version : the DXF version written: ``R2010`` (the contract), ``R2000``, or ``R12`` (built as R2010 and
        written by the R12 exporter of :mod:`fabrication.writers._dxf_r12`)
    """

    def __init__(self, sheet_size: tuple[float, float] | None = None,
                 usable: tuple[float, float, float, float] | None = None, title: str = "",
                 version: str = DXF_VERSION, stock: tuple[str, str] | None = None,
                 title_at: tuple[float, float] = (0.0, -80.0)):
        self.version = version
        self._ctx = _fixed_metadata()
        self._ctx.__enter__()
        try:
            self.doc = _new_doc(DXF_VERSION if version == "R12" else version)
        finally:
            self._ctx.__exit__(None, None, None)
        self.msp = self.doc.modelspace()
        if sheet_size is not None:
            w, h = float(sheet_size[0]), float(sheet_size[1])
            self.msp.add_lwpolyline([(0, 0), (w, 0), (w, h), (0, h)], close=True, dxfattribs={"layer": "SHEET"})
        if usable is not None:
            x0, y0, x1, y1 = (float(v) for v in usable)
            self.msp.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True,
                                    dxfattribs={"layer": "TRIM"})
        if stock is not None:
            add_stock(self.doc, self.msp, stock, title, insert=title_at)
        elif title:
            self.msp.add_text(dxf_text(title), height=40.0, dxfattribs={"layer": "LABEL", "insert": title_at})
        if self.doc.dxfversion >= "AC1018":          # $CUSTOMPROPERTY exists from R2004 on
            self.doc.header.custom_vars.append("PPFAB_OUTLINES", "nominal: no kerf offset, the CAM compensates")
            for process, note in KERF_NOTES.items():
                self.doc.header.custom_vars.append(f"PPFAB_KERF_{process.upper()}", note)

    def add_part(self, part: FlatPart, placement: Placement | None = None,
                 keep_out: tuple[np.ndarray, ...] = ()) -> None:
        """The part's outline on CUT (with XDATA), its label on LABEL, its marks on MARK.

        With ``placement`` everything is mapped to sheet coordinates; without, the part is
        drawn in its own flat frame.  ``keep_out``: more polylines ``(p, 2)`` (sheet coordinates) the label keeps
        clear of (the dimensioned diagonals of a per-type DXF).
        """
        def to_sheet(pts: np.ndarray) -> np.ndarray:
            p = np.asarray(pts, dtype=float)
            return place_points(p, placement) if placement is not None else p

        outline = to_sheet(part.outline)
        if placement is not None and placement.mirrored:
            outline = outline[::-1]                 # keep the outline counter-clockwise
        cut = self.msp.add_lwpolyline([tuple(map(float, p)) for p in outline], close=True,
                                      dxfattribs={"layer": "CUT"})
        tag = placement.nest_tag if placement is not None else ""
        cut.set_xdata(XDATA_APPID, xdata_strings(part.part_id, tag, part.kind, part.type_id)
                      + stock_xdata(str(part.meta.get("material", "")), part.meta.get("thickness_mm", "")))
        holes = np.asarray(getattr(part, "holes", np.zeros((0, 3))), dtype=float).reshape(-1, 3)
        circles = []
        for x, y, d in holes.tolist():
            c = to_sheet(np.array([[x, y]]))[0]
            hole = self.msp.add_circle((float(c[0]), float(c[1])), 0.5 * d, dxfattribs={"layer": "CUT"})
            hole.set_xdata(XDATA_APPID, [(1000, f"part_id={part.part_id}"), (1000, f"hole_mm={d:g}")])
            t = np.linspace(0.0, 2.0 * np.pi, 17)
            circles.append(c + (0.5 * d + 1.0) * np.c_[np.cos(t), np.sin(t)])
        marks = [to_sheet(m) for m in part.marks]
        for pts in marks:
            if len(pts) >= 2:
                self.msp.add_lwpolyline([tuple(map(float, p)) for p in pts], close=False,
                                        dxfattribs={"layer": "MARK"})
        bevels = self._add_bevels(part, to_sheet, outline)
        lines, back = _label_lines(part, tag, placement.mirrored if placement is not None else False)
        short = _short_side(outline)
        cap = PLATE_TEXT_MAX if part.kind == "beam" else PANEL_TEXT_MAX
        where = place_label(outline, lines, margin=float(np.clip(0.05 * short, 2.0, 40.0)),
                            max_height=float(np.clip(0.15 * short, 2.0, cap)), min_height=2.0,
                            keep_out=(tuple(marks) + tuple(circles) + tuple(bevels) if part.kind == "beam" else ())
                            + tuple(keep_out))
        from ezdxf.enums import TextEntityAlignment

        for pl in where.lines:
            ent = self.msp.add_text(dxf_text(pl.line.text), height=pl.height,
                                    dxfattribs={"layer": pl.line.layer, "rotation": pl.rotation_deg})
            ent.set_placement(tuple(map(float, pl.centre)), align=TextEntityAlignment.MIDDLE_CENTER)
            what = "face" if re.match(FACE_MARK_PATTERN, pl.line.text) else "id"
            if pl.line.layer in MARK_LAYERS:
                ent.set_xdata(XDATA_APPID, [(1000, f"part_id={part.part_id}"), (1000, f"mark={what}")])
            if back and what == "face" and pl.line.layer == "MARK":
                under = self.msp.add_text(dxf_text(back), height=pl.height,
                                          dxfattribs={"layer": "MARK_BACK", "rotation": pl.rotation_deg,
                                                      "text_generation_flag": 2})
                under.set_placement(tuple(map(float, pl.centre)), align=TextEntityAlignment.MIDDLE_CENTER)
                under.set_xdata(XDATA_APPID, [(1000, f"part_id={part.part_id}"), (1000, "mark=face")])
        if part.kind == "beam":
            for pts in marks:
                if len(pts) >= 2:
                    self.msp.add_lwpolyline([tuple(map(float, p)) for p in pts], close=False,
                                            dxfattribs={"layer": "MARK_BACK"})

    def _add_bevels(self, part: FlatPart, to_sheet, outline: np.ndarray) -> list[np.ndarray]:
        """A beam plate's bevelled top-edge spans on layer ``BEVEL``: the raised edge as cut (an open polyline,
        XDATA ``part_id=…``, ``bevel=…``) and its instruction as TEXT along it, inside the plate
        (:class:`fabrication.beams.flat.BevelMark`); the polylines and text boxes for the label to keep clear of."""
        from ezdxf.enums import TextEntityAlignment

        from shapely.geometry import Point, Polygon

        from ..marking import upright_deg

        body = Polygon(outline)
        out = []
        for bm in getattr(part, "bevels", ()):
            pts = to_sheet(bm.line)
            edge = self.msp.add_lwpolyline([tuple(map(float, p)) for p in pts], close=False,
                                           dxfattribs={"layer": BEVEL_LAYER})
            edge.set_xdata(XDATA_APPID, [(1000, f"part_id={part.part_id}"), (1000, f"bevel={bm.text}")])
            d = pts[1] - pts[0]
            length = float(np.linalg.norm(d))
            if length <= 0:
                continue
            d = d / length
            inward = np.array([-d[1], d[0]])
            if not body.contains(Point(0.5 * (pts[0] + pts[1]) + 0.5 * inward)):
                inward = -inward                              # towards the plate's body
            height = float(np.clip(length / (len(bm.text) * 1.2), 2.0, BEVEL_TEXT_MAX))
            at = 0.5 * (pts[0] + pts[1]) + 1.2 * height * inward
            text = self.msp.add_text(dxf_text(bm.text), height=height,
                                     dxfattribs={"layer": BEVEL_LAYER,
                                                 "rotation": upright_deg(float(np.degrees(np.arctan2(d[1], d[0]))))})
            text.set_placement(tuple(map(float, at)), align=TextEntityAlignment.MIDDLE_CENTER)
            text.set_xdata(XDATA_APPID, [(1000, f"part_id={part.part_id}"), (1000, "mark=bevel")])
            half = 0.5 * len(bm.text) * 0.8 * height * d
            across = 0.6 * height * inward
            out.append(pts)
            out.append(np.array([at - half - across, at + half - across, at + half + across, at - half + across,
                                 at - half - across]))
        return out

    def write(self, path: str | os.PathLike) -> Path:
        """Save (deterministic bytes)."""
        path = Path(path)
        sort_classes(self.doc)
        with _fixed_metadata():
            if self.version == "R12":
                from ._dxf_r12 import save_r12

                save_r12(self.doc, path)
            else:
                self.doc.saveas(path)
        return path


def write_sheet_dxfs(parts: list[FlatPart], nesting, folder: str | os.PathLike, prefix: str = "sheet",
                     title: str = "", version: str = DXF_VERSION) -> list[Path]:
    """One DXF per sheet of ``nesting`` (``{prefix}_01.dxf`` …) in ``folder``; returns the paths in sheet order."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    by_id = {p.part_id: p for p in parts}
    out = []
    for k, group in enumerate(nesting.by_sheet()):
        head = f"{title} sheet {k + 1}/{nesting.sheets}".strip()
        builder = CuttingSheet(nesting.sheet_size, nesting.usable, head, version,
                               stock_of([by_id[pl.part_id] for pl in group]))
        for pl in group:
            builder.add_part(by_id[pl.part_id], pl)
        out.append(builder.write(folder / sheet_file(prefix, k + 1, nesting.sheets)))
    return out


def write_part_dxf(part: FlatPart, path: str | os.PathLike, title: str = "", version: str = DXF_VERSION,
                   dimensions: bool = False) -> Path:
    """One part flat in its own coordinates (for processors whose optimiser re-nests); with ``dimensions`` its
    edges and diagonals dimensioned on layer DIM (:mod:`fabrication.writers._dxf_dimensions`)."""
    from ._dxf_dimensions import dimension_keep_out, title_position

    p = np.asarray(part.outline, dtype=float)
    builder = CuttingSheet(None, None, title, version, stock_of([part]),
                           title_at=title_position(p) if dimensions else (0.0, -80.0))
    builder.add_part(part, None, keep_out=dimension_keep_out(p) if dimensions else ())
    if dimensions:
        from ._dxf_dimensions import add_pane_dimensions

        add_pane_dimensions(builder.doc, part.outline)
    return builder.write(path)


# -- reading back ----------------------------------------------------------------------------------
@dataclass
class DXFPart:
    """A part found on CUT: its XDATA fields and its outline ``(k, 2)``."""

    part_id: str
    nest_tag: str
    points: np.ndarray
    closed: bool
    xdata: dict


@dataclass(frozen=True)
class DXFHole:
    """A CIRCLE on CUT inside a part: the part id of its XDATA, its centre ``(2,)`` and diameter."""

    part_id: str
    centre: np.ndarray
    diameter: float


@dataclass
class DXFText:
    """A TEXT entity: its layer, text, middle-centre point ``(2,)`` (the insert for left-aligned text), height,
    rotation (degrees), ``backward`` (mirrored, text generation flag 2) and its XDATA fields."""

    layer: str
    text: str
    centre: np.ndarray
    height: float
    rotation_deg: float
    backward: bool
    xdata: dict
    insert: np.ndarray | None = None
    """The insertion point ``(2,)`` as written (``centre`` is the alignment point of aligned text)."""


@dataclass(frozen=True)
class DXFDimension:
    """A DIMENSION entity: its handle, its text override (``""`` or ``"<>"``: the measurement), its measurement and
    the text of its rendered geometry block (the MTEXT a reader that ignores dimensions shows; ``None`` without)."""

    handle: str
    override: str
    measurement: float
    shown: str | None


@dataclass
class DXFContent:
    """What :func:`read_sheet_dxf` found in a file."""

    path: Path
    dxfversion: str
    insunits: int
    layers: list[str]
    parts: list[DXFPart]
    sheet_outline: np.ndarray | None
    trim_outline: np.ndarray | None
    labels: list[str]
    marks: int
    audit_errors: list[str] = field(default_factory=list)
    other_entities: list[str] = field(default_factory=list)
    dimensions: list[float] = field(default_factory=list)
    texts: list[DXFText] = field(default_factory=list)
    back_marks: int = 0
    mark_lines: list[tuple[str, np.ndarray]] = field(default_factory=list)
    dimension_texts: list[DXFDimension] = field(default_factory=list)
    bevels: list[tuple[str, np.ndarray]] = field(default_factory=list)
    """The bevelled edges on layer ``BEVEL``: part id and the polyline ``(2, 2)``."""
    bevel_texts: list[DXFText] = field(default_factory=list)
    """The bevel instructions on layer ``BEVEL`` (not part labels)."""
    circles: list[DXFHole] = field(default_factory=list)
    """Every CIRCLE on ``CUT``, with or without a part id (a cover plate's bolt holes have none)."""
    custom_vars: dict[str, str] = field(default_factory=dict)
    """The header's custom properties (R2004 and newer; empty for older files)."""

    @property
    def holes(self) -> list[DXFHole]:
        """The CIRCLEs on ``CUT`` inside a part (with a part id in their XDATA)."""
        return [c for c in self.circles if c.part_id]


def read_sheet_dxf(path: str | os.PathLike) -> DXFContent:
    """Re-read a DXF with ``ezdxf.readfile``, audit it and extract parts, outlines, labels and marks."""
    import ezdxf
    from ezdxf.entities import LWPolyline, Polyline

    path = Path(path)
    doc = ezdxf.readfile(path)
    auditor = doc.audit()
    errors = [f"{e.code}: {e.message}" for e in auditor.errors]
    parts, labels, marks, other, dims = [], [], 0, [], []
    texts: list[DXFText] = []
    mark_lines: list[tuple[str, np.ndarray]] = []
    dim_texts: list[DXFDimension] = []
    circles: list[DXFHole] = []
    bevel_lines: list[tuple[str, np.ndarray]] = []
    bevel_texts: list[DXFText] = []
    back = 0
    sheet = trim = None
    e: Any
    for e in doc.modelspace():
        layer = e.dxf.layer
        kind = e.dxftype()
        if kind == "POLYLINE" and isinstance(e, Polyline) and not (e.is_3d_polyline or e.is_poly_face_mesh
                                                                  or e.is_polygon_mesh):
            kind = "LWPOLYLINE"                 # an R12 file: a 2D POLYLINE is what LWPOLYLINE is in R2000+
            pts = np.array([(p[0], p[1]) for p in e.points()], dtype=float)
        elif kind == "LWPOLYLINE":
            assert isinstance(e, LWPolyline), "ezdxf reads LWPOLYLINE entities as LWPolyline"
            pts = np.array([(p[0], p[1]) for p in e.get_points("xy")], dtype=float)
        if kind == "LWPOLYLINE":
            if layer == "CUT":
                x = xdata_fields(e)
                parts.append(DXFPart(x.get("part_id", ""), x.get("nest_tag", ""), pts, bool(e.is_closed), x))
            elif layer == "SHEET":
                sheet = pts
            elif layer == "TRIM":
                trim = pts
            elif layer == "MARK":
                marks += 1
                mark_lines.append((layer, pts))
            elif layer == "MARK_BACK":
                back += 1
                mark_lines.append((layer, pts))
            elif layer == BEVEL_LAYER:
                bevel_lines.append((xdata_fields(e).get("part_id", ""), pts))
            else:
                other.append(f"LWPOLYLINE on {layer}")
        elif kind == "TEXT" and layer == BEVEL_LAYER:
            align = e.dxf.get("align_point") if e.dxf.get("halign", 0) or e.dxf.get("valign", 0) else None
            where = align if align is not None else e.dxf.insert
            bevel_texts.append(DXFText(layer, e.dxf.text, np.array([where[0], where[1]], dtype=float),
                                       float(e.dxf.height), float(e.dxf.get("rotation", 0.0)), False, xdata_fields(e)))
        elif kind == "TEXT" and layer in ("LABEL",) + MARK_LAYERS:
            if layer == "LABEL":
                labels.append(e.dxf.text)
            align = e.dxf.get("align_point") if e.dxf.get("halign", 0) or e.dxf.get("valign", 0) else None
            where = align if align is not None else e.dxf.insert
            ins = e.dxf.insert
            texts.append(DXFText(layer, e.dxf.text, np.array([where[0], where[1]], dtype=float), float(e.dxf.height),
                                 float(e.dxf.get("rotation", 0.0)), bool(int(e.dxf.get("text_generation_flag", 0)) & 2),
                                 xdata_fields(e), np.array([ins[0], ins[1]], dtype=float)))
        elif kind == "CIRCLE" and layer == "CUT":
            c = e.dxf.center
            circle = DXFHole(xdata_fields(e).get("part_id", ""), np.array([c[0], c[1]], dtype=float),
                             2.0 * float(e.dxf.radius))
            circles.append(circle)
            if not circle.part_id:
                other.append(f"{kind} on {layer}")
        elif kind == "DIMENSION" and layer == DIM_LAYER:
            dims.append(float(e.get_measurement()))
            block = doc.blocks.get(e.dxf.get("geometry", "")) if e.dxf.get("geometry") else None
            shown = next((str(getattr(x, "text", "")) for x in block if x.dxftype() == "MTEXT"), None) if block is not None else None
            dim_texts.append(DXFDimension(str(e.dxf.handle), str(e.dxf.get("text", "")), dims[-1], shown))
        else:
            other.append(f"{kind} on {layer}")
    custom = {str(k): str(val) for k, val in doc.header.custom_vars} if doc.dxfversion >= "AC1018" else {}
    return DXFContent(path, doc.dxfversion, int(doc.header.get("$INSUNITS", 0)), [la.dxf.name for la in doc.layers],
                      parts, sheet, trim, labels, marks, errors, other, dims, texts, back, mark_lines, dim_texts,
                      bevel_lines, bevel_texts, circles, custom)


def check_sheet_dxf(path: str | os.PathLike, require_sheet: bool = True, oldest: str = DXF_OLDEST) -> DXFContent:
    """:func:`read_sheet_dxf` plus the contract: raises :class:`VerificationError` naming the first problem.

    Audit without errors; ``oldest`` (R2000) or newer; ``$INSUNITS`` = 4 (R12 has none); the five layers exist;
    every CUT entity a closed LWPOLYLINE (POLYLINE in R12) with ``part_id`` and (on a sheet) ``nest_tag`` XDATA;
    part ids unique; nothing but those, TEXT and dimensions on DIM; on a sheet, the SHEET and TRIM outlines.
    """
    c = read_sheet_dxf(path)
    sheet_contract(c, Path(path).name, require_sheet, oldest)
    return c


def sheet_contract(c: DXFContent, name: str, require_sheet: bool = True, oldest: str = DXF_OLDEST) -> None:
    """The contract of :func:`check_sheet_dxf` on content already read: raises :class:`VerificationError` naming
    the first problem of file ``name``."""
    if c.audit_errors:
        raise VerificationError(f"{name}: ezdxf audit found {len(c.audit_errors)} error(s): {c.audit_errors[0]}")
    if c.dxfversion < oldest:
        raise VerificationError(f"{name}: DXF version {c.dxfversion} is older than {oldest}")
    if c.insunits != DXF_INSUNITS_MM and c.dxfversion > "AC1009":
        raise VerificationError(f"{name}: $INSUNITS is {c.insunits}, expected 4 (mm)")
    missing = [la for la in REQUIRED_LAYERS if la not in c.layers]
    if missing:
        raise VerificationError(f"{name}: layers {missing} are missing")
    if c.other_entities:
        raise VerificationError(f"{name}: unexpected entity {c.other_entities[0]}")
    seen = set()
    for p in c.parts:
        if not p.closed:
            raise VerificationError(f"{name}: CUT outline of {p.part_id or '?'} is not closed")
        if not p.part_id or (require_sheet and not p.nest_tag):
            raise VerificationError(f"{name}: a CUT outline has no PPFAB part_id/nest_tag XDATA")
        if p.part_id in seen:
            raise VerificationError(f"{name}: part {p.part_id} is cut twice")
        seen.add(p.part_id)
    if require_sheet and (c.sheet_outline is None or c.trim_outline is None):
        raise VerificationError(f"{name}: SHEET or TRIM outline missing")


def write_type_dxfs(parts: list[FlatPart], folder: str | os.PathLike, prefix: str = TYPE_PREFIX,
                    version: str = DXF_VERSION, dimensions: bool = False) -> dict[str, str]:
    """One flat DXF per type (its first part, in its own coordinates, with ``dimensions`` its edges and
    diagonals dimensioned); returns ``type_id → file name``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out: dict[str, str] = {}
    for p in parts:
        tid = p.type_id or p.part_id
        if tid in out:
            continue
        name = type_file(tid, prefix)
        write_part_dxf(p, folder / name, title=f"{tid} ({p.part_id})", version=version,
                       dimensions=dimensions)
        out[tid] = name
    return out


def dxf_files(build: "BuildRecord") -> Files:
    """One cutting sheet per glass and per plate sheet (:func:`~fabrication.contract.sheet_files`)."""
    nest = build.nesting
    return {"glass_sheets": sheet_files(GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, nest.glass.sheets),
            "beam_sheets": sheet_files(PLATE_SHEET_DIR, PLATE_SHEET_PREFIX, nest.plates.sheets)}


def type_dxf_files(parts: list[FlatPart], directory: str = TYPE_DIR) -> list[str]:
    """The per-type DXFs of ``parts`` (one per type, the first part of each, in part order)."""
    seen: dict[str, str] = {}
    for p in parts:
        seen.setdefault(p.type_id or p.part_id, f"{directory}/{type_file(p.type_id or p.part_id)}")
    return list(seen.values())


@writer("dxf", order=30, declare=dxf_files)
def write_dxf_files(build: "BuildRecord", out: Path, files: Files) -> str:
    """Glass and beam-plate cutting sheets (the per-type DXFs: :func:`write_dxf_type_files`)."""
    name = build.design.info.name
    nest = build.nesting
    glass = write_sheet_dxfs(list(nest.glass_parts), nest.glass, out / GLASS_SHEET_DIR, GLASS_SHEET_PREFIX,
                             f"{name} glass")
    plates = write_sheet_dxfs(list(nest.beam_parts), nest.plates, out / PLATE_SHEET_DIR, PLATE_SHEET_PREFIX,
                              f"{name} beam plates")
    return f"{len(glass)} glass + {len(plates)} plate sheets"


def dxf_type_files(build: "BuildRecord") -> Files:
    """The per-type DXFs: one per panel type (:func:`type_dxf_files`)."""
    return {"panel_type_dxfs": type_dxf_files(list(build.nesting.glass_parts))}


@writer("dxf_types", order=35, declare=dxf_type_files, enabled=lambda design: design.output.per_type_dxf)
def write_dxf_type_files(build: "BuildRecord", out: Path, files: Files) -> str:
    """With ``[output] per_type_dxf``, one flat DXF per panel type (in a second process on two cores,
    :mod:`fabrication.writers._parallel`)."""
    types = write_type_dxfs(list(build.nesting.glass_parts), out / TYPE_DIR,
                            dimensions=build.design.output.type_dimensions)
    return f"{len(types)} panel types"

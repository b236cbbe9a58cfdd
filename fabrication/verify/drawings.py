"""The installers' drawings (``drawings/*.svg``): each parses as SVG (``xml.etree``), the key plan names every
part of ``parts.csv`` in its text, every node with plates is on exactly one node sheet, and no two labels of a
view overlap (their ``data-part`` texts' boxes, :data:`fabrication.marking.LABEL_CHAR_WIDTH` per character).

Every sheet (views, node sheets, the erection drawing) is on a named paper (:mod:`fabrication.paper`): its size
and viewBox are the paper's in mm, it has a frame and a title block naming the project, the sheet, its number of
the total and the scale; every text is at least :data:`fabrication.paper.MIN_TEXT_MM` high on paper, every
label of one class (``data-class``: panel, beam) as high as the others, inside the frame, and no two texts of a
sheet overlap on paper.

Every panel polygon of a view (key plan, elevations) is where the source puts it: each pane's outline (its mesh
face inset by half the gap, :func:`._solids.reference_outline`) projected into the view
(:func:`fabrication.drawings.project`) and drawn in the picture frame the root's ``data-frame`` records, within
the drawing's 0.1 mm rounding; every pane drawn, one polygon per pane.  An attribute that is not a number (a text's position, a
polygon's points, the frame) is a finding naming the file and the element, never an error."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np

from ..contract import view_file
from . import Verification, check

_SVG = "{http://www.w3.org/2000/svg}"
POLYGON_TOL = 0.08
"""How far (picture mm) a drawn corner may be from the projected source: the drawing rounds each coordinate to 0.1 mm."""


def svg_texts(path) -> list[ET.Element]:
    """The ``<text>`` elements of an SVG file (raises ``ET.ParseError`` / ``ValueError`` when it is no SVG)."""
    root = ET.parse(path).getroot()
    if root.tag != f"{_SVG}svg":
        raise ValueError(f"root element is {root.tag}, not svg")
    return list(root.iter(f"{_SVG}text"))


def label_boxes(texts: list[ET.Element], bad: list[str] | None = None) -> list[tuple[str, object]]:
    """``(part id, box polygon)`` of every part label (``data-part``), in SVG coordinates; a label whose
    position, size or rotation is not a number is left out (and described in ``bad`` when given)."""
    import numpy as np
    from shapely.geometry import Polygon

    from ..marking import LABEL_CHAR_WIDTH

    out = []
    for t in texts:
        pid = t.get("data-part")
        if not pid:
            continue
        try:
            x, y, h = float(t.get("x", 0)), float(t.get("y", 0)), float(t.get("font-size", 0))
            rot = re.findall(r"rotate\(([-0-9.e]+)", t.get("transform", ""))
            a = np.radians(float(rot[0])) if rot else 0.0
        except ValueError:
            if bad is not None:
                bad.append(pid)
            continue
        if not np.isfinite([x, y, h, a]).all():
            if bad is not None:
                bad.append(pid)
            continue
        w = LABEL_CHAR_WIDTH * len(t.text or "") * h
        x0 = 0.0 if t.get("text-anchor") == "start" else -0.5 * w
        local = np.array([[x0, -0.5 * h], [x0 + w, -0.5 * h], [x0 + w, 0.5 * h], [x0, 0.5 * h]])
        r = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        out.append((pid, Polygon(local @ r.T + [x, y])))
    return out


@check("drawings")
def check_drawings(v: Verification) -> None:
    from shapely import STRtree

    files = v.manifest.get("files", {})
    views, sheets = files.get("drawings"), files.get("node_sheets")
    if views is None and sheets is None and not files.get("erection_drawing"):
        return
    # the key plan names the panels and the beam plates (glazing strips and splice plates are on their beams)
    parts = {r["part_id"] for r in (v.parts or []) if r.get("kind") in ("panel", "beam")}
    texts: dict[str, list[ET.Element]] = {}
    for rel in list(views or []) + list(sheets or []):
        try:
            texts[rel] = svg_texts(v.folder / rel)
        except (OSError, ET.ParseError, ValueError) as exc:
            v.error(rel, "", f"cannot be read as SVG: {exc}")
    plan = next((rel for rel in views or [] if rel.endswith(view_file("plan"))), None)
    if plan is None:
        v.error("manifest.json", "files.drawings", "no key plan")
    elif plan in texts:
        named = {t.text for t in texts[plan]}
        missing = sorted(parts - named)
        if missing:
            v.error(plan, missing[0], f"{len(missing)} part id(s) are not on the key plan: {', '.join(missing[:5])}")
    for rel in list(views or []) + list(sheets or []) + ([files["erection_drawing"]]
                                                          if files.get("erection_drawing") else []):
        if rel in texts or rel == files.get("erection_drawing"):
            check_sheet(v, rel)
    for rel in views or []:
        bad: list[str] = []
        boxes = label_boxes(texts.get(rel, []), bad)
        for pid in bad:
            v.error(rel, pid, "label's x, y, font-size or rotation is not a number")
        tree = STRtree([b for _, b in boxes])
        for i, (pid, b) in enumerate(boxes):
            for j in tree.query(b, predicate="intersects"):
                if j > i:
                    v.error(rel, pid, f"label overlaps the label of {boxes[int(j)][0]}")
    for rel in views or []:
        view = next((name for name in ("plan", "front", "side") if rel.endswith(view_file(name))), None)
        if view is not None and rel in texts:
            _check_view_polygons(v, rel, view)
    if files.get("erection_drawing"):
        _check_erection_drawing(v, files["erection_drawing"], files.get("erection_csv"))
    if files.get("drawings_pdf"):
        sheets_all = list(views or []) + ([files["erection_drawing"]] if files.get("erection_drawing") else []) + \
            list(sheets or [])
        check_pdf(v, files["drawings_pdf"], sheets_all)
    wanted = {r["node_id"] for r in (v.nodes or []) if r.get("beams")}
    count: dict[str, int] = {}
    for rel in sheets or []:
        for t in texts.get(rel, []):
            m = re.match(r"(N\d+) ", t.text or "")
            if m:
                count[m.group(1)] = count.get(m.group(1), 0) + 1
    bad = sorted(n for n in wanted if count.get(n, 0) != 1)
    if sheets is not None and bad:
        v.error("drawings/nodes", bad[0], f"{len(bad)} node(s) are not on exactly one node sheet: "
                                          f"{', '.join(bad[:5])}")


PDF_PAGE = re.compile(rb"/Type\s*/Page\b(?!s)")
PDF_MEDIA_BOX = re.compile(rb"/MediaBox\s*\[\s*([-0-9.]+)\s+([-0-9.]+)\s+([-0-9.]+)\s+([-0-9.]+)\s*\]")


def check_pdf(v: Verification, rel: str, sheets: list[str]) -> None:
    """``drawings.pdf`` read as bytes (its page objects are not compressed): a page per sheet of the set, and the
    pages' sizes (``MediaBox``, points) those of the sheets' paper (their ``viewBox`` in mm), as a multiset."""
    try:
        data = (v.folder / rel).read_bytes()
    except OSError as exc:
        v.error(rel, "", f"cannot be read: {exc}")
        return
    if not data.startswith(b"%PDF-"):
        v.error(rel, "", "is not a PDF file (no %PDF- header)")
        return
    pages = len(PDF_PAGE.findall(data))
    boxes = sorted((round((float(x1) - float(x0)) * 25.4 / 72.0), round((float(y1) - float(y0)) * 25.4 / 72.0))
                   for x0, y0, x1, y1 in PDF_MEDIA_BOX.findall(data))
    want = []
    for sheet in sheets:
        try:
            _, _, w, h = (float(t) for t in ET.parse(v.folder / sheet).getroot().get("viewBox", "").split())
        except (OSError, ET.ParseError, ValueError):
            continue                                        # reported by the sheet's own check
        want.append((round(w), round(h)))
    if pages != len(sheets):
        v.error(rel, "pages", f"{pages} page(s) for {len(sheets)} sheet(s) of the drawing set")
    elif boxes != sorted(want):
        v.error(rel, "pages", f"page sizes {boxes[:3]} … (mm) are not the sheets' paper sizes {sorted(want)[:3]} …")


def view_element(root: ET.Element) -> ET.Element:
    """The view of a sheet: the nested ``<svg>`` holding the picture frame (``data-frame``), else the root."""
    if root.get("data-frame") is not None:
        return root
    return next((el for el in root if el.tag == f"{_SVG}svg" and el.get("data-frame") is not None), root)


def paper_texts(root: ET.Element) -> list[tuple[ET.Element, float, object]]:
    """``(text element, height on paper mm, box polygon on paper)`` of every text of a sheet (nested views mapped
    by their ``x``, ``y`` and the ratio of ``width`` to the viewBox's); ``ValueError`` on a non-number."""
    from shapely.geometry import Polygon

    from ..marking import LABEL_CHAR_WIDTH

    out: list[tuple[ET.Element, float, object]] = []

    def walk(el: ET.Element, origin: np.ndarray, scale: float) -> None:
        for child in el:
            if child.tag == f"{_SVG}svg":
                _, _, w, _ = (float(t) for t in child.get("viewBox", "").split())
                s = float(child.get("width", "").removesuffix("mm")) / w
                at = origin + scale * np.array([float(child.get("x", 0)), float(child.get("y", 0))])
                walk(child, at, scale * s)
            elif child.tag == f"{_SVG}g":
                walk(child, origin, scale)
            elif child.tag == f"{_SVG}text":
                x, y, h = float(child.get("x", 0)), float(child.get("y", 0)), float(child.get("font-size", 0))
                rot = re.findall(r"rotate\(([-0-9.e]+)", child.get("transform", ""))
                a = np.radians(float(rot[0])) if rot else 0.0
                w = LABEL_CHAR_WIDTH * len(child.text or "") * h
                x0 = {"start": 0.0, "end": -w}.get(child.get("text-anchor", "start"), -0.5 * w)
                local = np.array([[x0, -0.5 * h], [x0 + w, -0.5 * h], [x0 + w, 0.5 * h], [x0, 0.5 * h]])
                r = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
                pts = origin + scale * (local @ r.T + [x, y])
                if not np.isfinite(pts).all() or not np.isfinite(h):
                    raise ValueError(f"text {child.text!r} has a position or size that is not a number")
                out.append((child, h * scale, Polygon(pts)))

    walk(root, np.zeros(2), 1.0)
    return out


def check_sheet(v: Verification, rel: str) -> None:
    """The sheet ``rel`` on its paper: size, frame, title block, text heights, texts inside the frame and apart
    (module docstring)."""
    from shapely import STRtree
    from shapely.geometry import box

    from ..paper import MIN_TEXT_MM, PAPER_SIZES, frame_box

    try:
        root = ET.parse(v.folder / rel).getroot()
    except (OSError, ET.ParseError) as exc:
        v.error(rel, "", f"cannot be read as SVG: {exc}")
        return
    paper = root.get("data-paper", "")
    if paper not in PAPER_SIZES:
        v.error(rel, "svg data-paper", f"{paper!r} is not a paper size ({', '.join(PAPER_SIZES)})")
        return
    w, h = PAPER_SIZES[paper]
    size = (root.get("width", ""), root.get("height", ""), root.get("viewBox", ""))
    want = (f"{w:g}mm", f"{h:g}mm", f"0 0 {w:g} {h:g}")
    if size != want:
        v.error(rel, "svg", f"width, height, viewBox {size} are not {paper} paper {want}")
    if not any(el.get("class") == "frame" for el in root.iter(f"{_SVG}rect")):
        v.error(rel, "frame", "sheet has no frame")
    fields = {t.get("data-field"): t.text or "" for g in root.iter(f"{_SVG}g") if g.get("class") == "title-block"
              for t in g.iter(f"{_SVG}text")}
    for name in ("project", "title", "sheet", "scale"):
        if not fields.get(name):
            v.error(rel, "title block", f"title block has no {name}")
    if fields.get("sheet") and not re.fullmatch(r"sheet \d+ of \d+", fields["sheet"]):
        v.error(rel, "title block", f"sheet field {fields['sheet']!r} is not 'sheet N of M'")
    try:
        texts = paper_texts(root)
    except ValueError as exc:
        v.error(rel, "text", str(exc))
        return
    inside, paper_box = box(*frame_box(paper)), box(0.0, 0.0, w, h)
    heights: dict[str, set[float]] = {}
    for el, ph, b in texts:
        name = (el.text or "")[:40]
        if ph < MIN_TEXT_MM - 0.005:                  # the sheet writes sizes to 6 digits
            v.error(rel, name, f"text is {ph:.2f} mm high on paper, under {MIN_TEXT_MM:g} mm")
        if el.get("data-class") == "grid":         # the grid reference lies in the margins
            if not paper_box.contains(b):
                v.error(rel, name, "grid reference leaves the paper")
        elif not inside.contains(b):
            v.error(rel, name, "text leaves the frame")
        if el.get("data-class") in ("panel", "beam"):
            heights.setdefault(el.get("data-class", ""), set()).add(round(ph, 2))
    for kind, hs in sorted(heights.items()):
        if len(hs) > 1:
            v.error(rel, f"{kind} labels", f"{kind} labels are {len(hs)} heights on paper "
                                          f"({', '.join(f'{x:g}' for x in sorted(hs))} mm), not one")
    tree = STRtree([b for _, _, b in texts])
    for i, (el, _, b) in enumerate(texts):
        for j in tree.query(b, predicate="intersects"):
            if j > i:
                v.error(rel, (el.text or "")[:40], f"text overlaps {(texts[int(j)][0].text or '')[:40]!r} on paper")


def _points(text: str) -> np.ndarray:
    """The ``points`` attribute of a polygon as ``(k, 2)``; ``ValueError`` when it is not pairs of numbers."""
    pts = np.array([[float(c) for c in pair.split(",")] for pair in text.split()], dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 3 or not np.isfinite(pts).all():
        raise ValueError("not three or more x,y pairs")
    return pts


def _check_view_polygons(v: Verification, rel: str, view: str) -> None:
    """Every panel polygon of the view ``rel`` where the pane's outline projects (module docstring)."""
    from scipy.spatial import cKDTree

    from ..drawings import project
    from ._shapes import cyclic_distance
    from ._solids import reference_outline

    root = view_element(ET.parse(v.folder / rel).getroot())
    try:
        x0, y1 = (float(t) for t in root.get("data-frame", "").split())
    except ValueError:
        v.error(rel, "svg data-frame", f"{root.get('data-frame')!r} is not two numbers (the picture frame)")
        return
    want: list[tuple[str, np.ndarray]] = []
    for row in (v.parts or []):
        if row.get("kind") != "panel":
            continue
        ref = reference_outline(v, row)
        if ref is not None:
            q = project(ref, view)
            want.append((row["part_id"], np.c_[q[:, 0] - x0, y1 - q[:, 1]]))
    if not want:
        return
    tree = cKDTree(np.array([w.mean(axis=0) for _, w in want]))
    k = min(8, len(want))                        # panes behind each other in an elevation project close together
    drawn: set[str] = set()
    count = 0
    furniture = {id(p) for g in root.iter(f"{_SVG}g") if g.get("class") == "scale-bar"
                 for p in g.iter(f"{_SVG}polygon")}
    panes = [el for el in root.iter(f"{_SVG}polygon") if id(el) not in furniture and el.get("class") != "north-arrow"]
    for n, el in enumerate(panes, start=1):                # the scale bar and the north arrow are no panes
        count += 1
        try:
            pts = _points(el.get("points", ""))
        except ValueError:
            v.error(rel, f"polygon {n}", f"points {el.get('points', '')[:60]!r} are not x,y numbers")
            continue
        near = np.atleast_1d(tree.query(pts.mean(axis=0), k=k)[1]).tolist()
        gaps = [cyclic_distance(want[j][1], pts) for j in near]
        hits = [want[j][0] for j, g in zip(near, gaps) if g <= POLYGON_TOL]
        drawn.update(hits)
        if not hits:
            gap, pid = gaps[0], want[near[0]][0]
            off = f"{gap:.3g} mm" if np.isfinite(gap) else f"{len(pts)} corners for {len(want[near[0]][1])},"
            v.error(rel, pid, f"polygon {n} nearest this pane is {off} from where its mesh face (inset by half the "
                              "gap) projects")
    for pid, _ in want:
        if pid not in drawn:
            v.error(rel, pid, "pane is drawn nowhere its outline projects")
    if count != len(want):
        v.error(rel, "polygons", f"{count} polygons for {len(want)} panes")


def _check_erection_drawing(v: Verification, rel: str, table: str | None) -> None:
    """The erection drawing parses as SVG and each of its part polygons (``data-part``, ``data-step``) is a part
    of the erection sequence (``erection.csv``) drawn once, at its step there."""
    from . import read_csv

    try:
        root = ET.parse(v.folder / rel).getroot()
    except (OSError, ET.ParseError) as exc:
        v.error(rel, "", f"cannot be read as SVG: {exc}")
        return
    if root.tag != f"{_SVG}svg":
        v.error(rel, "", f"root element is {root.tag}, not svg")
        return
    try:
        steps = {r.get("part_id", ""): r.get("step", "") for r in read_csv(v.folder / table)} if table else {}
    except (OSError, ValueError) as exc:
        v.error(table or rel, "", f"cannot be read ({exc})")
        return
    seen: set[str] = set()
    for n, el in enumerate(root.iter(f"{_SVG}polygon"), start=1):
        pid, step = el.get("data-part"), el.get("data-step")
        if pid is None:
            continue
        if pid in seen:
            v.error(rel, pid, f"part is drawn twice (polygon {n})")
        seen.add(pid)
        if table and pid not in steps:
            v.error(rel, pid, f"polygon {n} names a part that is not in {table}")
        elif table and step != steps[pid]:
            v.error(rel, pid, f"polygon {n} is drawn at step {step!r}, {table} erects the part at step {steps[pid]!r}")

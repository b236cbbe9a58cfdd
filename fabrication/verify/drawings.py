"""The installers' drawings (``drawings/*.svg``): each parses as SVG (``xml.etree``), the key plan names every
part of ``parts.csv`` in its text, every node with plates is on exactly one node sheet, and no two labels of a
view overlap (their ``data-part`` texts' boxes, :data:`fabrication.marking.LABEL_CHAR_WIDTH` per character).

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


@check("drawings", 80)
def check_drawings(v: Verification) -> None:
    from shapely import STRtree

    files = v.data.get("manifest", {}).get("files", {})
    views, sheets = files.get("drawings"), files.get("node_sheets")
    if views is None and sheets is None and not files.get("erection_drawing"):
        return
    # the key plan names the panels and the beam plates (glazing strips and splice plates are on their beams)
    parts = {r["part_id"] for r in v.data.get("parts", []) if r.get("kind") in ("panel", "beam")}
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
    wanted = {r["node_id"] for r in v.data.get("nodes", []) if r.get("beams")}
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

    root = ET.parse(v.folder / rel).getroot()
    try:
        x0, y1 = (float(t) for t in root.get("data-frame", "").split())
    except ValueError:
        v.error(rel, "svg data-frame", f"{root.get('data-frame')!r} is not two numbers (the picture frame)")
        return
    want: list[tuple[str, np.ndarray]] = []
    for row in v.data.get("parts", []):
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

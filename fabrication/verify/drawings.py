"""The installers' drawings (``drawings/*.svg``): each parses as SVG (``xml.etree``), the key plan names every
part of ``parts.csv`` in its text, every node with plates is on exactly one node sheet, and no two labels of a
view overlap (their ``data-part`` texts' boxes, :data:`fabrication.marking.LABEL_CHAR_WIDTH` per character)."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

from ..contract import view_file
from . import Verification, check

_SVG = "{http://www.w3.org/2000/svg}"


def svg_texts(path) -> list[ET.Element]:
    """The ``<text>`` elements of an SVG file (raises ``ET.ParseError`` / ``ValueError`` when it is no SVG)."""
    root = ET.parse(path).getroot()
    if root.tag != f"{_SVG}svg":
        raise ValueError(f"root element is {root.tag}, not svg")
    return list(root.iter(f"{_SVG}text"))


def label_boxes(texts: list[ET.Element]) -> list[tuple[str, object]]:
    """``(part id, box polygon)`` of every part label (``data-part``), in SVG coordinates."""
    import numpy as np
    from shapely.geometry import Polygon

    from ..marking import LABEL_CHAR_WIDTH

    out = []
    for t in texts:
        pid = t.get("data-part")
        if not pid:
            continue
        x, y, h = float(t.get("x", 0)), float(t.get("y", 0)), float(t.get("font-size", 0))
        rot = re.findall(r"rotate\(([-0-9.e]+)", t.get("transform", ""))
        a = np.radians(float(rot[0])) if rot else 0.0
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
    if views is None and sheets is None:
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
        boxes = label_boxes(texts.get(rel, []))
        tree = STRtree([b for _, b in boxes])
        for i, (pid, b) in enumerate(boxes):
            for j in tree.query(b, predicate="intersects"):
                if j > i:
                    v.error(rel, pid, f"label overlaps the label of {boxes[int(j)][0]}")
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

"""One installer's sheet per node type, as SVG (:mod:`fabrication.drawings` draws the views).

Node sheets: the node's plates seen along its axis (plate traces ``a × n`` with their thickness and part
ids), the angles between them, a slot detail (width, length, plate depth) and the list of the type's nodes
with their beams, angles and slot widths.  Text is drawn in the monospace font ``DejaVu Sans Mono``.
Labels follow the rules of the views (:mod:`fabrication.drawings`).
"""

from __future__ import annotations

import numpy as np

from .drawings import LIST_PITCH, SvgSheet
from .marking import LABEL_CHAR_WIDTH, upright_deg
from .paper import DEFAULT_PAPER, GAP, TEXT_MM, PaperSheet, SheetInfo, drawing_area, paper_advice


def direction_deg(t2: np.ndarray) -> float:
    """The direction of ``t2 (2,)`` in degrees (``atan2``), ``(−180°, 180°]``."""
    return float(np.degrees(np.arctan2(t2[1], t2[0])))


NODE_BAND = 50.0
"""Half the length of a plate's band in a node sheet's view along the axis (picture units)."""


NODE_UNIT_MM = 0.36
"""Paper mm per picture unit of a node sheet's diagram: its smallest text (7 units) is 2.52 mm high on paper."""


def node_rows(ntype) -> list[str]:
    """The rows of a node type's node list (node, beams, dihedral angles, slot width)."""
    rows = []
    for r in ntype.nodes:
        beams = " x ".join(b["part_id"] for b in r["beams"])
        dih = ", ".join(f"{p['dihedral_deg']:.2f}" for p in r.get("pairs", []) if p.get("dihedral_deg") is not None)
        sw = f"{r['slot_width_mm']:.2f}" if r.get("slot_width_mm") is not None else "-"
        rows.append(f"{r['node_id']:<7} {beams:<34} {dih:>14} {sw:>8}")
    return rows


NODE_TABLE_HEAD = f"{'node':<7} {'beams':<34} {'dihedral deg':>14} {'slot mm':>8}"


NODE_LABEL_HEIGHT = 8.0
"""Text height of a plate's id in a node sheet's diagram (picture units)."""


def _label_reach(ntype) -> float:
    """How far from the node centre a node sheet's plate ids reach (picture units, at least 130): the band, the
    gap, the longest id's box and its half depth."""
    longest = max([len(b["part_id"]) for b in ntype.nodes[0]["beams"]] + [1])
    return max(130.0, NODE_BAND + 6.0 + LABEL_CHAR_WIDTH * NODE_LABEL_HEIGHT * longest + 0.75 * NODE_LABEL_HEIGHT)


def _diagram_height(ntype) -> float:
    """Height of a node sheet's diagram (picture units): captions, the plates' square (twice the ids' reach) and
    the list of angle pairs under it."""
    return 100.0 + 2.0 * _label_reach(ntype) + 12.0 * max(len(ntype.nodes[0].get("pairs", [])) - 1, 0)


def _table_slots(ntype, paper: str, diagram_w: float) -> list[tuple[float, float, int]]:
    """The columns of the node list on paper beside and below the diagram: ``(x, y_top, rows)`` each."""
    ax0, ay0, ax1, ay1 = drawing_area(paper)
    h = TEXT_MM["note"]
    pitch = LIST_PITCH * h
    width = LABEL_CHAR_WIDTH * h * (max([len(NODE_TABLE_HEAD)] + [len(r) for r in node_rows(ntype)]) + 2)
    dw, dh = diagram_w * NODE_UNIT_MM, _diagram_height(ntype) * NODE_UNIT_MM
    out = []
    for x0, y0, x1 in ((ax0 + dw + GAP, ay0, ax1), (ax0, ay0 + dh + GAP, ax0 + max(dw, width))):
        n = int((ay1 - y0) // pitch) - 1
        x = x0
        while x + width <= x1 + 1e-9 and n > 0:
            out.append((x, y0, n))
            x += width
    return out


def node_pages(ntype, depth: float, thickness: float, paper: str = DEFAULT_PAPER) -> list[range]:
    """The node list of a type split into sheets: the row indices each sheet holds (each sheet shows the
    diagram, the list in columns beside and below it)."""
    n = len(ntype.nodes)
    cap = sum(k for _, _, k in _table_slots(ntype, paper, _node_picture(ntype, depth, thickness, None)[1]))
    if cap <= 0:
        from ppfab.errors import DesignError

        raise DesignError("output.paper", f"{paper} paper has no room for the node list of {ntype.type_id}: "
                                          f"{paper_advice(paper)}")
    return [range(a, min(a + cap, n)) for a in range(0, max(n, 1), cap)]


def node_sheet_svg(ntype, depth: float, thickness: float, ends: dict[str, np.ndarray] | None = None,
                   paper: str = DEFAULT_PAPER, sheet: SheetInfo | None = None, rows: range | None = None) -> str:
    """One node type (:class:`~fabrication.nodetypes.NodeType`) as an SVG sheet (see module docstring): the
    diagram (not to scale, :data:`NODE_UNIT_MM`) at the top left of the drawing area, the node list (``rows``,
    default all, :func:`node_pages`) in columns beside and below it.

    ``ends``: for a plate that ends at the type's representative node, the direction ``(3,)`` from the node into
    the plate — it is drawn on that side only (a corner's two plates meet in an L, not cross in an X); a plate
    running through is drawn on both sides.  Each label lies beyond its band's end, reading from the bottom or the
    right edge (:func:`~fabrication.marking.upright_deg`), inside the view's square, clear of the lines above and
    below it."""
    info = sheet or SheetInfo(project="", title=f"node type {ntype.type_id}", paper=paper)
    pic, right = _node_picture(ntype, depth, thickness, ends)
    page = PaperSheet(info, 0)
    page.frame()
    ax0, ay0, _, _ = drawing_area(info.paper)
    page.embed(pic.root, ax0, ay0, 1.0 / NODE_UNIT_MM).set("data-view", "node")
    table = node_rows(ntype)
    wanted = list(rows if rows is not None else range(len(table)))
    pitch = LIST_PITCH * TEXT_MM["note"]
    for x, y, n in _table_slots(ntype, info.paper, right):
        if not wanted:
            break
        page.text(NODE_TABLE_HEAD, x, y + 0.5 * pitch, "note", attrs={"class": "node-table-head"})
        for k in range(min(n, len(wanted))):
            page.text(table[wanted[k]], x, y + (k + 1.5) * pitch, "note", attrs={"data-node-row": "1"})
        wanted = wanted[n:]
    if wanted:
        raise ValueError(f"the node list of {ntype.type_id} does not fit its sheet: split it with node_pages()")
    return page.tostring()


def _node_picture(ntype, depth: float, thickness: float,
                  ends: dict[str, np.ndarray] | None) -> tuple[SvgSheet, float]:
    """The diagram of a node sheet (picture units, :data:`NODE_UNIT_MM`) and its width."""
    rep = ntype.nodes[0]
    axis = np.asarray(rep["axis"], dtype=float)
    height = _diagram_height(ntype)
    pic = SvgSheet((0.0, 0.0, 600.0, height), 1.0, f"node type {ntype.type_id}")
    top = height - 20.0
    ang_txt = ", ".join(f"{a:g}" for a in ntype.angles_deg) or "-"
    pic.text(f"Node type {ntype.type_id}: {ntype.joint}, {len(rep['beams'])} plates, dihedral {ang_txt} deg, "
             f"{len(ntype.nodes)} nodes", np.array([10.0, top]), 11.0, anchor="start")
    pic.text(f"axis of {rep['node_id']}: ({axis[0]:.4f}, {axis[1]:.4f}, {axis[2]:.4f}), pointing into the "
             "structure", np.array([10.0, top - 18.0]), 9.0, anchor="start")
    # plates seen along the axis: the square of side 2 reach round c (caption above, pairs below)
    reach = _label_reach(ntype)                # the ids' boxes stay inside the square of side 2 reach round c
    c = np.array([max(150.0, reach + 10.0), top - 40.0 - reach])
    ex = np.cross(axis, [0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.cross(axis, [1.0, 0.0, 0.0])
    ex /= np.linalg.norm(ex)
    ey = np.cross(axis, ex)
    pic.line(np.array([c - [6, 0], c + [6, 0]]), "#000", 0.8, **{"class": "node-centre"})
    pic.line(np.array([c - [0, 6], c + [0, 6]]), "#000", 0.8, **{"class": "node-centre"})
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
        pic.polygon(band, "#f4e3d7" if colour == "#b5541c" else "#d7e6f4", colour, 0.8,
                    **{"data-part": b["part_id"], "data-role": str(b.get("role", ""))})
        # the label beyond the band's end; on a through plate the end whose direction reads from the bottom or the
        # right edge, so it reads outwards from the node
        if side is not None:
            out = side * t2
        else:
            out = t2 if abs(upright_deg(direction_deg(t2)) - direction_deg(t2)) < 1e-9 else -t2
        ang = direction_deg(out)
        shown = upright_deg(ang)
        pic.text(b["part_id"], c + (NODE_BAND + 6.0) * out, NODE_LABEL_HEIGHT, shown, b["part_id"],
                 anchor="start" if abs(shown - ang) < 1e-6 else "end")
    for k, p in enumerate(rep.get("pairs", [])):
        if p.get("dihedral_deg") is None:
            continue
        pic.text(f"{p['a']} / {p['b']}: {p['dihedral_deg']:.2f} deg", np.array([10.0, c[1] - reach - 14.0 - 12 * k]),
                 8.0, anchor="start")
    pic.text("plates seen along the node axis", np.array([10.0, top - 34.0]), 8.0, anchor="start")
    # slot detail
    sx, sy = max(330.0, c[0] + reach + 40.0), top - 260.0
    scale = 180.0 / max(depth, 1e-9)
    width = ntype.slot_width_range
    if width is not None:
        w = width[1] * scale
        body = np.array([[sx, sy], [sx + 220, sy], [sx + 220, sy + depth * scale], [sx, sy + depth * scale]])
        pic.polygon(body, "#eef2f6", "#333", 0.8)
        slot = np.array([[sx + 110 - w / 2, sy + depth * scale], [sx + 110 - w / 2, sy + 0.5 * depth * scale],
                         [sx + 110 + w / 2, sy + 0.5 * depth * scale], [sx + 110 + w / 2, sy + depth * scale]])
        pic.polygon(slot, "white", "#c00", 0.8)
        pic.text("half-lap slot: row plate from the top, column from below",
                 np.array([sx - 10, sy + depth * scale + 30]), 7.0, anchor="start")
        # the slot's width and length beside the body (clear of its outline), at the slot's height
        pic.text(f"slot width {width[0]:.2f}-{width[1]:.2f} mm", np.array([sx + 226, sy + 0.75 * depth * scale]),
                 8.0, anchor="start")
        pic.text(f"slot length {0.5 * depth:g} mm", np.array([sx + 226, sy + 0.75 * depth * scale - 14]),
                 8.0, anchor="start")
        pic.text(f"plate depth {depth:g} mm, thickness {thickness:g} mm", np.array([sx, sy - 12]), 8.0,
                 anchor="start")
    else:
        pic.text(f"{ntype.joint} joint: no slots", np.array([sx, sy + 60]), 8.0, anchor="start")
        pic.text(f"plate depth {depth:g} mm, thickness {thickness:g} mm", np.array([sx, sy + 46]), 8.0,
                 anchor="start")
    right = max([600.0] + [float(t.box[:, 0].max()) + 6.0 for t in pic.texts])
    pic.extend_right(right - 600.0)
    return pic, right

"""Marking on the cutting sheets: every label and engraved text reads from the bottom or the right edge
(rotation in (−45°, 135°]: one reading direction per sheet); every beam plate carries one face mark on MARK and the opposite one on MARK_BACK, and the mark on MARK names the side of
the plate's plane ``n`` (``parts.csv`` ``plane``) that the face looking up from the sheet faces, from the
placement (``rotation_deg``, ``mirrored``) and the flat frame (``frame``) of ``parts.csv``
(:mod:`fabrication.marking`).

Every text and every mark line is checked against the part it lies on (the CUT outline around it):

* a text (LABEL, MARK, MARK_BACK) inside the usable area lies inside a part, and a part's id and nest tag texts
  name that part (``parts.csv``); an engraved text's XDATA ``part_id`` is that part; each part carries its id
  on LABEL once;
* a mark line, mapped back through the part's placement (``x, y, rotation_deg, mirrored``) into the part's own
  flat frame, is where the source puts it: a pane's reference L at the corner of its type's outline
  (``glass/types``, :func:`fabrication.panels.panel._mark_polylines` with ``panels.mark_size``), a beam plate's
  node axis lines ``top_k → top_k + depth · â_k`` (mesh vertex, node axis of ``nodes.csv`` brought into the
  plate plane) clipped to the plate's outline, within :data:`MARK_TOL`.
"""

from __future__ import annotations

import ast

import numpy as np

from ..marking import face_marks, reads_from_bottom_or_right
from ..contract import csv_value
from . import Verification, check
from ._shapes import frame_of, literal, number, to_frame

MARK_TOL = 0.01
"""How far (mm) a mark line's ends may be from where the source data puts them (the DXF keeps doubles; the
parts.csv placement is written to 1e-8 mm)."""


def up_normal(row: dict) -> np.ndarray | None:
    """The 3D normal of the face that looks up from the sheet: the image of the sheet's ``+z`` under the part's
    placement, ``A e_x × A e_y`` with ``A = [x_dir y_dir] · M · R(−θ)`` (``None`` without a frame)."""
    try:
        frame = ast.literal_eval(row.get("frame", "") or "None")
        a = np.radians(float(row["rotation_deg"]))
    except (ValueError, SyntaxError, KeyError):
        return None
    if not isinstance(frame, dict):
        return None
    rinv = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    m = np.diag([-1.0, 1.0]) if str(row.get("mirrored", "0")) == "1" else np.eye(2)
    lin = np.stack([frame["x_dir"], frame["y_dir"]], axis=1) @ (m @ rinv)
    return np.cross(lin[:, 0], lin[:, 1])


@check("marking")
def check_marking(v: Verification) -> None:
    rows = {r["part_id"]: r for r in (v.parts or [])}
    for rel, texts in v.dxf_texts.items():
        faces: dict[tuple[str, str], list[str]] = {}
        for t in texts:
            if not reads_from_bottom_or_right(t.rotation_deg):
                v.error(rel, t.xdata.get("part_id", t.text),
                        f"text {t.text!r} on {t.layer} is turned {t.rotation_deg:.1f}°: it reads from the top or the "
                        f"left edge (upside down against the sheet's other labels, which read from the bottom or the "
                        f"right edge, turned within (−45°, 135°])")
            if t.xdata.get("mark") == "face":
                faces.setdefault((t.xdata.get("part_id", ""), t.layer), []).append(t.text)
        for pid, (_, pts) in v.cut.items():
            row = rows.get(pid)
            if row is None or row.get("kind") != "beam" or v.cut[pid][0] != rel:
                continue
            top, under = faces.get((pid, "MARK"), []), faces.get((pid, "MARK_BACK"), [])
            up = up_normal(row)
            if up is None:
                continue
            try:
                n = np.asarray(ast.literal_eval(row["plane"]), dtype=float)[:3]
            except (ValueError, SyntaxError, KeyError):
                continue
            family = {"rows": 0, "cols": 1}.get(row.get("family", ""), 2)
            want = face_marks(family, 1 if float(up @ n) > 0 else -1)
            if top != [want[0]] or under != [want[1]]:
                v.error(rel, pid, f"face marks {top} / {under} (MARK / MARK_BACK), expected {want[0]!r} / "
                                  f"{want[1]!r} for mirrored={row.get('mirrored')}")
    _check_texts(v)
    _check_mark_lines(v)


def _sheet_parts(v: Verification) -> dict[str, list[tuple[str, np.ndarray]]]:
    """sheet file → ``(part id, CUT outline)`` of the parts cut on it (as the dxf check read them)."""
    out: dict[str, list[tuple[str, np.ndarray]]] = {}
    for pid, (rel, pts) in v.cut.items():
        out.setdefault(rel, []).append((pid, np.asarray(pts, dtype=float)))
    return out


def _locate(parts: list[tuple[str, np.ndarray]], points: np.ndarray) -> list[int | None]:
    """For each 2D point, the index in ``parts`` of the outline it lies in (``None``: in none)."""
    import shapely
    from shapely import Polygon, STRtree

    polys = [Polygon(p) for _, p in parts]
    out: list[int | None] = [None] * len(points)
    if not polys or not len(points):
        return out
    tree = STRtree(polys)
    hit = tree.query(shapely.points(np.asarray(points, dtype=float)), predicate="within")
    for i, j in zip(hit[0].tolist(), hit[1].tolist()):
        out[i] = j
    return out


def _check_texts(v: Verification) -> None:
    """Every text inside the usable area lies on a part and names it (its id or its nest tag)."""
    from shapely import Point, Polygon

    rows = {r["part_id"]: r for r in (v.parts or [])}
    trims = v.dxf_trim
    for rel, parts in _sheet_parts(v).items():
        texts = [t for t in v.dxf_texts.get(rel, [])]
        where = _locate(parts, np.array([t.centre for t in texts]).reshape(-1, 2))
        trim = trims.get(rel)
        usable = Polygon(trim) if trim is not None and len(trim) >= 3 else None
        ids_on_label: dict[str, int] = {}
        for t, k in zip(texts, where):
            what = f"{t.layer} text {t.text!r}"
            if k is None:
                if usable is not None and usable.contains(Point(*t.centre)):
                    v.error(rel, what, f"lies at ({t.centre[0]:.1f}, {t.centre[1]:.1f}) on no part's outline")
                continue
            pid = parts[k][0]
            row = rows.get(pid, {})
            own = {pid, csv_value(row.get("nest_tag", ""))} - {""}
            tagged = t.xdata.get("part_id")
            if tagged is not None and tagged != pid:
                v.error(rel, pid, f"{what} lies on {pid} but its XDATA names {tagged!r}")
            if t.xdata.get("mark") == "face":
                continue                                          # face marks: checked above
            if t.text not in own:
                named = "another part's id" if t.text in rows else "not this part's id or nest tag"
                v.error(rel, pid, f"{what} on the outline of {pid} is {named} (expected one of {sorted(own)})")
            elif t.layer == "LABEL" and t.text == pid:
                ids_on_label[pid] = ids_on_label.get(pid, 0) + 1
        for pid, _ in parts:
            if ids_on_label.get(pid, 0) != 1:
                v.error(rel, pid, f"part carries its id on LABEL {ids_on_label.get(pid, 0)} times, expected once")


def to_flat(points: np.ndarray, row: dict) -> np.ndarray | None:
    """Sheet points ``(k, 2)`` mapped back into the part's own flat frame through its parts.csv placement
    (``p = M R(−rotation)(s − (x, y))``); ``None`` when the placement cannot be read."""
    x, y, a = number(row.get("x")), number(row.get("y")), number(row.get("rotation_deg"))
    if not np.isfinite([x, y, a]).all():
        return None
    a = np.radians(a)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    q = (np.asarray(points, dtype=float) - [x, y]) @ rot
    if str(row.get("mirrored", "0")) == "1":
        q[:, 0] = -q[:, 0]
    return q


def _panel_marks(v: Verification, row: dict, flat_outline: np.ndarray) -> list[np.ndarray]:
    """The reference L of a pane in its flat frame: from its type's outline (the per-type DXF), else from its
    CUT outline mapped back (in the order the part was drawn)."""
    from ..panels.panel import _mark_polylines

    size = number(v.manifest.get("fabrication", {}).get("panels", {}).get("mark_size"), 0.0)
    outline = v.type_outlines.get(csv_value(row.get("type_id", "")))
    if outline is None:
        outline = flat_outline[::-1] if str(row.get("mirrored", "0")) == "1" else flat_outline
    return [np.asarray(m, dtype=float) for m in _mark_polylines(np.asarray(outline, dtype=float), size)]


def _plate_marks(v: Verification, row: dict, flat_outline: np.ndarray,
                 axes: dict[int, np.ndarray]) -> list[np.ndarray] | None:
    """The node axis lines of a beam plate in its flat frame, clipped to its outline (``None``: no frame)."""
    from shapely.geometry import LineString, Polygon

    frame, plane, nodes = frame_of(row), literal(row.get("plane", "")), literal(row.get("nodes", ""))
    mesh = v.mesh
    if frame is None or not isinstance(plane, list) or len(plane) != 4 or not isinstance(nodes, list) \
            or mesh is None:
        return None
    depth = float(v.manifest.get("fabrication", {}).get("beam_depth", 0.0))
    pn = np.asarray(plane, dtype=float)
    pn = pn / np.linalg.norm(pn[:3])
    poly = Polygon(flat_outline)
    out = []
    for k in nodes:
        k = int(k)
        if not 0 <= k < len(mesh.vertices) or k not in axes:
            return None
        p = mesh.vertices[k] - (mesh.vertices[k] @ pn[:3] + pn[3]) * pn[:3]
        a = axes[k] - (axes[k] @ pn[:3]) * pn[:3]
        if np.linalg.norm(a) < 1e-12:
            return None
        top = to_frame(p[None], frame)[0, :2]
        down = np.array([a @ frame["x_dir"], a @ frame["y_dir"]])
        seg = LineString([top, top + depth * down / np.linalg.norm(down)]).intersection(poly)
        for g in getattr(seg, "geoms", [seg]):
            if g.geom_type == "LineString" and g.length >= 1.0:
                out.append(np.asarray(g.coords, dtype=float))
    return out


def _line_gap(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance between corresponding points of two polylines, either direction (``inf``: counts
    differ)."""
    if a.shape != b.shape:
        return float("inf")
    return float(min(np.linalg.norm(a - b, axis=1).max(), np.linalg.norm(a - b[::-1], axis=1).max()))


def _check_mark_lines(v: Verification) -> None:
    """Every MARK / MARK_BACK line on a part, where the source data puts it (module docstring)."""
    rows = {r["part_id"]: r for r in (v.parts or [])}
    axes = {int(number(r.get("vertex"), -1)): np.array([number(r.get(c)) for c in ("axis_x", "axis_y", "axis_z")])
            for r in (v.nodes or [])}
    for rel, parts in _sheet_parts(v).items():
        lines = v.dxf_marks.get(rel, [])
        if not lines:
            continue
        mids = np.array([np.asarray(pts, dtype=float)[: 2].mean(axis=0) if len(pts) else [np.nan, np.nan]
                         for _, pts in lines]).reshape(-1, 2)
        where = _locate(parts, mids)
        found: dict[tuple[str, str], list[np.ndarray]] = {}
        for n, ((layer, pts), k) in enumerate(zip(lines, where)):
            if k is None:
                v.error(rel, f"{layer} line {n + 1}", f"lies at ({mids[n, 0]:.1f}, {mids[n, 1]:.1f}) on no part's "
                                                     "outline")
                continue
            found.setdefault((parts[k][0], layer), []).append(np.asarray(pts, dtype=float))
        for pid, outline in parts:
            row = rows.get(pid)
            if row is None or row.get("kind") not in ("panel", "beam"):
                continue
            flat = to_flat(outline, row)
            if flat is None:
                continue
            want = _panel_marks(v, row, flat) if row["kind"] == "panel" else _plate_marks(v, row, flat, axes)
            if want is None:
                continue
            for layer in ("MARK",) + (("MARK_BACK",) if row["kind"] == "beam" else ()):
                got = found.get((pid, layer), [])
                if row["kind"] == "panel" and not want and not got:
                    continue
                left = list(want)
                for pts in got:
                    q = to_flat(pts, row)
                    gaps = [_line_gap(q, w) for w in left] if q is not None else []
                    j = int(np.argmin(gaps)) if gaps else -1
                    if j < 0 or gaps[j] > MARK_TOL:
                        off = f"{gaps[j]:.3g} mm" if j >= 0 and np.isfinite(gaps[j]) else "away"
                        v.error(rel, pid, f"{layer} line is {off} from where "
                                          f"{'its type outline and panels.mark_size' if row['kind'] == 'panel' else 'its node axes'} "
                                          f"put it")
                        continue
                    left.pop(j)
                if left:
                    v.error(rel, pid, f"{len(left)} {layer} line(s) missing "
                                      f"({'the reference L' if row['kind'] == 'panel' else 'node axis lines'})")

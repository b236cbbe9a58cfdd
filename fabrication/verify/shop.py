"""Shop details re-read against ``parts.csv``: the bolt sets of ``bolts.csv`` and the material and thickness on
every DXF ppfab writes.

* ``bolts``: one row of ``bolts.csv`` per bolted splice (named by its first cover plate), recomputed from the
  splice rows of ``parts.csv`` (cover plate thickness, bolt count ``holes``) and the beam piece it joins (its
  ``thickness_mm``) with ``manifest.json`` ``fabrication.splices`` (``bolt``, ``category``,
  ``thread_projection``) by :func:`fabrication.glazing.bolts.bolt_set`: grip, length, washers, nut, category,
  quantity; a splice without a row, a row of no splice, or any other value is a finding.
* ``dxf_stock``: every cutting sheet, per-type DXF and splice DXF listed in the manifest (and the R12/R2000
  copies): each CUT outline's XDATA ``material``/``thickness_mm`` equal the ``parts.csv`` row of its ``part_id``
  (a splice DXF names the cover plate type: the rows of that ``type_id``); the header custom properties
  ``PPFAB_MATERIAL``/``PPFAB_THICKNESS_MM`` (R2004 and later) and the title on ``LABEL`` name the distinct values
  of the parts on the file.
* ``splice_holes``: every bolt hole of a cover plate in ``splices.step`` is cut in one of the two beam pieces it
  joins (a CUT circle of their plate sheet, mapped back through the placement and frame of ``parts.csv``) within
  0.01 mm and with ``hole_mm``; no piece has a hole of no splice.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..contract import STOCK_HEADER_VARS, csv_value, stock_title, thickness_text
from ..contract import BOLTS_COLUMNS
from ..glazing.bolts import BoltSpec, bolt_set
from . import Verification, check
from ._shapes import frame_of, to_frame

DXF_FILE_KEYS = ("glass_sheets", "beam_sheets", "panel_type_dxfs", "splice_dxfs", "dxf_r12", "dxf_r2000")
"""The ``files`` entries of the manifest that list DXF files."""


def _cover_pairs(parts: list[dict]) -> dict[str, dict]:
    """First cover plate id → its row (the ``A`` plate of every splice)."""
    return {r["part_id"]: r for r in parts if r.get("kind") == "splice" and r["part_id"].endswith("A")}


@check("bolts")
def check_bolts(v: Verification) -> None:
    m = v.manifest
    parts = v.parts
    if parts is None:
        return
    covers = _cover_pairs(parts)
    rel = m.get("files", {}).get("bolts_csv")
    if rel is None:
        if covers:
            v.error("manifest.json", "files.bolts_csv", f"missing: parts.csv has {len(covers)} bolted splices")
        return
    sp = m.get("fabrication", {}).get("splices", {})
    try:
        spec = BoltSpec.parse(str(sp.get("bolt", "")))
        category = str(sp.get("category", "A"))
        projection = float(sp.get("thread_projection", 5.0))
    except Exception as exc:                     # a bad manifest value: a finding, not a crash
        v.error("manifest.json", "fabrication.splices", f"the bolt cannot be recomputed ({exc})")
        return
    by_id = {r["part_id"]: r for r in parts}
    rows = v.read_table(rel)
    if rows is None:
        return
    if rows and list(rows[0]) != BOLTS_COLUMNS:
        v.error(rel, "header", f"columns {list(rows[0])} are not {BOLTS_COLUMNS}")
        return
    seen: set[str] = set()
    for n, r in enumerate(rows, start=1):
        sid = r.get("splice", "")
        cover = covers.get(sid)
        if cover is None:
            v.error(rel, f"row {n} column splice", f"{sid!r} is not the first cover plate of a splice in parts.csv")
            continue
        if sid in seen:
            v.error(rel, f"row {n}", f"{sid} is listed a second time")
            continue
        seen.add(sid)
        pieces = (cover.get("joins") or "").split(";")
        beam_row = by_id.get(pieces[0]) if len(pieces) == 2 else None
        try:
            cover_t = float(cover["thickness_mm"])
            holes = int(cover["holes"])
            beam_t = float(beam_row["thickness_mm"]) if beam_row is not None else float("nan")
            want = bolt_set(sid, cover.get("beam", ""), (pieces[0], pieces[-1]), spec, category, cover_t, beam_t,
                            holes, projection).row()
        except (KeyError, ValueError, TypeError) as exc:
            v.error("parts.csv", sid, f"the splice's bolts cannot be recomputed ({exc})")
            continue
        for column in BOLTS_COLUMNS:
            if not _same(r.get(column, ""), want[column]):
                v.error(rel, f"row {n} column {column}", f"{sid}: {r.get(column)!r} written, {want[column]!r} "
                                                         "recomputed from parts.csv and fabrication.splices")
    for sid in sorted(set(covers) - seen):
        v.error(rel, sid, "a bolted splice of parts.csv has no row")
    v.checked.append("bolts")


def _same(text: str, value: Any) -> bool:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            return abs(float(text) - float(value)) <= 1e-6
        except ValueError:
            return False
    return text == str(value)


def _dxf_files(files: dict) -> list[str]:
    out: list[str] = []
    for key in DXF_FILE_KEYS:
        entry = files.get(key)
        if isinstance(entry, list):
            out += [str(x) for x in entry if str(x).endswith(".dxf")]
    return out


@check("dxf_stock")
def check_dxf_stock(v: Verification) -> None:
    from ._dxf_read import dxf_content

    m = v.manifest
    parts = v.parts
    if parts is None:
        return
    by_id = {r["part_id"]: r for r in parts}
    by_type: dict[str, dict] = {}
    for r in parts:
        if r.get("kind") == "splice":
            by_type.setdefault(r.get("type_id", ""), r)
    for rel in _dxf_files(m.get("files", {})):
        try:
            content = dxf_content(v, rel)
        except Exception as exc:  # noqa: BLE001 - reported as a finding
            v.error(rel, "", f"cannot be read ({exc})")
            continue
        materials: set[str] = set()
        thicknesses: set[str] = set()
        titles = list(content.labels)
        for part in content.parts:                 # the closed outlines on CUT with their XDATA
            x = part.xdata
            pid = x.get("part_id", "")
            row = by_id.get(pid) or by_type.get(pid)
            if row is None:
                continue                         # the dxf check names outlines of no part
            want = (csv_value(str(row.get("material", ""))), thickness_text(row.get("thickness_mm", "")))
            got = (x.get("material"), x.get("thickness_mm"))
            if got != want:
                v.error(rel, pid, f"XDATA material/thickness_mm {got[0]!r}, {got[1]!r}; parts.csv has "
                                  f"{want[0]!r}, {want[1]!r}")
            materials.add(want[0])
            thicknesses.add(want[1])
        if not materials:
            continue
        stock = ("; ".join(sorted(materials)), "; ".join(sorted(thicknesses)))
        if not any(t.endswith(stock_title(*stock)) for t in titles):
            v.error(rel, "LABEL", f"no title names the stock: want text ending {stock_title(*stock)!r}")
        if content.dxfversion >= "AC1018":
            for name, value in zip(STOCK_HEADER_VARS, stock):
                have = content.custom_vars.get(name)
                if have != value:
                    v.error(rel, f"header {name}", f"{have!r}, the parts on it are {value!r} (parts.csv)")
    v.checked.append("dxf_stock")


HOLE_TOL = 0.01
"""How far (mm) a beam piece's hole may be from the cover plate's hole it takes the bolt of."""


def _unplace(points: np.ndarray, row: dict) -> np.ndarray:
    """Sheet points back into the part's own frame: the inverse of ``R(rotation)·M·p + (x, y)`` of parts.csv."""
    a = np.radians(float(row["rotation_deg"]))
    c, s = np.cos(a), np.sin(a)
    rot = np.array([[c, -s], [s, c]])
    p = (np.asarray(points, dtype=float) - np.array([float(row["x"]), float(row["y"])])) @ rot
    if str(row.get("mirrored", "")) in ("1", "True", "true"):
        p[:, 0] = -p[:, 0]
    return p


def _cover_holes(solid, frame: dict) -> np.ndarray:
    """Centres ``(h, 2)`` of the round holes of a cover plate solid, in a beam plate's frame (both rims of a
    hole project onto one centre)."""
    if hasattr(solid, "circle_centres"):                 # a record of the text-level reader
        centres = np.asarray(solid.circle_centres(), dtype=float).reshape(-1, 3)
    else:
        centres = np.array([[c.X, c.Y, c.Z] for c in (e.arc_center for e in solid.edges()
                                                       if str(e.geom_type).endswith("CIRCLE"))]).reshape(-1, 3)
    if not len(centres):
        return np.zeros((0, 2))
    xy = to_frame(centres, frame)[:, :2]
    out: list[np.ndarray] = []
    for q in xy:
        if all(np.linalg.norm(q - o) > 1e-6 for o in out):
            out.append(q)
    return np.array(out)


@check("splice_holes")
def check_splice_holes(v: Verification) -> None:
    """Every bolt hole of a cover plate (splices.step) is cut in one of the two beam pieces it joins (CUT circles
    of the plate sheets, mapped back through placement and frame into 3D) within :data:`HOLE_TOL`, with
    ``hole_mm``; a piece has no hole that no cover plate of its splices has."""
    from ._dxf_read import dxf_content

    m = v.manifest
    files = m.get("files", {})
    parts = v.parts
    rel = files.get("splices_step")
    if parts is None or rel is None:
        return
    from ._step_read import read_or_report

    read = read_or_report(v, rel)
    if read is None:
        return
    solids = {s.name: s.solid for s in read}
    by_id = {r["part_id"]: r for r in parts}
    sheets = {r["sheet_file"] for r in parts if r.get("kind") == "beam" and r.get("sheet_file")}
    cut: dict[str, list[tuple[np.ndarray, float]]] = {}          # piece → (centre in 3D, diameter)
    for sheet in sorted(sheets):
        try:
            content = dxf_content(v, sheet)
        except Exception as exc:  # noqa: BLE001 - reported as a finding
            v.error(sheet, "", f"cannot be read ({exc})")
            continue
        for hole in content.circles:
            pid = hole.part_id
            frame = frame_of(by_id[pid]) if pid in by_id else None
            if frame is None:
                continue                          # the dxf check names CUT entities of no part
            q = _unplace(hole.centre[None], by_id[pid])[0]
            cut.setdefault(pid, []).append((frame["origin"] + q[0] * frame["x_dir"] + q[1] * frame["y_dir"],
                                            hole.diameter))
    used: dict[str, set[int]] = {}
    for r in parts:
        if r.get("kind") != "splice":
            continue
        solid = solids.get(r["part_id"])
        pieces = (r.get("joins") or "").split(";")
        frame = frame_of(by_id[pieces[0]]) if pieces[0] in by_id else None
        if solid is None or len(pieces) != 2 or frame is None:
            continue                               # the splices check names a missing solid or join
        d0 = float(r.get("hole_mm") or 0.0)
        mine = [(pid, k, to_frame(c[None], frame)[0, :2], d)
                for pid in pieces for k, (c, d) in enumerate(cut.get(pid, []))]
        for q in _cover_holes(solid, frame):
            dist = [float(np.linalg.norm(q - c)) for _, _, c, _ in mine]
            k = int(np.argmin(dist)) if dist else -1
            if k < 0 or dist[k] > HOLE_TOL:
                far = f"the nearest is {dist[k]:.3f} mm away" if dist else "they have no holes"
                v.error(by_id[pieces[0]].get("sheet_file") or "parts.csv", f"{pieces[0]}/{pieces[1]}",
                        f"no hole at the bolt hole ({q[0]:.2f}, {q[1]:.2f}) of {r['part_id']} ({far})")
                continue
            pid, j, _, d = mine[k]
            used.setdefault(pid, set()).add(j)
            if abs(d - d0) > 1e-6:
                v.error(by_id[pid].get("sheet_file") or "parts.csv", pid,
                        f"hole at ({q[0]:.2f}, {q[1]:.2f}) is {d:g} mm, {r['part_id']} has {d0:g} mm")
    for pid, holes in sorted(cut.items()):
        stray = len(holes) - len(used.get(pid, set()))
        if stray:
            v.error(by_id[pid].get("sheet_file") or "parts.csv", pid,
                    f"{stray} hole(s) that no splice cover plate of the piece has")
    v.checked.append("splice_holes")

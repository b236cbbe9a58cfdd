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
"""

from __future__ import annotations

from typing import Any

from ..contract import BOLTS_CSV, STOCK_HEADER_VARS, stock_title, thickness_text
from ..glazing.bolts import BOLT_COLUMNS, BoltSpec, bolt_set
from . import Verification, check, read_csv

DXF_FILE_KEYS = ("glass_sheets", "beam_sheets", "panel_type_dxfs", "splice_dxfs", "dxf_r12", "dxf_r2000")
"""The ``files`` entries of the manifest that list DXF files."""


def _cover_pairs(parts: list[dict]) -> dict[str, dict]:
    """First cover plate id → its row (the ``A`` plate of every splice)."""
    return {r["part_id"]: r for r in parts if r.get("kind") == "splice" and r["part_id"].endswith("A")}


@check("bolts", 58)
def check_bolts(v: Verification) -> None:
    m = v.data.get("manifest", {})
    parts = v.data.get("parts")
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
    try:
        rows = read_csv(v.folder / rel)
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        v.error(rel, "", f"cannot be read ({exc})")
        return
    if rows and list(rows[0]) != list(BOLT_COLUMNS):
        v.error(rel, "header", f"columns {list(rows[0])} are not {list(BOLT_COLUMNS)}")
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
        for column in BOLT_COLUMNS:
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


@check("dxf_stock", 59)
def check_dxf_stock(v: Verification) -> None:
    import ezdxf

    m = v.data.get("manifest", {})
    parts = v.data.get("parts")
    if parts is None:
        return
    by_id = {r["part_id"]: r for r in parts}
    by_type: dict[str, dict] = {}
    for r in parts:
        if r.get("kind") == "splice":
            by_type.setdefault(r.get("type_id", ""), r)
    for rel in _dxf_files(m.get("files", {})):
        try:
            doc = ezdxf.readfile(v.folder / rel)
        except (OSError, ezdxf.DXFError) as exc:
            v.error(rel, "", f"cannot be read ({exc})")
            continue
        materials: set[str] = set()
        thicknesses: set[str] = set()
        titles: list[str] = []
        for e in doc.modelspace():
            layer = e.dxf.get("layer", "")
            if e.dxftype() == "TEXT" and layer == "LABEL":
                titles.append(str(e.dxf.text))
            if e.dxftype() not in ("LWPOLYLINE", "POLYLINE") or layer != "CUT":
                continue
            x = {}
            if e.has_xdata("PPFAB"):
                x = dict(str(val).split("=", 1) for code, val in e.get_xdata("PPFAB") if "=" in str(val))
            pid = x.get("part_id", "")
            row = by_id.get(pid) or by_type.get(pid)
            if row is None:
                continue                         # the dxf check names outlines of no part
            want = (str(row.get("material", "")), thickness_text(row.get("thickness_mm", "")))
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
        if doc.dxfversion >= "AC1018":
            for name, value in zip(STOCK_HEADER_VARS, stock):
                have = doc.header.custom_vars.get(name)
                if have != value:
                    v.error(rel, f"header {name}", f"{have!r}, the parts on it are {value!r} (parts.csv)")
    v.checked.append("dxf_stock")

"""Parts lists (``parts.csv``, ``parts.json``) and the glass order list (``order_list.csv``).

``parts.csv`` has one row per part with the contract columns
``part_id,kind,sheet,x,y,rotation_deg,nest_tag,area_mm2`` first (``sheet`` is the 1-based
sheet number used in the DXF file names and nest tags, ``x, y, rotation_deg`` the placement
that maps the part's flat outline onto the sheet: ``R(rotation) · M · p + (x, y)``, ``M`` the
mirror when ``mirrored``), then the part's own data: for panels ``face`` (0-based OBJ face)
and, on a regular patch, ``face_i, face_j``, ``type_id``, ``material``, ``thickness_mm``,
``width_mm``/``height_mm`` (smallest enclosing rectangle), ``perimeter_mm``, ``weight_kg``,
``planarity_dev_mm`` and the rest of :attr:`FlatPart.meta`.  Output is deterministic:
rows in the order given, fixed column order, numbers with fixed precision.
"""

from __future__ import annotations

import csv
import io
import json
import os
from pathlib import Path
from typing import TYPE_CHECKING

from .contract import (GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, NOT_ON_A_SHEET, ORDER_COLUMNS, PARTS_CONTRACT_COLUMNS,
                       PARTS_KNOWN_COLUMNS, PLATE_SHEET_DIR, PLATE_SHEET_PREFIX, csv_cell, json_safe, sheet_files)
from .flatpart import FlatPart, Placement
from .model import PartsTable

if TYPE_CHECKING:  # pragma: no cover
    from .records import BuildRecord



def _num(v: float, digits: int) -> float:
    r = round(float(v), digits)
    return 0.0 if r == 0 else r


def parts_table(build: "BuildRecord") -> PartsTable:
    """The parts list of a build (made once, by the pipeline, before any file is written): glass panels, then
    beam plates, each with its placement and the file of its cutting sheet (:func:`~fabrication.contract.
    sheet_files`, the names the DXF writer writes); then the glazing strips, splice cover plates and retention
    parts (:mod:`fabrication.glazing.rows`)."""
    nest = build.nesting
    rows = part_rows(list(nest.glass_parts), nest.glass.placements,
                     sheet_files(GLASS_SHEET_DIR, GLASS_SHEET_PREFIX, nest.glass.sheets)) + \
        part_rows(list(nest.beam_parts), nest.plates.placements,
                  sheet_files(PLATE_SHEET_DIR, PLATE_SHEET_PREFIX, nest.plates.sheets))
    g = build.glazing
    if g is None:
        return PartsTable(tuple(rows))
    from .glazing.rows import beam_joins, retention_part_rows, splice_rows, strip_rows

    joins = beam_joins(g)
    bite: dict[str, float] = {}
    for b in g.bites:
        bite[b.panel] = min(bite.get(b.panel, float("inf")), b.bite)
    for row in rows:
        if row["kind"] == "beam" and row["part_id"] in joins:
            row.update(joins[row["part_id"]])
        elif row["kind"] == "panel" and row["part_id"] in bite:
            row["bite_min_mm"] = round(bite[row["part_id"]], 3)
            row["setting_blocks"] = f"2 x {g.params.setting_block_length:g} mm"
    retention = build.retention
    extra = retention_part_rows(retention) if retention is not None else []
    return PartsTable(tuple(rows + strip_rows(g, build.beams) + splice_rows(g, build.beams) + extra))


def part_rows(parts: list[FlatPart], placements: list[Placement] | None = None,
              sheet_files: list[str] | None = None) -> list[dict]:
    """Rows of the parts list for ``parts`` (placements matched by part id; unplaced parts get blanks)."""
    by_id = {p.part_id: p for p in (placements or [])}
    rows = []
    for part in parts:
        pl = by_id.get(part.part_id)
        row: dict = {
            "part_id": part.part_id,
            "kind": part.kind,
            "sheet": pl.sheet + 1 if pl else NOT_ON_A_SHEET,
            "x": _num(pl.x, 8) if pl else "",
            "y": _num(pl.y, 8) if pl else "",
            "rotation_deg": _num(pl.rotation_deg, 10) if pl else "",
            "nest_tag": pl.nest_tag if pl else "",
            "area_mm2": _num(part.area, 3),
            "mirrored": int(bool(pl.mirrored)) if pl else "",
            "sheet_file": sheet_files[pl.sheet] if (pl and sheet_files) else "",
            "type_id": part.type_id,
        }
        for k, v in part.meta.items():
            if k not in row:
                row[k] = _num(v, 4) if isinstance(v, float) else v
        rows.append(row)
    return rows


def columns(rows: list[dict]) -> list[str]:
    """Contract columns, then the known ones present, then any others (sorted by name: those of
    :data:`~fabrication.contract.PARTS_MORE_COLUMNS` in a build of this version)."""
    present = {k for r in rows for k in r}
    cols = PARTS_CONTRACT_COLUMNS + [c for c in PARTS_KNOWN_COLUMNS if c in present]
    return cols + sorted(present - set(cols))


def csv_text(rows: list[dict], cols: list[str] | None = None) -> str:
    """CSV with ``\\n`` line ends (deterministic); text cells made safe by :func:`~fabrication.contract.csv_cell`."""
    cols = cols or columns(rows)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    for r in rows:
        w.writerow({c: csv_cell(r.get(c, "")) for c in cols})
    return buf.getvalue()


def write_parts_csv(rows: list[dict], path: str | os.PathLike) -> Path:
    """Write ``parts.csv`` (see the module docstring)."""
    path = Path(path)
    path.write_text(csv_text(rows), encoding="utf-8")
    return path


def write_parts_json(rows: list[dict], path: str | os.PathLike, extra: dict | None = None) -> Path:
    """Write ``parts.json``: ``{"units": "mm", "columns": [...], "parts": [rows], **extra}`` (sorted keys)."""
    path = Path(path)
    doc = {"units": "mm", "columns": columns(rows), "parts": rows}
    doc.update(extra or {})
    path.write_text(json.dumps(json_safe(doc), indent=1, sort_keys=True, ensure_ascii=False, allow_nan=False) + "\n",
                    encoding="utf-8")
    return path


def order_rows(parts: list[FlatPart], rotations: list[float], type_files: dict[str, str] | None = None) -> list[dict]:
    """Order list: one row per type (congruent parts), in order of first appearance.

    ``width_mm × height_mm`` is the smallest enclosing rectangle (``meta``) or else the bounding box.
    """
    import numpy as np

    groups: dict[str, list[FlatPart]] = {}
    for p in parts:
        groups.setdefault(p.type_id or p.part_id, []).append(p)
    rows = []
    for tid, members in groups.items():
        rep = members[0]
        w = rep.meta.get("width_mm")
        h = rep.meta.get("height_mm")
        if w is None or h is None:
            w, h = (float(v) for v in np.ptp(np.asarray(rep.outline, dtype=float), axis=0))
        rots = rep.rotations if rep.rotations is not None else rotations
        rows.append({
            "type_id": tid,
            "quantity": len(members),
            "parts": ";".join(m.part_id for m in members),
            "width_mm": _num(w, 1),
            "height_mm": _num(h, 1),
            "area_mm2": _num(rep.area, 1),
            "material": rep.meta.get("material", ""),
            "thickness_mm": rep.meta.get("thickness_mm", ""),
            "rotations": ";".join(f"{float(r):g}" for r in rots),
            "mirror_allowed": int(bool(rep.mirror_allowed)),
            "file": (type_files or {}).get(tid, ""),
        })
    return rows


def write_order_list(rows: list[dict], path: str | os.PathLike) -> Path:
    """Write the order list CSV (columns :data:`ORDER_COLUMNS`)."""
    path = Path(path)
    path.write_text(csv_text(rows, ORDER_COLUMNS), encoding="utf-8")
    return path

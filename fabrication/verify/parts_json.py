"""parts.json holds what parts.csv holds: the same columns, the same parts in the same order, equal values."""

from __future__ import annotations

import math

from ..contract import csv_value
from . import Verification, check
from ._shapes import literal


def _same(cell: str, value: object) -> bool:
    text = csv_value(cell)
    if value is None:
        return text in ("", "nan")
    if isinstance(value, bool):
        return text in (str(value), str(int(value)))
    if isinstance(value, (int, float)):
        try:
            x = float(text)
        except ValueError:
            return False
        return x == value or math.isclose(x, float(value), rel_tol=1e-12, abs_tol=1e-12)
    if isinstance(value, (list, dict)):
        return literal(text) == value
    return text == str(value)


@check("parts_json")
def check_parts_json(v: Verification) -> None:
    files = v.manifest.get("files", {})
    rel = files.get("parts_json")
    rows = (v.parts_csv_rows if v.parts_csv_rows is not None else v.parts)      # the cells as written
    if rel is None or rows is None:
        return
    doc = v.read_json(rel)
    if doc is None:
        return
    parts = doc.get("parts", []) if isinstance(doc, dict) else None
    if not isinstance(parts, list) or not all(isinstance(p, dict) for p in parts):
        v.error(rel, "parts", "must be a list of objects, one per part")
        return
    header = list(rows[0]) if rows else []
    if rows and doc.get("columns") != header:
        v.error(rel, "columns", f"{doc.get('columns')} differ from the parts.csv header")
    if [p.get("part_id") for p in parts] != [r["part_id"] for r in rows]:
        v.error(rel, "parts", f"{len(parts)} parts differ from the {len(rows)} rows of parts.csv (ids or order)")
        return
    for row, part in zip(rows, parts):
        for col, cell in row.items():
            if not isinstance(col, str):
                continue                            # cells past the header: the parts check names the row
            cell = "" if cell is None else cell     # a short row: the parts check names the cell
            value = part.get(col)
            if not _same(cell, value):
                v.error(rel, row["part_id"], f"{col} is {value!r}, parts.csv has {cell!r}")
    v.checked.append("parts_json")

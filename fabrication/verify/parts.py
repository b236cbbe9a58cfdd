"""parts.csv: contract columns, unique part ids and nest tags, one panel per mesh face, and every typed cell
readable.

The cells the checks compute with (numbers, the mesh face, the sheet, the plate frame, plane and nodes, a
strip's edge nodes) are read here with :class:`~fabrication.verify._cells.CellReader`: a bad cell is a finding
naming its row and column, and is blanked in the rows kept in :attr:`FolderData.parts`, so another check reads it as
absent instead of failing on it.  The rows as written are kept in :attr:`FolderData.parts_csv_rows` (the parts.json
check compares them)."""

from __future__ import annotations

from typing import Any

from ..contract import PART_KINDS, PARTS_CONTRACT_COLUMNS as PARTS_COLUMNS
from . import Verification, check
from ._cells import CellReader, frame_shape, ints_shape, plane_shape

NUMBER_COLUMNS = ("x", "y", "rotation_deg", "area_mm2", "thickness_mm", "width_mm", "height_mm", "perimeter_mm",
                  "weight_kg", "length_mm", "mass_kg", "depth_mm", "bar_start_mm", "bite_min_mm")
"""Columns holding a number where they hold anything (a column may be empty on rows of another kind)."""
INTEGER_COLUMNS = ("sheet", "face", "face_i", "face_j", "bar", "piece", "pieces")


def clean_rows(v: Verification, rel: str, rows: list[dict[str, Any]], faces: int | None) -> list[dict[str, Any]]:
    """``rows`` with their malformed typed cells blanked (each a finding); ``faces``: the mesh's face count, which
    a ``face`` cell must stay below.  A row with nothing to blank (cells past the header, missing cells, a bad
    cell) is the row itself, not a copy: at 88 × 60 faces parts.csv has 80,163 rows of 53 columns, and a copy of
    each held 175 MB more."""
    cells = CellReader(v, rel)
    out = []
    for n, row in enumerate(rows, start=1):
        blank: dict[str, str] = {}
        for c in ("part_id", "kind", "nest_tag"):
            if cells.text(n, row, c) is None:
                blank[c] = ""
        for c in NUMBER_COLUMNS:
            if c in row and cells.number(n, row, c, empty_ok=True) is None and row[c] not in ("", None):
                blank[c] = ""
        for c in INTEGER_COLUMNS:
            high = faces if c == "face" else None
            if c in row and cells.integer(n, row, c, empty_ok=True, low=0, high=high) is None \
                    and row[c] not in ("", None):
                blank[c] = ""
        if "mirrored" in row and row["mirrored"] not in ("", "0", "1", "True", "False", "true", "false"):
            v.error(rel, f"row {n} column mirrored", f"{row['mirrored']!r} is not 0 or 1")
            blank["mirrored"] = "0"
        for c, shape in (("frame", frame_shape), ("plane", plane_shape), ("nodes", ints_shape)):
            if c in row and cells.json(n, row, c, empty_ok=True, shape=shape) is None and row[c] not in ("", None):
                blank[c] = ""
        if "edge_nodes" in row and cells.id_list(n, row, "edge_nodes", count=2) is None \
                and row["edge_nodes"] not in ("", None):
            blank["edge_nodes"] = ""
        for c, value in row.items():
            if value is None and c is not None:
                blank[c] = ""
        if blank or None in row:
            row = dict(row)
            row.pop(None, None)                              # type: ignore[call-overload]  # cells past the header
            row.update(blank)
        out.append(row)
    return out


@check("parts")
def check_parts(v: Verification) -> None:
    files = v.manifest.get("files", {})
    rel = files.get("parts_csv")
    if rel is None:
        return
    raw = v.read_table(rel, PARTS_COLUMNS)
    if raw is None:
        return
    mesh = v.mesh
    rows = clean_rows(v, rel, raw, None if mesh is None else len(mesh.faces))
    v.read.parts_csv_rows = raw
    v.read.parts = rows
    ids, tags = set(), set()
    for r, row in enumerate(rows, start=2):
        if row["part_id"] in ids:
            v.error(rel, f"line {r}", f"part id {row['part_id']} appears twice")
        ids.add(row["part_id"])
        if row["nest_tag"] in tags:
            v.error(rel, f"line {r}", f"nest tag {row['nest_tag']} appears twice")
        tags.add(row["nest_tag"])
        if row["kind"] not in PART_KINDS:
            v.error(rel, row["part_id"], f"kind must be one of {', '.join(PART_KINDS)}, got {row['kind']!r}")
    panels = [row for row in rows if row["kind"] == "panel"]
    if mesh is not None and panels:
        faces = sorted(int(row["face"]) for row in panels if row["face"] != "")
        if faces != list(range(len(mesh.faces))):
            bare = sorted(set(range(len(mesh.faces))) - set(faces))
            v.error(rel, "panels", f"{len(panels)} panel rows for {len(mesh.faces)} mesh faces"
                                   + (f"; faces without a panel: {bare[:10]}" if bare else ""))
    v.checked.append("parts")

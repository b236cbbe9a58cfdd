"""parts.csv: contract columns, unique part ids and nest tags, one panel per mesh face."""

from __future__ import annotations

from ..contract import PART_KINDS, PARTS_CONTRACT_COLUMNS as PARTS_COLUMNS
from . import Verification, check, read_csv


@check("parts", 30)
def check_parts(v: Verification) -> None:
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("parts_csv")
    if rel is None:
        return
    rows = read_csv(v.folder / rel)
    v.data["parts"] = rows
    if rows:
        missing = [c for c in PARTS_COLUMNS if c not in rows[0]]
        if missing:
            v.error(rel, "columns", f"missing contract columns {missing}")
            return
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
    mesh = v.data.get("mesh")
    panels = [row for row in rows if row["kind"] == "panel"]
    if mesh is not None and panels:
        faces = sorted(int(row["face"]) for row in panels)
        if faces != list(range(len(mesh.faces))):
            bare = sorted(set(range(len(mesh.faces))) - set(faces))
            v.error(rel, "panels", f"{len(panels)} panel rows for {len(mesh.faces)} mesh faces"
                                   + (f"; faces without a panel: {bare[:10]}" if bare else ""))
    v.checked.append("parts")
